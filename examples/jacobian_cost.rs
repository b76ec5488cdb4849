//! Instructions of the control Jacobians next to the solves they follow, for callgrind
//! (docs/benchmarks.md, "Control Jacobian"): case S or H, `count` times each of
//!
//! - `cold`: a cold solve;
//! - `warm`: a warm solve (a [`Solver`] that has just solved the case at 0.99 times the
//!   tension solves it at full tension from that solution, as `tdcr bench` does);
//! - `tensions`: the tension columns of the tip Jacobian from that solver
//!   ([`Solver::tip_jacobian`], after the warm solve);
//! - `all`: every tip sensitivity ([`tdcr::tip_sensitivities`], 21 parameters on the prototype);
//! - `solver-all`: every tip sensitivity from that solver ([`Solver::tip_sensitivities`],
//!   after the warm solve: the Jacobian its verdict evaluated at the solution, not assembled);
//! - `kept-warm`, `kept-tensions`: `warm` and `tensions` with the solver's
//!   [`Solver::keep_tension_columns`] on (the verdict of the warm solve forms the tension
//!   columns' right-hand sides; their cost is the difference of the two warm rows).
//!
//! ```text
//! cargo build --release --example jacobian_cost
//! valgrind --tool=callgrind --toggle-collect='jacobian_cost::measured' \
//!     target/release/examples/jacobian_cost S tensions 10
//! ```
//! Instructions per call = the collected total / `count`.

use tdcr::{Parameter, Robot, Solution, Solver, cases, collocation};

/// The same robot with every tension scaled by `factor`.
fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.set_tension(t.tension() * factor);
    }
    r
}

/// What callgrind counts: one call of the stage `what`; `previous` is the solution at 0.99
/// times the tension that `solver` just returned, `warm` a solution of `robot`.
#[inline(never)]
fn measured(
    what: &str,
    robot: &Robot,
    solver: &mut Solver,
    previous: &Solution,
    warm: &Solution,
) -> Result<f64, tdcr::Error> {
    let tensions: Vec<Parameter> = (0..robot.tendons.len()).map(Parameter::Tension).collect();
    Ok(match what.trim_start_matches("kept-") {
        "cold" => collocation::solve(robot, &solver.options)?.tip().p[0],
        "warm" => solver.solve_from(robot, previous)?.tip().p[0],
        "tensions" => solver.tip_jacobian(robot, warm, &tensions)?[(0, 0)],
        "solver-all" => solver.tip_sensitivities(robot, warm)?.tension[(0, 0)],
        _ => tdcr::tip_sensitivities(robot, warm)?.tension[(0, 0)],
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: jacobian_cost S|H cold|warm|tensions|all|solver-all|kept-warm|kept-tensions COUNT";
    let (case, what, count) = match args.as_slice() {
        [_, c, w, n] => (c.as_str(), w.as_str(), n.parse::<usize>()?.max(1)),
        _ => return Err(usage.into()),
    };
    let robot = match case {
        "S" => cases::case_s(),
        "H" => cases::case_h(),
        _ => return Err(usage.into()),
    };
    let modes = [
        "cold",
        "warm",
        "tensions",
        "all",
        "solver-all",
        "kept-warm",
        "kept-tensions",
    ];
    if !modes.contains(&what) {
        return Err(usage.into());
    }
    let before = scaled(&robot, 0.99);
    let mut solver = Solver::new(Default::default());
    solver.keep_tension_columns(what.starts_with("kept-"));
    let mut sum = 0.0;
    // Round 0 runs uncounted work only (lazily built tables, caches).
    for round in 0..=count {
        // Uncounted: the previous solve, and the warm solve a Jacobian is taken at.
        let previous = solver.solve(&before)?;
        let warm = if what.ends_with("warm") {
            previous.clone()
        } else {
            solver.solve_from(&robot, &previous)?
        };
        if round > 0 {
            sum += measured(what, &robot, &mut solver, &previous, &warm)?;
        }
    }
    println!("{case} {what}: {count} calls, checksum {sum:.6e}");
    Ok(())
}
