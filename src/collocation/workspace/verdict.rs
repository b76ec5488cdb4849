//! The stability verdicts a [`Workspace`] holds for the Jacobian in its values: the
//! conjugate-point verdict (assessed once per Jacobian, with the roots left in the neutral
//! zone at the base) and the linearized dynamics' verdict with the factors held.

use super::{Workspace, all_finite};
use crate::collocation::stability::NeutralRoots;
use crate::collocation::system::System;
use crate::report::{SolveReport, Stability};
use crate::solution::State;
use std::time::Instant;

impl Workspace {
    /// The stability verdict of the Jacobian last factored (docs/stability.md), assessed
    /// by `assess` once per Jacobian: warm-started solves that converge by chord steps on
    /// an earlier, nearby Jacobian reuse its verdict at no cost.
    pub fn verdict(&mut self, assess: impl FnOnce(&[f64]) -> Stability) -> Stability {
        self.verdict_counted(|values| (assess(values), None))
    }

    /// [`Workspace::verdict`] for the conjugate-point test [`super::stability::count`], which
    /// also says where it left out a root in the neutral zone at the base, kept with the
    /// verdict ([`Workspace::neutral_root`]).
    pub(crate) fn verdict_counted(
        &mut self,
        assess: impl FnOnce(&[f64]) -> (Stability, Option<NeutralRoots>),
    ) -> Stability {
        if self.verdict.is_none() {
            let (verdict, neutral) = assess(&self.values);
            self.verdict = Some(verdict);
            self.neutral = neutral;
        }
        self.verdict.clone().unwrap_or_else(|| Stability::Unknown {
            reason: crate::report::NOT_ASSESSED.into(),
        })
    }

    /// The roots in the neutral zone at the base that the verdict held left out, if it did and
    /// nothing has decided them since ([`Workspace::settle_verdict`]).
    pub(crate) fn neutral_root(&self) -> Option<NeutralRoots> {
        self.verdict.as_ref().and(self.neutral)
    }

    /// Replaces the verdict held (of the Jacobian in the value buffer) by `verdict`, the
    /// decision on its roots in the neutral zone (module `neutral`).
    pub(crate) fn settle_verdict(&mut self, verdict: Stability) {
        self.verdict = Some(verdict);
        self.neutral = None;
    }

    /// The stability verdict of the Jacobian of `system` at `x`, assessed by `assess`, for a
    /// state the stored factors do not belong to (a solve that converged by chord steps on an
    /// earlier state's factors). The Jacobian is evaluated into the value buffer but not
    /// factored: the factors, and the residual of the last iterate, stay as they were (the
    /// error estimate and later chord steps use them); counted as a Jacobian evaluation.
    /// None for a non-finite Jacobian.
    pub fn verdict_at(
        &mut self,
        system: &System,
        x: &[State],
        report: &mut SolveReport,
        assess: impl FnOnce(&[f64]) -> (Stability, Option<NeutralRoots>),
    ) -> Option<Stability> {
        let t = Instant::now();
        let ok = self.verdict_jacobian(system, x);
        report.timings.assembly += t.elapsed();
        report.evaluations.jacobian += 1;
        report.evaluations.equations += system.rate_evaluations();
        self.verdict = None;
        self.neutral = None;
        self.unfactored = true;
        self.kept_ahead = false;
        if !ok || !all_finite(&self.values) {
            // The values belong to no state: nothing may take them (or columns) for one.
            self.drift = f64::INFINITY;
            self.forget_tension_rhs();
            return None;
        }
        self.drift = 0.0;
        Some(self.verdict_counted(assess))
    }

    /// The verdict already assessed of the Jacobian in the value buffer, when that Jacobian
    /// belongs to the last iterate ([`Workspace::jacobian_at_iterate`]) and the workspace holds
    /// factors (as [`super::equilibrium::stability_of`] requires before it reuses a verdict),
    /// and it left no root in the neutral zone at the base undecided ([`Workspace::neutral_root`]);
    /// None otherwise.
    pub(crate) fn held_verdict(&self) -> Option<Stability> {
        if self.factored && self.jacobian_at_iterate() && self.neutral.is_none() {
            self.verdict.clone()
        } else {
            None
        }
    }

    /// Keeps `verdict`, the linearized dynamics' verdict computed with the factors held
    /// (those of the Jacobian [`Workspace::linearize`] evaluated at the last iterate), for
    /// [`Workspace::dynamics_verdict`].
    pub(crate) fn keep_dynamics(&mut self, verdict: Stability) {
        self.dynamics = Some(verdict);
    }

    /// The verdict [`Workspace::keep_dynamics`] kept, while it still belongs to the last
    /// iterate: the factors are still those of the Jacobian evaluated there (a new
    /// factorization clears it) and no step has been taken since (the drift is zero; any
    /// step or a new Newton run makes it positive or infinite). The equilibrium choice and
    /// the end of a solve ask for the verdict of the same state; the second gets it here
    /// instead of a second linearization and Arnoldi run.
    pub(crate) fn dynamics_verdict(&self) -> Option<Stability> {
        if self.factors_at_iterate() {
            self.dynamics.clone()
        } else {
            None
        }
    }
}
