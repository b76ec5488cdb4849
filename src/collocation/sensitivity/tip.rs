//! Tip sensitivities in one call ([`tip_sensitivities`]: tensions, tip wrench, moduli,
//! base pose) and the whole-backbone position derivative with respect to one tension, both
//! from one [`Sensitivity`] (one factorization).

use super::{Difference, NodeDerivative, RELATIVE_STEP, Sensitivity};
use crate::error::Result;
use crate::model::length::{NodeQuadrature, speed_gradient};
use crate::model::robot::{Robot, RodModel};
use crate::model::rod::{Geometry, Rod, Section, Stiffness, shear_modulus};
use crate::model::routing::RoutingPoint;
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector, Matrix6, Matrix6x3, Vector3, Vector6};

/// Tip pose derivatives with respect to the moduli of a rod built from geometry. Each is a
/// 6-vector: tip position (m/Pa), then tip rotation vector, world frame (rad/Pa).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModulusSensitivities {
    /// d(tip pose)/dE at fixed Poisson's ratio (G follows E).
    pub youngs_modulus: Vector6<f64>,
    /// d(tip pose)/dE at fixed G (bending and extension only).
    pub youngs_modulus_fixed_shear: Vector6<f64>,
    /// d(tip pose)/dG at fixed E (shear and torsion only).
    pub shear_modulus: Vector6<f64>,
}

/// Derivatives of the tip pose at a solution. Every matrix has 6 rows: tip position x, y, z
/// (m per unit of the parameter), then the tip rotation as a world-frame rotation vector
/// omega, R_tip -> exp(hat(omega)) R_tip (rad per unit).
#[derive(Clone, Debug, PartialEq)]
pub struct TipSensitivities {
    /// d(tip pose)/d(tension_i), 6 x k (per N), one column per tendon. For a slack tendon
    /// the one-sided (pulling) derivative; zero for a displacement-controlled tendon (see
    /// `displacement`); NaN for a tendon with friction at 0 N, where it is not modelled
    /// ([`super::Sensitivity::tension`]).
    pub tension: DMatrix<f64>,
    /// d(tip pose)/d(q_i), 6 x k (per m of actuator pull-in), one column per tendon: zero
    /// for a tension-controlled tendon and for a slack one. With displacement-controlled
    /// tendons every derivative here holds their pull-ins (their tensions follow, as the
    /// actuators hold position).
    pub displacement: DMatrix<f64>,
    /// d(tip pose)/d(mu_i), 6 x k (per unit of the friction coefficient), one column per
    /// tendon: zero for a tendon without friction (mu = 0 or not set), where the derivative
    /// is not taken (docs/friction.md).
    pub friction: DMatrix<f64>,
    /// d(tip pose)/d(tip force), 6 x 3 (per N, world frame): the force half of the compliance.
    pub tip_force: Matrix6x3<f64>,
    /// d(tip pose)/d(tip moment), 6 x 3 (per N m, world frame): the moment half of the compliance.
    pub tip_moment: Matrix6x3<f64>,
    /// Derivatives with respect to E and G when the rod was built from geometry with a
    /// uniform section ([`crate::Rod::tube`], [`crate::Rod::solid_circle`]); `None` otherwise.
    pub moduli: Option<ModulusSensitivities>,
    /// d(tip pose)/d(base position), 6 x 3 (per m, world frame).
    pub base_position: Matrix6x3<f64>,
    /// d(tip pose)/d(base rotation), 6 x 3 (per rad): columns are the components of the
    /// world-frame rotation vector phi with R0 -> exp(hat(phi)) R0.
    pub base_rotation: Matrix6x3<f64>,
}

impl TipSensitivities {
    /// The 6 x 6 tip compliance: d(tip pose)/d(tip force, tip moment), columns force x, y, z
    /// (per N) then moment x, y, z (per N m).
    pub fn compliance(&self) -> Matrix6<f64> {
        let mut c = Matrix6::zeros();
        c.fixed_columns_mut::<3>(0).copy_from(&self.tip_force);
        c.fixed_columns_mut::<3>(3).copy_from(&self.tip_moment);
        c
    }
}

