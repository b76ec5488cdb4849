//! The buffers and factors Newton keeps for one mesh ([`Workspace`]): the Jacobian values,
//! residuals, steps and the linear solver's factors, reused across iterations, load steps
//! and solves on the same mesh, with the stability verdict of the Jacobian held and how far
//! the iterate has moved from it.

use super::linear::{Linear, LinearSolver};
use super::newton::STEP_TOLERANCE;
use super::residual::IntervalFactors;
use super::stability::NeutralRoots;
use super::system::{System, SystemBuffers, TensionSink};
use super::unknowns::nonzeros;
use crate::mesh::Mesh;
use crate::report::{SolveReport, Stability};
use crate::simd::avx2_fma;
use crate::solution::State;
use nalgebra::Vector6;
use std::cell::RefCell;
use std::time::Instant;

mod kept;
mod verdict;

/// How many finished workspaces a thread keeps for later solves ([`keep`], [`spare`]): the
/// meshes of one error-controlled solve (H takes two) and of a neighbouring robot's, so
/// that a batch of stateless solves skips the setup; the memory stays bounded (each is
/// about 3 kB per interval).
const SPARE: usize = 4;

thread_local! {
    /// Workspaces that solves finished with, least recently kept first, with their mesh and
    /// linear solver.
    static KEPT: RefCell<Vec<(Mesh, LinearSolver, Workspace)>> = const { RefCell::new(Vec::new()) };
}

/// Whether every entry of `values` is finite, checked in fixed-width chunks that the
/// compiler vectorizes (the Jacobian's check after each assembly), compiled for AVX2 where
/// the processor has it ([`avx2_fma!`]): 0 x is (signed) zero for a finite x and NaN for an
/// infinite or NaN one, and a sum with a NaN stays NaN.
pub(crate) fn all_finite(values: &[f64]) -> bool {
    avx2_fma!(all_finite_lanes(values))
}

/// [`all_finite`]'s lanes.
#[inline(always)]
fn all_finite_lanes(values: &[f64]) -> bool {
    let mut chunks = values.chunks_exact(8);
    let mut sums = [0.0f64; 8];
    for chunk in &mut chunks {
        for (sum, x) in sums.iter_mut().zip(chunk) {
            *sum += x * 0.0;
        }
    }
    sums.iter().all(|&sum| sum == 0.0) && chunks.remainder().iter().all(|x| x.is_finite())
}

/// Keeps `workspace` (built for `mesh` and `solver`) on this thread for a later solve on
/// the same mesh ([`spare`]); the least recently kept goes when there are more than
/// [`SPARE`].
pub(crate) fn keep(mesh: Mesh, solver: LinearSolver, workspace: Workspace) {
    KEPT.with(|kept| {
        let mut kept = kept.borrow_mut();
        kept.push((mesh, solver, workspace));
        if kept.len() > SPARE {
            kept.remove(0);
        }
    });
}

/// A workspace this thread kept for `mesh` and `solver`, in the state of a new one (no
/// factors, no verdict; its buffers' old contents are overwritten before they are read, as
/// between Newton iterations), with the kept copy of the mesh (equal to `mesh`), or None.
pub(crate) fn spare(mesh: &Mesh, solver: LinearSolver) -> Option<(Mesh, Workspace)> {
    KEPT.with(|kept| {
        let mut kept = kept.borrow_mut();
        let at = kept.iter().position(|(m, s, _)| *s == solver && m == mesh)?;
        let (mesh, _, mut workspace) = kept.remove(at);
        workspace.factored = false;
        workspace.verdict = None;
        workspace.neutral = None;
        workspace.drift = f64::INFINITY;
        workspace.unfactored = false;
        workspace.dynamics = None;
        workspace.kept_ahead = false;
        workspace.rates_valid = false;
        workspace.trial_rates_valid = false;
        workspace.trial.clear();
        workspace.keep_tensions = false;
        workspace.forget_tension_rhs();
        Some((mesh, workspace))
    })
}

