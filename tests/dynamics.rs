//! Stability from the linearized dynamics (docs/stability.md, "Loads that are not
//! conservative"): the cantilever's vibration frequencies, Euler's column by divergence
//! (agreeing with the conjugate-point test), Beck's column by flutter, a dead tip moment.

use nalgebra::Vector3;
use std::f64::consts::PI;
use tdcr::collocation::{self, DENSITY, Equilibrium, Options, vibration};
use tdcr::{Growth, Loads, Robot, Rod, Stability};

/// Issue 25's column: 0.5 m steel rod of radius 1 mm along +z, no gravity.
const LENGTH: f64 = 0.5;
const RADIUS: f64 = 1e-3;
const E: f64 = 200e9;

fn rod() -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, RADIUS, E, 0.3))
}

fn ei() -> f64 {
    E * PI * RADIUS.powi(4) / 4.0
}

fn nearest() -> Options {
    Options {
        equilibrium: Equilibrium::Nearest,
        ..Default::default()
    }
}

#[test]
fn the_unloaded_cantilever_vibrates_at_its_bending_frequencies() {
    let robot = rod();
    // Euler-Bernoulli: omega_k = (beta_k L)^2 sqrt(EI / (rho A L^4)), beta_1 L = 1.87510,
    // beta_2 L = 4.69409; each twice (the two bending planes of the round rod).
    let rho_a = DENSITY * PI * RADIUS * RADIUS;
    let omega = |beta_l: f64| beta_l * beta_l * (ei() / (rho_a * LENGTH.powi(4))).sqrt();
    let mut errors = Vec::new();
    for intervals in [16, 32, 64] {
        let options = Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        let solution = collocation::solve(&robot, &options).unwrap();
        let modes = vibration(&robot, &solution).unwrap();
        assert_eq!(modes.stability, Stability::Stable);
        for m in &modes.eigenvalues {
            // 1e-9: real up to Arnoldi's rounding
            assert!(m.im.abs() <= 1e-9 * m.norm(), "{m}");
        }
        let mu: Vec<f64> = modes.eigenvalues.iter().map(|m| m.re).collect();
        let error = |k: usize, beta_l: f64| (mu[k].sqrt() / omega(beta_l) - 1.0).abs();
        // The two planes give the same frequency (1e-9: rounding).
        assert!((mu[0] / mu[1] - 1.0).abs() < 1e-9 && (mu[2] / mu[3] - 1.0).abs() < 1e-9);
        errors.push([error(0, 1.875_104_07), error(2, 4.694_091_13)]);
    }
    eprintln!("relative frequency errors at 16, 32, 64 intervals: {errors:?}");
    for k in 0..2 {
        // Second order (the mass is interpolated linearly within an interval): halving h
        // divides the error by 4; 3.5 allows for rotary inertia and shear, which shift
        // omega by (r / L)^2 ~ 4e-6 and do not vanish with h.
        assert!(
            errors[0][k] / errors[1][k] > 3.5 && errors[1][k] / errors[2][k] > 3.5,
            "{errors:?}"
        );
    }
    // 1e-3 of the first two frequencies at 64 intervals
    assert!(errors[2][0] < 1e-3 && errors[2][1] < 1e-3, "{errors:?}");
}

/// Clamped-free column under a dead compressive tip load `p` (N).
fn dead_column(p: f64) -> Robot {
    rod().with_loads(Loads::none().with_tip_force(Vector3::new(0.0, 0.0, -p)))
}

#[test]
fn the_dead_load_column_diverges_past_euler_load_as_the_conjugate_point_test_says() {
    let p_cr = PI * PI * ei() / (4.0 * LENGTH * LENGTH);
    for (factor, stable) in [(0.99, true), (1.01, false), (1.5, false)] {
        let robot = dead_column(factor * p_cr);
        let solution = collocation::solve(&robot, &nearest()).unwrap();
        let modes = vibration(&robot, &solution).unwrap();
        eprintln!("{factor}: {:?}", &modes.eigenvalues[..6.min(modes.eigenvalues.len())]);
        assert_eq!(solution.report.stability.is_stable(), stable, "{factor}");
        match (&modes.stability, stable) {
            (Stability::Stable, true) => {}
            (
                Stability::Growing {
                    growth: Growth::Divergence,
                    ..
                },
                false,
            ) => {}
            (other, _) => panic!("{factor} P_cr: {other}"),
        }
    }
}
