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
//! - Base orientation R0 = Rx(alpha) Ry(beta) Rz(gamma) (rad): [`crate::so3::euler_xyz`], the convention
//!   of the robot file's `euler_xyz_deg` (rotate about x, then the new y, then the newest z;
//!   the columns of R0 are the body axes in world components). XYZ angles are singular at
//!   beta = +-90 deg, where only alpha + gamma (beta = 90 deg) or alpha - gamma (beta = -90
//!   deg) is determined: express the data in a world frame that keeps beta away from +-90 deg.
//!   tdcr's own prototype frame ([`crate::cases::prototype`], R0 = Ry(90 deg)) sits exactly on
//!   the singularity; the paper's tracker frame ([`crate::cases::prototype_in_paper_frame`], R0 =
//!   Rx(180 deg) Rz(-90 deg)) is far from it.
//! - Base position p0 (m, world frame), off by default.
//! - Offset scale c (dimensionless): every tendon offset r_i(s) becomes c r_i(s) (a common
//!   error in where the tendon holes are), off by default. It is nearly interchangeable with
//!   E for tendon-bent shapes (the tendon moment tau c r bends against E I); experiments with
//!   a tip load or with no tension separate them.
//! - Friction coefficient mu (dimensionless), off by default: the first tendon with friction's
//!   (docs/friction.md), which the robot must have (its coefficient is the start); the other
//!   tendons with friction keep their ratios to it (one shared value where they are equal).
//!   Each experiment's [`Measurement::motion`] says whether it is a loading (`pull`) or an
//!   unloading (`release`) step; the difference between the two is what identifies mu.
//!
//! # Method
//!
//! Levenberg-Marquardt with Marquardt's scaling (damping lambda diag(J^T J), so the step does
//! not depend on the units of the parameters) and Nielsen's damping update ([`crate::fit::lm`]). The unknowns are
//! scaled to order one: E / E_start, the angles in rad, p0 / L, c and mu / mu_start. Each iteration solves
//! every experiment at the trial parameters, warm-started from its last solution; an accepted
//! step then costs one [`tip_sensitivities`] per experiment, which gives the Jacobian columns:
//!
//! ```text
//! d p_k / dE      = moduli.youngs_modulus (rows 0..3)          (at fixed nu)
//! d p_k / d angle = base_rotation (rows 0..3) * W(alpha, beta)   (chain rule, below)
//! d p_k / d p0    = base_position (rows 0..3)
//! d p_k / dc      = Sensitivity::derivative of the scaled routings (central difference of
//!                   the residual, IFT solve)
//! d p_k / d mu     = sum over the tendons with friction of TipSensitivities::friction
//!                    times mu_i / mu (1 where the coefficients are equal)
//! ```
//!
//! The sensitivity module differentiates with respect to a world-frame rotation vector phi,
//! R0 -> exp(hat(phi)) R0. With R0 = Rx Ry Rz, dR0/dalpha = hat(x) R0,
//! dR0/dbeta = Rx hat(y) Ry Rz = hat(Rx y) R0 and dR0/dgamma = Rx Ry hat(z) Rz = hat(Rx Ry z) R0,
//! so d phi / d(alpha, beta, gamma) = W = [x, Rx(alpha) y, Rx(alpha) Ry(beta) z] (columns;
//! [`crate::so3::euler_rates`]). Its determinant is cos(beta): the singularity above.
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

mod problem;
mod result;
mod robots;

pub use problem::{CalibrationOptions, Fit, Measurement, Parameters};
pub use result::{Calibration, CalibrationTimings, NOISE_FACTOR, PoorFit, TipErrorStatistics, UNSTATED_NOISE_FRACTION};
pub use robots::{rotate_world, scaled_routing};

use super::lm::{Damping, FitTermination, accepts, gain_ratio};
use crate::collocation::sensitivity::{Difference, RELATIVE_STEP, Sensitivity, tip_sensitivities};
use crate::collocation::{self, Solver};
use crate::error::{Result, invalid};
use crate::model::robot::Robot;
use crate::so3::{euler_rates, wrap_angle};
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector, Vector3};
use problem::{Unknown, layout, validate};
use rayon::prelude::*;
use std::time::Instant;

