//! Sensitivities of a solved shape to tensions, loads, material and base pose, by the
//! implicit function theorem on the converged collocation system.
//!
//! # Method
//!
//! A collocation solution is a root of F(x; q) = 0, where x are the node states and q a
//! parameter of the robot (a tension, a tip-force component, E, ...). Differentiating
//! F(x(q); q) = 0 gives
//!
//! ```text
//! dx/dq = -J^-1 dF/dq,    J = dF/dx at the solution
//! ```
//!
//! J is the exact Newton Jacobian the solver already uses ([`crate::advanced::system::System::jacobian`]), assembled
//! once per [`Sensitivity`]; every parameter then costs one linear solve plus whatever
//! dF/dq costs. x is the solver's scaled right perturbation, 12 per node,
//! d = (dp / L, dtheta, dv, du L) with R -> R exp(hat(dtheta)) (docs/numerics.md), so the
//! solve gives dp/dq = L d_p, the world-frame rotation R dtheta, dv/dq = d_v and
//! du/dq = d_u / L at every node.
//!
//! The result is the exact derivative of the *discrete* solution on the solution's mesh:
//! it agrees with finite differences of full solves on that mesh to the finite-difference
//! error (tests/sensitivity.rs), and with the derivative of the continuous model to the
//! discretization error (order 4).
//!
//! # dF/dq
//!
//! **Exact** where the residual is linear in the parameter: the tip force and moment enter
//! only the tip rows, as -D^-1 R^T e and -L C^-1 R^T e (strain units, as the rows are
//! scaled); the base position only the base rows, as -e / L; a base rotation
//! R0 -> exp(hat(phi)) R0 only the base rotation rows log(R0^T R(0)), as -J_l^-1 R0^T.
//!
//! **Exact for the tensions**: eq. 13 is linear in each tension once the tendon's path terms
//! are formed (A_i = tau_i P_i / |p_i|), and so are the point loads where a tendon ends or
//! bends, so dF/dtau_i at fixed states is the tendon's own term per unit of tension
//! ([`System::parameter_columns`], docs/sensitivity.md, "Exact tension columns"), carried
//! through the collocation scheme's midpoint by the chain rule. One pass over the mesh
//! gives every tendon's column; a slack tendon (not in the model at 0 N) gets the right
//! derivative, the load its first pull adds. With tendons with friction the tension also
//! sets the capstan rows: there it stays differenced (below).
//!
//! **Differences** elsewhere (moduli, distributed force components, routing offsets, the
//! load scale, friction coefficients, tensions with friction, anything passed to
//! [`Sensitivity::derivative`]): the residual takes its parameters from a [`Robot`], so
//! dF/dq is differenced at fixed x with the parameter moved in a clone of the robot
//! (exact derivatives would need the model generic in its parameters, not only in the
//! state). The step is [`RELATIVE_STEP`] = 1e-4 times the parameter's scale. The residual
//! resolves a parameter's effect only to about 1e-11 relative, some 1e5 eps: eq. 13 is a
//! 6 x 6 solve that mixes EA (1e5 N on the prototype) with EI (4e-3 N m^2), so a change of
//! q perturbs its rounding. A central difference then carries a rounding error of about
//! 1e-11 / h_rel and a truncation error of about h_rel^2 (exactly h_rel^2 for E, where the
//! shape goes as 1/E), which balance near h_rel = 1e-4 at about 1e-8. Measured on the
//! prototype (cases S and H, 64 intervals) against Richardson-extrapolated references:
//! 1e-8 to 6e-8 relative for tensions and moduli at 1e-4, against up to 7e-7 at
//! eps^(1/3) = 6e-6 and 5e-5 at 1e-7 (the exact tension columns agree with those
//! differences to 2e-13 to 1e-7, tests/sensitivity.rs).
//!
//! Scales: a tension's (with friction) is its value, but at least E I / (L |r_i(0)|), the
//! tension that bends the rod through about a radian (2.2 N on the prototype; E I / L^2 for
//! a tendon on the centreline); E's and G's are their values.
//!
//! A tendon with zero tension is left out of the model, and a string cannot push, so its
//! derivative is the one-sided (right) derivative: exact without friction, else the
//! second-order forward difference (-3 F(0) + 4 F(h) - F(2h)) / (2h)
//! ([`Difference::Forward`]), with the log tensions of a tendon with friction at 0 N held
//! at the capstan profile of its first pull (`first_pull.rs`).
//!
//! # Conventions
//!
//! - Tip pose rows: position (m per unit of the parameter), then the tip rotation as a
//!   world-frame rotation vector omega, R_tip -> exp(hat(omega)) R_tip (rad per unit).
//!   The solver's body-frame perturbation dtheta of the last node maps to omega = R_tip dtheta.
//! - Base rotation: R0 -> exp(hat(phi)) R0 with phi a world-frame rotation vector (rad), the
//!   same convention as the tip rotation; base position p0 -> p0 + dp0 (m, world).
//! - Moduli (rods built from geometry, [`crate::model::rod::Geometry`]): d/dE at fixed Poisson's
//!   ratio (G = E / (2 (1 + nu)) follows E, as when a material's E is calibrated), d/dG at
//!   fixed E, and d/dE at fixed G from the chain rule
//!   d/dE|_G = d/dE|_nu - (G / E) d/dG|_E (dG/dE at fixed nu is G / E).
//!
//! # Cost
//!
//! One Jacobian assembly and one factorization (the structured elimination of
//! `collocation/linear/blocks.rs`; a [`crate::Solver`] after a warm solve factors the
//! Jacobian its stability verdict evaluated at the solution instead of assembling it),
//! then per parameter one solve with the stored factors ([`Workspace::solve_again`]), plus
//! one pass over the mesh for all tension columns together, and two residual evaluations
//! for a differenced parameter (three one-sided). The tip's tension columns, where nothing
//! needs the other nodes, are formed before the factoring and carried through it, which
//! gives their tip unknowns without a solve (`Workspace::factor_with_last`).
#![allow(non_snake_case)]

