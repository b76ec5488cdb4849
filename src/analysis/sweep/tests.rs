//! Sweeps: events located between steps, and the branch independent of the step size.

use super::*;
use crate::model::parameter::Parameter;
use crate::{Field, Rod, Routing, Tendon};
use nalgebra::Vector3;

/// `count` evenly spaced values from `a` to `b`.
fn linspace(a: f64, b: f64, count: usize) -> Vec<f64> {
    (0..count)
        .map(|k| a + (b - a) * k as f64 / (count - 1) as f64)
        .collect()
}

fn run(base: Robot, input: Input, values: Vec<f64>, options: collocation::Options) -> Vec<Step> {
    let ranges = Ranges::new(base, vec![(input, values)]).unwrap();
    let out = sweep(&ranges, SweepSolver::Collocation(options), None);
    assert!(out.failure.is_none(), "{:?}", out.failure);
    out.steps
}

/// The prototype's tendon 1 driven by its pull-in: under the rod's weight it is slack up
/// to about 2.06 mm (tests/cli.rs), so the third of 0, 2, 4, 6 mm finds it taut, and the
/// sweep locates where: the pull-in at which its solved tension leaves zero.
#[test]
fn a_tendon_going_taut_is_located() {
    let mut base = crate::cases::case_s();
    base.tendons[0].set_displacement(0.0);
    let steps = run(
        base.clone(),
        Input::Displacement(0),
        vec![0.0, 0.002, 0.004, 0.006],
        Default::default(),
    );
    let counts: Vec<usize> = steps.iter().map(|s| s.events.len()).collect();
    assert_eq!(counts, [0, 0, 1, 0]);
    let event = &steps[2].events[0];
    assert_eq!(event.kind, Kind::Taut(0));
    let Some((Input::Displacement(0), q)) = event.value else {
        panic!("{event:?}")
    };
    assert!(
        event.to_string().starts_with("tendon 1 taut at displacement.1 = "),
        "{event}"
    );
    // Either side of the located pull-in (6e-9 m = 1e-6 of the 6 mm range, the bracket's
    // width, plus its half) the tendon is slack, then taut.
    for (dq, taut) in [(-6e-9, false), (6e-9, true)] {
        let mut r = base.clone();
        r.tendons[0].set_displacement(q + dq);
        let s = collocation::solve(&r, &Default::default()).unwrap();
        assert_eq!(s.tendons[0].tension > 0.0, taut, "{q} {dq}");
    }
}

/// About twice Euler's load on a 0.5 m rod buckled towards -x by a 10 mN imperfection,
/// a tendon on the +x side: at 1 N the robot ends bent towards +x (docs/stability.md); the
/// sweep reports the bifurcation where the buckled state loses stability out of its plane
/// (0.124 N, at both step sizes) and a snap before 1 N; the steps after it are quiet.
#[test]
fn a_snap_through_is_located() {
    let mut base =
        Robot::new(Rod::tube(0.5, 0.001, 0.0, 200e9, 0.3)).with_tendon(Tendon::new(Routing::straight(0.015, 0.0), 0.0));
    base.loads.distributed_force = Field::Constant(Vector3::new(0.0, 0.0, -0.24));
    base.loads.tip_force = Vector3::new(-0.01, 0.0, -3.0);
    let mut located = Vec::new();
    for count in [3, 5] {
        let steps = run(
            base.clone(),
            Input::Parameter(Parameter::Tension(0)),
            linspace(0.0, 2.0, count),
            Default::default(),
        );
        let events: Vec<&Event> = steps.iter().flat_map(|s| &s.events).collect();
        let kinds: Vec<&str> = events.iter().map(|e| e.kind.name()).collect();
        assert_eq!(kinds, ["bifurcation", "snap"], "{events:?}");
        let Kind::Snap { distance } = events[1].kind else {
            panic!("{:?}", events[1])
        };
        // 0.5 to 1 m: the tip crosses from about -x to +x on a 0.5 m rod.
        assert!((0.5..1.0).contains(&distance), "{distance}");
        assert!((0.0..1.0).contains(&events[1].value.unwrap().1), "{events:?}");
        located.push(events[0].value.unwrap().1);
        let last = steps.last().unwrap().solution.tip_position();
        assert!(last.x > 0.0, "{last:?}");
        assert!(steps.iter().skip(2).all(|s| s.events.is_empty()));
    }
    // The same bifurcation from both step sizes: 2e-6 N is 1e-6 of the 2 N range, twice
    // (each location is within half its bracket of the crossing).
    assert!((located[0] - located[1]).abs() < 2e-6, "{located:?}");
}