/// The derivatives of `solution`'s tip pose with respect to the tensions, the tip wrench,
/// the moduli (rods built from geometry) and the base pose, by the implicit function
/// theorem on the collocation system (module docs).
///
/// Costs one Jacobian assembly, then one linear solve for each of the 12 exact parameters
/// (tip wrench, base pose) and each of the k + 2 differenced ones (tensions, E, G; k
/// without geometry) and the friction coefficients, which also take two or three residual
/// evaluations each. With friction each solve is the bordered one of
/// `collocation/friction` (the log tensions are unknowns too).
///
/// # Errors
/// As [`Sensitivity::new`] and [`Sensitivity::derivative`].
///
/// # Examples
/// ```
/// let robot = tdcr::cases::case_h();
/// let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
/// let sens = tdcr::collocation::sensitivity::tip_sensitivities(&robot, &solution).unwrap();
/// assert_eq!(sens.tension.shape(), (6, 5));
/// // A tip force along world +z moves the tip up.
/// assert!(sens.tip_force[(2, 2)] > 0.0);
/// ```
pub fn tip_sensitivities(robot: &Robot, solution: &Solution) -> Result<TipSensitivities> {
    // A displacement-controlled tendon's tension is the solved one.
    let solved = robot.with_tensions(&solution.tensions());
    let mut sens = Sensitivity::new(&solved, solution)?;
    let held = Held::new(&mut sens, robot, solution)?;
    // Without friction or held pull-ins, the 16 parameters besides the tensions cost six
    // transposed solves (the tip pose's multipliers) instead of one solve each.
    let multipliers = if held.holds() { None } else { sens.tip_multipliers()? };
    let mut tip = Tip {
        sens,
        held: &held,
        multipliers,
    };
    let k = robot.tendons.len();
    let mut tension = DMatrix::zeros(6, k);
    let mut displacement = DMatrix::zeros(6, k);
    let mut friction = DMatrix::zeros(6, k);
    for i in 0..k {
        if robot.tendons[i].displacement().is_some() {
            displacement.set_column(i, &held.pull(i)?);
        } else if robot.tendons[i].active_friction().is_some() && solution.tendons[i].tension == 0.0 {
            // Not modelled at 0 N with friction (Sensitivity::tension): NaN, not a guess.
            tension.set_column(i, &Vector6::repeat(f64::NAN));
        } else {
            // Forward solves: the columns a controller's Solver::tip_jacobian gives, to 1e-12.
            tension.set_column(i, &tip.sens.tension_tip(&held, i)?);
        }
        if robot.tendons[i].active_friction().is_some() {
            friction.set_column(i, &held.tip(&tip.sens.friction(i)?)?);
        }
    }
    let mut tip_force = Matrix6x3::zeros();
    let mut tip_moment = Matrix6x3::zeros();
    let mut base_position = Matrix6x3::zeros();
    let mut base_rotation = Matrix6x3::zeros();
    for j in 0..3 {
        tip_force.set_column(j, &tip.of(|s| s.tip_force_rhs(j))?);
        tip_moment.set_column(j, &tip.of(|s| s.tip_moment_rhs(j))?);
        base_position.set_column(j, &tip.of(|s| s.base_position_rhs(j))?);
        base_rotation.set_column(j, &tip.of(|s| s.base_rotation_rhs(j))?);
    }
    let moduli = moduli(&mut tip)?;
    Ok(TipSensitivities {
        tension,
        displacement,
        friction,
        tip_force,
        tip_moment,
        moduli,
        base_position,
        base_rotation,
    })
}

/// Derivatives with the pull-ins of the taut displacement-controlled tendons held: a
/// parameter's state derivative D_p changes their path lengths by dl = G D_p, and their
/// tensions follow to keep the lengths, S dtau = dl with S = C - dl/dtau
/// ([`TensionDirections`]); the tip moves by its own derivative plus d(tip)/dtau dtau.
/// Without such tendons it passes the derivatives through.
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
        unheld_friction(robot, &taut)?;
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

    /// The tip pose's derivative for the state derivative `d`, the pull-ins held.
    pub(super) fn tip(&self, d: &[NodeDerivative]) -> Result<Vector6<f64>> {
        let own = d[d.len() - 1].pose();
        let Some((h, schur)) = &self.directions else {
            return Ok(own);
        };
        let dtau = schur.solve(&h.length_change(d)).ok_or_else(super::singular)?;
        Ok(own + Vector6::from_iterator((&h.tip * dtau).iter().copied()))
    }

    /// d(tip pose)/dq_i for the displacement-controlled tendon `i` (per m): S dtau = e_i
    /// over the held tendons; zero for a slack one.
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

/// The linearization with what gives a right-hand side's tip derivative: the tip
/// multipliers (plain system), or a solve and the held pull-ins.
struct Tip<'s, 'a> {
    sens: Sensitivity<'a>,
    held: &'s Held,
    multipliers: Option<Vec<Vec<f64>>>,
}

impl Tip<'_, '_> {
    /// d(tip pose)/dq for the right-hand side `rhs` writes into the sensitivity's buffer.
    fn of(&mut self, rhs: impl FnOnce(&mut Sensitivity) -> Result<()>) -> Result<Vector6<f64>> {
        rhs(&mut self.sens)?;
        match &self.multipliers {
            Some(m) => Ok(self.sens.tip_by(m)),
            None => self.held.tip(&self.sens.respond()?),
        }
    }
}

