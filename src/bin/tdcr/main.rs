//! The `tdcr` command: solve robot files from the shell (docs/cli.md).
//!
//! With no arguments it runs the main job: the paper's prototype under all 32 experiments of
//! Table 2, one table on standard output and a picture of all shapes in `./out/`.
//! Exit codes: 0 success, 2 bad input, 3 did not converge, 1 anything else.

mod bench;
mod calibrate;

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::fmt::Write as _;
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};
use tdcr::Iteration;
use tdcr::io::{RobotFile, output};
use tdcr::plot::{Figure, LegendEntry, PALETTE, Style};
use tdcr::{Error, Method, Robot, Routing, Solution, SolveReport, cases, collocation, shooting};

/// Shape of tendon-driven continuum robots under load.
#[derive(Parser)]
#[command(
    name = "tdcr",
    version,
    args_conflicts_with_subcommands = true,
    after_help = "Without a command: solve the paper's prototype under the 32 experiments of Table 2, \
                  print a table and draw every shape into OUT_DIR.\n\
                  Exit codes: 0 success, 2 bad input, 3 did not converge, 1 anything else.\n\
                  Robot files: docs/robot-file.md; this command: docs/cli.md."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Folder for the main job's picture and table (created if missing).
    #[arg(long, value_name = "DIR", default_value = "out")]
    out_dir: PathBuf,
}

#[derive(Subcommand)]
enum Command {
    /// Solve one robot file.
    Solve(SolveArgs),
    /// Solve a sequence of robots (tension ranges), each warm-started from the last; CSV out.
    Sweep(SweepArgs),
    /// Check a robot file and explain every problem.
    Check {
        /// Robot file (TOML; `-` reads standard input).
        file: String,
    },
    /// Print the prototype (tendon 1 at 2.94 N) as a commented robot file to start from.
    Example,
    /// Time the reference cases S and H, cold and warm (docs/benchmarks.md).
    Bench(bench::BenchArgs),
    /// Fit E and the base XYZ Euler angles to measured tip positions (docs/calibration.md).
    Calibrate(calibrate::CalibrateArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    /// Sparse collocation with Newton (the main solver).
    Collocation,
    /// Shooting from the base (the independent cross-check).
    Shooting,
}

#[derive(Clone, Copy, Default, ValueEnum)]
enum Format {
    /// A table for people.
    #[default]
    Table,
    /// JSON (fields in docs/cli.md).
    Json,
    /// CSV, one row per sample.
    Csv,
}

/// Options shared by `solve` and `sweep`.
#[derive(Args)]
struct SolverArgs {
    /// Tip force (N, world frame), replacing the file's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    tip_force: Option<[f64; 3]>,
    /// Tip moment (N m, world frame), replacing the file's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    tip_moment: Option<[f64; 3]>,
    /// Solver, replacing the file's `[solver] method`.
    #[arg(long, value_enum)]
    method: Option<MethodArg>,
    /// A fixed mesh of N intervals (no refinement; Newton still converges fully). With
    /// --tol, the starting mesh.
    #[arg(long, value_name = "N", value_parser = parse_count)]
    nodes: Option<usize>,
    /// Refine the mesh adaptively until the estimated tip position error is below T (m).
    #[arg(long, value_name = "T", value_parser = parse_positive)]
    tol: Option<f64>,
    /// Print the solver's per-iteration table and counts to standard error.
    #[arg(short, long)]
    verbose: bool,
}

#[derive(Args)]
struct SolveArgs {
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

#[derive(Args)]
struct SweepArgs {
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
    /// Draw the tip trajectory (with the first and last shapes) into FILE.svg.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
}

fn parse_number(text: &str, what: &str) -> Result<f64, String> {
    let x: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number ({what})"))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("`{text}` is not finite ({what})"))
    }
}

fn parse_vector(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("`{text}` needs three comma-separated numbers X,Y,Z"));
    }
    let mut v = [0.0; 3];
    for (x, part) in v.iter_mut().zip(parts) {
        *x = parse_number(part, "a component")?;
    }
    Ok(v)
}

