//! The shooting solver, kept as an independent cross-check of collocation.
//!
//! Unknowns: the base strains (v(0), u(0)), 6 numbers. Each trial integrates eq. 13 from the
//! base with the Dormand-Prince 5(4) embedded Runge-Kutta pair, stepping the rotation on
//! SO(3) by Runge-Kutta-Munthe-Kaas (each step works in the local coordinates
//! R = R_n exp(theta), theta' = J_r(theta)^-1 u, so R stays orthonormal). At every interior
//! breakpoint the right-hand strains are found from the jump conditions by a small Newton
//! solve; the 6 tip conditions are the residual of an outer damped Newton iteration whose
//! Jacobian is taken by central differences. Displacement-controlled tendons add their
//! tensions to the unknowns and their complementarity (taut at its length or slack at 0 N,
//! in the Fischer-Burmeister form of collocation) to the residual, the path lengths
//! integrated along with the state (docs/actuation.md).
#![allow(non_snake_case)]

mod integrate;
mod problem;

use crate::error::{Result, invalid};
use crate::mesh::guess::{self, InitialGuess};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::model::friction;
use crate::report::{Iteration, Method, SolveReport, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Readable, Robot};
use nalgebra::DVector;
use problem::{Problem, jacobian};
use std::time::Instant;

/// The largest [`Options::max_iterations`] shooting accepts. Each iteration keeps one record
/// in the report's history, so the cap bounds that memory; it costs no solve anything, since
/// shooting's Newton (central-difference Jacobian, backtracking) either converges in a few
/// dozen iterations from the rigid-equilibrium guess or stalls, where more iterations do not
/// help. Its own constant, not collocation's: the cross-check shares no solver settings.
pub const MAX_ITERATIONS: usize = 10_000;

/// Shooting options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Relative and absolute local error tolerance of the integrator on the scaled state
    /// (p / L, theta, v, u L). Default 1e-10; down to 1e-12 is supported.
    pub integration_tolerance: f64,
    /// Newton stops when the scaled tip residual is below this. Default 1e-9 (dimensionless;
    /// the same meaning as `collocation::Options::residual_tolerance`).
    pub residual_tolerance: f64,
    /// Newton iteration limit. Default 50; at most [`MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// Where Newton starts. Default: the rigid-equilibrium estimate.
    pub initial_guess: InitialGuess,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            integration_tolerance: 1e-10,
            residual_tolerance: 1e-9,
            max_iterations: 50,
            initial_guess: InitialGuess::RigidEquilibrium,
        }
    }
}

impl Options {
    /// Checks the options: the integration tolerance in [1e-14, 1e-2], a positive Newton
    /// tolerance, from one to [`MAX_ITERATIONS`] iterations.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field.
    pub fn validate(&self) -> Result<()> {
        // 1e-14: below this the local error test is pure rounding and steps collapse
        if !(self.integration_tolerance.is_finite() && (1e-14..=1e-2).contains(&self.integration_tolerance)) {
            return Err(invalid(
                "shooting.integration_tolerance",
                format!("is {}", Readable(self.integration_tolerance)),
                "use a value in [1e-14, 1e-2] (1e-10 by default)",
            ));
        }
        if !(self.residual_tolerance.is_finite() && self.residual_tolerance > 0.0) {
            return Err(invalid(
                "shooting.residual_tolerance",
                format!("is {}", Readable(self.residual_tolerance)),
                "use a positive value (1e-9 by default)",
            ));
        }
        if self.max_iterations == 0 {
            return Err(invalid(
                "shooting.max_iterations",
                "is 0",
                "allow at least one Newton iteration",
            ));
        }
        if self.max_iterations > MAX_ITERATIONS {
            return Err(invalid(
                "shooting.max_iterations",
                format!("is {}, above the limit of {MAX_ITERATIONS}", self.max_iterations),
                "Newton converges in a few dozen iterations or not at all, so more only costs memory; the default is 50",
            ));
        }
        Ok(())
    }
}

/// A point of the integrated trajectory.
type Point = State;

/// An error at a state the iteration visited: the robot passed validation, so a tendon path
/// tangent that vanishes there (near the geometric limit a trial state can fold a tendon's
/// path) says nothing wrong of the input, and is a breakdown of the model at that state, not
/// [`crate::Error::SingularRouting`].
fn visited(error: crate::Error) -> crate::Error {
    match error {
        crate::Error::SingularRouting { tendon, s, speed } => crate::Error::Breakdown {
            s,
            what: format!(
                "tendon {}'s path tangent vanished (|p_i'| = {speed:.3e}) at a state shooting visited, \
                 not at the robot's unloaded shape",
                tendon + 1
            ),
        },
        other => other,
    }
}