/// The damping above which the fit stops as [`FitTermination::Stalled`]: 1e16 times
/// diag(J^T J) makes the step about 1e-16 of the gradient step, below rounding.
pub const MAX_DAMPING: f64 = 1e16;

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
/// use tdcr::cases::table2_measurement;
/// use tdcr::fit::calibration::{CalibrationOptions, Parameters, predict};
/// let robot = tdcr::cases::prototype();
/// let case_s = &tdcr::cases::table2()[11]; // tendon 1 at 2.94 N
/// let experiment = table2_measurement(case_s, &nalgebra::Matrix3::identity());
/// let tips = predict(&robot, &Parameters::of(&robot), &[experiment], &CalibrationOptions::default()).unwrap();
/// assert!((tips[0].x - tdcr::cases::TIP_S[0]).abs() < 1e-5);
/// ```
pub fn predict(
    robot: &Robot,
    parameters: &Parameters,
    experiments: &[Measurement],
    options: &CalibrationOptions,
) -> Result<Vec<Vector3<f64>>> {
    let check = CalibrationOptions {
        fit: Fit {
            youngs_modulus: false,
            euler: true,
            base_position: false,
            offset_scale: false,
            friction: false,
        },
        ..options.clone()
    };
    validate(robot, experiments, &check, parameters)?;
    let applied = parameters.apply(robot);
    let mut solvers: Vec<ExperimentSolver> = experiments
        .iter()
        .map(|_| ExperimentSolver::new(&options.collocation))
        .collect();
    // Never stopped: every experiment is solved.
    Ok(solve_all(&applied, experiments, &mut solvers, &|| false)?
        .unwrap_or_default()
        .iter()
        .map(Solution::tip_position)
        .collect())
}

/// Asked between chunks of a calibration's solves whether to stop ([`calibrate_until`]).
pub type Stop<'a> = &'a dyn Fn() -> bool;

/// The experiments solved (or differentiated) in parallel between two calls of a [`Stop`]:
/// 16 per thread keeps every thread busy and a chunk short (16 solves, a few ms each).
fn chunk_size() -> usize {
    16 * rayon::current_num_threads().max(1)
}

/// Per-experiment solver state: a collocation solver (keeping its workspace) and the last
/// accepted solution (the warm start).
struct ExperimentSolver {
    /// The solver of this experiment.
    solver: Solver,
    /// The last accepted solution.
    solution: Option<Solution>,
}

impl ExperimentSolver {
    /// A solver with `options` and no warm start yet.
    fn new(options: &collocation::Options) -> Self {
        ExperimentSolver {
            solver: Solver::new(options.clone()),
            solution: None,
        }
    }
}

/// Solves every experiment for the robot `applied` (parameters already set), warm-started
/// from each experiment's accepted solution; `solvers` are not updated. `None` when `stop`
/// said so between two chunks.
fn solve_all(
    applied: &Robot,
    experiments: &[Measurement],
    solvers: &mut [ExperimentSolver],
    stop: Stop<'_>,
) -> Result<Option<Vec<Solution>>> {
    let mut out = Vec::with_capacity(experiments.len());
    let size = chunk_size();
    for (chunk, chunk_solvers) in experiments.chunks(size).zip(solvers.chunks_mut(size)) {
        if stop() {
            return Ok(None);
        }
        let solved: Vec<Solution> = chunk
            .par_iter()
            .zip(chunk_solvers.par_iter_mut())
            .map(|(e, es)| {
                let robot = e.load(applied);
                match &es.solution {
                    Some(warm) => es.solver.solve_from(&robot, warm),
                    None => es.solver.solve(&robot),
                }
            })
            .collect::<Result<_>>()?;
        out.extend(solved);
    }
    Ok(Some(out))
}

