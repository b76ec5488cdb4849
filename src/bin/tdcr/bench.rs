//! `tdcr bench`: solve the reference cases S and H cold and warm many times and report the
//! median solve time, Newton iterations, tip error against the published reference tips and
//! the mesh, so anyone can measure tdcr on their machine (docs/benchmarks.md).

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
    /// Tip error to reach (m): each case uses the smallest mesh from 8 to 512 intervals that
    /// reaches it.
    #[arg(long, default_value_t = 1e-7, value_name = "METRES")]
    pub target: f64,
    /// Timed solves per case and start (the median is reported).
    #[arg(long, default_value_t = 200, value_name = "N")]
    pub repeats: usize,
}

/// Output formats of `tdcr bench`.
#[derive(Clone, Copy, ValueEnum)]
pub enum BenchFormat {
    /// A table for people.
    Table,
    /// A JSON list of {case, start, median_seconds, iterations, tip_error_m, nodes}; `nodes`
    /// counts mesh points, the table's intervals + 1.
    Json,
}

struct Row {
    case: &'static str,
    start: &'static str,
    median: Duration,
    iterations: usize,
    error: f64,
    intervals: usize,
}

/// The same robot with every tension scaled by `factor`.
fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.tension *= factor;
    }
    r
}

fn median(
    mut solve: impl FnMut() -> Result<Solution, tdcr::Error>,
    repeats: usize,
) -> Result<(Duration, Solution), tdcr::Error> {
    let mut times = Vec::with_capacity(repeats);
    let mut last = solve()?;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        last = solve()?;
        times.push(t.elapsed());
    }
    times.sort();
    Ok((times[times.len() / 2], last))
}

/// The median time of a warm solve of `robot` by a solver that has just solved `previous`
/// (untimed, before every timed solve), starting from that solution.
fn median_warm(
    solver: &mut collocation::Solver,
    previous: &Robot,
    robot: &Robot,
    repeats: usize,
) -> Result<(Duration, Solution), tdcr::Error> {
    let mut times = Vec::with_capacity(repeats);
    let mut last = solver.solve(previous)?;
    for _ in 0..repeats.max(1) {
        let guess = solver.solve(previous)?;
        let t = Instant::now();
        last = solver.solve_from(robot, &guess)?;
        times.push(t.elapsed());
    }
    times.sort();
    Ok((times[times.len() / 2], last))
}

/// Runs the benchmark; the text to print, or a message for a failed solve.
pub fn run(args: &BenchArgs) -> Result<String, String> {
    if !(args.target.is_finite() && args.target > 0.0) {
        return Err(format!("--target is {}; give a positive tip error in m", args.target));
    }
    let mut rows = Vec::new();
    for (case, robot, tip) in [
        ("S", cases::case_s(), cases::TIP_S),
        ("H", cases::case_h(), cases::TIP_H),
    ] {
        let reference = Vector3::from(tip);
        let intervals = [8, 12, 16, 24, 32, 48, 64, 96, 128, 192, 256, 384, 512]
            .into_iter()
            .find(|&n| {
                collocation::solve(
                    &robot,
                    &collocation::Options {
                        intervals: n,
                        ..Default::default()
                    },
                )
                .is_ok_and(|s| (s.tip_position() - reference).norm() <= args.target)
            })
            .ok_or_else(|| format!("case {case}: no mesh up to 512 intervals reaches {:.1e} m", args.target))?;
        let options = collocation::Options {
            intervals,
            ..Default::default()
        };
        let fail = |e: tdcr::Error| format!("case {case}: {e}");
        let (t, cold) = median(|| collocation::solve(&robot, &options), args.repeats).map_err(fail)?;
        rows.push(Row {
            case,
            start: "cold",
            median: t,
            iterations: cold.report.iterations,
            error: (cold.tip_position() - reference).norm(),
            intervals,
        });
        // Warm: a solver that has just solved the robot at 0.99 times the tension (the step
        // of a sweep or a control loop) solves it at full tension from that solution.
        let previous = scaled(&robot, 0.99);
        let mut solver = collocation::Solver::new(options.clone());
        let (t, warm) = median_warm(&mut solver, &previous, &robot, args.repeats).map_err(fail)?;
        rows.push(Row {
            case,
            start: "warm",
            median: t,
            iterations: warm.report.iterations,
            error: (warm.tip_position() - reference).norm(),
            intervals,
        });
    }
    let mut out = String::new();
    match args.format {
        BenchFormat::Table => {
            let _ = writeln!(
                out,
                "tdcr bench: collocation, median of {} solves each, tip error against the published reference tips",
                args.repeats
            );
            let _ = writeln!(out, "case  start  median (ms)  iterations  tip error (m)  intervals");
            for r in &rows {
                let _ = writeln!(
                    out,
                    "{:<4}  {:<5}  {:>11.4}  {:>10}  {:>13.2e}  {:>9}",
                    r.case,
                    r.start,
                    r.median.as_secs_f64() * 1e3,
                    r.iterations,
                    r.error,
                    r.intervals
                );
            }
        }
        BenchFormat::Json => {
            let list: Vec<serde_json::Value> = rows
                .iter()
                .map(|r| {
                    // `nodes` counts mesh points (intervals + 1); other tools read the key.
                    serde_json::json!({
                        "case": r.case, "start": r.start, "median_seconds": r.median.as_secs_f64(),
                        "iterations": r.iterations, "tip_error_m": r.error, "nodes": r.intervals + 1,
                    })
                })
                .collect();
            let _ = writeln!(out, "{}", serde_json::Value::Array(list));
        }
    }
    Ok(out)
}
