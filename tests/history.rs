//! Stick/slip friction over load histories (docs/friction.md section 8): a history of one
//! step from rest is the full-slip pull solve; pulling the prototype's tendon 1 up to
//! 4.91 N and letting it back out draws a closed hysteresis loop whose unloading branch
//! lies on the other side of the loading one, wider with more friction; a step that leaves
//! the tendon stuck moves the tip less than without friction; every step is in global
//! equilibrium; bad histories are refused with what to change.

use nalgebra::Vector3;
use tdcr::analysis::equilibrium::imbalance;
use tdcr::analysis::history::{Contact, HistoryResult, HistoryStep, REPEATED, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Error, Friction, Parameter, Robot, cases};

/// The paper's top tension (N).
const TOP: f64 = 4.91;

/// The prototype with friction `mu` on tendon 1, whose axial stiffness E_t A_t is 2000 N
/// (a 0.5 mm polymer line).
fn prototype(mu: f64) -> Robot {
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(mu));
    robot.tendons[0].stiffness = Some(2000.0);
    robot
}

/// Tendon 1's tension from 0 to `top` in `steps` equal steps and back.
fn ranges(robot: Robot, top: f64, steps: usize) -> Ranges {
    let values: Vec<f64> = (0..=steps).map(|k| top * k as f64 / steps as f64).collect();
    Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)])
        .unwrap()
        .up_down()
}

fn solved(result: HistoryResult) -> Vec<HistoryStep> {
    if let Some((k, e)) = &result.failure {
        panic!("step {k}: {e}");
    }
    result.steps
}

fn tip(step: &HistoryStep) -> Vector3<f64> {
    step.solution.tip_position()
}

#[test]
fn one_step_from_rest_is_the_full_slip_pull_solve() {
    let robot = prototype(0.1).with_tensions(&[TOP, 0.0, 0.0, 0.0, 0.0]);
    let ranges = Ranges::new(
        robot.clone(),
        vec![(Input::Parameter(Parameter::Tension(0)), vec![TOP])],
    )
    .unwrap();
    let steps = solved(history(&ranges, &Default::default()).unwrap());
    let pulled = tdcr::solve(&robot, &Default::default()).unwrap();
    let distance = (tip(&steps[0]) - pulled.tip_position()).norm();
    // 1e-10 m: the same equations on the same mesh; only the log tensions' round trip
    // through the tensions differs, at rounding
    assert!(
        distance < 1e-10,
        "history {:?} vs pull {:?}",
        tip(&steps[0]),
        pulled.tip_position()
    );
    assert_eq!(steps[0].zones[0].zones.len(), 1);
    assert_eq!(steps[0].zones[0].zones[0].contact, Contact::Pull);
    let delivered = steps[0].solution.tendons[0].delivered_tension;
    // 1e-12 N: the same profile to rounding
    assert!((delivered - pulled.tendons[0].delivered_tension).abs() < 1e-12);
}

/// The prototype with friction `mu` (E_t A_t 2000 N) on tendon 3 (x = -0.008 m: the top
/// side, which the rod's own weight, bending the rod down, stretches) at `tension`, and
/// tendon 1 without friction at 0 N; rigid (no stiffness) if `rigid`.
fn top_tendon(tension: f64, rigid: bool) -> Robot {
    let mut robot = cases::prototype().with_tensions(&[0.0, 0.0, tension, 0.0, 0.0]);
    robot.tendons[2].friction = Some(Friction::pull(0.1));
    robot.tendons[2].stiffness = (!rigid).then_some(2000.0);
    robot
}

/// `robot`'s history of tendon `i`'s (index) tension through `values`.
fn history_of(robot: &Robot, i: usize, values: &[f64]) -> Vec<HistoryStep> {
    let ranges = Ranges::new(
        robot.clone(),
        vec![(Input::Parameter(Parameter::Tension(i)), values.to_vec())],
    )
    .unwrap();
    solved(history(&ranges, &Default::default()).unwrap())
}

