//! Calibration of material and mounting parameters from measured tip positions (the
//! paper's section 5.1): Young's modulus E and the base orientation as XYZ Euler angles,
//! optionally the base position and a scale on the tendon offsets, fitted by
//! Levenberg-Marquardt with Jacobians from the implicit-function-theorem sensitivities of
//! [`crate::collocation::sensitivity`].
//!
//! # Problem
//!
//! Experiment k sets the tensions tau_k and the tip force F_k and measures the tip at
//! y_k (world frame). With the parameters P the model puts the tip at p_k(P) (a collocation
//! solve of the robot loaded as in experiment k), and the calibration minimizes
//!
//! ```text
//! S(P) = sum_k |p_k(P) - y_k|^2        (m^2)
//! ```
//!
//! The paper minimizes the plain sum of the distances, sum_k |p_k(P) - y_k|. Least squares is
//! used here because it is the maximum-likelihood fit for independent Gaussian measurement
//! noise, it is smooth where a residual vanishes (a distance has a kink there, which breaks
//! the quadratic model of Gauss-Newton and LM), and it gives the standard errors of the
//! fitted parameters from the same Jacobian. The sum of distances weighs outliers less; for
//! data with gross outliers, drop them or fit in stages. The two fits coincide when the
//! model explains the data to the noise.
//!
//! # Parameters and conventions
//!
//! - E (Pa) at fixed Poisson's ratio: G = E / (2 (1 + nu)) follows E, as in the paper
//!   (nu = 0.3125 held constant). The rod must be built from geometry with a uniform section
//!   ([`crate::Rod::tube`], [`crate::Rod::solid_circle`], or `poisson_ratio` in a robot file).
//! - Base orientation R0 = Rx(alpha) Ry(beta) Rz(gamma) (rad): [`euler_xyz`], the convention
//!   of the robot file's `euler_xyz_deg` (rotate about x, then the new y, then the newest z;
//!   the columns of R0 are the body axes in world components). XYZ angles are singular at
//!   beta = +-90 deg, where only alpha + gamma (beta = 90 deg) or alpha - gamma (beta = -90
//!   deg) is determined: express the data in a world frame that keeps beta away from +-90 deg.
//!   tdcr's own prototype frame ([`crate::cases::prototype`], R0 = Ry(90 deg)) sits exactly on
//!   the singularity; the paper's tracker frame ([`prototype_in_paper_frame`], R0 =
//!   Rx(180 deg) Rz(-90 deg)) is far from it.
//! - Base position p0 (m, world frame), off by default.
//! - Offset scale c (dimensionless): every tendon offset r_i(s) becomes c r_i(s) (a common
//!   error in where the tendon holes are), off by default. It is nearly interchangeable with
//!   E for tendon-bent shapes (the tendon moment tau c r bends against E I); experiments with
//!   a tip load or with no tension separate them.
//!
//! # Method
//!
//! Levenberg-Marquardt with Marquardt's scaling (damping lambda diag(J^T J), so the step does
//! not depend on the units of the parameters) and Nielsen's damping update. The unknowns are
//! scaled to order one: E / E_start, the angles in rad, p0 / L and c. Each iteration solves
//! every experiment at the trial parameters, warm-started from its last solution; an accepted
//! step then costs one [`tip_sensitivities`] per experiment, which gives the Jacobian columns:
//!
//! ```text
//! d p_k / dE      = moduli.youngs_modulus (rows 0..3)          (at fixed nu)
//! d p_k / d angle = base_rotation (rows 0..3) * W(alpha, beta)   (chain rule, below)
//! d p_k / d p0    = base_position (rows 0..3)
//! d p_k / dc      = Sensitivity::derivative of the scaled routings (central difference of
//!                   the residual, IFT solve)
//! ```
//!
//! The sensitivity module differentiates with respect to a world-frame rotation vector phi,
//! R0 -> exp(hat(phi)) R0. With R0 = Rx Ry Rz, dR0/dalpha = hat(x) R0,
//! dR0/dbeta = Rx hat(y) Ry Rz = hat(Rx y) R0 and dR0/dgamma = Rx Ry hat(z) Rz = hat(Rx Ry z) R0,
//! so d phi / d(alpha, beta, gamma) = W = [x, Rx(alpha) y, Rx(alpha) Ry(beta) z] (columns;
//! [`euler_rates`]). Its determinant is cos(beta): the singularity above.
//!
//! The model is solved by collocation on a fixed mesh (default 32 intervals) so that the tips
//! are smooth functions of the parameters; an adaptive mesh would make them jump.
//!
//! # Report
//!
//! Fitted values with standard errors (sigma^2 (J^T J)^-1, sigma estimated from the final
//! residuals), the residual of every experiment, and the tip-error statistics of the paper's
//! Table 3 (mean, min, max, standard deviation) at the start and at the fit.
#![allow(non_snake_case)]

use crate::cases;
use crate::collocation::sensitivity::{Difference, RELATIVE_STEP, Sensitivity, tip_sensitivities};
use crate::collocation::{self, Solver};
use crate::error::{Result, invalid};
use crate::io::locate::Position;
use crate::io::{FileError, Problem};
use crate::model::loads::{Field, PointLoad};
use crate::model::robot::Robot;
use crate::model::rod::{Section, Stiffness, shear_modulus};
use crate::model::routing::{Routing, RoutingPoint};
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// One experiment: the tensions and tip force applied and the tip position measured. Every
/// other load (gravity, distributed and point loads, the tip moment) is the robot's.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Tension of each tendon (N, >= 0), in the robot's tendon order; one per tendon.
    pub tensions: Vec<f64>,
    /// Tip force (N, world frame), replacing the robot's.
    pub tip_force: Vector3<f64>,
    /// Measured tip position (m, world frame).
    pub measured_tip: Vector3<f64>,
}

impl Experiment {
    /// `robot` loaded as in this experiment: its tensions and tip force set from this one.
    ///
    /// Precondition: one tension per tendon ([`calibrate`] checks it).
    pub fn load(&self, robot: &Robot) -> Robot {
        let mut loaded = robot.clone();
        for (t, &tension) in loaded.tendons.iter_mut().zip(&self.tensions) {
            t.tension = tension;
        }
        loaded.loads.tip_force = self.tip_force;
        loaded
    }
}

