//! The bordered system of tendons with friction linearized at a given solution, for the
//! sensitivities of [`crate::collocation::sensitivity`]: the implicit function theorem on
//! the residual (F, psi) of the backbone and capstan rows in the unknowns (x, z),
//!
//! ```text
//! [ J      F_z   ] [dx/dq]     [ dF/dq   ]
//! [ psi_x  psi_z ] [dz/dq] = - [ dpsi/dq ]
//! ```
//!
//! with the exact blocks Newton uses (module docs of [`super`]) and the same bordered solve.
//! A parameter's derivative dF/dq, dpsi/dq is the residual's at fixed (x, z): z is the log
//! tension relative to the base entry, so a base tension moves the whole profile with it.

use super::*;

impl<'r> Capstan<'r> {
    /// The border without rows of `system`, a system without friction built elsewhere
    /// (what [`Capstan::at_solution`] gives for a model without friction).
    pub(crate) fn plain(system: System<'r>) -> Self {
        debug_assert!(system.friction.is_none());
        Capstan::new(system)
    }

    /// The system of `model` on `mesh`, bordered by the log tensions of `solution`'s tendons
    /// with friction (from their tensions at the nodes of their spans); a border without
    /// rows when the model has no friction.
    pub(crate) fn at_solution(model: Model<'r>, mesh: Mesh, solution: &Solution) -> Self {
        let mut system = System::new(model, mesh);
        if crate::model::friction::any(system.model.robot) {
            let mut profile = Profile::new(&system.model, &system.mesh);
            for (j, &i) in profile.slipping.iter().enumerate() {
                let tensions = &solution.tendon_tensions[i];
                let (base, span) = (profile.base[j], profile.spans[j]);
                let last = tensions.len().saturating_sub(1);
                // A tendon at 0 N keeps its log tensions in no tension: 0 here, and
                // `linearize` solves its capstan rows for them.
                for (n, z) in profile.z[j].iter_mut().enumerate() {
                    let ratio = tensions.get(n.min(span).min(last)).map_or(1.0, |t| t / base);
                    *z = if ratio > 0.0 && ratio.is_finite() {
                        ratio.ln()
                    } else {
                        0.0
                    };
                }
                profile.z[j][0] = 0.0;
            }
            profile.deliver(&mut system.model);
            system.friction = Some(profile);
        }
        Capstan::new(system)
    }

    /// Tendon `i`'s log tensions z at the nodes 0..=span of its span (0 at the base) and their
    /// derivative in the last bordered solve ([`Capstan::respond`]; 0 at the base, where z is
    /// 0 by definition); None for a tendon without log tensions (no friction).
    pub(crate) fn log_tensions(&self, i: usize) -> Option<(Vec<f64>, Vec<f64>)> {
        let profile = self.system.friction.as_ref()?;
        let j = profile.slipping.iter().position(|&t| t == i)?;
        let span = profile.spans[j];
        let z = profile.z[j][..=span].to_vec();
        let dz = (0..=span)
            .map(|n| unknown(&self.offsets, &profile.spans, j, n).map_or(0.0, |u| self.border_step[u]))
            .collect();
        Some((z, dz))
    }

    /// Number of border rows (= log-tension unknowns); 0 without friction.
    pub(crate) fn border_rows(&self) -> usize {
        self.z.len()
    }

    /// The border row of slip j's capstan (or stick) row on link k (j in the order of
    /// [`crate::model::friction::slipping`], k within its span).
    pub(crate) fn capstan_row(&self, j: usize, k: usize) -> usize {
        self.offsets[j] + k
    }

    /// The backbone part dx (scaled node unknowns) of the bordered solve with the factors
    /// of Newton's last bordered Jacobian (its staircase) for the right-hand side `rhs_x` on
    /// the backbone rows and `rhs_z` on the border's, for the linearized dynamics
    /// (`collocation/dynamics/friction.rs`); false without factors or for a value that is not
    /// finite.
    pub(crate) fn solve_with_factors(&mut self, rhs_x: &[f64], rhs_z: &[f64], dx: &mut [f64]) -> bool {
        self.stairs.ready && self.solve_factored(rhs_x, rhs_z, dx).is_some_and(f64::is_finite)
    }

    /// Evaluates the bordered Jacobian at `x` (the profile's current log tensions) and
    /// factors it into the staircase, for a verdict that belongs to `x` when Newton's last
    /// factors belong to an earlier iterate; counted in `report`. False for a singular
    /// matrix.
    ///
    /// # Errors
    /// A model breakdown at a visited state or a border block that is not finite.
    pub(crate) fn factor_at(&mut self, x: &[State], report: &mut SolveReport) -> Result<bool> {
        let t = Instant::now();
        let mut residual = vec![0.0; self.system.unknowns() + self.z.len()];
        let mut values = vec![0.0; unknowns::nonzeros(&self.system.mesh)];
        self.evaluate(x, &mut residual, &mut values)?;
        report.evaluations.jacobian += 1;
        report.timings.assembly += t.elapsed();
        let t = Instant::now();
        let ok = self.factor(&values);
        report.timings.factorization += t.elapsed();
        Ok(ok)
    }