mod adjoint;
mod control;
mod ends;
mod exact;
mod first_pull;
mod held;
mod named;
mod tip;

pub use adjoint::{Adjoint, Cotangent, rotation_cotangent};
pub(crate) use control::{backbone_columns, tension_tips, tip_columns};
pub use control::{backbone_jacobian, columns, tip_jacobian};
pub(crate) use held::TensionDirections;
pub use held::{DisplacementSensitivities, displacement_sensitivities};
pub(crate) use tip::tip_sensitivities_from;
pub use tip::{ModulusSensitivities, TipSensitivities, backbone_tension_sensitivity, tip_sensitivities};

use crate::collocation::LinearSolver;
use crate::collocation::friction::Capstan;
use crate::collocation::newton::Workspace;
use crate::collocation::system::System;
use crate::collocation::unknowns::{self, nonzeros};
use crate::error::{Result, invalid};
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate_nodes;
use crate::model::equations::Model;
use crate::model::robot::{Robot, RodModel};
use crate::solution::{Solution, State};
use nalgebra::{Vector3, Vector6};

/// Relative finite-difference step for dF/dq, 1e-4: it balances the truncation (about
/// h_rel^2) against the rounding (about 1e-11 / h_rel) of differencing the residual in a
/// parameter (module docs), for an error near 1e-8.
pub const RELATIVE_STEP: f64 = 1e-4;

/// Largest scaled residual max-norm accepted at the given solution, 1e-8: a guard against
/// a solution of another robot or an unconverged one, not a precision target. The
/// linearization point is off the discrete solution by about 1e3 to 1e4 times the residual
/// (measured on case H: a residual of 5e-12 left the tip 8e-9 m off) and the sensitivities
/// err relatively by about as much: 1e-7 or less at the solver's default tolerance 1e-11,
/// up to 1e-4 at this limit. Shooting solutions at tolerance 1e-12 leave 5e-11 to 4e-10 on
/// their own nodes and pass.
pub const RESIDUAL_LIMIT: f64 = 1e-8;