#[test]
fn a_first_step_pulls_in_from_rest_a_tendon_the_rods_weight_stretches() {
    // Main refused step 1 of both: "tendon 3 would go slack near s = 0.0581 m while stuck
    // in its channel ...; take the history in smaller steps" (0.0605 m for the second).
    // It laid the material at rest along the straight reference rod, which the weight's
    // bending stretches on the top side by far more than 1 N does (E_t A_t r kappa, about
    // 20 N near the base), so the march let the tendon out at the base and stuck it beyond.
    let robot = top_tendon(1.0, false);
    let pulled = tdcr::solve(&robot, &Default::default()).unwrap();
    // Tendon 1 (no friction) at 0 then 1 N: step 1 chose the history's mesh, so it is the
    // full-slip pull solve itself, solved again with a node where the weight's bend and
    // tendon 3's turn the other way meet (docs/friction.md section 8, "Sliding steps at an
    // inflection"): one more interval.
    let steps = history_of(&robot, 0, &[0.0, 1.0]);
    assert_eq!(steps[0].solution.report.intervals, pulled.report.intervals + 1);
    let distance = (tip(&steps[0]) - pulled.tip_position()).norm();
    // 1e-10 m: the same equations, the mesh one node richer, as for tendon 1 above
    assert!(distance < 1e-10, "{distance:e} m from the full-slip pull solve");
    let delivered = steps[0].solution.tendons[2].delivered_tension;
    let difference = (delivered - pulled.tendons[2].delivered_tension).abs();
    // 1e-8 N: the full-slip solve's error of the tension with its kink inside a link
    // (measured 2.7e-9 N; 1e-12 N, rounding, before the node)
    assert!(difference < 1e-8, "{difference:e} N");
    for step in &steps {
        assert_eq!(step.zones[0].zones.len(), 1, "{:?}", step.zones);
    }
    assert_eq!(steps[0].zones[0].zones[0].contact, Contact::Pull);
    // Tendon 1 then bends the rod down: tendon 3's path lengthens and it slides out.
    assert_eq!(steps[1].zones[0].zones[0].contact, Contact::Release);
    // Tendon 3 itself at 1 then 2 N: step 1 is solved on the 2 N step's mesh, so it agrees
    // with the full-slip solve to the two answers' estimated errors.
    let steps = history_of(&robot, 2, &[1.0, 2.0]);
    let estimates = [&steps[0].solution, &pulled].map(|s| s.report.error_estimate.unwrap().tip_position);
    let distance = (tip(&steps[0]) - pulled.tip_position()).norm();
    assert!(
        distance <= estimates[0] + estimates[1],
        "{distance:e} m, estimates {estimates:?}"
    );
    for step in &steps {
        assert_eq!(step.zones[0].zones.len(), 1);
        assert_eq!(step.zones[0].zones[0].contact, Contact::Pull);
    }
}

#[test]
fn a_rigid_tendon_pulled_in_from_rest_needs_no_stiffness() {
    // Main refused step 1: the rigid tendon "sticks" (the same stretched rest material).
    let robot = top_tendon(1.0, true);
    let steps = history_of(&robot, 2, &[1.0, 2.0]);
    let pulled = tdcr::solve(&robot, &Default::default()).unwrap();
    let estimates = [&steps[0].solution, &pulled].map(|s| s.report.error_estimate.unwrap().tip_position);
    let distance = (tip(&steps[0]) - pulled.tip_position()).norm();
    // The two meshes differ (the history's is the 2 N step's): their estimates bound it.
    assert!(
        distance <= estimates[0] + estimates[1],
        "{distance:e} m, estimates {estimates:?}"
    );
    assert!(steps.iter().all(|s| s.zones[0].zones[0].contact == Contact::Pull));
}

#[test]
fn opposite_tendons_load_in_full_slip_and_their_slip_zones_on_one_stretch_on_the_way_back_are_refused() {
    // Tendons 1 and 3 lie on opposite sides, each moving the other's stuck tension by a
    // gain of the size of its own (docs/friction.md section 8, "Opposite tendons"): one held
    // at 1 N, the other pulled to 4.91 N and let back out. Going up, the swept tendon slides
    // in and the held one, whose path the bending lengthens, out, each all along. On the way
    // back the rod straightens and the held tendon's path shortens unevenly: its stuck
    // material's tension would change 3 to 7 times faster along s than friction can hold,
    // so a slip zone opens inside its stuck stretch (section 8, "Slip zones inside a stuck
    // stretch"). Its balance now reads the stuck tension with the other tendon answering
    // (section 8, "opp25": the coupled gain, about -1 N/N against the own -30), and settles;
    // its tension then moves the other tendon's stuck tension, which needs a zone on the
    // same stretch. The two zones' balances are one system, which the march does not
    // solve, so that step is refused at its first pass with both zones, at both tolerances.
    // Before opp25 the first step back did not settle in 40 passes (the held tendon's zone
    // balanced with its own gain alone); from 2026-12-07 (fifteenth session) to slip24 it
    // was refused by the cone check; before, answered as stuck, breaking Coulomb's law
    // without a word.
    for (swept, steps) in [(0, 10), (0, 20), (2, 10), (2, 20)] {
        let ranges = opposite(swept, steps);
        let result = history(&ranges, &Default::default()).unwrap();
        let Some((k, e)) = &result.failure else {
            panic!("tendon {}: every step answered", swept + 1);
        };
        assert_eq!(*k, steps + 1, "tendon {}: refused at step {k}: {e}", swept + 1);
        let e = e.to_string();
        assert!(
            e.contains("tendons 1 and 3 would both slip while stuck on both sides")
                && e.contains("slip zones lie on the same stretch"),
            "tendon {}: {e}",
            swept + 1
        );
        assert_eq!(result.steps.len(), *k);
        // Zones are listed for tendons 1 and 3 in that order.
        let (s, h) = (swept / 2, 1 - swept / 2);
        let contacts =
            |k: usize, t: usize| -> Vec<Contact> { result.steps[k].zones[t].zones.iter().map(|z| z.contact).collect() };
        assert_eq!(
            (contacts(steps, s), contacts(steps, h)),
            (vec![Contact::Pull], vec![Contact::Release])
        );
        for (k, step) in result.steps.iter().enumerate() {
            let e = imbalance(&ranges.robot(k as f64).unwrap(), &step.solution);
            // 1e-8: the solver's tolerance in the wrenches relative to the tension, as above
            assert!(e.max() < 1e-8, "tendon {}, step {k}: imbalance {e:?}", swept + 1);
        }
    }
}

