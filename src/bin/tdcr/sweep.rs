//! `tdcr sweep`: a sequence of robots over tension ranges, each solve warm-started from the
//! last; CSV out, optionally the tip trajectory as a picture.

use clap::Args;
use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tdcr::io::output;
use tdcr::plot::{Figure, LegendEntry, PALETTE, Style, shape_legend};
use tdcr::{Robot, Solution};

use crate::args::{SolverArgs, parse_disks, parse_sweep};
use crate::failure::{Failure, emit, note, picture_format, write_file, write_picture};
use crate::robot_args::{apply, read_robot, run_solver, set_tension};
use crate::tables::summary;

/// The arguments of `tdcr sweep`.
#[derive(Args)]
pub struct SweepArgs {
    /// Robot file (TOML; `-` reads standard input).
    file: String,
    /// Tension of tendon I (from 1): `I=START:STOP:COUNT` (COUNT evenly spaced values, N) or a
    /// fixed `I=NEWTONS`. Repeatable; every range must have the same COUNT.
    #[arg(long, value_name = "I=START:STOP:COUNT", value_parser = parse_sweep, required = true)]
    tension: Vec<(usize, Vec<f64>)>,
    #[command(flatten)]
    solver: SolverArgs,
    /// Write the CSV to FILE instead of standard output.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Draw the tip trajectory (with the first and last shapes) into FILE: PNG if its name
    /// ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// Spacer disks drawn on the two shapes of the picture (default: about 2.5 tendon offsets
    /// apart, 12 on the prototype; 0: none).
    #[arg(long, value_name = "N", value_parser = parse_disks, requires = "plot")]
    disks: Option<usize>,
}

/// A progress bar on standard error, shown only on a terminal and only once the work has
/// taken longer than [`Progress::DELAY`]; `batch` shows its progress with it too.
pub struct Progress {
    start: Instant,
    shown: bool,
    terminal: bool,
}

impl Progress {
    /// Half a second: shorter runs finish before a bar would be worth reading.
    const DELAY: Duration = Duration::from_millis(500);

    /// A bar that starts its clock now.
    pub fn new() -> Self {
        Progress {
            start: Instant::now(),
            shown: false,
            terminal: std::io::stderr().is_terminal(),
        }
    }

    /// Shows `done` of `total` steps (on a terminal, after [`Progress::DELAY`]).
    pub fn update(&mut self, done: usize, total: usize) {
        if !self.terminal || self.start.elapsed() < Self::DELAY {
            return;
        }
        let width = 30;
        let filled = width * done / total.max(1);
        let _ = write!(
            std::io::stderr().lock(),
            "\r[{}{}] {done}/{total}  {:.1} s ",
            "#".repeat(filled),
            ".".repeat(width - filled),
            self.start.elapsed().as_secs_f64()
        );
        self.shown = true;
    }

    /// Clears the bar, if shown.
    pub fn finish(&mut self) {
        if self.shown {
            let _ = write!(std::io::stderr().lock(), "\r{}\r", " ".repeat(60));
            self.shown = false;
        }
    }
}