/// The scaled max-norm of the order-6 residual at `states`, when `solution` is an order-6
/// answer (`error_estimate.order` 6, docs/numerics.md "The order-6 answer"), else infinity.
/// Such an answer solves the order-4 system shifted by the deferred correction's defect, so
/// its order-4 residual is of the size of the order-4 truncation (measured 3e-9 to 1e-6 on
/// S, H and random robots at 1e-8 to 1e-11 L), while its order-6 residual is at most
/// 2e-10 on them: that is the residual the guard checks for it.
///
/// # Errors
/// A model breakdown at a stage of the order-6 scheme.
fn order6_residual(system: &System, states: &[State], solution: &Solution) -> Result<f64> {
    if solution.report.error_estimate.map(|e| e.order) != Some(6) {
        return Ok(f64::INFINITY);
    }
    let mut residual = vec![0.0; system.unknowns()];
    let mut local = vec![0.0; states.len() - 1];
    let mut rates = vec![Vector6::zeros(); states.len()];
    system.order6_residual(states, &mut residual, &mut local, &mut rates)?;
    Ok(residual.iter().fold(
        0.0f64,
        |m, r| if r.is_finite() { m.max(r.abs()) } else { f64::INFINITY },
    ))
}

/// How dF/dq is differenced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Difference {
    /// (F(q + h) - F(q - h)) / (2h): second order, for parameters free on both sides.
    Central,
    /// (-3 F(q) + 4 F(q + h) - F(q + 2h)) / (2h): second order and one-sided, for a
    /// parameter at a bound (a slack tendon's tension, which cannot go negative).
    Forward,
}

/// The derivative of one node's state with respect to a scalar parameter q.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeDerivative {
    /// Arc length of the node (m).
    pub s: f64,
    /// dp/dq, world frame (m per unit of q).
    pub p: Vector3<f64>,
    /// World-frame rotation vector omega with R -> exp(hat(omega dq)) R (rad per unit of q).
    pub rotation: Vector3<f64>,
    /// dv/dq, body frame (per unit of q).
    pub v: Vector3<f64>,
    /// du/dq, body frame (rad/m per unit of q).
    pub u: Vector3<f64>,
}

impl NodeDerivative {
    /// The pose part: position rows then rotation rows.
    pub fn pose(&self) -> Vector6<f64> {
        let mut out = Vector6::zeros();
        out.fixed_rows_mut::<3>(0).copy_from(&self.p);
        out.fixed_rows_mut::<3>(3).copy_from(&self.rotation);
        out
    }
}

/// The collocation system linearized at a solution: its Jacobian and a linear-solver
/// workspace, ready to give the derivative of every node state with respect to any
/// parameter of the robot.
pub struct Sensitivity<'a> {
    /// The system at the solution (the robot as given, full load), bordered by the log
    /// tensions of its tendons with friction (a border without rows when it has none).
    border: Capstan<'a>,
    /// Node states of the solution.
    states: Vec<State>,
    /// Linear solver buffers for the mesh, holding the factors of the Jacobian at the solution.
    workspace: Workspace,
    /// Scratch: residuals at the stencil points and the right-hand side.
    scratch: [Vec<f64>; 3],
    /// -dF/dtau_i of every tendon (the right-hand sides), column-major
    /// ([`System::parameter_columns`]), evaluated at the first tension asked for or before
    /// factoring (one pass serves every tendon); frictionless systems only.
    tension_columns: Option<Vec<f64>>,
    /// The last node's unknowns of J x = -dF/dtau_i for every tendon, solved while
    /// factoring ([`Sensitivity::with_workspace`] with `tips`).
    tension_tips: Option<Vec<[f64; unknowns::NODE]>>,
    /// dF/dk_j of the six section stiffnesses, column-major, evaluated at the first modulus
    /// asked for ([`Sensitivity::stiffness`]).
    stiffness_columns: Option<Vec<f64>>,
}

