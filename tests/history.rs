//! Stick/slip friction over load histories (docs/friction.md section 8).

use tdcr::analysis::history::{Contact, HistoryResult, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, Robot, cases};

/// The prototype with friction `mu` and stiffness on tendon 1.
fn prototype(mu: f64) -> Robot {
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(mu));
    robot.tendons[0].stiffness = Some(2000.0);
    robot
}

fn up_down(robot: Robot, top: f64, steps: usize) -> HistoryResult {
    let values: Vec<f64> = (0..steps).map(|k| top * k as f64 / (steps - 1) as f64).collect();
    let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)]).unwrap();
    history(&ranges.up_down(), &Default::default()).unwrap()
}

#[test]
fn explore() {
    let result = up_down(prototype(0.1), 4.91, 6);
    if let Some((k, e)) = &result.failure {
        panic!("step {k}: {e}");
    }
    for step in &result.steps {
        let tip = step.solution.tip_position();
        let t = &step.solution.tendons[0];
        println!(
            "{:.3} {:.6} {:.6} {:.4} {:?} it {}",
            t.tension,
            tip.x,
            tip.z,
            t.delivered_tension,
            step.zones[0].zones.iter().map(|z| (z.start, z.end, z.contact.name())).collect::<Vec<_>>(),
            step.solution.report.iterations
        );
    }
    let _ = Contact::Stick;
}
