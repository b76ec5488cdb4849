//! The data of an inverse-statics problem: the target and the options, and the checks on
//! them before any solve.
#![allow(non_snake_case)]

use super::ROTATION_TOLERANCE;
use crate::collocation;
use crate::error::{Result, invalid};
use crate::model::length;
use crate::model::robot::Robot;
use crate::so3;
use nalgebra::{Matrix3, Vector3};

/// Where the tip should go.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// Tip position p* (m), world frame.
    pub position: Vector3<f64>,
    /// Tip orientation R* (body to world), or `None` for a position-only target. Its error
    /// log(R_tip R*^T) (rad) is weighted by [`InverseOptions::orientation_weight`].
    pub orientation: Option<Matrix3<f64>>,
}

impl Target {
    /// A position-only target (m, world frame).
    pub fn position(position: Vector3<f64>) -> Self {
        Target {
            position,
            orientation: None,
        }
    }

    /// A full-pose target: position (m, world frame) and orientation (body to world).
    pub fn pose(position: Vector3<f64>, orientation: Matrix3<f64>) -> Self {
        Target {
            position,
            orientation: Some(orientation),
        }
    }
}

/// Options of [`super::solve_tensions`] and [`super::solve_displacements`]. The bounds of the
/// adjusted inputs have no meaningful default and must be set: `InverseOptions::new(5.0)`
/// (tensions in [0, 5 N]) or `InverseOptions::displacements(0.0, 0.01)` (pull-ins in
/// [0, 10 mm]), or `InverseOptions { max_tension: 5.0, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseOptions {
    /// [`super::solve_tensions`]: upper bound tau_max for every tendon that may change (N),
    /// positive and finite; the lower bound is 0 (a string cannot push). Default 0, which
    /// is rejected: set it. [`super::solve_displacements`]: an optional tension limit (N)
    /// below the one it always applies, [`super::GEOMETRIC_SHARE`] of each tendon's
    /// geometric limit EI / r^2 (past which no equilibrium exists); 0 for none.
    pub max_tension: f64,
    /// [`super::solve_displacements`]: lower bound of every adjusted pull-in (m), finite; a
    /// negative value lets the actuator pay out tendon past its reference. Default 0.
    pub min_displacement: f64,
    /// [`super::solve_displacements`]: upper bound of every adjusted pull-in (m), the
    /// actuator's stroke, finite and above `min_displacement` (and, for an inextensible
    /// tendon, below its reference length). Default 0, which is rejected: set it.
    pub max_displacement: f64,
    /// Weighted tip error |e| at or below which the target counts as reached (m). Default
    /// 1e-6.
    pub tolerance: f64,
    /// Trial steps (each one forward solve) before giving up. Default 50.
    pub max_iterations: usize,
    /// Weight w of the orientation error (m/rad), > 0: a radian of tip rotation counts as w
    /// metres of tip displacement. Default `None`: the rod length.
    pub orientation_weight: Option<f64>,
    /// Options of every forward collocation solve. Default: [`collocation::Options`]'s
    /// default (32 intervals, fixed mesh).
    pub solver: collocation::Options,
    /// Indices (0-based) of the tendons whose input may change; the others keep the robot's
    /// input (tension or pull-in) and are not bounded. Default `None`: all tendons.
    pub free_tendons: Option<Vec<usize>>,
}

impl Default for InverseOptions {
    fn default() -> Self {
        InverseOptions {
            max_tension: 0.0,
            min_displacement: 0.0,
            max_displacement: 0.0,
            tolerance: 1e-6,
            max_iterations: 50,
            orientation_weight: None,
            // A fixed mesh: every iteration solves the same discretization, so the tip
            // error is smooth in the tensions.
            solver: collocation::Options::fixed(collocation::Options::default().intervals),
            free_tendons: None,
        }
    }
}

impl InverseOptions {
    /// Default options with the upper tension bound `max_tension` (N).
    pub fn new(max_tension: f64) -> Self {
        InverseOptions {
            max_tension,
            ..Default::default()
        }
    }

    /// Default options with the pull-in bounds `min_displacement`..`max_displacement` (m)
    /// for [`super::solve_displacements`].
    pub fn displacements(min_displacement: f64, max_displacement: f64) -> Self {
        InverseOptions {
            min_displacement,
            max_displacement,
            ..Default::default()
        }
    }
}

/// The inputs inverse statics adjusts, with their bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Adjusted {
    /// Tensions in [0, `max`] (N).
    Tensions {
        /// Upper bound (N).
        max: f64,
    },
    /// Actuator pull-ins in [`min`, `max`] (m).
    Displacements {
        /// Lower bound (m).
        min: f64,
        /// Upper bound (m).
        max: f64,
    },
}

impl Adjusted {
    /// The lower and upper bounds of every adjusted input (N or m).
    pub fn range(&self) -> (f64, f64) {
        match *self {
            Adjusted::Tensions { max } => (0.0, max),
            Adjusted::Displacements { min, max } => (min, max),
        }
    }
}