/// Tendons 1 and 3 with friction, tendon `swept + 1` pulled to 4.91 N in `steps` steps and
/// let back out with the other held at 1 N.
fn opposite(swept: usize, steps: usize) -> Ranges {
    let held = 2 - swept;
    let mut robot = top_tendon(0.0, false);
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    robot.tendons[held].set_tension(1.0);
    let values: Vec<f64> = (0..=steps).map(|k| TOP * k as f64 / steps as f64).collect();
    Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(swept)), values)])
        .unwrap()
        .up_down()
}

#[test]
fn opposite_tendons_estimates_are_honest_where_a_tight_history_solves() {
    // Converging is not enough: each answered step is compared with the same history at
    // 1e-11 L, which refuses the same step on the way back with the same reason (slip zones
    // of both tendons on one stretch, as above).
    // While the coupling of opposite tendons was one Jacobi step of the node's system, that
    // history failed at the first step back (the zones did not settle); with the node's
    // joint solve (docs/friction.md section 8, "Opposite tendons") it solves every step.
    // Every step meets the default tolerance with an honest estimate: before the sliding
    // steps were solved again with a node where a tendon's path stops turning ("Sliding
    // steps at an inflection"), tendon 3's steps 4, 5, 6, 16 and 17 (from 1) and tendon 1's
    // steps 1, 2, 20 and 21 missed it (estimates up to 1.9e-6 m against 2.4e-8 m), and
    // tendon 3's step 17 had 1.18 times its estimate as error, step 19 (met) 0.94.
    for swept in [0, 2] {
        let refused = check_opposite(&opposite(swept, 10), swept);
        // The first step back: the two tendons' slip zones on one stretch (docs/friction.md
        // section 8, "opp25"; main: the zones did not settle in 40 passes).
        assert!(
            refused
                .as_ref()
                .is_some_and(|e| e.contains("slip zones lie on the same stretch")),
            "tendon {}: {refused:?}",
            swept + 1
        );
    }
}

/// Every step the opposite-tendon history `ranges` (tendon `swept + 1` swept) answers at
/// the default tolerance slides all along and meets the tolerance, with an estimate not
/// below its error against the same history at 1e-11 L, which answers the same steps and
/// refuses the next one for the same reason, which it returns.
fn check_opposite(ranges: &Ranges, swept: usize) -> Option<String> {
    let answer = history(ranges, &Default::default()).unwrap();
    let steps = answer.steps;
    let reference = history(ranges, &tolerance(1e-11)).unwrap();
    assert_eq!(
        reference.steps.len(),
        steps.len(),
        "tendon {}: the histories stop at different steps",
        swept + 1
    );
    // The reason, without where (the two meshes place the stretch 5e-3 m apart at most).
    let reason = |f: &Option<(usize, Error)>| {
        f.as_ref()
            .map(|(k, e)| (*k, e.to_string().replace(|c: char| c.is_ascii_digit() || c == '.', "")))
    };
    assert_eq!(
        reason(&answer.failure),
        reason(&reference.failure),
        "tendon {}",
        swept + 1
    );
    let length = ranges.robot(0.0).unwrap().length();
    for (k, (step, exact)) in steps.iter().zip(&reference.steps).enumerate() {
        // Every answered step slides all along: the way back is refused at its first step
        // with a stuck stretch (above).
        let sticks = step
            .zones
            .iter()
            .any(|t| t.zones.iter().any(|z| z.contact == Contact::Stick));
        assert!(!sticks, "tendon {}, step {}: a stuck stretch", swept + 1, k + 1);
        let error = (tip(step) - tip(exact)).norm();
        let report = &step.solution.report;
        let estimate = report.error_estimate.expect("every step has an estimate");
        assert_eq!(
            report.tolerance_met,
            Some(true),
            "tendon {}, step {}: {estimate:?}",
            swept + 1,
            k + 1
        );
        // the default tolerance, 1e-7 L, against a reference whose tips are within 1e-10 m
        assert!(
            error <= 1e-7 * length,
            "tendon {}, step {}: tip error {error} m",
            swept + 1,
            k + 1
        );
        // a sliding step's deferred correction is its error to a fraction of a percent
        // (measured 0.998 to 1.002 with the nodes at the inflections): 1 % as on tendon 1's
        // loop
        let ratio = error / estimate.tip_position;
        assert!(
            ratio <= 1.01,
            "tendon {}, step {}: error / estimate {ratio}",
            swept + 1,
            k + 1
        );
    }
    answer.failure.map(|(_, e)| e.to_string())
}

