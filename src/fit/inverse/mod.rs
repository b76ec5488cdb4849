//! Inverse statics: tendon tensions, each within [0, tau_max] ([`solve_tensions`]), or
//! actuator pull-ins, each within [q_min, q_max] ([`solve_displacements`]), that put the tip
//! at a target position (and optionally orientation).
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
//! and the solver minimizes F = |e|^2 / 2 over the box 0 <= tau_i <= tau_max (for pull-ins,
//! e(q) over q_min <= q_i <= q_max; below, read q for tau where it differs). The residual
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
//! # Pull-ins
//!
//! [`solve_displacements`] iterates on the same unknowns, the free tendons' tensions, where
//! the tip is a smooth function of them and a slack tendon is simply one at the bound
//! tau = 0. (In the pull-ins themselves the tip has a kink wherever a tendon goes slack or
//! taut, and a slack tendon's derivative is zero.) The stroke is a constraint on the
//! tensions: the pull-in that holds tendon j just taut at tension tau_j,
//!
//! ```text
//! q_j(tau) = l_ref_j - l_j(tau) + c_j tau_j      (docs/actuation.md),
//! ```
//!
//! must lie in [q_min, q_max]; each step linearizes it with dq/dtau = C - dl/dtau, from the
//! same k solves as the tip's derivative
//! ([`crate::collocation::sensitivity::displacement_sensitivities`]'s tension directions),
//! so the step's model is minimized under the tension bound tau + d >= 0 and
//! q_min <= q + (dq/dtau) d <= q_max, a QP with general linear constraints (the primal
//! active-set method of `qp.rs`). A tendon at 0 N is given the pull-in q_j(tau): the largest
//! that leaves it slack, just taut. At the end the free tendons are made
//! displacement-controlled at those pull-ins (one within 1e-9 of the stroke's span of a
//! bound is put on it) and the robot is solved once more, warm, under displacement control:
//! the reported solution. The start is the robot solved with its free tendons' pull-ins
//! clamped into the stroke (a tension-controlled tendon's pull-in is the one its tension
//! holds).
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
//! - `Stationary`: the gradient J^T e projected onto the moves the active bounds allow
//!   vanishes (relative to
//!   |J_i| |e|, below [`GRADIENT_TOLERANCE`]): a (local) minimum of the tip error within
//!   the bounds, the closest the tendons can bring the tip.
//! - `NoProgress`: the step is below [`STEP_TOLERANCE`] times the tension scale, or it would
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

mod inputs;
mod problem;
mod qp;
mod result;

pub use inputs::GEOMETRIC_SHARE;
pub use problem::{Adjusted, InverseOptions, Target};
pub use result::{Bound, InverseSolution};

use super::lm::{Damping, FitTermination, accepts, gain_ratio};
use crate::Error;
use crate::collocation::Solver;
use crate::error::Result;
use crate::model::robot::Robot;
use crate::so3;
use crate::solution::Solution;
use inputs::Inputs;
use nalgebra::{DMatrix, DVector, Vector3};
use problem::validate;
use qp::{Constraints, solve_qp};

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

/// Step test, 1e-10 relative to the tension scale (`max_tension`, or for pull-ins the
/// largest [`Robot::tension_scale`] of the free tendons, 2.2 N on the prototype): below it
/// the tension change moves the tip by less than the forward-solve noise (about 1e-8 m; tip
/// sensitivities are at most a few centimetres per newton on the prototype, so 1e-10 of a
/// 5 N bound moves it 1e-11 m).
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
/// robot.tendons[1].set_tension(1.5);
/// let options = InverseOptions::new(5.0);
/// let goal = tdcr::collocation::solve(&robot, &options.solver).unwrap().tip_position();
/// robot.tendons[1].set_tension(0.0);
/// let found = solve_tensions(&robot, &Target::position(goal), &options).unwrap();
/// assert!(found.reachable);
/// assert!((found.tip_position() - goal).norm() <= options.tolerance);
/// ```
pub fn solve_tensions(robot: &Robot, target: &Target, options: &InverseOptions) -> Result<InverseSolution> {
    let adjusted = Adjusted::Tensions {
        max: options.max_tension,
    };
    minimize(robot, target, options, adjusted)
}

