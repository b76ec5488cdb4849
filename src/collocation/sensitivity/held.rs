//! Derivatives with displacement-controlled tendons' pull-ins held ([`Held`], the pull-in
//! columns of [`displacement_sensitivities`]): the tensions follow a parameter so that the
//! pull-ins the shape and tension profile take up stay what the actuators hold
//! (docs/actuation.md, "Sensitivities"; with friction docs/friction.md, section 3b).

use super::{NodeDerivative, Sensitivity};
use crate::collocation::friction::Capstan;
use crate::collocation::unknowns::node_increments;
use crate::error::Result;
use crate::model::length::{self, NodeQuadrature, speed_gradient};
use crate::model::robot::{Robot, RodModel};
use crate::model::routing::RoutingPoint;
use crate::solution::Solution;
use crate::solution::State;
use nalgebra::{DMatrix, DVector, Vector3, Vector6};

/// The node derivatives of the scaled unknowns `dx` at the node states `states` (rod length
/// `length`; on a Kirchhoff rod, `fixed_strain`, v does not move).
fn node_derivatives(dx: &[f64], states: &[State], fixed_strain: bool, length: f64) -> Vec<NodeDerivative> {
    states
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let [p, theta, v, u] = node_increments(dx, k, length);
            NodeDerivative {
                s: x.s,
                p,
                rotation: x.R * theta,
                v: if fixed_strain { Vector3::zeros() } else { v },
                u,
            }
        })
        .collect()
}

/// Derivatives with the pull-ins of the taut displacement-controlled tendons held: a
/// parameter's derivative (D_p of the node states, dz of the log tensions with friction)
/// changes the pull-ins their shape and tensions take up by dQ = -(G D_p - E dz) at fixed
/// base tensions, and the tensions follow to keep the pull-ins, S dtau = G D_p - E dz with
/// S = dQ/dtau ([`TensionDirections`]); the tip moves by its own derivative plus
/// d(tip)/dtau dtau. Without such tendons it passes the derivatives through.
pub(super) struct Held {
    /// The taut displacement-controlled tendons' directions and the LU factors of their
    /// S = C - dl/dtau; `None` without any.
    directions: Option<(TensionDirections, nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>)>,
}

impl Held {
    /// The held tendons of `robot` at `solution` (`sens` linearized there): taut ones (a
    /// slack tendon stays slack for small changes, also one just taut at 0 N).
    pub(super) fn new(sens: &mut Sensitivity, robot: &Robot, solution: &Solution) -> Result<Self> {
        let taut: Vec<usize> = (0..robot.tendons.len())
            .filter(|&i| {
                let state = &solution.tendons[i];
                robot.tendons[i].displacement().is_some() && state.slack == 0.0 && state.tension > 0.0
            })
            .collect();
        let directions = if taut.is_empty() {
            None
        } else {
            let h = TensionDirections::from(sens, solution, taut)?;
            let schur = h.displacement_by_tension().lu();
            Some((h, schur))
        };
        Ok(Held { directions })
    }

    /// Whether any tendon's pull-in is held (taut and displacement-controlled).
    pub(super) fn holds(&self) -> bool {
        self.directions.is_some()
    }

    /// Refuses the offset of a held tendon's routing: it moves the tendon's path length
    /// at fixed states too, a term the held derivatives do not include
    /// ([`crate::Error::InvalidInput`]); any other parameter passes.
    pub(super) fn check(&self, parameter: crate::model::parameter::Parameter) -> Result<()> {
        use crate::model::parameter::Parameter;
        match (parameter, self.directions()) {
            (Parameter::RoutingOffset(i, _), Some(h)) if h.tendons.contains(&i) => Err(crate::error::invalid(
                parameter.to_string(),
                format!(
                    "has no derivative here: tendon {} is displacement-controlled and taut, and its offset moves its \
                     path length, which the pull-in holds (a term these derivatives do not include)",
                    i + 1
                ),
                format!(
                    "give tendon {} a tension (its solved one) to differentiate in its routing",
                    i + 1
                ),
            )),
            _ => Ok(()),
        }
    }

    /// The held tendons' tension directions, when there are any (the adjoint's border).
    pub(super) fn directions(&self) -> Option<&TensionDirections> {
        self.directions.as_ref().map(|(h, _)| h)
    }

