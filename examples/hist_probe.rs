//! EXPERIMENT (hist10, not to be committed): the loop's tips at the default tolerance,
//! with TDCR_HIST_LEVELS split levels on every stuck step.
use tdcr::analysis::history::history;
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, cases, collocation};

fn main() {
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let values: Vec<f64> = (0..=10).map(|k| 4.91 * k as f64 / 10.0).collect();
    let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)])
        .expect("valid ranges")
        .up_down();
    let tol: f64 = std::env::var("TOL").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-7);
    let rtol: f64 = std::env::var("RTOL").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-11);
    let options = collocation::Options {
        tolerance: Some(tol),
        residual_tolerance: rtol,
        ..Default::default()
    };
    let result = history(&ranges, &options).expect("a valid history");
    if let Some((k, e)) = result.failure {
        panic!("step {k}: {e}");
    }
    for (n, step) in result.steps.iter().enumerate().skip(11).take(3) {
        let tip = step.solution.tip_position();
        let e = step.solution.report.error_estimate.map_or(f64::NAN, |e| e.tip_position);
        let zones: Vec<String> = step.zones[0]
            .zones
            .iter()
            .map(|z| format!("{} {:.6}-{:.6}", z.contact.name(), z.start, z.end))
            .collect();
        println!(
            "step {n} {} intervals tip {:.15e} {:.15e} est {e:.2e} {}",
            step.solution.report.intervals,
            tip.x,
            tip.z,
            zones.join(" ")
        );
    }
}
