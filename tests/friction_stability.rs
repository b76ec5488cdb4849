//! The stability verdict of equilibria with tendons with friction (docs/stability.md,
//! "Tendons with friction"): the linearized dynamics of the system bordered by the capstan
//! rows, each stretch's slip held.

use nalgebra::Vector3;
use std::f64::consts::PI;
use tdcr::collocation::{self, Equilibrium, Options, vibration};
use tdcr::{Friction, Growth, Loads, Motion, Robot, Rod, Routing, Stability, Tendon, cases};

fn friction(mu: f64, motion: Motion) -> Option<Friction> {
    Some(Friction {
        coefficient: mu,
        motion,
    })
}

#[test]
fn explore() {
    for mu in [0.0, 1e-9, 0.1] {
        for motion in [Motion::Pull, Motion::Release] {
            let mut s = cases::case_s();
            s.tendons[0].friction = friction(mu, motion);
            let sol = tdcr::solve(&s, &Default::default()).unwrap();
            let v = vibration(&s, &sol).unwrap();
            eprintln!("S mu {mu} {motion:?}: {} ; {:?}", sol.report.stability, &v.eigenvalues[..4.min(v.eigenvalues.len())]);
            let mut h = cases::case_h();
            h.tendons[4].friction = friction(mu, motion);
            let sol = tdcr::solve(&h, &Default::default()).unwrap();
            let v = vibration(&h, &sol).unwrap();
            eprintln!("H mu {mu} {motion:?}: {} ; {:?}", sol.report.stability, &v.eigenvalues[..4.min(v.eigenvalues.len())]);
        }
    }
}
