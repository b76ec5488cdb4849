//! The Jacobian evaluated where Newton would evaluate the residual ([`System::jacobian_rates`]):
//! the same residual and node rates bit for bit, for the Jacobian at a direct solve's answer
//! (docs/numerics.md, "The Jacobian at the answer, evaluated by Newton").

use super::System;
use crate::collocation::residual::{self, Delta, IntervalFactors};
use crate::collocation::unknowns::link_row;
use crate::error::Result;
use crate::solution::State;
use nalgebra::Vector6;

impl System<'_> {
    /// [`System::jacobian`] whose residual is bit for bit [`System::residual_rates`]'s, with
    /// the node rates written as that writes them ([`residual::interval_jacobian_as_residual`];
    /// the jump rows evaluated again in f64):
    /// a Jacobian evaluated where Newton would evaluate the residual. Returns whether `rates`
    /// were written: not for tendons with friction, whose residual gives none (its interval
    /// rows and the links' evaluations the capstan rows are read from are the residual's
    /// bit for bit: `friction::interval` forms them with the same arithmetic with or
    /// without derivatives).
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn jacobian_rates(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        rates: &mut [Vector6<f64>],
    ) -> Result<bool> {
        if self.friction.is_some() {
            self.jacobian(x, out, values)?;
            self.jump_residual_rows(x, out)?;
            return Ok(false);
        }
        self.jacobian_with(x, out, values, None, None, Some(rates))?;
        self.jump_residual_rows(x, out)?;
        Ok(true)
    }

    /// [`System::jacobian_rates`] that also keeps eq. 13's factored matrix at every
    /// interval's points in `kept` (one per link), as [`System::jacobian_keeping`] does: the
    /// Jacobian at a direct solve's answer whose verdict is the linearized dynamics', whose
    /// mass solves with those matrices. Frictionless systems only.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn jacobian_rates_keeping(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        rates: &mut [Vector6<f64>],
        kept: &mut [IntervalFactors],
    ) -> Result<()> {
        debug_assert!(self.friction.is_none(), "no factored matrices kept with friction");
        self.jacobian_with(x, out, values, Some(kept), None, Some(rates))?;
        self.jump_residual_rows(x, out)
    }

    /// The jump rows of the residual at `x` into `out`, as [`System::residual_rates`] writes
    /// them: their dual numbers' values in a Jacobian can differ from the f64 evaluation in
    /// the last bits. (The base and tip rows a Jacobian writes are the f64 residual's
    /// already: [`super::end_rows`].)
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(super) fn jump_residual_rows(&self, x: &[State], out: &mut [f64]) -> Result<()> {
        let z = Delta::<f64>::zeros();
        let links = x.len() - 1;
        for k in (0..links).filter(|&k| self.interval_sites[k].is_none()) {
            let sites = (&self.node_sites[k], &self.node_sites[k + 1]);
            let r = residual::jump(&self.model, sites, &x[k], &x[k + 1], &z, &z)?;
            out[link_row(k)..link_row(k + 1)].copy_from_slice(r.as_slice());
        }
        Ok(())
    }
}
