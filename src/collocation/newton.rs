//! Damped Newton on the collocation system, with chord steps on stored factors.
//!
//! Every buffer and the linear solver (for the sparse LU: the pattern and symbolic
//! factorization) are built once per mesh in [`Workspace`]; each iteration refills the
//! matrix values, refactors numerically and solves without allocating. Every step is
//! checked for finiteness (a numerically zero pivot shows up as inf/NaN): a singular matrix
//! is a [`Termination::SingularJacobian`], never a panic.
//!
//! One loop serves the plain system F(x) = 0 and the system bordered by unknowns of its own
//! (the tensions of displacement-controlled tendons and their length constraints,
//! `collocation/actuation.rs`): the border ([`Border`]) turns each step of J into the
//! bordered step and adds its rows to the residual, so that chord steps, the line search and
//! the stopping tests are the same code for both.

mod ahead;
mod norms;

use super::MAX_ITERATIONS;
use super::linear::Linear;
use super::system::System;
use super::unknowns;
pub use super::workspace::Workspace;
use crate::report::{Iteration, SolveReport, Termination};
use crate::solution::State;
use ahead::evaluate_trial_ahead;
pub(crate) use ahead::{run_ahead, run_bordered_ahead};
use norms::{max_norm, nan_max};
use std::time::Instant;

/// Armijo sufficient-decrease constant (Dennis & Schnabel's customary 1e-4).
const ARMIJO: f64 = 1e-4;
/// Smallest line-search fraction before giving up (2^-20: 20 halvings).
const MIN_DAMPING: f64 = 1.0 / 1_048_576.0;
/// A chord step (solved with the factors of an earlier Jacobian) is kept only when it cuts
/// the residual max-norm at least fourfold; otherwise it is discarded and the Jacobian is
/// evaluated afresh. Near a solution chord steps contract by the relative change of the
/// Jacobian since it was factored (1e-2 .. 1e-5 in the benchmarks) at a fifth of a Newton
/// step's cost; a step that does less than quarter the residual is not worth keeping.
pub const CHORD_CONTRACTION: f64 = 0.25;

/// Newton stops only when its remaining error is also below this (scaled unknowns: 1e-10 L
/// of position, 1e-10 rad): the residual test alone is not enough where the rows' scaling
/// (force rows in units of EA) hides a large bending compliance, and chord steps converge
/// only linearly. The remaining error is estimated from the last step and the contraction
/// theta of the last two (Deuflhard's error-oriented test): theta / (1 - theta) |dx| after a
/// chord step (linear convergence), theta^2 |dx| after a Newton step (quadratic).
pub(super) const STEP_TOLERANCE: f64 = 1e-10;

/// Chord steps go on while each shrinks the step at least this much (tenfold): slower
/// linear convergence costs more chord steps than one new Jacobian.
const CHORD_STEP_RATIO: f64 = 0.1;

/// Newton settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Stop when the scaled residual max-norm is at or below this.
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Start with chord steps on the factors already in the workspace: set it when they
    /// belong to a Jacobian evaluated near the starting point (the previous solve of a
    /// sweep, the previous load step). A chord step that does not contract fast enough
    /// falls back to a Newton step, so a wrong setting costs time, never the answer.
    pub reuse_factors: bool,
    /// Stop at the first damped step (returning [`Termination::MaxIterations`]): a caller
    /// that only wants a root Newton reaches directly, and has a better way otherwise.
    pub stop_when_damped: bool,
}

/// Which point of a Newton step an evaluation belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Point {
    /// The current iterate.
    Current,
    /// The trial point of a step (a line-search fraction of it).
    Trial,
}

