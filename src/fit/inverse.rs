//! Inverse statics: tendon tensions, each within [0, tau_max], that put the tip at a target
//! position (and optionally orientation).
//!
//! # Problem
//!
//! With tau the tensions of the tendons that may change (`free_tendons`), the tip error is
//!
//! ```text
//! e(tau) = [ p_tip(tau) - p*                 ]   (m, world frame)
//!          [ w log(R_tip(tau) R*^T)          ]   (only with a target orientation; w in m/rad)
//! ```
//!
//! and the solver minimizes F = |e|^2 / 2 over the box 0 <= tau_i <= tau_max. The residual
//! |e| is a length: the orientation part is an angle times the weight w (default: the rod
//! length, so that a radian counts like a tip displacement of one rod length).
//!
//! # Method: bounded Levenberg-Marquardt
//!
//! Each iteration linearizes e at the current tensions with the tip sensitivities of
//! [`crate::collocation::sensitivity`] (d(tip position)/d tau and the world-frame rotation vector
//! d omega/d tau by the implicit function theorem on the converged collocation system; for
//! a slack tendon the one-sided, pulling derivative). The rotation rows are mapped by
//! J_l(e_R)^-1, the derivative of log(exp(hat(omega)) exp(hat(e_R))) in omega. The step d
//! minimizes the damped model
//!
//! ```text
//! |e + J d|^2 / 2 + mu |d|^2 / 2    subject to   0 <= tau + d <= tau_max
//! ```
//!
//! exactly, by a primal active-set method (the model is strictly convex for mu > 0 and has
//! as many unknowns as free tendons, a handful). Unlike projecting an unconstrained step onto
//! the box, this keeps a tendon at a bound only while the model wants it there, so the
//! iteration slides along the faces of the box.
//!
//! The trial tensions are solved forward, warm-started from the last accepted solution with
//! a [`collocation::Solver`] that keeps its Newton workspace. The gain ratio rho = (actual
//! decrease of F) / (decrease predicted by the undamped model |e + J d|^2 / 2) decides:
//! the step is accepted when rho > [`ACCEPT_RATIO`], and the damping mu then shrinks by
//! max(1/3, 1 - (2 rho - 1)^3); otherwise mu grows by a factor nu that doubles on each
//! consecutive rejection (Nielsen's update, H. B. Nielsen, "Damping parameter in Marquardt's
//! method", IMM-REP-1999-05; as in Madsen, Nielsen & Tingleff, "Methods for non-linear least
//! squares problems", 2004, algorithm 3.16). The first mu is [`INITIAL_DAMPING`] times the
//! largest diagonal entry of J^T J.
//!
//! # Termination ([`InverseTermination`])
//!
//! - `Reached`: |e| <= `tolerance`; the target is reachable.
//! - `Stationary`: the gradient J^T e projected onto the box vanishes (relative to
//!   |J_i| |e|, below [`GRADIENT_TOLERANCE`]): a (local) minimum of the tip error within
//!   the bounds, the closest the tendons can bring the tip.
//! - `Stalled`: the step is below [`STEP_TOLERANCE`] times `max_tension`, or it would
//!   lower |e| by less than [`PROGRESS_FRACTION`] times `tolerance` even by the linear
//!   model: at a minimum that the gradient test did not resolve (forward-solve noise
//!   dominates there), or after the damping grew through repeated rejections.
//! - `MaxIterations`: `max_iterations` trial steps were taken.
//!
//! Only `Reached` sets `reachable`. Every other outcome returns the best tensions found and
//! their residual; [`InverseSolution::explain`] says how far the tip stayed and which
//! tendons sit at their bounds. The minimum found is local: a target that needs the rod to
//! curl around (behind the base) may be reachable from other tensions.
//!
//! # Accuracy
//!
//! The forward solves stop at a scaled residual of 1e-11 by default, which leaves the tip
//! about 1e-8 m off the exact discrete solution; tolerances below about 1e-7 m need a
//! tighter `solver.residual_tolerance`. The tensions and tips are those of the collocation
//! discretization on `solver`'s mesh; use a fixed mesh (the default), as adaptive
//! refinement changes the mesh, and so the tip, discontinuously between iterates.
#![allow(non_snake_case)]