    /// The tip pose's derivative for the state derivative `d`, the pull-ins held. `d` must
    /// be the last solve with `sens`'s factors, whose log tensions' derivative enters the
    /// held tendons' stretch with friction.
    pub(super) fn tip(&self, d: &[NodeDerivative], sens: &Sensitivity) -> Result<Vector6<f64>> {
        let own = d[d.len() - 1].pose();
        let Some((h, schur)) = &self.directions else {
            return Ok(own);
        };
        let dtau = schur.solve(&h.length_change(d, sens)).ok_or_else(super::singular)?;
        Ok(own + Vector6::from_iterator((&h.tip * dtau).iter().copied()))
    }

    /// d(tip pose)/dq_i for the displacement-controlled tendon `i` (per m): S dtau = e_i
    /// over the held tendons, d(tip)/dq = d(tip)/dtau (dQ/dtau)^-1 e_i; zero for a slack one.
    pub(super) fn pull(&self, i: usize) -> Result<Vector6<f64>> {
        let Some((h, schur)) = &self.directions else {
            return Ok(Vector6::zeros());
        };
        let Some(m) = h.tendons.iter().position(|&j| j == i) else {
            return Ok(Vector6::zeros());
        };
        let mut unit = DVector::zeros(h.tendons.len());
        unit[m] = 1.0;
        let dtau = schur.solve(&unit).ok_or_else(super::singular)?;
        Ok(Vector6::from_iterator((&h.tip * dtau).iter().copied()))
    }
}

/// Derivatives of a solution with respect to the pull-ins of its displacement-controlled
/// tendons (docs/actuation.md): what a resolved-rate controller needs.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementSensitivities {
    /// The displacement-controlled tendons (0-based indices), the columns' order.
    pub tendons: Vec<usize>,
    /// d(tip pose)/dq, 6 x k: tip position (m/m), then the world-frame tip rotation vector
    /// (rad/m), as in [`super::TipSensitivities`].
    pub tip: DMatrix<f64>,
    /// d(tau)/dq, k x k (N/m): row i the tension of `tendons[i]`. A slack tendon's row is
    /// 0 (it stays slack for small changes), also one just taut at 0 N.
    pub tension: DMatrix<f64>,
}

/// The derivatives of `solution`'s tip pose and tensions with respect to the pull-ins q of
/// `robot`'s displacement-controlled tendons, by the implicit function theorem on the
/// bordered system: with D_m = dx/dtau_m (one solve each with the factors of
/// [`Sensitivity`]), the taut tendons' constraints phi_j = l_ref_j - l_j - q_j + c_j tau_j = 0
/// give S dtau/dq = I with S_jm = c_j delta_jm - dl_j/dtau_m, where dl_j/dtau_m is
/// the length quadrature's derivative along D_m; slack tendons (at 0 N) keep dtau = 0.
/// With friction S = dQ/dtau also has the stretch of the varying tension along the log
/// tensions' derivative (docs/friction.md, section 3b, "Derivatives at a held pull-in").
/// Then d(tip)/dq = d(tip)/dtau dtau/dq.
///
/// # Errors
/// [`crate::Error::InvalidInput`] when the robot has no displacement-controlled tendon or
/// the Schur complement is singular (a tendon that cannot change its length); as
/// [`Sensitivity::new`] (the solution must be `robot`'s).
pub fn displacement_sensitivities(robot: &Robot, solution: &Solution) -> Result<DisplacementSensitivities> {
    let tendons: Vec<usize> = (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].displacement().is_some())
        .collect();
    if tendons.is_empty() {
        return Err(crate::error::invalid(
            "robot.tendons",
            "has no displacement-controlled tendon",
            "give a tendon a displacement (pull-in) or use tip_sensitivities for tensions",
        ));
    }
    // A tendon with friction at 0 N has no tension direction (Sensitivity::tension); it is
    // slack and stays so (dtau = 0), so it is left out of the solves and keeps zeros.
    let solved: Vec<usize> = tendons
        .iter()
        .copied()
        .filter(|&i| !(robot.tendons[i].active_friction().is_some() && solution.tendons[i].tension == 0.0))
        .collect();
    let directions = TensionDirections::new(robot, solution, solved)?;
    let taut: Vec<bool> = directions
        .tendons
        .iter()
        .map(|&i| solution.tendons[i].slack == 0.0 && solution.tendons[i].tension > 0.0)
        .collect();
    let part = directions.tension_by_displacement(&taut)?;
    let part_tip = &directions.tip * &part;
    let k = tendons.len();
    let (mut tip, mut tension) = (DMatrix::zeros(6, k), DMatrix::zeros(k, k));
    let at = |i: usize| tendons.iter().position(|&j| j == i).unwrap_or(0);
    for (a, &i) in directions.tendons.iter().enumerate() {
        tip.set_column(at(i), &part_tip.column(a));
        for (b, &j) in directions.tendons.iter().enumerate() {
            tension[(at(i), at(j))] = part[(a, b)];
        }
    }
    Ok(DisplacementSensitivities { tip, tendons, tension })
}

