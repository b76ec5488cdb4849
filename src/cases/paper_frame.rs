//! The prototype in the paper's measurement frame (section 5.1): the nominal and calibrated
//! parameters the paper reports, the turn into its frame, and the experiments of Table 2 as
//! calibration measurements.

use super::{Experiment, prototype, prototype_routings};
use crate::fit::calibration::{Measurement, rotate_world};
use crate::model::robot::Robot;
use nalgebra::{Matrix3, Vector3};

/// The paper's nominal base orientation, XYZ Euler angles (180, 0, -90) deg (section 5.1).
pub const PAPER_NOMINAL_EULER_DEG: [f64; 3] = [180.0, 0.0, -90.0];
/// The paper's calibrated base orientation, XYZ Euler angles (177.8, 2.2, -89.7) deg.
pub const PAPER_CALIBRATED_EULER_DEG: [f64; 3] = [177.8, 2.2, -89.7];
/// The paper's calibrated Young's modulus, 230 GPa (nominal 210 GPa,
/// [`crate::cases::YOUNGS_MODULUS`]).
pub const PAPER_CALIBRATED_YOUNGS_MODULUS: f64 = 230e9;

/// The turn from tdcr's prototype frame (gravity along -z, the rod along +x) to a frame in
/// which the prototype's base has the paper's nominal angles: T R0 = Rx(180 deg) Rz(-90 deg)
/// with R0 = Ry(90 deg) ([`crate::cases::prototype_base_rotation`]). Rows
/// `[[0,1,0],[0,0,-1],[-1,0,0]]`; gravity points along +y there, as in a camera frame with
/// y down (the paper measured in its optical tracker's frame; the frame is inferred from the
/// nominal angles, the paper does not state it).
pub fn paper_frame_rotation() -> Matrix3<f64> {
    Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0)
}

/// The prototype ([`crate::cases::prototype`]: nominal E, tendons slack, self weight) in the
/// frame of [`paper_frame_rotation`], where its base orientation is the paper's nominal XYZ
/// Euler angles (180, 0, -90) deg, away from the XYZ singularity.
pub fn prototype_in_paper_frame() -> Robot {
    rotate_world(&prototype(), &paper_frame_rotation())
}

/// The loads of a Table 2 experiment ([`crate::cases::table2`]) as a calibration measurement
/// in the world frame turned by `frame` ([`paper_frame_rotation`], or the identity for
/// tdcr's prototype frame), with the measured tip left at zero.
pub fn table2_measurement(experiment: &Experiment, frame: &Matrix3<f64>) -> Measurement {
    let mut tensions = vec![0.0; prototype_routings().len()];
    if let Some(i) = experiment.tendon {
        tensions[i - 1] = experiment.tension;
    }
    Measurement {
        tensions,
        tip_force: frame * Vector3::new(0.0, 0.0, -experiment.tip_load),
        measured_tip: Vector3::zeros(),
        motion: None,
    }
}