/// The most values a count option accepts (sweep steps, output samples): each costs memory
/// and a line of output.
const MAX_COUNT: usize = 1_000_000;

fn parse_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(format!("`{text}` is not a whole number from 1 to {MAX_COUNT}")),
    }
}

fn parse_samples(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (2..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{text}` is not a whole number from 2 (the ends count) to {MAX_COUNT}"
        )),
    }
}

fn parse_positive(text: &str) -> Result<f64, String> {
    let x = parse_number(text, "a tolerance in m")?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("`{text}` must be positive"))
    }
}

fn parse_tendon(text: &str) -> Result<(usize, &str), String> {
    let (index, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}` must look like I=NEWTONS, e.g. 1=2.94"))?;
    let index = parse_count(index.trim()).map_err(|_| format!("tendon number `{index}` must be 1 or more"))?;
    Ok((index, value))
}

fn parse_tension(text: &str) -> Result<(usize, f64), String> {
    let (index, value) = parse_tendon(text)?;
    let tension = parse_number(value, "a tension in N")?;
    if tension < 0.0 {
        return Err(format!("tension {tension} N is negative: a tendon can only pull"));
    }
    Ok((index, tension))
}

fn parse_sweep(text: &str) -> Result<(usize, Vec<f64>), String> {
    let (index, value) = parse_tendon(text)?;
    let parts: Vec<&str> = value.split(':').collect();
    let values = match parts.as_slice() {
        [single] => vec![parse_number(single, "a tension in N")?],
        [start, stop, count] => {
            let (a, b) = (parse_number(start, "START")?, parse_number(stop, "STOP")?);
            let count = parse_count(count).map_err(|e| format!("COUNT: {e}"))?;
            if count == 1 {
                vec![a]
            } else {
                (0..count)
                    .map(|k| a + (b - a) * k as f64 / (count - 1) as f64)
                    .collect()
            }
        }
        _ => return Err(format!("`{text}` must look like I=START:STOP:COUNT or I=NEWTONS")),
    };
    if values.iter().any(|&t| t < 0.0) {
        return Err(format!("`{text}` has negative tensions: a tendon can only pull"));
    }
    Ok((index, values))
}

/// Why the command stopped, and its exit code.
enum Failure {
    /// Bad input: a file, an option, a value (exit 2).
    Input(String),
    /// A solver did not converge (exit 3).
    NotConverged(String),
    /// Anything else, e.g. an output file that cannot be written (exit 1).
    Other(String),
    /// Standard output was closed by the reader (`tdcr | head`): stop quietly (exit 0).
    BrokenPipe,
}

impl Failure {
    fn code(&self) -> u8 {
        match self {
            Failure::Input(_) => 2,
            Failure::NotConverged(_) => 3,
            Failure::Other(_) => 1,
            Failure::BrokenPipe => 0,
        }
    }

    fn print(&self) {
        let text = match self {
            Failure::Input(t) | Failure::NotConverged(t) | Failure::Other(t) => t,
            Failure::BrokenPipe => return,
        };
        let mut err = std::io::stderr().lock();
        for line in text.lines() {
            // Indented lines continue the message above them (diagnostics, hints).
            let prefix = if line.starts_with(' ') { "" } else { "error: " };
            let _ = writeln!(err, "{prefix}{line}");
        }
    }
}

/// A solver error as a failure: input problems exit 2, solver failures 3, the rest 1.
fn solver_failure(e: Error) -> Failure {
    let text = e.to_string();
    if let Error::NotConverged { report, .. } = &e {
        return Failure::NotConverged(format!("{text}\n{}", diagnostics(report)));
    }
    if matches!(e, Error::IntervalCap { .. } | Error::Breakdown { .. }) {
        Failure::NotConverged(text)
    } else if matches!(e, Error::InvalidInput { .. } | Error::SingularRouting { .. }) {
        Failure::Input(text)
    } else {
        Failure::Other(text)
    }
}

/// Standard error, ignoring write errors (there is nowhere left to report them).
fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// Writes to standard output; a closed pipe stops the command quietly.
fn emit(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(Failure::BrokenPipe),
        Err(e) => Err(Failure::Other(format!("cannot write to standard output: {e}"))),
    }
}