/// What every pull-in derivative is made of: the tip's and the pull-ins' derivatives along
/// each of k tendons' tensions (the k solves of [`displacement_sensitivities`]); combining
/// them for a set of taut tendons is a k x k solve.
///
/// The pull-in a shape and tension profile take up is Q_j = l_ref_j - l_j + c_j tau_j
/// without friction (docs/actuation.md) and, for an elastic tendon with friction,
/// Q_j = l_ref_j - l_j + (1 / E_t A_t) [integral of tau_j(s) |p_ref'| ds + tau_j(0) L_free]
/// with tau_j(s) = tau_j(0) exp(z_j(s)) (docs/friction.md, section 3b), on the node
/// quadrature. Along a derivative of the node states D and of the log tensions dz at fixed
/// base tension, dQ_j = -G_j D + E_j dz with G_j the path length's gradient and
/// E_j dz = (1 / E_t A_t) sum_k w_k tau_j(s_k) |p_ref'(s_k)| dz_j(s_k) (the stretch's);
/// the base tension itself adds c_j = (1 / E_t A_t) [sum_k w_k exp(z_j(s_k)) |p_ref'(s_k)|
/// + L_free] (the compliance of the profile's shape).
pub(crate) struct TensionDirections {
    /// The tendons (0-based), the columns' order.
    pub(crate) tendons: Vec<usize>,
    /// d(tip pose)/dtau_m, 6 x k.
    pub(crate) tip: DMatrix<f64>,
    /// -dQ_j/dtau_m at a fixed base tension of j (m/N), k x k: dl_j/dtau_m minus the change
    /// of the stretch of j's varying tension (the latter with friction only).
    length: DMatrix<f64>,
    /// c_j (m/N): each tendon's compliance, dQ_j/dtau_j at fixed shape and log tensions.
    compliance: Vec<f64>,
    /// Each tendon's path-length quadrature and routing along it: dl_j along any derivative.
    paths: Vec<(NodeQuadrature, Vec<RoutingPoint>)>,
    /// Each elastic tendon with friction's stretch weights (node, w_k tau_j(s_k)
    /// |p_ref'(s_k)| / E_t A_t in m): E_j dz = sum of weight dz_j at the node; None for a
    /// tendon without friction (constant tension) or a rigid one (no stretch).
    stretch: Vec<Option<Vec<(usize, f64)>>>,
    /// The solution's node strains (v, u), where the path speeds are linearized.
    strains: Vec<(Vector3<f64>, Vector3<f64>)>,
    /// A Kirchhoff rod's: the paths do not change with the node coordinate v (the force's).
    fixed_strain: bool,
}

impl TensionDirections {
    /// The tension directions of `tendons` (0-based) at `solution`, a solution of `robot`,
    /// whatever their inputs.
    ///
    /// # Errors
    /// As [`Sensitivity::new`] and [`Sensitivity::tension`].
    pub(crate) fn new(robot: &Robot, solution: &Solution, tendons: Vec<usize>) -> Result<Self> {
        let solved = robot.with_tensions(&solution.tensions());
        let mut sens = Sensitivity::new(&solved, solution)?;
        Self::from(&mut sens, solution, tendons)
    }

    /// As [`TensionDirections::new`], with the factors of `sens` (linearized at `solution`
    /// with its solved tensions).
    ///
    /// # Errors
    /// As [`Sensitivity::tension`].
    pub(super) fn from(sens: &mut Sensitivity, solution: &Solution, tendons: Vec<usize>) -> Result<Self> {
        let mut directions = Self::layout(solution, &sens.border, tendons);
        for m in 0..directions.tendons.len() {
            // A tendon with friction at 0 N stretches under its first pull by the profile
            // exp(z*) (first_pull.rs), not the constant one its log tensions hold at 0 N.
            if let Some((_, z)) = sens.first_pull(directions.tendons[m])? {
                directions.first_pull_compliance(m, solution, &sens.border, &z);
            }
            let d = sens.tension(directions.tendons[m])?;
            directions.tip.set_column(m, &d[d.len() - 1].pose());
            let change = directions.length_change(&d, sens);
            directions.length.set_column(m, &change);
        }
        Ok(directions)
    }

