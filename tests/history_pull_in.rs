//! Stick/slip histories over pull-ins (docs/friction.md section 8): the prototype's tendon 1
//! pulled in and let back out with mu = 0.1 on an elastic tendon draws a closed loop whose
//! unloading branch lies on the other side, every step in global equilibrium, and each
//! step's pull-in is the one a tension history at its solved tension reports.

use nalgebra::Vector3;
use tdcr::analysis::equilibrium::imbalance;
use tdcr::analysis::history::{Contact, HistoryStep, REPEATED, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Robot, cases};

/// The prototype with friction 0.1 on tendon 1, E_t A_t = 2000 N (as tests/history.rs).
fn prototype() -> Robot {
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    robot
}

/// Tendon 1 pulled in from 0 to `top` (m) in `steps` equal steps and let back out.
fn pull_ins(top: f64, steps: usize) -> Ranges {
    let values: Vec<f64> = (0..=steps).map(|k| top * k as f64 / steps as f64).collect();
    Ranges::new(prototype(), vec![(Input::Displacement(0), values)])
        .unwrap()
        .up_down()
}

fn tip(step: &HistoryStep) -> Vector3<f64> {
    step.solution.tip_position()
}

#[test]
fn pulling_in_and_letting_out_draws_a_closed_loop() {
    // 20 mm of pull-in: about 4.9 N in full slip, the paper's top tension (the rod's weight
    // shortens tendon 1's path by 2.06 mm, so it is slack up to there).
    let ranges = pull_ins(0.02, 6);
    let result = history(&ranges, &Default::default()).unwrap();
    if let Some((k, e)) = &result.failure {
        panic!("step {k}: {e}");
    }
    let steps = result.steps;
    assert_eq!(steps.len(), 13);
    let rest = tip(&steps[0]);
    // Closed: back at 0 the tendon is slack and the robot
    // where it started (1e-9 m: two Newton solves of the same robot, as for tensions).
    let closing = (tip(&steps[12]) - rest).norm();
    assert!(closing < 1e-9, "the loop is open by {closing} m");
    for (k, step) in steps.iter().enumerate() {
        let t = &step.solution.tendons[0];
        let want = ranges.robot(k as f64).unwrap().tendons[0].displacement().unwrap();
        assert_eq!(t.displacement, want, "step {k}");
        // The balance at the solved tension (the input is the pull-in).
        let robot = ranges.robot(k as f64).unwrap().with_tensions(&step.solution.tensions());
        let e = imbalance(&robot, &step.solution);
        // 1e-8: the solver's tolerance in the wrenches relative to the tension, as for the
        // tension histories
        assert!(e.max() < 1e-8, "step {k}: imbalance {e:?}");
    }
    // Unloading on the other side. At the same pull-in the tendon holds about the same
    // integral of tension (the pull-in is the path's shortening plus the stretch, both
    // about proportional to it), but on the way back the tension rises toward the
    // termination instead of falling (measured at 3.3 mm: 0.358 N -> 0.343 N delivered up,
    // 0.339 N -> 0.353 N down). The base's curvature swings the whole rod, so the tip is
    // closer to rest on the way back (182.3 mm against 194.9 mm from rest at 16.7 mm).
    for k in 1..6 {
        let (up, down) = (&steps[k], &steps[12 - k]);
        let (bent_up, bent_down) = ((tip(up) - rest).norm(), (tip(down) - rest).norm());
        assert!(bent_down < bent_up, "step {k}: {bent_down} >= {bent_up}");
        let (a, b) = (&up.solution.tendons[0], &down.solution.tendons[0]);
        assert!(b.tension < a.tension && b.delivered_tension > a.delivered_tension);
        assert!(a.delivered_tension < a.tension && b.delivered_tension > b.tension);
    }
    // Loading slides in all along; the first step back (3.3 mm, a fifth of the pull-in)
    // slides out from the base entry and nowhere in.
    assert!(
        steps[1..=6]
            .iter()
            .all(|s| s.zones[0].zones.iter().all(|z| z.contact == Contact::Pull))
    );
    let back = &steps[7].zones[0].zones;
    assert_eq!(back.first().map(|z| z.contact), Some(Contact::Release));
    assert!(back.iter().all(|z| z.contact != Contact::Pull), "{back:?}");
}

#[test]
fn a_pull_in_history_step_reports_the_tension_a_tension_history_needs() {
    // The same loop driven by the tensions the pull-in history solved: the same tips.
    let ranges = pull_ins(0.02, 4);
    let by_pull_in = history(&ranges, &Default::default()).unwrap().steps;
    let tensions: Vec<f64> = by_pull_in.iter().map(|s| s.solution.tendons[0].tension).collect();
    let driven = Ranges::new(
        prototype(),
        vec![(Input::Parameter(tdcr::Parameter::Tension(0)), tensions)],
    )
    .unwrap();
    let by_tension = history(&driven, &Default::default()).unwrap().steps;
    assert_eq!(by_tension.len(), by_pull_in.len());
    for (k, (a, b)) in by_pull_in.iter().zip(&by_tension).enumerate() {
        let d = (tip(a) - tip(b)).norm();
        // 1e-9 m: the same tensions on the same mesh; the pull-in's Newton stops at 1e-12
        // of the tension scale, and each history's steps at the residual tolerance
        assert!(d < 1e-9, "step {k}: tips differ by {d:.2e} m");
        if a.solution.tendons[0].tension > 0.0 {
            let q = (a.solution.tendons[0].displacement - b.solution.tendons[0].displacement).abs();
            // 1e-12 m: the pull-in the tension history reports is the one the other held
            // (slack steps report their input, the tension history the slack's end)
            assert!(q < 1e-12, "step {k}: pull-ins differ by {q:.2e} m");
        }
    }
}

