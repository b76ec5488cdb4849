//! What a workspace keeps besides Newton's buffers: the buffers of the systems built on its
//! mesh (sites among them) and of the linearizations for sensitivities, and the tension
//! columns' right-hand sides its stability verdict forms with the Jacobian for a
//! [`crate::Solver`] that keeps them (docs/sensitivity.md, "Tension columns formed with the
//! verdict's Jacobian").

use super::Workspace;
use crate::collocation::residual::IntervalFactors;
use crate::collocation::system::System;
use crate::mesh::Mesh;
use crate::model::equations::Model;
use crate::report::SolveReport;
use crate::solution::State;

impl Workspace {
    /// A buffer of `len` values: one [`Workspace::give_buffer`] kept, its contents as they
    /// were (the caller writes every entry it reads), else a new zeroed one.
    pub(crate) fn take_buffer(&mut self, len: usize) -> Vec<f64> {
        match self.buffers.iter().position(|b| b.len() == len) {
            Some(at) => self.buffers.swap_remove(at),
            None => vec![0.0; len],
        }
    }

    /// Keeps `buffer` for a later [`Workspace::take_buffer`] (at most eight are kept).
    pub(crate) fn give_buffer(&mut self, buffer: Vec<f64>) {
        if self.buffers.len() < 8 {
            self.buffers.push(buffer);
        }
    }

    /// Makes [`Workspace::verdict_at`] form the tension columns' right-hand sides with the
    /// Jacobian (`on`) or not: what [`crate::Solver::keep_tension_columns`] asks for.
    pub(crate) fn keep_tension_columns(&mut self, on: bool) {
        self.keep_tensions = on;
    }

    /// Whether [`Workspace::verdict_at`] forms the tension columns' right-hand sides.
    pub(crate) fn keeps_tension_columns(&self) -> bool {
        self.keep_tensions
    }

    /// -dF/dtau_i of every tendon at the last iterate (column-major, `len` values), when
    /// the last [`Workspace::verdict_at`] formed them with the Jacobian still in the value
    /// buffer, unfactored, and no step was taken since; else None.
    pub(crate) fn take_tension_rhs(&mut self, len: usize) -> Option<Vec<f64>> {
        let columns = self.tension_rhs.take()?;
        if self.unfactored && self.drift == 0.0 && columns.len() == len {
            Some(columns)
        } else {
            self.give_buffer(columns);
            None
        }
    }

    /// Drops the tension columns' right-hand sides the last verdict formed (the value
    /// buffer gets another Jacobian), keeping their buffer.
    pub(crate) fn forget_tension_rhs(&mut self) {
        if let Some(columns) = self.tension_rhs.take() {
            self.give_buffer(columns);
        }
    }