    /// The quadratures, compliances and stretch weights of `tendons` (0-based) at
    /// `solution`, whose system (on its mesh, with its log tensions) `border` holds, without
    /// the directions: `tip` and the length changes are zero until
    /// [`TensionDirections::set_direction`] fills them.
    pub(crate) fn layout(solution: &Solution, border: &Capstan, tendons: Vec<usize>) -> Self {
        let robot = border.system().model.robot;
        let k = tendons.len();
        let rod_length = robot.length();
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let paths: Vec<(NodeQuadrature, Vec<RoutingPoint>)> = tendons
            .iter()
            .map(|&i| {
                let t = &robot.tendons[i];
                let quadrature = NodeQuadrature::new(&s, t.end(rod_length));
                let routing = quadrature
                    .weights
                    .iter()
                    .map(|&(node, _)| t.routing.at(s[node], rod_length))
                    .collect();
                (quadrature, routing)
            })
            .collect();
        let strains = solution.nodes.iter().map(|n| (n.v, n.u)).collect();
        let mut compliance = Vec::with_capacity(k);
        let mut stretch = Vec::with_capacity(k);
        for (&i, (quadrature, routing)) in tendons.iter().zip(&paths) {
            let t = &robot.tendons[i];
            let reference_length = solution.tendons[i].reference_length;
            match (t.stiffness, border.log_tensions(i)) {
                (Some(stiffness), Some((z, _))) => {
                    let unit = unit_stretch(border, (&s, quadrature, routing), &z, stiffness);
                    compliance.push(unit.iter().map(|(_, c)| c).sum::<f64>() + t.free_length / stiffness);
                    let base = solution.tendons[i].tension;
                    stretch.push(Some(unit.into_iter().map(|(node, c)| (node, c * base)).collect()));
                }
                _ => {
                    compliance.push(t.compliance(reference_length));
                    stretch.push(None);
                }
            }
        }
        TensionDirections {
            tip: DMatrix::zeros(6, k),
            length: DMatrix::zeros(k, k),
            tendons,
            compliance,
            paths,
            stretch,
            strains,
            fixed_strain: robot.rod_model == RodModel::Kirchhoff,
        }
    }

    /// Tendon m's compliance with its log tensions `z` (at every node) in place of the
    /// border's: a tendon with friction at 0 N, whose pull-in under its first pull stretches
    /// the profile exp(z*). Unchanged for a rigid tendon (no stretch).
    fn first_pull_compliance(&mut self, m: usize, solution: &Solution, border: &Capstan, z: &[f64]) {
        let robot = border.system().model.robot;
        let t = &robot.tendons[self.tendons[m]];
        let Some(stiffness) = t.stiffness else {
            return;
        };
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let (quadrature, routing) = &self.paths[m];
        let unit = unit_stretch(border, (&s, quadrature, routing), z, stiffness);
        self.compliance[m] = unit.iter().map(|(_, c)| c).sum::<f64>() + t.free_length / stiffness;
    }

    /// Sets tendon m's direction from the bordered solve of `border` that gave the scaled
    /// node derivative `dx` (its log tensions' derivative still in the border) at the
    /// states `states`: its length changes and, from the last node, its tip column.
    pub(crate) fn set_direction(&mut self, m: usize, dx: &[f64], states: &[State], border: &Capstan) {
        let d = node_derivatives(dx, states, self.fixed_strain, border.system().model.robot.length());
        let change = self.length_change_in(&d, border);
        self.length.set_column(m, &change);
        self.tip.set_column(m, &d[d.len() - 1].pose());
    }

    /// -dQ_j of every tendon at fixed base tensions along the bordered solve of `border`
    /// that gave the scaled node derivative `dx` at `states` ([`Self::length_change`]).
    pub(crate) fn change_along(&self, dx: &[f64], states: &[State], border: &Capstan) -> DVector<f64> {
        let d = node_derivatives(dx, states, self.fixed_strain, border.system().model.robot.length());
        self.length_change_in(&d, border)
    }

