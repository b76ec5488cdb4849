//! Friction in the channels (docs/friction.md): the delivered tension of the reference cases
//! S (a straight tendon) and H (a helical one) against the friction coefficient, in pull and
//! release, and the cost of a full-slip solve against the frictionless one.
//!
//! `cargo run --release --example friction`

use std::time::Instant;
use tdcr::{Friction, Motion, Robot, cases};

/// Median wall time (s) of `repeats` cold default solves of `robot`.
fn median_time(robot: &Robot, repeats: usize) -> f64 {
    let mut times: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            let solution = tdcr::solve(robot, &Default::default()).expect("solves");
            std::hint::black_box(solution);
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[repeats / 2]
}

fn main() -> Result<(), tdcr::Error> {
    let cases = [("S", cases::case_s(), 0), ("H", cases::case_h(), 4)];
    println!("case  mu    motion   delivered/N  ratio    tip angle/deg");
    for (name, robot, tendon) in &cases {
        for mu in [0.0, 0.05, 0.1, 0.2, 0.3] {
            for motion in [Motion::Pull, Motion::Release] {
                let mut rough = robot.clone();
                rough.tendons[*tendon].friction = Some(Friction {
                    coefficient: mu,
                    motion,
                });
                let solution = tdcr::solve(&rough, &Default::default())?;
                let t = &solution.tendons[*tendon];
                let tip = solution.tip().R.column(2).into_owned();
                let base = solution.base().R.column(2).into_owned();
                let angle = tip.dot(&base).clamp(-1.0, 1.0).acos().to_degrees();
                println!(
                    "{name:4}  {mu:4.2}  {:8} {:11.5}  {:7.5}  {angle:8.3}",
                    motion.name(),
                    t.delivered_tension,
                    t.delivered_tension / t.tension
                );
            }
        }
    }
    let repeats = 101;
    println!("\ncase  frictionless/ms  mu = 0.1/ms  ratio  (median of {repeats} cold default solves)");
    for (name, robot, tendon) in &cases {
        let mut rough = robot.clone();
        rough.tendons[*tendon].friction = Some(Friction::pull(0.1));
        let (a, b) = (median_time(robot, repeats), median_time(&rough, repeats));
        let solution = tdcr::solve(&rough, &Default::default())?;
        println!(
            "{name:4}  {:15.3}  {:11.3}  {:5.2}  ({} intervals, {} Newton + {} chord steps with friction)",
            a * 1e3,
            b * 1e3,
            b / a,
            solution.report.intervals,
            solution.report.newton_steps,
            solution.report.chord_steps
        );
    }
    Ok(())
}