fn write_file(path: &Path, text: &str, what: &str) -> Result<(), Failure> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::Other(format!("cannot create folder {} for the {what}: {e}", dir.display())))?;
    }
    std::fs::write(path, text)
        .map_err(|e| Failure::Other(format!("cannot write the {what} to {}: {e}", path.display())))
}

fn main() -> ExitCode {
    // clap prints usage errors and exits 2 itself (0 for --help and --version).
    let cli = Cli::parse();
    let result = match cli.command {
        None => main_job(&cli.out_dir),
        Some(Command::Solve(args)) => solve(&args),
        Some(Command::Sweep(args)) => sweep(&args),
        Some(Command::Check { file }) => check(&file),
        Some(Command::Example) => emit(&tdcr::io::example()),
        Some(Command::Bench(args)) => bench::run(&args)
            .map_err(Failure::NotConverged)
            .and_then(|text| emit(&text)),
        Some(Command::Calibrate(args)) => calibrate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            failure.print();
            ExitCode::from(failure.code())
        }
    }
}

// ---------------------------------------------------------------------------------------
// Reading robot files and applying command-line overrides

/// Reads and checks a robot file (`-`: standard input); every problem is one message line.
fn read_robot(file: &str) -> Result<(String, RobotFile), Failure> {
    let (name, text) = if file == "-" {
        let mut text = String::new();
        std::io::stdin()
            .read_to_string(&mut text)
            .map_err(|e| Failure::Input(format!("cannot read the robot file from standard input: {e}")))?;
        ("<stdin>".to_string(), text)
    } else {
        let text =
            std::fs::read_to_string(file).map_err(|e| Failure::Input(format!("cannot read robot file {file}: {e}")))?;
        (file.to_string(), text)
    };
    let robot = tdcr::io::parse(&text, &name).map_err(|e| Failure::Input(e.to_string()))?;
    Ok((name, robot))
}

fn set_tension(robot: &mut Robot, index: usize, tension: f64) -> Result<(), Failure> {
    let count = robot.tendons.len();
    match robot.tendons.get_mut(index.wrapping_sub(1)) {
        Some(t) => {
            t.tension = tension;
            Ok(())
        }
        None => Err(Failure::Input(format!(
            "--tension {index}=...: the robot has {count} tendon(s), numbered 1 to {count} in file order"
        ))),
    }
}

fn apply(file: &mut RobotFile, args: &SolverArgs) {
    let robot = &mut file.robot;
    if let Some(f) = args.tip_force {
        robot.loads.tip_force = f.into();
    }
    if let Some(m) = args.tip_moment {
        robot.loads.tip_moment = m.into();
    }
    let settings = &mut file.solver;
    match args.method {
        Some(MethodArg::Collocation) => settings.method = Method::Collocation,
        Some(MethodArg::Shooting) => settings.method = Method::Shooting,
        None => {}
    }
    let c = &mut settings.collocation;
    if let Some(n) = args.nodes {
        c.intervals = n;
        c.max_intervals = c.max_intervals.max(n);
        // --nodes alone means a fixed mesh, even if the file asks for refinement.
        if args.tol.is_none() {
            c.tolerance = None;
        }
    }
    if let Some(t) = args.tol {
        c.tolerance = Some(t);
    }
    if settings.method == Method::Shooting && (args.nodes.is_some() || args.tol.is_some()) {
        note("note: --nodes and --tol apply to collocation only; shooting integrates adaptively");
    }
}