/// The parameters a calibration fits, in SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameters {
    /// Young's modulus E (Pa); G = E / (2 (1 + nu)) follows at the rod's Poisson's ratio.
    /// NaN when the rod was not built from geometry (then E cannot be fitted).
    pub youngs_modulus: f64,
    /// Base orientation as XYZ Euler angles (alpha, beta, gamma) (rad):
    /// R0 = Rx(alpha) Ry(beta) Rz(gamma) ([`euler_xyz`]), the robot file's `euler_xyz_deg`.
    pub euler: Vector3<f64>,
    /// Base position p0 (m, world frame).
    pub base_position: Vector3<f64>,
    /// Factor on every tendon offset r_i(s), relative to the robot's routings (1: as given).
    pub offset_scale: f64,
}

impl Parameters {
    /// The parameters of `robot` as it is: E of its geometry (NaN without one), the Euler
    /// angles of its base rotation ([`euler_xyz_from`]), its base position, offset scale 1.
    pub fn of(robot: &Robot) -> Self {
        Parameters {
            youngs_modulus: robot.rod.geometry.map_or(f64::NAN, |g| g.youngs_modulus),
            euler: euler_xyz_from(&robot.base_rotation),
            base_position: robot.base_position,
            offset_scale: 1.0,
        }
    }

    /// The base rotation R0 = Rx(alpha) Ry(beta) Rz(gamma).
    pub fn base_rotation(&self) -> Matrix3<f64> {
        euler_xyz(&self.euler)
    }

    /// The Euler angles in degrees (alpha, beta, gamma), as the robot file's `euler_xyz_deg`.
    pub fn euler_deg(&self) -> Vector3<f64> {
        self.euler.map(f64::to_degrees)
    }

    /// A copy of `robot` with these parameters: the section rebuilt from the rod's geometry
    /// with E (when the rod has a geometry and E is finite), the base pose set, and every
    /// tendon offset multiplied by `offset_scale`.
    pub fn apply(&self, robot: &Robot) -> Robot {
        let mut out = robot.clone();
        if let (Some(g), true) = (&mut out.rod.geometry, self.youngs_modulus.is_finite()) {
            let e = self.youngs_modulus;
            g.youngs_modulus = e;
            out.rod.stiffness = Stiffness::Uniform(Section::tube(
                g.outer_radius,
                g.inner_radius,
                e,
                shear_modulus(e, g.poisson_ratio),
            ));
        }
        out.base_rotation = self.base_rotation();
        out.base_position = self.base_position;
        if self.offset_scale != 1.0 {
            for t in &mut out.tendons {
                t.routing = scaled_routing(&t.routing, self.offset_scale);
            }
        }
        out
    }
}

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

/// `routing` with its offset r(s) (and so r', r'') multiplied by `factor`.
pub fn scaled_routing(routing: &Routing, factor: f64) -> Routing {
    match routing {
        Routing::Straight { x, y } => Routing::straight(factor * x, factor * y),
        Routing::Helical { radius, turns, phase } => Routing::helical(factor * radius, *turns, *phase),
        Routing::Custom(f) => {
            let f = Arc::clone(f);
            Routing::custom(move |s, length| {
                let p = f(s, length);
                RoutingPoint {
                    r: p.r * factor,
                    r_s: p.r_s * factor,
                    r_ss: p.r_ss * factor,
                }
            })
        }
    }
}

/// The same robot described in a world frame turned by `rotation` (new world coordinates =
/// `rotation` times old): base pose, distributed loads, tip and point wrenches are rotated;
/// the body-frame data (rod, routings) are unchanged, and so is the shape relative to the base.
pub fn rotate_world(robot: &Robot, rotation: &Matrix3<f64>) -> Robot {
    let T = *rotation;
    let mut out = robot.clone();
    out.base_position = T * robot.base_position;
    out.base_rotation = T * robot.base_rotation;
    let turn = |field: &Field| match field {
        Field::Constant(v) => Field::Constant(T * v),
        Field::Varying(f) => {
            let f = Arc::clone(f);
            Field::Varying(Arc::new(move |s| T * f(s)))
        }
    };
    out.loads.distributed_force = turn(&robot.loads.distributed_force);
    out.loads.distributed_moment = turn(&robot.loads.distributed_moment);
    out.loads.tip_force = T * robot.loads.tip_force;
    out.loads.tip_moment = T * robot.loads.tip_moment;
    out.loads.point = robot
        .loads
        .point
        .iter()
        .map(|p| PointLoad {
            s: p.s,
            force: T * p.force,
            moment: T * p.moment,
        })
        .collect();
    out
}

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
    rotate_world(&cases::prototype(), &paper_frame_rotation())
}

/// The loads of a Table 2 experiment ([`crate::cases::table2`]) as a calibration experiment
/// in the world frame turned by `frame` ([`paper_frame_rotation`], or the identity for
/// tdcr's prototype frame), with the measured tip left at zero.
pub fn table2_experiment(experiment: &cases::Experiment, frame: &Matrix3<f64>) -> Experiment {
    let mut tensions = vec![0.0; cases::prototype_routings().len()];
    if let Some(i) = experiment.tendon {
        tensions[i - 1] = experiment.tension;
    }
    Experiment {
        tensions,
        tip_force: frame * Vector3::new(0.0, 0.0, -experiment.tip_load),
        measured_tip: Vector3::zeros(),
    }
}

/// Which parameters to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fit {
    /// Young's modulus E (at fixed Poisson's ratio). Default true.
    pub youngs_modulus: bool,
    /// The base XYZ Euler angles. Default true.
    pub euler: bool,
    /// The base position. Default false.
    pub base_position: bool,
    /// The tendon offset scale. Default false.
    pub offset_scale: bool,
}

impl Default for Fit {
    /// The paper's set: E and the Euler angles.
    fn default() -> Self {
        Fit {
            youngs_modulus: true,
            euler: true,
            base_position: false,
            offset_scale: false,
        }
    }
}

impl Fit {
    /// Every parameter: E, the Euler angles, the base position and the tendon offset scale.
    pub fn all() -> Self {
        Fit {
            youngs_modulus: true,
            euler: true,
            base_position: true,
            offset_scale: true,
        }
    }