#[test]
fn a_sliding_step_at_an_inflection_is_solved_with_a_node_there() {
    // Tendon 3 swept to 2.455 N with tendon 1 held at 1 N: the rod bends back near
    // s = 0.0188 m, where both tendons' paths stop turning, and on the history's mesh
    // (chosen at the top, 4.91 N, with no inflection) the step missed its tolerance by 77
    // times. It is solved with a node at each of the two points (a few 1e-8 m apart).
    // (The way back is refused: see the opposite loops above.)
    let steps = history(&opposite(2, 10), &Default::default()).unwrap().steps;
    let (top, at) = (&steps[6], &steps[5]);
    let intervals = top.solution.report.intervals;
    assert_eq!(at.solution.report.intervals, intervals + 2);
    assert_eq!(at.solution.report.tolerance_met, Some(true));
    // Its nodes include every node of the history's mesh.
    let s: Vec<f64> = at.solution.nodes.iter().map(|n| n.s).collect();
    for node in &top.solution.nodes {
        assert!(s.contains(&node.s), "node {} is not on the refined mesh", node.s);
    }
}

/// The 101-step opposite histories (tendon 1 or 3 swept in 50 steps each way): every
/// step checked as in the 21-step ones (before honest18 20 of tendon 1's and 31 of tendon
/// 3's sliding steps missed their tolerance, and tendon 3's step 13 met it with 1.9 times
/// its estimate as error; before hist20 tendon 1's stuck step 58 missed it, estimate
/// 1.8e-6 m, error 8.1e-6 m, docs/friction.md section 8, "hist20"). Long (about 40 s in
/// release): `cargo test --release --test history -- --ignored opposite_101`.
#[test]
#[ignore]
fn opposite_101_steps_estimates_are_honest() {
    for swept in [0, 2] {
        check_opposite(&opposite(swept, 50), swept);
    }
}

#[test]
fn a_one_step_history_reports_the_full_slip_solves_work_and_estimate() {
    let robot = prototype(0.1).with_tensions(&[2.0, 0.0, 0.0, 0.0, 0.0]);
    let ranges = Ranges::new(
        robot.clone(),
        vec![(Input::Parameter(Parameter::Tension(0)), vec![2.0])],
    )
    .unwrap();
    let steps = solved(history(&ranges, &Default::default()).unwrap());
    let pulled = tdcr::solve(&robot, &Default::default()).unwrap();
    let (step, full) = (&steps[0].solution.report, &pulled.report);
    // The step is that solve's answer on its mesh (the march holds it): its Newton
    // iterations and its estimate are the step's (main reported 0 and none).
    assert!(
        step.iterations > 0 && step.iterations == full.iterations,
        "{} vs {}",
        step.iterations,
        full.iterations
    );
    assert_eq!(step.error_estimate, full.error_estimate);
    assert_eq!(step.tolerance_met, Some(true));
}

/// The history of tendon 1's `tensions` on the prototype with mu = 0.1.
fn tension_history(tensions: &[f64]) -> Vec<HistoryStep> {
    let ranges = Ranges::new(
        prototype(0.1),
        vec![(Input::Parameter(Parameter::Tension(0)), tensions.to_vec())],
    )
    .unwrap();
    solved(history(&ranges, &Default::default()).unwrap())
}

/// Where tendon 1's first zone of `step` ends, and that zone's contact.
fn first_zone(step: &HistoryStep) -> (f64, Contact) {
    let zone = step.zones[0].zones[0];
    (zone.end, zone.contact)
}

#[test]
fn a_small_reversal_after_full_slip_slides_out_over_part_of_the_first_link() {
    // Steps 3 to 4 of the brief's history (main: "did not settle in 40 passes" at step 4),
    // and letting out 0.1 %, 0.7 %, 1 % and 5 % of the top: each slides out from the base
    // entry and sticks beyond. The stuck tension at a node moves with the node's own
    // tension (the cross-section's load) about 30 times as much the other way, which the
    // march now reads (docs/friction.md section 8, "The march's own tension").
    let top = 5.8406468246737075;
    let mut last = 0.0;
    for fraction in [0.999, 5.8 / top, 0.99, 0.95] {
        let steps = tension_history(&[0.0, 2.375632203228038, top, top * fraction]);
        let (up, back) = (&steps[2], &steps[3]);
        assert!(up.zones[0].zones.iter().all(|z| z.contact == Contact::Pull));
        let (end, contact) = first_zone(back);
        let zones = &back.zones[0].zones;
        assert!(
            contact == Contact::Release && zones.len() == 2 && zones[1].contact == Contact::Stick,
            "{fraction}: {zones:?}"
        );
        // In the continuum the slide-out zone ends where the sliding profile, rising from
        // the new base tension, meets the top's, falling: mu (K(s*) + K(s*)) = ln(top / new)
        // with K the path's turning from the base, read from the top step's tension
        // profile (tau(s) = top exp(-mu K(s))). 2 % (measured 0.8 to 1.0 %): the shape near
        // the base moves with the step (the rod's whole response, beyond the section's).
        let mu = 0.1;
        let turning = |s: f64| -(up.solution.tension_at(0, s).unwrap() / top).ln() / mu;
        let target = (1.0 / fraction).ln() / (2.0 * mu);
        let (mut lo, mut hi) = (0.0, 0.242);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if turning(mid) < target { lo = mid } else { hi = mid }
        }
        // Or within the step's largest link before the boundary: a zone within two nodes
        // of the base gets no boundary node (split.rs), so it ends on a node.
        let link = (back.solution.nodes.windows(2))
            .filter(|w| w[0].s < end.max(lo))
            .map(|w| w[1].s - w[0].s)
            .fold(0.0, f64::max);
        assert!(
            (end - lo).abs() < 0.02 * lo + link,
            "{fraction}: zone ends at {end} m, the continuum at {lo} m, link {link} m"
        );
        // The larger the reversal, the longer the slide-out zone.
        assert!(end > last, "{fraction}: {end} after {last}");
        last = end;
        // 1e-8: every step in global equilibrium to the solver's tolerance (as the loop's).
        let robot = prototype(0.1).with_tensions(&[top * fraction, 0.0, 0.0, 0.0, 0.0]);
        let e = imbalance(&robot, &back.solution);
        assert!(e.max() < 1e-8, "{fraction}: imbalance {e:?}");
    }
}

