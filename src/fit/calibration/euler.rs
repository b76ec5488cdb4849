//! XYZ Euler angles of the base orientation, R0 = Rx(alpha) Ry(beta) Rz(gamma): the matrix,
//! the angles of a matrix, and the rates d phi / d(alpha, beta, gamma) (docs/calibration.md).
#![allow(non_snake_case)]

use nalgebra::{Matrix3, Rotation3, Vector3};
use std::f64::consts::PI;

/// R = Rx(alpha) Ry(beta) Rz(gamma) for angles (alpha, beta, gamma) in rad: intrinsic
/// rotations about x, then the new y, then the newest z (equivalently extrinsic z, y, x).
/// The robot file's `euler_xyz_deg` is this with the angles in degrees.
///
/// # Examples
/// ```
/// use nalgebra::Vector3;
/// use tdcr::fit::calibration::euler_xyz;
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
/// use tdcr::fit::calibration::{euler_xyz, euler_xyz_from};
/// let angles = Vector3::new(3.1, -0.4, -1.6);
/// assert!((euler_xyz_from(&euler_xyz(&angles)) - angles).amax() < 1e-14);
/// ```
pub fn euler_xyz_from(rotation: &Matrix3<f64>) -> Vector3<f64> {
    let R = rotation;
    // R = [[cb cc, -cb sc, sb], [., ., -sa cb], [., ., ca cb]] (docs/calibration.md).
    let cb = R[(0, 0)].hypot(R[(0, 1)]);
    let beta = R[(0, 2)].atan2(cb);
    let (alpha, gamma) = if cb > EULER_SINGULAR {
        ((-R[(1, 2)]).atan2(R[(2, 2)]), (-R[(0, 1)]).atan2(R[(0, 0)]))
    } else {
        // Rx(a) Ry(+-90 deg) = rows [., ., .], [sa, ca, 0], [., sa, 0] up to the sign of
        // the first column: alpha from R[2,1], R[1,1] with gamma = 0.
        (R[(2, 1)].atan2(R[(1, 1)]), 0.0)
    };
    Vector3::new(wrap(alpha), beta, wrap(gamma))
}

/// An angle (rad) in (-pi, pi].
pub fn wrap(angle: f64) -> f64 {
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