/// The 3N x n Jacobian of the tips in the scaled unknowns at the solutions of `applied`.
fn jacobian(
    applied: &Robot,
    params: &Parameters,
    experiments: &[Measurement],
    solutions: &[Solution],
    unknowns: &[Unknown],
    start: &Parameters,
    stop: Stop<'_>,
) -> Result<Option<DMatrix<f64>>> {
    let length = applied.length();
    let W = euler_rates(&params.euler);
    let mut blocks: Vec<DMatrix<f64>> = Vec::with_capacity(experiments.len());
    let size = chunk_size();
    for (chunk, chunk_solutions) in experiments.chunks(size).zip(solutions.chunks(size)) {
        if stop() {
            return Ok(None);
        }
        let chunk_blocks: Vec<DMatrix<f64>> = chunk
            .par_iter()
            .zip(chunk_solutions.par_iter())
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
                        // Every tendon with friction moves with mu (the first one's), in
                        // proportion to its coefficient: the sum of their columns, each times
                        // its coefficient over the first's (1 where they are equal).
                        Unknown::Friction => {
                            let first = Parameters::of(&robot).friction;
                            (0..robot.tendons.len())
                                .map(|i| {
                                    let column = sens.friction.fixed_view::<3, 1>(0, i).into_owned();
                                    match robot.tendons[i].active_friction() {
                                        Some(f) if f.coefficient != first => column * (f.coefficient / first),
                                        _ => column,
                                    }
                                })
                                .sum()
                        }
                    };
                    block.set_column(j, &(column * u.scale(start, length)));
                }
                Ok(block)
            })
            .collect::<Result<_>>()?;
        blocks.extend(chunk_blocks);
    }
    let mut J = DMatrix::zeros(3 * experiments.len(), unknowns.len());
    for (k, b) in blocks.iter().enumerate() {
        J.view_mut((3 * k, 0), (3, unknowns.len())).copy_from(b);
    }
    Ok(Some(J))
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
fn residual_vector(solutions: &[Solution], experiments: &[Measurement]) -> DVector<f64> {
    DVector::from_iterator(
        3 * experiments.len(),
        solutions
            .iter()
            .zip(experiments)
            .flat_map(|(s, e)| (s.tip_position() - e.measured_tip).iter().copied().collect::<Vec<_>>()),
    )
}

/// The stacked residuals as one vector per experiment.
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
/// A fit that stops without converging ([`FitTermination::MaxIterations`],
/// [`FitTermination::Stalled`]) is still returned, with the best parameters found: check
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
/// use tdcr::cases::{paper_frame_rotation, prototype_in_paper_frame, table2_measurement};
/// use tdcr::fit::calibration::{calibrate, predict, CalibrationOptions, Parameters};
/// let robot = prototype_in_paper_frame();
/// // Synthetic data: E 5 % stiffer than nominal, six experiments of Table 2.
/// let mut truth = Parameters::of(&robot);
/// truth.youngs_modulus *= 1.05;
/// let options = CalibrationOptions::default();
/// let mut experiments: Vec<_> = tdcr::cases::table2()[..31]
///     .iter()
///     .step_by(5)
///     .map(|e| table2_measurement(e, &paper_frame_rotation()))
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
pub fn calibrate(robot: &Robot, experiments: &[Measurement], options: &CalibrationOptions) -> Result<Calibration> {
    // A stop that never fires: the fit always runs to its end.
    calibrate_until(robot, experiments, options, &|| false).map(|fit| fit.expect("never stopped"))
}