    /// Names of the fitted parameters, e.g. `["E", "alpha", "beta", "gamma"]`.
    pub fn names(&self) -> Vec<&'static str> {
        layout(self).iter().map(|u| u.name()).collect()
    }
}

/// Calibration options. `CalibrationOptions { fit: Fit { base_position: true, ..Default::default() }, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationOptions {
    /// Which parameters to fit. Default: E and the Euler angles.
    pub fit: Fit,
    /// Where the fit starts. Default `None`: the robot's own parameters ([`Parameters::of`]).
    pub start: Option<Parameters>,
    /// Collocation options of every solve; the mesh must be fixed (`tolerance: None`).
    /// Default: 32 intervals, residual tolerance 1e-12 (instead of the solver's 1e-11: a
    /// solve stopped just under 1e-11 can leave the tip 1e-8 m off, which would be noise in
    /// the fit; at 1e-12 Newton takes its last step to the rounding floor).
    pub collocation: collocation::Options,
    /// Levenberg-Marquardt iterations (trial steps, accepted or not). Default 50.
    pub max_iterations: usize,
    /// Stop when the largest step of the scaled unknowns (E / E_start, angles in rad,
    /// p0 / L, offset scale) is at most this (dimensionless). Default 1e-9: a change of E by
    /// 1e-9 of itself or of an angle by 1e-9 rad moves the prototype's tip by about 1e-10 m,
    /// a hundredth of the solve precision.
    pub step_tolerance: f64,
    /// Stop when every column of the Jacobian is orthogonal to the residual vector within
    /// this cosine (dimensionless, MINPACK's gtol). Default 1e-10.
    pub gradient_tolerance: f64,
    /// Stop when an accepted step lowers the cost by at most this fraction of it. Default
    /// 1e-12: far below what any parameter resolvable in the data changes.
    pub cost_tolerance: f64,
    /// Initial damping lambda, relative to diag(J^T J) (dimensionless). Default 1e-3
    /// (Marquardt's; close to Gauss-Newton from the first step).
    pub initial_damping: f64,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            fit: Fit::default(),
            start: None,
            collocation: collocation::Options {
                residual_tolerance: 1e-12,
                ..Default::default()
            },
            max_iterations: 50,
            step_tolerance: 1e-9,
            gradient_tolerance: 1e-10,
            cost_tolerance: 1e-12,
            initial_damping: 1e-3,
        }
    }
}

/// The damping above which the fit stops as [`Termination::Stalled`]: 1e16 times
/// diag(J^T J) makes the step about 1e-16 of the gradient step, below rounding.
pub const MAX_DAMPING: f64 = 1e16;

/// Why a calibration stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// Converged: the step fell below the step tolerance.
    StepTolerance,
    /// Converged: the residual is orthogonal to every Jacobian column within the gradient
    /// tolerance (a stationary point), or zero.
    GradientTolerance,
    /// Converged: an accepted step lowered the cost by less than the cost tolerance.
    CostTolerance,
    /// Not converged: the iteration limit was reached first.
    MaxIterations,
    /// Not converged: no step lowered the cost, even with the damping at [`MAX_DAMPING`].
    Stalled,
}

impl Termination {
    /// Whether this is a convergence test passing.
    pub fn converged(&self) -> bool {
        matches!(
            self,
            Termination::StepTolerance | Termination::GradientTolerance | Termination::CostTolerance
        )
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Termination::StepTolerance => "converged: the parameter step fell below the step tolerance",
            Termination::GradientTolerance => {
                "converged: the residuals are orthogonal to every parameter's effect on the tips (a stationary point)"
            }
            Termination::CostTolerance => {
                "converged: the last accepted step lowered the sum of squared tip errors by less than the cost tolerance"
            }
            Termination::MaxIterations => {
                "stopped at the iteration limit before a convergence test passed; raise max_iterations or start closer"
            }
            Termination::Stalled => {
                "stalled: no step lowered the sum of squared tip errors even at the largest damping; the parameters may not be identifiable from these experiments"
            }
        })
    }
}

/// One Levenberg-Marquardt iteration (one trial step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iteration {
    /// Cost S = sum of squared tip errors after the iteration (m^2): the trial's if accepted,
    /// else unchanged.
    pub cost: f64,
    /// Largest component of the trial step in the scaled unknowns.
    pub step: f64,
    /// The damping lambda the step was computed with (relative to diag(J^T J)).
    pub damping: f64,
    /// Gain ratio: actual over predicted decrease of the cost (NaN when a trial solve failed).
    pub gain: f64,
    /// Whether the step was accepted.
    pub accepted: bool,
}

/// Tip-error statistics over a set of experiments, as in the paper's Table 3 (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipErrorStatistics {
    /// Number of experiments.
    pub count: usize,
    /// Mean tip error (m).
    pub mean: f64,
    /// Smallest tip error (m).
    pub min: f64,
    /// Largest tip error (m).
    pub max: f64,
    /// Sample standard deviation (n - 1 in the denominator; 0 for one experiment) (m).
    pub std_dev: f64,
    /// Root mean square (m).
    pub rms: f64,
}

impl TipErrorStatistics {
    /// The statistics of tip errors |p_k - y_k| (m); NaN fields for no errors.
    pub fn of(errors: &[f64]) -> Self {
        let n = errors.len();
        let mean = errors.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        let (min, max) = if n == 0 {
            (f64::NAN, f64::NAN)
        } else {
            errors
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &e| (a.min(e), b.max(e)))
        };
        TipErrorStatistics {
            count: n,
            mean,
            min,
            max,
            std_dev: if n == 0 { f64::NAN } else { var.sqrt() },
            rms: (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt(),
        }
    }
}

/// Wall-clock time of a calibration, split by stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Collocation solves of all experiments.
    pub solves: Duration,
    /// Tip sensitivities (Jacobian columns).
    pub sensitivities: Duration,
    /// Everything, validation included.
    pub total: Duration,
}

