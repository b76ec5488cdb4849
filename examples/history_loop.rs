//! The prototype's hysteresis loop (docs/friction.md section 8): tendon 1 (mu = 0.1,
//! E_t A_t = 2000 N) pulled from 0 to 4.91 N in 10 steps and let back out, solved as a load
//! history at the default tolerance and at tighter ones; prints each step's tip, delivered
//! tension and zones, and the largest tip difference to the tightest solve (the history's
//! discretization error at each tolerance).
//!
//! `history_loop STEPS REFERENCE` takes STEPS steps each way instead of 10 (50: the 101-step
//! history of docs/benchmarks.md "Load history") against a history at REFERENCE L instead of
//! 1e-11, at the default tolerance only, and lists the steps that miss it
//! (`tolerance_met = false`) with their position and rotation errors and estimates.

use tdcr::analysis::history::history;
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, cases, collocation};

/// The reference history's tolerance (relative to L), unless given.
const REFERENCE: f64 = 1e-11;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let count: usize = args.first().map_or(10, |a| a.parse().expect("STEPS is a count"));
    let reference_tolerance: f64 = args
        .get(1)
        .map_or(REFERENCE, |a| a.parse().expect("REFERENCE is a number"));
    let tolerances: &[f64] = if args.is_empty() { &[1e-7, 1e-8, 1e-9] } else { &[1e-7] };
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let values: Vec<f64> = (0..=count).map(|k| 4.91 * k as f64 / count as f64).collect();
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
    let reference = solve(reference_tolerance);
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
    for &tolerance in tolerances {
        let steps = solve(tolerance);
        let worst = steps
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a.solution.tip_position() - b.solution.tip_position()).norm())
            .fold(0.0, f64::max);
        let intervals = steps[0].solution.report.intervals;
        println!(
            "tolerance {tolerance:e}: {intervals} intervals, largest tip difference to {reference_tolerance:e}: {worst:.3e} m"
        );
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
        // The steps (from 1, as the CSV) that say they miss the tolerance.
        for (k, (a, b)) in steps.iter().zip(&reference).enumerate() {
            let report = &a.solution.report;
            if report.tolerance_met == Some(false) {
                let (ta, tb) = (a.solution.tip(), b.solution.tip());
                let rotation = (ta.R.transpose() * tb.R).trace();
                let angle = ((rotation - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
                println!(
                    "  step {} misses: tip error {:.2e} m, rotation error {angle:.1e} rad, estimate {:?}",
                    k + 1,
                    (ta.p - tb.p).norm(),
                    report.error_estimate
                );
            }
        }
    }
}