/// [`calibrate`], asking `stop` between chunks of its solves and sensitivities (a few
/// milliseconds of work each) whether to give up: `None` when it said so (a front end's
/// Ctrl-C), the calibration otherwise.
///
/// # Errors
/// As [`calibrate`].
pub fn calibrate_until(
    robot: &Robot,
    experiments: &[Measurement],
    options: &CalibrationOptions,
    stop: Stop<'_>,
) -> Result<Option<Calibration>> {
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
    let mut timings = CalibrationTimings::default();
    let mut solvers: Vec<ExperimentSolver> = experiments
        .iter()
        .map(|_| ExperimentSolver::new(&options.collocation))
        .collect();
    let (mut solves, mut sensitivity_evaluations) = (0, 0);

    // Start: solve, residuals, Jacobian.
    let mut params = start;
    let mut applied = params.apply(robot);
    let t = Instant::now();
    let Some(solutions) = solve_all(&applied, experiments, &mut solvers, stop)? else {
        return Ok(None);
    };
    timings.solves += t.elapsed();
    solves += experiments.len();
    let mut r = residual_vector(&solutions, experiments);
    let start_residuals = per_experiment(&r);
    let mut cost = r.norm_squared();
    let t = Instant::now();
    let Some(mut J) = jacobian(&applied, &params, experiments, &solutions, &unknowns, &start, stop)? else {
        return Ok(None);
    };
    timings.sensitivities += t.elapsed();
    sensitivity_evaluations += experiments.len();
    for (es, s) in solvers.iter_mut().zip(solutions) {
        es.solution = Some(s);
    }

    let mut damping = Damping::new(options.initial_damping);
    let mut history = Vec::new();
    let mut termination = FitTermination::MaxIterations;
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
            termination = FitTermination::GradientTolerance;
            break;
        }
        let A = J.transpose() * &J;
        // diag(J^T J), floored at 1e-12 of its largest entry so that a parameter without
        // effect (a zero column) still gets damped.
        let largest = A.diagonal().max();
        let D = A.diagonal().map(|d| d.max(1e-12 * largest));
        let mut M = A.clone();
        for j in 0..n {
            M[(j, j)] += damping.value() * D[j];
        }
        let Some(chol) = M.cholesky() else {
            damping.reject();
            if damping.value() > MAX_DAMPING {
                termination = FitTermination::Stalled;
                break;
            }
            continue;
        };
        let delta = chol.solve(&(-&g));
        let step = delta.amax();
        if step <= options.step_tolerance {
            termination = FitTermination::StepTolerance;
            break;
        }
        let trial_z = &z + &delta;
        let trial = to_params(&trial_z);
        let trial_robot = trial.apply(robot);
        let t = Instant::now();
        let solved = match solve_all(&trial_robot, experiments, &mut solvers, stop) {
            Ok(None) => return Ok(None),
            Ok(Some(solutions)) => Ok(solutions),
            Err(e) => Err(e),
        };
        timings.solves += t.elapsed();
        solves += experiments.len();
        // Decrease of S = |r|^2 predicted by the linear model |r + J delta|^2:
        // -2 g.delta - delta^T A delta (positive for any lambda > 0).
        let predicted = -2.0 * g.dot(&delta) - (delta.transpose() * &A * &delta)[(0, 0)];
        let (gain, new) = match solved {
            Ok(solutions) => {
                let r_new = residual_vector(&solutions, experiments);
                let c = r_new.norm_squared();
                (gain_ratio(cost, c, predicted), Some((solutions, r_new, c)))
            }
            Err(_) => (f64::NAN, None),
        };
        // Any decrease is taken (the ratio threshold is 0).
        let accepted = accepts(gain, predicted, 0.0);
        let trial_cost = new.as_ref().map_or(f64::NAN, |(_, _, c)| *c);
        history.push(damping.update(accepted, gain, step, cost, trial_cost));
        if let (true, Some((solutions, r_new, c))) = (accepted, new) {
            let decrease = (cost - c) / cost;
            z = trial_z;
            params = trial;
            applied = trial_robot;
            r = r_new;
            cost = c;
            let t = Instant::now();
            let Some(next) = jacobian(&applied, &params, experiments, &solutions, &unknowns, &start, stop)? else {
                return Ok(None);
            };
            J = next;
            timings.sensitivities += t.elapsed();
            sensitivity_evaluations += experiments.len();
            for (es, s) in solvers.iter_mut().zip(solutions) {
                es.solution = Some(s);
            }
            if decrease <= options.cost_tolerance {
                termination = FitTermination::CostTolerance;
                break;
            }
        } else if damping.value() > MAX_DAMPING {
            termination = FitTermination::Stalled;
            break;
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
            friction: 0.0,
        };
        for (j, u) in unknowns.iter().enumerate() {
            u.set(&mut se, noise_estimate * inverse[(j, j)].sqrt() * scales[j]);
        }
        se
    });
    let mut fitted = params;
    fitted.euler = fitted.euler.map(wrap_angle);
    let residuals = per_experiment(&r);
    let tips = solvers
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
    Ok(Some(Calibration {
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
    }))
}