/// Everything Newton needs for one mesh, built once and reused across iterations, load
/// steps and solves on the same mesh.
pub struct Workspace {
    pub(super) linear: Linear,
    pub(super) values: Vec<f64>,
    pub(super) residual: Vec<f64>,
    pub(super) trial_residual: Vec<f64>,
    /// The simplified Newton correction -J^-1 F(trial) of the monotonicity test.
    pub(super) simplified: Vec<f64>,
    pub(super) rhs: Vec<f64>,
    pub(super) step: Vec<f64>,
    pub(super) trial: Vec<State>,
    /// The rates (v', u') of eq. 13 at the nodes, evaluated with `residual` when
    /// `rates_valid` ([`System::residual_rates`]); `trial_rates` go with `trial_residual`.
    pub(super) rates: Vec<Vector6<f64>>,
    pub(super) trial_rates: Vec<Vector6<f64>>,
    /// Whether `rates` belong to `residual` (written with it by the same evaluation); every
    /// other write of `residual` clears it.
    pub(super) rates_valid: bool,
    /// Whether `trial_rates` belong to `trial_residual`.
    pub(super) trial_rates_valid: bool,
    /// Whether the linear solver holds the factors of a successful solve.
    pub(super) factored: bool,
    /// The stability verdict of the Jacobian in `values`, once assessed (cleared whenever
    /// `values` change).
    pub(super) verdict: Option<Stability>,
    /// The conjugate points the verdict in `verdict` left out as within the neutral zone at
    /// the base ([`super::stability::count`]) and nothing has decided yet (module `neutral`
    /// decides them by the linearized dynamics, [`Workspace::settle_verdict`]).
    neutral: Option<NeutralRoots>,
    /// How far the last iterate has moved from the point where the Jacobian in `values` was
    /// evaluated: the sum of the max-norms of the (scaled) steps accepted since, infinite
    /// when that point is not known ([`Workspace::factor`], [`Workspace::solve_linear`]).
    pub(super) drift: f64,
    /// Whether `values` hold a Jacobian [`Workspace::verdict_at`] evaluated but did not
    /// factor (the factors are an earlier Jacobian's).
    pub(super) unfactored: bool,
    /// The verdict of the linearized dynamics computed with the factors held
    /// ([`Workspace::keep_dynamics`]; cleared whenever they change).
    dynamics: Option<Stability>,
    /// The buffers of the systems built on this mesh, kept between them
    /// ([`Workspace::system`], [`Workspace::keep_system`]).
    system: SystemBuffers,
    /// Eq. 13's factored matrices at each interval's points, as the last
    /// [`Workspace::linearize_keeping`] evaluated them.
    kept: Vec<IntervalFactors>,
    /// Whether `kept` belongs to the Jacobian Newton evaluated ahead into `values`
    /// ([`Workspace::jacobian_ahead`] with `keep`; read while `values` are unfactored and
    /// the iterate's, [`Workspace::kept_at_iterate`]).
    kept_ahead: bool,
    /// Buffers a linearization for sensitivities handed back for the next one
    /// ([`Workspace::take_buffer`], [`Workspace::give_buffer`]).
    buffers: Vec<Vec<f64>>,
    /// Whether [`Workspace::verdict_at`] also forms the tension columns' right-hand sides
    /// ([`Workspace::keep_tension_columns`]).
    keep_tensions: bool,
    /// -dF/dtau_i of every tendon (column-major) that the last [`Workspace::verdict_at`]
    /// formed with the Jacobian in `values`; taken by [`Workspace::take_tension_rhs`].
    tension_rhs: Option<Vec<f64>>,
    /// The buffers of the Jacobians that form the tension columns, kept for the next.
    tension_sink: TensionSink,
}