impl<'a> Sensitivity<'a> {
    /// Linearizes `robot`'s collocation system at `solution`, on the mesh through the
    /// solution's nodes.
    ///
    /// `solution` should come from [`crate::collocation::solve`] on this robot: the mesh is
    /// rebuilt from its node arc lengths and the robot's breakpoints, and the sensitivities
    /// are those of the collocation discretization on it. A fine shooting solution also
    /// works (its nodes then form the mesh; on the prototype the result agrees with a
    /// 64-interval collocation solution to 1e-6).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] when the robot is invalid, when the solution's nodes do
    /// not form a mesh of this robot (other breakpoints), when the solution does not solve
    /// the robot's collocation system (scaled residual above [`RESIDUAL_LIMIT`]; for an
    /// order-6 answer, the order-6 residual's, docs/numerics.md "The order-6 answer"), or when the
    /// Jacobian there is singular (a bifurcation, where no sensitivity exists); a model
    /// breakdown at the solution's states.
    pub fn new(robot: &'a Robot, solution: &Solution) -> Result<Self> {
        Self::with_workspace(robot, solution, None, None, false, false)
    }

    /// As [`Sensitivity::new`], factoring in `workspace` when it was built for the
    /// solution's mesh with the structured solver (a [`crate::Solver`]'s, which keeps its
    /// buffers and pattern), else in a new one; [`Sensitivity::into_workspace`] gives it back.
    /// With `evaluated`, the workspace's value buffer already holds the Jacobian of this
    /// robot's collocation system at the solution's states, from a solve that converged
    /// there (a [`crate::Solver`]'s stability verdict after a warm solve,
    /// [`Workspace::evaluated_at_solution`]): those values are factored, without assembling
    /// the Jacobian again or checking the residual. With `tips` and no friction, every
    /// tendon's tension column is formed first and carried through the factoring, which
    /// gives the tip's unknowns of each ([`Workspace::factor_with_last`]; what
    /// [`Sensitivity::tension_tip`] returns, bitwise as solving with the factors would).
    /// `mesh`, when the caller built it already, is `Mesh::from_points(robot, s)` for the
    /// solution's node arc lengths s (not built again).
    ///
    /// # Errors
    /// As [`Sensitivity::new`].
    pub(crate) fn with_workspace(
        robot: &'a Robot,
        solution: &Solution,
        workspace: Option<Workspace>,
        mesh: Option<Mesh>,
        evaluated: bool,
        tips: bool,
    ) -> Result<Self> {
        robot.validate()?;
        if solution.tendons.len() != robot.tendons.len() {
            return Err(invalid(
                "solution",
                format!(
                    "has {} tendon state(s), but the robot has {} tendon(s)",
                    solution.tendons.len(),
                    robot.tendons.len()
                ),
                "pass a solution of this robot (same tendons in file order)",
            ));
        }
        let points = || solution.nodes.iter().map(|n| n.s).collect::<Vec<_>>();
        let mesh = mesh.map_or_else(|| Mesh::from_points(robot, &points()), Ok)?;
        let same =
            mesh.nodes.len() == solution.nodes.len() && mesh.nodes.iter().zip(&solution.nodes).all(|(m, n)| m.s == n.s);
        if !same {
            return Err(invalid(
                "solution",
                format!(
                    "has {} nodes, but the mesh through their arc lengths and the robot's {} breakpoints has {}",
                    solution.nodes.len(),
                    robot.breakpoints().len(),
                    mesh.nodes.len()
                ),
                "pass a solution of this robot (same tendon terminations and point loads)",
            ));
        }
        let model = solved_model(robot, solution);
        let states: Vec<State> = interpolate_nodes(&model, &solution.nodes, &mesh);
        let mut workspace = workspace;
        // With the verdict's Jacobian at the solution in the workspace, the sites its system
        // left there are this robot's (the caller vouches for it, as for the values).
        let kept = evaluated
            && !crate::model::friction::any(robot)
            && workspace
                .as_ref()
                .is_some_and(|w| w.evaluated_at_solution() && w.has_sites_of(&model, &mesh));
        let mut border = if kept && let Some(w) = workspace.as_mut() {
            Capstan::plain(w.kept_system(model, mesh))
        } else {
            Capstan::at_solution(model, mesh, solution)
        };
        let n = border.system().unknowns() + border.border_rows();
        let mut buffer = |len: usize| {
            workspace
                .as_mut()
                .map_or_else(|| vec![0.0; len], |w| w.take_buffer(len))
        };
        let scratch = [buffer(n), buffer(n), buffer(n)];
        // The tension right-hand sides to carry through the factoring, formed once the
        // solution is known to solve the system.
        let count = robot.tendons.len();
        let carry = tips && border.border_rows() == 0;
        let mut last = vec![[0.0; unknowns::NODE]; if carry { count } else { 0 }];
        if let Some(mut workspace) = workspace.take_if(|w| evaluated && w.evaluated_at_solution()) {
            // The right-hand sides the verdict formed with these values, if it did
            // ([`crate::Solver::keep_tension_columns`]), else one pass over the mesh.
            let carried = carry
                .then(|| match workspace.take_tension_rhs(n * count) {
                    Some(columns) => Ok(columns),
                    None => exact::tension_rhs_columns(border.system(), &states, workspace.take_buffer(n * count)),
                })
                .transpose()?;
            let ok = match &carried {
                Some(columns) => workspace.factor_evaluated_with_last(columns, count, &mut last),
                None => workspace.factor_evaluated(),
            };
            if !ok {
                return Err(singular());
            }
            return Ok(Sensitivity {
                border,
                states,
                workspace,
                scratch,
                tension_tips: carried.is_some().then_some(last),
                tension_columns: carried,
                stiffness_columns: None,
            });
        }
        let [mut residual, second, third] = scratch;
        // The assembly writes every value: a kept buffer serves.
        let len = nonzeros(&border.system().mesh);
        let mut values = workspace
            .as_mut()
            .map_or_else(|| vec![0.0; len], |w| w.take_buffer(len));
        border.linearize(&states, &mut residual, &mut values)?;
        let mut norm = residual.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        if norm > RESIDUAL_LIMIT && border.border_rows() == 0 && residual.iter().all(|r| r.is_finite()) {
            norm = norm.min(order6_residual(border.system(), &states, solution)?);
        }
        if norm > RESIDUAL_LIMIT || residual.iter().any(|r| !r.is_finite()) {
            return Err(invalid(
                "solution",
                format!(
                    "leaves a scaled residual of {norm:.3e} on this robot's collocation system (limit {RESIDUAL_LIMIT:.0e})"
                ),
                "pass a converged collocation solution of this robot (collocation::solve_from polishes a nearby one)",
            ));
        }
        let mut workspace = match workspace {
            Some(w) => w,
            None => Workspace::new(border.system(), LinearSolver::Blocks)?,
        };
        let carried = carry
            .then(|| exact::tension_rhs_columns(border.system(), &states, workspace.take_buffer(n * count)))
            .transpose()?;
        // Factor once; every parameter then costs one solve with the stored factors.
        let ok = match &carried {
            Some(columns) => workspace.factor_with_last(&values, columns, count, &mut last),
            None => workspace.factor(&values),
        };
        if !ok {
            return Err(singular());
        }
        workspace.give_buffer(values);
        Ok(Sensitivity {
            border,
            states,
            workspace,
            scratch: [residual, second, third],
            tension_tips: carried.is_some().then_some(last),
            tension_columns: carried,
            stiffness_columns: None,
        })
    }