fn run_solver(robot: &Robot, file: &RobotFile, warm: Option<&Solution>) -> Result<Solution, Failure> {
    let s = &file.solver;
    match (s.method, warm) {
        (Method::Collocation, None) => collocation::solve(robot, &s.collocation),
        (Method::Collocation, Some(w)) => collocation::solve_from(robot, &s.collocation, w),
        (Method::Shooting, _) => shooting::solve(robot, &s.shooting),
    }
    .map_err(solver_failure)
}

// ---------------------------------------------------------------------------------------
// Reports

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `x` with `decimals` decimals, right-aligned in `width`, without a minus sign on a
/// value that rounds to zero.
fn fixed(x: f64, width: usize, decimals: usize) -> String {
    let scale = 10f64.powi(decimals as i32);
    let x = if (x * scale).round() == 0.0 { 0.0 } else { x };
    format!("{x:>width$.decimals$}")
}

fn history_table(history: &[Iteration]) -> String {
    let mut out = String::from("   iter   residual       step    damping  jacobian\n");
    for (k, it) in history.iter().enumerate() {
        let _ = writeln!(
            out,
            "  {:>5}  {:>9.3e}  {:>9.3e}  {:>9.4}  {}",
            k + 1,
            it.residual,
            it.step,
            it.damping,
            if it.fresh_jacobian { "new" } else { "reused" }
        );
    }
    out
}

/// What a solver did, for `-v` and for failures (indented: continuation lines).
fn diagnostics(report: &SolveReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "  termination: {}", report.termination);
    let _ = writeln!(
        out,
        "  {} Newton iterations over {} load step(s) on {} mesh(es); final scaled residual {:.3e}",
        report.iterations, report.load_steps, report.meshes, report.residual
    );
    let _ = writeln!(
        out,
        "  {} intervals, {} unknowns, {} Jacobian non-zeros{}",
        report.intervals,
        report.unknowns,
        report.nonzeros,
        report
            .tip_error_estimate
            .map_or(String::new(), |e| format!(", estimated tip error {e:.2e} m"))
    );
    let e = &report.evaluations;
    let _ = writeln!(
        out,
        "  evaluations: {} residuals, {} Jacobians, {} of eq. 13",
        e.residual, e.jacobian, e.equations
    );
    let t = &report.timings;
    let _ = writeln!(
        out,
        "  time: assembly {:.2} ms, factorization {:.2} ms, solve {:.2} ms, total {:.2} ms",
        ms(t.assembly),
        ms(t.factorization),
        ms(t.solve),
        ms(t.total)
    );
    if !report.history.is_empty() {
        let _ = writeln!(out, "  last Newton run (scaled max-norms):");
        out.push_str(&history_table(&report.history));
    }
    out
}

fn summary(report: &SolveReport, settings: &tdcr::io::SolverSettings) -> String {
    let mesh = match (report.method, settings.collocation.tolerance) {
        (Method::Shooting, _) => format!("{} integration steps", report.intervals),
        (Method::Collocation, None) => format!("a fixed mesh of {} intervals", report.intervals),
        (Method::Collocation, Some(t)) => format!(
            "an adaptive mesh of {} intervals (tip tolerance {t:.1e} m, estimate {})",
            report.intervals,
            report.tip_error_estimate.map_or("n/a".into(), |e| format!("{e:.1e} m"))
        ),
    };
    format!(
        "{} on {mesh}: converged in {} Newton iterations ({} load step(s)), scaled residual {:.1e}, {:.1} ms",
        report.method,
        report.iterations,
        report.load_steps,
        report.residual,
        ms(report.timings.total)
    )
}