/// Solves `robot` by shooting.
///
/// Displacement-controlled tendons (docs/actuation.md) add their tensions to the unknowns
/// and one complementarity row each to the residual, in the Fischer-Burmeister form of the
/// collocation solve: psi_j = sqrt(a^2 + b^2) - a - b with a = tau_j / T_j and
/// b = phi_j / L, phi_j = l_ref_j - l_j - q_j + c_j tau_j the gap, the path lengths l_j
/// integrated along with the state. psi_j = 0 exactly when the tendon is taut (phi_j = 0,
/// tau_j >= 0) or slack (tau_j = 0, phi_j >= 0), so one semismooth Newton iteration finds
/// which tendons are slack; at convergence a tendon on the slack side gets exactly 0 N.
///
/// # Errors
/// Invalid input, a model breakdown, or [`Error::NotConverged`] with the report.
pub fn solve(robot: &Robot, options: &Options) -> Result<Solution> {
    robot.validate()?;
    options.validate()?;
    if friction::any(robot) && robot.has_displacement_inputs() {
        // The pull-ins fix the base-entry tensions of solves with friction at given
        // tensions (docs/friction.md section 3b), from the frictionless robot's.
        let start = Instant::now();
        let mut smooth = robot.clone();
        for t in &mut smooth.tendons {
            t.friction = None;
        }
        let first = solve(&smooth, options)?;
        // Differences for dphi/dtau: shooting imports nothing from collocation's linearization.
        let mut solution = crate::model::pull_in::hold(
            robot,
            &first.tensions(),
            None,
            options.residual_tolerance,
            |r, _| solve(r, options),
            |_, _, _| None,
        )?;
        solution.report.timings.total = start.elapsed();
        return Ok(solution);
    }
    let start = Instant::now();
    let mut problem = Problem::new(robot);
    let mut report = SolveReport::new(Method::Shooting);
    report.meshes = 1;
    report.load_steps = 1;

    // Initial guess: base strains of the rigid-equilibrium estimate at the starting tensions.
    let base = guess::initial_absolute(
        &Model::new(&problem.robot),
        &Mesh::uniform(robot, 64)?.nodes,
        options.initial_guess,
    )[0];
    let base_x = problem.scale.to_unknowns(&base.v, &base.u);
    let x0 = problem.unknowns(&base_x);
    report.unknowns = x0.len();
    let (x, smooth, mut trajectory) = newton(&mut problem, x0, options, &mut report).map_err(visited)?;
    if problem.finish(&x, &smooth) {
        // A slack tendon's tension went from its iterate (within the tolerance of 0) to
        // exactly 0: integrate once more, so that the shape is the one of the tensions
        // reported, and report the residual there.
        let at = problem.unknowns(&x.fixed_rows::<6>(0).into_owned());
        let mut traj = Vec::new();
        let g = problem
            .residual(&at, options, &mut traj, &mut report)
            .map_err(visited)?;
        report.residual = problem.complementarity(&at, &g).amax();
        trajectory = traj;
    }
    report.intervals = trajectory.len().saturating_sub(1);
    let model = Model::new(&problem.robot);
    let ends = segment_ends(&model, &trajectory);
    if friction::any(&problem.robot) {
        // The tensions along the tendons with friction: the converged trial once more (it is
        // deterministic, so the trajectory is the same), recording them.
        let mut profile = Vec::new();
        let paths: Vec<(usize, f64)> = Vec::new();
        let base = x.fixed_rows::<6>(0).into_owned();
        let mut traj = Vec::new();
        integrate::shoot(
            &model,
            &problem.scale,
            &base,
            &paths,
            options,
            &mut traj,
            Some(&mut profile),
            &mut report,
        )?;
        report.timings.total = start.elapsed();
        return nodes::solution_with_tensions(&model, &traj, &ends, (&profile, None), None, report);
    }
    report.timings.total = start.elapsed();
    nodes::solution(&model, &trajectory, &ends, None, report)
}

/// The merit a trial step must decrease: the residual's max-norm for tension inputs (as
/// before displacement inputs), its Euclidean norm with complementarity rows, since the
/// semismooth Newton step is a descent direction of 0.5 |F|^2 (De Luca, Facchinei & Kanzow
/// 1996) but need not decrease the max-norm.
fn merit(res: &DVector<f64>, complementarity: bool) -> f64 {
    if complementarity { res.norm() } else { res.amax() }
}

