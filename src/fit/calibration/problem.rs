//! The data of a calibration problem: the measurements, the parameters fitted, which of them
//! to fit and the options, and the checks on them before any solve.

use super::robots::scaled_routing;
use crate::collocation;
use crate::error::{Result, invalid};
use crate::model::robot::Robot;
use crate::model::rod::{Section, Stiffness, shear_modulus};
use crate::model::tendon::Motion;
use crate::so3::{euler_xyz, euler_xyz_from};
use nalgebra::{Matrix3, Vector3};

/// One measurement of a calibration experiment: the tensions and tip force applied and the
/// tip position measured. Every other load (gravity, distributed and point loads, the tip
/// moment) is the robot's. (Not [`crate::cases::Experiment`], a row of the paper's Table 2;
/// [`crate::cases::table2_measurement`] turns one into this.)
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Tension of each tendon (N, >= 0), in the robot's tendon order; one per tendon.
    pub tensions: Vec<f64>,
    /// Tip force (N, world frame), replacing the robot's.
    pub tip_force: Vector3<f64>,
    /// Measured tip position (m, world frame).
    pub measured_tip: Vector3<f64>,
    /// The motion of the tendons with friction in this experiment (docs/friction.md):
    /// [`Motion::Pull`] for a step of a loading branch, [`Motion::Release`] for one of an
    /// unloading branch; `None` keeps each tendon's own. Ignored without friction.
    pub motion: Option<Motion>,
}

