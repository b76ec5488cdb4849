//! Rotation-group helpers: hat/vee, the exponential and logarithm maps and the right
//! Jacobian of SO(3), generic over the scalar so that forward-mode automatic
//! differentiation (num-dual) flows through them.
//!
//! Every function is smooth at the identity: near theta = 0 the trigonometric ratios are
//! evaluated from their Taylor series in theta^2, so dual numbers get exact derivatives
//! there too (sqrt(theta^2) would have an infinite derivative at 0).
//!
//! XYZ Euler angles (f64 only): [`euler_xyz`], its inverse [`euler_xyz_from`] and the rates
//! [`euler_rates`], for the robot file's `euler_xyz_deg` and the calibration's base angles.

use crate::Real;
use nalgebra::{Matrix3, Rotation3, Vector3};
use std::f64::consts::PI;

/// Below this theta^2 (|theta| < 1/2) the trigonometric ratios come from their Taylor
/// series in theta^2 ([`SIN_RATIO`] and the others, seven terms each): the first omitted
/// term is then below 1e-16 relative, no sin/cos is evaluated for the short rotations of a
/// mesh interval, and the cancellation of the closed forms near 0 is avoided.
const SERIES_THETA_SQ: f64 = 0.25;
/// Below this sin^2(theta) [`log`] uses its (shorter) series for asin(x)/x; its first
/// omitted term is then below 1e-24.
const LOG_SERIES_SIN_SQ: f64 = 1e-6;

/// sin t / t = sum (-1)^k t^2k / (2k+1)!.
const SIN_RATIO: [f64; 7] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
];
/// (1 - cos t) / t^2 = sum (-1)^k t^2k / (2k+2)!.
const COS_RATIO: [f64; 7] = [
    0.5,
    -1.0 / 24.0,
    1.0 / 720.0,
    -1.0 / 40_320.0,
    1.0 / 3_628_800.0,
    -1.0 / 479_001_600.0,
    1.0 / 87_178_291_200.0,
];
/// (t - sin t) / t^3 = sum (-1)^k t^2k / (2k+3)!.
const SIN_DEFECT_RATIO: [f64; 7] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5_040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
    -1.0 / 6_227_020_800.0,
    1.0 / 1_307_674_368_000.0,
];
/// e(t) = 1/t^2 - (1 + cos t) / (2 t sin t) = sum (-1)^k B_2k+2 t^2k / (2k+2)! (B: the
/// Bernoulli numbers), the coefficient of hat(theta)^2 in J_r^-1.
const JR_INV_RATIO: [f64; 7] = [
    1.0 / 12.0,
    1.0 / 720.0,
    1.0 / 30_240.0,
    1.0 / 1_209_600.0,
    1.0 / 47_900_160.0,
    691.0 / 1_307_674_368_000.0,
    1.0 / 74_724_249_600.0,
];

/// sum coefficients[k] t2^k by Horner's rule.
fn series<T: Real>(t2: T, coefficients: &[f64]) -> T {
    coefficients.iter().rev().fold(T::zero(), |acc, &k| acc * t2 + c(k))
}

/// The hat map: `hat(a) * b == a x b`.
pub fn hat<T: Real>(a: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -a[2], a[1], a[2], z, -a[0], -a[1], a[0], z)
}

/// The vee map, inverse of [`hat`] on skew-symmetric matrices (reads the skew part).
pub fn vee<T: Real>(m: &Matrix3<T>) -> Vector3<T> {
    let half = T::from_f64(0.5).unwrap_or_else(T::one);
    Vector3::new(
        (m[(2, 1)] - m[(1, 2)]) * half,
        (m[(0, 2)] - m[(2, 0)]) * half,
        (m[(1, 0)] - m[(0, 1)]) * half,
    )
}

fn c<T: Real>(x: f64) -> T {
    T::from_f64(x).unwrap_or_else(T::zero)
}

