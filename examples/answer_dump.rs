//! Every number a default solve returns, printed exactly (shortest round-trip form), for a
//! before/after comparison of a change that must not move answers (docs/benchmarks.md,
//! "Checking that answers did not move"): cases S and H, the same as Kirchhoff rods, the
//! Table 2 experiments and 40 random prototype rows, each cold and warm (from the answer at
//! 0.99 times the tension), with their nodes, tendon states, estimate, verdict, steps and
//! meshes.
//!
//! ```text
//! cargo run --release --example answer_dump > before.txt   # build, change, run again
//! cargo run --release --example answer_dump > after.txt && cmp before.txt after.txt
//! ```

use tdcr::{Robot, RodModel, Solution, cases, collocation};

/// The same robot with every tension scaled by `factor`.
fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.set_tension(t.tension() * factor);
    }
    r
}

/// Uniform in [0, 1) from a fixed linear congruential sequence.
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// One answer's lines: nodes, tendon states, and the report without its timings.
fn print(name: &str, solution: &Solution) {
    let r = &solution.report;
    println!(
        "{name}: iterations {} newton {} chord {} meshes {} intervals {} residual {:?}",
        r.iterations, r.newton_steps, r.chord_steps, r.meshes, r.intervals, r.residual
    );
    println!("{name}: estimate {:?} met {:?}", r.error_estimate, r.tolerance_met);
    println!("{name}: stability {:?}", r.stability);
    println!("{name}: path {:?} notes {:?}", r.path, r.notes);
    for n in &solution.nodes {
        println!(
            "{name}: node {:?} {:?} {:?} {:?} {:?}",
            n.s,
            n.p.as_slice(),
            n.R.as_slice(),
            n.v.as_slice(),
            n.u.as_slice()
        );
    }
    println!("{name}: tendons {:?}", solution.tendons);
    println!("{name}: tensions {:?}", solution.tendon_tensions);
}

fn main() -> Result<(), tdcr::Error> {
    let mut robots: Vec<(String, Robot)> = vec![("S".into(), cases::case_s()), ("H".into(), cases::case_h())];
    for (name, robot) in [("S", cases::case_s()), ("H", cases::case_h())] {
        let mut k = robot.clone();
        k.rod_model = RodModel::Kirchhoff;
        robots.push((format!("{name}-kirchhoff"), k));
    }
    for e in cases::table2() {
        robots.push((e.label(), e.robot()));
    }
    let mut state = 29;
    for i in 0..40 {
        let mut robot = cases::prototype();
        for t in robot.tendons.iter_mut() {
            t.set_tension(3.0 * uniform(&mut state));
        }
        robots.push((format!("row{i}"), robot));
    }
    let options = collocation::Options::default();
    for (name, robot) in &robots {
        print(&format!("{name} cold"), &collocation::solve(robot, &options)?);
        let mut solver = collocation::Solver::new(options.clone());
        let previous = solver.solve(&scaled(robot, 0.99))?;
        print(&format!("{name} warm"), &solver.solve_from(robot, &previous)?);
    }
    Ok(())
}
