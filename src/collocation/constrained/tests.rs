//! The verdict of displacement-controlled tendons, against the linearized dynamics of the
//! bordered system (an eigenvalue computation independent of the count).

use super::Border;
use crate::collocation::{self, Options, dynamics, stability};
use crate::model::rod::Section;
use crate::report::{Growth, Stability};
use crate::{Loads, Robot, Rod, Routing, Solution, Tendon};
use nalgebra::Vector3;
use std::f64::consts::PI;

const LENGTH: f64 = 0.2;
const OFFSET: f64 = 0.005;

/// A steel column (radius 0.5 mm) twenty times stiffer out of the x-z plane than in it, so
/// that it buckles and snaps in that plane only, under a dead tip force 1.5 times its Euler
/// load with a 1 % imperfection towards -x, and one straight tendon on the +x side.
fn column(tendon: Tendon) -> Robot {
    let (r, e, g) = (0.5e-3, 200e9, 200e9 / 2.6);
    let (a, i) = (PI * r * r, PI * r.powi(4) / 4.0);
    let rod = Rod::new(
        LENGTH,
        Section::explicit(e * a, g * a, 20.0 * e * i, e * i, 2.0 * g * i),
    );
    let p = 1.5 * PI * PI * e * i / (4.0 * LENGTH * LENGTH);
    Robot::new(rod)
        .with_loads(Loads::none().with_tip_force(Vector3::new(-0.01 * p, 0.0, -p)))
        .with_tendon(tendon)
}

/// (constant-tension verdict, plain dynamics, bordered dynamics) at the solved state.
fn verdicts(robot: &Robot, solution: &Solution) -> (Stability, Stability, Stability) {
    let (system, x, mut ws, mut report) = crate::collocation::test_support::linearized_at(robot, solution);
    let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
    let counted = ws.verdict(|v| stability::assess(v, &s));
    let plain = dynamics::assess(&system, &x, &mut ws, false);
    let border = Border::new(&system, &x, &mut ws, &mut report).unwrap();
    let bordered = dynamics::assess_bordered(&system, &x, &mut ws, &mut |a| border.project(&x, a));
    (counted, plain, bordered)
}

/// Pulling the tendon in 20 steps takes the column from buckled towards -x (the tendon on the
/// convex side) to nearly straight, through the snap a tension would cause (the tension rises
/// to a maximum, 4.13 N, a fold of the tension, and falls to 0.27 N): every state is stable
/// held at its pull-in, and the bordered
/// linearized dynamics agrees on each; past the tension's maximum the same states at constant
/// tension are unstable (the conjugate-point test and the plain dynamics agree on that).
#[test]
fn a_pull_in_holds_the_states_a_tension_would_snap_through() {
    let options = Options::default();
    let free = collocation::solve(&column(Tendon::new(Routing::straight(OFFSET, 0.0), 0.0)), &options).unwrap();
    assert!(
        free.tip_position().x < -0.02 * LENGTH,
        "buckled towards -x: {}",
        free.tip_position()
    );
    let start = free.tendons[0].displacement;
    let mut previous = free.clone();
    let (mut held, mut peak, mut past_peak) = (0, 0.0f64, 0);
    let steps = 20;
    for k in 1..=steps {
        let q = start + (k as f64 / steps as f64) * start.abs();
        let robot = column(Tendon::pulled(Routing::straight(OFFSET, 0.0), q));
        let solution = collocation::solve_from(&robot, &options, &previous).unwrap();
        let tau = solution.tendons[0].tension;
        assert_eq!(solution.report.stability, Stability::Stable, "q = {q} m, tau = {tau} N");
        if tau > 0.0 {
            let (counted, plain, bordered) = verdicts(&robot, &solution);
            assert_eq!(bordered, Stability::Stable, "q = {q} m: the bordered dynamics");
            match counted {
                Stability::Stable => assert_eq!(plain, Stability::Stable, "q = {q} m"),
                Stability::Unstable { directions: 1, .. } => {
                    assert!(
                        matches!(
                            plain,
                            Stability::Growing {
                                growth: Growth::Divergence,
                                ..
                            }
                        ),
                        "q = {q} m: {plain:?}"
                    );
                    held += 1;
                }
                other => panic!("q = {q} m: {other:?}"),
            }
            if tau < peak {
                past_peak += 1;
            }
            peak = peak.max(tau);
        }
        previous = solution;
    }
    // 0.01 L: nearly straight at zero pull-in (0.5 % of L measured).
    assert!(
        previous.tip_position().x.abs() < 0.01 * LENGTH,
        "{}",
        previous.tip_position()
    );
    // The states the pull-in holds and a tension would not: those past the tension's maximum.
    // Unstable at constant tension exactly past the tension's maximum (a fold of the tension):
    // the states sampled after the largest tension (10 of 20), and possibly the sample of the
    // largest tension itself, which the fold can precede between two samples (measured: it
    // does, 11 unstable).
    assert!(past_peak >= 5, "past the peak {past_peak}");
    assert!(
        held == past_peak || held == past_peak + 1,
        "held {held}, past the peak {past_peak}"
    );
}