/// (sin t / t, (1 - cos t) / t^2, t^2) for the rotation vector `theta`, t = |theta|.
fn ratios<T: Real>(theta: &Vector3<T>) -> (T, T, T) {
    let t2 = theta.norm_squared();
    if t2 < c(SERIES_THETA_SQ) {
        (series(t2, &SIN_RATIO), series(t2, &COS_RATIO), t2)
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (T::one() - t.cos()) / t2, t2)
    }
}

/// The exponential map: the rotation by angle |theta| about theta / |theta| (Rodrigues).
pub fn exp<T: Real>(theta: &Vector3<T>) -> Matrix3<T> {
    let (a, b, _) = ratios(theta);
    let k = hat(theta);
    Matrix3::identity() + k * a + k * k * b
}

/// The right Jacobian J_r(theta): d/ds exp(theta(s)) = exp(theta) hat(J_r(theta) theta').
pub fn right_jacobian<T: Real>(theta: &Vector3<T>) -> Matrix3<T> {
    let t2 = theta.norm_squared();
    let k = hat(theta);
    // (1 - cos t) / t^2 and (t - sin t) / t^3
    let (b, d) = if t2 < c(SERIES_THETA_SQ) {
        (series(t2, &COS_RATIO), series(t2, &SIN_DEFECT_RATIO))
    } else {
        let t = t2.sqrt();
        ((T::one() - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    Matrix3::identity() - k * b + k * k * d
}

/// The inverse of the right Jacobian: theta' = J_r(theta)^-1 u when R = R0 exp(theta),
/// R' = R hat(u). Valid for |theta| < 2 pi.
pub fn right_jacobian_inv<T: Real>(theta: &Vector3<T>) -> Matrix3<T> {
    let t2 = theta.norm_squared();
    let k = hat(theta);
    let e = if t2 < c(SERIES_THETA_SQ) {
        series(t2, &JR_INV_RATIO)
    } else {
        let t = t2.sqrt();
        T::one() / t2 - (T::one() + t.cos()) / (c::<T>(2.0) * t * t.sin())
    };
    Matrix3::identity() + k * c::<T>(0.5) + k * k * e
}

/// [`exp`], [`right_jacobian`] and [`right_jacobian_inv`] of one rotation vector (f64),
/// with theta^2, hat(theta) and its square evaluated once for the three: the same
/// operations as the three functions (hat(theta)^2 written out, each entry summed as
/// nalgebra's product sums it), so the same bits. Always inlined, so that it is compiled
/// with its caller's target features (the interval Jacobian's AVX2 build,
/// `collocation/point.rs`), where the three functions were calls.
#[inline(always)]
pub(crate) fn exp_and_jacobians(theta: &Vector3<f64>) -> [Matrix3<f64>; 3] {
    let t2 = theta.norm_squared();
    // (sin t / t, (1 - cos t) / t^2, (t - sin t) / t^3, e(t^2)) as the three functions
    // form them.
    let (a, b, d, e) = if t2 < SERIES_THETA_SQ {
        (
            series(t2, &SIN_RATIO),
            series(t2, &COS_RATIO),
            series(t2, &SIN_DEFECT_RATIO),
            series(t2, &JR_INV_RATIO),
        )
    } else {
        let t = t2.sqrt();
        let (sin, cos) = (t.sin(), t.cos());
        (
            sin / t,
            (1.0 - cos) / t2,
            (t - sin) / (t2 * t),
            1.0 / t2 - (1.0 + cos) / (2.0 * t * sin),
        )
    };
    let k = hat(theta);
    let kk = hat_squared(&k);
    // I + k c1 + k^2 c2 entry by entry (J_r's I - k b as I + k (-b): the same bits).
    let combine = |c1: f64, c2: f64| combine(&k, &kk, c1, c2);
    [combine(a, b), combine(-b, d), combine(0.5, e)]
}

/// [`exp`] of an f64 rotation vector, the same operations as [`exp`] (hat(theta)^2 and the
/// sum I + k a + k^2 b as [`exp_and_jacobians`] writes them out), so the same bits: the
/// scalar reference that the rigid-equilibrium guess's exponential in lanes
/// (`mesh/guess/lanes.rs`) is tested against.
#[cfg(test)]
pub(crate) fn exp_inlined(theta: &Vector3<f64>) -> Matrix3<f64> {
    let (a, b) = exp_ratios(theta.norm_squared());
    let k = hat(theta);
    combine(&k, &hat_squared(&k), a, b)
}

/// (sin t / t, (1 - cos t) / t^2) for t^2 = `t2`, as [`ratios`] forms them (f64): the
/// coefficients of the rigid-equilibrium guess's exponential in lanes
/// (`mesh/guess/lanes.rs`), always inlined so that it is compiled into the guess's AVX2
/// build.
#[inline(always)]
pub(crate) fn exp_ratios(t2: f64) -> (f64, f64) {
    if t2 < SERIES_THETA_SQ {
        (series(t2, &SIN_RATIO), series(t2, &COS_RATIO))
    } else {
        let t = t2.sqrt();
        (t.sin() / t, (1.0 - t.cos()) / t2)
    }
}

/// k^2 for k = hat(theta), each entry summed as nalgebra's product sums it (so the same
/// bits as `k * k`).
#[inline(always)]
fn hat_squared(k: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        k[(0, 0)] * k[(0, 0)] + k[(0, 1)] * k[(1, 0)] + k[(0, 2)] * k[(2, 0)],
        k[(0, 0)] * k[(0, 1)] + k[(0, 1)] * k[(1, 1)] + k[(0, 2)] * k[(2, 1)],
        k[(0, 0)] * k[(0, 2)] + k[(0, 1)] * k[(1, 2)] + k[(0, 2)] * k[(2, 2)],
        k[(1, 0)] * k[(0, 0)] + k[(1, 1)] * k[(1, 0)] + k[(1, 2)] * k[(2, 0)],
        k[(1, 0)] * k[(0, 1)] + k[(1, 1)] * k[(1, 1)] + k[(1, 2)] * k[(2, 1)],
        k[(1, 0)] * k[(0, 2)] + k[(1, 1)] * k[(1, 2)] + k[(1, 2)] * k[(2, 2)],
        k[(2, 0)] * k[(0, 0)] + k[(2, 1)] * k[(1, 0)] + k[(2, 2)] * k[(2, 0)],
        k[(2, 0)] * k[(0, 1)] + k[(2, 1)] * k[(1, 1)] + k[(2, 2)] * k[(2, 1)],
        k[(2, 0)] * k[(0, 2)] + k[(2, 1)] * k[(1, 2)] + k[(2, 2)] * k[(2, 2)],
    )
}

/// I + k c1 + k2 c2 entry by entry, summed as nalgebra's `I + k * c1 + k2 * c2` sums each
/// entry. Slice iterators: nalgebra's matrix iterators stayed unrolled loops of pointer steps.
#[inline(always)]
fn combine(k: &Matrix3<f64>, k2: &Matrix3<f64>, c1: f64, c2: f64) -> Matrix3<f64> {
    let mut m = Matrix3::identity();
    for ((m, kn), kkn) in m.as_mut_slice().iter_mut().zip(k.as_slice()).zip(k2.as_slice()) {
        *m = *m + kn * c1 + kkn * c2;
    }
    m
}

/// d(J_r^-1(theta) u)/d(theta) (3 x 3), f64 only: the Jacobian evaluation's derivative of
/// theta' = J_r^-1(theta) u. With K = hat(theta), t = |theta| and
/// J_r^-1 = I + K / 2 + e K^2, e(t^2) = 1/t^2 - (1 + cos t) / (2 t sin t) (as in
/// [`right_jacobian_inv`]), and w = theta x (theta x u) = theta (theta . u) - t^2 u:
///
/// d/dtheta = -hat(u) / 2 + e ((theta . u) I + theta u^T - 2 u theta^T) + 2 e'(t^2) w theta^T.
///
/// For t < 1/2 e and e' come from their Taylor series in t^2 (coefficients from the
/// Bernoulli numbers, first omitted term below 1e-12 relative); beyond, from the closed form
/// de/dt = -2/t^3 + (t / sin^2(t/2) + 2 cot(t/2)) / (4 t^2), e' = (de/dt) / (2 t).
pub fn d_right_jacobian_inv_u(theta: &Vector3<f64>, u: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = theta.norm_squared();
    let (e, de) = if t2 < SERIES_THETA_SQ {
        // e' = sum k c_k t^2(k-1) for e = sum c_k t^2k.
        let k = &JR_INV_RATIO;
        let de = (1..k.len()).rev().fold(0.0, |acc, i| acc * t2 + i as f64 * k[i]);
        (series(t2, k), de)
    } else {
        let t = t2.sqrt();
        let (sin, cos) = (0.5 * t).sin_cos();
        let cot = cos / sin;
        let e = 1.0 / t2 - cot / (2.0 * t);
        let de_dt = -2.0 / (t2 * t) + (t / (sin * sin) + 2.0 * cot) / (4.0 * t2);
        (e, de_dt / (2.0 * t))
    };
    let tu = theta.dot(u);
    let w = theta * tu - u * t2;
    -hat(u) * 0.5
        + (Matrix3::identity() * tu + theta * u.transpose() - u * theta.transpose() * 2.0) * e
        + w * theta.transpose() * (2.0 * de)
}

/// The logarithm map: the rotation vector theta with exp(theta) = q, |theta| <= pi.
///
/// `q` must be a rotation matrix. Smooth at the identity (series in sin^2) and
/// well-conditioned up to, but not at, |theta| = pi, where the axis is read from the
/// symmetric part.
pub fn log<T: Real>(q: &Matrix3<T>) -> Vector3<T> {
    let w = vee(q); // sin(t) * axis
    let cos = (q.trace() - T::one()) * c(0.5);
    let s2 = w.norm_squared();
    if cos > c(0.0) && s2 < c(LOG_SERIES_SIN_SQ) {
        // asin(x)/x = 1 + x^2/6 + 3x^4/40 + 5x^6/112 with x^2 = sin^2 t
        let f = T::one() + s2 / c(6.0) + s2 * s2 * c(3.0 / 40.0) + s2 * s2 * s2 * c(5.0 / 112.0);
        return w * f;
    }
    if cos > c(-0.9) {
        let sin = s2.sqrt();
        return w * (sin.atan2(cos) / sin);
    }
    // Near pi: (q + q^T)/2 - cos I = (1 - cos) a a^T; take the largest column.
    let sym: Matrix3<T> = (q + q.transpose()) * c::<T>(0.5) - Matrix3::<T>::identity() * cos;
    let mut k = 0;
    for i in 1..3 {
        if sym[(i, i)] > sym[(k, k)] {
            k = i;
        }
    }
    let col: Vector3<T> = sym.column(k).into();
    let mut axis = col / col.norm();
    if axis.dot(&w) < c(0.0) {
        axis = -axis;
    }
    let angle = s2.sqrt().atan2(cos);
    axis * angle
}

/// Largest deviation of `r^T r` from the identity and of det(r) from 1: 0 for a rotation.
pub fn orthonormality_error(r: &Matrix3<f64>) -> f64 {
    let e = (r.transpose() * r - Matrix3::identity()).abs().max();
    e.max((r.determinant() - 1.0).abs())
}

// XYZ Euler angles: R0 = Rx(alpha) Ry(beta) Rz(gamma), the robot file's `euler_xyz_deg` and the
// base orientation calibration fits; the matrix, the angles of a matrix, and the rates
// d phi / d(alpha, beta, gamma) (docs/calibration.md).

/// R = Rx(alpha) Ry(beta) Rz(gamma) for angles (alpha, beta, gamma) in rad: intrinsic
/// rotations about x, then the new y, then the newest z (equivalently extrinsic z, y, x).
/// The robot file's `euler_xyz_deg` is this with the angles in degrees, and calibration
/// fits the base orientation as these angles (docs/calibration.md).
///
/// # Examples
/// ```
/// use nalgebra::Vector3;
/// use tdcr::so3::euler_xyz;
/// // The prototype's base rotation (body z along world +x) is Ry(90 deg).
/// let r = euler_xyz(&Vector3::new(0.0, 90f64.to_radians(), 0.0));
/// assert!((r - tdcr::cases::prototype_base_rotation()).amax() < 1e-15);
/// ```
pub fn euler_xyz(angles: &Vector3<f64>) -> Matrix3<f64> {
    (Rotation3::from_axis_angle(&Vector3::x_axis(), angles[0])
        * Rotation3::from_axis_angle(&Vector3::y_axis(), angles[1])
        * Rotation3::from_axis_angle(&Vector3::z_axis(), angles[2]))
    .into_inner()
}

/// Below this |cos(beta)| the XYZ angles are taken as singular (beta = +-90 deg) when read
/// from a matrix: sqrt(eps) = 1.5e-8, where reading alpha and gamma from entries of size
/// |cos(beta)| would lose as much as setting gamma = 0 does (about 1e-8 rad either way).
const EULER_SINGULAR: f64 = 1.5e-8;

/// The XYZ Euler angles (alpha, beta, gamma) (rad) of a rotation, R = [`euler_xyz`] of them:
/// beta in [-pi/2, pi/2], alpha and gamma in (-pi, pi]. At beta = +-pi/2, where only
/// alpha +- gamma is determined, gamma is set to 0.
///
/// Precondition: `rotation` is orthonormal with determinant +1.
///
/// # Examples
/// ```
/// use nalgebra::Vector3;
/// use tdcr::so3::{euler_xyz, euler_xyz_from};
/// let angles = Vector3::new(3.1, -0.4, -1.6);
/// assert!((euler_xyz_from(&euler_xyz(&angles)) - angles).amax() < 1e-14);
/// ```
pub fn euler_xyz_from(rotation: &Matrix3<f64>) -> Vector3<f64> {
    let r = rotation;
    // R = [[cb cc, -cb sc, sb], [., ., -sa cb], [., ., ca cb]] (docs/calibration.md).
    let cb = r[(0, 0)].hypot(r[(0, 1)]);
    let beta = r[(0, 2)].atan2(cb);
    let (alpha, gamma) = if cb > EULER_SINGULAR {
        ((-r[(1, 2)]).atan2(r[(2, 2)]), (-r[(0, 1)]).atan2(r[(0, 0)]))
    } else {
        // Rx(a) Ry(+-90 deg) = rows [., ., .], [sa, ca, 0], [., sa, 0] up to the sign of
        // the first column: alpha from R[2,1], R[1,1] with gamma = 0.
        (r[(2, 1)].atan2(r[(1, 1)]), 0.0)
    };
    Vector3::new(wrap_angle(alpha), beta, wrap_angle(gamma))
}

/// An angle (rad) in (-pi, pi].
pub fn wrap_angle(angle: f64) -> f64 {
    let a = angle.rem_euclid(2.0 * PI);
    if a > PI { a - 2.0 * PI } else { a }
}

/// W = d phi / d(alpha, beta, gamma): the world-frame rotation vector phi
/// (R -> exp(hat(phi)) R) per unit change of each XYZ Euler angle, columns
/// x, Rx(alpha) y, Rx(alpha) Ry(beta) z. det W = cos(beta).
pub fn euler_rates(angles: &Vector3<f64>) -> Matrix3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), angles[0]);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), angles[1]);
    Matrix3::from_columns(&[Vector3::x(), rx * Vector3::y(), rx * (ry * Vector3::z())])
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use num_dual::Dual64;

    /// The three maps evaluated together give the bits of each evaluated alone, below and
    /// above the series switch (|theta| = 1/2) and at theta = 0; so does the always-inlined
    /// exponential [`exp_inlined`].
    #[test]
    fn exp_and_jacobians_gives_the_three_functions_bits() {
        for theta in [
            Vector3::zeros(),
            Vector3::new(1e-9, -2e-9, 3e-10),
            Vector3::new(0.01, -0.03, 0.002),
            Vector3::new(0.3, -0.2, 0.25),
            Vector3::new(0.4, 0.3, -0.1),
            Vector3::new(1.3, -0.7, 2.1),
        ] {
            let [e, jr, jri] = exp_and_jacobians(&theta);
            let bits = |m: &Matrix3<f64>| m.map(f64::to_bits);
            assert_eq!(bits(&e), bits(&exp(&theta)), "{theta}");
            assert_eq!(bits(&exp_inlined(&theta)), bits(&exp(&theta)), "{theta}");
            assert_eq!(bits(&jr), bits(&right_jacobian(&theta)), "{theta}");
            assert_eq!(bits(&jri), bits(&right_jacobian_inv(&theta)), "{theta}");
        }
    }

    #[test]
    fn series_match_closed_forms_below_the_switch() {
        for t in [0.1f64, 0.3, 0.4999] {
            let t2 = t * t;
            let (sin, cos) = t.sin_cos();
            let pairs = [
                (series(t2, &SIN_RATIO), sin / t),
                (series(t2, &COS_RATIO), (1.0 - cos) / t2),
                (series(t2, &SIN_DEFECT_RATIO), (t - sin) / (t2 * t)),
                (series(t2, &JR_INV_RATIO), 1.0 / t2 - (1.0 + cos) / (2.0 * t * sin)),
            ];
            for (from_series, closed) in pairs {
                // 1e-13: the closed forms lose about eps / t^2 to cancellation at t = 0.1
                assert_relative_eq!(from_series, closed, max_relative = 1e-13);
            }
        }
    }

    #[test]
    fn d_right_jacobian_inv_u_matches_forward_mode() {
        let u = Vector3::new(0.3, -1.7, 12.0);
        // Both branches, both sides of the switch at t = 1/2, and near pi.
        for t in [0.0, 1e-4, 0.03, 0.2, 0.4999, 0.5001, 1.3, 2.9] {
            let theta = Vector3::new(0.48, -0.6, 0.64) * t;
            let analytic = d_right_jacobian_inv_u(&theta, &u);
            for j in 0..3 {
                let d = Vector3::from_fn(|i, _| Dual64::new(theta[i], if i == j { 1.0 } else { 0.0 }));
                let column = right_jacobian_inv(&d) * u.map(Dual64::from);
                for i in 0..3 {
                    // Rounding of the two evaluations: a few ulps of the largest entry.
                    assert!(
                        (analytic[(i, j)] - column[i].eps).abs() <= 1e-13 * u.norm(),
                        "t = {t}, ({i}, {j}): {} vs {}",
                        analytic[(i, j)],
                        column[i].eps
                    );
                }
            }
        }
    }

    fn num_jr(theta: &Vector3<f64>, u: &Vector3<f64>) -> Vector3<f64> {
        // exp(theta)^T d/de exp(theta + e J^-1 u) at e = 0 should be hat(u).
        let h = 1e-6;
        let dir = right_jacobian_inv(theta) * u;
        let d = (exp(&(theta + dir * h)) - exp(&(theta - dir * h))) / (2.0 * h);
        vee(&(exp(theta).transpose() * d))
    }

    #[test]
    fn exp_log_round_trip_across_angles() {
        // Angles from 0 through the series switch and up to just below pi.
        for &t in &[0.0, 1e-9, 1e-4, 1e-3, 0.5, 2.0, 3.0, 3.1, std::f64::consts::PI - 1e-5] {
            let theta = Vector3::new(0.3, -0.5, 0.8).normalize() * t;
            let r = exp(&theta);
            assert!(orthonormality_error(&r) < 1e-15, "t = {t}");
            // 1e-12: log near pi loses digits as 1/sin(t)
            assert_relative_eq!(log(&r), theta, epsilon = 1e-12);
        }
    }

    #[test]
    fn right_jacobian_inverse_is_inverse_and_matches_exp() {
        for &t in &[0.0, 1e-5, 0.7, 2.5] {
            let theta = Vector3::new(-0.2, 0.9, 0.4).normalize() * t;
            let p = right_jacobian(&theta) * right_jacobian_inv(&theta);
            assert_relative_eq!(p, Matrix3::identity(), epsilon = 1e-14);
            let u = Vector3::new(0.3, -1.0, 2.0);
            // 1e-8: central difference with step 1e-6
            assert_relative_eq!(num_jr(&theta, &u), u, epsilon = 1e-8);
        }
    }

    #[test]
    fn dual_derivatives_are_finite_at_identity() {
        use num_dual::Dual64;
        let theta = Vector3::new(Dual64::from(0.0).derivative(), 0.0.into(), 0.0.into());
        let r = exp(&theta);
        // d exp / d theta_x at 0 is hat(e_x)
        assert_eq!(r[(2, 1)].eps, 1.0);
        let l = log(&r);
        assert_eq!(l[0].eps, 1.0);
        assert!(l[1].eps == 0.0 && l[2].eps == 0.0);
    }
    #[test]
    fn euler_angles_compose_about_x_then_y_then_z() {
        // Rx(a) Ry(b) Rz(c) applied to e_z: Rz leaves it, Ry(90 deg) turns it to +x.
        let r = euler_xyz(&Vector3::new(0.0, 90f64.to_radians(), 0.0));
        // 1e-15: cos(pi/2) rounds to 6e-17
        assert!((r * Vector3::z() - Vector3::x()).amax() < 1e-15);
        // The order: with alpha = 90 deg first about x, then beta = 90 deg about the new y
        // (which is world z), e_z ends at Rx(90) (Ry(90) e_z) = Rx(90) e_x = e_x, and e_x
        // at Rx(90) (Ry(90) e_x) = Rx(90) (-e_z) = e_y.
        let r = euler_xyz(&Vector3::new(90f64.to_radians(), 90f64.to_radians(), 0.0));
        // 1e-15: products of cos(pi/2) rounding
        assert!((r * Vector3::z() - Vector3::x()).amax() < 1e-15);
        assert!((r * Vector3::x() - Vector3::y()).amax() < 1e-15);
    }

    #[test]
    fn euler_angles_round_trip_and_at_the_singularity() {
        for angles in [
            Vector3::new(3.1, -0.4, -1.6),
            Vector3::new(-0.2, 1.2, 2.9),
            Vector3::new(0.0, 0.0, 0.0),
        ] {
            let back = euler_xyz_from(&euler_xyz(&angles));
            // 1e-14: atan2 of entries accurate to rounding
            assert!((back - angles).amax() < 1e-14, "{angles:?} -> {back:?}");
        }
        // beta = 90 deg: only alpha + gamma is determined; gamma comes back 0 and the matrix
        // is the same.
        let angles = Vector3::new(0.3, std::f64::consts::FRAC_PI_2, 0.2);
        let back = euler_xyz_from(&euler_xyz(&angles));
        assert_eq!(back.z, 0.0);
        // 1e-14: the rotation is recovered to rounding
        assert!((euler_xyz(&back) - euler_xyz(&angles)).amax() < 1e-14);
        assert_eq!(wrap_angle(3.0 * PI), PI);
        // 1e-15: one rem_euclid of a value of order 2 pi
        assert!((wrap_angle(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn euler_rates_are_the_rotation_vector_per_angle() {
        let angles = Vector3::new(0.4, -0.7, 1.1);
        let w = euler_rates(&angles);
        let r0 = euler_xyz(&angles);
        for k in 0..3 {
            // Central difference of R(angles + h e_k) R0^T = exp(hat(phi)): phi / (2h).
            let h = 1e-6;
            let plus = euler_xyz(&(angles + Vector3::ith(k, h)));
            let minus = euler_xyz(&(angles - Vector3::ith(k, h)));
            let phi = (log(&(plus * r0.transpose())) - log(&(minus * r0.transpose()))) / (2.0 * h);
            // 1e-8: central difference with step 1e-6
            assert!((phi - w.column(k)).amax() < 1e-8, "{k}: {phi:?}");
        }
        // det W = cos(beta)
        // 1e-14: a 3 x 3 determinant of unit columns, rounding only
        assert!((w.determinant() - angles.y.cos()).abs() < 1e-14);
    }
}