/// Issue 25's sweep: a two-segment robot standing along +z (0.4 m, radius 0.5 mm, 50 GPa,
/// six straight tendons at 10 mm, three ending at mid-length) under a 0.3 N payload, about
/// eight times its Euler load, buckled towards +x by a 0.3 mN imperfection; tendon 5 (at
/// 180 deg, on the -x side) pulled from 0 to 0.2 N. The buckled state loses stability out
/// of its plane at 1.7793 mN (a bifurcation), and the robot snaps there to the -x side (it
/// swings round the vertical through states out of the plane, docs/stability.md).
fn payload_robot() -> Robot {
    let mut robot = Robot::new(Rod::tube(0.4, 0.0005, 0.0, 50e9, 0.3));
    for (k, deg) in [0.0f64, 120.0, 240.0, 60.0, 180.0, 300.0].iter().enumerate() {
        let a = deg.to_radians();
        let mut tendon = Tendon::new(Routing::straight(0.01 * a.cos(), 0.01 * a.sin()), 0.0);
        if k < 3 {
            tendon = tendon.ending_at(0.2);
        }
        robot = robot.with_tendon(tendon);
    }
    robot.loads.tip_force = Vector3::new(3e-4, 0.0, -0.3);
    robot
}

/// The smallest eigenvalue of the symmetric part of the tip's positional compliance
/// d p(L) / d F_tip (m/N): negative proves the state unstable (pushing the tip moves it
/// against the push).
fn least_compliance(robot: &Robot, solution: &Solution) -> f64 {
    let s = collocation::sensitivity::tip_sensitivities(robot, solution).unwrap();
    let c = s.compliance().fixed_view::<3, 3>(0, 0).into_owned();
    (0.5 * (c + c.transpose())).symmetric_eigenvalues().min()
}

/// The payload robot past its out-of-plane bifurcation (tendon 5 at 1.7793 mN): the default
/// solve from rest returns the stable state, hanging on the tendon's side (tip at x < 0),
/// not the unstable planar state bent towards the lateral load. Just past the bifurcation
/// (1.8 mN) the load path crosses it near the full load (98 % of the way): the planar state
/// loses stability out of its plane, no stable branch leaves it, and the robot swings round
/// the vertical to the tendon's side. The path snaps there, and the report says so
/// (docs/stability.md, "Snapping from a bifurcation"). Before the corrector's Newton step at
/// the predicted point (2026-12-06) the path wandered off the planar branch into the
/// swinging family, went round it for 400 steps and landed from a fold ("snaps at the
/// fold", 460 iterations): the same state, reached by a less physical route. The sweep
/// tests below locate the bifurcation at 1.7793 mN to 1e-6 of the range.
#[test]
fn the_payload_robot_past_its_bifurcation_is_stable() {
    let values = vec![0.0018, 0.02, 0.1];
    let ranges = Ranges::new(payload_robot(), vec![(Input::Parameter(Parameter::Tension(4)), values)]).unwrap();
    for k in 0..3 {
        let robot = ranges.robot(k as f64).unwrap();
        let solution = collocation::solve(&robot, &Default::default()).unwrap();
        let report = &solution.report;
        assert_eq!(report.stability.verdict(), "stable", "step {k}: {report:?}");
        // -1e-9 m/N: rounding in a compliance of about 1 m/N.
        assert!(least_compliance(&robot, &solution) > -1e-9, "step {k}");
        let tip = solution.tip_position();
        // The stable state hangs on the tendon's side (x = -0.18 m, z = -0.22 m), in the
        // plane of the tendon and the lateral load (1e-6 m: the swing mode is nearly neutral).
        assert!(tip.x < -0.17 && tip.y.abs() < 1e-6 && tip.z < -0.2, "step {k}: {tip:?}");
        let crate::report::PathTaken::LoadPath { bifurcations, .. } = &report.path else {
            panic!("step {k}: {:?}", report.path)
        };
        // 300: the 1.8 mN solve takes about 190 iterations (most of them the damped motion's
        // time steps), the others below 40.
        assert!(report.iterations < 300, "step {k}: {} iterations", report.iterations);
        // At 1.8 mN the snap from the bifurcation, recorded on the path, with its note; the
        // larger tensions pull the robot to the tendon's side before any bifurcation.
        let snapped = report
            .notes
            .iter()
            .any(|n| n.contains("loses its stability at the bifurcation") && n.contains("it snaps there"));
        assert_eq!(snapped, k == 0, "step {k}: {:?}", report.notes);
        assert_eq!(bifurcations.len(), usize::from(k == 0), "step {k}: {bifurcations:?}");
    }
}

