//! The stability verdict of equilibria with tendons with friction (docs/stability.md,
//! "Tendons with friction"): the linearized dynamics of the system bordered by the capstan
//! rows, each stretch's slip held. Vanishing friction gives the frictionless verdict, the
//! prototype is stable pulled and released, and a column carrying a friction tendon
//! diverges past Euler's load.

use nalgebra::{Complex, Vector3};
use std::f64::consts::PI;
use tdcr::collocation::{self, Equilibrium, Options, vibration};
use tdcr::{Friction, Growth, Loads, Motion, Robot, Rod, Routing, Solution, Stability, Tendon, cases};

fn friction(mu: f64, motion: Motion) -> Option<Friction> {
    Some(Friction {
        coefficient: mu,
        motion,
    })
}

/// The growth rate of a `Growing` verdict (panics on any other).
fn divergence_rate(stability: &Stability) -> f64 {
    match stability {
        Stability::Growing {
            growth: Growth::Divergence,
            rate,
        } => *rate,
        other => panic!("expected divergence, got {other}"),
    }
}

/// The lowest modes' eigenvalues mu (1/s^2) of a solution of `robot`.
fn lowest(robot: &Robot, solution: &Solution, count: usize) -> Vec<Complex<f64>> {
    let modes = vibration(robot, solution).unwrap();
    assert!(modes.eigenvalues.len() >= count, "{modes:?}");
    modes.eigenvalues[..count].to_vec()
}

#[test]
fn vanishing_friction_gives_the_frictionless_verdict() {
    // The prototype's cases S (tendon 1) and H (tendon 5): tension control is conservative,
    // so the frictionless verdict is the conjugate-point test's, and its vibration modes are
    // those `vibration` gives the frictionless robot.
    for (robot, tendon) in [(cases::case_s(), 0), (cases::case_h(), 4)] {
        let frictionless = tdcr::solve(&robot, &Default::default()).unwrap();
        assert_eq!(frictionless.report.stability, Stability::Stable);
        let want = lowest(&robot, &frictionless, 4);
        for motion in [Motion::Pull, Motion::Release] {
            let mut rough = robot.clone();
            rough.tendons[tendon].friction = friction(1e-9, motion);
            let solution = tdcr::solve(&rough, &Default::default()).unwrap();
            assert_eq!(solution.report.stability, Stability::Stable, "{motion:?}");
            for (got, want) in lowest(&rough, &solution, 4).iter().zip(&want) {
                // 1e-7 relative: mu = 1e-9 moves the lowest modes by at most 6e-10 relative
                // (measured), and the two solves' meshes and rounding by less
                assert!(
                    (got - want).norm() <= 1e-7 * want.norm(),
                    "{motion:?}: {got} against {want}"
                );
            }
        }
    }
    // Past Euler's load the frictionless state is unstable by the conjugate-point test; its
    // growth rate is the linearized dynamics' of the frictionless robot.
    let rough = column(1.05, 1e-9, TENSION);
    let solution = collocation::solve(&rough, &nearest()).unwrap();
    let got = divergence_rate(&solution.report.stability);
    // The frictionless column on the same mesh: the solve with friction has a node where
    // the tendon's path stops turning (the column bends both ways; docs/friction.md section
    // 8, "honest19"), and on the frictionless solve's own mesh the rate differs by its
    // discretization, 7.4e-6 relative (measured)
    let robot = column(1.05, 0.0, TENSION);
    let same_mesh = Options {
        mesh: Some(solution.nodes.iter().map(|n| n.s).collect()),
        tolerance: None,
        ..nearest()
    };
    let frictionless = collocation::solve(&robot, &same_mesh).unwrap();
    assert!(matches!(frictionless.report.stability, Stability::Unstable { .. }));
    let want = divergence_rate(&vibration(&robot, &frictionless).unwrap().stability);
    eprintln!("growth rate {got} 1/s with mu = 1e-9, {want} 1/s without friction");
    // 1e-6 relative: the solve's verdict uses Newton's last bordered factors, at an iterate
    // one converged step from the answer, and mu = 1e-9 moves the rate (1.3e-13 measured)
    assert!((got / want - 1.0).abs() < 1e-6, "{got} against {want}");
}

