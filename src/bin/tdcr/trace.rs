//! `tdcr trace`: one input varied along a branch of equilibria by pseudo-arclength
//! continuation, through folds, with the stability of every point; CSV or JSON out, and a
//! picture of the branch.

use clap::{Args, ValueEnum};
use std::path::PathBuf;
use tdcr::collocation::{Trace, trace};
use tdcr::io::csv_table::CsvTable;
use tdcr::io::output;
use tdcr::plot::{Chart, Mark, Segment, significant};
use tdcr::{Parameter, Readable};

use crate::args::SolverArgs;
use crate::failure::{Failure, emit, note, picture_format, write_file};
use crate::robot_args::{apply, read_robot};

/// The output formats of `trace`.
#[derive(Clone, Copy, Default, ValueEnum)]
pub enum TraceFormat {
    /// CSV, one row per point of the branch.
    #[default]
    Csv,
    /// JSON: the range, folds, bifurcations and points.
    Json,
}

/// A tip coordinate.
#[derive(Clone, Copy, Default, ValueEnum)]
pub enum Coordinate {
    /// World x.
    #[default]
    X,
    /// World y.
    Y,
    /// World z.
    Z,
}

/// The arguments of `tdcr trace`.
#[derive(Args)]
pub struct TraceArgs {
    /// Robot file (TOML; `-` reads standard input).
    file: String,
    /// The input and its range, NAME=START:STOP: `tension.I` (N, I from 1),
    /// `tip_force.x|y|z` (N), `tip_moment.x|y|z` (N m), `base_position.x|y|z` (m),
    /// `distributed_force.x|y|z` (N/m, that component at every s) or `load_scale` (every
    /// tension and load times the value) (docs/parameters.md).
    #[arg(long, value_name = "NAME=START:STOP", allow_hyphen_values = true)]
    param: String,
    #[command(flatten)]
    tendons: crate::robot_args::TendonArgs,
    #[command(flatten)]
    friction: crate::robot_args::FrictionArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Output format.
    #[arg(long, value_enum, default_value_t)]
    format: TraceFormat,
    /// Write the output to FILE instead of standard output (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Draw the branch (the parameter against a tip coordinate; stable solid, unstable
    /// dashed, folds marked) into FILE: PNG if its name ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// The tip coordinate of the picture.
    #[arg(long, value_enum, default_value_t)]
    coordinate: Coordinate,
    /// The picture's title instead of the file name and the parameter (`--title ""`: none).
    #[arg(long, value_name = "TEXT", requires = "plot")]
    title: Option<String>,
    /// Leave out the picture's subtitle (the range, points and iterations).
    #[arg(long, requires = "plot")]
    no_subtitle: bool,
}

/// `NAME=START:STOP`.
fn parse_range(text: &str) -> Result<(&str, f64, f64), Failure> {
    let bad = || {
        Failure::Input(format!(
            "--param `{text}` must look like NAME=START:STOP, for example tension.1=0:40 or tip_force.z=0:-5"
        ))
    };
    let (name, range) = text.split_once('=').ok_or_else(bad)?;
    let (a, b) = range.split_once(':').ok_or_else(bad)?;
    let number = |v: &str| v.trim().parse::<f64>().ok().filter(|x| x.is_finite());
    match (number(a), number(b)) {
        (Some(a), Some(b)) if a != b => Ok((name.trim(), a, b)),
        (Some(_), Some(_)) => Err(Failure::Input(format!(
            "--param `{text}`: START and STOP are equal; give two different values"
        ))),
        _ => Err(bad()),
    }
}