/// Unknowns y and rows psi(x, y) = 0 that border the collocation system F(x, y) = 0, for
/// [`run_bordered`]: the tensions of displacement-controlled tendons and their length
/// constraints (`collocation/actuation.rs`). Newton's loop holds x, F and the step dx and
/// takes every decision (chord or Newton step, line search, stopping); the border holds y,
/// psi and its step dy, and the collocation system at its y (F depends on the tensions). Its
/// rows count in the residual norm and the merit, its scaled step in the step norm.
/// [`NoBorder`] is the plain system's.
pub(crate) trait Border {
    /// Runs `f` on the collocation system at the border unknowns of `point`.
    fn on<R>(&mut self, point: Point, f: impl FnOnce(&System) -> R) -> R;

    /// Evaluates the border's rows at the states `x` and the unknowns of `point`, kept as
    /// that point's rows.
    fn rows(&mut self, point: Point, x: &[State]);

    /// The rows of `point` (scaled, dimensionless), as last evaluated.
    fn residual(&self, point: Point) -> &[f64];

    /// Called after Newton has factored the Jacobian J at the current point (states `x`):
    /// computes what the steps need from this linearization.
    ///
    /// # Errors
    /// The [`Termination`] to stop with (a model breakdown, a singular solve).
    fn factored(&mut self, x: &[State], at: &mut Linearization, report: &mut SolveReport) -> Result<(), Termination>;

    /// Whether the border factors and solves the whole bordered system itself, from the
    /// Jacobian J Newton assembles and its own blocks: `None` when Newton factors J and
    /// hands the border J^-1 (-F) (the default); `Some(held)` when Newton skips J's own
    /// factorization, `held` saying whether the border holds factors for a chord step.
    fn own_factors(&self) -> Option<bool> {
        None
    }

    /// The bordered step at `point` (states `x`): `a` holds J^-1 (-F) for the factored J and
    /// the residual F at `point` (with [`Border::own_factors`], nothing at
    /// [`Point::Current`], whose F the border reads from `at`, and -F at [`Point::Trial`]),
    /// and becomes dx. The border's step dy goes with it: for
    /// [`Point::Current`] it is kept for [`Border::trial`]; for [`Point::Trial`] (a simplified
    /// correction, measured only) it is not. Returns the max-norm of the scaled dy, None when
    /// the border's own system is singular. `at` lends the factors of J for further
    /// solves (timed into `report`).
    fn step(
        &mut self,
        point: Point,
        x: &[State],
        a: &mut [f64],
        at: &mut Linearization,
        report: &mut SolveReport,
    ) -> Option<f64>;

    /// Sets the trial unknowns to y + alpha dy.
    fn trial(&mut self, alpha: f64);

    /// Makes the trial point's unknowns and rows the current ones.
    fn accept(&mut self);
}

/// The border of no unknowns: Newton on the plain collocation system.
pub(crate) struct NoBorder<'s, 'a>(pub &'s System<'a>);

impl Border for NoBorder<'_, '_> {
    fn on<R>(&mut self, _: Point, f: impl FnOnce(&System) -> R) -> R {
        f(self.0)
    }
    fn rows(&mut self, _: Point, _: &[State]) {}
    fn residual(&self, _: Point) -> &[f64] {
        &[]
    }
    fn factored(&mut self, _: &[State], _: &mut Linearization, _: &mut SolveReport) -> Result<(), Termination> {
        Ok(())
    }
    fn step(
        &mut self,
        _: Point,
        _: &[State],
        _: &mut [f64],
        _: &mut Linearization,
        _: &mut SolveReport,
    ) -> Option<f64> {
        Some(0.0)
    }
    fn trial(&mut self, _: f64) {}
    fn accept(&mut self) {}
}

/// Newton's linearization at the current point, lent to a border: the collocation residual F
/// there and the factors of its Jacobian J, for further right-hand sides.
pub(crate) struct Linearization<'w> {
    linear: &'w mut Linear,
    residual: &'w [f64],
    values: &'w [f64],
}