    /// Factors the bordered matrix (its staircase) from the Jacobian values `ws` holds and
    /// has factored ([`Capstan::linearize`] then the workspace's factoring), unless it is
    /// factored already; false for a singular matrix or a workspace without factors.
    pub(crate) fn factor_from(&mut self, ws: &Workspace) -> bool {
        ws.has_factors() && (self.stairs.ready || self.factor(&ws.values))
    }

    /// The system whose backbone rows the border borders.
    pub(crate) fn system(&self) -> &System<'r> {
        &self.system
    }

    /// The collocation system, giving up the capstan rows.
    pub(crate) fn into_system(self) -> System<'r> {
        self.system
    }

    /// Tendon `i`'s input tension (N): at the base entry for a tendon with friction (the
    /// model's own tension there is the delivered one), the model's otherwise.
    pub(crate) fn input_tension(&self, i: usize) -> f64 {
        let profile = self.system.friction.as_ref();
        profile
            .and_then(|p| p.slipping.iter().position(|&t| t == i).map(|j| p.base[j]))
            .unwrap_or(self.system.model.tensions[i])
    }

    /// The system with `model` in place of this one's (a parameter moved), the same mesh
    /// and the same log tensions: its residual at the same node states is the residual at
    /// the same unknowns (x, z) for the moved parameter.
    pub(crate) fn moved<'s>(&self, model: Model<'s>) -> System<'s> {
        let mut system = System::new(model, self.system.mesh.clone());
        if let Some(own) = &self.system.friction {
            let mut profile = Profile::new(&system.model, &system.mesh);
            profile.z.clone_from(&own.z);
            profile.deliver(&mut system.model);
            system.friction = Some(profile);
        }
        system
    }

    /// The residual (F, psi) of `system` (this border's layout) at the node states `x`:
    /// the backbone rows into `out[..n]` and the capstan rows, read from the links the
    /// residual has just evaluated, into `out[n..]`.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn residual_of(&self, system: &System, x: &[State], out: &mut [f64]) -> Result<()> {
        let n = system.unknowns();
        let (rows, psi) = out.split_at_mut(n);
        system.residual(x, rows)?;
        self.psi_of(system, psi);
        Ok(())
    }

    /// The capstan rows of `system`'s profile ([`capstan_rows`]) into `psi`.
    fn psi_of(&self, system: &System, psi: &mut [f64]) {
        if let Some(profile) = system.friction.as_ref() {
            capstan_rows(profile, &self.offsets, psi);
        }
    }

    /// The Jacobian of the backbone rows at `x` into `values` and the residual (F, psi)
    /// into `residual`, then the border's blocks (psi_x, psi_z, F_z) read from the same
    /// evaluation, ready for [`Capstan::respond`] once `values` are factored.
    ///
    /// # Errors
    /// A model breakdown at a visited state or a border block that is not finite.
    pub(crate) fn linearize(&mut self, x: &[State], residual: &mut [f64], values: &mut [f64]) -> Result<()> {
        self.evaluate(x, residual, values)?;
        let unloaded = self.system.friction.as_ref().is_some_and(|p| p.base.contains(&0.0));
        if unloaded {
            // A tendon at 0 N loads nothing, so its capstan rows are linear in its log
            // tensions (psi_z is their whole derivative): one forward substitution solves them.
            let n = self.system.unknowns();
            let rhs: Vec<f64> = residual[n..].iter().map(|p| -p).collect();
            let mut dz = vec![0.0; rhs.len()];
            if !self.forward(&rhs, &mut dz) {
                return Err(super::super::sensitivity::singular());
            }
            for (z, d) in self.z.iter_mut().zip(&dz) {
                *z += d;
            }
            self.evaluate(x, residual, values)?;
        }
        Ok(())
    }

    /// The Jacobian and residual at `x` and the current log tensions, and the border's blocks.
    fn evaluate(&mut self, x: &[State], residual: &mut [f64], values: &mut [f64]) -> Result<()> {
        self.load(Point::Current);
        let n = self.system.unknowns();
        let (rows, psi) = residual.split_at_mut(n);
        self.system.jacobian(x, rows, values)?;
        self.psi_of(&self.system, psi);
        self.read_border(x).map_err(|_| {
            error::invalid(
                "solution",
                "gives a capstan row whose derivatives are not finite",
                "pass a converged solution of this robot",
            )
        })
    }

    /// (dx/dq, dz/dq) for the right-hand side `rhs` = -(dF/dq, dpsi/dq) by the bordered
    /// solve with the factors in `ws`: dx/dq (scaled node unknowns), None for a singular
    /// system or a value that is not finite.
    pub(crate) fn respond(&mut self, rhs: &[f64], ws: &mut Workspace) -> Option<Vec<f64>> {
        let n = self.system.unknowns();
        if self.z.is_empty() {
            return ws.solve_again(&rhs[..n]).map(<[f64]>::to_vec);
        }
        // The bordered matrix, factored once per linearization with the workspace's Jacobian.
        if !ws.has_factors() || (!self.stairs.ready && !self.factor(&ws.values)) {
            return None;
        }
        let mut dx = vec![0.0; n];
        self.solve_factored(&rhs[..n], &rhs[n..], &mut dx)?;
        Some(dx)
    }
}
