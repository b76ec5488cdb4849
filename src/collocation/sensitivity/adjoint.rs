//! Gradients of a scalar function of a solved shape with respect to the robot's parameters
//! by the adjoint (reverse, vector-Jacobian) form of the implicit function theorem: what a
//! training loop's backward pass needs (docs/sensitivity.md, "Adjoint gradients").
//!
//! # Method
//!
//! The outputs y (tip position, tip orientation, backbone points at chosen arc lengths)
//! are functions of the node states x, and x(q) solves F(x; q) = 0. For a cotangent ybar
//! (dloss/dy), the chain rule with dx/dq = J^-1 (-dF/dq) gives
//!
//! ```text
//! dloss/dq = ybar . (dy/dx) dx/dq = lambda . (-dF/dq),   J^T lambda = (dy/dx)^T ybar
//! ```
//!
//! so one transposed solve with the factors of the converged Jacobian serves every
//! parameter, which then costs only its -dF/dq (exact, or two residual evaluations; the same
//! vectors as the forward sensitivities, `named.rs`). The gradient equals the forward
//! sensitivities contracted with the cotangent, to rounding (tests/adjoint.rs).
//!
//! # Held pull-ins
//!
//! A displacement-controlled tendon keeps its pull-in q_m: its tension tau_m follows so
//! that its length constraint holds. With the state derivatives D_m = dx/dtau_m of the
//! taut ones, G the path lengths' derivative in the states and S = C - G [D_m] (the
//! constraints' Schur complement, [`super::displacement_sensitivities`]), the forward
//! derivative of the outputs in a parameter is Y D_q + Y [D_m] S^-1 G D_q (Y = dy/dx), and
//! in a pull-in Y [D_m] S^-1 e_m. Contracted with ybar:
//!
//! ```text
//! c_m = ybar . Y D_m = lambda . (-dF/dtau_m),     w = S^-T c,
//! dloss/dq_m = w_m,    dloss/dq = (lambda + mu) . (-dF/dq),   J^T mu = G^T w,
//! ```
//!
//! so the pull-ins cost one more transposed solve (and the k solves S needs); the tension
//! of a displacement-controlled tendon has no gradient of its own (its pull-in sets it).
//! The routing offset of a held tendon also moves its path length at fixed states, a
//! term this does not include: it is refused with what to do.
//!
//! # Outputs and their cotangents
//!
//! In the solver's scaled increments (12 per node, d = (dp / L, dtheta, dv, du L), R -> R
//! exp(hat(dtheta))):
//!
//! - tip position p(L) (m): dp = L d_p, so the cotangent enters the tip node's d_p slot as
//!   L pbar;
//! - tip orientation as the world-frame rotation vector omega, R_tip -> exp(hat(omega))
//!   R_tip: omega = R_tip dtheta, so omegabar enters the dtheta slot as R_tip^T omegabar.
//!   A cotangent Rbar on the rotation matrix itself becomes omegabar by
//!   [`rotation_cotangent`];
//! - backbone point p(s_j), the cubic Hermite interpolant of [`Solution::at`] on the
//!   interval (k, k + 1) holding s_j: p = h00 p_k + h10 h R_k v_k + h01 p_k+1 + h11 h
//!   R_k+1 v_k+1, and d(R v) = R (dtheta x v) + R dv, so node k's slots get L h00 pbar
//!   (d_p), h10 h v_k x (R_k^T pbar) (dtheta) and h10 h R_k^T pbar (d_v), likewise node k + 1
//!   with h01 and h11.

use super::control::pulled;
use super::held::Held;
use super::{Sensitivity, singular};
use crate::collocation::unknowns::{NODE, P, THETA, V};
use crate::error::{Result, invalid};
use crate::model::parameter::Parameter;
use crate::model::robot::{Robot, RodModel};
use crate::solution::Solution;
use nalgebra::{DVector, Matrix3, Vector3};

/// A cotangent (the gradient of a scalar loss) on the outputs of a solved robot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cotangent {
    /// dloss/dp(L): on the tip position (1/m per unit of loss), world frame.
    pub tip_position: Vector3<f64>,
    /// dloss/domega: on the tip orientation's world-frame rotation vector omega, R_tip ->
    /// exp(hat(omega)) R_tip (per rad); [`rotation_cotangent`] converts one on R_tip.
    pub tip_rotation: Vector3<f64>,
    /// dloss/dp(s_j): on the backbone points at the [`Adjoint`]'s arc lengths, one each
    /// (empty when there are none).
    pub points: Vec<Vector3<f64>>,
}

