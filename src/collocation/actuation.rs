//! Displacement-controlled tendons in the collocation solver (docs/actuation.md).
//!
//! A tendon given a pull-in q_j instead of a tension makes its tension tau_j an unknown,
//! fixed by the length constraint (with the gap phi_j, the length the actuator has not
//! taken up)
//!
//! ```text
//! phi_j(x, tau) = l_ref_j - l_j(x) - q_j + c_j tau_j,   tau_j >= 0, phi_j >= 0, tau_j phi_j = 0,
//! ```
//!
//! where l_j(x) is the path length by the node quadrature ([`NodeQuadrature`]), l_ref_j its
//! unloaded value and c_j the tendon's compliance (0 when inextensible). The
//! complementarity (a tendon cannot push) is solved inside Newton in the semismooth
//! Fischer-Burmeister form psi_j = sqrt(a^2 + b^2) - a - b = 0 with a = tau_j / T_j and
//! b = phi_j / L (T_j a tension scale): psi_j = 0 exactly when a, b >= 0 and a b = 0. Unlike
//! min(a, b), its square is continuously differentiable, so the Newton step is a descent
//! direction of the merit |F|^2 + |psi|^2 and the line search works across the kink
//! between taut and slack (with min, solves with several antagonists stalled there).
//! Iterates may pass through negative tensions; at convergence a tendon on the slack side
//! (b > a) gets exactly 0 N.
//!
//! The k tension unknowns border the block-banded system without changing its structure:
//!
//! ```text
//! [ J                   F_tau          ] [dx  ]   [ -F   ]
//! [ -(q_j/L) G_j   p_j/T_j + (q_j/L) c_j ] [dtau] = [ -psi ]
//! ```
//!
//! with G_j = dl_j/dx (exact: the quadrature weights times the speed's gradient, on the
//! strains of each node) and F_tau = dF/dtau by a forward difference of the residual at
//! fixed x. One factorization of J (the structured elimination) gives a = J^-1 (-F) and the
//! k columns X = J^-1 F_tau; then dx = a - X dtau with dtau from the k x k Schur complement
//! S_jm = p_j / T_j delta_jm + (q_j / L) (G_j . X_m + c_j delta_jm) (right-hand side
//! -psi_j + (q_j / L) G_j . a). Here (p_j, q_j) = (a / r - 1, b / r - 1), r = sqrt(a^2 + b^2),
//! is the derivative of psi_j in (a, b); at a = b = 0, where psi is not differentiable, the
//! element (1/sqrt 2 - 1)(1, 1) of its generalized gradient. Taut (b = 0 < a) the row is the
//! linearized constraint; slack (a = 0 < b) it is dtau_j = -tau_j. Chord steps reuse the
//! factors and X.
//!
//! The Newton loop is the tension solve's ([`newton::run_bordered`]: chord steps, line
//! search, stopping tests); this module is its border ([`Tensions`]): the tensions, the rows
//! psi, the columns X and the Schur step.
//!
//! Meshing is the tension solve's ([`refine::to_tolerance`]): the starting mesh from the
//! initial guess, an error estimate on every converged mesh, re-meshing to the tolerance,
//! each mesh's solve warm-started from the last one's states and tensions.
#![allow(non_snake_case)]

use super::newton::{self, Border, Linearization, Point, Settings, Workspace};
use super::system::System;
use super::unknowns::{self, NODE, U, V};
use super::{
    Cache, Cached, Level, Options, cold_start, initial_mesh, interpolate, record_estimate, refine, resolves,
    segment_ends,
};
use super::{constrained, estimate};
use crate::Robot;
use crate::dense::solve_dense;
use crate::error;
use crate::mesh::guess::{self, InitialGuess};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::model::length::{self, NodeQuadrature};
use crate::model::robot::RodModel;
use crate::model::routing::RoutingPoint;
use crate::model::tension_guess::starting_tensions;
use crate::report::{Method, SolveReport, Stability, Termination};
use crate::solution::{Solution, State};
use nalgebra::Vector3;
use std::time::Instant;