/// The Newton iteration from `x`: the converged unknowns, the smooth residual there
/// ([`Problem::residual`]) and the trajectory.
fn newton(
    problem: &mut Problem,
    mut x: DVector<f64>,
    options: &Options,
    report: &mut SolveReport,
) -> Result<(DVector<f64>, DVector<f64>, Vec<Point>)> {
    let length = problem.robot.length();
    let bordered = !problem.displaced.is_empty();
    let mut trajectory = Vec::new();
    let mut smooth = problem.residual(&x, options, &mut trajectory, report)?;
    let mut res = problem.complementarity(&x, &smooth);
    let mut norm = res.amax();
    report.termination = Termination::MaxIterations;
    for _ in 0..options.max_iterations {
        if norm < options.residual_tolerance {
            report.termination = Termination::Converged;
            break;
        }
        // A breakdown while differencing (a trial state where a tendon loses its tangent,
        // say) ends the iteration: the state is unphysical, not the input.
        let Ok(J) = jacobian(problem, &x, &smooth, options, report) else {
            report.termination = Termination::NonFinite;
            break;
        };
        let Some(step) = problem.bounded_step(&J, &x, &res) else {
            report.termination = Termination::SingularJacobian;
            break;
        };
        if !step.iter().all(|v| v.is_finite()) {
            report.termination = Termination::SingularJacobian;
            break;
        }
        // Backtracking: halve until the merit decreases (Armijo-free: the cross-check
        // only needs robustness, not efficiency).
        let current = merit(&res, bordered);
        let mut damping = 1.0;
        let mut accepted = false;
        while damping > 1e-4 {
            let trial = problem.project(&x + &step * damping);
            let mut traj = Vec::new();
            if let Ok(g) = problem.residual(&trial, options, &mut traj, report) {
                let r = problem.complementarity(&trial, &g);
                if r.amax().is_finite() && (merit(&r, bordered) < current || r.amax() <= options.residual_tolerance) {
                    report.iterations += 1;
                    report.newton_steps += 1;
                    report.history.push(Iteration {
                        residual: norm,
                        step: step.amax(),
                        damping,
                        fresh_jacobian: true,
                    });
                    x = trial;
                    norm = r.amax();
                    res = r;
                    smooth = g;
                    trajectory = traj;
                    accepted = true;
                    break;
                }
            }
            damping *= 0.5;
        }
        if !accepted {
            report.termination = Termination::LineSearchFailed;
            break;
        }
    }
    if norm < options.residual_tolerance {
        report.termination = Termination::Converged;
        // One more full Newton step, kept only if it lowers the residual: at quadratic
        // convergence it takes the residual from the tolerance down to the noise floor.
        // Optional, so a difference trial that breaks down skips it: near a tendon's
        // geometric limit a perturbed base strain can fold the tendon's path although the
        // converged state does not (99.9 % of the limit, tests/errors.rs).
        let polish = jacobian(problem, &x, &smooth, options, report).ok();
        if let Some(step) = polish.and_then(|J| problem.bounded_step(&J, &x, &res)) {
            let trial = problem.project(&x + &step);
            let mut traj = Vec::new();
            if let Ok(g) = problem.residual(&trial, options, &mut traj, report) {
                let r = problem.complementarity(&trial, &g);
                if r.amax() < norm {
                    report.iterations += 1;
                    report.newton_steps += 1;
                    report.history.push(Iteration {
                        residual: norm,
                        step: step.amax(),
                        damping: 1.0,
                        fresh_jacobian: true,
                    });
                    norm = r.amax();
                    x = trial;
                    smooth = g;
                    trajectory = traj;
                }
            }
        }
    }
    problem.set_tensions(&x);
    report.residual = norm;
    if report.termination != Termination::Converged {
        report.intervals = trajectory.len().saturating_sub(1);
        return Err(Error::NotConverged {
            method: Method::Shooting,
            report: Box::new(report.clone()),
            worst_s: length,
            hint: "shooting is a cross-check; use collocation (with load continuation) for hard cases".into(),
        });
    }
    Ok((x, smooth, trajectory))
}

/// The end of the segment each trajectory point belongs to (a breakpoint appears twice:
/// left limit, then right limit).
fn segment_ends(model: &Model, traj: &[Point]) -> Vec<f64> {
    let length = model.robot.length();
    let breaks = model.robot.breakpoints();
    let mut out = Vec::with_capacity(traj.len());
    for (k, pt) in traj.iter().enumerate() {
        let is_right_limit = k > 0 && traj[k - 1].s == pt.s;
        let end = breaks
            .iter()
            .copied()
            .find(|&b| if is_right_limit { b > pt.s } else { b >= pt.s })
            .unwrap_or(length);
        out.push(end);
    }
    out
}
