//! `tdcr sweep`: a sequence of robots over tension, pull-in or other input ranges, solved by
//! the library's sweep (`tdcr::analysis::sweep`: each solve warm-started from the last, the
//! snaps, bifurcations and taut/slack tendons between steps located); CSV out, optionally
//! the tip trajectory as a picture.

use clap::Args;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tdcr::analysis::sweep::{Input, Kind, Ranges, Sweep, SweepSolver};
use tdcr::{Parameter, Robot, Solution};

use crate::args::{SolverArgs, parse_disks, parse_displacement_sweep, parse_param_sweep, parse_sweep};
use crate::failure::{Failure, emit, note, picture_format, write_file, write_picture};
use crate::failure::{solver_failure, with_likely_causes};
use crate::robot_args::{FrictionArgs, apply, read_robot, set_displacement, set_tension};
use crate::sweep_csv::{header, row};
use crate::sweep_picture::{Drawn, Shape, chosen, picture};
use crate::tables::summary;

/// The arguments of `tdcr sweep`.
#[derive(Args)]
pub struct SweepArgs {
    /// Robot file (TOML; `-` reads standard input).
    file: String,
    /// Tension of tendon I (from 1): `I=START:STOP:COUNT` (COUNT evenly spaced values, N) or a
    /// fixed `I=NEWTONS`. Repeatable; every range must have the same COUNT.
    #[arg(long, value_name = "I=START:STOP:COUNT", value_parser = parse_sweep, required_unless_present_any = ["param", "displacement"])]
    tension: Vec<(usize, Vec<f64>)>,
    /// Actuator pull-in of tendon I (from 1), which makes it displacement-controlled (its
    /// tension solved): `I=START:STOP:COUNT` (COUNT evenly spaced values, m; negative
    /// releases it) or a fixed `I=METRES`. Repeatable; every range must have the same COUNT.
    /// The CSV gets a `displacement.I` column, and `tension.I` holds the solved tension.
    #[arg(long, value_name = "I=START:STOP:COUNT", value_parser = parse_displacement_sweep, allow_hyphen_values = true)]
    pub(crate) displacement: Vec<(usize, Vec<f64>)>,
    /// Any other input: `NAME=START:STOP:COUNT` or `NAME=VALUE`, NAME one of
    /// `tension.I` (N), `tip_force.x|y|z` (N), `tip_moment.x|y|z` (N m),
    /// `base_position.x|y|z` (m), `distributed_force.x|y|z` (N/m, that component at every s),
    /// `load_scale` or `youngs_modulus` (Pa) (docs/parameters.md). Repeatable, with the same
    /// COUNT as every other range.
    #[arg(long, value_name = "NAME=START:STOP:COUNT", value_parser = parse_param_sweep, allow_hyphen_values = true)]
    param: Vec<(String, Vec<f64>)>,
    #[command(flatten)]
    friction: FrictionArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Warm-start the first step from a saved solution: the JSON of `tdcr solve --format
    /// json` for this robot.
    #[arg(long, value_name = "SOLUTION.json", conflicts_with = "history")]
    start: Option<PathBuf>,
    /// Solve the steps as a load history with stick/slip friction, each from the tendon
    /// state the last left (docs/friction.md): `up-down` (every range up, then back down)
    /// or the swept input's values in order, `V1,V2,...`. The CSV gets the direction of
    /// each step and each tendon with friction's delivered tension and zones; `--plot`
    /// draws the hysteresis loop.
    #[arg(long, value_name = "up-down|V1,V2,...", value_parser = crate::history::parse_history)]
    history: Option<crate::history::History>,
    /// Write the CSV to FILE instead of standard output (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Draw the tip trajectory (with the first and last shapes) into FILE: PNG if its name
    /// ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
    /// The y axis of a history's loop (`--history` with `--plot`): `tip_displacement` (the
    /// tip's distance from the first step, mm; the default), `bending_angle` (deg), or
    /// `tip_x`, `tip_y`, `tip_z` (mm).
    #[arg(long, value_name = "NAME", value_parser = crate::history::parse_loop_axis, requires_all = ["history", "plot"])]
    loop_y: Option<tdcr::analysis::history::LoopAxis>,
    /// Spacer disks drawn on the first and last shapes of the picture (default: about 2.5
    /// tendon offsets apart, 12 on the prototype; 0: none).
    #[arg(long, value_name = "N", value_parser = parse_disks, requires = "plot")]
    disks: Option<usize>,
    /// Shapes drawn in the picture: N evenly spaced steps including the first and last
    /// (default 2), or `all`. Snaps are always drawn with the shapes either side.
    #[arg(long, value_name = "N|all", value_parser = parse_shapes, default_value = "2", requires = "plot")]
    shapes: Shapes,
    #[command(flatten)]
    picture: crate::picture::PictureArgs,
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