impl Linearization<'_> {
    /// The collocation residual F at the current point.
    pub(crate) fn residual(&self) -> &[f64] {
        self.residual
    }

    /// The Jacobian J whose factors these are, in [`unknowns::pattern`] order. (After a
    /// Jacobian evaluated ahead at a trial point that did not end the run, the values are
    /// that point's and the factors an earlier Jacobian's; a border with its own factors
    /// reads the values only in [`Border::factored`], right after Newton evaluated them.)
    pub(crate) fn values(&self) -> &[f64] {
        self.values
    }

    /// Solves J out = rhs with the factors (timed into `report`); false for a non-finite
    /// result.
    pub(crate) fn solve(&mut self, rhs: &[f64], out: &mut [f64], report: &mut SolveReport) -> bool {
        let t = Instant::now();
        self.linear.solve_again(rhs, out);
        report.timings.solve += t.elapsed();
        out.iter().all(|v| v.is_finite())
    }
}

/// The residual of `system` at the states `x` into `out`, counted and timed in `report`;
/// false on a model breakdown.
pub(crate) fn residual(system: &System, x: &[State], out: &mut [f64], report: &mut SolveReport) -> bool {
    let t = Instant::now();
    let ok = system.residual(x, out).is_ok();
    report.timings.assembly += t.elapsed();
    report.evaluations.residual += 1;
    report.evaluations.equations += system.rate_evaluations();
    ok
}

/// The collocation residual at the states `x` and `point`'s border unknowns into `out`, the
/// node rates of eq. 13 on the way into `rates` ([`System::residual_rates`]; `filled` says
/// whether they were written), and the border's rows there; false on a model breakdown.
fn evaluate<B: Border>(
    border: &mut B,
    point: Point,
    x: &[State],
    (out, rates, filled): (&mut [f64], &mut [nalgebra::Vector6<f64>], &mut bool),
    report: &mut SolveReport,
) -> bool {
    let ok = border.on(point, |system| {
        let t = Instant::now();
        let result = system.residual_rates(x, out, rates);
        report.timings.assembly += t.elapsed();
        report.evaluations.residual += 1;
        report.evaluations.equations += system.rate_evaluations();
        *filled = matches!(result, Ok(true));
        result.is_ok()
    });
    border.rows(point, x);
    ok
}

/// [`evaluate`] at the trial point `ws.trial` (a chord or Newton step's end) into the
/// workspace's trial residual and rates.
fn evaluate_trial<B: Border>(border: &mut B, ws: &mut Workspace, report: &mut SolveReport) -> bool {
    evaluate(
        border,
        Point::Trial,
        &ws.trial,
        (&mut ws.trial_residual, &mut ws.trial_rates, &mut ws.trial_rates_valid),
        report,
    )
}

/// The Jacobian at the states `x` into the workspace's values and the residual there into
/// its residual (the border's rows are not evaluated), counted and timed in `report`; false
/// on a model breakdown or a value that is not finite.
fn jacobian<B: Border>(border: &mut B, x: &[State], ws: &mut Workspace, report: &mut SolveReport) -> bool {
    let t = Instant::now();
    ws.rates_valid = false;
    ws.forget_tension_rhs();
    let ok = border.on(Point::Current, |system| {
        report.evaluations.equations += system.rate_evaluations();
        system.jacobian(x, &mut ws.residual, &mut ws.values).is_ok()
    });
    report.timings.assembly += t.elapsed();
    report.evaluations.jacobian += 1;
    ws.drift = 0.0;
    ok && super::workspace::all_finite(&ws.values)
}

/// Whether the error left after the last step is below [`STEP_TOLERANCE`], from the norms
/// of the last two full steps and whether the last was a Newton step (`fresh`).
fn stops(before_last: f64, last_step: f64, fresh: bool) -> bool {
    let theta = last_step / before_last;
    // One step: its length bounds the error; two: the contraction extrapolates it; steps
    // that no longer contract have reached the rounding floor.
    if before_last.is_infinite() {
        last_step <= STEP_TOLERANCE
    } else if theta >= 1.0 {
        true
    } else if fresh {
        // Quadratic: e_k+1 = C e_k^2 with theta = C e_k-1 gives e_k+1 = theta^2 |dx_k|.
        theta * theta * last_step <= STEP_TOLERANCE
    } else {
        // Linear: e_k+1 = theta e_k and |dx_k| = (1 - theta) e_k.
        theta / (1.0 - theta) * last_step <= STEP_TOLERANCE
    }
}

