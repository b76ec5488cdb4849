//! Closed-form answers the solvers are tested against (tests/analytic.rs): circular arcs
//! (pure tip moment, one straight tendon), linear beam theory and the large-deflection
//! elastica by elliptic integrals.

use nalgebra::Vector3;
use std::f64::consts::FRAC_PI_2;

/// Point on a circular arc of curvature `kappa` about body y, starting at the origin along
/// z, at arc length `s`, in a rod whose axial stretch is `stretch` (p' = stretch R e_z).
pub fn arc_about_y(kappa: f64, s: f64, stretch: f64) -> Vector3<f64> {
    let t = kappa * s;
    Vector3::new(1.0 - t.cos(), 0.0, t.sin()) * (stretch / kappa)
}

/// Tip deflection of a cantilever of length `length` under a small perpendicular tip force
/// `force` (N): Euler-Bernoulli F L^3 / (3 EI) plus Timoshenko shear F L / GA (m).
pub fn small_tip_force_deflection(force: f64, length: f64, ei: f64, ga: f64) -> f64 {
    force * length.powi(3) / (3.0 * ei) + force * length / ga
}

/// Tip deflection of a cantilever under a small uniform perpendicular load `w` (N/m):
/// w L^4 / (8 EI) plus shear w L^2 / (2 GA) (m).
pub fn small_uniform_load_deflection(w: f64, length: f64, ei: f64, ga: f64) -> f64 {
    w * length.powi(4) / (8.0 * ei) + w * length * length / (2.0 * ga)
}

/// Carlson's symmetric elliptic integral R_F(x, y, z) by duplication (Carlson 1995, DLMF
/// 19.36.1); stops when the relative spread is below 1e-4, where the 5th-order series
/// leaves an error of order 1e-24.
fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    loop {
        let mu = (x + y + z) / 3.0;
        let (dx, dy, dz) = (1.0 - x / mu, 1.0 - y / mu, 1.0 - z / mu);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-4 {
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / mu.sqrt();
        }
        let lambda = (x * y).sqrt() + (y * z).sqrt() + (z * x).sqrt();
        x = (x + lambda) / 4.0;
        y = (y + lambda) / 4.0;
        z = (z + lambda) / 4.0;
    }
}

/// Carlson's R_D(x, y, z) = R_J(x, y, z, z) by duplication (Carlson 1995; the series as in
/// Numerical Recipes' `rd`), same stopping rule as [`carlson_rf`].
fn carlson_rd(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    let (mut sum, mut fac) = (0.0, 1.0);
    loop {
        let mu = (x + y + 3.0 * z) / 5.0;
        let (dx, dy, dz) = ((mu - x) / mu, (mu - y) / mu, (mu - z) / mu);
        if dx.abs().max(dy.abs()).max(dz.abs()) < 1e-4 {
            let (ea, eb) = (dx * dy, dz * dz);
            let (ec, ed) = (ea - eb, ea - 6.0 * eb);
            let ee = ed + ec + ec;
            let (c1, c2, c3, c4) = (3.0 / 14.0, 1.0 / 6.0, 9.0 / 22.0, 3.0 / 26.0);
            let (c5, c6) = (0.25 * c1, 1.5 * c4);
            let series = 1.0 + ed * (-c1 + c5 * ed - c6 * dz * ee) + dz * (c2 * ee + dz * (-c3 * ec + dz * c4 * ea));
            return 3.0 * sum + fac * series / (mu * mu.sqrt());
        }
        let lambda = (x * y).sqrt() + (y * z).sqrt() + (z * x).sqrt();
        sum += fac / (z.sqrt() * (z + lambda));
        fac *= 0.25;
        x = (x + lambda) / 4.0;
        y = (y + lambda) / 4.0;
        z = (z + lambda) / 4.0;
    }
}

/// Incomplete elliptic integral of the first kind F(phi, k) (modulus k).
fn elliptic_f(phi: f64, k: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    s * carlson_rf(c * c, 1.0 - k * k * s * s, 1.0)
}

/// Incomplete elliptic integral of the second kind E(phi, k) (modulus k).
fn elliptic_e(phi: f64, k: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    let d = 1.0 - k * k * s * s;
    s * carlson_rf(c * c, d, 1.0) - k * k * s.powi(3) / 3.0 * carlson_rd(c * c, d, 1.0)
}

