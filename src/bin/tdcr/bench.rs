//! `tdcr bench`: solve the reference cases S and H cold and warm many times at the default
//! (error-controlled) settings and report the median solve time, Newton iterations, the
//! solver's own tip error estimate next to the true error against the published reference
//! tips, and the mesh the solver chose, so anyone can measure what users get on their
//! machine (docs/benchmarks.md). Each solve is timed twice: wall-clock time and the CPU time
//! of the solving thread (Linux; the time the thread ran, which a shared machine's other
//! processes do not inflate the way they inflate wall time).

use super::args::parse_positive;
use clap::{Args, ValueEnum};
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::time::{Duration, Instant};
use tdcr::{Robot, Solution, cases, collocation};

/// Options of `tdcr bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Output format.
    #[arg(long, value_enum, default_value_t = BenchFormat::Table)]
    pub format: BenchFormat,
    /// Tip tolerance relative to the rod length, as `tdcr solve --tol` (default: the
    /// library's default, 1e-7).
    #[arg(long, value_name = "TOL", value_parser = parse_positive)]
    pub tol: Option<f64>,
    /// Timed solves per case and start (the median is reported).
    #[arg(long, default_value_t = 200, value_name = "N")]
    pub repeats: usize,
}

/// Output formats of `tdcr bench`.
#[derive(Clone, Copy, ValueEnum)]
pub enum BenchFormat {
    /// A table for people.
    Table,
    /// A JSON list of {case, start, median_seconds, median_cpu_seconds, iterations, newton_steps, chord_steps,
    /// tip_error_m, error_estimate_m, intervals, nodes}; `nodes` counts mesh points
    /// (intervals + 1); `median_cpu_seconds` is null where thread CPU time is not available.
    Json,
}

struct Row {
    case: &'static str,
    start: &'static str,
    median: Duration,
    cpu: Option<Duration>,
    iterations: usize,
    newton: usize,
    chord: usize,
    error: f64,
    estimate: Option<f64>,
    intervals: usize,
}

impl Row {
    fn of(
        case: &'static str,
        start: &'static str,
        (median, cpu): (Duration, Option<Duration>),
        solution: &Solution,
        reference: &Vector3<f64>,
    ) -> Self {
        Row {
            case,
            start,
            median,
            cpu,
            iterations: solution.report.iterations,
            newton: solution.report.newton_steps,
            chord: solution.report.chord_steps,
            error: (solution.tip_position() - reference).norm(),
            estimate: solution.report.error_estimate.map(|e| e.tip_position),
            intervals: solution.report.intervals,
        }
    }
}

/// The same robot with every tension scaled by `factor`.
fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.set_tension(t.tension() * factor);
    }
    r
}

/// CPU time the calling thread has run so far (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`), or
/// `None` where that clock is not available.
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn thread_cpu_time() -> Option<Duration> {
    /// `struct timespec` of 64-bit Linux.
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    unsafe extern "C" {
        fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
    }
    /// Linux's clock id of the calling thread's CPU time.
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = Timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `t` is a valid, writable `struct timespec`; the call writes only into it.
    let status = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) };
    (status == 0).then(|| Duration::new(t.tv_sec as u64, t.tv_nsec as u32))
}

/// CPU time the calling thread has run so far: not available on this platform.
#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn thread_cpu_time() -> Option<Duration> {
    None
}

/// Wall-clock and thread CPU time of one call of `f`, with its result.
fn timed<T>(f: impl FnOnce() -> T) -> (Duration, Option<Duration>, T) {
    let (c, t) = (thread_cpu_time(), Instant::now());
    let out = f();
    let wall = t.elapsed();
    let cpu = thread_cpu_time().zip(c).map(|(b, a)| b.saturating_sub(a));
    (wall, cpu, out)
}

/// Medians of wall and CPU times (`None` if any CPU time is missing).
struct Times {
    wall: Vec<Duration>,
    cpu: Option<Vec<Duration>>,
}

impl Times {
    fn with_capacity(n: usize) -> Self {
        Times {
            wall: Vec::with_capacity(n),
            cpu: Some(Vec::with_capacity(n)),
        }
    }

    fn push(&mut self, wall: Duration, cpu: Option<Duration>) {
        self.wall.push(wall);
        self.cpu = self.cpu.take().and_then(|mut v| {
            cpu.map(|c| {
                v.push(c);
                v
            })
        });
    }