impl Workspace {
    /// Builds the buffers and, for the sparse path, the pattern and symbolic LU of
    /// `system`'s mesh.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] if faer rejects the pattern (cannot happen for a valid mesh).
    pub fn new(system: &System, solver: LinearSolver) -> crate::error::Result<Self> {
        let n = system.unknowns();
        Ok(Workspace {
            linear: Linear::new(&system.mesh, solver)?,
            values: vec![0.0; nonzeros(&system.mesh)],
            residual: vec![0.0; n],
            trial_residual: vec![0.0; n],
            simplified: vec![0.0; n],
            rhs: vec![0.0; n],
            step: vec![0.0; n],
            trial: Vec::with_capacity(system.mesh.nodes.len()),
            rates: vec![Vector6::zeros(); system.mesh.nodes.len()],
            trial_rates: vec![Vector6::zeros(); system.mesh.nodes.len()],
            rates_valid: false,
            trial_rates_valid: false,
            factored: false,
            verdict: None,
            neutral: None,
            drift: f64::INFINITY,
            unfactored: false,
            dynamics: None,
            system: SystemBuffers::default(),
            kept: Vec::new(),
            kept_ahead: false,
            buffers: Vec::new(),
            keep_tensions: false,
            tension_rhs: None,
            tension_sink: TensionSink::default(),
        })
    }

    /// Non-zeros stored in the Jacobian.
    pub fn nonzeros(&self) -> usize {
        self.values.len()
    }

    /// Factorizes the current matrix and solves J step = -residual.
    /// Returns false for a zero pivot or a non-finite step.
    pub(super) fn solve(&mut self, report: &mut SolveReport) -> bool {
        self.verdict = None;
        self.neutral = None;
        self.dynamics = None;
        self.unfactored = false;
        for (r, f) in self.rhs.iter_mut().zip(&self.residual) {
            *r = -f;
        }
        // The factoring overwrites the stored factors: none are usable until it succeeds.
        self.factored = false;
        let times = self.linear.solve(&self.values, &self.rhs, &mut self.step);
        let Some((factor_time, solve_time)) = times else {
            return false;
        };
        report.timings.factorization += factor_time;
        report.timings.solve += solve_time;
        self.factored = true;
        self.step.iter().all(|x| x.is_finite())
    }

    /// Marks `values` as a Jacobian just assembled that the linear solver will not factor
    /// (a border that factors the bordered system itself, [`super::newton::Border::own_factors`]):
    /// the factors held and the verdicts belong to no Jacobian now.
    pub(super) fn assembled(&mut self) {
        self.verdict = None;
        self.neutral = None;
        self.dynamics = None;
        self.unfactored = false;
        self.factored = false;
    }

    /// Solves J step = -residual with the stored factors of an earlier Jacobian (a chord
    /// step). Returns false when there are none or the step is not finite.
    pub(super) fn chord(&mut self, report: &mut SolveReport) -> bool {
        if !self.factored {
            return false;
        }
        for (r, f) in self.rhs.iter_mut().zip(&self.residual) {
            *r = -f;
        }
        let t = Instant::now();
        self.linear.solve_again(&self.rhs, &mut self.step);
        report.timings.solve += t.elapsed();
        self.step.iter().all(|x| x.is_finite())
    }

    /// Solves J x = rhs for Jacobian `values` in [`pattern`](super::unknowns::pattern) order with this workspace's
    /// linear solver: the hook tests use to cross-check the solvers and to force a singular
    /// matrix. None for a zero pivot or a non-finite result.
    pub fn solve_linear(&mut self, values: &[f64], rhs: &[f64]) -> Option<&[f64]> {
        self.values.copy_from_slice(values);
        self.rates_valid = false;
        for (r, f) in self.residual.iter_mut().zip(rhs) {
            *r = -f;
        }
        let mut report = SolveReport::new(crate::report::Method::Collocation);
        self.drift = f64::INFINITY;
        self.solve(&mut report).then_some(&self.step[..])
    }

    /// Evaluates the residual and the Jacobian of `system` at `x`, factors the Jacobian and
    /// solves for the Newton step (a Newton step's work, without moving `x`); counted in
    /// `report` as a Jacobian evaluation. False for a non-finite residual or Jacobian or a
    /// zero pivot. The residual is then [`Workspace::residual`], the Jacobian
    /// [`Workspace::jacobian`], and [`Workspace::solve_again`] solves with its factors.
    pub fn linearize(&mut self, system: &System, x: &[State], report: &mut SolveReport) -> bool {
        self.linearize_with(system, x, report, |_| {}, 0.0, None)
    }

