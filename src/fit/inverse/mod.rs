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
//! a [`crate::collocation::Solver`] that keeps its Newton workspace. The gain ratio rho = (actual
//! decrease of F) / (decrease predicted by the undamped model |e + J d|^2 / 2) decides:
//! the step is accepted when rho > [`ACCEPT_RATIO`], and the damping mu then shrinks by
//! max(1/3, 1 - (2 rho - 1)^3); otherwise mu grows by a factor nu that doubles on each
//! consecutive rejection (Nielsen's update, H. B. Nielsen, "Damping parameter in Marquardt's
//! method", IMM-REP-1999-05; as in Madsen, Nielsen & Tingleff, "Methods for non-linear least
//! squares problems", 2004, algorithm 3.16; shared with calibration in [`crate::fit::lm`]). The first mu is [`INITIAL_DAMPING`] times the
//! largest diagonal entry of J^T J.
//!
//! # Termination ([`FitTermination`])
//!
//! - `Reached`: |e| <= `tolerance`; the target is reachable.
//! - `Stationary`: the gradient J^T e projected onto the box vanishes (relative to
//!   |J_i| |e|, below [`GRADIENT_TOLERANCE`]): a (local) minimum of the tip error within
//!   the bounds, the closest the tendons can bring the tip.
//! - `NoProgress`: the step is below [`STEP_TOLERANCE`] times `max_tension`, or it would
//!   lower |e| by less than [`PROGRESS_FRACTION`] times `tolerance` even by the linear
//!   model: at a minimum that the gradient test did not resolve (forward-solve noise
//!   dominates there), or after the damping grew through repeated rejections.
//! - `MaxIterations`: `max_iterations` trial steps were taken.
//!
//! # Redundant tendons
//!
//! With more free tendons than target coordinates (four straight tendons for a tip
//! position), many tensions put the tip at the target. The iteration returns the one it
//! reaches from the starting tensions: each damped step minimizes |e + J d|^2 + mu |d|^2,
//! whose minimizer has no component in the null space of J (tension changes the
//! linearized tip does not see, such as pulling opposing tendons together) unless a bound
//! is active. The result keeps the start's share of such co-contraction: for a linear tip
//! map without active bounds it is exactly the solution nearest the start, and on the
//! prototype its change from the start is within a few per cent of orthogonal to the null
//! space (tests/inverse_redundant.rs). It is not the least-norm tension; start from low
//! tensions to get low ones.
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

mod problem;
mod qp;

pub use problem::{InverseOptions, Target};

use super::lm::{Damping, FitIteration, FitTermination, accepts, gain_ratio};
use crate::collocation::Solver;
use crate::collocation::sensitivity::Sensitivity;
use crate::error::Result;
use crate::model::robot::Robot;
use crate::so3;
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector, Vector3};
use problem::validate;
use qp::box_qp;

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
    /// Whether the residual is within the tolerance (only for [`FitTermination::Reached`]).
    pub reachable: bool,
    /// Why the iteration stopped.
    pub termination: FitTermination,
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
    /// Every trial step: cost F = |e|^2 / 2 (m^2), largest tension change (N), damping mu,
    /// gain ratio, whether accepted.
    pub trials: Vec<FitIteration>,
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
    /// stayed, why the iteration stopped, which tendons sit at their bounds (numbered from
    /// 1, as on the command line), and, with more free tendons than target coordinates, which
    /// of the many solutions this is (the one reached from the starting tensions, close to
    /// the nearest to them; not the least-norm one).
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
            if self.termination == FitTermination::MaxIterations {
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
                // 1-based, as the command line and robot files number tendons.
                .map(|i| format!("tendon {}", i + 1))
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
        let free = self.bounds.iter().filter(|&&b| b != Bound::Held).count();
        let coordinates = if self.target.orientation.is_some() { 6 } else { 3 };
        if free > coordinates {
            // What the iteration does (module docs): damped least-squares steps from the
            // starting tensions, each without a component in the null space of the tip
            // Jacobian at its iterate.
            text.push_str(&format!(
                "; {free} free tendons for {coordinates} target coordinates, so many tensions give this tip: \
                 these are the ones reached from the starting tensions, each step the smallest tension change \
                 that makes its progress (no component along changes the tip does not see, such as pulling \
                 opposing tendons together), so they keep the start's co-contraction: close to the solution \
                 nearest the start, not the least-norm tensions (start from lower tensions for lower ones)"
            ));
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
    let mut damping: Option<Damping> = None;
    let mut trials = Vec::new();
    let mut jacobian: Option<DMatrix<f64>> = None;
    let termination = loop {
        if e.norm() <= options.tolerance {
            break FitTermination::Reached;
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
            break FitTermination::Stationary;
        }
        if iterations >= options.max_iterations {
            break FitTermination::MaxIterations;
        }
        let JtJ = J.transpose() * &J;
        let largest = JtJ.diagonal().amax();
        if largest <= 0.0 {
            // No free tendon moves the tip at all (caught by `stationary` unless rounding).
            break FitTermination::Stationary;
        }
        let damping = damping.get_or_insert_with(|| Damping::new(INITIAL_DAMPING * largest));
        let mu = damping.value();
        let mut H = JtJ;
        for i in 0..free.len() {
            H[(i, i)] += mu;
        }
        let lower = -&tau;
        let upper = tau.map(|t| max - t);
        let d = box_qp(&H, &g, &lower, &upper);
        if d.amax() <= STEP_TOLERANCE * max {
            break FitTermination::NoProgress;
        }
        // Decrease of F predicted by the undamped linear model: positive for the minimizer
        // of the damped model whenever d != 0.
        let model = (&e + &J * &d).norm();
        let predicted = 0.5 * (e.norm_squared() - model * model);
        if predicted.is_nan() || predicted <= 0.0 || e.norm() - model < PROGRESS_FRACTION * options.tolerance {
            break FitTermination::NoProgress;
        }
        let mut trial = current.clone();
        for (k, &i) in free.iter().enumerate() {
            trial.tendons[i].tension = (tau[k] + d[k]).clamp(0.0, max);
        }
        iterations += 1;
        forward_solves += 1;
        let trial_solution = solver.solve_from(&trial, &solution)?;
        let e_trial = tip_error(&trial_solution, target, weight);
        let cost = 0.5 * e.norm_squared();
        let trial_cost = 0.5 * e_trial.norm_squared();
        let rho = gain_ratio(cost, trial_cost, predicted);
        let accepted = accepts(rho, predicted, ACCEPT_RATIO);
        trials.push(damping.update(accepted, rho, d.amax(), cost, trial_cost));
        if accepted {
            current = trial;
            solution = trial_solution;
            e = e_trial;
            history.push(e.norm());
        } else {
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
        reachable: termination == FitTermination::Reached,
        termination,
        bounds,
        iterations,
        forward_solves,
        jacobians,
        history,
        trials,
        tolerance: options.tolerance,
        max_tension: max,
        target: target.clone(),
        solution,
    })
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
