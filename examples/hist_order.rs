//! Experiment (docs/friction.md section 8, "Order 4 on stuck links"): the stuck steps' tips
//! of the 10-step loop, each solved on its history mesh split into 2^L parts
//! (`TDCR_SPLIT_LEVEL=L`, the boundary node re-estimated on that mesh until it settles),
//! with the pointwise load on stuck links where `TDCR_POINTWISE` is set.
//! `hist_order STEPS INTERVALS` (default 10 32).
use tdcr::analysis::history::history;
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, cases, collocation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let count: usize = args.first().map_or(10, |a| a.parse().unwrap());
    let intervals: usize = args.get(1).map_or(32, |a| a.parse().unwrap());
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let values: Vec<f64> = (0..=count).map(|k| 4.91 * k as f64 / count as f64).collect();
    let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)])
        .unwrap()
        .up_down();
    let options = collocation::Options {
        tolerance: None,
        intervals,
        ..Default::default()
    };
    let result = history(&ranges, &options).unwrap();
    if let Some((k, e)) = result.failure {
        panic!("step {k}: {e}");
    }
    for (k, step) in result.steps.iter().enumerate() {
        if !step.zones[0].zones.iter().any(|z| z.contact.name() == "stick") {
            continue;
        }
        let tip = step.solution.tip_position();
        let r = step.solution.nodes.last().unwrap().state().R;
        println!(
            "step {k} intervals {} tip {:.17e} {:.17e} {:.17e} R {:.17e} {:.17e} {:.17e}",
            step.solution.report.intervals,
            tip.x,
            tip.y,
            tip.z,
            r[(0, 0)],
            r[(1, 0)],
            r[(2, 0)]
        );
    }
}