    /// Shows `done` of `total` steps, the rate and the time left (on a terminal, after
    /// [`Progress::DELAY`]).
    pub fn update(&mut self, done: usize, total: usize) {
        let elapsed = self.start.elapsed().as_secs_f64();
        if !self.terminal || elapsed < Self::DELAY.as_secs_f64() {
            return;
        }
        let width = 30;
        let filled = width * done / total.max(1);
        let rate = done as f64 / elapsed;
        let left = if rate > 0.0 {
            format!("{:.0} s left", total.saturating_sub(done) as f64 / rate)
        } else {
            String::new()
        };
        let _ = write!(
            std::io::stderr().lock(),
            "\r[{}{}] {done}/{total}  {elapsed:.1} s, {rate:.0}/s, {left} ",
            "#".repeat(filled),
            ".".repeat(width - filled),
        );
        self.shown = true;
    }

    /// Clears the bar, if shown.
    pub fn finish(&mut self) {
        if self.shown {
            let _ = write!(std::io::stderr().lock(), "\r{}\r", " ".repeat(90));
            self.shown = false;
        }
    }
}

/// The ranges of a sweep: the `--param` inputs parsed for the robot, and the number of steps.
pub(crate) struct Plan<'a> {
    /// The `--param` inputs and their values.
    pub(crate) params: Vec<(Parameter, &'a Vec<f64>)>,
    /// The number of steps.
    steps: usize,
}

impl<'a> Plan<'a> {
    /// Checks the ranges of `args` for `robot`: at least one with COUNT >= 2, one COUNT for
    /// all, each tendon given once and by tension or pull-in, not both.
    fn new(args: &'a SweepArgs, robot: &Robot) -> Result<Self, Failure> {
        let params: Vec<(Parameter, &Vec<f64>)> = args
            .param
            .iter()
            .map(|(name, v)| {
                Parameter::parse(name, robot)
                    .map(|p| (p, v))
                    .map_err(|e| Failure::Input(format!("--param {name}=...: {e}")))
            })
            .collect::<Result<_, _>>()?;
        let lengths = args
            .tension
            .iter()
            .map(|(_, v)| v.len())
            .chain(args.displacement.iter().map(|(_, v)| v.len()))
            .chain(params.iter().map(|(_, v)| v.len()));
        let steps = lengths.clone().max().unwrap_or(0);
        let listed = matches!(args.history, Some(crate::history::History::Values(_)));
        if steps < 2 && !listed {
            return Err(Failure::Input(
                "sweep needs at least one range with COUNT >= 2, e.g. --tension 1=0:6:61, --displacement 1=0:0.004:41 \
                 or --param tip_force.z=0:-1:11"
                    .into(),
            ));
        }
        if let Some(n) = lengths.clone().find(|&n| n != 1 && n != steps) {
            return Err(Failure::Input(format!(
                "a range has {n} values but another has {steps}: give every range the same COUNT"
            )));
        }
        for (k, (i, _)) in args.tension.iter().enumerate() {
            if args.tension[..k].iter().any(|(j, _)| j == i) {
                return Err(Failure::Input(format!(
                    "--tension {i}=... is given twice: give each tendon one range or value"
                )));
            }
        }
        for (k, (i, _)) in args.displacement.iter().enumerate() {
            if args.displacement[..k].iter().any(|(j, _)| j == i) {
                return Err(Failure::Input(format!(
                    "--displacement {i}=... is given twice: give each tendon one range or value"
                )));
            }
            if args.tension.iter().any(|(j, _)| j == i) {
                return Err(Failure::Input(format!(
                    "--tension {i}=... and --displacement {i}=... both given: drive a tendon by its tension or by its \
                     displacement"
                )));
            }
        }
        for (k, (p, _)) in params.iter().enumerate() {
            let given = |ranges: &[(usize, Vec<f64>)], t: usize| ranges.iter().any(|(j, _)| *j == t + 1);
            let by_option = match *p {
                Parameter::Tension(t) if given(&args.tension, t) => Some(("--tension", t + 1)),
                Parameter::Displacement(t) if given(&args.displacement, t) => Some(("--displacement", t + 1)),
                _ => None,
            };
            let twice = match by_option {
                Some((option, i)) => Some(format!("{option} {i}=... and --param {p}=... both set {p}")),
                None => params[..k]
                    .iter()
                    .any(|(q, _)| q == p)
                    .then(|| format!("--param {p}=... is given twice")),
            };
            if let Some(twice) = twice {
                return Err(Failure::Input(format!("{twice}: give each input one range or value")));
            }
            if let Parameter::Tension(t) = p
                && args.displacement.iter().any(|(j, _)| *j == t + 1)
            {
                return Err(Failure::Input(format!(
                    "--displacement {}=... and --param {p}=... both given: drive a tendon by its tension or by its \
                     displacement",
                    t + 1
                )));
            }
        }
        Ok(Plan { params, steps })
    }