    /// [`Workspace::linearize`] that also keeps eq. 13's factored matrix at every
    /// interval's points ([`System::jacobian_keeping`]) in [`Workspace::kept`], for the mass
    /// of the linearized dynamics at `x`. Frictionless systems only (with friction the
    /// interval Jacobian is friction's, which keeps nothing here).
    pub(crate) fn linearize_keeping(&mut self, system: &System, x: &[State], report: &mut SolveReport) -> bool {
        debug_assert!(system.friction.is_none(), "no factored matrices kept with friction");
        let links = x.len() - 1;
        if self.kept.len() != links {
            self.kept = vec![IntervalFactors::identity(); links];
        }
        let mut kept = std::mem::take(&mut self.kept);
        let ok = self.linearize_with(system, x, report, |_| {}, 0.0, Some(&mut kept));
        self.kept = kept;
        ok
    }

    /// The factored matrices the last [`Workspace::linearize_keeping`] kept, one per link.
    pub(crate) fn kept(&self) -> &[IntervalFactors] {
        &self.kept
    }

    /// [`Workspace::linearize`] with `shift` applied to the Jacobian's values before they are
    /// factored (J + M / dt, the matrix of an implicit step of the damped motion, module
    /// `relax`): the factors and values are then not the Jacobian's, and no verdict, chord
    /// step or sensitivity takes them for it (the drift is infinite).
    pub(super) fn linearize_shifted(
        &mut self,
        system: &System,
        x: &[State],
        report: &mut SolveReport,
        shift: impl FnOnce(&mut [f64]),
    ) -> bool {
        self.linearize_with(system, x, report, shift, f64::INFINITY, None)
    }

    /// [`Workspace::linearize`] with `shift` applied to the values before they are factored,
    /// the drift set to `drift` (0: the factors are the Jacobian's at `x`), eq. 13's
    /// factored matrices kept in `kept` when given.
    fn linearize_with(
        &mut self,
        system: &System,
        x: &[State],
        report: &mut SolveReport,
        shift: impl FnOnce(&mut [f64]),
        drift: f64,
        kept: Option<&mut [IntervalFactors]>,
    ) -> bool {
        let t = Instant::now();
        self.rates_valid = false;
        let ok = system
            .jacobian_keeping(x, &mut self.residual, &mut self.values, kept)
            .is_ok();
        report.timings.assembly += t.elapsed();
        report.evaluations.jacobian += 1;
        report.evaluations.equations += system.rate_evaluations();
        shift(&mut self.values);
        self.drift = drift;
        ok && all_finite(&self.values) && all_finite(&self.residual) && self.solve(report)
    }

    /// The residual of the last [`Workspace::linearize`] or Newton run (its final iterate).
    pub fn residual(&self) -> &[f64] {
        &self.residual
    }

    /// Makes the trial point's node rates (and whether they are valid) the current ones,
    /// with the residuals they belong to (Newton accepting a step).
    pub(super) fn swap_rates(&mut self) {
        std::mem::swap(&mut self.rates, &mut self.trial_rates);
        std::mem::swap(&mut self.rates_valid, &mut self.trial_rates_valid);
    }

    /// The rates (v', u') of eq. 13 at the nodes that the evaluation of
    /// [`Workspace::residual`] gave ([`System::residual_rates`]), when it was such an
    /// evaluation (Newton's residual at its iterate; not a Jacobian's), else None.
    pub(crate) fn residual_rates(&self) -> Option<&[Vector6<f64>]> {
        self.rates_valid.then_some(&self.rates[..])
    }

    /// The Jacobian values of the last evaluation, in
    /// [`pattern`](super::unknowns::pattern) order.
    pub fn jacobian(&self) -> &[f64] {
        &self.values
    }

