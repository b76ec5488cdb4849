//! The order-6 answer at tight tolerances (docs/numerics.md, "The order-6 answer"): where
//! the order-4 solution x4 misses a tight tolerance, the deferred correction that estimates
//! its error is carried out, and the corrected, order-6 solution x6 is returned with an
//! order-8 estimate of its own error, so that the mesh needs the intervals order 6 needs.
//!
//! x6 solves phi4(x6) = phi4(x4) - phi6(x4) (the defect of the order-6 residual at x4): by
//! [`CORRECTIONS`] chord steps with Newton's factors from x4. Its error is estimated as the
//! order-4 one is, one order up: phi8(x6) = J (x6 - x*) + O(h^8) + O(|x6 - x*|^2), so one
//! solve J e = -phi8(x6) with the same factors gives e = x* - x6 (the total error of the
//! returned state, chord iteration included), and the intervals' rows of phi8(x6), of size
//! C h^7, are the local errors the next mesh equidistributes.

use super::estimate::{self, Correction};
use super::newton::Workspace;
use super::order8;
use super::refine;
use super::system::System;
use super::unknowns;
use crate::error::Result;
use crate::report::{ErrorEstimate, SolveReport};
use crate::solution::State;
use nalgebra::Vector6;

/// Tolerances (relative to L) at or below which an order-4 solution that misses the
/// tolerance is replaced by the order-6 one: where the order-4 mesh grows past a few
/// hundred intervals (S and H at 1e-9 L and below need 2 to 10 times fewer intervals and
/// 1.7 to 5 times fewer instructions; docs/benchmarks.md, "Tight tolerances"). The default
/// 1e-7 keeps the order-4 answer (docs/numerics.md, "The order-6 answer", says why).
pub(crate) const ORDER6_BELOW: f64 = 1e-8;

/// The factor on the order-8 estimate of the order-6 error. That estimate is
/// asymptotically exact, but its own error (the order-8 scheme's truncation, O(h^2)
/// relative) is not negligible on the coarse meshes order 6 runs on: the true tip errors
/// measured up to 1.11 times it on case S's 32 intervals (case H 1.00, the elastica 1.03,
/// 60 random robots at 1e-10 L at most 1.02 where a 32x finer reference resolves the
/// error); 1.25 keeps those below the reported estimate. On 600 random robots the true
/// error beyond the reference's uncertainty is at most 0.86 of the reported estimate,
/// since the stages keep their strains' low part (up to 1.97 before, which no factor
/// covered: a rounding floor of the order-6 answer, docs/numerics.md, "Why the estimate was
/// low on some random robots").
pub const SAFETY: f64 = 1.25;

/// Rounding, relative to L (and in rad): added to the order-6 estimate, which sees
/// truncation only. Solutions of cases S and H on 2048 and 4096 intervals agree to
/// 1.7e-13 L, so true errors below that are not resolved by any reference; 4e-13 (about
/// 1800 eps) covers it with the same room as [`SAFETY`]. Tolerances below it cannot be
/// met. The floors of 3e-12 to 2e-11 L some random robots (L / r of 670 to 4700) had in the
/// order-6 answer were the stages' strains rounded near 1 (a force of EA eps), which the
/// order-6 answer and its estimate now keep (`collocation::stage`; docs/numerics.md, "Why the
/// estimate was low on some random robots").
pub const ROUNDING: f64 = 4e-13;

/// Chord steps on phi4(x) = phi4(x4) - phi6(x4) from x4 with Newton's factors: with
/// factors a step old, one step leaves an error of about 1e-3 of the correction (the order-6
/// solution's error then floors at that fraction of the order-4 one), two give order 6.
const CORRECTIONS: usize = 2;

/// The error estimate of the converged order-4 solution `x` on `system` (its residual
/// `phi4`, the node rates of eq. 13 there when known, the factors in `ws`), and, when `tolerance` (relative to L) is at most
/// [`ORDER6_BELOW`] and that estimate misses it, `x` replaced by the order-6 solution with
/// its order-8 estimate. `None` when no estimate exists (a singular Jacobian, a model
/// breakdown at a stage). A failed order-6 attempt, or one whose estimate misses the
/// tolerance by more than the order-4 one, keeps the order-4 answer; a returned one adds
/// the steps taken to the workspace's drift (its Jacobian is then not the answer's, and
/// the stability verdict evaluates one at x6).
pub(crate) fn estimate(
    system: &System,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    phi4: &[f64],
    node_rates: Option<Vec<nalgebra::Vector6<f64>>>,
    tolerance: Option<f64>,
    report: &mut SolveReport,
) -> Option<Correction> {
    let order4 = estimate::estimate_with(system, ws, x, Some(phi4), node_rates)
        .ok()
        .flatten()?;
    let length = system.model.robot.length();
    let Some(tol) = tolerance.filter(|&tol| {
        tol <= ORDER6_BELOW && system.friction.is_none() && !refine::meets(&order4.estimate, tol, length)
    }) else {
        return Some(order4);
    };
    // The order-6 answer where its estimate is the smaller (on a mesh too coarse for the
    // expansion the correction rests on, it need not be).
    let miss = |e: &ErrorEstimate| (e.tip_position / (tol * length)).max(e.tip_rotation / tol);
    // The order-6 answer's defect is evaluated again with the stages' strains kept below
    // their last place (super::stage), not taken from the estimate's.
    match order6(system, ws, x, &order4.node_rates, report) {
        Ok(Some((x6, order6, moved))) if miss(&order6.estimate) < miss(&order4.estimate) => {
            *x = x6;
            // The Jacobian the workspace holds is now that far from the answer.
            ws.drift += moved;
            Some(order6)
        }
        _ => Some(order4),
    }
}