/// Actuator pull-ins within [`min_displacement`, `max_displacement`] that bring the tip of
/// `robot` to `target`, by the same bounded Levenberg-Marquardt on d(tip)/dq (module docs,
/// "Pull-ins"). The free tendons become displacement-controlled: a tension-controlled one
/// starts at the pull-in its tension holds, a displacement-controlled one at its pull-in,
/// both clamped into the bounds. Slack tendons are reported as [`Bound::Slack`]; the
/// returned pull-in of a tendon that ends slack is the largest that leaves the same shape
/// (the tendon just taut at 0 N), unless a bound holds it lower.
///
/// [`min_displacement`]: InverseOptions::min_displacement
/// [`max_displacement`]: InverseOptions::max_displacement
///
/// # Errors
/// As [`solve_tensions`], with `options.min_displacement` not finite and
/// `options.max_displacement` not finite or not above the lower bound, or not below an
/// inextensible free tendon's path length, in place of `options.max_tension`.
///
/// # Examples
/// ```
/// use tdcr::fit::inverse::{InverseOptions, Target, solve_displacements};
/// let mut robot = tdcr::cases::prototype();
/// robot.tendons[1].set_displacement(0.003); // pull tendon 2 in by 3 mm
/// // A stroke of +-1 cm: under its own weight the rod's upper tendons need letting out.
/// let options = InverseOptions::displacements(-0.01, 0.01);
/// let goal = tdcr::collocation::solve(&robot, &options.solver).unwrap().tip_position();
/// robot.tendons[1].set_tension(0.0); // forget it: start from the tensions (all 0)
/// let found = solve_displacements(&robot, &Target::position(goal), &options).unwrap();
/// assert!(found.reachable);
/// assert!((found.tip_position() - goal).norm() <= options.tolerance);
/// ```
pub fn solve_displacements(robot: &Robot, target: &Target, options: &InverseOptions) -> Result<InverseSolution> {
    let adjusted = Adjusted::Displacements {
        min: options.min_displacement,
        max: options.max_displacement,
    };
    minimize(robot, target, options, adjusted)
}

