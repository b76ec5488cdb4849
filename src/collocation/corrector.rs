//! The corrector of the pseudo-arclength continuation (`collocation/path.rs`): one
//! predictor-corrector step along a path's tangent, converged on the hyperplane normal to
//! it by a Newton step at the predicted point and chord steps on its factors (docs/numerics.md,
//! "Corrector"), refreshing the Jacobian when they contract too slowly; on a family's branch with its phase condition as well (module `phase`); and the
//! polish of a point at its own lambda to the solve's tolerance.

use super::homotopy::{Homotopy, Point, dot, f_lambda, max_norm, residual, tangent};
use super::newton::{self, Settings, Workspace};
use super::phase::Phase;
use super::system::System;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// The most corrector iterations of one step.
const MAX_CORRECTOR: usize = 8;
/// A chord corrector step must at least halve the residual, or the Jacobian is refreshed.
const CHORD_RATIO: f64 = 0.5;
/// A chord corrector that contracts faster than [`CHORD_RATIO`] is still refreshed when, at
/// the contraction it shows, it would need more than this many further steps to reach the
/// tolerance (docs/numerics.md, "Corrector"): a steady contraction of 0.35 per step, as
/// near the turn of a slightly imperfect column, otherwise runs to 7 chord steps where a
/// fresh Jacobian converges in 1 or 2.
const CHORD_STEPS_LEFT: i32 = 3;
/// Points on the way to lambda = 1 are guides, not answers: they are corrected to this
/// scaled residual (a relative state error of about 1e-6), and only the landing at
/// lambda = 1 is converged to the solve's tolerance.
pub(super) const PATH_TOLERANCE: f64 = 1e-6;

/// One predictor-corrector step of length `h` from `point`, its first corrector step a Newton
/// step at the predicted point (the Jacobian and dF/dlambda evaluated there; the chord on the
/// factors at `point` contracts as O(h), on these as O(h^2)). Returns the converged states,
/// their lambda and the corrector iterations, or None (the step is to be shortened). With
/// a `phase`, the step also keeps the phase condition relative to `point` (module `phase`).
#[allow(clippy::too_many_arguments)]
pub(super) fn correct(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    h: f64,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
    phase: Option<&Phase>,
) -> Option<(Vec<State>, f64, usize)> {
    let tolerance = PATH_TOLERANCE.max(settings.tolerance);
    correct_to(system, homotopy, ws, point, h, tolerance, report, r, phase)
}