    /// The system, the solution's node states and the workspace holding the factors of the
    /// Jacobian there (the linearized dynamics runs on them: collocation/dynamics.rs).
    /// Without friction the factors are those of the whole system; with friction they are the
    /// backbone block's only (the capstan rows are eliminated per solve).
    pub(crate) fn into_parts(self) -> (System<'a>, Vec<State>, Workspace) {
        (self.border.into_system(), self.states, self.workspace)
    }

    /// The border (the system with its capstan rows), the solution's node states and the
    /// workspace holding the factors of the backbone block's Jacobian there, for the
    /// linearized dynamics with friction (collocation/dynamics/friction.rs), which factors
    /// the bordered matrix from them.
    pub(crate) fn into_border(self) -> (Capstan<'a>, Vec<State>, Workspace) {
        (self.border, self.states, self.workspace)
    }

    /// The linear-solver workspace, holding the factors of the Jacobian at the solution,
    /// with this linearization's buffers for the next one's ([`Workspace::take_buffer`]).
    pub(crate) fn into_workspace(self) -> Workspace {
        let mut workspace = self.workspace;
        // The system's buffers (its sites among them) for the next system on the mesh.
        workspace.keep_system(self.border.into_system());
        let columns = [self.tension_columns, self.stiffness_columns];
        self.scratch
            .into_iter()
            .chain(columns.into_iter().flatten())
            .for_each(|b| workspace.give_buffer(b));
        workspace
    }