/// The cotangent on the world-frame rotation vector omega (R -> exp(hat(omega)) R) of a
/// cotangent `R_bar` (dloss/dR_ij) on the rotation matrix `R`: dloss = <Rbar, hat(omega) R>
/// = <Rbar R^T, hat(omega)>, the vee of the antisymmetric part of A = Rbar R^T times two:
/// (A_32 - A_23, A_13 - A_31, A_21 - A_12).
pub fn rotation_cotangent(R: &Matrix3<f64>, R_bar: &Matrix3<f64>) -> Vector3<f64> {
    let a = R_bar * R.transpose();
    Vector3::new(a[(2, 1)] - a[(1, 2)], a[(0, 2)] - a[(2, 0)], a[(1, 0)] - a[(0, 1)])
}

/// A solved robot linearized for gradients: the factors of its collocation Jacobian and the
/// arc lengths of its sampled backbone points.
pub struct Adjoint<'a> {
    /// The linearization and the -dF/dq of every parameter.
    sensitivity: Sensitivity<'a>,
    /// The taut displacement-controlled tendons, whose pull-ins are held (module docs,
    /// "Held pull-ins").
    held: Held,
    /// Arc lengths s_j of the sampled backbone points (m), in [0, L].
    samples: Vec<f64>,
    /// The solution (for the Hermite interpolant's intervals and node states).
    solution: Solution,
    /// lambda = J^-T (dy/dx)^T ybar for the last cotangent; scratch for the next one.
    multiplier: Vec<f64>,
}

impl<'a> Adjoint<'a> {
    /// Linearizes `robot`'s collocation system at `solution` (as [`Sensitivity::new`]) for
    /// outputs that include the backbone points at arc lengths `samples` (m).
    ///
    /// Displacement-controlled tendons keep their pull-ins: the gradients are those of the
    /// robot as it is driven (module docs, "Held pull-ins"), and `displacement.I` is a
    /// parameter.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a sample outside [0, L] or not finite, for a robot
    /// with friction; as [`Sensitivity::new`].
    pub fn new(robot: &'a Robot, solution: &Solution, samples: &[f64]) -> Result<Self> {
        if let Some(i) = robot.tendons.iter().position(|t| t.active_friction().is_some()) {
            return Err(invalid(
                format!("tendon {}", i + 1),
                "has friction; the adjoint gradients solve the frictionless system's transpose, not the system \
                 bordered by the capstan rows",
                "use tip_sensitivities (forward sensitivities handle friction), or set the tendon's friction to 0",
            ));
        }
        let length = robot.length();
        if let Some(s) = samples.iter().find(|s| !(s.is_finite() && (0.0..=length).contains(*s))) {
            return Err(invalid(
                "samples",
                format!("has the arc length {s} m, outside the rod [0, {length}] m"),
                "give backbone sample points between 0 and the rod length",
            ));
        }
        let mut sensitivity = Sensitivity::new(robot, solution)?;
        let held = Held::new(&mut sensitivity, robot, solution)?;
        let unknowns = sensitivity.border.system().unknowns();
        Ok(Adjoint {
            sensitivity,
            held,
            samples: samples.to_vec(),
            solution: solution.clone(),
            multiplier: vec![0.0; unknowns],
        })
    }

    /// The arc lengths of the sampled backbone points (m).
    pub fn samples(&self) -> &[f64] {
        &self.samples
    }

    /// The backbone points p(s_j) (m, world frame), from [`Solution::at`].
    pub fn points(&self) -> Vec<Vector3<f64>> {
        self.samples.iter().map(|&s| self.solution.at(s).p).collect()
    }