/// [`correct`], converged to the scaled residual `tolerance` (a located event's point is
/// converged as tightly as a solve, not as a guide).
#[allow(clippy::too_many_arguments)]
pub(super) fn correct_to(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    h: f64,
    tolerance: f64,
    report: &mut SolveReport,
    r: &mut [f64],
    phase: Option<&Phase>,
) -> Option<(Vec<State>, f64, usize)> {
    let n = point.tx.len();
    let nf = n as f64;
    let step: Vec<f64> = point.tx.iter().map(|v| v * h).collect();
    let mut x = Vec::with_capacity(point.x.len());
    system.retract(&point.x, &step, 1.0, &mut x);
    let lambda_pred = point.lambda + h * point.tl;
    let mut lambda = lambda_pred;
    // Displacement from the predicted point, in the scaled unknowns.
    let mut d = vec![0.0; n];
    // The first step is a Newton step at the predicted point: the chord on the last point's
    // factors contracts as O(h), on the prediction's as O(h^2) (docs/numerics.md, "Corrector").
    homotopy.set(system, lambda);
    if !ws.linearize(system, &x, report) {
        return None;
    }
    let mut fl = f_lambda(system, homotopy, &x, lambda, report)?;
    let mut fresh = true;
    let mut norm = f64::INFINITY;
    let mut next = Vec::with_capacity(x.len());
    // b = -J^-1 F_lambda belongs to the factors: solved once per factorization, not per
    // corrector step. The other buffers are allocated once per step.
    let solve_b = |ws: &mut Workspace, fl: &[f64], b: &mut Vec<f64>| -> Option<()> {
        let rhs: Vec<f64> = fl.iter().map(|v| -v).collect();
        b.clear();
        b.extend_from_slice(ws.solve_again(&rhs)?);
        Some(())
    };
    let mut b = Vec::with_capacity(n);
    solve_b(ws, &fl, &mut b)?;
    // With a phase condition: e = J^-1 (-psi) for the same factors, the unknown mu, and the
    // phase row's value at the prediction, <c, h t_x> / n.
    let mut e = match phase {
        Some(p) => p.e(ws)?,
        None => Vec::new(),
    };
    let mut mu = 0.0;
    let c_step = phase.map_or(0.0, |p| h * dot(&p.c, &point.tx) / nf);
    let (mut rhs, mut delta) = (vec![0.0; n], vec![0.0; n]);
    for iteration in 1..=MAX_CORRECTOR {
        if !residual(system, homotopy, &x, lambda, r, report) {
            return None;
        }
        if let Some(p) = phase {
            r.iter_mut().zip(&p.psi).for_each(|(r, s)| *r += mu * s);
        }
        let new_norm = max_norm(r);
        if new_norm <= tolerance && iteration > 1 {
            return Some((x, lambda, iteration - 1));
        }
        // The residual after k more chord steps at the contraction theta seen is about
        // theta^k times the present one.
        let theta = new_norm / norm;
        if iteration > 1 && (theta > CHORD_RATIO || theta.powi(CHORD_STEPS_LEFT) * new_norm > tolerance) {
            // The chord contracts too slowly: refresh the Jacobian here.
            if !ws.linearize(system, &x, report) {
                return None;
            }
            fl = f_lambda(system, homotopy, &x, lambda, report)?;
            solve_b(ws, &fl, &mut b)?;
            if let Some(p) = phase {
                e = p.e(ws)?;
            }
            fresh = true;
            if new_norm > 2.0 * norm {
                return None;
            }
        }
        norm = new_norm;
        report.iterations += 1;
        if fresh {
            report.newton_steps += 1;
        } else {
            report.chord_steps += 1;
        }
        fresh = false;
        rhs.iter_mut().zip(r.iter()).for_each(|(q, v)| *q = -v);
        let a = ws.solve_again(&rhs)?;
        let g = (dot(&point.tx, &d) + dot(&point.tx, a)) / nf + point.tl * (lambda - lambda_pred);
        let denominator = dot(&point.tx, &b) / nf + point.tl;
        let (dl, dm) = match phase {
            None => {
                if denominator.abs() < 1e-14 {
                    return None;
                }
                (-g / denominator, 0.0)
            }
            // The two border rows: [<t, b>/n + t_l, <t, e>/n; <c, b>/n, <c, e>/n] (dl, dmu) =
            // -(g, <c, d + a>/n + <c, h t_x>/n), by Cramer's rule.
            Some(p) => {
                let (te, cb, ce) = (dot(&point.tx, &e) / nf, dot(&p.c, &b) / nf, dot(&p.c, &e) / nf);
                let q = (dot(&p.c, &d) + dot(&p.c, a)) / nf + c_step;
                let det = denominator * ce - te * cb;
                if !det.is_finite() || det == 0.0 {
                    return None;
                }
                ((-g * ce + q * te) / det, (-q * denominator + g * cb) / det)
            }
        };
        delta
            .iter_mut()
            .zip(a.iter().zip(&b))
            .for_each(|(s, (a, b))| *s = a + dl * b);
        if dm != 0.0 {
            delta.iter_mut().zip(&e).for_each(|(s, e)| *s += dm * e);
        }
        mu += dm;
        if !delta.iter().all(|v| v.is_finite()) {
            return None;
        }
        system.retract(&x, &delta, 1.0, &mut next);
        std::mem::swap(&mut x, &mut next);
        d.iter_mut().zip(&delta).for_each(|(d, s)| *d += s);
        lambda += dl;
    }
    None
}

/// `point` converged to the solve's tolerance at its lambda (a parameter's path only: Newton
/// solves F = 0, not a Newton homotopy's residual), with its tangent oriented as before.
pub(super) fn polish(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    settings: &Settings,
    report: &mut SolveReport,
    phase: &mut Option<Phase>,
) -> Option<(Point, Vec<f64>)> {
    if !matches!(homotopy, Homotopy::Parameter { .. }) {
        return None;
    }
    homotopy.set(system, point.lambda);
    let x = match phase.as_ref() {
        // On a family's branch, with its phase condition at fixed lambda (the hyperplane of
        // the tangent (0, 1) through the point): Newton alone has the family's singular
        // Jacobian.
        Some(p) => {
            let at = Point {
                x: point.x.clone(),
                lambda: point.lambda,
                tx: vec![0.0; point.tx.len()],
                tl: 1.0,
            };
            let mut r = vec![0.0; system.unknowns()];
            let tolerance = settings.tolerance;
            let (x, _, _) = correct_to(system, homotopy, ws, &at, 0.0, tolerance, report, &mut r, Some(p))?;
            x
        }
        None => {
            let mut x = point.x.clone();
            let (term, _) = newton::run(system, ws, &mut x, settings, report);
            if term != Termination::Converged {
                return None;
            }
            x
        }
    };
    if !ws.linearize(system, &x, report) {
        return None;
    }
    let previous = Some((point.tx.as_slice(), point.tl));
    match phase.take() {
        Some(p) => {
            *phase = Some(p.refreshed(ws)?);
            phase
                .as_ref()?
                .tangent(system, homotopy, ws, x, point.lambda, previous, report)
        }
        None => tangent(system, homotopy, ws, x, point.lambda, previous, report),
    }
}