    /// The robot the system belongs to.
    pub fn robot(&self) -> &'a Robot {
        self.border.system().model.robot
    }

    /// Number of nodes (the solution's).
    pub fn nodes(&self) -> usize {
        self.states.len()
    }

    /// The derivative of every node state with respect to a scalar parameter q, one entry
    /// per node.
    ///
    /// `perturb(robot, dq)` changes q by dq in a clone of the robot (it must not move
    /// breakpoints); `step` is the difference step h in q's unit, `difference` the stencil.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a step that is not positive and finite, a
    /// perturbation that moves a breakpoint, or a singular Jacobian (a bifurcation such as
    /// buckling, where no sensitivity exists); a model breakdown at a perturbed robot.
    ///
    /// # Examples
    /// ```
    /// use tdcr::collocation::sensitivity::{Difference, Sensitivity};
    /// let robot = tdcr::cases::case_s();
    /// let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
    /// let mut sens = Sensitivity::new(&robot, &solution).unwrap();
    /// // Tip motion per newton of tendon 1's tension (2.94 N), stepping 1e-4 of it.
    /// let step = tdcr::collocation::sensitivity::RELATIVE_STEP * 2.94;
    /// let d = sens
    ///     .derivative(step, Difference::Central, |r, dq| {
    ///         let t = &mut r.tendons[0];
    ///         t.set_tension(t.tension() + dq)
    ///     })
    ///     .unwrap();
    /// let tip = d.last().unwrap();
    /// assert!(tip.p.norm() > 0.0);
    /// ```
    pub fn derivative(
        &mut self,
        step: f64,
        difference: Difference,
        perturb: impl Fn(&mut Robot, f64),
    ) -> Result<Vec<NodeDerivative>> {
        self.differenced(step, difference, |border, states, dq, out| {
            exact::residual_at(border, states, &perturb, dq, out)
        })
    }

    /// As [`Sensitivity::derivative`], with `residual(border, states, dq, out)` writing the
    /// residual (backbone rows, then the capstan rows of tendons with friction) at the
    /// solution's `states` (and log tensions) for the parameter moved by dq into `out`.
    fn differenced(
        &mut self,
        step: f64,
        difference: Difference,
        residual: impl FnMut(&mut Capstan<'a>, &[State], f64, &mut [f64]) -> Result<()>,
    ) -> Result<Vec<NodeDerivative>> {
        self.differenced_rhs(step, difference, residual)?;
        self.respond()
    }

    /// Writes -dF/dq, differenced as [`Sensitivity::differenced`] says, into the right-hand
    /// side buffer `scratch[0]`.
    fn differenced_rhs(
        &mut self,
        step: f64,
        difference: Difference,
        mut residual: impl FnMut(&mut Capstan<'a>, &[State], f64, &mut [f64]) -> Result<()>,
    ) -> Result<()> {
        if !(step.is_finite() && step > 0.0) {
            return Err(invalid(
                "step",
                format!("is {step}"),
                "give a positive finite difference step",
            ));
        }
        let [f0, f1, f2] = &mut self.scratch;
        let (offsets, weights): ([f64; 3], [f64; 3]) = match difference {
            Difference::Central => ([step, -step, 0.0], [1.0, -1.0, 0.0]),
            Difference::Forward => ([0.0, step, 2.0 * step], [-3.0, 4.0, -1.0]),
        };
        let terms = if difference == Difference::Central { 2 } else { 3 };
        for (out, &dq) in [&mut *f0, &mut *f1, &mut *f2].into_iter().zip(&offsets).take(terms) {
            residual(&mut self.border, &self.states, dq, out)?;
        }
        // rhs = -dF/dq, written over f0.
        let scale = -1.0 / (2.0 * step);
        for i in 0..f0.len() {
            let mut d = weights[0] * f0[i] + weights[1] * f1[i];
            if terms == 3 {
                d += weights[2] * f2[i];
            }
            f0[i] = d * scale;
        }
        Ok(())
    }

    /// Solves J dx = rhs for the right-hand side in `scratch[0]` (-dF/dq, then -dpsi/dq
    /// with friction: the bordered solve) and converts the scaled dx into node derivatives.
    fn respond(&mut self) -> Result<Vec<NodeDerivative>> {
        let dx = self
            .border
            .respond(&self.scratch[0], &mut self.workspace)
            .ok_or_else(singular)?;
        let length = self.robot().length();
        // On a Kirchhoff rod v = v* whatever the parameter: the V unknowns are the force's.
        let fixed_strain = self.robot().rod_model == RodModel::Kirchhoff;
        Ok(self
            .states
            .iter()
            .enumerate()
            .map(|(k, x)| {
                let [p, theta, v, u] = unknowns::node_increments(&dx, k, length);
                NodeDerivative {
                    s: x.s,
                    p,
                    rotation: x.R * theta,
                    v: if fixed_strain { Vector3::zeros() } else { v },
                    u,
                }
            })
            .collect())
    }

    /// Tendon `tendon` (0-based) of `robot`: [`crate::Error::InvalidInput`] when out of range.
    fn tendon_of(robot: &'a Robot, tendon: usize) -> Result<&'a crate::model::tendon::Tendon> {
        robot.tendons.get(tendon).ok_or_else(|| {
            invalid(
                "tendon",
                format!("is {tendon}, but the robot has {} tendons", robot.tendons.len()),
                "give a 0-based tendon index",
            )
        })
    }
}

/// The model of `robot` at the tensions of `solution`: a displacement-controlled tendon's
/// tension is the solved one (its pull-in held fixed), a tension-controlled tendon's its input.
fn solved_model<'a>(robot: &'a Robot, solution: &Solution) -> Model<'a> {
    let mut model = Model::new(robot);
    for (i, t) in robot.tendons.iter().enumerate() {
        if t.displacement().is_some() {
            model.tensions[i] = solution.tendons[i].tension;
        }
    }
    model
}

/// Characteristic force E I / L^2 (N): the step scale of a tendon on the centreline.
fn force_scale(robot: &Robot) -> f64 {
    robot.bending_stiffness() / robot.length().powi(2)
}

/// The error for a solution at a singular point of the collocation system.
pub(super) fn singular() -> crate::Error {
    invalid(
        "solution",
        "is at a singular point of the collocation system (zero pivot or non-finite step)",
        "no sensitivity exists at a bifurcation such as buckling; move the loads slightly",
    )
}