#[test]
fn a_repeated_step_is_the_last_state_stuck_all_along() {
    // A repeated tension at the top and, after a release, at the bottom of a reversal
    // (main: the second "did not settle" once the split levels read the material).
    let steps = tension_history(&[0.0, 3.0, 3.0, 2.0, 2.0, 4.0]);
    for k in [2, 4] {
        let (last, step) = (&steps[k - 1], &steps[k]);
        assert_eq!(step.solution.tip_position(), last.solution.tip_position());
        assert_eq!(first_zone(step), (0.242, Contact::Stick));
        let report = &step.solution.report;
        assert_eq!(report.iterations, 0);
        assert_eq!(report.error_estimate, last.solution.report.error_estimate);
        assert!(report.error_estimate.is_some() && report.notes.iter().any(|n| n == REPEATED));
        assert_eq!(report.stability.verdict(), "stable");
    }
    // The step after the repeat goes on from the same state: the pull to 4 N slides in all
    // along as from the release to 2 N.
    assert_eq!(first_zone(&steps[5]), (0.242, Contact::Pull));
}

#[test]
fn a_held_step_is_an_equilibrium_and_is_noted_once() {
    // A step repeated twice keeps one note (review: the second copy carried the first's).
    let steps = tension_history(&[0.0, 3.0, 2.0, 2.0, 2.0]);
    for step in &steps[3..] {
        let notes = &step.solution.report.notes;
        assert_eq!(notes.iter().filter(|n| *n == REPEATED).count(), 1, "{notes:?}");
    }
    // The held answer is the equilibrium the solver finds for an input 1e-7 N away, stuck
    // all along: the tips agree to the two answers' estimates plus 1e-7 N times the
    // sliding slope (an upper bound on the stuck one's).
    let near = tension_history(&[0.0, 3.0, 2.0, 2.0000001]);
    assert_eq!(first_zone(&near[3]), (0.242, Contact::Stick));
    let estimate = |s: &HistoryStep| s.solution.report.error_estimate.unwrap().tip_position;
    let slope = (tip(&steps[1]) - tip(&steps[2])).norm();
    let bound = estimate(&steps[3]) + estimate(&near[3]) + 1e-7 * slope;
    let gap = (tip(&steps[3]) - tip(&near[3])).norm();
    assert!(gap <= bound, "held and solved differ by {gap} m, more than {bound} m");
}

#[test]
fn an_unloaded_tendon_is_slack() {
    let steps = tension_history(&[0.0, 2.0, 0.0]);
    for k in [0, 2] {
        // At 0 N there is no normal force, so nothing for friction to hold (main said
        // `release`).
        assert_eq!(first_zone(&steps[k]), (0.242, Contact::Slack));
        assert_eq!(steps[k].zones[0].zones.len(), 1);
    }
}

#[test]
fn pulling_and_releasing_draws_a_closed_loop() {
    let steps = solved(history(&ranges(prototype(0.1), TOP, 10), &Default::default()).unwrap());
    assert_eq!(steps.len(), 21);
    let rest = tip(&steps[0]);
    // Closed: back at 0 N the tendon is slack all along and the robot is where it started
    // (1e-9 m: two Newton solves of the same robot, each to its residual tolerance).
    let closing = (tip(&steps[20]) - rest).norm();
    assert!(closing < 1e-9, "the loop is open by {closing} m");
    // The unloading branch lies on the other side: at every tension between, the tip is
    // further from rest on the way back (the stuck tendon keeps more of its tension).
    for k in 1..10 {
        let (up, down) = (&steps[k], &steps[20 - k]);
        assert_eq!(up.solution.tendons[0].tension, down.solution.tendons[0].tension);
        let (bent_up, bent_down) = ((tip(up) - rest).norm(), (tip(down) - rest).norm());
        assert!(bent_down > bent_up, "step {k}: {bent_down} <= {bent_up}");
    }
    // The first step back leaves the tendon stuck beyond a stretch that slides out.
    let back = &steps[11].zones[0].zones;
    assert_eq!(back.first().map(|z| z.contact), Some(Contact::Release));
    assert_eq!(back.last().map(|z| z.contact), Some(Contact::Stick));
    // Loading from rest slides the tendon in all along.
    assert!(
        steps[1..=10]
            .iter()
            .all(|s| s.zones[0].zones.iter().all(|z| z.contact == Contact::Pull))
    );
    // Every step reports an error estimate, a stuck one too (from its split meshes).
    assert!(steps.iter().all(|s| s.solution.report.error_estimate.is_some()));
}