/// `tdcr trace`: traces the branch, writes the points and the picture, and says on
/// standard error where the branch folds. Exits 3 when the branch could not be followed to
/// the end (after writing the points it has).
pub fn run(args: &TraceArgs) -> Result<(), Failure> {
    if let Some(path) = &args.plot {
        picture_format(path)?;
    }
    let (name, mut file) = read_robot(&args.file)?;
    args.tendons.apply(&mut file.robot)?;
    args.friction.apply(&mut file.robot)?;
    apply(&mut file, &args.solver);
    let (param, from, to) = parse_range(&args.param)?;
    let parameter = Parameter::parse(param, &file.robot).map_err(|e| Failure::Input(e.to_string()))?;
    let t = trace(&file.robot, parameter, from, to, &file.solver.collocation).map_err(|e| with_flags(e, parameter))?;
    let text = match args.format {
        TraceFormat::Csv => csv(&t),
        TraceFormat::Json => json(&t),
    };
    match crate::failure::out_path(&args.out) {
        Some(path) => {
            write_file(path, &text, "trace")?;
            note(&format!("wrote {}", path.display()));
        }
        None => emit(&text)?,
    }
    let values = |v: &[f64]| v.iter().map(|x| significant(*x)).collect::<Vec<_>>().join(", ");
    let unit = parameter.unit();
    note(&format!(
        "trace of {parameter} from {} to {} {unit}: {} points, {} iterations, {:.1} ms{}{}",
        Readable(from),
        Readable(to),
        t.points.len(),
        t.report.iterations,
        t.report.timings.total.as_secs_f64() * 1e3,
        if t.folds.is_empty() {
            String::new()
        } else {
            format!(
                "; FOLDS at {} {unit}: loaded past them the robot snaps through",
                values(&t.folds)
            )
        },
        if t.bifurcations.is_empty() {
            String::new()
        } else {
            format!(
                "; BIFURCATIONS at {} {unit}: the branch loses stability without a fold",
                values(&t.bifurcations)
            )
        }
    ));
    if let Some(path) = &args.plot {
        let mut chart = picture(&name, &t, args.coordinate);
        if let Some(title) = &args.title {
            chart.title = title.clone();
        }
        if args.no_subtitle {
            chart.subtitle.clear();
        }
        let bytes = match picture_format(path)? {
            tdcr::plot::Format::Svg => chart.to_svg().into_bytes(),
            tdcr::plot::Format::Png => {
                chart
                    .to_png(tdcr::plot::PNG_SCALE)
                    .map_err(|e| Failure::Other(format!("cannot draw the branch: {e}")))?
                    .data
            }
        };
        write_file(path, bytes, "picture")?;
        note(&format!("wrote {}", path.display()));
    }
    match &t.stopped {
        Some(why) => Err(Failure::NotConverged(format!(
            "the branch could not be followed past {} {unit}: {why}; the output holds the points up to there",
            t.points
                .last()
                .map_or(String::from("its start"), |p| significant(p.value))
        ))),
        None => Ok(()),
    }
}

/// A trace's error as the command line prints it: the library's message, and where it
/// suggests a sweep instead, the `tdcr sweep` arguments that run it.
fn with_flags(e: tdcr::Error, parameter: Parameter) -> Failure {
    let sweep = match &e {
        tdcr::Error::InvalidInput { field, .. }
            if field == "parameter"
                && matches!(
                    parameter,
                    Parameter::YoungsModulus
                        | Parameter::Displacement(_)
                        | Parameter::RoutingOffset(..)
                        | Parameter::Friction(_)
                ) =>
        {
            Some(format!("tdcr sweep --param {parameter}=START:STOP:COUNT"))
        }
        tdcr::Error::InvalidInput { field, .. } if field.ends_with(".displacement") => {
            Some("tdcr sweep --displacement I=START:STOP:COUNT".to_string())
        }
        tdcr::Error::ModelLimit { field, .. } if field.ends_with(".friction") => {
            Some("--friction I=0 for each tendon named".to_string())
        }
        _ => None,
    };
    match (crate::failure::solver_failure(e), sweep) {
        (Failure::Input(text), Some(command)) => Failure::Input(format!("{text} (on the command line: {command})")),
        (Failure::Limit(text), Some(command)) => Failure::Limit(format!("{text} (on the command line: {command})")),
        (f, _) => f,
    }
}

fn csv(t: &Trace) -> String {
    let parameter = t.parameter.to_string();
    let mut table = CsvTable::new([
        "point",
        &parameter,
        "tip_x",
        "tip_y",
        "tip_z",
        "stability",
        "unstable_directions",
        "fold",
        "iterations",
    ]);
    for (k, p) in t.points.iter().enumerate() {
        table.row([
            (k + 1).to_string(),
            output::number(p.value),
            output::number(p.tip_position.x),
            output::number(p.tip_position.y),
            output::number(p.tip_position.z),
            p.verdict().to_string(),
            p.unstable_directions.map_or(String::new(), |d| d.to_string()),
            u8::from(p.fold).to_string(),
            p.iterations.to_string(),
        ]);
    }
    table.finish()
}