/// The payload robot warm-started at 1.7 mN (stable, bent towards the lateral load, +x) and
/// solved at 1.8, 1.9 and 5 mN, as a sweep's step does: the warm start is unstable past the
/// bifurcation at 1.7793 mN, its Newton homotopy ends on the unstable planar state, and the
/// load path from rest crosses the bifurcation with no stable branch beyond. A warm solve's
/// path snaps there as a cold one's does (it ended on the unstable planar state, labelled
/// `load_path`, before 2026-12-06), to the stable state on the tendon's side.
#[test]
fn a_warm_solve_past_the_bifurcation_snaps_to_the_stable_state() {
    let robot = |t: f64| {
        let mut r = payload_robot();
        r.tendons[4].set_tension(t);
        r
    };
    let start = collocation::solve(&robot(0.0017), &Default::default()).unwrap();
    assert!(start.report.stability.is_stable() && start.tip_position().x > 0.17);
    for t in [0.0018, 0.0019, 0.005] {
        let solution = collocation::solve_from(&robot(t), &Default::default(), &start).unwrap();
        let (tip, report) = (solution.tip_position(), &solution.report);
        let case = format!(
            "{t} N: tip {tip:?}, {} {:?} {:?}",
            report.stability, report.path, report.notes
        );
        assert!(report.stability.is_stable(), "{case}");
        // -1e-9 m/N: rounding in a compliance of about 1 m/N.
        assert!(least_compliance(&robot(t), &solution) > -1e-9, "{case}");
        // The tendon's side, as cold (1e-6 m: the swing mode is nearly neutral).
        assert!(tip.x < -0.17 && tip.y.abs() < 1e-6 && tip.z < -0.2, "{case}");
        assert!(
            report.notes.iter().any(|n| n.contains("it snaps there")) && report.path.bifurcations().len() == 1,
            "{case}"
        );
        // 300: measured 143-204 iterations (most of them the damped motion's time steps).
        assert!(report.iterations < 300, "{case}: {} iterations", report.iterations);
    }
    // A sweep's bisection keeps to the warm start's branch instead (crate-internal
    // `solve_on_branch`): the planar state, unstable, where the branch loses stability.
    let on_branch = collocation::solve_on_branch(&robot(0.0019), &Default::default(), &start).unwrap();
    assert!(on_branch.tip_position().x > 0.17, "{:?}", on_branch.tip_position());
    assert_eq!(on_branch.report.stability.verdict(), "unstable");
}