/// Relative step of the forward difference dF/dtau_j: the residual resolves a parameter's
/// effect to about 1e-11 relative (collocation::sensitivity), so the error of a forward
/// difference, about h + 1e-11 / h, is smallest near h = sqrt(1e-11) = 3e-6. Newton then
/// contracts by at least that factor per step near the solution.
pub(super) const TENSION_STEP: f64 = 3e-6;

/// One displacement-controlled tendon's length constraint on one mesh.
pub(super) struct Constraint {
    /// Index of the tendon in the robot.
    pub(super) tendon: usize,
    /// Pull-in q_j (m).
    displacement: f64,
    /// l_ref_j (m).
    reference_length: f64,
    /// c_j (m/N).
    pub(super) compliance: f64,
    /// T_j (N), [`Robot::tension_scale`]: the scale of a in psi_j.
    pub(super) tension_scale: f64,
    /// The path-length quadrature on the mesh's nodes.
    quadrature: NodeQuadrature,
    /// The routing at each quadrature node, in the quadrature's order.
    routing: Vec<RoutingPoint>,
    /// On a Kirchhoff rod the strain v* at each quadrature node (the node coordinate v
    /// carries the internal force there, and the path length does not depend on it).
    fixed_strain: Option<Vec<Vector3<f64>>>,
}

impl Constraint {
    /// The constraint of the robot's tendon `tendon` (displacement-controlled) on `mesh`.
    pub(super) fn new(robot: &Robot, tendon: usize, mesh: &Mesh) -> Self {
        let t = &robot.tendons[tendon];
        let length = robot.length();
        let s: Vec<f64> = mesh.nodes.iter().map(|n| n.s).collect();
        let quadrature = NodeQuadrature::new(&s, t.end(length));
        let routing = quadrature
            .weights
            .iter()
            .map(|&(k, _)| t.routing.at(s[k], length))
            .collect();
        let fixed_strain = (robot.rod_model == RodModel::Kirchhoff).then(|| {
            let nodes = &mesh.nodes;
            quadrature
                .weights
                .iter()
                .map(|&(k, _)| robot.rod.reference_on(nodes[k].s, nodes[k].segment_end).v_star)
                .collect()
        });
        let reference_length = length::reference_length(robot, tendon);
        Constraint {
            tendon,
            displacement: t.displacement().unwrap_or(0.0),
            reference_length,
            compliance: t.compliance(reference_length),
            tension_scale: robot.tension_scale(tendon),
            quadrature,
            routing,
            fixed_strain,
        }
    }

    /// The strain v at quadrature node `j` (node k) of the states `x`.
    fn strain(&self, x: &[State], j: usize, k: usize) -> Vector3<f64> {
        self.fixed_strain.as_ref().map_or(x[k].v, |v| v[j])
    }

    /// l_j(x) (m).
    fn length(&self, x: &[State]) -> f64 {
        self.quadrature
            .weights
            .iter()
            .zip(&self.routing)
            .enumerate()
            .map(|(j, (&(k, w), rp))| w * length::speed(rp, &self.strain(x, j, k), &x[k].u))
            .sum()
    }

    /// phi_j (m).
    fn gap(&self, x: &[State], tension: f64) -> f64 {
        self.reference_length - self.length(x) - self.displacement + self.compliance * tension
    }

    /// Whether (phi, tau) is on the taut side of the complementarity (b <= a).
    fn taut(&self, gap: f64, tension: f64, length: f64) -> bool {
        gap / length <= tension / self.tension_scale
    }

    /// psi_j = sqrt(a^2 + b^2) - a - b, a = tau_j / T_j, b = phi_j / L: zero at a solution
    /// (dimensionless, Fischer-Burmeister).
    fn complementarity(&self, gap: f64, tension: f64, length: f64) -> f64 {
        let (a, b) = (tension / self.tension_scale, gap / length);
        a.hypot(b) - a - b
    }