fn json(t: &Trace) -> String {
    let points: Vec<serde_json::Value> = t
        .points
        .iter()
        .map(|p| {
            serde_json::json!({
                "value": p.value,
                "tip": [p.tip_position.x, p.tip_position.y, p.tip_position.z],
                "stability": p.verdict(),
                "unstable_directions": p.unstable_directions,
                "fold": p.fold,
                "iterations": p.iterations,
            })
        })
        .collect();
    let value = serde_json::json!({
        "parameter": t.parameter.to_string(),
        "from": t.range.0,
        "to": t.range.1,
        "folds": t.folds,
        "bifurcations": t.bifurcations,
        "stopped": t.stopped,
        "iterations": t.report.iterations,
        "points": points,
    });
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    text
}

/// `value` with its unit, if it has one: `0.173 N`, `1.5` (a load scale).
fn with_unit(value: f64, unit: &str) -> String {
    if unit.is_empty() {
        significant(value)
    } else {
        format!("{} {unit}", significant(value))
    }
}

/// The branch: parameter against a tip coordinate (mm), stable solid, unstable dashed,
/// folds and bifurcations marked.
fn picture(name: &str, t: &Trace, coordinate: Coordinate) -> Chart {
    let (axis, label) = match coordinate {
        Coordinate::X => (0, "x"),
        Coordinate::Y => (1, "y"),
        Coordinate::Z => (2, "z"),
    };
    let (stable, unstable) = ("#1f5fa8", "#e07b00");
    let y = |p: &tdcr::collocation::TracePoint| p.tip_position[axis] * 1e3;
    let mut chart = Chart {
        title: format!("{name}: branch of equilibria in {}", t.parameter),
        subtitle: vec![format!(
            "pseudo-arclength continuation from {} to {} {}, {} points, {} iterations",
            significant(t.range.0),
            significant(t.range.1),
            t.parameter.unit(),
            t.points.len(),
            t.report.iterations
        )],
        x_label: t.parameter.axis_label(),
        y_label: format!("tip {label} (mm)"),
        ..Default::default()
    };
    for w in t.points.windows(2) {
        let bad = w.iter().any(|p| p.unstable_directions.is_some_and(|d| d > 0));
        chart.segments.push(Segment {
            ends: [(w[0].value, y(&w[0])), (w[1].value, y(&w[1]))],
            dashed: bad,
            color: if bad { unstable } else { stable }.into(),
        });
    }
    for p in t.points.iter().filter(|p| p.fold) {
        chart.marks.push(Mark {
            at: (p.value, y(p)),
            label: format!("fold at {}", with_unit(p.value, t.parameter.unit())),
            color: "#c0392b".into(),
        });
    }
    for &b in &t.bifurcations {
        let nearest = t
            .points
            .iter()
            .min_by(|p, q| (p.value - b).abs().total_cmp(&(q.value - b).abs()));
        if let Some(p) = nearest {
            chart.marks.push(Mark {
                at: (p.value, y(p)),
                label: format!("bifurcation at {}", with_unit(b, t.parameter.unit())),
                color: "#7d3c98".into(),
            });
        }
    }
    // The legend names only what the chart shows.
    let dashed = chart.segments.iter().any(|s| s.dashed);
    if chart.segments.iter().any(|s| !s.dashed) {
        chart
            .legend
            .push(("stable equilibria".into(), stable.into(), Some(false)));
    }
    if dashed {
        chart.legend.push((
            "unstable equilibria (a disturbance makes the robot leave them)".into(),
            unstable.into(),
            Some(true),
        ));
    }
    if t.points.iter().any(|p| p.fold) {
        chart.legend.push((
            "fold: loaded past it, the robot snaps to another state".into(),
            "#c0392b".into(),
            None,
        ));
    }
    if !t.bifurcations.is_empty() {
        chart.legend.push((
            "bifurcation: stability changes without a fold (another branch crosses)".into(),
            "#7d3c98".into(),
            None,
        ));
    }
    chart
}