    /// dloss/dq for each of `parameters`, for the loss whose gradient on the outputs is
    /// `cotangent`: one transposed solve, then a dot product with each parameter's -dF/dq
    /// (module docs). Units: loss per unit of each parameter (per N, per Pa, ...).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] when `cotangent.points` does not have one entry per
    /// sample, for a parameter the robot does not have, or a singular Jacobian; as
    /// [`Sensitivity::parameter`].
    pub fn gradient(&mut self, cotangent: &Cotangent, parameters: &[Parameter]) -> Result<Vec<f64>> {
        self.multiplier_for(cotangent)?;
        let pulls = self.hold_pull_ins()?;
        let robot = self.sensitivity.robot();
        parameters.iter().try_for_each(|&p| self.held.check(p))?;
        parameters
            .iter()
            .map(|&p| match p {
                Parameter::Displacement(i) => {
                    pulled(robot, i)?;
                    Ok(pulls.iter().find(|(j, _)| *j == i).map_or(0.0, |(_, w)| *w))
                }
                // Its pull-in sets it (a zero column, as in the tip Jacobian).
                Parameter::Tension(i) if robot.tendons.get(i).is_some_and(|t| t.displacement().is_some()) => Ok(0.0),
                _ => {
                    self.sensitivity.parameter_rhs(p)?;
                    Ok(self.dot_rhs())
                }
            })
            .collect()
    }

    /// lambda . (-dF/dq) for the right-hand side in the sensitivity's buffer.
    fn dot_rhs(&self) -> f64 {
        self.multiplier
            .iter()
            .zip(&self.sensitivity.scratch[0])
            .map(|(l, r)| l * r)
            .sum()
    }

    /// With held pull-ins, turns the multiplier lambda = J^-T (dy/dx)^T ybar into
    /// J^-T ((dy/dx)^T ybar + G^T w) with w = S^-T c, c_m = lambda . (-dF/dtau_m) (module
    /// docs, "Held pull-ins"), and returns w per held tendon: (tendon, dloss/dq_tendon).
    fn hold_pull_ins(&mut self) -> Result<Vec<(usize, f64)>> {
        let Some(h) = self.held.directions() else {
            return Ok(Vec::new());
        };
        let mut c = DVector::zeros(h.tendons.len());
        for (m, &i) in h.tendons.iter().enumerate() {
            self.sensitivity.tension_rhs(i)?;
            c[m] = self.dot_rhs();
        }
        let w = h
            .displacement_by_tension()
            .transpose()
            .lu()
            .solve(&c)
            .ok_or_else(singular)?;
        let g = &mut self.sensitivity.scratch[1];
        g.fill(0.0);
        h.add_length_cotangent(&w, self.solution.length(), g);
        let mu = self.sensitivity.workspace.solve_transposed(g).ok_or_else(singular)?;
        for (l, m) in self.multiplier.iter_mut().zip(mu) {
            *l += m;
        }
        Ok(h.tendons.iter().copied().zip(w.iter().copied()).collect())
    }

    /// Solves J^T lambda = (dy/dx)^T ybar into `multiplier`.
    fn multiplier_for(&mut self, cotangent: &Cotangent) -> Result<()> {
        if cotangent.points.len() != self.samples.len() {
            return Err(invalid(
                "cotangent.points",
                format!(
                    "has {} entries, but there are {} sample points",
                    cotangent.points.len(),
                    self.samples.len()
                ),
                "give one cotangent per backbone sample point",
            ));
        }
        let length = self.solution.length();
        let g = &mut self.multiplier;
        g.fill(0.0);
        let nodes = &self.solution.nodes;
        let tip = nodes.len() - 1;
        let fixed_strain = self.sensitivity.robot().rod_model == RodModel::Kirchhoff;
        add(g, tip, P, &(cotangent.tip_position * length));
        add(g, tip, THETA, &(nodes[tip].R.transpose() * cotangent.tip_rotation));
        for (&s, pbar) in self.samples.iter().zip(&cotangent.points) {
            let (k, [h00, h10, h01, h11]) = self.solution.interval(s, false);
            let h = nodes[k + 1].s - nodes[k].s;
            for (node, value, slope) in [(k, h00, h10 * h), (k + 1, h01, h11 * h)] {
                let body = nodes[node].R.transpose() * pbar;
                add(g, node, P, &(pbar * (length * value)));
                add(g, node, THETA, &(nodes[node].v.cross(&body) * slope));
                // The slope R v moves with the coordinate v only on a Cosserat rod.
                if !fixed_strain {
                    add(g, node, V, &(body * slope));
                }
            }
        }
        let lambda = self.sensitivity.workspace.solve_transposed(g).ok_or_else(singular)?;
        self.multiplier.copy_from_slice(lambda);
        Ok(())
    }
}

/// Adds `value` to the three slots from `slot` of node `node` in the scaled vector `g`.
fn add(g: &mut [f64], node: usize, slot: usize, value: &Vector3<f64>) {
    for i in 0..3 {
        g[node * NODE + slot + i] += value[i];
    }
}
