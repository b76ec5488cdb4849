//! F of eq. 13 in an interval's local coordinates and its linearization at one point of
//! the interval ([`rhs_linearized_inline`]), from the point's rotation ([`PointFrame`]):
//! the pointwise step of the interval Jacobian's chain rule (`residual::interval_jacobian`,
//! the friction intervals).
#![allow(non_snake_case)]

use super::residual::Block;
use super::unknowns::{P, THETA, U, V};
use crate::model::equations::Site;
use crate::model::linearize::{self, Linearization};
use crate::so3;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// F, dF/dy (12 x 12) and dF/dphi (12 x 3, for a right perturbation of the interval's frame
/// R_k -> R_k exp(hat(phi))) at one point of an interval.
pub(super) struct PointLinearization {
    pub(super) f: Block<f64>,
    pub(super) f_y: SMatrix<f64, 12, 12>,
    pub(super) f_frame: SMatrix<f64, 12, 3>,
}

/// The rotation at a point of an interval whose local coordinate is theta: exp(theta),
/// R = R_k exp(theta), J_r(theta) and J_r(theta)^-1, evaluated once (`so3::exp_and_jacobians`) and shared by the point's eq. 13
/// linearization ([`rhs_linearized_inline`]) and the chain rule ([`super::ends::EndColumns`]).
pub(super) struct PointFrame {
    /// exp(theta).
    pub(super) E: Matrix3<f64>,
    /// R_k exp(theta).
    pub(super) R: Matrix3<f64>,
    /// J_r(theta).
    pub(super) Jr: Matrix3<f64>,
    /// J_r(theta)^-1.
    pub(super) Jri: Matrix3<f64>,
    /// theta = 0 exactly (an interval's start node): E, J_r and J_r^-1 are the identity.
    start: bool,
}

impl PointFrame {
    /// The frame at theta of an interval starting at `Rk`.
    #[inline(always)]
    pub(super) fn new(Rk: &Matrix3<f64>, theta: &Vector3<f64>) -> Self {
        let [E, Jr, Jri] = so3::exp_and_jacobians(theta);
        PointFrame {
            E,
            R: Rk * E,
            Jr,
            Jri,
            start: false,
        }
    }

    /// The frame at the interval's start node (theta = 0): `so3::exp`, `so3::right_jacobian`
    /// and `so3::right_jacobian_inv` give the identity there (every off-diagonal term a
    /// signed zero added to 0), and a product with the identity gives the other factor's
    /// values, so this skips them with the same values (signed zeros aside).
    #[inline(always)]
    pub(super) fn start(Rk: &Matrix3<f64>) -> Self {
        PointFrame {
            E: Matrix3::identity(),
            R: *Rk,
            Jr: Matrix3::identity(),
            Jri: Matrix3::identity(),
            start: true,
        }
    }
}

