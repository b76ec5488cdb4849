//! A classical nonlinear rod benchmark: the cantilever under a dead tip load perpendicular
//! to its straight axis (the elastica of Bisshopp & Drucker, "Large deflection of cantilever
//! beams", Quarterly of Applied Mathematics 3(3), 1945), whose tip is given in closed form by
//! elliptic integrals. The reference values are computed here from that closed form
//! (docs/validation.md derives it), not copied from a table.

use nalgebra::Vector3;
use std::f64::consts::FRAC_PI_2;
use tdcr::{Loads, Robot, Rod, Section, collocation};

/// The integral of `f` over [a, b] by 8-point Gauss-Legendre on 64 panels: for the smooth
/// integrands below (1/sqrt(1 - k^2 sin^2) with k <= 0.99 is at most 7.1) exact to rounding.
fn integral(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    // Abscissae and weights of 8-point Gauss-Legendre on [-1, 1].
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let panels = 64;
    let h = (b - a) / panels as f64;
    (0..panels)
        .map(|i| {
            let mid = a + h * (i as f64 + 0.5);
            X.iter()
                .zip(W)
                .map(|(x, w)| w * (f(mid + 0.5 * h * x) + f(mid - 0.5 * h * x)))
                .sum::<f64>()
                * 0.5
                * h
        })
        .sum()
}

/// Incomplete elliptic integrals of the first and second kind, F(phi, k) and E(phi, k).
fn elliptic(phi: f64, k: f64) -> (f64, f64) {
    let d = |t: f64| (1.0 - (k * t.sin()).powi(2)).sqrt();
    (integral(0.0, phi, |t| 1.0 / d(t)), integral(0.0, phi, d))
}

/// The elastica's tip for the load parameter alpha = P L^2 / EI: (along the original axis,
/// deflection along the load) / L and the tip angle (rad).
///
/// With theta the tangent's angle from the original axis, EI theta'' = -P cos theta,
/// theta(0) = 0, theta'(L) = 0. Substituting 1 + sin theta = 2 k^2 sin^2 phi, with
/// k^2 = (1 + sin theta_L) / 2 and sin phi_1 = 1 / (sqrt(2) k) at the base:
/// sqrt(alpha) = K(k) - F(phi_1, k), x_L / L = sqrt(2 sin theta_L / alpha),
/// y_L / L = 1 - 2 (E(k) - E(phi_1, k)) / sqrt(alpha).
fn elastica(alpha: f64) -> (f64, f64, f64) {
    let length_of = |k: f64| {
        let phi1 = (1.0 / (2f64.sqrt() * k)).asin();
        let (kk, ee) = elliptic(FRAC_PI_2, k);
        let (f1, e1) = elliptic(phi1, k);
        (kk - f1, ee - e1)
    };
    // Bisection on k in (1/sqrt(2), 1): K - F(phi_1) grows from 0 as k does.
    let (mut lo, mut hi) = (1.0 / 2f64.sqrt(), 0.999);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if length_of(mid).0 < alpha.sqrt() {
            lo = mid
        } else {
            hi = mid
        }
    }
    let k = 0.5 * (lo + hi);
    let theta = (2.0 * k * k - 1.0).asin();
    let (_, e) = length_of(k);
    ((2.0 * theta.sin() / alpha).sqrt(), 1.0 - 2.0 * e / alpha.sqrt(), theta)
}

#[test]
fn the_closed_form_has_the_small_load_limit() {
    // Linear beam theory: deflection alpha / 3, tip angle alpha / 2, for small alpha.
    let alpha = 1e-4;
    let (_, y, theta) = elastica(alpha);
    // 1e-3 relative: the next terms are O(alpha^2) relative to these
    assert!((y / (alpha / 3.0) - 1.0).abs() < 1e-3, "{y}");
    assert!((theta / (alpha / 2.0) - 1.0).abs() < 1e-3, "{theta}");
}

#[test]
fn cantilever_under_a_dead_tip_load_is_the_elastica() {
    let (length, ei) = (1.0, 1.0);
    // Stiff in shear and extension (EA = GA = 1e8 EI / L^2 against P <= 10 EI / L^2): the
    // Cosserat rod is the inextensible, unshearable elastica to P / EA <= 1e-7. (With 1e9 the
    // default solve fails: docs/validation.md.)
    let rod = Rod::new(length, Section::explicit(1e8, 1e8, ei, ei, 1.0));
    for alpha in [1.0, 2.0, 5.0, 10.0] {
        let force = alpha * ei / (length * length);
        let robot = Robot::new(rod.clone()).with_loads(Loads::none().with_tip_force(Vector3::new(-force, 0.0, 0.0)));
        let solution = collocation::solve(&robot, &Default::default()).unwrap();
        let tip = solution.tip_position();
        let tangent = solution.tip().R * Vector3::z();
        let (x, y, theta) = elastica(alpha);
        eprintln!(
            "alpha {alpha}: x/L {x:.6}, y/L {y:.6}, tip angle {theta:.6} rad; tdcr off by {:.1e} L, {:.1e} L, {:.1e} rad",
            tip.z / length - x,
            -tip.x / length - y,
            (-tangent.x).atan2(tangent.z) - theta
        );
        // 3e-7 L: the default tip tolerance of 1e-7 L plus shear and extension, P / EA <= 1e-7
        // (measured at most 1.0e-7 L)
        assert!(
            (tip.z - x * length).abs() < 3e-7 * length,
            "alpha {alpha}: {tip} vs ({x}, {y})"
        );
        assert!(
            (-tip.x - y * length).abs() < 3e-7 * length,
            "alpha {alpha}: {tip} vs ({x}, {y})"
        );
        assert!(tip.y.abs() < 1e-12, "{tip}");
        // 3e-7 rad: the default tip orientation tolerance of 1e-7 rad and the same shear
        // (measured at most 3.4e-8 rad)
        assert!(((-tangent.x).atan2(tangent.z) - theta).abs() < 3e-7, "alpha {alpha}");
    }
}