use crate::collocation::sensitivity::Sensitivity;
use crate::collocation::{self, Solver};
use crate::error::{Result, invalid};
use crate::model::robot::Robot;
use crate::so3;
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use std::fmt;

/// First damping mu relative to the largest diagonal entry of J^T J, 1e-3: the value
/// Madsen, Nielsen & Tingleff (2004, section 3.2) recommend when the start is not known to
/// be good; the first step is then nearly a Gauss-Newton step restricted to the box.
pub const INITIAL_DAMPING: f64 = 1e-3;

/// Smallest gain ratio that accepts a step, 1e-4 (Moré, "The Levenberg-Marquardt
/// algorithm: implementation and theory", 1978): any step that realizes a ten-thousandth of
/// the predicted decrease is taken.
pub const ACCEPT_RATIO: f64 = 1e-4;

/// Projected-gradient test, 1e-6: largest |projected (J^T e)_i| / (|J_i| |e|), the cosine
/// between the error and a free column of J. At cosine c, moving that tension alone can
/// lower |e| by only about c^2 |e| / 2 to first order (5e-13 |e|). Forward-solve rounding
/// puts a floor under it: on the prototype the iteration stalls at cosines of 5e-7 to 5e-6,
/// where the predicted decrease of F is 1e-11 of F, the size of the solve's noise.
pub const GRADIENT_TOLERANCE: f64 = 1e-6;

/// Step test, 1e-10 relative to `max_tension`: below it the tension change moves the tip by
/// less than the forward-solve noise (about 1e-8 m; tip sensitivities are at most a few
/// centimetres per newton on the prototype, so 1e-10 of a 5 N bound moves it 1e-11 m).
pub const STEP_TOLERANCE: f64 = 1e-10;

/// Progress test, 1e-3: the iteration stops when the step would lower the weighted tip
/// error |e| by less than this fraction of `tolerance` (1e-9 m at the default), even by
/// the linear model's prediction. Such a step cannot change the answer at the requested
/// precision, and near a minimum that is not the target it only chases the forward-solve
/// noise (measured on the prototype: the tail of an unreachable solve spends 5 to 8
/// rejected forward solves there without it).
pub const PROGRESS_FRACTION: f64 = 1e-3;

/// Largest deviation from orthonormality accepted for a target orientation, 1e-6: a
/// rotation matrix typed with seven digits passes; anything else is not a rotation.
pub const ROTATION_TOLERANCE: f64 = 1e-6;

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

/// Options of [`solve_tensions`]. `max_tension` has no meaningful default and must be set:
/// `InverseOptions { max_tension: 5.0, ..Default::default() }` or `InverseOptions::new(5.0)`.
#[derive(Clone, Debug, PartialEq)]
pub struct InverseOptions {
    /// Upper bound tau_max for every tendon that may change (N), > 0 and finite; the lower
    /// bound is 0 (a string cannot push). Default 0, which is rejected: set it.
    pub max_tension: f64,
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
    /// Indices (0-based) of the tendons whose tension may change; the others keep the
    /// robot's tension and are not bounded by `max_tension`. Default `None`: all tendons.
    pub free_tendons: Option<Vec<usize>>,
}