    /// Whether the Jacobian in the value buffer belongs to the last iterate: it was evaluated
    /// there, or within Newton's own stopping distance of it (1e-10 in the scaled unknowns,
    /// the iteration error a converged state is allowed), so that a verdict of those values is the
    /// iterate's. Newton's last Jacobian is evaluated one step before its answer (after a
    /// single Newton step followed by chord steps, at the guess), which it does not belong to.
    pub fn jacobian_at_iterate(&self) -> bool {
        self.drift <= STEP_TOLERANCE
    }

    /// Whether the value buffer holds the Jacobian evaluated exactly at the last iterate
    /// (by Newton's last step there or by [`Workspace::verdict_at`]), so that factoring it
    /// gives the sensitivities of that state.
    pub fn evaluated_at_solution(&self) -> bool {
        self.drift == 0.0
    }

    /// Makes the stored factors those of the Jacobian in the value buffer when that was
    /// evaluated at the last iterate ([`Workspace::evaluated_at_solution`]): factors it
    /// when [`Workspace::verdict_at`] left it unfactored, and keeps its verdict (the values
    /// are the same). False for a zero pivot, or when the buffer holds no such Jacobian.
    pub fn factor_evaluated(&mut self) -> bool {
        if !self.evaluated_at_solution() {
            return false;
        }
        if !self.unfactored {
            return self.factored;
        }
        let (verdict, neutral) = (self.verdict.take(), self.neutral);
        self.residual.fill(0.0);
        self.rates_valid = false;
        let mut report = SolveReport::new(crate::report::Method::Collocation);
        let ok = self.solve(&mut report);
        (self.verdict, self.neutral) = (verdict, neutral);
        ok
    }

    /// [`Workspace::factor_evaluated`], also giving the last node's 12 unknowns of
    /// J x = rhs_j for the `count` right-hand sides in `rhs` (column-major, each of the
    /// unknowns' length) into `last`: carried through the factoring where the values are
    /// still unfactored ([`crate::collocation::linear`]'s `factor_with_last`, the same bits
    /// as [`Workspace::solve_again_last`] after it), else solved with the factors.
    /// False as [`Workspace::factor_evaluated`], or for a non-finite result.
    pub(crate) fn factor_evaluated_with_last(
        &mut self,
        rhs: &[f64],
        count: usize,
        last: &mut [[f64; crate::collocation::unknowns::NODE]],
    ) -> bool {
        if self.evaluated_at_solution() && self.unfactored {
            let verdict = self.verdict.take();
            if let Some(ok) = self.linear.factor_with_last(&self.values, rhs, count, last) {
                self.factored_without_solve(ok);
                self.verdict = verdict;
                return ok && last.iter().flatten().all(|x| x.is_finite());
            }
            self.verdict = verdict;
        }
        self.factor_evaluated() && self.solve_again_last_each(rhs, count, last)
    }

    /// [`Workspace::factor`], also giving the last node's unknowns for `rhs` as
    /// [`Workspace::factor_evaluated_with_last`] does.
    pub(crate) fn factor_with_last(
        &mut self,
        values: &[f64],
        rhs: &[f64],
        count: usize,
        last: &mut [[f64; crate::collocation::unknowns::NODE]],
    ) -> bool {
        if let Some(ok) = self.linear.factor_with_last(values, rhs, count, last) {
            self.values.copy_from_slice(values);
            self.drift = f64::INFINITY;
            self.verdict = None;
            self.neutral = None;
            self.factored_without_solve(ok);
            return ok && last.iter().flatten().all(|x| x.is_finite());
        }
        self.factor(values) && self.solve_again_last_each(rhs, count, last)
    }

    /// The state a factoring with a zero right-hand side ([`Workspace::solve`]) leaves (a
    /// zero residual, the verdicts cleared), after a factoring that solved for no step (the
    /// step buffer is not written: Newton writes it before reading it): `ok` whether it
    /// succeeded.
    fn factored_without_solve(&mut self, ok: bool) {
        self.dynamics = None;
        self.unfactored = false;
        self.residual.fill(0.0);
        self.rates_valid = false;
        self.factored = ok;
    }