#[test]
fn the_prototype_with_friction_pulled_and_released_is_stable() {
    for (robot, tendon) in [(cases::case_s(), 0), (cases::case_h(), 4)] {
        for motion in [Motion::Pull, Motion::Release] {
            let mut rough = robot.clone();
            rough.tendons[tendon].friction = friction(0.1, motion);
            let solution = tdcr::solve(&rough, &Default::default()).unwrap();
            assert_eq!(solution.report.stability, Stability::Stable, "{motion:?}");
            // The verdict says what it covers: motions that keep the slip direction.
            let notes = &solution.report.notes;
            assert!(notes.iter().any(|n| n.contains("slip direction held")), "{notes:?}");
            // The same verdict from a linearization of its own at the answer.
            assert_eq!(vibration(&rough, &solution).unwrap().stability, Stability::Stable);
            // The mass with the capstan rows' response: the two lowest modes stay within 5 % of
            // the frictionless robot's (measured about 1 %: mu = 0.1 changes the tendon's load by
            // about 13 % at the tip, the rod's stiffness and inertia not at all), real and positive.
            let smooth = tdcr::solve(&robot, &Default::default()).unwrap();
            let (with, without) = (lowest(&rough, &solution, 2), lowest(&robot, &smooth, 2));
            for (a, b) in with.iter().zip(&without) {
                assert!(a.im == 0.0 && a.re > 0.0, "{motion:?}: {with:?}");
                assert!(
                    (a.re / b.re - 1.0).abs() < 0.05,
                    "{motion:?}: {with:?} against {without:?}"
                );
            }
        }
    }
}

/// Issue 25's column: 0.5 m steel rod of radius 1 mm along +z, no gravity.
const LENGTH: f64 = 0.5;
const RADIUS: f64 = 1e-3;
const E: f64 = 200e9;
/// The friction tendon's tension (N): light, its moment at 0.8 mm about 1e-5 of P L.
const TENSION: f64 = 0.05;

/// Euler's load of the clamped-free column (N).
fn p_cr() -> f64 {
    PI * PI * E * PI * RADIUS.powi(4) / 4.0 / (4.0 * LENGTH * LENGTH)
}

/// The column under a dead compressive tip force `factor` P_cr with an imperfection of 1e-6
/// of it along x, carrying a straight tendon at 0.8 mm off the axis at `tension` N with
/// friction `mu` (pulled).
fn column(factor: f64, mu: f64, tension: f64) -> Robot {
    let p = factor * p_cr();
    let mut tendon = Tendon::new(Routing::straight(0.8e-3, 0.0), tension);
    if mu > 0.0 {
        tendon = tendon.with_friction(Friction::pull(mu));
    }
    Robot::new(Rod::solid_circle(LENGTH, RADIUS, E, 0.3))
        .with_loads(Loads::none().with_tip_force(Vector3::new(1e-6 * p, 0.0, -p)))
        .with_tendon(tendon)
}

/// The state nearest the straight guess: below Euler's load the one state, above it the
/// nearly straight unstable one (the load path would take the stable buckled branch).
fn nearest() -> Options {
    Options {
        equilibrium: Equilibrium::Nearest,
        ..Default::default()
    }
}