/// The modulus derivatives when the rod's uniform section is the one its geometry gives.
fn moduli(tip: &mut Tip) -> Result<Option<ModulusSensitivities>> {
    let Some(g) = built_from_geometry(&tip.sens.robot().rod) else {
        return Ok(None);
    };
    let (o, i, e, nu) = (g.outer_radius, g.inner_radius, g.youngs_modulus, g.poisson_ratio);
    let shear = shear_modulus(e, nu);
    let (youngs_modulus, shear_modulus) = if tip.sens.exact_stiffness() {
        // The section is linear in (E, G): dk/dG at fixed E is the section of E = 0, G = 1.
        let unit_shear = stiffnesses(&Section::tube(o, i, 0.0, 1.0));
        (
            tip.of(|s| s.stiffness_rhs(&youngs_modulus_direction(g)))?,
            tip.of(|s| s.stiffness_rhs(&unit_shear))?,
        )
    } else {
        let by_g = tip
            .sens
            .derivative(RELATIVE_STEP * shear, Difference::Central, |r, d| {
                r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e, shear + d));
            })?;
        let by_e = youngs_modulus(&mut tip.sens, g)?;
        (tip.held.tip(&by_e)?, tip.held.tip(&by_g)?)
    };
    Ok(Some(ModulusSensitivities {
        youngs_modulus,
        // d/dE|_nu = d/dE|_G + (dG/dE)|_nu d/dG|_E with dG/dE|_nu = G / E.
        youngs_modulus_fixed_shear: youngs_modulus - shear_modulus * (shear / e),
        shear_modulus,
    }))
}

/// The geometry of `rod` when its uniform section is the one the geometry gives (to
/// rounding): only then are E and G what the stiffness was built from.
pub(super) fn built_from_geometry(rod: &Rod) -> Option<Geometry> {
    let (Some(g), Stiffness::Uniform(section)) = (rod.geometry, &rod.stiffness) else {
        return None;
    };
    let shear = shear_modulus(g.youngs_modulus, g.poisson_ratio);
    let built = Section::tube(g.outer_radius, g.inner_radius, g.youngs_modulus, shear);
    // 1e-12 relative: the same formulas give the section to rounding.
    let close = |a: &Vector3<f64>, b: &Vector3<f64>| (a - b).norm() <= 1e-12 * b.norm();
    (close(&section.kse, &built.kse) && close(&section.kbt, &built.kbt)).then_some(g)
}

/// The derivative of every node state with respect to E at fixed Poisson's ratio, for a rod
/// built from `geometry` (its uniform section the geometry's).
///
/// # Errors
/// As [`Sensitivity::derivative`].
pub(super) fn youngs_modulus(sens: &mut Sensitivity, geometry: Geometry) -> Result<Vec<NodeDerivative>> {
    let (o, i, e, nu) = (
        geometry.outer_radius,
        geometry.inner_radius,
        geometry.youngs_modulus,
        geometry.poisson_ratio,
    );
    if sens.exact_stiffness() {
        return sens.stiffness(&youngs_modulus_direction(geometry));
    }
    sens.derivative(RELATIVE_STEP * e, Difference::Central, |r, d| {
        r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e + d, shear_modulus(e + d, nu)));
    })
}

/// dk/dE at fixed Poisson's ratio for a rod built from `geometry`: every stiffness is
/// proportional to E, so dk/dE = k / E.
pub(super) fn youngs_modulus_direction(geometry: Geometry) -> [f64; 6] {
    let (o, i, e, nu) = (
        geometry.outer_radius,
        geometry.inner_radius,
        geometry.youngs_modulus,
        geometry.poisson_ratio,
    );
    let mut dk = stiffnesses(&Section::tube(o, i, e, shear_modulus(e, nu)));
    dk.iter_mut().for_each(|k| *k /= e);
    dk
}

/// The six diagonal stiffnesses of a section, kse then kbt, as [`Sensitivity::stiffness`]
/// takes them.
fn stiffnesses(section: &Section) -> [f64; 6] {
    let (a, b) = (section.kse, section.kbt);
    [a[0], a[1], a[2], b[0], b[1], b[2]]
}

/// Whole-backbone sensitivity: d p(s) / d tau_i (m/N, world frame) at each of `solution`'s
/// nodes, for tendon index `tendon` (0-based). For a slack tendon, the one-sided (pulling)
/// derivative.
///
/// # Errors
/// As [`Sensitivity::new`] and [`Sensitivity::tension`].
///
/// # Examples
/// ```
/// let robot = tdcr::cases::case_s();
/// let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
/// let dp = tdcr::collocation::sensitivity::backbone_tension_sensitivity(&robot, &solution, 0).unwrap();
/// assert_eq!(dp.len(), solution.nodes.len());
/// assert!(dp[0].norm() < 1e-12); // the base is clamped
/// ```
pub fn backbone_tension_sensitivity(robot: &Robot, solution: &Solution, tendon: usize) -> Result<Vec<Vector3<f64>>> {
    let mut sens = Sensitivity::new(robot, solution)?;
    Ok(sens.tension(tendon)?.iter().map(|d| d.p).collect())
}