impl Measurement {
    /// `robot` loaded as in this experiment: its tensions and tip force set from this one,
    /// and the motion of its tendons with friction when this one gives it.
    ///
    /// Precondition: one tension per tendon ([`super::calibrate`] checks it).
    pub fn load(&self, robot: &Robot) -> Robot {
        let mut loaded = robot.clone();
        for (t, &tension) in loaded.tendons.iter_mut().zip(&self.tensions) {
            t.set_tension(tension);
            if let (Some(f), Some(motion)) = (&mut t.friction, self.motion) {
                f.motion = motion;
            }
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
    /// Friction coefficient mu (dimensionless) of the robot's first tendon with friction
    /// (docs/friction.md); the other tendons with friction keep their coefficients' ratios
    /// to it (one shared value where they are equal), so fitting it scales them all. 0 when
    /// no tendon of the robot has friction (then mu cannot be fitted).
    pub friction: f64,
}

impl Parameters {
    /// The parameters of `robot` as it is: E of its geometry (NaN without one), the Euler
    /// angles of its base rotation ([`euler_xyz_from`]), its base position, offset scale 1,
    /// the friction coefficient of its first tendon with friction (0 without one).
    pub fn of(robot: &Robot) -> Self {
        Parameters {
            youngs_modulus: robot.rod.geometry.map_or(f64::NAN, |g| g.youngs_modulus),
            euler: euler_xyz_from(&robot.base_rotation),
            base_position: robot.base_position,
            offset_scale: 1.0,
            friction: robot
                .tendons
                .iter()
                .find_map(|t| t.active_friction())
                .map_or(0.0, |f| f.coefficient),
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
    /// tendon offset multiplied by `offset_scale`, and the first tendon with friction given
    /// the coefficient `friction`, the others theirs times the same factor (when it is > 0
    /// and finite; 0 leaves the robot's).
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
        let first = Parameters::of(robot).friction;
        if self.friction.is_finite() && self.friction > 0.0 && first > 0.0 {
            // Equal coefficients take the value itself (no rounding of a ratio).
            let factor = self.friction / first;
            for f in out.tendons.iter_mut().filter_map(|t| t.friction.as_mut()) {
                if f.coefficient == first {
                    f.coefficient = self.friction;
                } else if f.coefficient > 0.0 {
                    f.coefficient *= factor;
                }
            }
        }
        out
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
    /// The friction coefficient: the first tendon with friction's, the others' kept in
    /// proportion ([`Parameters::friction`]). Default false.
    pub friction: bool,
}

impl Default for Fit {
    /// The paper's set: E and the Euler angles.
    fn default() -> Self {
        Fit {
            youngs_modulus: true,
            euler: true,
            base_position: false,
            offset_scale: false,
            friction: false,
        }
    }
}

impl Fit {
    /// Every parameter of a frictionless robot: E, the Euler angles, the base position and
    /// the tendon offset scale (not the friction coefficient).
    pub fn all() -> Self {
        Fit {
            youngs_modulus: true,
            euler: true,
            base_position: true,
            offset_scale: true,
            friction: false,
        }
    }

    /// No parameter: the start of a selection, `Fit { friction: true, ..Fit::none() }`.
    pub fn none() -> Self {
        Fit {
            youngs_modulus: false,
            euler: false,
            base_position: false,
            offset_scale: false,
            friction: false,
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
            // A fixed mesh: every experiment and iteration solves the same discretization,
            // so the cost function is smooth in the parameters.
            collocation: collocation::Options {
                residual_tolerance: 1e-12,
                tolerance: None,
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

/// One fitted unknown and its scaling to order one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Unknown {
    /// E / E_start.
    YoungsModulus,
    /// Euler angle 0, 1, 2 (rad).
    Euler(usize),
    /// Base position component / L.
    BasePosition(usize),
    /// Offset scale.
    OffsetScale,
    /// mu / mu_start.
    Friction,
}

impl Unknown {
    fn name(&self) -> &'static str {
        match self {
            Unknown::YoungsModulus => "E",
            Unknown::Euler(i) => ["alpha", "beta", "gamma"][*i],
            Unknown::BasePosition(i) => ["x0", "y0", "z0"][*i],
            Unknown::OffsetScale => "offset_scale",
            Unknown::Friction => "mu",
        }
    }

    /// Physical units per scaled unit.
    pub(super) fn scale(&self, start: &Parameters, length: f64) -> f64 {
        match self {
            Unknown::YoungsModulus => start.youngs_modulus,
            Unknown::Euler(_) | Unknown::OffsetScale => 1.0,
            Unknown::BasePosition(_) => length,
            Unknown::Friction => start.friction,
        }
    }

    pub(super) fn get(&self, p: &Parameters) -> f64 {
        match self {
            Unknown::YoungsModulus => p.youngs_modulus,
            Unknown::Euler(i) => p.euler[*i],
            Unknown::BasePosition(i) => p.base_position[*i],
            Unknown::OffsetScale => p.offset_scale,
            Unknown::Friction => p.friction,
        }
    }

    pub(super) fn set(&self, p: &mut Parameters, value: f64) {
        match self {
            Unknown::YoungsModulus => p.youngs_modulus = value,
            Unknown::Euler(i) => p.euler[*i] = value,
            Unknown::BasePosition(i) => p.base_position[*i] = value,
            Unknown::OffsetScale => p.offset_scale = value,
            Unknown::Friction => p.friction = value,
        }
    }
}

pub(super) fn layout(fit: &Fit) -> Vec<Unknown> {
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
    if fit.friction {
        out.push(Unknown::Friction);
    }
    out
}

/// Checks the robot, experiments and options before any solve.
pub(super) fn validate(
    robot: &Robot,
    experiments: &[Measurement],
    options: &CalibrationOptions,
    start: &Parameters,
) -> Result<()> {
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
            "fit at least one of E, the Euler angles, the base position, the offset scale, the friction coefficient",
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
    if options.fit.friction && !crate::model::friction::any(robot) {
        return Err(invalid(
            "robot.tendons",
            "have no friction, so a friction coefficient cannot be fitted",
            "give the tendons whose friction to fit a start coefficient (robot file `friction = 0.1`), or do not fit mu",
        ));
    }
    let p = start;
    if options.fit.friction && !(p.friction.is_finite() && p.friction > 0.0) {
        return Err(invalid(
            "options.start.friction",
            format!("is {}", p.friction),
            "start the friction coefficient above 0 (e.g. 0.1): the fit moves it relative to its start",
        ));
    }
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