    /// The library's ranges of the sweep on `base`: the tensions, the pull-ins, then the
    /// `--param` inputs (the order [`Plan::robot`] sets them in).
    fn ranges(&self, args: &SweepArgs, base: &Robot) -> Result<Ranges, Failure> {
        let inputs = args
            .tension
            .iter()
            .map(|(i, v)| (Input::Parameter(Parameter::Tension(i - 1)), v.clone()))
            .chain(
                args.displacement
                    .iter()
                    .map(|(i, v)| (Input::Displacement(i - 1), v.clone())),
            )
            .chain(self.params.iter().map(|(p, v)| (Input::Parameter(*p), (*v).clone())))
            .collect();
        Ranges::new(base.clone(), inputs).map_err(|e| Failure::Input(e.to_string()))
    }

    /// The robot of step `k` (from 0): `base` with every range at its k-th value.
    fn robot(&self, args: &SweepArgs, base: &Robot, k: usize) -> Result<Robot, Failure> {
        let mut robot = base.clone();
        for &(i, ref v) in &args.tension {
            set_tension(&mut robot, i, at(v, k))?;
        }
        for &(i, ref v) in &args.displacement {
            set_displacement(&mut robot, i, at(v, k))?;
        }
        let values = self.params.iter().map(|(p, v)| (*p, at(v, k)));
        Parameter::apply_all(&mut robot, values).map_err(|e| Failure::Input(e.to_string()))?;
        Ok(robot)
    }
}

/// The number of shapes a sweep picture draws (`--shapes`; `None`: all).
#[derive(Clone, Copy, Debug)]
struct Shapes(Option<usize>);

fn parse_shapes(text: &str) -> Result<Shapes, String> {
    match text {
        "all" => Ok(Shapes(None)),
        _ => match text.parse::<usize>() {
            Ok(n) if n >= 1 => Ok(Shapes(Some(n))),
            _ => Err(format!("`{text}` is not a number of shapes (1 or more) or `all`")),
        },
    }
}

/// The k-th value of a range, or its one value.
pub(crate) fn at(v: &[f64], k: usize) -> f64 {
    v[if v.len() == 1 { 0 } else { k }]
}

