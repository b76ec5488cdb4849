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

/// What a border leaves for the next one built for a verdict ([`Capstan::into_kept`],
/// [`Capstan::with_kept`]): its staircase (whose buffers fit a mesh with the same log
/// tensions at its nodes) and the residual and Jacobian buffers of
/// [`Capstan::factor_at`]. A history's verdicts build one border per step.
#[derive(Default)]
pub(crate) struct Kept {
    pub(super) stairs: Option<Staircase>,
    pub(super) at_buffers: (Vec<f64>, Vec<f64>),
}

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
        // Zeroed, in the buffers a border before may have left ([`Capstan::with_kept`]).
        let (mut residual, mut values) = std::mem::take(&mut self.at_buffers);
        for (buffer, len) in [
            (&mut residual, self.system.unknowns() + self.z.len()),
            (&mut values, unknowns::nonzeros(&self.system.mesh)),
        ] {
            buffer.clear();
            buffer.resize(len, 0.0);
        }
        // The verdict's mass reads eq. 13 with friction at the same points.
        self.keep_responses(true);
        let evaluated = self.evaluate(x, &mut residual, &mut values);
        self.keep_responses(false);
        let ok = evaluated.map(|()| {
            report.evaluations.jacobian += 1;
            report.timings.assembly += t.elapsed();
            let t = Instant::now();
            let ok = self.factor(&values);
            report.timings.factorization += t.elapsed();
            ok
        });
        self.at_buffers = (residual, values);
        ok
    }

    /// The system, and the staircase and buffers for a later border on this thread
    /// ([`Capstan::with_kept`]).
    pub(crate) fn into_kept(self) -> (System<'r>, Kept) {
        let kept = Kept {
            stairs: Some(self.stairs),
            at_buffers: self.at_buffers,
        };
        (self.system, kept)
    }

    /// Factors the bordered Jacobian at `x` into the staircase from the backbone Jacobian
    /// `values` Newton evaluated there in place of its last residual
    /// ([`newton::run_bordered_ahead`]), with the border's blocks read from the links'
    /// evaluations that Jacobian left ([`Capstan::read_border`]): what [`Capstan::factor_at`]
    /// factors, without evaluating it again. False when a link's last evaluation is not a
    /// Jacobian's (then [`Capstan::factor_at`] is the way) or for a singular matrix.
    pub(crate) fn factor_evaluated(&mut self, x: &[State], values: &[f64], report: &mut SolveReport) -> bool {
        if self.read_border(x).is_err() {
            return false;
        }
        let t = Instant::now();
        let ok = self.factor(values);
        report.timings.factorization += t.elapsed();
        ok
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::unknowns::nonzeros;
    use crate::{Friction, Motion};
    use nalgebra::{Vector3, Vector6};

    /// `System::jacobian_rates` on a system with friction (what `newton::run_bordered_ahead`
    /// evaluates in place of the residual at its predicted last trial point) gives
    /// `System::residual`'s backbone rows and the capstan rows read from the links'
    /// evaluations bit for bit, and `System::jacobian`'s values, at the solutions with
    /// friction of case S (tendon 1 pulled and released, and with tendon 2 also rough), of
    /// case H (the helical tendon 5) and of S with a dead tip moment, and at states moved off
    /// them (a trial point that is not a root).
    #[test]
    fn the_bordered_jacobian_at_a_trial_point_gives_the_residual_evaluation_bits() {
        // The first entry whose bits differ, if any.
        let bits = |a: &[f64], b: &[f64]| a.iter().zip(b).position(|(a, b)| a.to_bits() != b.to_bits());
        let mut robots = Vec::new();
        for motion in [Motion::Pull, Motion::Release] {
            let mut s = crate::cases::case_s();
            s.tendons[0].friction = Some(Friction {
                coefficient: 0.1,
                motion,
            });
            robots.push(s);
        }
        let mut two = crate::cases::case_s();
        two.tendons[1].set_tension(1.0);
        two.tendons[0].friction = Some(Friction::pull(0.1));
        two.tendons[1].friction = Some(Friction::pull(0.2));
        robots.push(two);
        let mut h = crate::cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        robots.push(h);
        let mut moment = crate::cases::case_s();
        moment.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
        moment.tendons[0].friction = Some(Friction::pull(0.1));
        robots.push(moment);
        for (case, robot) in robots.iter().enumerate() {
            let solution = crate::collocation::solve(robot, &crate::collocation::Options::default()).unwrap();
            let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
            let mesh = Mesh::from_points(robot, &s).unwrap();
            let border = Capstan::at_solution(Model::new(robot), mesh, &solution);
            let system = border.system();
            assert!(system.friction.is_some(), "{case}");
            let answer: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
            // Every node's strains moved by 1e-4 (and its position by 1e-4 L): far from the
            // root in the residual's last bits, so that no coincidence of small rows hides a
            // difference.
            let length = robot.length();
            let moved: Vec<State> = answer
                .iter()
                .map(|x| State {
                    p: x.p + Vector3::new(1e-4, -2e-4, 1e-4) * length,
                    v: x.v + Vector3::new(1e-4, 0.0, -1e-4),
                    u: x.u + Vector3::new(0.0, 1e-1, 2e-1),
                    ..*x
                })
                .collect();
            for (at, x) in [answer, moved].iter().enumerate() {
                let (n, m) = (system.unknowns(), border.border_rows());
                let mut residual = vec![0.0; n + m];
                border.residual_of(system, x, &mut residual).unwrap();
                let (mut plain, mut values) = (vec![0.0; n], vec![0.0; nonzeros(&system.mesh)]);
                system.jacobian(x, &mut plain, &mut values).unwrap();
                let mut with = vec![f64::NAN; n + m];
                let mut with_values = vec![f64::NAN; values.len()];
                let mut rates = vec![Vector6::zeros(); x.len()];
                let written = system
                    .jacobian_rates(x, &mut with[..n], &mut with_values, &mut rates)
                    .unwrap();
                assert!(!written, "{case}: no node rates with friction");
                border.psi_of(system, &mut with[n..]);
                assert!(m > 0 && residual.iter().all(|r| r.is_finite()), "{case} {at}");
                assert_eq!(bits(&residual, &with), None, "{case} {at}");
                assert_eq!(bits(&values, &with_values), None, "{case} {at}");
            }
        }
    }
}