/// The result of [`calibrate`].
#[derive(Clone, Debug)]
pub struct Calibration {
    /// What was fitted.
    pub fit: Fit,
    /// The parameters the fit started from.
    pub start: Parameters,
    /// The fitted parameters (angles in (-pi, pi]); the others as at the start.
    pub fitted: Parameters,
    /// Standard errors of the fitted parameters, sigma sqrt(diag((J^T J)^-1)) in the same
    /// units, with sigma = [`Calibration::noise_estimate`]; 0 for parameters not fitted.
    /// `None` when there are no more residuals than unknowns or J^T J is singular (as at
    /// beta = +-90 deg).
    pub standard_errors: Option<Parameters>,
    /// Noise estimate sigma = sqrt(S / (3 N - n)) per coordinate (m), N experiments and n
    /// unknowns; NaN when 3 N = n.
    pub noise_estimate: f64,
    /// The robot with the fitted parameters (the robot's own tensions and tip force).
    pub robot: Robot,
    /// Model tip of every experiment at the fitted parameters (m, world).
    pub tips: Vec<Vector3<f64>>,
    /// Model tip minus measured tip of every experiment at the fit (m, world).
    pub residuals: Vec<Vector3<f64>>,
    /// Model tip minus measured tip of every experiment at the start (m, world).
    pub start_residuals: Vec<Vector3<f64>>,
    /// Table 3 statistics of the tip errors at the start.
    pub start_errors: TipErrorStatistics,
    /// Table 3 statistics of the tip errors at the fit.
    pub errors: TipErrorStatistics,
    /// Why the iteration stopped.
    pub termination: Termination,
    /// Levenberg-Marquardt iterations (trial steps, accepted or not).
    pub iterations: usize,
    /// Every iteration.
    pub history: Vec<Iteration>,
    /// Collocation solves (one per experiment per evaluated parameter set).
    pub solves: usize,
    /// Tip sensitivity evaluations (one per experiment per accepted parameter set).
    pub sensitivity_evaluations: usize,
    /// Timings.
    pub timings: Timings,
}

impl Calibration {
    /// Whether a convergence test passed ([`Termination::converged`]).
    pub fn converged(&self) -> bool {
        self.termination.converged()
    }

    /// The tip error |p_k - y_k| of every experiment at the fit (m).
    pub fn tip_errors(&self) -> Vec<f64> {
        self.residuals.iter().map(|r| r.norm()).collect()
    }

    /// The tip error of every experiment at the start (m).
    pub fn start_tip_errors(&self) -> Vec<f64> {
        self.start_residuals.iter().map(|r| r.norm()).collect()
    }
}

/// One fitted unknown and its scaling to order one.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Unknown {
    /// E / E_start.
    YoungsModulus,
    /// Euler angle 0, 1, 2 (rad).
    Euler(usize),
    /// Base position component / L.
    BasePosition(usize),
    /// Offset scale.
    OffsetScale,
}

impl Unknown {
    fn name(&self) -> &'static str {
        match self {
            Unknown::YoungsModulus => "E",
            Unknown::Euler(i) => ["alpha", "beta", "gamma"][*i],
            Unknown::BasePosition(i) => ["x0", "y0", "z0"][*i],
            Unknown::OffsetScale => "offset_scale",
        }
    }

    /// Physical units per scaled unit.
    fn scale(&self, start: &Parameters, length: f64) -> f64 {
        match self {
            Unknown::YoungsModulus => start.youngs_modulus,
            Unknown::Euler(_) | Unknown::OffsetScale => 1.0,
            Unknown::BasePosition(_) => length,
        }
    }

    fn get(&self, p: &Parameters) -> f64 {
        match self {
            Unknown::YoungsModulus => p.youngs_modulus,
            Unknown::Euler(i) => p.euler[*i],
            Unknown::BasePosition(i) => p.base_position[*i],
            Unknown::OffsetScale => p.offset_scale,
        }
    }

    fn set(&self, p: &mut Parameters, value: f64) {
        match self {
            Unknown::YoungsModulus => p.youngs_modulus = value,
            Unknown::Euler(i) => p.euler[*i] = value,
            Unknown::BasePosition(i) => p.base_position[*i] = value,
            Unknown::OffsetScale => p.offset_scale = value,
        }
    }
}

fn layout(fit: &Fit) -> Vec<Unknown> {
    let mut out = Vec::new();
    if fit.youngs_modulus {
        out.push(Unknown::YoungsModulus);
    }
    if fit.euler {
        out.extend((0..3).map(Unknown::Euler));
    }
    if fit.base_position {
        out.extend((0..3).map(Unknown::BasePosition));
    }
    if fit.offset_scale {
        out.push(Unknown::OffsetScale);
    }
    out
}

/// Checks the robot, experiments and options before any solve.
fn validate(robot: &Robot, experiments: &[Experiment], options: &CalibrationOptions, start: &Parameters) -> Result<()> {
    robot.validate()?;
    if experiments.is_empty() {
        return Err(invalid(
            "experiments",
            "is empty",
            "give at least two experiments (each gives 3 tip coordinates for 4 parameters by default)",
        ));
    }
    let k = robot.tendons.len();
    for (i, e) in experiments.iter().enumerate() {
        if e.tensions.len() != k {
            return Err(invalid(
                format!("experiments[{i}].tensions"),
                format!("has {} values, but the robot has {k} tendons", e.tensions.len()),
                "give one tension per tendon, in the robot's tendon order (0 for a slack tendon)",
            ));
        }
        if let Some((j, t)) = e
            .tensions
            .iter()
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t >= 0.0))
        {
            return Err(invalid(
                format!("experiments[{i}].tensions[{j}]"),
                format!("is {t} N"),
                "tensions must be finite and >= 0 (a tendon can only pull)",
            ));
        }
        for (field, v, unit) in [("tip_force", &e.tip_force, "N"), ("measured_tip", &e.measured_tip, "m")] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(invalid(
                    format!("experiments[{i}].{field}"),
                    format!("is ({}, {}, {}) {unit}", v[0], v[1], v[2]),
                    "every component must be finite",
                ));
            }
        }
    }
    let unknowns = layout(&options.fit);
    if unknowns.is_empty() {
        return Err(invalid(
            "options.fit",
            "selects no parameter",
            "fit at least one of E, the Euler angles, the base position, the offset scale",
        ));
    }
    if 3 * experiments.len() < unknowns.len() {
        return Err(invalid(
            "experiments",
            format!(
                "give {} tip coordinates for {} unknowns",
                3 * experiments.len(),
                unknowns.len()
            ),
            "give at least as many tip coordinates (3 per experiment) as unknowns, better several times as many",
        ));
    }
    if options.fit.youngs_modulus {
        let uniform = matches!(robot.rod.stiffness, Stiffness::Uniform(_));
        if robot.rod.geometry.is_none() || !uniform {
            return Err(invalid(
                "robot.rod",
                "was not built from geometry (radii, E and Poisson's ratio) with a uniform section, so its Young's modulus cannot be fitted",
                "build the rod with Rod::tube or Rod::solid_circle (in a robot file give poisson_ratio, not shear_modulus), or do not fit E",
            ));
        }
    }
    let p = start;
    let finite = p.euler.iter().chain(p.base_position.iter()).all(|x| x.is_finite()) && p.offset_scale.is_finite();
    let positive_e = p.youngs_modulus > 0.0 && p.youngs_modulus.is_finite();
    if !finite || p.offset_scale <= 0.0 || (options.fit.youngs_modulus && !positive_e) {
        return Err(invalid(
            "options.start",
            format!("is {p:?}"),
            "start from finite parameters with E > 0 and offset scale > 0 (or leave it None: the robot's own)",
        ));
    }
    let o = options;
    if o.collocation.tolerance.is_some() {
        return Err(invalid(
            "options.collocation.tolerance",
            "is set (adaptive mesh refinement)",
            "calibrate on a fixed mesh (tolerance None) so that the model tips are smooth in the parameters",
        ));
    }
    let tolerances = [o.step_tolerance, o.gradient_tolerance, o.cost_tolerance];
    if o.max_iterations == 0 || tolerances.iter().any(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(invalid(
            "options",
            format!(
                "has max_iterations {}, step, gradient, cost tolerances {tolerances:?}",
                o.max_iterations
            ),
            "use max_iterations >= 1 and finite tolerances >= 0 (CalibrationOptions::default())",
        ));
    }
    if !(o.initial_damping.is_finite() && o.initial_damping > 0.0) {
        return Err(invalid(
            "options.initial_damping",
            format!("is {}", o.initial_damping),
            "give a positive damping, 1e-3 by default",
        ));
    }
    Ok(())
}