/// `tdcr sweep`: solves every step ([`tdcr::analysis::sweep::Sweep`]), writes the CSV (the
/// steps before a failure too) and the picture.
pub fn run(args: &SweepArgs) -> Result<(), Failure> {
    if let Some(path) = &args.plot {
        picture_format(path)?;
    }
    if args.history.is_some() && args.friction.gives_motion() {
        return Err(Failure::Input(
            "--motion has no effect with --history: each step decides stick and slip from the last step's \
             tendon state"
                .into(),
        ));
    }
    let (name, mut file) = read_robot(&args.file)?;
    // The file's warnings say what the file gives, before the options replace it.
    let read_warnings = file.warnings();
    apply(&mut file, &args.solver);
    args.friction.apply(&mut file.robot)?;
    let plan = Plan::new(args, &file.robot)?;
    let steps = plan.steps;
    for &(i, ref v) in &args.tension {
        set_tension(&mut file.robot, i, v[0])?;
    }
    for &(i, ref v) in &args.displacement {
        set_displacement(&mut file.robot, i, v[0])?;
    }
    crate::failure::warn_file(&name, &read_warnings, &file);
    // Every step's robot must be valid before any is solved (a pull-in longer than the
    // tendon's path, a negative modulus): bad input, exit 2, not a failed solve.
    for k in 0..steps {
        let robot = plan.robot(args, &file.robot, k)?;
        if let Err(e) = robot.validate() {
            return Err(Failure::Input(format!(
                "sweep step {} of {steps} ({}) is not a valid robot: {e}",
                k + 1,
                step_inputs(&robot)
            )));
        }
    }
    let mut csv = header(args, &plan, &file.robot);
    let start = args
        .start
        .as_deref()
        .map(|p| crate::robot_args::read_start(p, &file.robot))
        .transpose()?;
    let solver = match file.solver.method {
        tdcr::Method::Collocation => SweepSolver::Collocation(file.solver.collocation.clone()),
        tdcr::Method::Shooting => SweepSolver::Shooting(file.solver.shooting),
    };
    let inputs = plan.ranges(args, &file.robot)?;
    if let Some(h) = &args.history {
        if file.solver.method != tdcr::Method::Collocation {
            return Err(Failure::Input(
                "--history solves by collocation: leave out --method shooting (or the robot file's method)".into(),
            ));
        }
        let ranges = crate::history::steps(&inputs, &file.robot, h)?;
        return crate::history::run(
            &name,
            &ranges,
            &file.solver.collocation,
            crate::failure::out_path(&args.out),
            (args.plot.as_deref(), args.loop_y.unwrap_or_default()),
        );
    }
    let mut sweep = Sweep::new(&inputs, solver, start);
    let mut progress = Progress::new();
    let mut failure = None;
    let mut past_limit = PastLimits::default();
    let chosen = chosen(args.shapes.0, steps);
    let mut drawn = Drawn::default();
    let mut previous: Option<Shape> = None;
    while let Some(result) = sweep.step() {
        // The step just solved (or failed): the steps before it were solved.
        let k = drawn.tips.len();
        let robot = inputs.robot(k as f64).map_err(|e| Failure::Input(e.to_string()))?;
        let step = match result {
            Ok(step) => step,
            Err(e) => {
                failure = Some(step_failure(
                    with_likely_causes(solver_failure(e), &robot),
                    k,
                    steps,
                    &robot,
                ));
                break;
            }
        };
        past_limit.record(&robot, &step.solution, k, &name, &mut progress);
        for e in step.events.iter().filter(|e| matches!(e.kind, Kind::Snap { .. })) {
            progress.finish();
            note(&format!("warning: sweep step {}: {e}", k + 1));
            if let (true, Some(before)) = (args.plot.is_some(), previous.clone()) {
                let after = (robot.clone(), step.solution.clone());
                drawn.snaps.push((k, before, after, e.to_string()));
            }
        }
        // A bifurcation into an unstable state: on standard error too (the CSV's column alone
        // is easy to miss).
        for e in step.events.iter().filter(|e| {
            matches!(e.kind, Kind::Bifurcation { after, .. } if after.has_unstable_directions()
                || matches!(after, tdcr::analysis::sweep::Instability::Growing { .. }))
        }) {
            progress.finish();
            note(&format!("warning: sweep step {}: {e}", k + 1));
        }
        let event: Vec<String> = step.events.iter().map(ToString::to_string).collect();
        let event = event.join("; ");
        row(&mut csv, (args, &plan, &file.robot), k, &step.solution, &event);
        if args.solver.verbose {
            progress.finish();
            note(&format!(
                "step {}: {}",
                k + 1,
                summary(&step.solution.report, file.robot.length())
            ));
        }
        drawn.tips.push(step.solution.tip_position());
        if args.plot.is_some() {
            let shape = (robot, step.solution);
            if chosen.binary_search(&k).is_ok() {
                drawn.shapes.push((k, shape.clone()));
            }
            previous = Some(shape);
        }
        progress.update(k + 1, steps);
    }
    progress.finish();
    past_limit.summary(&name, drawn.tips.len());
    let csv = csv.finish();
    match crate::failure::out_path(&args.out) {
        Some(path) => {
            write_file(path, &csv, "CSV")?;
            note(&format!("wrote {}", path.display()));
        }
        None => emit(&csv)?,
    }
    if let Some(path) = &args.plot {
        // A sweep that failed part-way draws the steps it solved; the last of them is the
        // last shape.
        if let (Some(last), false) = (
            previous,
            drawn.shapes.last().is_some_and(|(k, _)| k + 1 == drawn.tips.len()),
        ) {
            drawn.shapes.push((drawn.tips.len() - 1, last));
        }
        if !drawn.tips.is_empty() {
            let title = format!("{name}: tip trajectory over {} solves", drawn.tips.len());
            let mut figure = picture(&title, ranges(args, &plan), args.disks, &drawn);
            args.picture.apply(&mut figure);
            write_picture(path, &figure, "plot")?;
        }
    }
    failure.map_or(Ok(()), Err)
}

/// A failed step's failure, its message headed by the step and its tendon inputs.
fn step_failure(f: Failure, k: usize, steps: usize, robot: &Robot) -> Failure {
    let head = format!("sweep step {} of {steps} ({})", k + 1, step_inputs(robot));
    // Exit 2 for bad input, as `solve` exits (the checks before the first solve should have
    // found it).
    f.headed(&head, "the CSV holds the steps before it")
}

