//! Inverse statics on the paper's prototype: make a target tip position with known
//! tensions (tendon 2 at 1.5 N, the helical tendon 5 at 2.0 N), forget them, and find
//! tensions in [0, 5] N that put the tip there again; then ask for a point out of reach;
//! then reach the first target by actuator pull-ins within a 1 cm stroke instead.
//!
//! Run with `cargo run --release --example inverse_statics`.

use nalgebra::Vector3;
use std::time::Instant;
use tdcr::fit::inverse::{InverseOptions, Target, solve_displacements, solve_tensions};
use tdcr::{cases, collocation};

fn main() -> tdcr::Result<()> {
    let options = InverseOptions::new(5.0);

    let mut pulled = cases::prototype();
    pulled.tendons[1].set_tension(1.5);
    pulled.tendons[4].set_tension(2.0);
    let goal = collocation::solve(&pulled, &options.solver)?.tip_position();
    println!("target tip: ({:.6}, {:.6}, {:.6}) m", goal.x, goal.y, goal.z);
    println!("made with tensions [0, 1.5, 0, 0, 2] N; starting from all slack\n");

    for (label, target) in [
        ("reachable target", Target::position(goal)),
        (
            "target 1 m ahead of the base",
            Target::position(Vector3::new(1.0, 0.0, 0.0)),
        ),
    ] {
        let start = Instant::now();
        let found = solve_tensions(&cases::prototype(), &target, &options)?;
        let elapsed = start.elapsed();
        let tip = found.tip_position();
        let tensions: Vec<String> = found.tensions.iter().map(|t| format!("{t:.4}")).collect();
        println!("{label}");
        println!("  tensions:     [{}] N", tensions.join(", "));
        println!("  achieved tip: ({:.6}, {:.6}, {:.6}) m", tip.x, tip.y, tip.z);
        println!(
            "  tip error:    {:.3e} m (reachable: {})",
            found.residual, found.reachable
        );
        println!(
            "  iterations:   {} ({} forward solves, {} sensitivity evaluations) in {:.1} ms",
            found.iterations,
            found.forward_solves,
            found.jacobians,
            elapsed.as_secs_f64() * 1e3
        );
        println!("  {}\n", found.explain());
    }

    // The same target in actuator space: pull-ins within a 1 cm stroke, from rest.
    let stroke = InverseOptions::displacements(0.0, 0.01);
    let start = Instant::now();
    let found = solve_displacements(&cases::prototype(), &Target::position(goal), &stroke)?;
    let elapsed = start.elapsed();
    let pull_ins: Vec<String> = found.displacements.iter().map(|q| format!("{:.4}", q * 1e3)).collect();
    let tensions: Vec<String> = found.tensions.iter().map(|t| format!("{t:.4}")).collect();
    println!("reachable target by pull-ins in [0, 10] mm");
    println!("  pull-ins:     [{}] mm", pull_ins.join(", "));
    println!("  tensions:     [{}] N", tensions.join(", "));
    println!("  bounds:       {:?}", found.bounds);
    println!(
        "  tip error:    {:.3e} m in {} iterations ({} forward solves), {:.1} ms",
        found.residual,
        found.iterations,
        found.forward_solves,
        elapsed.as_secs_f64() * 1e3
    );
    println!("  {}", found.explain());
    Ok(())
}