/// Checks the target and options for adjusting `adjusted`; returns the free tendon indices.
pub(super) fn validate(
    robot: &Robot,
    target: &Target,
    options: &InverseOptions,
    adjusted: Adjusted,
) -> Result<Vec<usize>> {
    let p = target.position;
    if p.iter().any(|x| !x.is_finite()) {
        return Err(invalid(
            "target.position",
            format!("is ({}, {}, {}) m", p.x, p.y, p.z),
            "give a finite tip position in m, world frame",
        ));
    }
    if let Some(R) = target.orientation {
        let error = if R.iter().all(|x| x.is_finite()) {
            so3::orthonormality_error(&R)
        } else {
            f64::INFINITY
        };
        if !(error <= ROTATION_TOLERANCE && R.determinant() > 0.0) {
            return Err(invalid(
                "target.orientation",
                format!(
                    "is not a rotation (orthonormality error {error:.3e}, determinant {:.6})",
                    R.determinant()
                ),
                "give a proper rotation matrix, body to world, or None for a position-only target",
            ));
        }
    }
    match adjusted {
        Adjusted::Tensions { max } => {
            if !(max.is_finite() && max > 0.0) {
                return Err(invalid(
                    "options.max_tension",
                    format!("is {max} N"),
                    "set the upper tension bound to a positive, finite value in N (it has no default)",
                ));
            }
        }
        Adjusted::Displacements { min, max } => {
            let limit = options.max_tension;
            if !(limit.is_finite() && limit >= 0.0) {
                return Err(invalid(
                    "options.max_tension",
                    format!("is {limit} N"),
                    "give a positive tension limit in N, or 0 for the geometric limits alone",
                ));
            }
            if !max.is_finite() {
                return Err(invalid(
                    "options.max_displacement",
                    format!("is {max} m"),
                    "set the actuator's stroke: a finite upper pull-in bound in m (it has no default)",
                ));
            }
            if !min.is_finite() {
                return Err(invalid(
                    "options.min_displacement",
                    format!("is {min} m"),
                    "give a finite lower pull-in bound in m",
                ));
            }
            if max <= min {
                return Err(invalid(
                    "options.max_displacement",
                    // + 0.0: -0 prints as 0
                    format!("is {max} m, not above min_displacement {} m", min + 0.0),
                    "set the actuator's stroke: a finite upper pull-in bound in m above min_displacement \
                     (it has no default)",
                ));
            }
        }
    }
    let tol = options.tolerance;
    if !(tol.is_finite() && tol > 0.0) {
        return Err(invalid(
            "options.tolerance",
            format!("is {tol} m"),
            "give a positive tip tolerance in m (default 1e-6)",
        ));
    }
    if options.max_iterations == 0 {
        return Err(invalid(
            "options.max_iterations",
            "is 0",
            "allow at least one step (default 50)",
        ));
    }
    if let Some(w) = options.orientation_weight
        && !(w.is_finite() && w > 0.0)
    {
        return Err(invalid(
            "options.orientation_weight",
            format!("is {w} m/rad"),
            "give a positive weight in m/rad, or None for the rod length",
        ));
    }
    let limit = crate::collocation::sensitivity::RESIDUAL_LIMIT;
    if options.solver.residual_tolerance > limit {
        return Err(invalid(
            "options.solver.residual_tolerance",
            format!(
                "is {:e}, above the {limit:e} the sensitivities need",
                options.solver.residual_tolerance
            ),
            "keep the collocation default 1e-11",
        ));
    }
    let k = robot.tendons.len();
    if k == 0 {
        return Err(invalid(
            "robot.tendons",
            "is empty",
            "inverse statics needs at least one tendon to adjust",
        ));
    }
    let free = match &options.free_tendons {
        None => (0..k).collect(),
        Some(list) => {
            if list.is_empty() {
                return Err(invalid(
                    "options.free_tendons",
                    "lists no tendon",
                    "give at least one tendon index, or None for all tendons",
                ));
            }
            for (j, &i) in list.iter().enumerate() {
                if i >= k {
                    return Err(invalid(
                        format!("options.free_tendons[{j}]"),
                        format!("is {i}, but the robot has {k} tendons"),
                        format!("give 0-based tendon indices below {k}"),
                    ));
                }
                if list[..j].contains(&i) {
                    return Err(invalid(
                        format!("options.free_tendons[{j}]"),
                        format!("repeats tendon {i}"),
                        "list each tendon once",
                    ));
                }
            }
            list.clone()
        }
    };
    if let Adjusted::Displacements { max, .. } = adjusted {
        for &i in &free {
            let t = &robot.tendons[i];
            let path = length::reference_length(robot, i);
            // No shape takes up an inextensible tendon's whole path (docs/actuation.md).
            if t.stiffness.is_none() && max >= path {
                return Err(invalid(
                    "options.max_displacement",
                    format!(
                        "is {max} m, but tendon {} (inextensible) runs {path:.6} m along the backbone",
                        i + 1
                    ),
                    "give a stroke below the tendon's path length, or make the tendon elastic",
                ));
            }
        }
    }
    Ok(free)
}