/// The model tip of every experiment for the given parameters: one collocation solve each
/// (on `options.collocation`'s fixed mesh), in parallel. The measured tips are ignored; use
/// this to make synthetic data or to check a calibration on other experiments.
///
/// # Errors
/// Invalid input as in [`calibrate`] (E is applied only when the rod has a geometry); the
/// solver's errors when an experiment does not solve.
///
/// # Examples
/// ```
/// use tdcr::fit::calibration::{CalibrationOptions, Parameters, predict, table2_experiment};
/// let robot = tdcr::cases::prototype();
/// let case_s = &tdcr::cases::table2()[11]; // tendon 1 at 2.94 N
/// let experiment = table2_experiment(case_s, &nalgebra::Matrix3::identity());
/// let tips = predict(&robot, &Parameters::of(&robot), &[experiment], &CalibrationOptions::default()).unwrap();
/// assert!((tips[0].x - tdcr::cases::TIP_S[0]).abs() < 1e-5);
/// ```
pub fn predict(
    robot: &Robot,
    parameters: &Parameters,
    experiments: &[Experiment],
    options: &CalibrationOptions,
) -> Result<Vec<Vector3<f64>>> {
    let check = CalibrationOptions {
        fit: Fit {
            youngs_modulus: false,
            euler: true,
            base_position: false,
            offset_scale: false,
        },
        ..options.clone()
    };
    validate(robot, experiments, &check, parameters)?;
    let applied = parameters.apply(robot);
    let mut sites: Vec<Site> = experiments.iter().map(|_| Site::new(&options.collocation)).collect();
    Ok(solve_all(&applied, experiments, &mut sites)?
        .iter()
        .map(Solution::tip_position)
        .collect())
}

/// Per-experiment solver state: a collocation solver (keeping its workspace) and the last
/// accepted solution (the warm start).
struct Site {
    solver: Solver,
    solution: Option<Solution>,
}

impl Site {
    fn new(options: &collocation::Options) -> Self {
        Site {
            solver: Solver::new(options.clone()),
            solution: None,
        }
    }
}

/// Solves every experiment for the robot `applied` (parameters already set), warm-started
/// from each site's accepted solution; the sites are not updated.
fn solve_all(applied: &Robot, experiments: &[Experiment], sites: &mut [Site]) -> Result<Vec<Solution>> {
    experiments
        .par_iter()
        .zip(sites.par_iter_mut())
        .map(|(e, site)| {
            let robot = e.load(applied);
            match &site.solution {
                Some(warm) => site.solver.solve_from(&robot, warm),
                None => site.solver.solve(&robot),
            }
        })
        .collect()
}

/// The 3N x n Jacobian of the tips in the scaled unknowns at the solutions of `applied`.
fn jacobian(
    applied: &Robot,
    params: &Parameters,
    experiments: &[Experiment],
    solutions: &[Solution],
    unknowns: &[Unknown],
    start: &Parameters,
) -> Result<DMatrix<f64>> {
    let length = applied.length();
    let W = euler_rates(&params.euler);
    let blocks: Vec<DMatrix<f64>> = experiments
        .par_iter()
        .zip(solutions.par_iter())
        .map(|(e, solution)| -> Result<DMatrix<f64>> {
            let robot = e.load(applied);
            let sens = tip_sensitivities(&robot, solution)?;
            let mut block = DMatrix::zeros(3, unknowns.len());
            let rotation = sens.base_rotation.fixed_rows::<3>(0) * W;
            for (j, u) in unknowns.iter().enumerate() {
                let column: Vector3<f64> = match u {
                    Unknown::YoungsModulus => match &sens.moduli {
                        Some(m) => m.youngs_modulus.fixed_rows::<3>(0).into_owned(),
                        None => {
                            return Err(invalid(
                                "robot.rod",
                                "has no modulus sensitivity (its section is not the one its geometry gives)",
                                "build the rod from geometry, or do not fit E",
                            ));
                        }
                    },
                    Unknown::Euler(i) => rotation.column(*i).into_owned(),
                    Unknown::BasePosition(i) => sens.base_position.fixed_rows::<3>(0).column(*i).into_owned(),
                    Unknown::OffsetScale => offset_column(&robot, solution, params.offset_scale)?,
                };
                block.set_column(j, &(column * u.scale(start, length)));
            }
            Ok(block)
        })
        .collect::<Result<_>>()?;
    let mut J = DMatrix::zeros(3 * experiments.len(), unknowns.len());
    for (k, b) in blocks.iter().enumerate() {
        J.view_mut((3 * k, 0), (3, unknowns.len())).copy_from(b);
    }
    Ok(J)
}