/// The payload robot from rest just past the loss of stability of its planar state bent
/// towards the lateral load (+x), at 1.7793 mN: the load path crosses that loss near the full
/// load, where the swing's conjugate point lies within the neutral zone at the base and the
/// lowest vibration mode decides it (docs/stability.md, "A root at the base"), and snaps
/// there. Each answer is stable with a positive tip compliance: at 1.78 mN a state out of
/// the plane (tip at (0.006, -0.181, -0.218) m, measured: one of the family of states through
/// which the +x state, unstable from 1.7793 mN, swings round the vertical to the -x one,
/// stable from about 1.7807 mN), at 1.79 and 1.794 mN the -x state; at 1.7794 mN, 0.1 uN
/// past the loss, a member of the swing near +x (tip at (0.157, -0.089, -0.218) m), which
/// the damped motion reaches only since it takes a state at rest as it is (module `relax`;
/// before, 3 062 iterations and the +x state, `UNSTABLE`). Before 2026-12-06 the
/// path ended at 1.78 mN on the +x state, labelled `stable` though its tip compliance has an
/// eigenvalue of -1.5e6 m/N (out of the plane).
#[test]
fn the_payload_robot_just_past_the_loss_of_stability_snaps_to_a_stable_state() {
    for t in [0.0017794, 0.00178, 0.00179, 0.001794] {
        let mut robot = payload_robot();
        robot.tendons[4].set_tension(t);
        let solution = collocation::solve(&robot, &Default::default()).unwrap();
        let (tip, report) = (solution.tip_position(), &solution.report);
        let case = format!("{t} N: tip {tip:?}, {} {:?}", report.stability, report.path);
        assert!(report.stability.is_stable(), "{case}");
        // -1e-9 m/N: rounding in a compliance of about 1 m/N.
        assert!(least_compliance(&robot, &solution) > -1e-9, "{case}");
        // Not the +x state (tip x = 0.181 m), which lost its stability: 0.17 m leaves 11 mm,
        // the swing's states at 1.78 mN are 0.17 m from it.
        assert!(tip.x < 0.17, "{case}");
        assert!(
            report.notes.iter().any(|n| n.contains("it snaps there")) && report.path.bifurcations().len() == 1,
            "{case}"
        );
        // 300: measured 145-203 iterations (most of them the damped motion's time steps).
        assert!(report.iterations < 300, "{case}: {} iterations", report.iterations);
    }
}

/// The planar payload state just past its loss of stability (1.7793 mN): the conjugate point
/// of the swing round the vertical lies within the neutral zone at the base (4.4e-8 L at
/// 1.78 mN, 6.9e-7 L at 1.79, 9.5e-7 L at 1.794), where a round column's exact zero lies
/// too; the lowest
/// vibration mode decides it, and the verdict is `unstable`, as the tip compliance proves
/// (docs/stability.md, "A root at the base"). At 1.75 mN the state is stable.
#[test]
fn no_stable_verdict_on_the_planar_payload_state_past_its_loss_of_stability() {
    let robot = |t: f64| {
        let mut r = payload_robot();
        r.tendons[4].set_tension(t);
        r
    };
    let start = collocation::solve(&robot(0.00175), &Default::default()).unwrap();
    assert_eq!(start.report.stability.verdict(), "stable");
    // -1e-9 m/N: rounding in a compliance of about 1 m/N.
    assert!(least_compliance(&robot(0.00175), &start) > -1e-9);
    let nearest = collocation::Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    for t in [0.00178, 0.00179, 0.001794] {
        let solution = collocation::solve_from(&robot(t), &nearest, &start).unwrap();
        let tip = solution.tip_position();
        // The planar state bent towards the lateral load (1e-6 m: the swing is nearly neutral).
        assert!(tip.x > 0.17 && tip.y.abs() < 1e-6, "{t} N: {tip:?}");
        assert_eq!(solution.report.stability.verdict(), "unstable", "{t} N");
        // Measured -1.5e6, -1.0e5 and -7.3e4 m/N: -1e3 m/N is far outside any rounding.
        let least = least_compliance(&robot(t), &solution);
        assert!(least < -1e3, "{t} N: {least:e} m/N");
    }
}