    /// (dpsi/da, dpsi/db) at (phi, tau): (a / r - 1, b / r - 1), and at a = b = 0 the
    /// generalized gradient's element (1/sqrt 2 - 1)(1, 1).
    fn complementarity_gradient(&self, gap: f64, tension: f64, length: f64) -> (f64, f64) {
        let (a, b) = (tension / self.tension_scale, gap / length);
        let r = a.hypot(b);
        if r == 0.0 {
            let g = std::f64::consts::FRAC_1_SQRT_2 - 1.0;
            (g, g)
        } else {
            (a / r - 1.0, b / r - 1.0)
        }
    }

    /// G_j . z: the change of l_j along the scaled step z (12 per node, du = z_U / L).
    pub(super) fn length_change(&self, x: &[State], z: &[f64], length: f64) -> f64 {
        self.quadrature
            .weights
            .iter()
            .zip(&self.routing)
            .enumerate()
            .map(|(j, (&(k, w), rp))| {
                let (dv, du) = length::speed_gradient(rp, &self.strain(x, j, k), &x[k].u);
                let part = |i: usize| Vector3::new(z[k * NODE + i], z[k * NODE + i + 1], z[k * NODE + i + 2]);
                // On a Kirchhoff rod the length does not change with the coordinate v.
                let dv = if self.fixed_strain.is_some() {
                    0.0
                } else {
                    dv.dot(&part(V))
                };
                w * (dv + du.dot(&part(U)) / length)
            })
            .sum()
    }
}

/// Sets the tensions of the constrained tendons in `model` to `tau`.
fn load(model: &mut Model, constraints: &[Constraint], tau: &[f64]) {
    for (c, &t) in constraints.iter().zip(tau) {
        model.tensions[c.tendon] = t;
    }
}

/// The border of the displacement-controlled tendons on one mesh, built once per mesh: their
/// tensions tau and complementarity rows psi (at the current and the trial point), the
/// columns X = J^-1 dF/dtau of the last Jacobian, and the collocation system, whose model
/// holds the tensions of the last evaluation.
struct Tensions<'r> {
    /// The collocation system; its model's tensions are set before every evaluation.
    system: System<'r>,
    constraints: Vec<Constraint>,
    /// Backbone length L (m).
    length: f64,
    /// F at (x, tau + h e_j), then its difference quotient.
    probe: Vec<f64>,
    /// X_j = J^-1 dF/dtau_j, one per constraint.
    columns: Vec<Vec<f64>>,
    /// Tensions tau_j (N) of the current and the trial point.
    tau: Vec<f64>,
    trial_tau: Vec<f64>,
    /// psi_j of the current and the trial point.
    psi: Vec<f64>,
    trial_psi: Vec<f64>,
    /// The step dtau (N), and the dtau of the last simplified correction.
    dtau: Vec<f64>,
    simplified: Vec<f64>,
    /// The k x k Schur system, row major, and its right-hand side.
    schur: Vec<f64>,
    schur_rhs: Vec<f64>,
}

impl<'r> Tensions<'r> {
    /// The border of the robot's displacement-controlled tendons on `system`'s mesh,
    /// starting from their tensions in its model.
    fn new(system: System<'r>) -> Self {
        let robot = system.model.robot;
        let constraints: Vec<Constraint> = robot
            .tendons
            .iter()
            .enumerate()
            .filter(|(_, t)| t.displacement().is_some())
            .map(|(i, _)| Constraint::new(robot, i, &system.mesh))
            .collect();
        let n = unknowns::unknowns(system.mesh.nodes.len());
        let k = constraints.len();
        let tau: Vec<f64> = constraints.iter().map(|c| system.model.tensions[c.tendon]).collect();
        Tensions {
            length: robot.length(),
            system,
            constraints,
            probe: vec![0.0; n],
            columns: vec![vec![0.0; n]; k],
            trial_tau: tau.clone(),
            tau,
            psi: vec![0.0; k],
            trial_psi: vec![0.0; k],
            dtau: vec![0.0; k],
            simplified: vec![0.0; k],
            schur: vec![0.0; k * k],
            schur_rhs: vec![0.0; k],
        }
    }