    /// The system of a copy of `model` on `mesh` (this workspace's mesh), built in the
    /// buffers the last system on it left ([`Workspace::keep_system`]).
    pub(crate) fn system<'a>(&mut self, model: &Model<'a>, mesh: Mesh) -> System<'a> {
        System::with_buffers(model, mesh, std::mem::take(&mut self.system))
    }

    /// Whether the sites the last system on this workspace's mesh left can be `model`'s on
    /// `mesh` ([`SystemBuffers::has_sites_of`]).
    pub(crate) fn has_sites_of(&self, model: &Model, mesh: &Mesh) -> bool {
        self.system.has_sites_of(model, mesh)
    }

    /// The system of `model` on `mesh` (this workspace's mesh) with the sites the last
    /// system on it left, which must be `model`'s ([`Workspace::has_sites_of`]; the caller
    /// vouches that its robot is that system's).
    pub(crate) fn kept_system<'a>(&mut self, model: Model<'a>, mesh: Mesh) -> System<'a> {
        System::with_kept_sites(model, mesh, std::mem::take(&mut self.system))
    }

    /// Keeps the buffers of `system` (built on this workspace's mesh) for the next
    /// [`Workspace::system`]; returns its mesh.
    pub(crate) fn keep_system(&mut self, system: System) -> Mesh {
        let (mesh, buffers) = system.into_parts();
        self.system = buffers;
        mesh
    }

    /// Marks the value buffer as holding a Jacobian Newton evaluated at a trial point in
    /// place of its residual (`newton::run_ahead`), not factored (the factors stay an
    /// earlier Jacobian's), as [`Workspace::verdict_at`] leaves it: its verdict not yet
    /// assessed, and belonging to no iterate until Newton accepts that point (which sets
    /// the drift to zero when `finite`).
    pub(crate) fn evaluated_ahead(&mut self) {
        self.verdict = None;
        self.neutral = None;
        self.unfactored = true;
        self.drift = f64::INFINITY;
    }

    /// The Jacobian of `system` at the trial point into the value buffer, the residual and
    /// node rates there as a residual evaluation writes them ([`System::jacobian_rates`]):
    /// Newton's evaluation ahead of a verdict. With `keep` (a verdict of the linearized
    /// dynamics, frictionless) it keeps eq. 13's factored matrices at every interval's
    /// points for the mass, as [`Workspace::linearize_keeping`] does
    /// ([`System::jacobian_rates_keeping`], [`Workspace::kept_at_iterate`]); else it forms the
    /// tension columns' right-hand sides when this workspace keeps them (as
    /// [`Workspace::verdict_jacobian`]; with friction, the backbone rows' Jacobian alone,
    /// whose links' evaluations the border reads). Returns whether the rates were written.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn jacobian_ahead(&mut self, system: &System, keep: bool) -> crate::error::Result<bool> {
        self.forget_tension_rhs();
        self.kept_ahead = false;
        if keep {
            let links = self.trial.len() - 1;
            if self.kept.len() != links {
                self.kept = vec![IntervalFactors::identity(); links];
            }
            system.jacobian_rates_keeping(
                &self.trial,
                &mut self.trial_residual,
                &mut self.values,
                &mut self.trial_rates,
                &mut self.kept,
            )?;
            self.kept_ahead = true;
            return Ok(true);
        }
        let plain = system.friction.is_none() && !system.model.robot.has_displacement_inputs();
        if !(self.keep_tensions && plain) {
            return system.jacobian_rates(
                &self.trial,
                &mut self.trial_residual,
                &mut self.values,
                &mut self.trial_rates,
            );
        }
        let mut columns = self.take_buffer(system.unknowns() * system.model.robot.tendons.len());
        let result = system.jacobian_rates_and_tensions(
            &self.trial,
            &mut self.trial_residual,
            &mut self.values,
            &mut self.trial_rates,
            &mut columns,
            &mut self.tension_sink,
        );
        match result {
            Ok(()) => {
                self.tension_rhs = Some(columns);
                Ok(true)
            }
            Err(e) => {
                self.give_buffer(columns);
                Err(e)
            }
        }
    }

    /// Whether the value buffer holds the Jacobian Newton evaluated at the last iterate in
    /// place of its residual there, keeping eq. 13's factored matrices
    /// ([`Workspace::jacobian_ahead`] with `keep`, then [`Workspace::kept`]), not yet
    /// factored: what the linearized dynamics' verdict needs there but the factors.
    pub(crate) fn kept_at_iterate(&self) -> bool {
        self.kept_ahead && self.unfactored && self.drift == 0.0
    }

    /// Factors the Jacobian in the value buffer ([`Workspace::kept_at_iterate`]), keeping
    /// the residual of the iterate and its node rates (the step solved on the way is not
    /// read): then [`Workspace::factors_at_iterate`] holds, as after
    /// [`Workspace::linearize_keeping`] there. False for a zero pivot, or without such a
    /// Jacobian.
    pub(crate) fn factor_kept(&mut self, report: &mut SolveReport) -> bool {
        if !self.kept_at_iterate() {
            return false;
        }
        self.solve(report)
    }

    /// The Jacobian of `system` at `x` into the value buffer and the residual there into
    /// the trial residual, for [`Workspace::verdict_at`], with the tension columns'
    /// right-hand sides when this workspace keeps them and a Jacobian in the tensions would
    /// read them (no friction, no displacement-controlled tendon:
    /// `Sensitivity::with_workspace`); false on a model breakdown.
    pub(super) fn verdict_jacobian(&mut self, system: &System, x: &[State]) -> bool {
        self.forget_tension_rhs();
        let plain = system.friction.is_none() && !system.model.robot.has_displacement_inputs();
        if !(self.keep_tensions && plain) {
            return system.jacobian(x, &mut self.trial_residual, &mut self.values).is_ok();
        }
        let mut columns = self.take_buffer(system.unknowns() * system.model.robot.tendons.len());
        let ok = system
            .jacobian_and_tensions(
                x,
                &mut self.trial_residual,
                &mut self.values,
                &mut columns,
                &mut self.tension_sink,
            )
            .is_ok();
        if ok {
            self.tension_rhs = Some(columns);
        } else {
            self.give_buffer(columns);
        }
        ok
    }
}