#[test]
fn a_column_with_a_friction_tendon_diverges_past_eulers_load() {
    // The load at which the lowest mode's mu crosses zero, interpolated linearly between
    // the nearly straight states at 0.99 and 1.01 P_cr.
    let critical = |mu: f64| {
        let at = |factor: f64| {
            let robot = column(factor, mu, TENSION);
            let solution = collocation::solve(&robot, &nearest()).unwrap();
            lowest(&robot, &solution, 1)[0].re
        };
        let (below, above) = (at(0.99), at(1.01));
        0.99 + 0.02 * below / (below - above)
    };
    for mu in [0.1, 0.3] {
        for (factor, stable) in [(0.95, true), (0.99, true), (1.01, false), (1.05, false), (1.2, false)] {
            let robot = column(factor, mu, TENSION);
            let solution = collocation::solve(&robot, &nearest()).unwrap();
            let verdict = &solution.report.stability;
            if stable {
                assert_eq!(*verdict, Stability::Stable, "mu {mu}, {factor} P_cr");
            } else {
                divergence_rate(verdict);
                // The frictionless robot at the same load: unstable by the conjugate points.
                let smooth = column(factor, 0.0, TENSION);
                let state = collocation::solve(&smooth, &nearest()).unwrap();
                assert!(matches!(state.report.stability, Stability::Unstable { .. }), "{factor}");
            }
        }
        let (with, without) = (critical(mu), critical(0.0));
        eprintln!("critical load: {with} P_cr with mu = {mu}, {without} P_cr without friction");
        // 1e-4 P_cr: the linear interpolation over 0.02 P_cr and the mesh (Euler's load of
        // the discretized column, an imperfection of 1e-5)
        assert!((without - 1.0).abs() < 1e-4, "{without}");
        // 1e-4 mu P_cr: the light tendon on a nearly straight path barely loads its channel,
        // so friction moves the critical load by about 2.5e-5 mu P_cr (measured: -2.6e-6 at
        // mu = 0.1, -7.5e-6 at 0.3)
        assert!((with - without).abs() < 1e-4 * mu, "{with} against {without}");
    }
}

/// A column past Euler's load with a friction tendon at default settings (the load path's
/// choice), solved cold: its straight tendon turns nothing, so the solve takes the direct
/// route (docs/friction.md section 3, "The direct route"). Newton with friction from the
/// straight guess lands on the nearly straight state, whose verdict is a divergence, so
/// that answer does not stand and the solve falls back to the full choice on the
/// frictionless robot: the load path to the buckled state, stable. Without the fallback
/// the answer would be the straight state.
#[test]
fn a_column_past_eulers_load_with_friction_reaches_the_load_paths_state() {
    let options = Options::default();
    let robot = column(1.2, 0.1, TENSION);
    let solution = collocation::solve(&robot, &options).unwrap();
    let report = &solution.report;
    assert!(matches!(report.path, tdcr::PathTaken::LoadPath { .. }), "{report:?}");
    assert_eq!(report.stability, Stability::Stable, "{report:?}");
    // The state Newton lands on from the straight guess, unstable with friction as without.
    let straight = collocation::solve(&robot, &nearest()).unwrap();
    divergence_rate(&straight.report.stability);
    // The frictionless robot's load path reaches the buckled state the answer with friction
    // starts from; the light tendon barely moves it.
    let smooth = collocation::solve(&column(1.2, 0.0, TENSION), &options).unwrap();
    assert!(
        matches!(smooth.report.path, tdcr::PathTaken::LoadPath { .. }),
        "{:?}",
        smooth.report
    );
    let (tip, buckled, nearly_straight) = (solution.tip_position(), smooth.tip_position(), straight.tip_position());
    // Buckled at 1.2 P_cr the tip is 0.32 m off the axis of the 0.5 m column (measured),
    // the nearly straight state's 0.17 mm: 50 mm and 1 mm separate them by far.
    assert!(buckled.x.abs() > 0.05, "{buckled}");
    assert!(nearly_straight.x.abs() < 1e-3, "{nearly_straight}");
    // 1e-4 of the deflection: friction moves the buckled tip by 4.4e-6 m (measured), the
    // tangential loads of a 0.05 N tendon at mu = 0.1 against the tip force's bending.
    assert!(
        (tip - buckled).norm() < 1e-4 * buckled.x.abs(),
        "{tip} against {buckled}"
    );
}