#[test]
fn the_payload_sweep_is_the_same_at_every_step_size() {
    let ranges = |count| {
        Ranges::new(
            payload_robot(),
            vec![(Input::Parameter(Parameter::Tension(4)), linspace(0.0, 0.2, count))],
        )
        .unwrap()
    };
    let mut runs = Vec::new();
    for count in [11, 21, 41] {
        let ranges = ranges(count);
        let out = sweep(&ranges, SweepSolver::Collocation(Default::default()), None);
        assert!(out.failure.is_none(), "{:?}", out.failure);
        for (k, step) in out.steps.iter().enumerate() {
            let robot = ranges.robot(k as f64).unwrap();
            let least = least_compliance(&robot, &step.solution);
            if step.solution.report.stability.is_stable() {
                // -1e-9 m/N: rounding in a compliance of about 1 m/N.
                assert!(
                    least > -1e-9,
                    "step {k} of {count}: stable with compliance {least:e} m/N"
                );
            }
        }
        runs.push(out.steps);
    }
    let events: Vec<Vec<(&str, f64)>> = runs
        .iter()
        .map(|steps| {
            steps
                .iter()
                .flat_map(|s| &s.events)
                .map(|e| (e.kind.name(), e.value.unwrap().1))
                .collect()
        })
        .collect();
    for run in &events {
        let kinds: Vec<&str> = run.iter().map(|e| e.0).collect();
        assert_eq!(kinds, ["bifurcation", "snap"], "{events:?}");
        // 2e-7 N: 1e-6 of the 0.2 N range, the events' location. The snap is where the
        // stable state the robot was on lost its stability (no stable state is near past
        // it; the sweep found the -x one only at a later step, which depends on the step
        // size), so it is at the bifurcation itself.
        for e in [0, 1] {
            assert!((run[e].1 - events[0][e].1).abs() < 2e-7, "{events:?}");
        }
        // Where the planar state's lowest vibration mode changes sign, 1.7793065 mN
        // (bisected to 1e-11 N on `collocation::vibration` of the +x state solved from
        // 1.75 mN with `nearest`, 2026-12-06), to 2e-7 N (1e-6 of the range: the bracket);
        // its tip compliance turns negative there. Before 2026-12-06 the sweep located
        // 1.795 mN: the swing's conjugate point leaves the neutral zone at the base there, and
        // the verdict counted none before.
        assert!((run[0].1 - 1.7793065e-3).abs() < 2e-7, "{events:?}");
        assert!((run[1].1 - run[0].1).abs() < 2e-7, "{events:?}");
    }
    // The same jump at every step size (1e-7 m: twice the tip tolerance of the landing
    // solve, 1e-7 L = 4e-8 m): it lands on the -x branch at the snap (whose state there is
    // stable from 1.7807 mN on; the robot swings to it through states out of the plane).
    let jumps: Vec<f64> = runs
        .iter()
        .map(|steps| {
            let snap = steps.iter().flat_map(|s| &s.events).find(|e| e.kind.name() == "snap");
            let Some(Event {
                kind: Kind::Snap { distance },
                from_unstable: false,
                ..
            }) = snap
            else {
                panic!("{snap:?}")
            };
            *distance
        })
        .collect();
    // 0.36 m: the tip crosses from x = +0.18 m to x = -0.18 m.
    assert!((jumps[0] - 0.3614).abs() < 1e-3, "{jumps:?}");
    assert!(jumps.iter().all(|j| (j - jumps[0]).abs() < 1e-7), "{jumps:?}");
    // The same branch: every 0.02 N the three sweeps agree (2e-9 m: the solves' tolerance,
    // each state reached from a different warm start) where they are stable.
    for (k, step) in runs[0]
        .iter()
        .enumerate()
        .filter(|(_, s)| s.solution.report.stability.is_stable())
    {
        for (run, stride) in runs[1..].iter().zip([2, 4]) {
            let other = &run[k * stride].solution;
            let gap = (other.tip_position() - step.solution.tip_position()).norm();
            assert!(gap < 2e-9, "step {k}: {gap:e} m");
            assert_eq!(
                other.report.stability.verdict(),
                step.solution.report.stability.verdict()
            );
        }
    }
}

/// Euler's column (the prototype's rod along +z, P_cr = pi^2 EI / (4 L^2) = 0.177893 N,
/// docs/stability.md) loaded past P_cr in a sweep: the straight column that every step
/// ends on is stable below P_cr and unstable (two directions) above, and each step's
/// verdict says so; the sweep locates the bifurcation at P_cr.
#[test]
fn every_step_has_its_own_verdict_and_the_bifurcation_is_located() {
    let p_cr = 0.177893;
    let base = Robot::new(Rod::tube(0.242, 0.0004, 0.0, 210e9, 0.3125));
    let options = collocation::Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    let values: Vec<f64> = [0.9, 0.95, 1.05, 1.1].iter().map(|f| -f * p_cr).collect();
    let steps = run(base, Input::Parameter(Parameter::TipForce(2)), values, options);
    let verdicts: Vec<&str> = steps.iter().map(|s| s.solution.report.stability.verdict()).collect();
    assert_eq!(verdicts, ["stable", "stable", "unstable", "unstable"]);
    let counts: Vec<usize> = steps.iter().map(|s| s.events.len()).collect();
    assert_eq!(counts, [0, 0, 1, 0]);
    let e = &steps[2].events[0];
    assert_eq!(
        e.kind,
        Kind::Bifurcation {
            before: Instability::Directions(0),
            after: Instability::Directions(2)
        }
    );
    // P_cr of the rod to 5e-4 relative: the discretization's error in the critical load
    // at the default tolerance (docs/stability.md measures 0.08 % for the trace's coarser
    // location); the bracket itself is 1e-6 of the range wide.
    let p = -e.value.unwrap().1;
    assert!((p / p_cr - 1.0).abs() < 5e-4, "{p} against {p_cr}");
}

