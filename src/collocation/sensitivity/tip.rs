//! Tip sensitivities in one call ([`tip_sensitivities`]: tensions, tip wrench, moduli,
//! base pose) and the whole-backbone position derivative with respect to one tension, both
//! from one [`Sensitivity`] (one factorization), and the solves for the tip alone.

use super::held::Held;
use super::{Difference, NodeDerivative, RELATIVE_STEP, Sensitivity, singular};
use crate::collocation::{LinearSolver, unknowns, workspace};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::model::robot::Robot;
use crate::model::rod::{Geometry, Rod, Section, Stiffness, shear_modulus};
use crate::solution::Solution;
use nalgebra::{DMatrix, Matrix6, Matrix6x3, Vector3, Vector6};

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
    /// the one-sided (pulling) derivative, with friction too (the first pull's capstan
    /// profile, [`super::Sensitivity::tension`]); zero for a displacement-controlled tendon
    /// (see `displacement`).
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
/// `collocation/friction` (the log tensions are unknowns too). The linear-solver workspace
/// is the one this thread kept for the mesh, as a stateless solve takes one, and is kept
/// for the next call.
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
    // Without pull-ins to hold, the tension columns' tips come out of the factoring.
    let tips = !robot.has_displacement_inputs();
    // The workspace this thread kept for the mesh (the last call's on it, as a stateless
    // solve takes one), given back at the end; None when the points make no mesh (the
    // linearization then reports what is wrong, robot first).
    let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mesh = Mesh::from_points(&solved, &s).ok();
    let (kept, workspace) = match mesh.as_ref().map(|m| (m, workspace::spare(m, LinearSolver::Blocks))) {
        Some((_, Some((kept, w)))) => (Some(kept), Some(w)),
        Some((m, None)) => (Some(m.clone()), None),
        None => (None, None),
    };
    let mut sens = Sensitivity::with_workspace(&solved, solution, workspace, mesh, false, tips)?;
    let out = tip_sensitivities_from(&mut sens, robot, solution)?;
    if let Some(mesh) = kept {
        workspace::keep(mesh, LinearSolver::Blocks, sens.into_workspace());
    }
    Ok(out)
}

/// Every tip sensitivity of [`tip_sensitivities`] from `sens`, the linearization of `robot`
/// (its tensions the solved ones) at `solution`, however it was factored: the stateless
/// function's workspace, or a [`crate::Solver`]'s ([`crate::Solver::tip_sensitivities`]).
///
/// # Errors
/// As [`tip_sensitivities`].
pub(crate) fn tip_sensitivities_from(
    sens: &mut Sensitivity,
    robot: &Robot,
    solution: &Solution,
) -> Result<TipSensitivities> {
    let held = Held::new(sens, robot, solution)?;
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
        } else {
            // Forward solves: the columns a controller's Solver::tip_jacobian gives, to 1e-12.
            tension.set_column(i, &tip.sens.tension_tip(&held, i)?);
        }
        if robot.tendons[i].active_friction().is_some() {
            let d = tip.sens.friction(i)?;
            friction.set_column(i, &held.tip(&d, tip.sens)?);
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

impl Sensitivity<'_> {
    /// The tip pose's derivative (position, then the world-frame rotation vector) for the
    /// right-hand side in `scratch[0]`, from the last node of the solve alone
    /// ([`Workspace::solve_again_last`]: no back substitution through the other nodes);
    /// bitwise the last entry of [`Sensitivity::respond`]'s. None with friction, whose
    /// bordered solve needs every node.
    fn tip_response(&mut self) -> Result<Option<Vector6<f64>>> {
        if self.border.border_rows() > 0 {
            return Ok(None);
        }
        let n = self.border.system().unknowns();
        let dx = self
            .workspace
            .solve_again_last(&self.scratch[0][..n])
            .ok_or_else(singular)?;
        Ok(Some(self.tip_pose(&dx)))
    }

    /// The tip pose's derivative (position, then the world-frame rotation vector) from the
    /// last node's scaled unknowns `dx`.
    fn tip_pose(&self, dx: &[f64; unknowns::NODE]) -> Vector6<f64> {
        let tip = &self.states[self.states.len() - 1];
        let length = self.robot().length();
        let [p, theta, ..] = unknowns::node_increments(dx, 0, length);
        let rotation = tip.R * theta;
        Vector6::new(p[0], p[1], p[2], rotation[0], rotation[1], rotation[2])
    }

    /// The tip pose's derivative in tendon `tendon`'s tension (per N), the pull-ins `held`:
    /// [`Sensitivity::tension`]'s last node, solved for the tip alone where nothing needs
    /// the other nodes (no friction, no held pull-ins).
    ///
    /// # Errors
    /// As [`Sensitivity::tension`].
    pub(super) fn tension_tip(&mut self, held: &Held, tendon: usize) -> Result<Vector6<f64>> {
        if !held.holds() {
            if let Some(dx) = self.tension_tips.as_ref().and_then(|t| t.get(tendon)) {
                return Ok(self.tip_pose(dx));
            }
            self.tension_rhs(tendon)?;
            if let Some(pose) = self.tip_response()? {
                return Ok(pose);
            }
        }
        let d = self.tension(tendon)?;
        held.tip(&d, self)
    }
}

/// The linearization with what gives a right-hand side's tip derivative: the tip
/// multipliers (plain system), or a solve and the held pull-ins.
struct Tip<'s, 'a> {
    sens: &'s mut Sensitivity<'a>,
    held: &'s Held,
    multipliers: Option<Vec<Vec<f64>>>,
}

impl Tip<'_, '_> {
    /// d(tip pose)/dq for the right-hand side `rhs` writes into the sensitivity's buffer.
    fn of(&mut self, rhs: impl FnOnce(&mut Sensitivity) -> Result<()>) -> Result<Vector6<f64>> {
        rhs(self.sens)?;
        match &self.multipliers {
            Some(m) => Ok(self.sens.tip_by(m)),
            None => {
                let d = self.sens.respond()?;
                self.held.tip(&d, self.sens)
            }
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
        // Each held right after its own solve (the log tensions' derivative is the last one's).
        let by_g = tip
            .sens
            .derivative(RELATIVE_STEP * shear, Difference::Central, |r, d| {
                r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e, shear + d));
            })?;
        let by_g = tip.held.tip(&by_g, tip.sens)?;
        let by_e = youngs_modulus(tip.sens, g)?;
        (tip.held.tip(&by_e, tip.sens)?, by_g)
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
