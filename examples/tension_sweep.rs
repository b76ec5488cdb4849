//! A tension sweep on the paper's prototype with a reusable solver: each solve is
//! warm-started from the last and reuses the mesh workspace.
//!
//! `cargo run --release --example tension_sweep`

use tdcr::{cases, collocation};

fn main() -> Result<(), tdcr::Error> {
    let mut robot = cases::prototype();
    let mut solver = collocation::Solver::new(collocation::Options::default());
    let mut previous: Option<tdcr::Solution> = None;
    println!("tension (N)  tip x (mm)  tip y (mm)  tip z (mm)  iterations  time (ms)");
    for step in 0..=12 {
        // Tendon 5 (the helix) from 0 to 6 N.
        robot.tendons[4].set_tension(0.5 * step as f64);
        let solution = match &previous {
            Some(guess) => solver.solve_from(&robot, guess)?,
            None => solver.solve(&robot)?,
        };
        let tip = solution.tip_position() * 1e3;
        println!(
            "{:>11.2}  {:>10.2}  {:>10.2}  {:>10.2}  {:>10}  {:>9.3}",
            robot.tendons[4].tension(),
            tip.x,
            tip.y,
            tip.z,
            solution.report.iterations,
            solution.report.timings.total.as_secs_f64() * 1e3
        );
        previous = Some(solution);
    }
    Ok(())
}