/// d tip / d c for the offset scale c: the routings of `robot` are c times the original, so
/// moving c by dq scales them by (c + dq) / c. Central difference of the residual at
/// [`RELATIVE_STEP`] of c, solved by the implicit function theorem.
fn offset_column(robot: &Robot, solution: &Solution, scale: f64) -> Result<Vector3<f64>> {
    let mut sens = Sensitivity::new(robot, solution)?;
    let d = sens.derivative(RELATIVE_STEP * scale, Difference::Central, |r, dq| {
        for t in &mut r.tendons {
            t.routing = scaled_routing(&t.routing, (scale + dq) / scale);
        }
    })?;
    Ok(d[d.len() - 1].p)
}

/// Stacked residuals (model tip - measured tip), 3 per experiment.
fn residual_vector(solutions: &[Solution], experiments: &[Experiment]) -> DVector<f64> {
    DVector::from_iterator(
        3 * experiments.len(),
        solutions
            .iter()
            .zip(experiments)
            .flat_map(|(s, e)| (s.tip_position() - e.measured_tip).iter().copied().collect::<Vec<_>>()),
    )
}

fn per_experiment(r: &DVector<f64>) -> Vec<Vector3<f64>> {
    (0..r.len() / 3)
        .map(|k| Vector3::new(r[3 * k], r[3 * k + 1], r[3 * k + 2]))
        .collect()
}

/// Fits the selected parameters of `robot` to the measured tips of `experiments` by
/// Levenberg-Marquardt on the sum of squared tip errors (module docs).
///
/// `robot` supplies everything not fitted (geometry, Poisson's ratio, tendons, gravity and
/// other loads) and, unless `options.start` is given, the starting parameters. Each
/// experiment replaces the tensions and the tip force.
///
/// A fit that stops without converging ([`Termination::MaxIterations`],
/// [`Termination::Stalled`]) is still returned, with the best parameters found: check
/// [`Calibration::converged`].
///
/// # Errors
/// [`crate::Error::InvalidInput`] naming the field for: no experiments, a tension count
/// other than the robot's tendon count, a negative or non-finite tension, a non-finite tip
/// force or measured tip, fewer tip coordinates than unknowns, no parameter selected, E
/// selected for a rod without geometry, an adaptive mesh, bad options. The solver's errors
/// when an experiment does not solve at the start parameters (a trial step whose solve
/// fails is rejected instead).
///
/// # Examples
/// ```
/// use tdcr::fit::calibration::{calibrate, predict, prototype_in_paper_frame, table2_experiment,
///     paper_frame_rotation, CalibrationOptions, Parameters};
/// let robot = prototype_in_paper_frame();
/// // Synthetic data: E 5 % stiffer than nominal, six experiments of Table 2.
/// let mut truth = Parameters::of(&robot);
/// truth.youngs_modulus *= 1.05;
/// let options = CalibrationOptions::default();
/// let mut experiments: Vec<_> = tdcr::cases::table2()[..31]
///     .iter()
///     .step_by(5)
///     .map(|e| table2_experiment(e, &paper_frame_rotation()))
///     .collect();
/// let tips = predict(&robot, &truth, &experiments, &options).unwrap();
/// for (e, tip) in experiments.iter_mut().zip(tips) {
///     e.measured_tip = tip;
/// }
/// let fit = calibrate(&robot, &experiments, &options).unwrap();
/// assert!(fit.converged());
/// assert!((fit.fitted.youngs_modulus / truth.youngs_modulus - 1.0).abs() < 1e-6);
/// assert!(fit.errors.max < 1e-8);
/// ```
pub fn calibrate(robot: &Robot, experiments: &[Experiment], options: &CalibrationOptions) -> Result<Calibration> {
    let begin = Instant::now();
    let start = options.start.unwrap_or_else(|| Parameters::of(robot));
    validate(robot, experiments, options, &start)?;
    let unknowns = layout(&options.fit);
    let length = robot.length();
    let scales: Vec<f64> = unknowns.iter().map(|u| u.scale(&start, length)).collect();
    let to_params = |z: &DVector<f64>| {
        let mut p = start;
        for (j, u) in unknowns.iter().enumerate() {
            u.set(&mut p, z[j] * scales[j]);
        }
        p
    };
    let mut z = DVector::from_iterator(
        unknowns.len(),
        unknowns.iter().zip(&scales).map(|(u, s)| u.get(&start) / s),
    );
    let mut timings = Timings::default();
    let mut sites: Vec<Site> = experiments.iter().map(|_| Site::new(&options.collocation)).collect();
    let (mut solves, mut sensitivity_evaluations) = (0, 0);

    // Start: solve, residuals, Jacobian.
    let mut params = start;
    let mut applied = params.apply(robot);
    let t = Instant::now();
    let solutions = solve_all(&applied, experiments, &mut sites)?;
    timings.solves += t.elapsed();
    solves += experiments.len();
    let mut r = residual_vector(&solutions, experiments);
    let start_residuals = per_experiment(&r);
    let mut cost = r.norm_squared();
    let t = Instant::now();
    let mut J = jacobian(&applied, &params, experiments, &solutions, &unknowns, &start)?;
    timings.sensitivities += t.elapsed();
    sensitivity_evaluations += experiments.len();
    for (site, s) in sites.iter_mut().zip(solutions) {
        site.solution = Some(s);
    }

    let mut lambda = options.initial_damping;
    let mut nu = 2.0;
    let mut history = Vec::new();
    let mut termination = Termination::MaxIterations;
    let n = unknowns.len();
    while history.len() < options.max_iterations {
        let g = J.transpose() * &r;
        // MINPACK's gtol: the largest cosine between the residual and a column.
        let rn = r.norm();
        let cosine = (0..n)
            .map(|j| {
                let c = J.column(j).norm();
                if c > 0.0 && rn > 0.0 {
                    g[j].abs() / (c * rn)
                } else {
                    0.0
                }
            })
            .fold(0.0f64, f64::max);
        if rn == 0.0 || cosine <= options.gradient_tolerance {
            termination = Termination::GradientTolerance;
            break;
        }
        let A = J.transpose() * &J;
        // diag(J^T J), floored at 1e-12 of its largest entry so that a parameter without
        // effect (a zero column) still gets damped.
        let largest = A.diagonal().max();
        let D = A.diagonal().map(|d| d.max(1e-12 * largest));
        let mut M = A.clone();
        for j in 0..n {
            M[(j, j)] += lambda * D[j];
        }
        let Some(chol) = M.cholesky() else {
            lambda *= nu;
            nu *= 2.0;
            if lambda > MAX_DAMPING {
                termination = Termination::Stalled;
                break;
            }
            continue;
        };
        let delta = chol.solve(&(-&g));
        let step = delta.amax();
        if step <= options.step_tolerance {
            termination = Termination::StepTolerance;
            break;
        }
        let trial_z = &z + &delta;
        let trial = to_params(&trial_z);
        let trial_robot = trial.apply(robot);
        let t = Instant::now();
        let solved = solve_all(&trial_robot, experiments, &mut sites);
        timings.solves += t.elapsed();
        solves += experiments.len();
        // Decrease of S = |r|^2 predicted by the linear model |r + J delta|^2:
        // -2 g.delta - delta^T A delta (positive for any lambda > 0).
        let predicted = -2.0 * g.dot(&delta) - (delta.transpose() * &A * &delta)[(0, 0)];
        let (gain, new) = match solved {
            Ok(solutions) => {
                let r_new = residual_vector(&solutions, experiments);
                let c = r_new.norm_squared();
                ((cost - c) / predicted, Some((solutions, r_new, c)))
            }
            Err(_) => (f64::NAN, None),
        };
        let accepted = gain > 0.0 && predicted > 0.0;
        if let (true, Some((solutions, r_new, c))) = (accepted, new) {
            let decrease = (cost - c) / cost;
            z = trial_z;
            params = trial;
            applied = trial_robot;
            r = r_new;
            cost = c;
            let t = Instant::now();
            J = jacobian(&applied, &params, experiments, &solutions, &unknowns, &start)?;
            timings.sensitivities += t.elapsed();
            sensitivity_evaluations += experiments.len();
            for (site, s) in sites.iter_mut().zip(solutions) {
                site.solution = Some(s);
            }
            lambda *= (1.0 - (2.0 * gain - 1.0).powi(3)).max(1.0 / 3.0);
            nu = 2.0;
            history.push(Iteration {
                cost,
                step,
                damping: lambda,
                gain,
                accepted: true,
            });
            if decrease <= options.cost_tolerance {
                termination = Termination::CostTolerance;
                break;
            }
        } else {
            history.push(Iteration {
                cost,
                step,
                damping: lambda,
                gain,
                accepted: false,
            });
            lambda *= nu;
            nu *= 2.0;
            if lambda > MAX_DAMPING {
                termination = Termination::Stalled;
                break;
            }
        }
    }

    let m = r.len();
    let noise_estimate = if m > n {
        (cost / (m - n) as f64).sqrt()
    } else {
        f64::NAN
    };
    let standard_errors = (m > n).then(|| (J.transpose() * &J).cholesky()).flatten().map(|chol| {
        let inverse = chol.inverse();
        let mut se = Parameters {
            youngs_modulus: 0.0,
            euler: Vector3::zeros(),
            base_position: Vector3::zeros(),
            offset_scale: 0.0,
        };
        for (j, u) in unknowns.iter().enumerate() {
            u.set(&mut se, noise_estimate * inverse[(j, j)].sqrt() * scales[j]);
        }
        se
    });
    let mut fitted = params;
    fitted.euler = fitted.euler.map(wrap);
    let residuals = per_experiment(&r);
    let tips = sites
        .iter()
        .map(|s| {
            s.solution
                .as_ref()
                .map_or(Vector3::repeat(f64::NAN), Solution::tip_position)
        })
        .collect();
    let errors: Vec<f64> = residuals.iter().map(|r| r.norm()).collect();
    let start_errors: Vec<f64> = start_residuals.iter().map(|r| r.norm()).collect();
    timings.total = begin.elapsed();
    Ok(Calibration {
        fit: options.fit,
        start,
        fitted,
        standard_errors,
        noise_estimate,
        robot: fitted.apply(robot),
        tips,
        residuals,
        start_residuals,
        start_errors: TipErrorStatistics::of(&start_errors),
        errors: TipErrorStatistics::of(&errors),
        termination,
        iterations: history.len(),
        history,
        solves,
        sensitivity_evaluations,
        timings,
    })
}

