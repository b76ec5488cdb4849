//! The prototype's hysteresis loop (docs/friction.md section 8): tendon 1 (mu = 0.1,
//! E_t A_t = 2000 N) pulled from 0 to 4.91 N in 10 steps and let back out, solved as a load
//! history at the default tolerance and at tighter ones; prints each step's tip, delivered
//! tension and zones, and the largest tip difference to the tightest solve (the history's
//! discretization error at each tolerance).

use tdcr::analysis::history::history;
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, cases, collocation};

/// The reference history's tolerance (relative to L).
const REFERENCE: f64 = 1e-11;

fn main() {
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let values: Vec<f64> = (0..=10).map(|k| 4.91 * k as f64 / 10.0).collect();
    let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)])
        .expect("valid ranges")
        .up_down();
    let solve = |tolerance: f64| {
        let options = collocation::Options {
            tolerance: Some(tolerance),
            ..Default::default()
        };
        let result = history(&ranges, &options).expect("a valid history");
        if let Some((k, e)) = result.failure {
            panic!("step {k}: {e}");
        }
        result.steps
    };
    let reference = solve(REFERENCE);
    for step in &reference {
        let t = &step.solution.tendons[0];
        let zones: Vec<String> = step.zones[0]
            .zones
            .iter()
            .map(|z| format!("{} {:.4}-{:.4}", z.contact.name(), z.start, z.end))
            .collect();
        let tip = step.solution.tip_position();
        let estimate = step.solution.report.error_estimate.map_or(f64::NAN, |e| e.tip_position);
        println!(
            "{:6.3} N  est {estimate:.1e} m on {:4} intervals  tip ({:+.6}, {:+.6}, {:+.6}) m  delivered {:.5} N  {}",
            t.tension,
            step.solution.report.intervals,
            tip.x,
            tip.y,
            tip.z,
            t.delivered_tension,
            zones.join(" ")
        );
    }
    for tolerance in [1e-7, 1e-8, 1e-9] {
        let steps = solve(tolerance);
        let worst = steps
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a.solution.tip_position() - b.solution.tip_position()).norm())
            .fold(0.0, f64::max);
        let intervals = steps[0].solution.report.intervals;
        println!("tolerance {tolerance:e}: {intervals} intervals, largest tip difference to 1e-11: {worst:.3e} m");
        let each: Vec<String> = steps
            .iter()
            .zip(&reference)
            .map(|(a, b)| format!("{:.1e}", (a.solution.tip_position() - b.solution.tip_position()).norm()))
            .collect();
        println!("  by step: {}", each.join(" "));
        // Each step's true error over its estimate, and its intervals.
        let ratios: Vec<String> = steps
            .iter()
            .zip(&reference)
            .map(|(a, b)| {
                let error = (a.solution.tip_position() - b.solution.tip_position()).norm();
                let report = &a.solution.report;
                match report.error_estimate {
                    Some(e) => format!("{:.3}/{}", error / e.tip_position, report.intervals),
                    None => format!("none/{}", report.intervals),
                }
            })
            .collect();
        println!("  true / estimate, intervals: {}", ratios.join(" "));
    }
}