/// The order-6 solution on `system`'s mesh from the converged order-4 solution `x` and its
/// estimated error (the reported one: 1.25 times the order-8 estimate plus 4e-13 L of
/// rounding, docs/numerics.md "The order-6 answer"), whatever the tolerance: what the answer at a tight tolerance is made of,
/// for tests and convergence studies. Uses the factors in `ws` when it holds some (Newton's,
/// as a solve does), else factors the Jacobian at `x`. `None` when a linear solve fails.
///
/// # Errors
/// A model breakdown at a visited state.
pub fn corrected(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    report: &mut SolveReport,
) -> Result<Option<(Vec<State>, ErrorEstimate)>> {
    if !ws.has_factors() && !ws.linearize(system, x, report) {
        return Ok(None);
    }
    let mut phi4 = vec![0.0; system.unknowns()];
    let mut rates = vec![Vector6::zeros(); x.len()];
    if !system.residual_rates(x, &mut phi4, &mut rates)? {
        return Ok(None);
    }
    Ok(order6(system, ws, x, &rates, report)?.map(|(x6, c, moved)| {
        ws.drift += moved;
        (x6, c.estimate)
    }))
}

/// The order-6 solution from the order-4 one `x4` (node rates of eq. 13 there `rates`), its
/// order-8 estimate and the sum of the max-norms of the steps from x4 (scaled unknowns);
/// `None` when a solve is not finite. The defect phi4(x4) - phi6(x4) and the chord steps'
/// order-4 residuals are evaluated with the stages' strains kept below their last place
/// ([`System::residual_split`], [`System::order6_residual_split`]; docs/numerics.md, "Why
/// the estimate was low on some random robots").
///
/// # Errors
/// A model breakdown at a visited state.
fn order6(
    system: &System,
    ws: &mut Workspace,
    x4: &[State],
    rates: &[Vector6<f64>],
    report: &mut SolveReport,
) -> Result<Option<(Vec<State>, Correction, f64)>> {
    let n = system.unknowns();
    let length = system.model.robot.length();
    let mut x = x4.to_vec();
    let mut next = Vec::with_capacity(x.len());
    let mut residual = vec![0.0; n];
    let mut defect = vec![0.0; n];
    system.residual_split(x4, &mut residual)?;
    system.order6_residual_split(x4, &mut defect, rates)?;
    count(system, report);
    for (d, r) in defect.iter_mut().zip(&residual) {
        *d = r - *d;
    }
    let mut rhs = vec![0.0; n];
    let mut moved = 0.0;
    for step in 0..CORRECTIONS {
        if step > 0 {
            system.residual_split(&x, &mut residual)?;
            count(system, report);
        }
        for ((r, d), f) in rhs.iter_mut().zip(&defect).zip(&residual) {
            *r = d - f;
        }
        let Some(dx) = ws.solve_again(&rhs) else {
            return Ok(None);
        };
        moved += dx.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
        unknowns::retract(&x, dx, 1.0, length, &mut next);
        std::mem::swap(&mut x, &mut next);
    }
    let mut local = vec![0.0; x.len() - 1];
    let mut rates = vec![Vector6::zeros(); x.len()];
    order8::residual(system, &x, &mut rhs, &mut local, &mut rates)?;
    for r in rhs.iter_mut() {
        *r = -*r;
    }
    let Some(e) = ws.solve_again(&rhs) else {
        return Ok(None);
    };
    let mut correction = estimate::correction(e, x.len(), length, local, rates);
    correction.estimate.order = 6;
    let estimate = &mut correction.estimate;
    estimate.tip_position = SAFETY * estimate.tip_position + ROUNDING * length;
    estimate.tip_rotation = SAFETY * estimate.tip_rotation + ROUNDING;
    estimate.backbone_max = SAFETY * estimate.backbone_max + ROUNDING * length;
    Ok(Some((x, correction, moved)))
}

/// Counts one residual evaluation of `system` in `report`.
fn count(system: &System, report: &mut SolveReport) {
    report.evaluations.residual += 1;
    report.evaluations.equations += system.rate_evaluations();
}