/// `tdcr sweep`: solves every step, writes the CSV (the steps before a failure too) and the
/// picture.
pub fn run(args: &SweepArgs) -> Result<(), Failure> {
    if let Some(path) = &args.plot {
        picture_format(path)?;
    }
    let (name, mut file) = read_robot(&args.file)?;
    apply(&mut file, &args.solver);
    let steps = args.tension.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
    if steps < 2 {
        return Err(Failure::Input(
            "sweep needs at least one range with COUNT >= 2, e.g. --tension 1=0:6:61".into(),
        ));
    }
    if let Some((i, v)) = args.tension.iter().find(|(_, v)| v.len() != 1 && v.len() != steps) {
        return Err(Failure::Input(format!(
            "--tension {i}=... has {} values but another range has {steps}: give every range the same COUNT",
            v.len()
        )));
    }
    for (k, (i, _)) in args.tension.iter().enumerate() {
        if args.tension[..k].iter().any(|(j, _)| j == i) {
            return Err(Failure::Input(format!(
                "--tension {i}=... is given twice: give each tendon one range or value"
            )));
        }
    }
    for &(i, ref v) in &args.tension {
        set_tension(&mut file.robot, i, v[0])?;
    }
    let count = file.robot.tendons.len();
    let mut csv = String::from("step");
    for i in 1..=count {
        let _ = write!(csv, ",tension_{i}");
    }
    csv.push_str(
        ",tip_x,tip_y,tip_z,bending_angle_deg,iterations,load_steps,solve_time,intervals,tip_error_estimate\n",
    );
    let mut tips = Vec::with_capacity(steps);
    let (mut first, mut last): (Option<(Robot, Solution)>, Option<Solution>) = (None, None);
    let mut progress = Progress::new();
    let mut failure = None;
    for k in 0..steps {
        let mut robot = file.robot.clone();
        for &(i, ref v) in &args.tension {
            set_tension(&mut robot, i, v[if v.len() == 1 { 0 } else { k }])?;
        }
        let solution = match run_solver(&robot, &file, last.as_ref()) {
            Ok(s) => s,
            Err(f) => {
                let tensions: Vec<String> = robot
                    .tendons
                    .iter()
                    .map(|t| tdcr::Readable(t.tension).to_string())
                    .collect();
                let text = match f {
                    Failure::NotConverged(t) | Failure::Input(t) | Failure::Other(t) => t,
                    Failure::BrokenPipe => String::new(),
                };
                failure = Some(Failure::NotConverged(format!(
                    "sweep step {} of {steps} (tensions {} N) failed; the CSV holds the steps before it\n{text}",
                    k + 1,
                    tensions.join(", ")
                )));
                break;
            }
        };
        let tip = solution.tip_position();
        let _ = write!(csv, "{}", k + 1);
        for t in &robot.tendons {
            let _ = write!(csv, ",{}", t.tension);
        }
        let report = &solution.report;
        let _ = writeln!(
            csv,
            ",{},{},{},{},{},{},{},{},{}",
            output::number(tip.x),
            output::number(tip.y),
            output::number(tip.z),
            output::bending_angle(&solution).to_degrees(),
            report.iterations,
            report.load_steps,
            report.timings.total.as_secs_f64(),
            report.intervals,
            report
                .error_estimate
                .map_or(String::new(), |e| output::number(e.tip_position))
        );
        if args.solver.verbose {
            progress.finish();
            note(&format!("step {}: {}", k + 1, summary(report, file.robot.length())));
        }
        tips.push(tip);
        if first.is_none() {
            first = Some((robot.clone(), solution.clone()));
        }
        last = Some(solution);
        progress.update(k + 1, steps);
    }
    progress.finish();
    match &args.out {
        Some(path) => {
            write_file(path, &csv, "CSV")?;
            note(&format!("wrote {}", path.display()));
        }
        None => emit(&csv)?,
    }
    if let (Some(path), Some((robot0, first)), Some(last)) = (&args.plot, &first, &last) {
        let mut figure = Figure::new(&format!("{name}: tip trajectory over {} solves", tips.len()));
        let ranges: Vec<String> = args
            .tension
            .iter()
            .map(|(i, v)| format!("tendon {i}: {} to {} N", v[0], v[v.len() - 1]))
            .collect();
        figure.subtitle.push(ranges.join("; "));
        let mut start = Style::new("#999999");
        start.dash = Some("5 3".into());
        start.disks = args.disks;
        start.distributed_load = false;
        figure.add_shape(robot0, first, &start);
        let mut robot1 = file.robot.clone();
        for &(i, ref v) in &args.tension {
            set_tension(&mut robot1, i, v[(tips.len() - 1).min(v.len() - 1)])?;
        }
        let mut end = Style::new("#555555");
        end.disks = args.disks;
        figure.add_shape(&robot1, last, &end);
        figure.panel_mut().curves.push(tdcr::plot::Curve {
            points: tips.clone(),
            color: PALETTE[3].into(),
            width: 2.0,
            dash: None,
            opacity: 1.0,
        });
        figure
            .panel_mut()
            .markers
            .extend(tips.iter().map(|&point| tdcr::plot::Marker {
                point,
                color: PALETTE[3].into(),
                radius: 1.8,
            }));
        figure.legend = vec![
            LegendEntry::line("tip trajectory (a dot per solve)", PALETTE[3]).width(2.0),
            LegendEntry::line("first shape", "#999999").dash("5 3"),
            LegendEntry::line("last shape", "#555555"),
            LegendEntry::line("pulled tendons of each shape (thin lines)", "#555555").width(1.2),
        ];
        // Disks and loads of the last shape.
        let legend = shape_legend(&robot1, &end);
        let extra = legend.into_iter().filter(|e| e.symbol != tdcr::plot::Symbol::Line);
        figure.legend.extend(extra);
        write_picture(path, &figure, "plot")?;
    }
    failure.map_or(Ok(()), Err)
}
