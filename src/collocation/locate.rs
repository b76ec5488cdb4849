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

use super::homotopy::{Homotopy, Point, tangent};
use super::newton::{self, Settings, Workspace};
use super::path::{correct_to, index};
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

/// The lambda of the fold crossed by the step of arclength `h` from `point` (`fl` its
/// dF/dlambda) to `next`: within [`LOCATED`] of the fold, or `next.lambda` when a middle
/// point fails to converge.
#[allow(clippy::too_many_arguments)]
pub(super) fn fold(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, fl, h): (&Point, &[f64], f64),
    next: &Point,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
) -> f64 {
    let side = point.tl > 0.0;
    let (mut lo, mut hi) = (0.0, h);
    let (mut lambda, mut slope) = (next.lambda, next.tl.abs().max(point.tl.abs()));
    for _ in 0..MAX_BISECTIONS {
        if (hi - lo) * slope <= 0.5 * LOCATED {
            break;
        }
        let m = 0.5 * (lo + hi);
        let located = correct_to(
            system,
            homotopy,
            ws,
            point,
            m,
            fl,
            false,
            settings.tolerance,
            report,
            r,
            None,
        );
        let Some((x, l, _)) = located else { break };
        homotopy.set(system, l);
        if !ws.linearize(system, &x, report) {
            break;
        }
        let Some((p, _)) = tangent(system, homotopy, ws, x, l, Some((&point.tx, point.tl)), report) else {
            break;
        };
        if (p.tl > 0.0) == side {
            lo = m;
        } else {
            hi = m;
        }
        (lambda, slope) = (l, p.tl.abs());
    }
    restore(system, homotopy, ws, next, report);
    lambda
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
    let (mut lo, mut hi) = (point.lambda, next.lambda);
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
        if index(system, ws, report) == before {
            lo = m;
        } else {
            hi = m;
        }
    }
    restore(system, homotopy, ws, next, report);
    0.5 * (lo + hi)
}