/// The loop's steps solved with `options`.
fn loop_steps(options: &tdcr::collocation::Options) -> Vec<HistoryStep> {
    solved(history(&ranges(prototype(0.1), TOP, 10), options).unwrap())
}

/// Options with a tip tolerance of `tolerance` L.
fn tolerance(tolerance: f64) -> tdcr::collocation::Options {
    tdcr::collocation::Options {
        tolerance: Some(tolerance),
        ..Default::default()
    }
}

#[test]
fn every_step_meets_the_default_tolerance_with_an_honest_estimate() {
    let steps = loop_steps(&Default::default());
    let reference = loop_steps(&tolerance(1e-11));
    let length = prototype(0.1).length();
    let mut stuck = 0;
    for (k, (step, exact)) in steps.iter().zip(&reference).enumerate() {
        let error = (tip(step) - tip(exact)).norm();
        let report = &step.solution.report;
        let estimate = report.error_estimate.expect("every step has an estimate");
        assert_eq!(report.tolerance_met, Some(true), "step {k}: {estimate:?}");
        // the default tolerance, 1e-7 L, against a reference whose tips are within 1e-10 m
        assert!(error <= 1e-7 * length, "step {k}: tip error {error} m");
        let ratio = error / estimate.tip_position;
        if step.zones[0].zones.iter().any(|z| z.contact == Contact::Stick) {
            stuck += 1;
            // an estimate must not be below the error: the difference of two split meshes
            // plus the carried material's error they share (its interpolation and the
            // inherited node error), which is most of the first stuck step's estimate, so
            // that step sits close to 1 (measured 0.976, 0.114, 0.483; docs/friction.md
            // section 8): the bound is the honesty requirement itself, not a fitted margin
            assert!(ratio <= 1.0, "stuck step {k}: error / estimate {ratio}");
        } else {
            // a sliding step's deferred correction is its error itself to a fraction of a
            // percent (measured 0.999 to 1.003): 1 % for that term and the reference's error
            assert!(ratio <= 1.01, "step {k}: error / estimate {ratio}");
        }
    }
    assert_eq!(stuck, 3, "the first three steps back stick beyond a sliding stretch");
}

#[test]
fn a_stuck_step_meets_the_tolerance_on_few_intervals_with_an_honest_estimate() {
    // Stuck links with per-point multipliers are of order 4 like sliding ones, so the
    // graded levels cut only the links at the stick/slip boundary at the full rate
    // (docs/friction.md section 8, "ord23"): the first stuck step meets 1e-7 L on level 3,
    // every link cut in two and the boundary's in eight (82 intervals). With a constant
    // multiplier per stuck link (order 2) every stuck link was cut in eight (226
    // intervals, 7 times the history's 32): 3 times is the bound between the two.
    let steps = loop_steps(&Default::default());
    let reference = loop_steps(&tolerance(1e-11));
    let history_intervals = steps[10].solution.report.intervals;
    let first = &steps[11];
    assert!(first.zones[0].zones.iter().any(|z| z.contact == Contact::Stick));
    let report = &first.solution.report;
    assert!(
        report.intervals <= 3 * history_intervals,
        "the first stuck step ends on {} intervals (history's mesh {history_intervals})",
        report.intervals
    );
    assert_eq!(report.tolerance_met, Some(true));
    let error = (tip(first) - tip(&reference[11])).norm();
    let estimate = report.error_estimate.expect("a stuck step has an estimate");
    // the honesty requirement itself (measured 0.285)
    assert!(error <= estimate.tip_position, "error {error} m, estimate {estimate:?}");
}

#[test]
fn a_stuck_steps_last_level_settles_in_two_passes() {
    // A stuck link's multiplier divides by the capacity of the link's last evaluation, so
    // Newton's own iterations carry it along with the shape and the second pass of march
    // and Newton only confirms the pattern (docs/friction.md section 8, "Where a stuck
    // step's levels spend").
    let steps = loop_steps(&Default::default());
    let first = &steps[11];
    assert!(first.zones[0].zones.iter().any(|z| z.contact == Contact::Stick));
    // The report counts every solve of the step: the history's mesh and the split levels
    // (59, 113 and 226 intervals before ord23, the last on 82 since). Measured 26 in all (30 since ord23); while the last march's capacity was
    // held over each Newton solve, the three levels alone took 14 + 14 + 11 = 39.
    let iterations = first.solution.report.iterations;
    assert!(
        iterations <= 30,
        "the first stuck step's solves took {iterations} iterations"
    );
}