    /// Sets the model's tensions to the current ones and returns the system. After
    /// convergence to the scaled residual `tolerance` (`converged`, at the states `x`), a
    /// tendon on the slack side, or on the taut side within `tolerance` of 0 N in tau / T
    /// (just taut), gets exactly 0 N: its tension is within the solve's tolerance of 0.
    fn finish(mut self, converged: Option<f64>, x: &[State]) -> System<'r> {
        if let Some(tolerance) = converged {
            for (c, t) in self.constraints.iter().zip(self.tau.iter_mut()) {
                let taut = c.taut(c.gap(x, *t), *t, self.length) && *t > tolerance * c.tension_scale;
                if !taut {
                    *t = 0.0;
                }
            }
        }
        load(&mut self.system.model, &self.constraints, &self.tau);
        self.system
    }
}

impl Border for Tensions<'_> {
    fn on<R>(&mut self, point: Point, f: impl FnOnce(&System) -> R) -> R {
        let tau = match point {
            Point::Current => &self.tau,
            Point::Trial => &self.trial_tau,
        };
        load(&mut self.system.model, &self.constraints, tau);
        f(&self.system)
    }

    /// psi_j (Fischer-Burmeister, [`Constraint::complementarity`]).
    fn rows(&mut self, point: Point, x: &[State]) {
        let (tau, psi) = match point {
            Point::Current => (&self.tau, &mut self.psi),
            Point::Trial => (&self.trial_tau, &mut self.trial_psi),
        };
        for ((c, &t), o) in self.constraints.iter().zip(tau).zip(psi.iter_mut()) {
            *o = c.complementarity(c.gap(x, t), t, self.length);
        }
    }

    fn residual(&self, point: Point) -> &[f64] {
        match point {
            Point::Current => &self.psi,
            Point::Trial => &self.trial_psi,
        }
    }

    /// X_j = J^-1 dF/dtau_j by a forward difference in tau_j at fixed x (F is linear in
    /// the tensions up to the curvature of the tendon paths' dependence on x, which x fixes).
    fn factored(&mut self, x: &[State], at: &mut Linearization, report: &mut SolveReport) -> Result<(), Termination> {
        load(&mut self.system.model, &self.constraints, &self.tau);
        for (j, c) in self.constraints.iter().enumerate() {
            let tau = self.tau[j];
            let h = TENSION_STEP * tau.max(c.tension_scale);
            self.system.model.tensions[c.tendon] = tau + h;
            let ok = newton::residual(&self.system, x, &mut self.probe, report);
            self.system.model.tensions[c.tendon] = tau;
            if !ok {
                return Err(Termination::NonFinite);
            }
            for (p, f) in self.probe.iter_mut().zip(at.residual()) {
                *p = (*p - f) / h;
            }
            if !at.solve(&self.probe, &mut self.columns[j], report) {
                return Err(Termination::SingularJacobian);
            }
        }
        Ok(())
    }

    /// The Schur step (module docs): dtau from the k x k system of the linearized psi rows,
    /// then dx = a - X dtau. The norm is max_j |dtau_j| / T_j.
    fn step(
        &mut self,
        point: Point,
        x: &[State],
        a: &mut [f64],
        _: &mut Linearization,
        _: &mut SolveReport,
    ) -> Option<f64> {
        let k = self.constraints.len();
        let (tau, dtau) = match point {
            Point::Current => (&self.tau, &mut self.dtau),
            Point::Trial => (&self.trial_tau, &mut self.simplified),
        };
        for (j, c) in self.constraints.iter().enumerate() {
            let t = tau[j];
            let gap = c.gap(x, t);
            let (p, q) = c.complementarity_gradient(gap, t, self.length);
            let (p, q) = (p / c.tension_scale, q / self.length);
            let row = &mut self.schur[j * k..(j + 1) * k];
            // dpsi = p dtau + q dphi, dphi = -G (a - X dtau) + c dtau.
            for (m, entry) in row.iter_mut().enumerate() {
                let own = if m == j { p + q * c.compliance } else { 0.0 };
                *entry = q * c.length_change(x, &self.columns[m], self.length) + own;
            }
            self.schur_rhs[j] = q * c.length_change(x, a, self.length) - c.complementarity(gap, t, self.length);
        }
        if !solve_dense(&mut self.schur, &mut self.schur_rhs, k) {
            return None;
        }
        dtau.copy_from_slice(&self.schur_rhs);
        for (column, &d) in self.columns.iter().zip(dtau.iter()) {
            if d != 0.0 {
                for (s, c) in a.iter_mut().zip(column) {
                    *s -= c * d;
                }
            }
        }
        let finite = a.iter().chain(dtau.iter()).all(|v| v.is_finite());
        let norm = dtau
            .iter()
            .zip(&self.constraints)
            .fold(0.0, |m: f64, (d, c)| m.max(d.abs() / c.tension_scale));
        finite.then_some(norm)
    }

    /// tau + alpha dtau (psi keeps the solution's tensions >= 0; an iterate may pass
    /// through negative ones).
    fn trial(&mut self, alpha: f64) {
        for ((t, &tau), &d) in self.trial_tau.iter_mut().zip(&self.tau).zip(&self.dtau) {
            *t = tau + alpha * d;
        }
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.psi, &mut self.trial_psi);
        self.tau.copy_from_slice(&self.trial_tau);
    }
}