/// The scaled residual max-norm over the collocation rows and the border's.
fn norm(residual: &[f64], border: &[f64]) -> f64 {
    nan_max(max_norm(residual), max_norm(border))
}

/// The merit 0.5 |(F, psi)|^2 of the line search.
fn merit(residual: &[f64], border: &[f64]) -> f64 {
    0.5 * residual.iter().chain(border).map(|x| x * x).sum::<f64>()
}

/// Runs damped Newton from `x` (updated in place). Returns the termination reason and the
/// row of the largest final residual.
///
/// After an undamped Newton step (and at the start when `settings.reuse_factors`), the next
/// step is first tried as a chord step with the factors already in the workspace: it costs
/// one residual and one re-solve instead of a Jacobian, a factorization and a residual, and
/// it is kept only when it cuts the residual fourfold ([`CHORD_CONTRACTION`]). Convergence is
/// always judged on the residual itself, so chord steps change the cost, not the answer's
/// tolerance.
pub fn run(
    system: &System,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> (Termination, usize) {
    run_bordered(&mut NoBorder(system), ws, x, settings, report)
}

/// [`run`] on the collocation system bordered by `border`'s unknowns and rows (docs/actuation.md
/// for the tensions of displacement-controlled tendons): the same steps and tests, with the
/// border's rows in the residual norm and the merit and its scaled step in the step norm.
/// The worst row of the result counts the border's rows after the collocation rows.
pub(crate) fn run_bordered<B: Border>(
    border: &mut B,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> (Termination, usize) {
    run_with(border, ws, x, settings, report, None)
}

/// [`run_bordered`], evaluating the Jacobian at a trial point predicted to be the last when
/// `ahead` is given ([`run_ahead`]; `Some(keep)`: keeping eq. 13's factored matrices).
fn run_with<B: Border>(
    border: &mut B,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
    ahead: Option<bool>,
) -> (Termination, usize) {
    use Point::{Current, Trial};
    report.history.clear();
    // Reserved up front so that recording iterations never allocates inside the loop; at
    // most MAX_ITERATIONS records, the bound `Options::validate` enforces, so that a caller
    // of this function with a huge limit cannot overflow the reservation.
    report.history.reserve(settings.max_iterations.min(MAX_ITERATIONS));
    let length = border.on(Current, |system| system.model.robot.length());
    let worst = |ws: &Workspace, border: &B| worst_row(&ws.residual, border.residual(Current));
    // The Jacobian held belongs to an earlier run's point (or system): not to this run's
    // iterates until this run evaluates one.
    ws.drift = f64::INFINITY;
    // A run that starts with a Newton step takes the residual at the start from the
    // Jacobian's evaluation there (`System::jacobian` writes both), not from one more
    // residual evaluation before it.
    let mut assembled = !settings.reuse_factors && settings.max_iterations > 0;
    let ok = if assembled {
        let ok = jacobian(border, x, ws, report);
        border.rows(Current, x);
        ok
    } else {
        evaluate(
            border,
            Current,
            x,
            (&mut ws.residual, &mut ws.rates, &mut ws.rates_valid),
            report,
        )
    };
    if !ok || !norm(&ws.residual, border.residual(Current)).is_finite() {
        return (Termination::NonFinite, worst(ws, border));
    }
    let mut chord = settings.reuse_factors;
    // A border that factors the bordered system itself (no factorization of J alone).
    let own = border.own_factors().is_some();
    // Norms of the last two steps taken (full steps only: a damped one says nothing of the
    // remaining error).
    let (mut last_step, mut before_last) = (f64::INFINITY, f64::INFINITY);
    // Whether the last step was a Newton step (quadratic convergence) or a chord step.
    let mut last_fresh = false;
    for iteration in 0..settings.max_iterations {
        let norm_x = norm(&ws.residual, border.residual(Current));
        let settled = stops(before_last, last_step, last_fresh);
        // At least one step: a guess (the rigid estimate of a lightly loaded rod, say) can
        // meet an absolute tolerance without being the discrete solution.
        if norm_x <= settings.tolerance && iteration > 0 && (settled || norm_x == 0.0) {
            report.residual = norm_x;
            return (Termination::Converged, worst(ws, border));
        }
        report.iterations += 1;
        let held = match border.own_factors() {
            Some(held) => held,
            None => chord && ws.chord(report),
        };
        if chord
            && held
            && let Some(border_step) = border.step(
                Current,
                x,
                &mut ws.step,
                &mut Linearization {
                    linear: &mut ws.linear,
                    residual: &ws.residual,
                    values: &ws.values,
                },
                report,
            )
        {
            let step_norm = nan_max(max_norm(&ws.step), border_step);
            unknowns::retract(x, &ws.step, 1.0, length, &mut ws.trial);
            border.trial(1.0);
            // The Jacobian there when the step would end the run and leave the one held
            // too far for the verdict (drift beyond STEP_TOLERANCE).
            let (ok, finite) = match ahead {
                Some(keep) if ws.drift + step_norm > STEP_TOLERANCE && stops(last_step, step_norm, false) => {
                    evaluate_trial_ahead(border, ws, keep, report)
                }
                _ => (evaluate_trial(border, ws, report), false),
            };
            let trial_norm = norm(&ws.trial_residual, border.residual(Trial));
            if ok && (trial_norm <= settings.tolerance || trial_norm <= CHORD_CONTRACTION * norm_x) {
                report.history.push(Iteration {
                    residual: norm_x,
                    step: step_norm,
                    damping: 1.0,
                    fresh_jacobian: false,
                });
                report.chord_steps += 1;
                // A chord step that shrinks the step less than tenfold converges slowly
                // (the Jacobian has moved): the next step is a Newton step.
                if step_norm > CHORD_STEP_RATIO * last_step {
                    chord = false;
                }
                (before_last, last_step) = (last_step, step_norm);
                last_fresh = false;
                ws.drift = if finite { 0.0 } else { ws.drift + step_norm };
                std::mem::swap(x, &mut ws.trial);
                std::mem::swap(&mut ws.residual, &mut ws.trial_residual);
                ws.swap_rates();
                border.accept();
                continue;
            }
        }
        // A Newton step: the Jacobian at x (already there on the first step of a run that
        // starts with one).
        report.newton_steps += 1;
        if !std::mem::take(&mut assembled) && !jacobian(border, x, ws, report) {
            return (Termination::NonFinite, worst(ws, border));
        }
        if own {
            ws.assembled();
        } else if !ws.solve(report) {
            return (Termination::SingularJacobian, worst(ws, border));
        }
        let mut at = Linearization {
            linear: &mut ws.linear,
            residual: &ws.residual,
            values: &ws.values,
        };
        if let Err(termination) = border.factored(x, &mut at, report) {
            return (termination, worst(ws, border));
        }
        let Some(border_step) = border.step(Current, x, &mut ws.step, &mut at, report) else {
            return (Termination::SingularJacobian, worst(ws, border));
        };
        let step_norm = nan_max(max_norm(&ws.step), border_step);
        let phi = merit(&ws.residual, border.residual(Current));
        let mut alpha = 1.0;
        // Whether the value buffer holds the finite Jacobian at the full step's end.
        let mut finite_ahead = false;
        loop {
            unknowns::retract(x, &ws.step, alpha, length, &mut ws.trial);
            border.trial(alpha);
            let ok = match ahead {
                Some(keep) if alpha == 1.0 && step_norm > STEP_TOLERANCE && stops(last_step, step_norm, true) => {
                    let (ok, finite) = evaluate_trial_ahead(border, ws, keep, report);
                    finite_ahead = finite;
                    ok
                }
                _ => evaluate_trial(border, ws, report),
            };
            let phi_trial = merit(&ws.trial_residual, border.residual(Trial));
            // Armijo on 0.5|F|^2, whose slope along the Newton step is -|F|^2 = -2 phi; a
            // trial already within tolerance is accepted (at rounding level phi cannot fall).
            // With a border, F includes its rows: the semismooth step has the same slope.
            let done = norm(&ws.trial_residual, border.residual(Trial)) <= settings.tolerance;
            let finite = ok && phi_trial.is_finite();
            if finite && (done || phi_trial <= (1.0 - 2.0 * ARMIJO * alpha) * phi) {
                break;
            }
            // Or the natural monotonicity test (Deuflhard's NLEQ-ERR), which measures the
            // trial by its simplified Newton correction -J^-1 F(trial) with the same factors
            // and so does not depend on how the rows are scaled: a tiny tip force in rows
            // scaled by EA can make the residual grow along a step that halves the error.
            if finite {
                if own {
                    for (r, f) in ws.simplified.iter_mut().zip(&ws.trial_residual) {
                        *r = -f;
                    }
                } else {
                    for (r, f) in ws.rhs.iter_mut().zip(&ws.trial_residual) {
                        *r = -f;
                    }
                    let t = Instant::now();
                    ws.linear.solve_again(&ws.rhs, &mut ws.simplified);
                    report.timings.solve += t.elapsed();
                }
                let mut at = Linearization {
                    linear: &mut ws.linear,
                    residual: &ws.residual,
                    values: &ws.values,
                };
                if let Some(border_step) = border.step(Trial, &ws.trial, &mut ws.simplified, &mut at, report)
                    && nan_max(max_norm(&ws.simplified), border_step) <= (1.0 - alpha / 4.0) * step_norm
                {
                    break;
                }
            }
            alpha *= 0.5;
            if alpha < MIN_DAMPING {
                report.residual = norm_x;
                return (Termination::LineSearchFailed, worst(ws, border));
            }
        }
        report.history.push(Iteration {
            residual: norm_x,
            step: step_norm,
            damping: alpha,
            fresh_jacobian: true,
        });
        if alpha < 1.0 && settings.stop_when_damped {
            report.residual = norm_x;
            return (Termination::MaxIterations, worst(ws, border));
        }
        std::mem::swap(x, &mut ws.trial);
        std::mem::swap(&mut ws.residual, &mut ws.trial_residual);
        ws.swap_rates();
        border.accept();
        ws.drift = if finite_ahead && alpha == 1.0 {
            0.0
        } else if ws.unfactored {
            // The values are the full step's end's, or not finite.
            f64::INFINITY
        } else {
            alpha * step_norm
        };
        last_fresh = true;
        (before_last, last_step) = if alpha == 1.0 {
            (last_step, step_norm)
        } else {
            (f64::INFINITY, f64::INFINITY)
        };
        // Far from the solution (a damped step) a stale Jacobian is not worth trying.
        chord = alpha == 1.0;
    }
    let norm_x = norm(&ws.residual, border.residual(Current));
    report.residual = norm_x;
    if norm_x <= settings.tolerance {
        (Termination::Converged, worst(ws, border))
    } else {
        (Termination::MaxIterations, worst(ws, border))
    }
}

/// The row of the largest residual over the collocation rows and then the border's
/// (numbered after them).
fn worst_row(residual: &[f64], border: &[f64]) -> usize {
    residual
        .iter()
        .chain(border)
        .enumerate()
        .max_by(|a, b| a.1.abs().partial_cmp(&b.1.abs()).unwrap_or(std::cmp::Ordering::Greater))
        .map_or(0, |(i, _)| i)
}