impl Default for InverseOptions {
    fn default() -> Self {
        InverseOptions {
            max_tension: 0.0,
            tolerance: 1e-6,
            max_iterations: 50,
            orientation_weight: None,
            solver: collocation::Options::default(),
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
}

/// Why [`solve_tensions`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InverseTermination {
    /// The weighted tip error is at or below the tolerance.
    Reached,
    /// The gradient of the tip error, projected onto the tension bounds, vanishes.
    Stationary,
    /// The damped step became negligible, or would lower the tip error by less than
    /// [`PROGRESS_FRACTION`] of the tolerance.
    Stalled,
    /// The iteration limit was reached first.
    MaxIterations,
}

impl fmt::Display for InverseTermination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InverseTermination::Reached => "reached: the weighted tip error is within the tolerance",
            InverseTermination::Stationary => {
                "stationary: no tension change within the bounds reduces the tip error to first order"
            }
            InverseTermination::Stalled => {
                "stalled: no step within the bounds promises to reduce the tip error by a meaningful amount"
            }
            InverseTermination::MaxIterations => {
                "stopped at the iteration limit before the tip error reached tolerance"
            }
        })
    }
}

/// Where a tendon's tension ended up relative to its bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// Strictly between 0 and `max_tension`.
    Inside,
    /// At the lower bound 0: slack.
    Slack,
    /// At the upper bound `max_tension`.
    Saturated,
    /// Not free to change (not in `free_tendons`): the robot's tension.
    Held,
}

/// The result of [`solve_tensions`]: the best tensions found, their solved shape, and how
/// close the tip came.
#[derive(Clone, Debug)]
pub struct InverseSolution {
    /// Tension of every tendon (N), in the robot's order (held tendons keep theirs).
    pub tensions: Vec<f64>,
    /// The forward solution at these tensions.
    pub solution: Solution,
    /// Weighted tip error |e| (m): position error and, with a target orientation, the
    /// rotation angle times the orientation weight.
    pub residual: f64,
    /// Tip position error |p_tip - p*| (m).
    pub position_error: f64,
    /// Tip rotation error, the angle of R_tip R*^T (rad), when the target has an orientation.
    pub orientation_error: Option<f64>,
    /// Whether the residual is within the tolerance (only for [`InverseTermination::Reached`]).
    pub reachable: bool,
    /// Why the iteration stopped.
    pub termination: InverseTermination,
    /// Where each tendon's tension sits relative to [0, `max_tension`].
    pub bounds: Vec<Bound>,
    /// Trial steps taken (accepted and rejected).
    pub iterations: usize,
    /// Forward collocation solves (the start plus one per trial step).
    pub forward_solves: usize,
    /// Sensitivity evaluations (the start plus one per accepted step, when needed).
    pub jacobians: usize,
    /// Residual (m) at the start and after each accepted step.
    pub history: Vec<f64>,
    /// The tolerance the residual was tested against (m).
    pub tolerance: f64,
    /// The upper tension bound (N).
    pub max_tension: f64,
    /// The target.
    pub target: Target,
}

impl InverseSolution {
    /// Achieved tip position (m), world frame.
    pub fn tip_position(&self) -> Vector3<f64> {
        self.solution.tip_position()
    }

    /// A few sentences for a person: whether the target was reached, how far the tip
    /// stayed, why the iteration stopped, and which tendons sit at their bounds.
    pub fn explain(&self) -> String {
        let mut text = if self.reachable {
            format!(
                "target reached: weighted tip error {:.3e} m <= tolerance {:.1e} m after {} iterations",
                self.residual, self.tolerance, self.iterations
            )
        } else {
            let mut t = format!(
                "target unreachable with tensions in [0, {} N]: the closest tip found is {:.6} m from the target \
                 position (weighted tip error {:.6} m > tolerance {:.1e} m)",
                self.max_tension, self.position_error, self.residual, self.tolerance
            );
            if self.termination == InverseTermination::MaxIterations {
                t.push_str(&format!(
                    "; not settled after {} iterations, so more iterations may still reach it",
                    self.iterations
                ));
            }
            t
        };
        if let Some(angle) = self.orientation_error {
            text.push_str(&format!("; orientation error {:.4} deg", angle.to_degrees()));
        }
        if !self.reachable {
            text.push_str(&format!("; {}", self.termination));
        }
        let list = |b: Bound| {
            let items: Vec<String> = (0..self.bounds.len())
                .filter(|&i| self.bounds[i] == b)
                .map(|i| format!("tendons[{i}]"))
                .collect();
            items.join(", ")
        };
        let saturated = list(Bound::Saturated);
        if !saturated.is_empty() {
            text.push_str(&format!("; at the upper bound {} N: {saturated}", self.max_tension));
        }
        let slack = list(Bound::Slack);
        if !slack.is_empty() {
            text.push_str(&format!("; slack (0 N): {slack}"));
        }
        if !self.reachable {
            // A tip cannot get farther from the base than the rod is long (tendons only
            // compress it), so this distance bounds the position error from below.
            let distance = (self.target.position - self.solution.base().p).norm();
            let length = self.solution.length();
            if distance > length {
                text.push_str(&format!(
                    "; the target is {distance:.6} m from the base, farther than the rod length {length} m, \
                     so no tensions reach it (the position error is at least about {:.6} m)",
                    distance - length
                ));
            }
        }
        text
    }
}