#[test]
fn a_repeated_pull_in_is_the_last_state_stuck_all_along() {
    // The brief's history (main: "did not settle in 40 passes" at step 4, the repeat) and a
    // repeat in the middle of the way back.
    for (list, repeats) in [
        (vec![0.0, 0.01, 0.02, 0.02, 0.015], vec![3]),
        (vec![0.0, 0.01, 0.01, 0.02, 0.015, 0.015, 0.01], vec![2, 5]),
    ] {
        let ranges = Ranges::new(prototype(), vec![(Input::Displacement(0), list.clone())]).unwrap();
        let result = history(&ranges, &Default::default()).unwrap();
        if let Some((k, e)) = &result.failure {
            panic!("{list:?}, step {k}: {e}");
        }
        let steps = result.steps;
        assert_eq!(steps.len(), list.len());
        for k in repeats {
            let (last, step) = (&steps[k - 1], &steps[k]);
            assert_eq!(step.solution.tip_position(), last.solution.tip_position());
            assert_eq!(step.solution.tendons[0].tension, last.solution.tendons[0].tension);
            let zones = &step.zones[0].zones;
            assert!(zones.len() == 1 && zones[0].contact == Contact::Stick, "{zones:?}");
            let report = &step.solution.report;
            assert!(report.iterations == 0 && report.error_estimate.is_some());
            assert!(report.notes.iter().any(|n| n == REPEATED));
            // The step after it slides from the base entry the way the input moves.
            let way = if list[k + 1] > list[k] {
                Contact::Pull
            } else {
                Contact::Release
            };
            assert_eq!(steps[k + 1].zones[0].zones[0].contact, way, "{list:?}, step {}", k + 1);
        }
    }
}

#[test]
fn a_rigid_tendon_pulled_in_further_slides_in_all_along() {
    // Tendon 1 rigid (no stiffness), pulled in 8 then 12 mm: each step slides in all along,
    // which needs no stiffness, and matches the full-slip pull solve of its pull-in. Until
    // 2026-12-07 (fifteenth session) the second step's Newton started at the first step's
    // tension, where nothing is driven and the rigid tendon sticks all along, and the step
    // was refused as statically indeterminate (a new-user check).
    let mut robot = prototype();
    robot.tendons[0].stiffness = None;
    let ranges = Ranges::new(robot.clone(), vec![(Input::Displacement(0), vec![0.008, 0.012])]).unwrap();
    let (step, full) = second_step_and_its_full_slip_solve(&ranges);
    // two solves of the same discrete problem from different starts, each to Newton's
    // tolerance: their tips agree far below the 2.4e-8 m tolerance
    let gap = (tip(&step) - full.tip_position()).norm();
    assert!(gap < 1e-10, "{gap} m from the full-slip solve");
}

/// The second step of the history of `ranges`, which must solve with tendon 1 sliding in
/// all along, and the full-slip solve of its inputs.
fn second_step_and_its_full_slip_solve(ranges: &Ranges) -> (tdcr::analysis::history::HistoryStep, tdcr::Solution) {
    let result = history(ranges, &Default::default()).unwrap();
    if let Some((k, e)) = &result.failure {
        panic!("step {k}: {e}");
    }
    let step = result.steps[1].clone();
    assert_eq!(step.zones[0].zones.len(), 1);
    assert_eq!(step.zones[0].zones[0].contact, Contact::Pull);
    let full = tdcr::solve(&ranges.robot(1.0).unwrap(), &Default::default()).unwrap();
    (step, full)
}

#[test]
fn a_rigid_pull_in_from_slack_straight_to_its_top_starts_again_from_rest() {
    // A flexible rod (user23's nitinol: 0.3 m, r = 0.5 mm, E = 60 GPa, standing up under
    // its weight) with two opposite rigid tendons, mu = 0.2, tendon 1 pulled in 0 then
    // 6 mm. Step 1 leaves both slack; step 2 is then loaded from rest, as a first step is,
    // and is the full-slip pull solve of its pull-in. Until 2026-12-07 (sixteenth session)
    // its Newton started from the slack, straight rod and stalled (30 iterations, scaled
    // residual 4e2) where the full-slip solve and a one-step history of 6 mm solve.
    let tendon = |x: f64| {
        let mut t = tdcr::Tendon::new(tdcr::Routing::straight(x, 0.0), 0.0);
        t.friction = Some(Friction::pull(0.2));
        t
    };
    let robot = Robot::new(tdcr::Rod::solid_circle(0.3, 0.0005, 60e9, 0.33))
        .with_loads(tdcr::Loads::self_weight(0.2, -Vector3::z()))
        .with_tendon(tendon(0.005))
        .with_tendon(tendon(-0.005));
    let ranges = Ranges::new(robot, vec![(Input::Displacement(0), vec![0.0, 0.006])]).unwrap();
    let (step, full) = second_step_and_its_full_slip_solve(&ranges);
    assert_eq!(step.zones[1].zones[0].contact, Contact::Slack);
    // the same discrete problem on the same mesh (the history's, chosen by this step's
    // full-slip solve) from different starts, each to Newton's tolerance: far below the
    // 3e-8 m tolerance
    let gap = (tip(&step) - full.tip_position()).norm();
    assert!(gap < 1e-10, "{gap} m from the full-slip solve");
    assert!(step.solution.report.error_estimate.is_some());
    // Its work counts the failed attempt's and the full-slip solve's iterations too.
    assert!(
        step.solution.report.iterations > full.report.iterations,
        "{}",
        step.solution.report.iterations
    );
}