/// Tip of the inextensible, unshearable elastica: a cantilever of unit length clamped along
/// z, dead tip load perpendicular to it along x with load parameter `lambda` = P L^2 / EI.
/// Returns (x, z) / L.
///
/// EI theta'' = -P cos(theta) with theta(0) = 0, theta'(L) = 0. Substituting
/// 1 + sin(theta) = 2 k^2 sin^2(phi) gives ds = dphi / (sqrt(P/EI) sqrt(1 - k^2 sin^2 phi))
/// with phi from phi1 = asin(1 / (k sqrt 2)) at the base to pi/2 at the tip, so
/// sqrt(lambda) = K(k) - F(phi1, k) fixes k; then sin(theta) ds integrates to
/// x sqrt(lambda) = (K - F(phi1)) - 2 (E - E(phi1)) and cos(theta) ds to
/// z = sqrt(2 sin(theta_L) / lambda) with sin(theta_L) = 2 k^2 - 1.
pub fn elastica_tip(lambda: f64) -> (f64, f64) {
    let phi1 = |k: f64| (1.0 / (k * 2f64.sqrt())).asin();
    let length_of = |k: f64| elliptic_f(FRAC_PI_2, k) - elliptic_f(phi1(k), k);
    // Bisection on k in (1/sqrt 2, 1): the length grows monotonically with k.
    let (mut lo, mut hi) = (1.0 / 2f64.sqrt(), 1.0 - 1e-15);
    while hi - lo > 1e-16 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if length_of(mid) > lambda.sqrt() {
            hi = mid
        } else {
            lo = mid
        }
    }
    let k = 0.5 * (lo + hi);
    let x = (length_of(k) - 2.0 * (elliptic_e(FRAC_PI_2, k) - elliptic_e(phi1(k), k))) / lambda.sqrt();
    let z = (2.0 * (2.0 * k * k - 1.0) / lambda).sqrt();
    (x, z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn elliptic_integrals_match_agm_and_tabulated_values() {
        // Complete K(k) = pi / (2 AGM(1, sqrt(1 - k^2))), independent of Carlson's forms.
        for k in [0.1, 1.0 / 2f64.sqrt(), 0.9, 0.999] {
            let (mut a, mut b) = (1.0, (1.0 - k * k).sqrt());
            for _ in 0..30 {
                (a, b) = ((a + b) / 2.0, (a * b).sqrt());
            }
            // 1e-14: both are converged to rounding
            assert!(
                (elliptic_f(FRAC_PI_2, k) / (PI / (2.0 * a)) - 1.0).abs() < 1e-14,
                "K({k})"
            );
        }
        // E(1/sqrt 2) = 1.3506438810476755 (Abramowitz & Stegun 17.3, table 17.1 at m = 1/2).
        // 1e-15: rounding
        assert!((elliptic_e(FRAC_PI_2, 1.0 / 2f64.sqrt()) - 1.350_643_881_047_675_5).abs() < 1e-15);
        // E(phi, 0) = phi, F(phi, 1) = atanh(sin phi).
        assert!((elliptic_e(0.7, 0.0) - 0.7).abs() < 1e-15);
        assert!((elliptic_f(0.7, 1.0) - 0.7f64.sin().atanh()).abs() < 1e-14);
    }

    #[test]
    fn elastica_reference_is_right() {
        // Bisshopp & Drucker (1945), P L^2/EI = 1: x/L = 0.30172, z/L = 0.94357; and 30-digit
        // mpmath values of the same formulas for 1 and 10.
        for (lambda, x, z) in [
            (1.0, 0.301_720_773_799_813_5, 0.943_566_763_716_623_1),
            (10.0, 0.810_609_024_880_296_5, 0.445_004_402_246_248_7),
        ] {
            let (xc, zc) = elastica_tip(lambda);
            // 1e-13: bisection to rounding; k near 1/sqrt 2 costs a few digits in z
            assert!((xc - x).abs() < 1e-13 && (zc - z).abs() < 1e-13, "{lambda}: {xc} {zc}");
        }
    }
}