    /// -dQ_j (m per unit of the parameter) of every tendon at fixed base tensions along the
    /// derivative `d` of the node states and the log tensions' derivative of the same solve
    /// of `sens` ([`Sensitivity::log_tensions`]): the quadrature of the path speed's gradient
    /// (docs/actuation.md), less the change of the stretch with friction (type docs).
    fn length_change(&self, d: &[NodeDerivative], sens: &Sensitivity) -> DVector<f64> {
        self.length_change_in(d, &sens.border)
    }

    /// [`Self::length_change`] with the log tensions' derivative of the last bordered solve
    /// of `border`.
    fn length_change_in(&self, d: &[NodeDerivative], border: &Capstan) -> DVector<f64> {
        DVector::from_iterator(
            self.tendons.len(),
            self.paths
                .iter()
                .zip(&self.stretch)
                .zip(&self.tendons)
                .map(|(((quadrature, routing), stretch), &i)| {
                    let dl = quadrature
                        .weights
                        .iter()
                        .zip(routing)
                        .map(|(&(node, w), rp)| {
                            let (v, u) = &self.strains[node];
                            let (dv, du) = speed_gradient(rp, v, u);
                            w * (dv.dot(&d[node].v) + du.dot(&d[node].u))
                        })
                        .sum::<f64>();
                    let stretched = match (stretch, border.log_tensions(i)) {
                        (Some(weights), Some((_, dz))) => weights.iter().map(|&(node, c)| c * dz[node]).sum(),
                        _ => 0.0,
                    };
                    dl - stretched
                }),
        )
    }

    /// Adds G^T w to the scaled cotangent `g` (12 per node, d = (dp / L, dtheta, dv, du L)):
    /// the transpose of [`TensionDirections::length_change`]'s path-length part (the
    /// adjoint has no friction, so no stretch part), w_j weighting tendon j's path length
    /// (rod length `length`, m). Node k's dv slot gets sum_j w_j weight dspeed/dv,
    /// its du slot sum_j w_j weight dspeed/du / L (du = d_u / L).
    pub(super) fn add_length_cotangent(&self, w: &DVector<f64>, length: f64, g: &mut [f64]) {
        use crate::collocation::unknowns::{NODE, U, V};
        for ((quadrature, routing), &w_j) in self.paths.iter().zip(w.iter()) {
            for (&(node, weight), rp) in quadrature.weights.iter().zip(routing) {
                let (v, u) = &self.strains[node];
                let (dv, du) = speed_gradient(rp, v, u);
                for i in 0..3 {
                    if !self.fixed_strain {
                        g[node * NODE + V + i] += w_j * weight * dv[i];
                    }
                    g[node * NODE + U + i] += w_j * weight * du[i] / length;
                }
            }
        }
    }

    /// dq/dtau (m/N, k x k): how the pull-ins that hold the tendons just taut change with
    /// the tensions, C - dl/dtau (q_j = l_ref_j - l_j + c_j tau_j), with friction also the
    /// change of the varying tension's stretch (type docs).
    pub(crate) fn displacement_by_tension(&self) -> DMatrix<f64> {
        let mut q = -&self.length;
        for (j, c) in self.compliance.iter().enumerate() {
            q[(j, j)] += c;
        }
        q
    }

    /// dtau/dq (N/m, k x k) with the tendons flagged in `taut` taut (their constraints
    /// hold: S dtau = dq, S = C - dl/dtau) and the others slack (dtau = 0).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] when the Schur complement is singular.
    pub(crate) fn tension_by_displacement(&self, taut: &[bool]) -> Result<DMatrix<f64>> {
        let k = self.tendons.len();
        let mut schur = self.displacement_by_tension();
        let mut rhs = DMatrix::<f64>::identity(k, k);
        for j in 0..k {
            if !taut[j] {
                schur.row_mut(j).fill(0.0);
                schur[(j, j)] = 1.0;
                rhs[(j, j)] = 0.0;
            }
        }
        schur.lu().solve(&rhs).ok_or_else(super::singular)
    }
}

