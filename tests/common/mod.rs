//! Shared by the integration tests: run every solver on a robot.
//!
//! To test a new solver everywhere, add it to [`try_solve_all`]; tests loop over what it
//! returns and never depend on how many solvers there are.
#![allow(dead_code)] // each test crate uses a different subset

pub mod cli;

use std::f64::consts::{FRAC_PI_2, PI};
use tdcr::cases::analytic::elastica_tip;
use tdcr::nalgebra::Vector3;
use tdcr::shooting::{self, Options};
use tdcr::{Loads, Result, Robot, Rod, Section, Solution};

/// Every solver's result on `robot`, labelled by solver name, at tight tolerances.
pub fn try_solve_all(robot: &Robot) -> Vec<(&'static str, Result<Solution>)> {
    vec![
        (
            "collocation",
            // 256 intervals: order-4 error below 1e-10 relative on the smooth analytic cases
            tdcr::collocation::solve(robot, &tdcr::collocation::Options::fixed(256)),
        ),
        (
            "shooting",
            // 1e-12: the tightest integration tolerance shooting supports
            shooting::solve(
                robot,
                &Options {
                    integration_tolerance: 1e-12,
                    ..Default::default()
                },
            ),
        ),
    ]
}

/// Every solver's solution of `robot`; panics with the solver's name and error if one
/// fails.
pub fn solve_all(robot: &Robot) -> Vec<(&'static str, Solution)> {
    try_solve_all(robot)
        .into_iter()
        .map(|(name, result)| (name, result.unwrap_or_else(|e| panic!("{name}: {e}"))))
        .collect()
}

/// `solution`'s robot solved again on its mesh with every interval split into `k` equal
/// parts, warm-started from it, to a residual of 1e-13 without error control: the reference
/// an estimate is checked against (its own error falls as k^-4 below the solution's).
pub fn on_split_mesh(robot: &Robot, solution: &Solution, k: usize) -> Result<Solution> {
    let finer: Vec<f64> = solution
        .nodes
        .windows(2)
        .flat_map(|w| (0..k).map(move |i| w[0].s + i as f64 / k as f64 * (w[1].s - w[0].s)))
        .collect();
    let fine = tdcr::collocation::Options {
        mesh: Some(finer),
        tolerance: None,
        residual_tolerance: 1e-13,
        ..Default::default()
    };
    tdcr::collocation::solve_from(robot, &fine, solution)
}

/// The cantilever of tests/analytic.rs (0.5 m, EI = 2 N m^2, EA = GA =
/// 1e5 EI/L^2) under a tip force P = `lambda` EI/L^2 along x, and its exact tip: the
/// inextensible elastica's plus the shift P L / K along the load.
pub fn elastica_cantilever(lambda: f64) -> (Robot, Vector3<f64>) {
    let (length, ei) = (0.5, 2.0);
    let stiff = 1e5 * ei / (length * length);
    let rod = Rod::new(length, Section::explicit(stiff, stiff, ei, ei, 0.75 * ei));
    let force = lambda * ei / (length * length);
    let robot = Robot::new(rod).with_loads(Loads::none().with_tip_force(Vector3::new(force, 0.0, 0.0)));
    let (x, z) = elastica_tip(lambda);
    (
        robot,
        Vector3::new(x * length + force * length / stiff, 0.0, z * length),
    )
}

/// Complete elliptic integrals K(k) and E(k) by Simpson's rule on 20 000 intervals (the
/// integrands are smooth for k <= 0.999, the largest modulus below; error below 1e-10).
pub fn elliptic_k_e(k: f64) -> (f64, f64) {
    let n = 20_000;
    let h = FRAC_PI_2 / n as f64;
    let (mut kk, mut ee) = (0.0, 0.0);
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let d = (1.0 - (k * (i as f64 * h).sin()).powi(2)).sqrt();
        kk += w / d;
        ee += w * d;
    }
    (kk * h / 3.0, ee * h / 3.0)
}

/// The tip of the inextensible buckled clamped-free column (the elastica) at P / P_cr = `ratio` > 1:
/// (lateral, axial) / L. With k = sin(alpha / 2) (alpha the tip angle), P / P_cr =
/// (2 K(k) / pi)^2, the lateral deflection is 2 k / K(k) and the height 2 E(k) / K(k) - 1.
pub fn column_elastica(ratio: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, 0.999_999);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let (kk, _) = elliptic_k_e(mid);
        if (2.0 * kk / PI).powi(2) < ratio {
            lo = mid
        } else {
            hi = mid
        }
    }
    let k = 0.5 * (lo + hi);
    let (kk, ee) = elliptic_k_e(k);
    (2.0 * k / kk, 2.0 * ee / kk - 1.0)
}