/// F(s, y) of an interval with frame `Rk` and its derivatives at a point of `site`,
/// assembled from the strain-rate linearization `lin` at R = R_k exp(theta) and the
/// kinematics p' = R_k exp(theta) v, theta' = J_r(theta)^-1 u (v the strain of the
/// coordinate, [`Site::strain`]: constant on a Kirchhoff rod), with the point's `frame`
/// ([`PointFrame`] at y's theta; [`PointFrame::start`] only where that is exactly 0).
/// Always inlined, so that in the interval Jacobian's AVX2 copy it is compiled for AVX2
/// too (the same operations in the same order).
#[inline(always)]
pub(super) fn rhs_linearized_inline(
    site: &Site,
    lin: &Linearization,
    Rk: &Matrix3<f64>,
    y: &Block<f64>,
    frame: &PointFrame,
) -> PointLinearization {
    let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
    let v = site.strain(&y.fixed_rows::<3>(V).into());
    let u: Vector3<f64> = y.fixed_rows::<3>(U).into();
    let PointFrame { E, R, Jr, Jri, start } = frame;
    debug_assert!(!start || theta == Vector3::zeros(), "the start frame is for theta = 0");
    // Products with a hat matrix are taken as cross products (`linearize::mul_hat`): the
    // same values as the 3 x 3 product, whose terms with hat's zeros add signed zeros, and
    // no vectors with zero lanes, which the AVX2 build moved with the `vmovq` encoding
    // valgrind 3.19 cannot decode (docs/benchmarks.md).

    let mut f = Block::zeros();
    f.fixed_rows_mut::<3>(P).copy_from(&(R * v));
    let mut f_y = SMatrix::<f64, 12, 12>::zeros();
    let mut f_frame = SMatrix::<f64, 12, 3>::zeros();
    if !site.inextensible {
        f_y.fixed_view_mut::<3, 3>(0, 6).copy_from(R);
    }
    f_y.fixed_view_mut::<6, 6>(6, 6).copy_from(&lin.d_strains);
    if *start {
        // theta = 0: J_r = J_r^-1 = exp(theta) = I, R = R_k, and d(J_r^-1 u)/dtheta =
        // -hat(u) / 2 (so3::d_right_jacobian_inv_u at theta = 0, every other term a
        // signed zero).
        f.fixed_rows_mut::<3>(THETA).copy_from(&u);
        let p_theta = linearize::mul_hat(&-Rk, &v);
        f_y.fixed_view_mut::<3, 3>(0, 3).copy_from(&p_theta);
        // -hat(u) / 2 and I entry by entry (their non-zero entries, for the same reason).
        for (r, c, value) in [
            (0, 1, u[2]),
            (0, 2, -u[1]),
            (1, 0, -u[2]),
            (1, 2, u[0]),
            (2, 0, u[1]),
            (2, 1, -u[0]),
        ] {
            f_y[(3 + r, 3 + c)] = value * 0.5;
        }
        for i in 0..3 {
            f_y[(3 + i, 9 + i)] = 1.0;
        }
        f_y.fixed_view_mut::<6, 3>(6, 3).copy_from(&lin.d_rotation);
        f_frame.fixed_view_mut::<3, 3>(0, 0).copy_from(&p_theta);
        f_frame.fixed_view_mut::<6, 3>(6, 0).copy_from(&lin.d_rotation);
    } else {
        f.fixed_rows_mut::<3>(THETA).copy_from(&(Jri * u));
        // p' = R_k exp(theta) v: exp(theta + d) = exp(theta) exp(J_r d)
        f_y.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(linearize::mul_hat(&-R, &v) * *Jr));
        f_y.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&so3::d_right_jacobian_inv_u(&theta, &u));
        f_y.fixed_view_mut::<3, 3>(3, 9).copy_from(Jri);
        // (v', u') depend on theta through R = R_k exp(theta): a right perturbation J_r d
        f_y.fixed_view_mut::<6, 3>(6, 3).copy_from(&(lin.d_rotation * *Jr));
        // R_k exp(phi) w = R_k w - R_k hat(w) phi;  R_k exp(phi) E = R_k E exp(E^T phi)
        f_frame
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&linearize::mul_hat(&-Rk, &(E * v)));
        f_frame
            .fixed_view_mut::<6, 3>(6, 0)
            .copy_from(&(lin.d_rotation * E.transpose()));
    }
    f.fixed_rows_mut::<6>(V).copy_from(&lin.rates);
    PointLinearization { f, f_y, f_frame }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::equations::Model;
    use crate::model::linearize::linearize;
    use nalgebra::Rotation3;

    /// The start node's frame gives the values of the general frame at theta = 0 (F, dF/dy
    /// and dF/dphi compared with ==, so equal up to the sign of a zero): the shortcut skips
    /// exp, J_r, J_r^-1 and products with the identity, not a term.
    #[test]
    fn the_start_frame_gives_the_general_frames_values_at_theta_zero() {
        let robot = crate::collocation::test_support::pulled_prototype();
        let model = Model::new(&robot);
        let length = robot.length();
        let Rk = *Rotation3::from_euler_angles(0.3, -0.2, 0.7).matrix();
        for s in [0.0, 0.3 * length, length] {
            let site = model.site(s);
            let (v, u) = (Vector3::new(0.01, -0.02, 1.001), Vector3::new(3.0, -1.5, 0.4));
            let lin = linearize(&model, &site, length, &Rk, &v, &u).unwrap();
            let mut y = Block::zeros();
            y.fixed_rows_mut::<3>(V).copy_from(&v);
            y.fixed_rows_mut::<3>(U).copy_from(&u);
            let fast = rhs_linearized_inline(&site, &lin, &Rk, &y, &PointFrame::start(&Rk));
            let general = rhs_linearized_inline(&site, &lin, &Rk, &y, &PointFrame::new(&Rk, &Vector3::zeros()));
            assert_eq!(fast.f, general.f, "s = {s}");
            assert_eq!(fast.f_y, general.f_y, "s = {s}");
            assert_eq!(fast.f_frame, general.f_frame, "s = {s}");
        }
    }
}
