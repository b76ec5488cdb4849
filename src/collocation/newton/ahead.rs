//! Newton's evaluation of the Jacobian at the trial point its step test predicts to be the
//! last, in place of the residual there, for a verdict that needs the Jacobian at the
//! answer (docs/numerics.md, "The Jacobian at the answer, evaluated by Newton"): the entry
//! points [`run_ahead`] and [`run_bordered_ahead`] and the evaluation itself.

use super::{Border, NoBorder, Point, Settings, Workspace, evaluate_trial, run_with};
use crate::collocation::system::System;
use crate::report::{SolveReport, Termination};
use crate::solution::State;
use std::time::Instant;

/// [`evaluate_trial`] by a Jacobian evaluation at the trial point into the value buffer
/// ([`System::jacobian_rates`]: the residual and node rates bit for bit those of the
/// residual evaluation; with `keep`, eq. 13's factored matrices kept for the mass of the
/// linearized dynamics), counted as a Jacobian evaluation, not factored
/// ([`Workspace::evaluated_ahead`]). Returns whether it succeeded and whether the values
/// are finite; a breakdown of the Jacobian alone falls back to [`evaluate_trial`].
pub(super) fn evaluate_trial_ahead<B: Border>(
    border: &mut B,
    ws: &mut Workspace,
    keep: bool,
    report: &mut SolveReport,
) -> (bool, bool) {
    let t = Instant::now();
    let result = border.on(Point::Trial, |system| {
        report.evaluations.equations += system.rate_evaluations();
        ws.jacobian_ahead(system, keep)
    });
    report.timings.assembly += t.elapsed();
    report.evaluations.jacobian += 1;
    ws.evaluated_ahead();
    match result {
        Ok(filled) => {
            ws.trial_rates_valid = filled;
            border.rows(Point::Trial, &ws.trial);
            (true, crate::collocation::workspace::all_finite(&ws.values))
        }
        Err(_) => (evaluate_trial(border, ws, report), false),
    }
}

/// [`run`](super::run) for a state whose stability verdict follows from the Jacobian at the answer
/// ([`crate::collocation::equilibrium`]'s direct solve, no friction: conservative loads, with the tension
/// columns when the workspace keeps them, or loads that are not conservative, whose
/// linearized dynamics also read eq. 13's factored matrices there, which it keeps;
/// [`Workspace::jacobian_ahead`]): a trial point that the step-based stopping test already
/// predicts to be the last (the error left after its step below [`STEP_TOLERANCE`](super::STEP_TOLERANCE), and the
/// Jacobian held too far from it for the verdict to take) gets the Jacobian evaluated there
/// instead of the residual, which gives the same residual and node rates bit for bit; the
/// verdict then takes that Jacobian instead of evaluating it again (docs/numerics.md, "The
/// Jacobian at the answer, evaluated by Newton"). Every decision and iterate is [`run`](super::run)'s.
pub(crate) fn run_ahead(
    system: &System,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> (Termination, usize) {
    let keep = crate::collocation::stability::non_conservative(&system.model).is_some();
    run_with(&mut NoBorder(system), ws, x, settings, report, Some(keep))
}

/// [`run_bordered`](super::run_bordered) for a state whose stability verdict factors the bordered Jacobian at the
/// answer (a full-slip solve with friction, `collocation/friction`): a trial point predicted
/// to be the last gets the collocation Jacobian evaluated there in place of the residual, as
/// in [`run_ahead`] (the same residual bits, and the links' evaluations the border reads its
/// rows and blocks from), left unfactored for the verdict ([`Workspace::evaluated_at_solution`]
/// with the values unfactored; the border's factors stay those of Newton's last Jacobian).
/// Every decision and iterate is [`run_bordered`](super::run_bordered)'s.
pub(crate) fn run_bordered_ahead<B: Border>(
    border: &mut B,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> (Termination, usize) {
    run_with(border, ws, x, settings, report, Some(false))
}