/// The bounded Levenberg-Marquardt iteration (module docs) on the inputs `adjusted`.
fn minimize(robot: &Robot, target: &Target, options: &InverseOptions, adjusted: Adjusted) -> Result<InverseSolution> {
    robot.validate()?;
    let free = validate(robot, target, options, adjusted)?;
    let inputs = Inputs::new(robot, adjusted, free, options.max_tension);
    let weight = options.orientation_weight.unwrap_or_else(|| robot.length());
    let mut solver = Solver::new(options.solver.clone());
    let (mut current, mut solution, mut forward_solves) = inputs.start(robot, &mut solver)?;
    let (mut jacobians, mut iterations) = (0, 0);
    let mut e = tip_error(&solution, target, weight);
    let mut history = vec![e.norm()];
    // Damping mu (set from the first Jacobian) and its growth factor nu on rejection.
    let mut damping: Option<Damping> = None;
    let mut trials = Vec::new();
    // The last linearization, kept when a step is rejected (the iterate did not move).
    let mut linearization: Option<(DMatrix<f64>, Constraints)> = None;
    // The tension scale of the step test: the bound, or for pull-ins the tensions that
    // bend the rod through about a radian (E I / (L |r|) at the free tendons' offsets).
    let scale = inputs.tension_scale(&current);
    let termination = loop {
        if e.norm() <= options.tolerance {
            break FitTermination::Reached;
        }
        let tau = inputs.tensions(&current);
        let (J, constraints) = match linearization.take() {
            Some(l) => l,
            None => {
                jacobians += 1;
                let l = inputs.linearize(&current, &solution, &tau)?;
                (error_jacobian(&l.tip, weight, &e), l.constraints)
            }
        };
        let g = J.transpose() * &e;
        if stationary(&J, &g, &e, &constraints) {
            break FitTermination::Stationary;
        }
        if iterations >= options.max_iterations {
            break FitTermination::MaxIterations;
        }
        let JtJ = J.transpose() * &J;
        let largest = JtJ.diagonal().amax();
        if largest <= 0.0 {
            // No free input moves the tip at all (caught by `stationary` unless rounding).
            break FitTermination::Stationary;
        }
        let damping = damping.get_or_insert_with(|| Damping::new(INITIAL_DAMPING * largest));
        let mu = damping.value();
        let mut H = JtJ;
        for i in 0..tau.len() {
            H[(i, i)] += mu;
        }
        let d = solve_qp(&H, &g, &constraints);
        if d.amax() <= STEP_TOLERANCE * scale {
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
        inputs.set(&mut trial, &(&tau + &d));
        iterations += 1;
        forward_solves += 1;
        // A trial the forward solver cannot converge (a step into a hard region) is a
        // rejected step: the damping grows and the next step is shorter.
        let trial_solution = match solver.solve_from(&trial, &solution) {
            Ok(s) => Some(s),
            Err(Error::NotConverged { .. }) => None,
            Err(other) => return Err(other),
        };
        let e_trial = trial_solution.as_ref().map(|s| tip_error(s, target, weight));
        let cost = 0.5 * e.norm_squared();
        let trial_cost = e_trial.as_ref().map_or(f64::NAN, |e| 0.5 * e.norm_squared());
        let rho = gain_ratio(cost, trial_cost, predicted);
        let accepted = accepts(rho, predicted, ACCEPT_RATIO);
        trials.push(damping.update(accepted, rho, d.amax(), cost, trial_cost));
        match (accepted, trial_solution, e_trial) {
            (true, Some(s), Some(e_new)) => {
                current = trial;
                solution = s;
                e = e_new;
                history.push(e.norm());
            }
            _ => linearization = Some((J, constraints)),
        }
    };
    let (current, solution, finishing) = inputs.finish(current, solution, &mut solver)?;
    forward_solves += finishing;
    let e = tip_error(&solution, target, weight);
    let bounds = (0..current.tendons.len())
        .map(|i| inputs.bound(i, &current, &solution))
        .collect();
    let tip = solution.tip();
    Ok(InverseSolution {
        tensions: solution.tensions(),
        displacements: solution.tendons.iter().map(|t| t.displacement).collect(),
        residual: e.norm(),
        position_error: (tip.p - target.position).norm(),
        orientation_error: target.orientation.map(|R| so3::log(&(tip.R * R.transpose())).norm()),
        reachable: termination == FitTermination::Reached && e.norm() <= options.tolerance,
        termination,
        bounds,
        iterations,
        forward_solves,
        jacobians,
        history,
        trials,
        tolerance: options.tolerance,
        adjusted,
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

/// de/d(inputs) from the tip pose's derivative columns `tip` (6 x free): rows as
/// [`tip_error`]. The rotation rows map the world-frame rotation vector omega
/// (R -> exp(hat(omega)) R) through d log(exp(hat(omega)) exp(hat(e_R))) / d omega =
/// J_l(e_R)^-1 = J_r(-e_R)^-1.
fn error_jacobian(tip: &DMatrix<f64>, weight: f64, e: &DVector<f64>) -> DMatrix<f64> {
    let mut J = tip.rows(0, 3).into_owned();
    if e.len() == 6 {
        let e_R = Vector3::new(e[3], e[4], e[5]) / weight;
        let map = so3::right_jacobian_inv(&(-e_R)) * weight;
        let rotation = map * tip.rows(3, 3);
        J = J.insert_rows(3, 3, 0.0);
        J.rows_mut(3, 3).copy_from(&rotation);
    }
    J
}

/// Whether the gradient g = J^T e, projected onto the cone of moves the active constraints
/// allow (the projection of -g, by the QP min |d|^2 / 2 + g^T d under them), vanishes
/// relative to |J_i| |e| (the cosine between e and each free column) for every free input.
/// On a box this is the usual projected gradient: g_i, or 0 where a bound blocks -g_i.
fn stationary(J: &DMatrix<f64>, g: &DVector<f64>, e: &DVector<f64>, constraints: &Constraints) -> bool {
    let identity = DMatrix::identity(g.len(), g.len());
    let projected = solve_qp(&identity, g, &constraints.active());
    let norm_e = e.norm();
    (0..g.len()).all(|i| {
        let scale = J.column(i).norm() * norm_e;
        scale == 0.0 || projected[i].abs() <= GRADIENT_TOLERANCE * scale
    })
}