#[test]
fn the_fine_loops_stuck_steps_have_honest_estimates() {
    // 50 steps each way: the stick/slip boundary moves about one link of the history's
    // mesh per step, so each stuck step's boundary lies next to the last one, the kink of
    // the carried material (docs/friction.md section 8, "The material's kinks").
    let steps = solved(history(&ranges(prototype(0.1), TOP, 50), &Default::default()).unwrap());
    // 1e-10 L: its stuck steps' estimates are 4e-13 to 5e-11 m, far below the errors checked
    let reference = solved(history(&ranges(prototype(0.1), TOP, 50), &tolerance(1e-10)).unwrap());
    let length = prototype(0.1).length();
    let (mut stuck, mut missed) = (0, Vec::new());
    for (k, (step, exact)) in steps.iter().zip(&reference).enumerate() {
        if !step.zones[0].zones.iter().any(|z| z.contact == Contact::Stick) {
            continue;
        }
        stuck += 1;
        let error = (tip(step) - tip(exact)).norm();
        let report = &step.solution.report;
        let estimate = report.error_estimate.expect("a stuck step has an estimate");
        // the honesty requirement itself, as on the 10-step loop (measured at most 0.988)
        assert!(
            error <= estimate.tip_position,
            "stuck step {k}: error {error} m, estimate {estimate:?}"
        );
        if report.tolerance_met == Some(true) {
            // the default tolerance, 1e-7 L, where the step says it meets it
            assert!(error <= 1e-7 * length, "stuck step {k}: tip error {error} m");
        } else {
            missed.push(k);
        }
    }
    assert_eq!(stuck, 16, "the first 16 steps back stick beyond a sliding stretch");
    // Every stuck step meets the tolerance with the quintic material (docs/friction.md
    // section 8). With the cubic the first four steps back missed it and said so (51 to 54:
    // the cubic's interpolation of a material without kinks); with stencils straddling the
    // kinks eleven did (51 to 61), with tip errors up to 9.3e-7 m.
    assert_eq!(missed, Vec::<usize>::new(), "stuck steps missing the tolerance");
}

#[test]
fn a_stuck_step_cut_short_by_the_interval_cap_does_not_claim_its_tolerance() {
    // A cap of the start mesh's 32 intervals leaves the split levels 2 x the history's
    // intervals (the history's mesh is within the cap too): graded level 3 cuts the stuck
    // links in 8 and the sliding ones in 2, more than that, so every stuck step ends at
    // level 1 or 2, whose difference leaves out the sliding links' error (docs/friction.md
    // section 8, "Graded levels"): none may say it meets the tolerance. 1e-5 L: loose
    // enough that a level-1 difference meets it (step 13's did before, 1.4e-8 m on 47
    // intervals), so the test fails where the cut-short step claims it.
    let capped = tdcr::collocation::Options {
        max_intervals: 32,
        tolerance: Some(1e-5),
        ..Default::default()
    };
    let steps = loop_steps(&capped);
    let mut stuck = 0;
    for (k, step) in steps.iter().enumerate() {
        if step.zones[0].zones.iter().any(|z| z.contact == Contact::Stick) {
            stuck += 1;
            assert_eq!(step.solution.report.tolerance_met, Some(false), "stuck step {k}");
        }
    }
    assert_eq!(stuck, 3, "the first three steps back stick beyond a sliding stretch");
}

#[test]
fn a_stuck_step_converges_on_split_meshes() {
    // Without a tolerance a stuck step is solved once more on its mesh split in two, and
    // returns that answer: 32, 64 and 128 intervals from meshes of 16, 32 and 64.
    let tip_back = |intervals: usize| {
        let options = tdcr::collocation::Options {
            tolerance: None,
            intervals,
            ..Default::default()
        };
        let steps = loop_steps(&options);
        assert_eq!(steps[11].solution.report.intervals, 2 * intervals);
        tip(&steps[11])
    };
    let reference = tip(&loop_steps(&tolerance(1e-11))[11]);
    let errors: Vec<f64> = [16, 32, 64].iter().map(|&n| (tip_back(n) - reference).norm()).collect();
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "errors {errors:?}");
    let order = (errors[0] / errors[2]).log2() / 2.0;
    // a stuck link's friction multiplier was constant across it: order 2 (docs/friction.md
    // section 8; per point since ord23, order 4 where the boundary sits at a node); single halvings are irregular, as the stick/slip boundary moves within
    // its link (measured 1.9e-5, 6.7e-7, 3.3e-7 m: 4.8 then 1.0, 2.9 over both); 1.8 is
    // order 2 with that room
    assert!(order > 1.8, "errors {errors:?}: order {order}");
}

#[test]
fn the_loop_widens_with_friction() {
    let width = |mu: f64| -> f64 {
        let steps = solved(history(&ranges(prototype(mu), TOP, 6), &Default::default()).unwrap());
        (1..6)
            .map(|k| (tip(&steps[k]) - tip(&steps[12 - k])).norm())
            .fold(0.0, f64::max)
    };
    let widths = [width(0.05), width(0.1), width(0.2)];
    assert!(
        widths[0] > 0.0 && widths[0] < widths[1] && widths[1] < widths[2],
        "widths {widths:?}"
    );
}