/// Per unit base tension, the stretch of the tension profile exp(z) (z at the nodes) on the
/// node quadrature of a tendon's reference path (as TendonState::displacement): each
/// quadrature node and its weight times exp(z) times the reference path speed over the
/// tendon's axial stiffness `stiffness` (N). `path` holds the node arc lengths, the
/// quadrature and the routing at its nodes, `border` the rod and the mesh.
fn unit_stretch(
    border: &Capstan,
    (s, quadrature, routing): (&[f64], &NodeQuadrature, &[RoutingPoint]),
    z: &[f64],
    stiffness: f64,
) -> Vec<(usize, f64)> {
    let robot = border.system().model.robot;
    let mesh = &border.system().mesh;
    quadrature
        .weights
        .iter()
        .zip(routing)
        .map(|(&(node, w), rp)| {
            let reference = robot.rod.reference_on(s[node], mesh.nodes[node].segment_end);
            let speed = length::speed(rp, &reference.v_star, &reference.u_star);
            (node, w * z[node].exp() * speed / stiffness)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::{self, Options};
    use crate::{Friction, cases};

    /// dQ/dtau of an elastic tendon with friction at 0 N (case S's tendon 2, E_t A_t = 2000 N,
    /// mu = 0.2, beside tendon 1 pulled at 2.94 N with mu = 0.1): its column against the
    /// pull-ins of full solves at small tensions on the same mesh, (Q(h) - Q(0)) / h at
    /// h = 1e-3 and 1e-4 N, Richardson-extrapolated. Its own entry includes the stretch of
    /// its first pull's profile exp(z*) (before: exp(0), the constant tension's).
    #[test]
    fn pull_in_slopes_of_an_unloaded_tendon_with_friction_match_solves() {
        let mut robot = cases::case_s();
        robot.tendons[0].friction = Some(Friction::pull(0.1));
        robot.tendons[1].friction = Some(Friction::pull(0.2));
        for t in &mut robot.tendons[..2] {
            t.stiffness = Some(2000.0);
        }
        let options = Options {
            intervals: 64,
            tolerance: None,
            residual_tolerance: 1e-12,
            ..Default::default()
        };
        let reference = collocation::solve(&robot, &options).unwrap();
        let directions = TensionDirections::new(&robot, &reference, vec![0, 1]).unwrap();
        let slopes = directions.displacement_by_tension();
        let pull_ins = |h: f64| {
            let mut pulled = robot.clone();
            pulled.tendons[1].set_tension(h);
            let solved = collocation::solve_from(&pulled, &options, &reference).unwrap();
            assert_eq!(solved.nodes.len(), reference.nodes.len());
            [0, 1].map(|j| (solved.tendons[j].displacement - reference.tendons[j].displacement) / h)
        };
        let (coarse, fine) = (pull_ins(1e-3), pull_ins(1e-4));
        // The constant profile's own compliance, for the size of what the first pull changes.
        let unit = |z: &[f64]| -> f64 {
            let border = Capstan::at_solution(
                crate::model::equations::Model::new(&robot),
                crate::mesh::Mesh::from_points(&robot, &reference.nodes.iter().map(|n| n.s).collect::<Vec<_>>())
                    .unwrap(),
                &reference,
            );
            let s: Vec<f64> = reference.nodes.iter().map(|n| n.s).collect();
            let (quadrature, routing) = &directions.paths[1];
            unit_stretch(&border, (&s, quadrature, routing), z, 2000.0)
                .iter()
                .map(|(_, c)| c)
                .sum()
        };
        let constant = unit(&vec![0.0; reference.nodes.len()]);
        for j in 0..2 {
            let extrapolated = (fine[j] * 10.0 - coarse[j]) / 9.0;
            let error = (slopes[(j, 1)] - extrapolated).abs();
            eprintln!(
                "dQ_{}/dtau_2: {:.9e} m/N, solves {extrapolated:.9e} (off by {error:.1e}); the constant profile's \
                 compliance {constant:.4e}, the first pull's {:.4e}",
                j + 1,
                slopes[(j, 1)],
                directions.compliance[1] - robot.tendons[1].free_length / 2000.0
            );
            // 1e-9 m/N: the pull-ins' rounding (about 1e-14 m) over 1e-4 N carried through
            // the extrapolation, and the extrapolation's truncation (the quotients' curvature
            // times 1e-7 N^2); measured 1.1e-12 and 3.1e-10. Far below what the first pull's
            // profile changes in the tendon's own entry (1.7e-5 m/N here).
            assert!(
                error <= 1e-9,
                "dQ_{}/dtau_2 {} against {extrapolated}",
                j + 1,
                slopes[(j, 1)]
            );
        }
        // The profile matters: the constant one's compliance is 1.7e-5 m/N more.
        assert!((directions.compliance[1] - robot.tendons[1].free_length / 2000.0 - constant).abs() > 1e-6);
    }
}