fn solution_table(name: &str, file: &RobotFile, solution: &Solution, samples: &[output::Sample]) -> String {
    let tip = solution.tip();
    let tangent = tip.R.column(2);
    let mut out = String::new();
    let _ = writeln!(out, "{name}: {}", summary(&solution.report, &file.solver));
    let row = |v: [f64; 3], w: usize, d: usize| v.map(|x| fixed(x, w, d)).join(" ");
    let _ = writeln!(out, "tip position (mm):     {}", row((tip.p * 1e3).into(), 10, 4));
    let _ = writeln!(
        out,
        "tip tangent R(L) e3:   {}",
        row(tangent.into_owned().into(), 10, 6)
    );
    let _ = writeln!(
        out,
        "bending angle (deg):   {}",
        fixed(output::bending_angle(solution).to_degrees(), 10, 4)
    );
    let _ = writeln!(
        out,
        "\n{:>9} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "s/mm", "x/mm", "y/mm", "z/mm", "nx/N", "ny/N", "nz/N", "mx/N mm", "my/N mm", "mz/N mm"
    );
    for x in samples {
        let _ = writeln!(
            out,
            "{} {} {} {}",
            fixed(x.s * 1e3, 9, 3),
            row((x.p * 1e3).into(), 10, 4),
            row(x.n.into(), 10, 5),
            row((x.m * 1e3).into(), 10, 4)
        );
    }
    out
}

fn describe(routing: &Routing) -> String {
    match routing {
        Routing::Straight { x, y } => format!("straight ({:.3}, {:.3}) mm", x * 1e3, y * 1e3)
            .replace(".000", "")
            .replace("-0)", "0)"),
        Routing::Helical { radius, turns, .. } => {
            let plural = if turns.abs() == 1.0 { "" } else { "s" };
            format!("helix, {turns} turn{plural}, {:.3} mm", radius * 1e3).replace(".000", "")
        }
        Routing::Custom(_) => "custom routing".into(),
    }
}

// ---------------------------------------------------------------------------------------
// Commands

fn check(file: &str) -> Result<(), Failure> {
    let (name, parsed) = read_robot(file)?;
    let r = &parsed.robot;
    let pulled = r.tendons.iter().filter(|t| t.tension > 0.0).count();
    emit(&format!(
        "{name}: OK: a {:.4} m rod with {} tendon(s) ({pulled} pulled), {} point load(s); solver: {}\n",
        r.length(),
        r.tendons.len(),
        r.loads.point.len(),
        parsed.solver.method
    ))
}