#[test]
fn a_stuck_step_moves_the_tip_less_than_without_friction() {
    let steps = solved(history(&ranges(prototype(0.1), TOP, 10), &Default::default()).unwrap());
    let (peak, back) = (&steps[10], &steps[11]);
    assert!(back.zones[0].zones.iter().any(|z| z.contact == Contact::Stick));
    let mut smooth = prototype(0.0);
    smooth.tendons[0].friction = None;
    let at = |t: f64| {
        tdcr::solve(&smooth.with_tensions(&[t, 0.0, 0.0, 0.0, 0.0]), &Default::default())
            .unwrap()
            .tip_position()
    };
    let frictionless = (at(back.solution.tendons[0].tension) - at(TOP)).norm();
    let stuck = (tip(back) - tip(peak)).norm();
    assert!(
        stuck < frictionless,
        "stuck step {stuck} m, frictionless {frictionless} m"
    );
}

#[test]
fn every_step_is_in_global_equilibrium() {
    let ranges = ranges(prototype(0.1), TOP, 5);
    let steps = solved(history(&ranges, &Default::default()).unwrap());
    for (k, step) in steps.iter().enumerate() {
        let robot = ranges.robot(k as f64).unwrap();
        let e = imbalance(&robot, &step.solution);
        // 1e-8: the solver's tolerance in the wrenches relative to the tension, as for the
        // full-slip solves
        assert!(e.max() < 1e-8, "step {k}: imbalance {e:?}");
    }
}

#[test]
fn a_history_step_that_is_not_finite_is_refused() {
    let values = vec![0.0, f64::NAN, 1.0];
    let Err(Error::InvalidInput { field, problem, .. }) =
        Ranges::new(prototype(0.1), vec![(Input::Parameter(Parameter::Tension(0)), values)])
    else {
        panic!("a NaN step was accepted");
    };
    assert_eq!(field, "tension.1");
    assert!(problem.contains("NaN"), "{problem}");
}

#[test]
fn a_rigid_tendon_that_sticks_is_refused_with_what_to_set() {
    let mut robot = prototype(0.1);
    robot.tendons[0].stiffness = None;
    let result = history(&ranges(robot, TOP, 4), &Default::default()).unwrap();
    // A model limit, not bad input (front25): the rigid tendon is valid, its stuck tension
    // indeterminate.
    let Some((k, Error::ModelLimit { field, hint, .. })) = result.failure else {
        panic!("a rigid tendon was let out without an error: {:?}", result.failure);
    };
    // Loading from rest slides all along (no stick zone): the first step back sticks.
    assert_eq!(k, 5);
    assert_eq!(field, "tendons[0].stiffness");
    assert!(hint.contains("stiffness"), "{hint}");
}

#[test]
fn a_residual_tolerance_tighter_than_the_stick_row_resolves_is_named() {
    // The prototype's loop with a residual tolerance of 5e-14 (the sliding steps reach
    // about 2e-14): the first step back sticks beyond 45 mm at about 4 N, whose stick row
    // resolves log tension only to E_t A_t eps / tau, about 1.1e-13, so Newton cannot reach
    // 5e-14 there. The tension is healthy (not going slack), so the step keeps Newton's
    // error, whose hint now names the residual tolerance (main: only "take smaller steps",
    // which does not help).
    let options = tdcr::collocation::Options {
        residual_tolerance: 5e-14,
        ..Default::default()
    };
    let result = history(&ranges(prototype(0.1), TOP, 10), &options).unwrap();
    let Some((k, Error::NotConverged { hint, .. })) = &result.failure else {
        panic!("{:?}", result.failure);
    };
    assert!(*k > 10, "a step back, where the tendon sticks: step {k}, {hint}");
    assert!(hint.contains("loosen residual_tolerance"), "{hint}");
}

#[test]
fn a_history_without_friction_is_refused() {
    let ranges = ranges(cases::prototype(), TOP, 2);
    let Err(Error::InvalidInput { problem, .. }) = history(&ranges, &Default::default()) else {
        panic!("a history without friction was solved");
    };
    assert!(problem.contains("none has friction"), "{problem}");
}

#[test]
fn up_down_goes_back_without_repeating_the_top() {
    let ranges = ranges(prototype(0.1), 2.0, 2);
    let values = &ranges.inputs()[0].1;
    assert_eq!(values, &vec![0.0, 1.0, 2.0, 1.0, 0.0]);
    assert_eq!(ranges.steps(), 5);
}

#[test]
fn a_failed_step_reports_no_estimate_tolerance_or_verdict() {
    // With at most 6 Newton iterations the solve that chooses the history's mesh converges
    // and step 1 (from rest, 8 iterations) does not. Until 2026-12-07 (fifteenth session)
    // its error's report kept that solve's estimate, `tolerance_met` and `stable` verdict,
    // none of which belongs to the failed step (a new-user check).
    let options = tdcr::collocation::Options {
        max_iterations: 6,
        ..Default::default()
    };
    let result = history(&ranges(prototype(0.1), TOP, 10), &options).unwrap();
    let Some((0, Error::NotConverged { report, .. })) = &result.failure else {
        panic!("{:?}", result.failure);
    };
    assert_eq!(report.error_estimate, None);
    assert_eq!(report.tolerance_met, None);
    assert!(
        matches!(report.stability, tdcr::Stability::Unknown { .. }),
        "{:?}",
        report.stability
    );
}