/// Tensions within [0, `max_tension`] that bring the tip of `robot` to `target`, by bounded
/// Levenberg-Marquardt on the tip sensitivities (module docs).
///
/// Starts from the robot's tensions (free ones clamped into the bounds). A target that
/// cannot be reached is not an error: the result has `reachable: false`, the best tensions
/// and their residual, and [`InverseSolution::explain`] says why.
///
/// # Errors
/// [`crate::Error::InvalidInput`] naming the field for a non-finite target position
/// (`target.position`), a target orientation that is not a rotation
/// (`target.orientation`), `options.max_tension` not positive and finite,
/// `options.tolerance` not positive and finite, `options.max_iterations` zero,
/// `options.orientation_weight` not positive and finite,
/// `options.solver.residual_tolerance` above [`crate::collocation::sensitivity::RESIDUAL_LIMIT`] (the
/// sensitivities need converged solves), an index out of range or repeated
/// in `options.free_tendons[i]`, an empty `options.free_tendons`, or a robot without
/// tendons (`robot.tendons`); an invalid robot; any error of a forward solve
/// ([`crate::Error::NotConverged`], ...) or of the sensitivities, propagated.
///
/// # Examples
/// ```
/// use tdcr::fit::inverse::{InverseOptions, Target, solve_tensions};
/// let mut robot = tdcr::cases::prototype();
/// robot.tendons[1].tension = 1.5;
/// let options = InverseOptions::new(5.0);
/// let goal = tdcr::collocation::solve(&robot, &options.solver).unwrap().tip_position();
/// robot.tendons[1].tension = 0.0;
/// let found = solve_tensions(&robot, &Target::position(goal), &options).unwrap();
/// assert!(found.reachable);
/// assert!((found.tip_position() - goal).norm() <= options.tolerance);
/// ```
pub fn solve_tensions(robot: &Robot, target: &Target, options: &InverseOptions) -> Result<InverseSolution> {
    robot.validate()?;
    let free = validate(robot, target, options)?;
    let max = options.max_tension;
    let weight = options.orientation_weight.unwrap_or_else(|| robot.length());
    let mut current = robot.clone();
    for &i in &free {
        let t = &mut current.tendons[i].tension;
        *t = t.clamp(0.0, max);
    }
    let mut solver = Solver::new(options.solver.clone());
    let mut solution = solver.solve(&current)?;
    let (mut forward_solves, mut jacobians, mut iterations) = (1, 0, 0);
    let mut e = tip_error(&solution, target, weight);
    let mut history = vec![e.norm()];
    // Damping mu (set from the first Jacobian) and its growth factor nu on rejection.
    let mut damping: Option<f64> = None;
    let mut growth = 2.0;
    let mut jacobian: Option<DMatrix<f64>> = None;
    let termination = loop {
        if e.norm() <= options.tolerance {
            break InverseTermination::Reached;
        }
        let J = match jacobian.take() {
            Some(J) => J,
            None => {
                jacobians += 1;
                error_jacobian(&current, &solution, weight, &e, &free)?
            }
        };
        let tau = DVector::from_iterator(free.len(), free.iter().map(|&i| current.tendons[i].tension));
        let g = J.transpose() * &e;
        if stationary(&J, &g, &e, &tau, max) {
            break InverseTermination::Stationary;
        }
        if iterations >= options.max_iterations {
            break InverseTermination::MaxIterations;
        }
        let JtJ = J.transpose() * &J;
        let largest = JtJ.diagonal().amax();
        if largest <= 0.0 {
            // No free tendon moves the tip at all (caught by `stationary` unless rounding).
            break InverseTermination::Stationary;
        }
        let mu = *damping.get_or_insert(INITIAL_DAMPING * largest);
        let mut H = JtJ;
        for i in 0..free.len() {
            H[(i, i)] += mu;
        }
        let lower = -&tau;
        let upper = tau.map(|t| max - t);
        let d = box_qp(&H, &g, &lower, &upper);
        if d.amax() <= STEP_TOLERANCE * max {
            break InverseTermination::Stalled;
        }
        // Decrease of F predicted by the undamped linear model: positive for the minimizer
        // of the damped model whenever d != 0.
        let model = (&e + &J * &d).norm();
        let predicted = 0.5 * (e.norm_squared() - model * model);
        if predicted.is_nan() || predicted <= 0.0 || e.norm() - model < PROGRESS_FRACTION * options.tolerance {
            break InverseTermination::Stalled;
        }
        let mut trial = current.clone();
        for (k, &i) in free.iter().enumerate() {
            trial.tendons[i].tension = (tau[k] + d[k]).clamp(0.0, max);
        }
        iterations += 1;
        forward_solves += 1;
        let trial_solution = solver.solve_from(&trial, &solution)?;
        let e_trial = tip_error(&trial_solution, target, weight);
        let rho = 0.5 * (e.norm_squared() - e_trial.norm_squared()) / predicted;
        if rho > ACCEPT_RATIO {
            current = trial;
            solution = trial_solution;
            e = e_trial;
            history.push(e.norm());
            let shrink = 1.0 - (2.0 * rho - 1.0).powi(3);
            damping = Some(mu * shrink.max(1.0 / 3.0));
            growth = 2.0;
        } else {
            damping = Some(mu * growth);
            growth *= 2.0;
            jacobian = Some(J);
        }
    };
    let tensions: Vec<f64> = current.tendons.iter().map(|t| t.tension).collect();
    let bounds = (0..tensions.len())
        .map(|i| {
            if !free.contains(&i) {
                Bound::Held
            } else if tensions[i] <= 0.0 {
                Bound::Slack
            } else if tensions[i] >= max {
                Bound::Saturated
            } else {
                Bound::Inside
            }
        })
        .collect();
    let tip = solution.tip();
    Ok(InverseSolution {
        tensions,
        residual: e.norm(),
        position_error: (tip.p - target.position).norm(),
        orientation_error: target.orientation.map(|R| so3::log(&(tip.R * R.transpose())).norm()),
        reachable: termination == InverseTermination::Reached,
        termination,
        bounds,
        iterations,
        forward_solves,
        jacobians,
        history,
        tolerance: options.tolerance,
        max_tension: max,
        target: target.clone(),
        solution,
    })
}