/// Derivatives of a solution with respect to the pull-ins of its displacement-controlled
/// tendons (docs/actuation.md): what a resolved-rate controller needs.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplacementSensitivities {
    /// The displacement-controlled tendons (0-based indices), the columns' order.
    pub tendons: Vec<usize>,
    /// d(tip pose)/dq, 6 x k: tip position (m/m), then the world-frame tip rotation vector
    /// (rad/m), as in [`TipSensitivities`].
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
    unheld_friction(robot, &tendons)?;
    let directions = TensionDirections::new(robot, solution, tendons)?;
    let taut: Vec<bool> = directions
        .tendons
        .iter()
        .map(|&i| solution.tendons[i].slack == 0.0 && solution.tendons[i].tension > 0.0)
        .collect();
    let tension = directions.tension_by_displacement(&taut)?;
    Ok(DisplacementSensitivities {
        tip: &directions.tip * &tension,
        tendons: directions.tendons,
        tension,
    })
}

/// An error naming the first of the displacement-controlled `tendons` with friction: their
/// pull-ins' derivatives would need the stretch of the varying tension's derivative, not
/// modelled yet (docs/friction.md section 3b).
fn unheld_friction(robot: &Robot, tendons: &[usize]) -> Result<()> {
    match tendons.iter().find(|&&i| robot.tendons[i].active_friction().is_some()) {
        None => Ok(()),
        Some(&i) => Err(crate::error::invalid(
            format!("tendons[{i}].displacement"),
            "is a pull-in on a tendon with friction, and derivatives at held pull-ins do not model friction yet",
            "differentiate in the tension: give the tendon the tension its solve reports instead of the pull-in",
        )),
    }
}

/// What every pull-in derivative is made of: the tip's and the path lengths' derivatives
/// along each of k tendons' tensions (the k solves of [`displacement_sensitivities`]);
/// combining them for a set of taut tendons is a k x k solve.
pub(crate) struct TensionDirections {
    /// The tendons (0-based), the columns' order.
    pub(crate) tendons: Vec<usize>,
    /// d(tip pose)/dtau_m, 6 x k.
    pub(crate) tip: DMatrix<f64>,
    /// dl_j/dtau_m (m/N), k x k.
    length: DMatrix<f64>,
    /// c_j (m/N): each tendon's compliance at its reference length.
    compliance: Vec<f64>,
    /// Each tendon's path-length quadrature and routing along it: dl_j along any derivative.
    paths: Vec<(NodeQuadrature, Vec<RoutingPoint>)>,
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
    fn from(sens: &mut Sensitivity, solution: &Solution, tendons: Vec<usize>) -> Result<Self> {
        let robot = sens.robot();
        let k = tendons.len();
        let rod_length = robot.length();
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let paths = tendons
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
        let compliance = tendons
            .iter()
            .map(|&i| robot.tendons[i].compliance(solution.tendons[i].reference_length))
            .collect();
        let mut directions = TensionDirections {
            tip: DMatrix::zeros(6, k),
            length: DMatrix::zeros(k, k),
            tendons,
            compliance,
            paths,
            strains,
            fixed_strain: robot.rod_model == RodModel::Kirchhoff,
        };
        for m in 0..k {
            let d = sens.tension(directions.tendons[m])?;
            directions.tip.set_column(m, &d[d.len() - 1].pose());
            let change = directions.length_change(&d);
            directions.length.set_column(m, &change);
        }
        Ok(directions)
    }

    /// dl_j (m per unit of the parameter) of every tendon along the derivative `d` of the
    /// node states: the quadrature of the path speed's gradient (docs/actuation.md).
    fn length_change(&self, d: &[NodeDerivative]) -> DVector<f64> {
        DVector::from_iterator(
            self.tendons.len(),
            self.paths.iter().map(|(quadrature, routing)| {
                quadrature
                    .weights
                    .iter()
                    .zip(routing)
                    .map(|(&(node, w), rp)| {
                        let (v, u) = &self.strains[node];
                        let (dv, du) = speed_gradient(rp, v, u);
                        w * (dv.dot(&d[node].v) + du.dot(&d[node].u))
                    })
                    .sum::<f64>()
            }),
        )
    }

    /// Adds G^T w to the scaled cotangent `g` (12 per node, d = (dp / L, dtheta, dv, du L)):
    /// the transpose of [`TensionDirections::length_change`], w_j weighting tendon j's path
    /// length (rod length `length`, m). Node k's dv slot gets sum_j w_j weight dspeed/dv,
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
    /// the tensions, C - dl/dtau (q_j = l_ref_j - l_j + c_j tau_j).
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