// ---------------------------------------------------------------------------------------
// The experiments CSV file

/// The tip-force and measured-tip columns of the experiments CSV, after the tensions.
pub const CSV_VECTOR_COLUMNS: [&str; 6] = [
    "tip_force_x",
    "tip_force_y",
    "tip_force_z",
    "measured_x",
    "measured_y",
    "measured_z",
];

/// The header of an experiments CSV for a robot with `tendons` tendons:
/// `tension_1,...,tension_k,tip_force_x,tip_force_y,tip_force_z,measured_x,measured_y,measured_z`.
pub fn csv_header(tendons: usize) -> String {
    let mut names: Vec<String> = (1..=tendons).map(|i| format!("tension_{i}")).collect();
    names.extend(CSV_VECTOR_COLUMNS.iter().map(|s| s.to_string()));
    names.join(",")
}

/// The experiments as CSV (docs/calibration.md): the header of [`csv_header`], then one row
/// per experiment in SI units (N, N, m), numbers written to round-trip exactly.
///
/// Precondition: every experiment has the same number of tensions.
pub fn to_csv(experiments: &[Experiment]) -> String {
    let k = experiments.first().map_or(0, |e| e.tensions.len());
    let mut out = csv_header(k);
    out.push('\n');
    for e in experiments {
        let values: Vec<String> = e
            .tensions
            .iter()
            .chain(e.tip_force.iter())
            .chain(e.measured_tip.iter())
            .map(|x| format!("{x:?}"))
            .collect();
        out.push_str(&values.join(","));
        out.push('\n');
    }
    out
}

/// At most this many problems are listed for one CSV file: enough to see a pattern.
const MAX_CSV_PROBLEMS: usize = 20;