/// Euler's column of the test above, swept with `equilibrium = "nearest"` from 1.1 to 10
/// P_cr: every step is the straight column, unstable, and its second buckling load (9 P_cr
/// for a clamped-free column, where two more directions become unstable) is crossed from an
/// unstable state; the sweep locates it along that unstable branch, and its text says so.
#[test]
fn a_bifurcation_on_an_unstable_branch_is_located_along_it() {
    let p_cr = 0.177893;
    let base = Robot::new(Rod::tube(0.242, 0.0004, 0.0, 210e9, 0.3125));
    let options = collocation::Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    let values: Vec<f64> = [1.1, 5.0, 10.0].iter().map(|f| -f * p_cr).collect();
    let steps = run(base, Input::Parameter(Parameter::TipForce(2)), values, options);
    let verdicts: Vec<&str> = steps.iter().map(|s| s.solution.report.stability.verdict()).collect();
    assert_eq!(verdicts, ["unstable", "unstable", "unstable"]);
    let counts: Vec<usize> = steps.iter().map(|s| s.events.len()).collect();
    assert_eq!(counts, [0, 0, 1]);
    let e = &steps[2].events[0];
    assert_eq!(
        e.kind,
        Kind::Bifurcation {
            before: Instability::Directions(2),
            after: Instability::Directions(4)
        }
    );
    assert!(e.from_unstable, "{e:?}");
    assert!(
        e.to_string()
            .ends_with("(on an unstable branch the robot had already left)"),
        "{e}"
    );
    // 9 P_cr to 2e-4 relative: the discretization's error in the second mode's critical
    // load at the default tolerance (measured 2.2e-5; the first mode's bound above is 5e-4),
    // with p_cr rounded to 6 digits; the bracket itself is 1e-6 of the range wide.
    let p = -e.value.unwrap().1;
    assert!((p / (9.0 * p_cr) - 1.0).abs() < 2e-4, "{p} against {}", 9.0 * p_cr);
}

/// The gallery's snapping column (docs/gallery/column.toml) swept from 0 to 0.2 N of its
/// tendon in one step: the state buckled towards the imperfection (-x) loses stability at
/// 0.1240275 N, and the bisection's warm solve at 0.125 N may reach the state the robot snaps
/// to (+x, 0.8 m away) by the load path from rest. That point left the -x branch and belongs
/// to the right end of the bracket; taken for the left one (the corrector's refresh rule,
/// docs/numerics.md "Corrector"), the sweep narrowed on the step's end and reported a snap at
/// 0.1499992 N and a second one of 0.0 mm.
#[test]
fn a_bisection_point_that_snapped_belongs_past_the_change() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/gallery/column.toml")).unwrap();
    let base = crate::io::parse(&text, "column.toml").unwrap().robot;
    let steps = run(
        base,
        Input::Parameter(Parameter::Tension(0)),
        vec![0.0, 0.2],
        Default::default(),
    );
    let events = &steps[1].events;
    let kinds: Vec<&str> = events.iter().map(|e| e.kind.name()).collect();
    assert_eq!(kinds, ["bifurcation", "snap"], "{events:?}");
    for e in events {
        // Both at the located loss of stability, 0.1240275 N (0.1241737 N before 2026-12-06:
        // where the swing's conjugate point left the verdict's neutral zone at the base; the
        // tip compliance is negative from 0.12404 N, -4.0e5 m/N there); the
        // bracket is 1e-6 of the 0.2 N range wide, and 1e-6 N more allows for the guides'
        // error in where the count changes
        let tension = e.value.as_ref().unwrap().1;
        assert!((tension - 0.1240275).abs() < 1.2e-6, "{events:?}");
    }
    // The snap lands on the tendon's side: measured 799.9 mm
    assert!(
        matches!(events[1].kind, Kind::Snap { distance } if distance > 0.79),
        "{events:?}"
    );
    assert!(steps[1].solution.report.stability.is_stable());
}