    fn medians(self) -> (Duration, Option<Duration>) {
        let mid = |mut v: Vec<Duration>| {
            v.sort();
            v[v.len() / 2]
        };
        (mid(self.wall), self.cpu.map(mid))
    }
}

fn median(
    mut solve: impl FnMut() -> Result<Solution, tdcr::Error>,
    repeats: usize,
) -> Result<((Duration, Option<Duration>), Solution), tdcr::Error> {
    let mut times = Times::with_capacity(repeats);
    let mut last = solve()?;
    for _ in 0..repeats.max(1) {
        let (wall, cpu, out) = timed(&mut solve);
        last = out?;
        times.push(wall, cpu);
    }
    Ok((times.medians(), last))
}

/// The median times of a warm solve of `robot` by a solver that has just solved `previous`
/// (untimed, before every timed solve), starting from that solution.
fn median_warm(
    solver: &mut collocation::Solver,
    previous: &Robot,
    robot: &Robot,
    repeats: usize,
) -> Result<((Duration, Option<Duration>), Solution), tdcr::Error> {
    let mut times = Times::with_capacity(repeats);
    let mut last = solver.solve(previous)?;
    for _ in 0..repeats.max(1) {
        let guess = solver.solve(previous)?;
        let (wall, cpu, out) = timed(|| solver.solve_from(robot, &guess));
        last = out?;
        times.push(wall, cpu);
    }
    Ok((times.medians(), last))
}

/// Runs the benchmark; the text to print, or a message for a failed solve.
pub fn run(args: &BenchArgs) -> Result<String, String> {
    let options = collocation::Options {
        tolerance: args.tol.or(collocation::Options::default().tolerance),
        ..Default::default()
    };
    let mut rows = Vec::new();
    for (case, robot, tip) in [
        ("S", cases::case_s(), cases::TIP_S),
        ("H", cases::case_h(), cases::TIP_H),
    ] {
        let reference = Vector3::from(tip);
        let fail = |e: tdcr::Error| format!("case {case}: {e}");
        let (t, cold) = median(|| collocation::solve(&robot, &options), args.repeats).map_err(fail)?;
        rows.push(Row::of(case, "cold", t, &cold, &reference));
        // Warm: a solver that has just solved the robot at 0.99 times the tension (the step
        // of a sweep or a control loop) solves it at full tension from that solution.
        let previous = scaled(&robot, 0.99);
        let mut solver = collocation::Solver::new(options.clone());
        let (t, warm) = median_warm(&mut solver, &previous, &robot, args.repeats).map_err(fail)?;
        rows.push(Row::of(case, "warm", t, &warm, &reference));
    }
    let mut out = String::new();
    match args.format {
        BenchFormat::Table => {
            let _ = writeln!(
                out,
                "tdcr bench: collocation at tolerance {:.0e} L, median of {} solves each (wall and thread CPU time); the solver's \
                 estimate of its tip error next to the true error against the published reference tips",
                options.tolerance.unwrap_or(f64::NAN),
                args.repeats
            );
            let _ = writeln!(
                out,
                "case  start  median (ms)  CPU (ms)  Newton + chord steps  tip error (m)  estimate (m)  intervals"
            );
            for r in &rows {
                let _ = writeln!(
                    out,
                    "{:<4}  {:<5}  {:>11.4}  {:>8}  {:>20}  {:>13.2e}  {:>12}  {:>9}",
                    r.case,
                    r.start,
                    r.median.as_secs_f64() * 1e3,
                    r.cpu.map_or("n/a".into(), |c| format!("{:.4}", c.as_secs_f64() * 1e3)),
                    format!("{} + {}", r.newton, r.chord),
                    r.error,
                    r.estimate.map_or("none".into(), |e| format!("{e:.2e}")),
                    r.intervals
                );
            }
        }
        BenchFormat::Json => {
            let list: Vec<serde_json::Value> = rows
                .iter()
                .map(|r| {
                    // `nodes` counts mesh points (intervals + 1), kept for tools that read it.
                    serde_json::json!({
                        "case": r.case, "start": r.start, "median_seconds": r.median.as_secs_f64(),
                        "median_cpu_seconds": r.cpu.map(|c| c.as_secs_f64()),
                        "iterations": r.iterations, "newton_steps": r.newton, "chord_steps": r.chord,
                        "tip_error_m": r.error, "error_estimate_m": r.estimate,
                        "intervals": r.intervals, "nodes": r.intervals + 1,
                    })
                })
                .collect();
            let _ = writeln!(out, "{}", serde_json::Value::Array(list));
        }
    }
    Ok(out)
}
