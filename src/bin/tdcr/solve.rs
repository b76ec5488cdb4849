//! `tdcr solve`: one robot file, as a table, JSON or CSV, optionally with a picture.

use clap::{Args, ValueEnum};
use std::path::PathBuf;
use tdcr::io::output;
use tdcr::plot::{Figure, LegendEntry, PALETTE, Style};

use crate::args::{SolverArgs, parse_samples, parse_tension};
use crate::failure::{Failure, emit, note, write_file};
use crate::robot_args::{apply, read_robot, run_solver, set_tension};
use crate::tables::{describe, diagnostics, solution_table, summary};

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
    /// Tension of tendon I (numbered from 1) in N, replacing the file's. Repeatable.
    #[arg(long, value_name = "I=NEWTONS", value_parser = parse_tension)]
    tension: Vec<(usize, f64)>,
    #[command(flatten)]
    solver: SolverArgs,
    /// Output at K evenly spaced arc lengths (interpolated with the scheme's own
    /// interpolant) instead of at the solution's nodes.
    #[arg(long, value_name = "K", value_parser = parse_samples)]
    samples: Option<usize>,
    /// Add the tip Jacobians (d tip pose / d tensions, tip force, tip moment) to the JSON
    /// output (docs/cli.md).
    #[arg(long)]
    jacobian: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,
    /// Write the output to FILE instead of standard output.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Draw the shape into FILE.svg.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
}

/// `tdcr solve`: solves one robot file and writes the output (and the picture).
pub fn run(args: &SolveArgs) -> Result<(), Failure> {
    let (name, mut file) = read_robot(&args.file)?;
    for &(i, t) in &args.tension {
        set_tension(&mut file.robot, i, t)?;
    }
    apply(&mut file, &args.solver);
    crate::failure::warn_scales(&name, &file.robot);
    let solution = run_solver(&file.robot, &file, None)?;
    if args.jacobian && !matches!(args.format, Format::Json) {
        note("note: --jacobian adds the tip Jacobians to the JSON output only (--format json)");
    }
    if args.solver.verbose {
        note(&format!("{name}: {}", summary(&solution.report, file.robot.length())));
        note(diagnostics(&solution.report).trim_end());
    }
    let text = match args.format {
        Format::Json => {
            let jacobian = if args.jacobian {
                Some(
                    tdcr::collocation::sensitivity::tip_sensitivities(&file.robot, &solution)
                        .map_err(|e| Failure::Other(e.to_string()))?,
                )
            } else {
                None
            };
            output::json(&file.robot, &solution, args.samples, jacobian.as_ref())
        }
        Format::Csv => output::csv(&output::samples(&file.robot, &solution, args.samples)),
        Format::Table => solution_table(
            &name,
            &file,
            &solution,
            &output::samples(&file.robot, &solution, args.samples),
        ),
    };
    match &args.out {
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
        figure.add_shape(&file.robot, &solution, &style);
        figure.legend.push(LegendEntry {
            label: "backbone".into(),
            color: "#000000".into(),
            dash: None,
        });
        for (i, t) in file.robot.tendons.iter().enumerate() {
            figure.legend.push(LegendEntry {
                label: format!("tendon {}: {}, {} N", i + 1, describe(&t.routing), t.tension),
                color: PALETTE[i % PALETTE.len()].into(),
                dash: (t.tension == 0.0).then(|| "1 2".into()),
            });
        }
        write_file(path, &figure.to_svg(), "plot")?;
        note(&format!("wrote {}", path.display()));
    }
    Ok(())
}
