//! Locating the folds and bifurcations of a traced branch within the continuation step that
//! crossed them, to [`LOCATED`] of the traced range (docs/stability.md, "Tracing a branch"),
//! instead of reporting the first point past them.
//!
//! - A **fold** is where lambda turns back: the tangent's t_lambda changes sign. The step
//!   from `point` of arclength h found it; bisection on the arclength of that step (each
//!   middle point corrected on the bordered system to the solve's tolerance, its tangent
//!   oriented along the path) keeps the sign change inside a bracket [s_lo, s_hi]. Over the
//!   bracket lambda moves by at most (s_hi - s_lo) max |t_lambda|, and |t_lambda| falls to
//!   zero at the fold, so the bracket is narrowed until that bound is below [`LOCATED`].
//! - A **bifurcation** is where the number of unstable directions changes without a fold:
//!   the branch is a graph over lambda there, so bisection is on lambda itself, each middle
//!   point predicted along `point`'s tangent and converged by Newton at fixed lambda, the
//!   count taken from its Jacobian.
//!
//! Both leave the Jacobian of `next` (the point past the event) factored, as the path
//! expects after an accepted step.

use super::homotopy::{Homotopy, Point, dot, tangent};
use super::neutral::index;
use super::newton::{self, Settings, Workspace};
use super::path::correct_to;
use super::phase::{generic, kernel};
use super::system::System;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// Events are located to this share of the traced range (lambda runs over [0, 1]).
pub(super) const LOCATED: f64 = 1e-6;
/// The most bisections: each halves the bracket, so 60 take any step below 1e-18 of itself.
const MAX_BISECTIONS: usize = 60;

/// Factors the Jacobian of `next` again (the bisection factored others).
fn restore(system: &mut System, homotopy: &Homotopy, ws: &mut Workspace, next: &Point, report: &mut SolveReport) {
    homotopy.set(system, next.lambda);
    // The path checks the factors at its next step: a failure here is a failed step there.
    let _ = ws.linearize(system, &next.x, report);
}

/// The lambda of the fold crossed by the step of arclength `h` from `point` to `next`: within [`LOCATED`] of the fold, or `next.lambda` when a middle
/// point fails to converge.
#[allow(clippy::too_many_arguments)]
pub(super) fn fold(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, h): (&Point, f64),
    next: &Point,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
) -> f64 {
    let bracket = fold_bracket(system, homotopy, ws, (point, h), next.tl, settings, report, r);
    restore(system, homotopy, ws, next, report);
    bracket.lambda.unwrap_or(next.lambda)
}

/// Where a bisection of a fold's step ended ([`fold_bracket`]).
pub(super) struct FoldBracket {
    /// Whether the bracket narrowed to [`LOCATED`] (not: a middle point failed to converge,
    /// or its Jacobian or tangent failed).
    pub located: bool,
    /// The load factor of the last middle point corrected (None when none was).
    pub lambda: Option<f64>,
    /// The last middle point corrected on `point`'s side of the fold (before the turn): its
    /// load factor and state (None when none was).
    pub before: Option<(f64, Vec<State>)>,
}

/// Bisection on the arclength of the step `h` from `point` that crossed a fold (the tangent's
/// t_lambda past it `next_tl`): each middle point corrected on the bordered system to the
/// solve's tolerance and its tangent oriented along the path, the bracket kept around the
/// sign change of t_lambda until lambda moves over it by at most [`LOCATED`]. Leaves the
/// factors of the last middle point (the caller restores or uses them).
#[allow(clippy::too_many_arguments)]
pub(super) fn fold_bracket(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, h): (&Point, f64),
    next_tl: f64,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
) -> FoldBracket {
    let side = point.tl > 0.0;
    let (mut lo, mut hi) = (0.0, h);
    let mut slope = next_tl.abs().max(point.tl.abs());
    let mut bracket = FoldBracket {
        located: false,
        lambda: None,
        before: None,
    };
    for _ in 0..MAX_BISECTIONS {
        if (hi - lo) * slope <= 0.5 * LOCATED {
            bracket.located = true;
            break;
        }
        let m = 0.5 * (lo + hi);
        let located = correct_to(system, homotopy, ws, point, m, settings.tolerance, report, r, None);
        let Some((x, l, _)) = located else { break };
        homotopy.set(system, l);
        if !ws.linearize(system, &x, report) {
            break;
        }
        let Some((p, _)) = tangent(system, homotopy, ws, x, l, Some((&point.tx, point.tl)), report) else {
            break;
        };
        (bracket.lambda, slope) = (Some(l), p.tl.abs());
        if (p.tl > 0.0) == side {
            lo = m;
            bracket.before = Some((l, p.x));
        } else {
            hi = m;
        }
    }
    bracket
}

/// The lambda where the number of unstable directions changes from `before` (at `point`)
/// between `point` and `next` (no fold between them): the middle of a bracket [`LOCATED`]
/// wide, or of the last bracket reached when a middle point fails to converge.
pub(super) fn bifurcation(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, before): (&Point, Option<usize>),
    next: &Point,
    settings: &Settings,
    report: &mut SolveReport,
) -> f64 {
    let (lo, hi, _) = bisect_count(system, homotopy, ws, (point, before), next.lambda, settings, report);
    restore(system, homotopy, ws, next, report);
    0.5 * (lo + hi)
}