/// The swept ranges, as the picture's subtitle says them.
fn ranges(args: &SweepArgs, plan: &Plan) -> String {
    let ranges: Vec<String> = args
        .tension
        .iter()
        .map(|(i, v)| format!("tendon {i}: {} to {} N", v[0], v[v.len() - 1]))
        .chain(
            args.displacement
                .iter()
                .map(|(i, v)| format!("tendon {i} pulled in: {} to {} mm", v[0] * 1e3, v[v.len() - 1] * 1e3)),
        )
        .chain(
            plan.params
                .iter()
                .map(|(p, v)| format!("{p}: {} to {} {}", v[0], v[v.len() - 1], p.unit())),
        )
        .collect();
    ranges.join("; ")
}

/// The tendons whose solved tension reached the geometric limit in a sweep: each is warned
/// about at its first such step and summed up at the end.
#[derive(Default)]
struct PastLimits(Vec<PastLimit>);

impl PastLimits {
    /// Records the solved tensions of step `k` (from 0), warning at a tendon's first step
    /// past its limit.
    fn record(&mut self, robot: &Robot, solution: &Solution, k: usize, name: &str, progress: &mut Progress) {
        for w in robot.solved_tensions(&solution.tensions()) {
            let tdcr::model::scales::Warning::SolvedTension { tendon, tension, .. } = w else {
                continue;
            };
            let limit = robot.geometric_limit(tendon);
            match self.0.iter_mut().find(|p| p.tendon == tendon) {
                Some(p) => {
                    p.steps += 1;
                    if tension > p.largest.1 {
                        p.largest = (k + 1, tension);
                    }
                    p.limits = (p.limits.0.min(limit), p.limits.1.max(limit));
                }
                None => {
                    progress.finish();
                    note(&format!("warning: {name}: sweep step {}: {w}", k + 1));
                    self.0.push(PastLimit {
                        tendon,
                        steps: 1,
                        first: k + 1,
                        largest: (k + 1, tension),
                        limits: (limit, limit),
                    });
                }
            }
        }
    }

    /// A line per tendon past its limit at more than one of the `solved` steps.
    fn summary(&self, name: &str, solved: usize) {
        for p in self.0.iter().filter(|p| p.steps > 1) {
            let limit = if p.limits.0 == p.limits.1 {
                format!("{} N", limit_text(p.limits.0))
            } else {
                format!("{} to {} N", limit_text(p.limits.0), limit_text(p.limits.1))
            };
            note(&format!(
                "warning: {name}: tendon {}: the solved tension was at or past the geometric limit ({limit}) in {} of \
                 the {solved} steps solved, from step {}; the largest {} N at step {}",
                p.tendon + 1,
                p.steps,
                p.first,
                limit_text(p.largest.1),
                p.largest.0
            ));
        }
    }
}

/// A tendon whose solved tension reached its geometric limit in a sweep.
struct PastLimit {
    /// The tendon (from 0).
    tendon: usize,
    /// The steps at or past the limit.
    steps: usize,
    /// The first of them (from 1).
    first: usize,
    /// The step (from 1) of the largest tension, and the tension (N).
    largest: (usize, f64),
    /// The smallest and largest limit EI / r^2 over those steps (N; a swept modulus moves it).
    limits: (f64, f64),
}

/// The tendon inputs of a sweep step, each tendon named: `tendon 1 pull-in 0.3 m, tendon 2
/// tension 0 N` (the first 8 tendons, then a count).
fn step_inputs(robot: &Robot) -> String {
    const SHOWN: usize = 8;
    let mut parts: Vec<String> = robot
        .tendons
        .iter()
        .take(SHOWN)
        .enumerate()
        .map(|(i, t)| match t.displacement() {
            Some(q) => format!("tendon {} pull-in {} m", i + 1, tdcr::Readable(q)),
            None => format!("tendon {} tension {} N", i + 1, tdcr::Readable(t.tension())),
        })
        .collect();
    if robot.tendons.len() > SHOWN {
        parts.push(format!("{} more tendons", robot.tendons.len() - SHOWN));
    }
    if parts.is_empty() {
        "no tendons".into()
    } else {
        parts.join(", ")
    }
}

/// A tension for a message as the warnings print it: 3 significant digits, whole newtons
/// from 100 N (a solved tension has many more digits).
fn limit_text(x: f64) -> String {
    if !(x.is_finite() && x != 0.0) {
        tdcr::Readable(x).to_string()
    } else if (100.0..1e5).contains(&x.abs()) {
        format!("{x:.0}")
    } else {
        let digits = 2 - x.abs().log10().floor() as i32;
        let scale = 10f64.powi(digits);
        tdcr::Readable((x * scale).round() / scale).to_string()
    }
}