/// Checks the target and options; returns the free tendon indices.
fn validate(robot: &Robot, target: &Target, options: &InverseOptions) -> Result<Vec<usize>> {
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
    let max = options.max_tension;
    if !(max.is_finite() && max > 0.0) {
        return Err(invalid(
            "options.max_tension",
            format!("is {max} N"),
            "set the upper tension bound to a positive, finite value in N (it has no default)",
        ));
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
    Ok(free)
}

/// The tip error e (module docs): 3 rows, or 6 with a target orientation.
fn tip_error(solution: &Solution, target: &Target, weight: f64) -> DVector<f64> {
    let tip = solution.tip();
    let dp = tip.p - target.position;
    match target.orientation {
        None => DVector::from_column_slice(dp.as_slice()),
        Some(R) => {
            let w = so3::log(&(tip.R * R.transpose())) * weight;
            DVector::from_column_slice(&[dp.x, dp.y, dp.z, w.x, w.y, w.z])
        }
    }
}

/// de/d tau for the free tendons: one column per free tendon, rows as [`tip_error`]. The
/// rotation rows map the world-frame rotation vector omega (R -> exp(hat(omega)) R) through
/// d log(exp(hat(omega)) exp(hat(e_R))) / d omega = J_l(e_R)^-1 = J_r(-e_R)^-1.
fn error_jacobian(
    robot: &Robot,
    solution: &Solution,
    weight: f64,
    e: &DVector<f64>,
    free: &[usize],
) -> Result<DMatrix<f64>> {
    let mut sens = Sensitivity::new(robot, solution)?;
    let rows = e.len();
    let map = (rows == 6).then(|| {
        let e_R = Vector3::new(e[3], e[4], e[5]) / weight;
        so3::right_jacobian_inv(&(-e_R)) * weight
    });
    let mut J = DMatrix::zeros(rows, free.len());
    for (k, &i) in free.iter().enumerate() {
        let d = sens.tension(i)?;
        let tip = &d[d.len() - 1];
        for r in 0..3 {
            J[(r, k)] = tip.p[r];
        }
        if let Some(m) = map {
            let w = m * tip.rotation;
            for r in 0..3 {
                J[(3 + r, k)] = w[r];
            }
        }
    }
    Ok(J)
}

/// Whether the gradient g = J^T e, projected onto the box [0, max], vanishes relative to
/// |J_i| |e| (the cosine between e and each free column) for every free tendon.
fn stationary(J: &DMatrix<f64>, g: &DVector<f64>, e: &DVector<f64>, tau: &DVector<f64>, max: f64) -> bool {
    let norm_e = e.norm();
    (0..g.len()).all(|i| {
        // Moving tension i by -g_i decreases F; a bound blocks that direction.
        let blocked = (tau[i] <= 0.0 && g[i] >= 0.0) || (tau[i] >= max && g[i] <= 0.0);
        let scale = J.column(i).norm() * norm_e;
        blocked || scale == 0.0 || g[i].abs() <= GRADIENT_TOLERANCE * scale
    })
}

/// Minimizer of d^T H d / 2 + g^T d over lower <= d <= upper (lower <= 0 <= upper), for
/// symmetric positive definite H, by the primal active-set method (Nocedal & Wright,
/// "Numerical Optimization", algorithm 16.3, specialized to bounds): from the feasible
/// d = 0, minimize over the free variables; if that leaves the box, step to the first bound
/// and fix that variable there; otherwise release the fixed variable whose multiplier has
/// the wrong sign, or stop. Each pass solves a Cholesky system of at most n unknowns; the
/// objective decreases strictly, so no working set repeats.
fn box_qp(H: &DMatrix<f64>, g: &DVector<f64>, lower: &DVector<f64>, upper: &DVector<f64>) -> DVector<f64> {
    #[derive(Clone, Copy, PartialEq)]
    enum Set {
        Free,
        Lower,
        Upper,
    }
    let n = g.len();
    let mut d = DVector::zeros(n);
    let mut set = vec![Set::Free; n];
    // A working set is never repeated, and each pass adds or releases one bound; 10 (n + 1)
    // passes is far beyond what a handful of tendons needs (a guard, not a tuning knob).
    for _ in 0..10 * (n + 1) {
        let free: Vec<usize> = (0..n).filter(|&i| set[i] == Set::Free).collect();
        if !free.is_empty() {
            // Minimize over the free variables with the fixed ones at their bounds:
            // H_FF x_F = -(g_F + H_FB d_B).
            let m = free.len();
            let mut A = DMatrix::zeros(m, m);
            let mut b = DVector::zeros(m);
            for (a, &i) in free.iter().enumerate() {
                for (c, &j) in free.iter().enumerate() {
                    A[(a, c)] = H[(i, j)];
                }
                b[a] = -g[i]
                    - (0..n)
                        .filter(|&j| set[j] != Set::Free)
                        .map(|j| H[(i, j)] * d[j])
                        .sum::<f64>();
            }
            let Some(chol) = A.cholesky() else {
                return d;
            };
            let x = chol.solve(&b);
            // Longest fraction alpha of the way to x that stays in the box.
            let mut alpha = 1.0;
            let mut block = None;
            for (a, &i) in free.iter().enumerate() {
                let step = x[a] - d[i];
                if x[a] < lower[i] && step < 0.0 {
                    let t = (lower[i] - d[i]) / step;
                    if t < alpha {
                        alpha = t;
                        block = Some((i, Set::Lower));
                    }
                } else if x[a] > upper[i] && step > 0.0 {
                    let t = (upper[i] - d[i]) / step;
                    if t < alpha {
                        alpha = t;
                        block = Some((i, Set::Upper));
                    }
                }
            }
            for (a, &i) in free.iter().enumerate() {
                d[i] += alpha.max(0.0) * (x[a] - d[i]);
                d[i] = d[i].clamp(lower[i], upper[i]);
            }
            if let Some((i, side)) = block {
                d[i] = if side == Set::Lower { lower[i] } else { upper[i] };
                set[i] = side;
                continue;
            }
        }
        // At the minimizer over the current free set: a fixed variable whose gradient
        // points into the box would decrease the objective if released.
        let gradient = H * &d + g;
        let mut release = None;
        let mut worst = 0.0;
        for i in 0..n {
            let push = match set[i] {
                Set::Free => 0.0,
                Set::Lower => -gradient[i],
                Set::Upper => gradient[i],
            };
            if push > worst {
                worst = push;
                release = Some(i);
            }
        }
        match release {
            Some(i) => set[i] = Set::Free,
            None => return d,
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over a fine grid of a 2-D box: the active-set minimizer is no worse.
    #[test]
    fn box_qp_matches_grid_search() {
        let H = DMatrix::from_row_slice(2, 2, &[2.0, 0.9, 0.9, 1.0]);
        let q = |d: &DVector<f64>, g: &DVector<f64>| 0.5 * d.dot(&(&H * d)) + g.dot(d);
        for g in [[3.0, -1.0], [-4.0, -4.0], [0.1, 0.2], [-0.5, 2.0], [5.0, 5.0]] {
            let g = DVector::from_row_slice(&g);
            let (lo, hi) = (
                DVector::from_row_slice(&[-1.0, 0.0]),
                DVector::from_row_slice(&[0.5, 1.5]),
            );
            let d = box_qp(&H, &g, &lo, &hi);
            let mut best = f64::INFINITY;
            for a in 0..=300 {
                for b in 0..=300 {
                    let x = DVector::from_row_slice(&[-1.0 + 1.5 * a as f64 / 300.0, 1.5 * b as f64 / 300.0]);
                    best = best.min(q(&x, &g));
                }
            }
            assert!((0..2).all(|i| d[i] >= lo[i] && d[i] <= hi[i]));
            // The grid spacing 5e-3 leaves the grid minimum up to about 1e-4 above the true one.
            assert!(q(&d, &g) <= best + 1e-12, "g = {g:?}: {} vs grid {best}", q(&d, &g));
            // KKT: the gradient vanishes in free coordinates and points out of the box at
            // active bounds (1e-12: rounding of a 2 x 2 Cholesky solve with O(1) entries).
            let gradient = &H * &d + &g;
            for i in 0..2 {
                let ok = if d[i] == lo[i] {
                    gradient[i] >= -1e-12
                } else if d[i] == hi[i] {
                    gradient[i] <= 1e-12
                } else {
                    gradient[i].abs() <= 1e-12
                };
                assert!(ok, "g = {g:?}: d = {d:?}, gradient = {gradient:?}");
            }
        }
    }
}
