//! The derivatives with their own right-hand sides: the tension columns (exact, one pass
//! over the mesh for every tendon; differenced with friction), the friction coefficients
//! (differenced), the section stiffnesses (E and G), and the six tip-pose multipliers of the adjoint form that `tip_sensitivities` contracts its other columns with
//! (module docs of `sensitivity`, docs/sensitivity.md "Exact tension columns"); and the
//! residual at the solution with a parameter moved, which every differenced one takes.

use super::{Difference, NodeDerivative, RELATIVE_STEP, Sensitivity, singular};
use crate::collocation::friction::Capstan;
use crate::collocation::system::{Columns, System};
use crate::collocation::unknowns;
use crate::error::{Result, invalid};
use crate::model::equations::Model;
use crate::model::robot::Robot;
use crate::solution::State;
use nalgebra::Vector6;

impl Sensitivity<'_> {
    /// The derivative of every node state with respect to tendon `tendon`'s tension
    /// (per N); for a slack tendon the one-sided (right) derivative, the response to its
    /// first pull. Exact without friction ([`crate::collocation::system::System::parameter_columns`]: the residual is
    /// linear in each tension at fixed states; one pass over the mesh serves every tendon);
    /// with tendons with friction, whose tensions also set the capstan rows, central
    /// differences of the bordered residual (one-sided for a slack tendon).
    ///
    /// A tendon with friction at 0 N gets the one-sided derivative at 0+ too, the response
    /// to its first pull with the capstan profile of the current shape
    /// (`first_pull.rs`, docs/friction.md section 3, "Sensitivities").
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a tendon index out of range; as
    /// [`Sensitivity::derivative`].
    pub fn tension(&mut self, tendon: usize) -> Result<Vec<NodeDerivative>> {
        self.tension_rhs(tendon)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::tension`] into the right-hand side buffer.
    pub(super) fn tension_rhs(&mut self, tendon: usize) -> Result<()> {
        let robot = self.robot();
        Self::tendon_of(robot, tendon)?;
        if self.border.border_rows() > 0 {
            return self.friction_tension_rhs(tendon);
        }
        let n = self.border.system().unknowns();
        if self.tension_columns.is_none() {
            let columns = vec![0.0; n * robot.tendons.len()];
            self.tension_columns = Some(tension_rhs_columns(self.border.system(), &self.states, columns)?);
        }
        let columns = self.tension_columns.as_deref().unwrap_or_default();
        self.scratch[0][..n].copy_from_slice(&columns[tendon * n..(tendon + 1) * n]);
        Ok(())
    }

    /// The derivative of every node state along a change `dk` of the section's six diagonal
    /// stiffnesses (kse = (GA, GA, EA) in N, then kbt = (EIxx, EIyy, GJ) in N m^2, per unit
    /// of the parameter that moves them): exact, for a rod whose section does not vary along
    /// it ([`crate::collocation::system::System::parameter_columns`] with [`crate::collocation::system::Columns::Stiffness`]; eq. 13 and the
    /// point-load rows are linear in each stiffness at fixed states). A modulus moves them in
    /// proportion: d/dE at fixed Poisson's ratio is `dk = k / E`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a rod whose section varies along it or with
    /// segments (use [`Sensitivity::derivative`]), or with tendons with friction; a model
    /// breakdown; a singular Jacobian.
    pub fn stiffness(&mut self, dk: &[f64; 6]) -> Result<Vec<NodeDerivative>> {
        self.stiffness_rhs(dk)?;
        self.respond()
    }

    /// Whether [`Sensitivity::stiffness`] applies: a uniform section, no friction.
    pub(super) fn exact_stiffness(&self) -> bool {
        let uniform = matches!(self.robot().rod.stiffness, crate::model::rod::Stiffness::Uniform(_));
        uniform && self.border.border_rows() == 0
    }

    /// Writes -dF/dq of [`Sensitivity::stiffness`] into the right-hand side buffer.
    pub(super) fn stiffness_rhs(&mut self, dk: &[f64; 6]) -> Result<()> {
        if !self.exact_stiffness() {
            return Err(invalid(
                "rod.stiffness",
                "has no exact stiffness derivative here: the section varies along the rod, or tendons have friction",
                "difference the residual instead (Sensitivity::derivative)",
            ));
        }
        let n = self.border.system().unknowns();
        if self.stiffness_columns.is_none() {
            let mut columns = vec![0.0; n * 6];
            self.border
                .system()
                .parameter_columns(&self.states, Columns::Stiffness, &mut columns)?;
            self.stiffness_columns = Some(columns);
        }
        let columns = self.stiffness_columns.as_deref().unwrap_or_default();
        let rhs = &mut self.scratch[0];
        rhs.fill(0.0);
        for (j, &w) in dk.iter().enumerate().filter(|(_, w)| **w != 0.0) {
            for (r, d) in rhs.iter_mut().zip(&columns[j * n..(j + 1) * n]) {
                *r -= w * d;
            }
        }
        Ok(())
    }

    /// [`Sensitivity::tension_rhs`] with tendons with friction: central differences of the
    /// bordered residual (the tension also sets the profile's base and the capstan rows, so
    /// it is moved in a clone of the robot and every row follows), one-sided for a slack
    /// tendon; steps [`RELATIVE_STEP`] times the tension, but at least the tension that bends
    /// the rod through about a radian.
    fn friction_tension_rhs(&mut self, tendon: usize) -> Result<()> {
        let robot = self.robot();
        let t = &robot.tendons[tendon];
        let bend = super::first_pull::bend_scale(robot, tendon);
        let tension = self.border.input_tension(tendon);
        let step = RELATIVE_STEP * tension.max(bend);
        // Central needs q - h inside the model's domain (tension > 0 keeps the tendon in it).
        let difference = if tension > step {
            Difference::Central
        } else {
            Difference::Forward
        };
        if tension == 0.0 && t.active_friction().is_some() {
            // The first pull: the one-sided limit at 0+ (first_pull.rs).
            return self.first_pull_rhs(tendon, step);
        }
        let perturb = |r: &mut Robot, dq: f64| r.tendons[tendon].set_tension(tension + dq);
        self.differenced_rhs(step, difference, |border, states, dq, out| {
            residual_at(border, states, &perturb, dq, out)
        })
    }

    /// The six tip-pose multipliers of the plain system (no friction): lambda_k = J^-T g_k
    /// with g_k the tip position's component k (k < 3, L in the tip's d_p slot) or the tip
    /// rotation's (R_tip^T e in its dtheta slot), so that d(tip pose)_k/dq = lambda_k .
    /// (-dF/dq) for every parameter (the adjoint form, docs/sensitivity.md "Adjoint
    /// gradients"): six transposed solves instead of one solve per parameter. None with
    /// friction (the bordered system).
    ///
    /// # Errors
    /// A singular Jacobian.
    pub(super) fn tip_multipliers(&mut self) -> Result<Option<Vec<Vec<f64>>>> {
        if self.border.border_rows() > 0 {
            return Ok(None);
        }
        let tip = self.states.len() - 1;
        let (length, R) = (self.robot().length(), self.states[tip].R);
        let mut out = Vec::with_capacity(6);
        for k in 0..6 {
            let g = &mut self.scratch[1];
            g.fill(0.0);
            if k < 3 {
                g[tip * unknowns::NODE + unknowns::P + k] = length;
            } else {
                let body = R.transpose().column(k - 3).into_owned();
                for i in 0..3 {
                    g[tip * unknowns::NODE + unknowns::THETA + i] = body[i];
                }
            }
            out.push(self.workspace.solve_transposed(g).ok_or_else(singular)?.to_vec());
        }
        Ok(Some(out))
    }

    /// The derivative of every node state with respect to tendon `tendon`'s friction
    /// coefficient mu (per unit of mu), by central differences of the residual (backbone and
    /// capstan rows) with the step [`RELATIVE_STEP`] (mu's scale is 1; forward differences
    /// for mu below the step) and the bordered solve (docs/friction.md).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a tendon index out of range or a tendon without
    /// friction (mu = 0: the log tensions are not unknowns there, so the derivative would
    /// need another system); as [`Sensitivity::derivative`].
    pub fn friction(&mut self, tendon: usize) -> Result<Vec<NodeDerivative>> {
        self.friction_rhs(tendon)?;
        self.respond()
    }

    /// Writes -dF/dmu of [`Sensitivity::friction`] into the right-hand side buffer.
    ///
    /// # Errors
    /// As [`Sensitivity::friction`].
    pub(super) fn friction_rhs(&mut self, tendon: usize) -> Result<()> {
        let robot = self.robot();
        let t = Self::tendon_of(robot, tendon)?;
        let Some(friction) = t.active_friction() else {
            return Err(invalid(
                format!("tendons[{tendon}].friction"),
                "is 0 or not set, and the derivative in the friction coefficient is taken where it is > 0",
                "give the tendon a positive friction coefficient (e.g. 1e-3) to differentiate there",
            ));
        };
        let mu = friction.coefficient;
        // mu's scale is 1, not mu: it acts through exp(mu Theta) with turning angles Theta
        // of about a radian, so a step of 1e-4 truncates at about 1e-8 as for the other
        // parameters, and rounds 1 / mu times less than 1e-4 mu would (d tip / d mu within
        // 5e-7 of differences of solves at mu = 0.05 with 1e-4 mu, measured; tests/
        // friction_pull_in.rs). Below the step the stencil stays on mu's side of 0.
        let difference = if mu > RELATIVE_STEP {
            Difference::Central
        } else {
            Difference::Forward
        };
        let perturb = |r: &mut crate::Robot, dq: f64| {
            if let Some(f) = &mut r.tendons[tendon].friction {
                f.coefficient = mu + dq;
            }
        };
        self.differenced_rhs(RELATIVE_STEP, difference, |border, states, dq, out| {
            residual_at(border, states, &perturb, dq, out)
        })
    }

    /// The tip pose's derivative for the right-hand side in the buffer, by the multipliers
    /// of [`Sensitivity::tip_multipliers`].
    pub(super) fn tip_by(&self, multipliers: &[Vec<f64>]) -> Vector6<f64> {
        let rhs = &self.scratch[0];
        Vector6::from_fn(|k, _| multipliers[k].iter().zip(rhs).map(|(l, r)| l * r).sum())
    }
}

/// -dF/dtau_i of every tendon of `system` (no friction) at `states`, column-major in
/// `out` (its length the unknowns times the tendons; [`System::parameter_columns`],
/// negated): the tension columns' right-hand sides.
///
/// # Errors
/// A model breakdown at a visited state.
pub(super) fn tension_rhs_columns(system: &System, states: &[State], mut out: Vec<f64>) -> Result<Vec<f64>> {
    system.parameter_columns(states, Columns::Tensions, &mut out)?;
    out.iter_mut().for_each(|d| *d = -*d);
    Ok(out)
}

/// The residual (backbone rows, then capstan rows) of `border`'s system at `states` and
/// its log tensions for the robot with its parameter moved by dq.
pub(super) fn residual_at(
    border: &Capstan,
    states: &[State],
    perturb: &impl Fn(&mut Robot, f64),
    dq: f64,
    out: &mut [f64],
) -> Result<()> {
    let robot = border.system().model.robot;
    let mut probe = robot.clone();
    perturb(&mut probe, dq);
    if probe.breakpoints() != robot.breakpoints() {
        return Err(invalid(
            "perturbation",
            "moves a breakpoint (tendon termination or point load), which changes the mesh",
            "differentiate with respect to parameters that keep the breakpoints",
        ));
    }
    let mut model = Model::new(&probe);
    for (i, t) in probe.tendons.iter().enumerate() {
        if t.displacement().is_some() {
            model.tensions[i] = border.system().model.tensions[i];
        }
    }
    let system = border.moved(model);
    border.residual_of(&system, states, out)
}