/// Reads an experiments CSV (docs/calibration.md) for a robot with `tendons` tendons.
///
/// The first line that is neither blank nor a `#` comment is the header: the column names
/// of [`csv_header`] in any order, each once. Every following non-blank, non-comment line is
/// one experiment with a finite number in every column (tensions >= 0). `file` names the
/// source in messages.
///
/// # Errors
/// A [`FileError`] listing every problem (up to 20) with its line and column (characters,
/// from 1) and the column name: unknown, repeated or missing columns, a row with the wrong
/// number of fields, a value that is not a finite number, a negative tension, no rows.
///
/// # Examples
/// ```
/// let text = "tension_1,tip_force_x,tip_force_y,tip_force_z,measured_x,measured_y,measured_z\n\
///             2.94,0,0,-0.098,0.15,0,-0.16\n";
/// let experiments = tdcr::fit::calibration::parse_csv(text, "data.csv", 1).unwrap();
/// assert_eq!(experiments[0].tensions, vec![2.94]);
/// let bad = tdcr::fit::calibration::parse_csv(&text.replace("0.15", "x"), "data.csv", 1).unwrap_err();
/// assert!(bad.to_string().starts_with("data.csv:2:17: `measured_x` (column 5)"), "{bad}");
/// ```
pub fn parse_csv(text: &str, file: &str, tendons: usize) -> std::result::Result<Vec<Experiment>, FileError> {
    let mut problems = Vec::new();
    let at = |line: usize, column: usize| Some(Position { line, column });
    let mut lines = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let expected: Vec<String> = csv_header(tendons).split(',').map(str::to_string).collect();
    let Some((header_line, header)) = lines.next() else {
        return Err(FileError {
            file: file.to_string(),
            problems: vec![Problem {
                position: None,
                field: String::new(),
                message: format!("has no header line; start with `{}`", csv_header(tendons)),
            }],
        });
    };
    // Column index -> which value it holds (index into `expected`).
    let mut slots: Vec<Option<usize>> = Vec::new();
    for (column, name) in fields(header) {
        let name = name.trim();
        let slot = expected.iter().position(|e| e == name);
        if slot.is_some() && slots.contains(&slot) {
            problems.push(Problem {
                position: at(header_line, column),
                field: crate::io::printable(name),
                message: "is repeated; give each column once".into(),
            });
        } else if slot.is_none() {
            let hint = match name.strip_prefix("tension_").and_then(|i| i.parse::<usize>().ok()) {
                Some(i) => format!("the robot has {tendons} tendon(s), so tension_{i} is not one of its columns"),
                None => format!("the columns are {}", expected.join(",")),
            };
            problems.push(Problem {
                position: at(header_line, column),
                field: crate::io::printable(name),
                message: format!("is not a column of the experiments file; {hint}"),
            });
        }
        slots.push(slot);
    }
    for (i, name) in expected.iter().enumerate() {
        if !slots.contains(&Some(i)) {
            problems.push(Problem {
                position: at(header_line, 1),
                field: name.clone(),
                message: format!(
                    "is missing from the header; the robot has {tendons} tendon(s), so the header is `{}`",
                    expected.join(",")
                ),
            });
        }
    }
    if !problems.is_empty() {
        return Err(FileError {
            file: file.to_string(),
            problems,
        });
    }
    let mut experiments = Vec::new();
    for (line, row) in lines {
        if problems.len() >= MAX_CSV_PROBLEMS {
            break;
        }
        let cells = fields(row);
        if cells.len() != slots.len() {
            problems.push(Problem {
                position: at(line, 1),
                field: String::new(),
                message: format!("has {} fields, but the header has {} columns", cells.len(), slots.len()),
            });
            continue;
        }
        let mut values = vec![0.0; expected.len()];
        let mut ok = true;
        for (index, ((column, cell), slot)) in cells.into_iter().zip(&slots).enumerate() {
            let Some(slot) = *slot else { continue };
            let name = &expected[slot];
            let cell = cell.trim();
            let problem = match cell.parse::<f64>() {
                Ok(x) if !x.is_finite() => Some(format!("is `{cell}`, not a finite number")),
                Ok(x) if slot < tendons && x < 0.0 => Some(format!("is {x} N: a tendon can only pull (tension >= 0)")),
                Ok(x) => {
                    values[slot] = x;
                    None
                }
                Err(_) => Some(format!(
                    "is `{}`, not a number (SI units: N and m, e.g. 2.94 or -1.5e-3)",
                    crate::io::printable(cell)
                )),
            };
            if let Some(message) = problem {
                ok = false;
                problems.push(Problem {
                    position: at(line, column),
                    field: name.clone(),
                    message: format!("(column {}) {message}", index + 1),
                });
            }
        }
        if ok {
            let v = |i: usize| Vector3::new(values[tendons + i], values[tendons + i + 1], values[tendons + i + 2]);
            experiments.push(Experiment {
                tensions: values[..tendons].to_vec(),
                tip_force: v(0),
                measured_tip: v(3),
            });
        }
    }
    if problems.is_empty() && experiments.is_empty() {
        problems.push(Problem {
            position: None,
            field: String::new(),
            message: "has a header but no experiments; add one row per experiment".into(),
        });
    }
    if problems.is_empty() {
        Ok(experiments)
    } else {
        if problems.len() >= MAX_CSV_PROBLEMS {
            problems.push(Problem {
                position: None,
                field: String::new(),
                message: format!("stopped after {MAX_CSV_PROBLEMS} problems"),
            });
        }
        Err(FileError {
            file: file.to_string(),
            problems,
        })
    }
}

/// The comma-separated fields of a line with the character column (from 1) where each starts.
fn fields(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut column = 1;
    for field in line.split(',') {
        out.push((column, field));
        column += field.chars().count() + 1;
    }
    out
}

/// Deterministic standard normal numbers for synthetic measurements (the tests, the
/// walk-through): splitmix64 uniforms (Steele, Lea & Flood 2014) through Box-Muller, so the
/// same seed gives the same noise on every machine.
pub struct GaussianNoise(u64);

impl GaussianNoise {
    /// A sequence starting from `seed`.
    pub fn new(seed: u64) -> Self {
        GaussianNoise(seed)
    }

    /// A uniform number in (0, 1] (53 random bits, so ln(u) is finite).
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// The next standard normal number (mean 0, standard deviation 1).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}
