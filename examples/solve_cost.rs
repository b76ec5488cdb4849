//! Instructions per default solve, for callgrind (docs/benchmarks.md, "Where a solve's
//! instructions go"): solves case S or H (or SM: S with a dead tip moment, whose verdict
//! comes from the linearized dynamics) cold, or warm (a solver that has just solved the
//! case at 0.99 times the tension solves it at full tension from that solution, as `tdcr
//! bench` does), `count` times inside [`measured`], after one untimed solve of the same kind.
//!
//! ```text
//! cargo build --release --example solve_cost
//! valgrind --tool=callgrind --toggle-collect='solve_cost::measured' \
//!     target/release/examples/solve_cost S cold 20
//! ```
//! Instructions per solve = the collected total / `count`. `TOL` (relative to L) and
//! `INTERVALS` (the starting mesh's fewest intervals) replace the defaults.

use tdcr::{Robot, Solution, cases, collocation};

/// The same robot with every tension scaled by `factor`.
fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.set_tension(t.tension() * factor);
    }
    r
}

/// The solves that callgrind counts: `count` (at least 1) cold solves, or `count` warm ones
/// each after an uncounted solve at 0.99 times the tension (`previous`).
#[inline(never)]
fn measured(
    robot: &Robot,
    mut previous: Option<(&Robot, &mut collocation::Solver)>,
    options: &collocation::Options,
    count: usize,
) -> Result<Solution, tdcr::Error> {
    let mut once = || match previous.as_mut() {
        None => collocation::solve(robot, options),
        Some((previous, solver)) => {
            let guess = uncounted(solver, previous)?;
            solver.solve_from(robot, &guess)
        }
    };
    let mut last = once()?;
    for _ in 1..count {
        last = once()?;
    }
    Ok(last)
}

/// The uncounted solve before each warm one (callgrind's toggle stops inside it).
#[inline(never)]
fn uncounted(solver: &mut collocation::Solver, previous: &Robot) -> Result<Solution, tdcr::Error> {
    std::hint::black_box(solver.solve(previous))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: solve_cost S|H|SM cold|warm COUNT [TOL [INTERVALS]]";
    let (case, start, count) = match args.as_slice() {
        [_, c, s, n, ..] => (c.as_str(), s.as_str(), n.parse::<usize>()?.max(1)),
        _ => return Err(usage.into()),
    };
    let robot = match case {
        "S" => cases::case_s(),
        "H" => cases::case_h(),
        // Case S with a dead tip moment (2, 1, 0) mN m: not conservative, so its verdict
        // comes from the linearized dynamics (docs/stability.md).
        "SM" => {
            let mut robot = cases::case_s();
            robot.loads.tip_moment = nalgebra::Vector3::new(2e-3, 1e-3, 0.0);
            robot
        }
        _ => return Err(usage.into()),
    };
    let mut options = collocation::Options::default();
    if let Some(tol) = args.get(4) {
        options.tolerance = Some(tol.parse()?);
    }
    // The fewest intervals of the starting mesh, for studies of the first mesh.
    if let Some(intervals) = args.get(5) {
        options.intervals = intervals.parse()?;
    }
    let solution = match start {
        "cold" => {
            collocation::solve(&robot, &options)?;
            measured(&robot, None, &options, count)?
        }
        "warm" => {
            let previous = scaled(&robot, 0.99);
            let mut solver = collocation::Solver::new(options.clone());
            let guess = solver.solve(&previous)?;
            solver.solve_from(&robot, &guess)?;
            measured(&robot, Some((&previous, &mut solver)), &options, count)?
        }
        _ => return Err(usage.into()),
    };
    let r = &solution.report;
    println!(
        "{case} {start}: {} intervals, {} + {} steps, estimate {:.2e} m",
        r.intervals,
        r.newton_steps,
        r.chord_steps,
        r.error_estimate.map_or(f64::NAN, |e| e.tip_position)
    );
    Ok(())
}