/// Solves a robot with displacement-controlled tendons (validated, with `options`
/// validated): Newton bordered by the tensions ([`Tensions`]) on each mesh of the sequence of
/// [`refine::to_tolerance`], from the warm start's tensions, else the given ones, else the
/// tensions of the small-deflection estimate ([`starting_tensions`]).
///
/// # Errors
/// As [`super::solve`].
pub(super) fn solve(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
) -> error::Result<Solution> {
    let start = Instant::now();
    let mut work = robot.clone();
    let estimated = starting_tensions(&mut work, warm);
    let mut report = SolveReport::new(Method::Collocation);
    let mut mesh = initial_mesh(&work, options, warm)?;
    if options.tolerance.is_none() {
        resolves(&work, options, &mesh)?;
    }
    let x = match warm {
        Some(w) => interpolate(&Model::new(&work), w, &mesh),
        None => {
            // As a tension solve; then estimated tensions are corrected on the guess.
            let mut x0 = cold_start(&Model::new(&work), options, &mut mesh)?;
            if estimated && options.initial_guess == InitialGuess::RigidEquilibrium {
                correct_on_guess(&mut work, &mesh, &mut x0);
            }
            x0
        }
    };
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut model = Model::new(&work);
    let level = refine::to_tolerance(
        &mut model,
        mesh,
        x,
        options,
        &mut report,
        cache,
        |model, mesh, x, report, cache| solve_on_mesh(model, mesh, x, &settings, options, start, report, cache),
    )?;
    record_estimate(&mut report, level.correction.as_ref(), options, work.length());
    let t = Instant::now();
    let system = System::new(model.clone(), level.mesh.clone());
    report.stability = match cache.as_mut() {
        Some(c) => constrained::stability(&system, &level.x, &mut c.workspace, &mut report),
        None => Stability::Unknown {
            reason: "no workspace was kept for the verdict".into(),
        },
    };
    report.timings.stability += t.elapsed();
    report.timings.total = start.elapsed();
    let rates = level.correction.as_ref().map(|c| c.node_rates.as_slice());
    nodes::solution(&model, &level.x, &segment_ends(&level.mesh), rates, report)
}