fn solve(args: &SolveArgs) -> Result<(), Failure> {
    let (name, mut file) = read_robot(&args.file)?;
    for &(i, t) in &args.tension {
        set_tension(&mut file.robot, i, t)?;
    }
    apply(&mut file, &args.solver);
    let solution = run_solver(&file.robot, &file, None)?;
    if args.jacobian && !matches!(args.format, Format::Json) {
        note("note: --jacobian adds the tip Jacobians to the JSON output only (--format json)");
    }
    if args.solver.verbose {
        note(&format!("{name}: {}", summary(&solution.report, &file.solver)));
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
        figure.subtitle.push(summary(&solution.report, &file.solver));
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

/// A progress bar on standard error, shown only on a terminal and only once the work has
/// taken longer than [`Progress::DELAY`].
struct Progress {
    start: Instant,
    shown: bool,
    terminal: bool,
}

impl Progress {
    /// Half a second: shorter runs finish before a bar would be worth reading.
    const DELAY: Duration = Duration::from_millis(500);

    fn new() -> Self {
        Progress {
            start: Instant::now(),
            shown: false,
            terminal: std::io::stderr().is_terminal(),
        }
    }

    fn update(&mut self, done: usize, total: usize) {
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

    fn finish(&mut self) {
        if self.shown {
            let _ = write!(std::io::stderr().lock(), "\r{}\r", " ".repeat(60));
            self.shown = false;
        }
    }
}

fn sweep(args: &SweepArgs) -> Result<(), Failure> {
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
    for &(i, ref v) in &args.tension {
        set_tension(&mut file.robot, i, v[0])?;
    }
    let count = file.robot.tendons.len();
    let mut csv = String::from("step");
    for i in 1..=count {
        let _ = write!(csv, ",tension_{i}");
    }
    csv.push_str(",tip_x,tip_y,tip_z,bending_angle_deg,iterations,load_steps,solve_time\n");
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
                let tensions: Vec<String> = robot.tendons.iter().map(|t| format!("{}", t.tension)).collect();
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
            ",{},{},{},{},{},{},{}",
            output::number(tip.x),
            output::number(tip.y),
            output::number(tip.z),
            output::bending_angle(&solution).to_degrees(),
            report.iterations,
            report.load_steps,
            report.timings.total.as_secs_f64()
        );
        if args.solver.verbose {
            progress.finish();
            note(&format!("step {}: {}", k + 1, summary(report, &file.solver)));
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
        figure.add_shape(robot0, first, &start);
        let mut robot1 = file.robot.clone();
        for &(i, ref v) in &args.tension {
            set_tension(&mut robot1, i, v[(tips.len() - 1).min(v.len() - 1)])?;
        }
        figure.add_shape(&robot1, last, &Style::new("#555555"));
        figure.curves.push(tdcr::plot::Curve {
            points: tips.clone(),
            color: PALETTE[3].into(),
            width: 2.0,
            dash: None,
            opacity: 1.0,
        });
        figure.markers.extend(tips.iter().map(|&point| tdcr::plot::Marker {
            point,
            color: PALETTE[3].into(),
            radius: 1.8,
        }));
        for (label, color, dash) in [
            ("tip trajectory", PALETTE[3], None),
            ("first shape", "#999999", Some("5 3")),
            ("last shape", "#555555", None),
        ] {
            figure.legend.push(LegendEntry {
                label: label.into(),
                color: color.into(),
                dash: dash.map(Into::into),
            });
        }
        write_file(path, &figure.to_svg(), "plot")?;
        note(&format!("wrote {}", path.display()));
    }
    failure.map_or(Ok(()), Err)
}

/// Styles of the main job's picture: colour by tendon, dash by tip load.
fn table2_style(e: &cases::Experiment) -> Style {
    let color = e.tendon.map_or("#000000", |i| PALETTE[(i - 1) % PALETTE.len()]);
    let mut style = Style::new(color);
    style.dash = if e.tip_load == 0.0 {
        None
    } else if e.tip_load < 0.15 {
        Some("7 3".into())
    } else {
        Some("2 2".into())
    };
    style
}

fn main_job(out_dir: &Path) -> Result<(), Failure> {
    let start = Instant::now();
    let experiments = cases::table2();
    let options = collocation::Options::default();
    let routings = cases::prototype_routings();
    emit(&format!(
        "The prototype of Rucker & Webster (2011, section 5) under the {} experiments of Table 2\n\
         collocation on a fixed mesh of {} intervals (tdcr::collocation::Options::default()); tip in mm, world frame\n\n",
        experiments.len(),
        options.intervals
    ))?;
    let header = format!(
        "{:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>5} {:>7}\n\
         {:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>5} {:>7}\n",
        "#",
        "configuration",
        "tendon",
        "tension",
        "tip load",
        "tip x",
        "tip y",
        "tip z",
        "bend",
        "iters",
        "time",
        "",
        "",
        "",
        "N",
        "N",
        "mm",
        "mm",
        "mm",
        "deg",
        "",
        "ms"
    );
    emit(&header)?;
    let mut csv = String::from(
        "experiment,configuration,tendon,tension,tip_load,tip_x,tip_y,tip_z,bending_angle_deg,iterations,intervals,solve_time\n",
    );
    let mut figure = Figure::new("The prototype under the 32 experiments of Table 2 (Rucker & Webster 2011)");
    let mut failures = Vec::new();
    let mut solver_time = Duration::ZERO;
    let mut intervals = Vec::new();
    for (k, e) in experiments.iter().enumerate() {
        let robot = e.robot();
        let tendon = e
            .tendon
            .map_or("-".to_string(), |i| format!("{i}: {}", describe(&routings[i - 1])));
        let row = match collocation::solve(&robot, &options) {
            Ok(solution) => {
                let tip = solution.tip_position();
                let bend = output::bending_angle(&solution).to_degrees();
                let report = &solution.report;
                solver_time += report.timings.total;
                intervals.push(report.intervals);
                let _ = writeln!(
                    csv,
                    "{},\"{}\",{},{},{},{},{},{},{},{},{},{}",
                    k + 1,
                    e.label(),
                    e.tendon.map_or(String::new(), |i| i.to_string()),
                    e.tension,
                    e.tip_load,
                    output::number(tip.x),
                    output::number(tip.y),
                    output::number(tip.z),
                    bend,
                    report.iterations,
                    report.intervals,
                    report.timings.total.as_secs_f64()
                );
                let line = format!(
                    "{:>3}  {:<24} {:<27} {:>7.2} {:>8.3} {} {} {} {:>7.2} {:>5} {:>7.1}\n",
                    k + 1,
                    e.label(),
                    tendon,
                    e.tension,
                    e.tip_load,
                    fixed(tip.x * 1e3, 9, 2),
                    fixed(tip.y * 1e3, 9, 2),
                    fixed(tip.z * 1e3, 9, 2),
                    bend,
                    report.iterations,
                    ms(report.timings.total)
                );
                figure.add_shape(&robot, &solution, &table2_style(e));
                line
            }
            Err(err) => {
                failures.push(format!("experiment {} ({}): {err}", k + 1, e.label()));
                format!(
                    "{:>3}  {:<24} {:<27} {:>7.2} {:>8.3}  did not solve: {err}\n",
                    k + 1,
                    e.label(),
                    tendon,
                    e.tension,
                    e.tip_load
                )
            }
        };
        emit(&row)?;
    }
    intervals.sort_unstable();
    intervals.dedup();
    let mesh = match intervals.as_slice() {
        [n] => format!("{n} intervals each"),
        _ => format!("{:?} intervals", intervals),
    };
    emit(&format!(
        "\n{} of {} solved ({mesh}); solver time {:.0} ms, wall time {:.0} ms\n",
        experiments.len() - failures.len(),
        experiments.len(),
        ms(solver_time),
        ms(start.elapsed())
    ))?;

    figure.subtitle.push(format!(
        "collocation, {mesh}; colour: the tendon pulled (0.98 to 6.87 N); dash: the tip load"
    ));
    figure.legend.push(LegendEntry {
        label: "no tension".into(),
        color: "#000000".into(),
        dash: None,
    });
    for (i, routing) in routings.iter().enumerate() {
        figure.legend.push(LegendEntry {
            label: format!("tendon {}: {}", i + 1, describe(routing)),
            color: PALETTE[i].into(),
            dash: None,
        });
    }
    for (label, dash) in [
        ("no tip load", None),
        ("0.098 N tip load (10 g)", Some("7 3")),
        ("0.196 N tip load (20 g)", Some("2 2")),
    ] {
        figure.legend.push(LegendEntry {
            label: label.into(),
            color: "#666666".into(),
            dash: dash.map(Into::into),
        });
    }
    let svg_path = out_dir.join("table2.svg");
    let csv_path = out_dir.join("table2.csv");
    write_file(&svg_path, &figure.to_svg(), "picture")?;
    write_file(&csv_path, &csv, "table")?;
    emit(&format!(
        "picture of all shapes: {}\ntable as CSV (SI units): {}\n",
        svg_path.display(),
        csv_path.display()
    ))?;
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Failure::NotConverged(failures.join("\n")))
    }
}