    /// [`Workspace::solve_again_last`] for each of the `count` right-hand sides in `rhs`.
    fn solve_again_last_each(
        &mut self,
        rhs: &[f64],
        count: usize,
        last: &mut [[f64; crate::collocation::unknowns::NODE]],
    ) -> bool {
        let n = rhs.len() / count.max(1);
        for (j, x) in last.iter_mut().take(count).enumerate() {
            match self.solve_again_last(&rhs[j * n..(j + 1) * n]) {
                Some(v) => *x = v,
                None => return false,
            }
        }
        true
    }

    /// Whether the stored factors are those of the Jacobian evaluated at the last iterate,
    /// with no step taken since (the drift is zero and [`Workspace::verdict_at`] has not
    /// replaced the values): what [`Workspace::linearize`] there would give again.
    pub(crate) fn factors_at_iterate(&self) -> bool {
        self.drift == 0.0 && self.factored && !self.unfactored
    }

    /// Whether the workspace holds the factors of a successful solve.
    pub fn has_factors(&self) -> bool {
        self.factored
    }

    /// Factors the Jacobian with these `values` (in [`crate::collocation::unknowns::pattern`]
    /// order) for later [`Workspace::solve_again`] calls, as the sensitivities need. The
    /// structured elimination carries the right-hand side through its panels, so factoring
    /// is a solve with a zero right-hand side at the same cost. False for a zero pivot.
    pub fn factor(&mut self, values: &[f64]) -> bool {
        self.values.copy_from_slice(values);
        self.residual.fill(0.0);
        self.rates_valid = false;
        let mut report = SolveReport::new(crate::report::Method::Collocation);
        self.drift = f64::INFINITY;
        self.solve(&mut report)
    }

    /// Solves J x = rhs with the factorization of the last successful solve (a Newton step or
    /// [`Workspace::solve_linear`]) for another right-hand side: no refactorization, so many
    /// right-hand sides (sensitivities, one per parameter) cost one factorization. None for
    /// a non-finite result.
    pub fn solve_again(&mut self, rhs: &[f64]) -> Option<&[f64]> {
        if !self.factored {
            return None;
        }
        self.linear.solve_again(rhs, &mut self.step);
        all_finite(&self.step).then_some(&self.step[..])
    }

    /// The last node's 12 unknowns of [`Workspace::solve_again`]'s solution, without
    /// solving for the other nodes' (the tip's derivatives alone). None without factors or
    /// for a non-finite result.
    pub fn solve_again_last(&mut self, rhs: &[f64]) -> Option<[f64; crate::collocation::unknowns::NODE]> {
        if !self.factored {
            return None;
        }
        let x = self.linear.solve_again_last(rhs, &mut self.step);
        x.iter().all(|x| x.is_finite()).then_some(x)
    }

    /// Solves J^T y = c with the same factorization as [`Workspace::solve_again`]: the
    /// adjoint solve behind gradients of outputs (`collocation/sensitivity/adjoint.rs`).
    /// None without factors or for a non-finite result.
    pub fn solve_transposed(&mut self, c: &[f64]) -> Option<&[f64]> {
        if !self.factored {
            return None;
        }
        self.linear.solve_transposed(c, &mut self.step);
        self.step.iter().all(|x| x.is_finite()).then_some(&self.step[..])
    }
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    /// Every position of an infinity or a NaN is seen, inside the 8-wide chunks and in the
    /// remainder; finite values, huge ones included, pass.
    #[test]
    fn all_finite_sees_every_non_finite_entry() {
        let finite: Vec<f64> = (0..21).map(|i| (i as f64 - 10.0) * 1e300).collect();
        assert!(all_finite(&finite) && all_finite(&[]));
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for at in 0..finite.len() {
                let mut v = finite.clone();
                v[at] = bad;
                assert!(!all_finite(&v), "{bad} at {at}");
            }
        }
    }
}
