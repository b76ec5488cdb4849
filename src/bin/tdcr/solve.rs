//! `tdcr solve`: one robot file, as a table, JSON or CSV, optionally with a picture.

use clap::{Args, ValueEnum};
use std::path::PathBuf;
use tdcr::io::output;
use tdcr::plot::{Figure, Style, solved_shape_legend};

use crate::args::{SolverArgs, parse_disks, parse_samples};
use crate::failure::{Failure, emit, note, picture_format, write_file, write_picture};
use crate::robot_args::{FrictionArgs, TendonArgs, apply, read_robot, run_solver};
use crate::tables::{diagnostics, solution_table, summary};

/// The output formats of `solve`.
#[derive(Clone, Copy, Default, ValueEnum)]
pub enum Format {
    /// A table for people.
    #[default]
    Table,
    /// JSON (fields in docs/cli.md).
    Json,
    /// CSV, one row per sample.
    Csv,
}

/// The arguments of `tdcr solve`.
#[derive(Args)]
pub struct SolveArgs {
    /// Robot file (TOML; `-` reads standard input).
    file: String,
    #[command(flatten)]
    tendons: TendonArgs,
    #[command(flatten)]
    friction: FrictionArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Output at K evenly spaced arc lengths (interpolated with the scheme's own
    /// interpolant) instead of at the solution's nodes.
    #[arg(long, value_name = "K", value_parser = parse_samples)]
    samples: Option<usize>,
    /// Add the tip Jacobian. Bare `--jacobian`: every tip Jacobian (d tip pose / d tensions,
    /// pull-ins, friction coefficients, tip force, tip moment) in the JSON output. `--jacobian=COLUMNS`: only those
    /// columns (comma-separated parameter names such as `tension.2`, `friction.1` or
    /// `tip_force.z`, or the groups `tension`, `tip_force`,
    /// `tip_moment`, `base_position`), as a 6 x n table or under `tip_jacobian` in the JSON
    /// (docs/cli.md).
    #[arg(long, value_name = "COLUMNS", num_args = 0..=1, require_equals = true, default_missing_value = "all")]
    jacobian: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,
    /// Write the output to FILE instead of standard output (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Draw the shape into FILE: PNG if its name ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// Warm-start from a saved solution: the JSON of `tdcr solve --format json` for this
    /// robot, for example of other tensions.
    #[arg(long, value_name = "SOLUTION.json")]
    start: Option<PathBuf>,
    /// Spacer disks drawn in the picture, evenly spaced (default: about 2.5 tendon offsets
    /// apart, 12 on the prototype; 0: none).
    #[arg(long, value_name = "N", value_parser = parse_disks, requires = "plot")]
    disks: Option<usize>,
    #[command(flatten)]
    picture: crate::picture::PictureArgs,
}

/// `tdcr solve`: solves one robot file and writes the output (and the picture).
pub fn run(args: &SolveArgs) -> Result<(), Failure> {
    if let Some(path) = &args.plot {
        picture_format(path)?;
    }
    let (name, mut file) = read_robot(&args.file)?;
    // The file's warnings say what the file gives, before the options replace it.
    let read_warnings = file.warnings();
    args.tendons.apply(&mut file.robot)?;
    args.friction.apply(&mut file.robot)?;
    apply(&mut file, &args.solver);
    crate::failure::warn_file(&name, &read_warnings, &file);
    crate::failure::warn_scales(&name, &file.robot);
    let start = args
        .start
        .as_deref()
        .map(|p| crate::robot_args::read_start(p, &file.robot))
        .transpose()?;
    let solution = run_solver(&file.robot, &file, start.as_ref())?;
    crate::failure::warn_equilibrium(&name, &solution.report);
    crate::failure::warn_solved_tensions(&name, &file.robot, &solution, |_| false);
    let columns = match args.jacobian.as_deref() {
        None | Some("all") => None,
        Some(list) => {
            let names: Vec<&str> = list.split(',').map(str::trim).collect();
            let wrt = tdcr::collocation::sensitivity::columns(&names, &file.robot)
                .map_err(|e| Failure::Input(format!("--jacobian={list}: {e}")))?;
            // A column the solution has no derivative in (the friction coefficient of a
            // tendon without friction) is bad input, in the option's words.
            let tip = tdcr::collocation::sensitivity::tip_jacobian(&file.robot, &solution, &wrt).map_err(|e| {
                match crate::failure::solver_failure(e) {
                    Failure::Input(text) => Failure::Input(format!("--jacobian={list}: {text}")),
                    other => other,
                }
            })?;
            Some((wrt, tip))
        }
    };
    let all = args.jacobian.as_deref() == Some("all");
    if all && !matches!(args.format, Format::Json) {
        note(
            "note: --jacobian adds the tip Jacobians to the JSON output only (--format json); --jacobian=tension prints the tension columns as a table",
        );
    }
    if columns.is_some() && matches!(args.format, Format::Csv) {
        note("note: --jacobian=COLUMNS adds the tip Jacobian to the table and JSON outputs, not to the CSV");
    }
    if args.solver.verbose {
        note(&format!("{name}: {}", summary(&solution.report, file.robot.length())));
        note(diagnostics(&solution.report).trim_end());
    }
    let text = match args.format {
        Format::Json => match &columns {
            Some((wrt, tip)) => output::json_with_tip_jacobian(&file.robot, &solution, args.samples, wrt, tip),
            None => {
                let jacobian = if all {
                    Some(
                        tdcr::collocation::sensitivity::tip_sensitivities(&file.robot, &solution)
                            .map_err(|e| Failure::Other(e.to_string()))?,
                    )
                } else {
                    None
                };
                output::json(&file.robot, &solution, args.samples, jacobian.as_ref())
            }
        },
        Format::Csv => output::csv(
            &file.robot,
            &solution,
            &output::samples(&file.robot, &solution, args.samples),
        ),
        Format::Table => {
            let mut text = solution_table(
                &name,
                &file,
                &solution,
                &output::samples(&file.robot, &solution, args.samples),
            );
            if let Some((wrt, tip)) = &columns {
                text.push_str(&jacobian_table(wrt, tip));
            }
            text
        }
    };
    match crate::failure::out_path(&args.out) {
        Some(path) => {
            write_file(path, &text, "output")?;
            note(&format!("wrote {}", path.display()));
        }
        None => emit(&text)?,
    }
    if let Some(path) = &args.plot {
        let mut figure = Figure::new(&format!("{name}: solved shape"));
        figure.subtitle.push(summary(&solution.report, file.robot.length()));
        let mut style = Style::new("#000000");
        style.slack_tendons = true;
        style.tendon_colors = true;
        style.disks = args.disks;
        // The file's own disks, unless --disks asks for others.
        style.placed_disks = file.disks.clone().filter(|_| args.disks.is_none());
        figure.add_shape(&file.robot, &solution, &style);
        figure.legend = solved_shape_legend(&file.robot, &solution, &style);
        args.picture.apply(&mut figure);
        write_picture(path, &figure, "plot")?;
    }
    Ok(())
}

/// The chosen columns of the tip Jacobian as a table: one row per tip coordinate (position
/// in m, then the world-frame rotation vector in rad, per unit of each column's parameter).
fn jacobian_table(wrt: &[tdcr::Parameter], tip: &tdcr::nalgebra::DMatrix<f64>) -> String {
    let mut text = String::from(
        "\ntip Jacobian (rows: tip position in m, then tip rotation vector in rad, world frame, per unit of each column)\n",
    );
    text.push_str(&format!("{:<6}", ""));
    for p in wrt {
        text.push_str(&format!(" {:>14}", p.to_string()));
    }
    text.push('\n');
    for (r, label) in ["p.x", "p.y", "p.z", "rot.x", "rot.y", "rot.z"].iter().enumerate() {
        text.push_str(&format!("{label:<6}"));
        for c in 0..tip.ncols() {
            // + 0.0 prints an exact zero without its sign (-0.0 + 0.0 = 0.0).
            text.push_str(&format!(" {:>14.6e}", tip[(r, c)] + 0.0));
        }
        text.push('\n');
    }
    text
}