/// Newton bordered by the tensions on `mesh` from `x` and the tensions in `model` (then the
/// solved ones), and the error estimate; `cache` keeps the workspace's buffers (not its
/// factors: it holds no tension columns). A non-convergence's report has the total time.
#[allow(clippy::too_many_arguments)]
fn solve_on_mesh(
    model: &mut Model,
    mesh: Mesh,
    mut x: Vec<State>,
    settings: &Settings,
    options: &Options,
    start: Instant,
    report: &mut SolveReport,
    cache: &mut Cache,
) -> error::Result<Level> {
    // The tensions move into this mesh's system and back (on an error the sequence ends).
    let tensions = std::mem::take(&mut model.tensions);
    let system = System::new(Model { tensions, ..*model }, mesh);
    let mut ws = match cache.take() {
        Some(c) if c.mesh == system.mesh && c.solver == options.linear_solver => c.workspace,
        _ => Workspace::new(&system, options.linear_solver)?,
    };
    let mut tensions = Tensions::new(system);
    let (termination, worst) = newton::run_bordered(&mut tensions, &mut ws, &mut x, settings, report);
    let k = tensions.constraints.len();
    let converged = (termination == Termination::Converged).then_some(settings.tolerance);
    let system = tensions.finish(converged, &x);
    report.termination = termination;
    report.intervals = system.mesh.intervals();
    report.unknowns = unknowns::unknowns(system.mesh.nodes.len()) + k;
    report.nonzeros = unknowns::nonzeros(&system.mesh);
    let correction = if termination == Termination::Converged {
        let t = Instant::now();
        // A breakdown at a stage of the order-6 scheme leaves the solution without an estimate.
        let correction = estimate::estimate(&system, &mut ws, &x).ok().flatten();
        report.timings.estimate += t.elapsed();
        Ok(correction)
    } else {
        report.timings.total = start.elapsed();
        Err(crate::Error::NotConverged {
            method: Method::Collocation,
            report: Box::new(report.clone()),
            worst_s: system.row_position(worst.min(system.unknowns() - 1)),
            hint: "warm-start from the solution of a smaller pull-in (a sweep), refine the mesh, or check that \
                   the pull-ins are reachable"
                .into(),
        })
    };
    model.tensions = system.model.tensions;
    *cache = Some(Cached {
        mesh: system.mesh.clone(),
        solver: options.linear_solver,
        workspace: ws,
        last: None,
    });
    correction.map(|correction| Level {
        mesh: system.mesh,
        x,
        correction,
    })
}

/// Corrects the small-deflection tensions of `robot`'s taut displacement-controlled tendons
/// once on the rigid-equilibrium initial guess `x` on `mesh`, and evaluates the guess again at
/// the corrected tensions. The guess carries what the small-deflection compliance leaves
/// out (the self weight and other external loads, the large deflection), so its gaps phi_j
/// (docs/actuation.md, "The start") measure the estimate's error: the correction solves
/// (K + C) dtau = -phi on the taut tendons (K of the unloaded robot, as a chord step would)
/// and keeps the tensions >= 0. One correction costs one guess and the path lengths on it,
/// about a residual evaluation; it takes case S from 12.6 % to 1.2 % off (H: 1.2 % to 0.1 %),
/// and a second would not pay for itself (measured, docs/actuation.md "Cost").
fn correct_on_guess(robot: &mut Robot, mesh: &Mesh, x: &mut Vec<State>) {
    let taut: Vec<usize> = (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].displacement().is_some() && robot.tendons[i].tension() > 0.0)
        .collect();
    if taut.is_empty() {
        return;
    }
    let (n, k) = (robot.tendons.len(), taut.len());
    let compliance = length::pull_in_compliance(robot);
    let constraints: Vec<Constraint> = taut.iter().map(|&i| Constraint::new(robot, i, mesh)).collect();
    let mut a: Vec<f64> = (0..k * k)
        .map(|e| {
            let (r, c) = (e / k, e % k);
            compliance[taut[r] * n + taut[c]] + if r == c { constraints[r].compliance } else { 0.0 }
        })
        .collect();
    let mut dtau: Vec<f64> = constraints
        .iter()
        .map(|c| -c.gap(x, robot.tendons[c.tendon].tension()))
        .collect();
    if !solve_dense(&mut a, &mut dtau, k) {
        return;
    }
    for (c, d) in constraints.iter().zip(&dtau) {
        let t = &mut robot.tendons[c.tendon];
        t.hold_tension((t.tension() + d).max(0.0));
    }
    *x = guess::initial(&Model::new(robot), &mesh.nodes, InitialGuess::RigidEquilibrium);
}