/// The same column solved from the frictionless nearly straight state (a warm start),
/// which takes the provisional route (docs/friction.md section 3, "Which start"; a warm
/// start never takes the direct route): the frictionless Newton from the warm states goes
/// straight to the nearly straight state, which the choice accepts without its verdict;
/// the answer with friction built on it diverges, and the solve falls back to the full
/// choice: the load path to the buckled state, stable. Without the fallback the answer
/// would be the nearly straight state.
#[test]
fn a_warm_column_past_eulers_load_with_friction_falls_back_to_the_load_paths_state() {
    let options = Options::default();
    let straight = collocation::solve(&column(1.2, 0.0, TENSION), &nearest()).unwrap();
    assert!(
        matches!(straight.report.stability, Stability::Unstable { .. }),
        "{:?}",
        straight.report
    );
    let solution = collocation::solve_from(&column(1.2, 0.1, TENSION), &options, &straight).unwrap();
    let report = &solution.report;
    assert!(matches!(report.path, tdcr::PathTaken::LoadPath { .. }), "{report:?}");
    assert_eq!(report.stability, Stability::Stable, "{report:?}");
    // The cold solve's buckled state (the direct route's fallback, the test above): the
    // two routes end in the same full choice from the same frictionless load path.
    let cold = collocation::solve(&column(1.2, 0.1, TENSION), &options).unwrap();
    let (tip, buckled, nearly_straight) = (solution.tip_position(), cold.tip_position(), straight.tip_position());
    // Buckled at 1.2 P_cr the tip is 0.32 m off the axis (measured), the nearly straight
    // state's 0.17 mm: 50 mm and 1 mm separate them by far.
    assert!(tip.x.abs() > 0.05, "{tip}");
    assert!(nearly_straight.x.abs() < 1e-3, "{nearly_straight}");
    // 1e-9 m: both are the load path's end refined to the default tolerance 1e-7 L (5e-8 m
    // on this 0.5 m column) from the same frictionless states (measured: identical).
    assert!((tip - buckled).norm() < 1e-9, "{tip} against {buckled}");
}

/// A load-history step gets the verdict of its own linearized dynamics, its stick/slip
/// pattern held, with the note of that scope (collocation/dynamics/stuck.rs; its modes are
/// checked there).
#[test]
fn history_steps_get_a_verdict() {
    use tdcr::Parameter;
    use tdcr::analysis::history::history;
    use tdcr::analysis::sweep::{Input, Ranges};
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let ranges = Ranges::new(
        robot.clone(),
        vec![(Input::Parameter(Parameter::Tension(0)), vec![1.0, 2.0, 1.5])],
    )
    .unwrap();
    let result = history(&ranges, &Default::default()).unwrap();
    assert!(result.failure.is_none());
    for step in &result.steps {
        assert_eq!(step.solution.report.stability, Stability::Stable);
        let notes = &step.solution.report.notes;
        assert!(
            notes.iter().any(|n| n.contains("each stuck stretch held stuck")),
            "{notes:?}"
        );
    }
}