/// [`bifurcation`]'s bisection on the count, for the state: the states at the end of the
/// last bracket past the change (converged by Newton at its lambda) and that lambda, or None
/// when no middle point past it converged. The factors in `ws` are then those of the last
/// middle point.
pub(super) fn past_bifurcation(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, before): (&Point, Option<usize>),
    upper: f64,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(Vec<State>, f64)> {
    let (_, hi, past) = bisect_count(system, homotopy, ws, (point, before), upper, settings, report);
    past.map(|x| (x, hi))
}

/// Bisection between `point.lambda` and `upper` on the number of unstable directions, each
/// middle point converged by Newton from the tangent's prediction, until the bracket is
/// [`LOCATED`] wide or a middle point fails: the last bracket (lo, hi) and the states of
/// the last middle point found past the change, if any.
fn bisect_count(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, before): (&Point, Option<usize>),
    upper: f64,
    settings: &Settings,
    report: &mut SolveReport,
) -> (f64, f64, Option<Vec<State>>) {
    let (mut lo, mut hi) = (point.lambda, upper);
    let mut past = None;
    let mut x: Vec<State> = Vec::with_capacity(point.x.len());
    for _ in 0..MAX_BISECTIONS {
        if (hi - lo).abs() <= LOCATED || point.tl == 0.0 {
            break;
        }
        let m = 0.5 * (lo + hi);
        let step: Vec<f64> = point.tx.iter().map(|v| v * (m - point.lambda) / point.tl).collect();
        system.retract(&point.x, &step, 1.0, &mut x);
        homotopy.set(system, m);
        let (term, _) = newton::run(system, ws, &mut x, settings, report);
        if term != Termination::Converged || !ws.linearize(system, &x, report) {
            break;
        }
        if index(system, ws, &x, false, report) == before {
            lo = m;
        } else {
            (hi, past) = (m, Some(x.clone()));
        }
    }
    (lo, hi, past)
}

/// The most secant steps of [`critical`]; each is one Newton solve on the branch, which near
/// a straight column's bifurcation is linear in lambda and converges in one or two steps.
const SECANT_STEPS: usize = 8;

/// The signed eigenvalue of least magnitude of the Jacobian of `system` at `x` (factored
/// there on return): inverse iteration from a generic start gives its eigenvector z and
/// |J^-1 z| = 1 / |sigma|, the sign that of <z, J^-1 z>. None if a solve fails.
fn least_eigenvalue(system: &System, ws: &mut Workspace, x: &[State], report: &mut SolveReport) -> Option<f64> {
    if !ws.linearize(system, x, report) {
        return None;
    }
    let (z, growth) = kernel(ws, generic(ws.residual().len()), false, None)?;
    let w = ws.solve_again(&z)?;
    let sign = dot(&z, w).signum();
    (growth.is_finite() && growth > 0.0).then(|| sign / growth)
}

/// The bifurcation point crossed between `point` (on the branch before it) and the state
/// `beyond` at load factor `upper` past it, on `point`'s branch (a symmetric column's
/// straight states): the root of the least eigenvalue of the Jacobian along the branch, by
/// the Illinois variant of regula falsi on lambda, each point predicted along `point`'s
/// tangent and converged by Newton at fixed lambda. Stops when the bracket is [`LOCATED`]
/// wide or after [`SECANT_STEPS`]: the converged states at the last point and its lambda, or
/// None if the eigenvalue does not change sign or a Newton solve fails. The factors in `ws`
/// are those of the returned point.
pub(super) fn critical(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    (beyond, upper): (&[State], f64),
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(Vec<State>, f64)> {
    if point.tl == 0.0 {
        return None;
    }
    homotopy.set(system, upper);
    let s_hi = least_eigenvalue(system, ws, beyond, report)?;
    homotopy.set(system, point.lambda);
    let s_lo = least_eigenvalue(system, ws, &point.x, report)?;
    if s_lo.signum() == s_hi.signum() {
        return None;
    }
    let ((mut lo, mut f_lo), (mut hi, mut f_hi)) = ((point.lambda, s_lo), (upper, s_hi));
    let mut best = None;
    let mut last_side = 0;
    let mut x = Vec::with_capacity(point.x.len());
    for _ in 0..SECANT_STEPS {
        let m = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let step: Vec<f64> = point.tx.iter().map(|v| v * (m - point.lambda) / point.tl).collect();
        system.retract(&point.x, &step, 1.0, &mut x);
        homotopy.set(system, m);
        let (term, _) = newton::run(system, ws, &mut x, settings, report);
        if term != Termination::Converged {
            return None;
        }
        let f = least_eigenvalue(system, ws, &x, report)?;
        best = Some((x.clone(), m));
        // Illinois: the end kept twice running has its value halved.
        if f.signum() == f_lo.signum() {
            (lo, f_lo) = (m, f);
            if last_side == -1 {
                f_hi *= 0.5;
            }
            last_side = -1;
        } else {
            (hi, f_hi) = (m, f);
            if last_side == 1 {
                f_lo *= 0.5;
            }
            last_side = 1;
        }
        if (hi - lo).abs() <= LOCATED {
            break;
        }
    }
    best
}