#[test]
fn a_column_with_a_friction_tendon_held_or_in_a_history_diverges_past_eulers_load() {
    use tdcr::Parameter;
    use tdcr::analysis::history::history;
    use tdcr::analysis::sweep::{Input, Ranges};
    for (factor, stable) in [(0.95, true), (0.99, true), (1.01, false), (1.05, false), (1.2, false)] {
        let mut robot = column(factor, 0.1, TENSION);
        robot.tendons[0].stiffness = Some(2000.0);
        let full = collocation::solve(&robot, &nearest()).unwrap();
        // Held at the pull-in its 0.05 N state takes up (an elastic tendon, E_t A_t = 2000 N,
        // on the x side stiffens the bending in its plane; the column still buckles out of it).
        let mut held = robot.clone();
        held.tendons[0].set_displacement(full.tendons[0].displacement);
        let pulled = collocation::solve(&held, &nearest()).unwrap();
        // 1e-3 relative: the same state solved through the pull-in loop (its tension to
        // the loop's 1e-12 and the mesh it lands on)
        let tension = pulled.tendons[0].tension;
        assert!((tension / TENSION - 1.0).abs() < 1e-3, "{factor}: {tension} N");
        // As a one-step history from rest (sliding in all along: the full-slip system).
        let ranges = Ranges::new(
            robot.clone(),
            vec![(Input::Parameter(Parameter::Tension(0)), vec![TENSION])],
        )
        .unwrap();
        let steps = history(&ranges, &nearest()).unwrap();
        assert!(steps.failure.is_none(), "{factor}: {:?}", steps.failure);
        let step = &steps.steps[0].solution;
        let notes = &pulled.report.notes;
        assert!(notes.iter().any(|n| n.contains("slip direction held")), "{notes:?}");
        if stable {
            assert_eq!(full.report.stability, Stability::Stable, "{factor}");
            assert_eq!(pulled.report.stability, Stability::Stable, "held, {factor}");
            assert_eq!(step.report.stability, Stability::Stable, "history, {factor}");
        } else {
            let want = divergence_rate(&full.report.stability);
            let held_rate = divergence_rate(&pulled.report.stability);
            let step_rate = divergence_rate(&step.report.stability);
            eprintln!("{factor} P_cr: growth rate {want} full slip, {held_rate} held, {step_rate} history step");
            // 1e-5 relative: the history's step is the full-slip system on its mesh (the
            // same as the solve's) with a node added where the tendon's path stops turning
            // (docs/friction.md section 8, "honest18"), its verdict from a Jacobian at that
            // answer: the growth rate's change with that node (measured 5.4e-6; 1e-6 on the
            // same mesh)
            let extra = step.report.intervals - full.report.intervals;
            assert!(extra <= 2, "{extra} more intervals");
            assert!((step_rate / want - 1.0).abs() < 1e-5, "{step_rate} against {want}");
            // The out-of-plane buckling mode does not stretch the tendon (at y = 0), so
            // holding it leaves that mode's growth: 1e-3 relative (measured within 4.1e-5:
            // the held tension follows the small in-plane part of the mode)
            assert!((held_rate / want - 1.0).abs() < 1e-3, "{held_rate} against {want}");
        }
    }
}

/// Friction with displacement control gets the verdict of the held dynamics (the pull-ins'
/// length conditions bordering the capstan rows, collocation/dynamics/pulled.rs): case S
/// held at 5 mm, pulled and released, is stable.
#[test]
fn held_pull_ins_with_friction_get_a_verdict() {
    for motion in [Motion::Pull, Motion::Release] {
        let mut held = cases::case_s();
        held.tendons[0].friction = friction(0.1, motion);
        held.tendons[0].set_displacement(0.005);
        let solution = tdcr::solve(&held, &Default::default()).unwrap();
        assert_eq!(solution.report.stability, Stability::Stable, "{motion:?}");
        let notes = &solution.report.notes;
        assert!(notes.iter().any(|n| n.contains("slip direction held")), "{notes:?}");
    }
}

/// A pull-in history's steps get the verdict with their stick/slip pattern and their pull-ins
/// held: the prototype's tendon 1 pulled in to 20 mm and let out in small steps (stuck
/// stretches on the way out) is stable on every step.
#[test]
fn a_pull_in_history_is_stable_on_every_step() {
    use tdcr::analysis::history::{Contact, history};
    use tdcr::analysis::sweep::{Input, Ranges};
    let mut robot = cases::prototype();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[0].stiffness = Some(2000.0);
    let values = vec![0.0, 0.01, 0.02, 0.0195, 0.019];
    let ranges = Ranges::new(robot, vec![(Input::Displacement(0), values)]).unwrap();
    let result = history(&ranges, &Default::default()).unwrap();
    assert!(result.failure.is_none(), "{:?}", result.failure);
    let stuck = result
        .steps
        .iter()
        .filter(|s| s.zones[0].zones.iter().any(|z| z.contact == Contact::Stick))
        .count();
    assert!(stuck > 0, "no stuck step");
    for (k, step) in result.steps.iter().enumerate() {
        let report = &step.solution.report;
        assert_eq!(report.stability, Stability::Stable, "step {k}");
        let notes = &report.notes;
        assert!(
            notes.iter().any(|n| n.contains("each stuck stretch held stuck")),
            "step {k}: {notes:?}"
        );
    }
}
