//! Control Jacobians: the columns a controller asks for (tensions, say) of the tip pose's
//! derivative ([`tip_jacobian`]) and of the backbone positions' at chosen arc lengths
//! ([`backbone_jacobian`]), from one factorization and one solve per column, without the
//! parameters nobody asked for.
//!
//! Each column is the one [`super::tip_sensitivities`] computes for that parameter (the
//! same right-hand side, step and stencil), so the two agree to rounding. A
//! [`crate::Solver`] computes them with the workspace of its last solve (no allocation of
//! buffers or pattern, [`crate::Solver::tip_jacobian`]).
//!
//! # Backbone points
//!
//! The position at an arc length between nodes is the solution's cubic Hermite interpolant
//! ([`Solution::at`]) of the node positions p_k and rates p_k' = R_k v_k, so its derivative
//! is the same interpolant of dp_k/dq and d(p_k')/dq = omega_k x (R_k v_k) + R_k dv_k/dq
//! (R -> exp(hat(omega dq)) R, [`NodeDerivative`]): the exact derivative of what
//! `solution.at(s).p` returns on the solution's mesh.

use super::held::Held;
use super::tip::{built_from_geometry, youngs_modulus};
use super::{NodeDerivative, Sensitivity};
use crate::error::{Result, invalid};
use crate::model::parameter::Parameter;
use crate::model::robot::Robot;
use crate::solution::Solution;
use nalgebra::{DMatrix, Vector3};

/// The parameters named by `names` for a control Jacobian of `robot`, in order: a
/// parameter's name ([`Parameter`]: `tension.2`, `tip_force.z`, `youngs_modulus`, ...) or a
/// group, `tension` (every tendon, file order), `tip_force`, `tip_moment` or
/// `base_position` (x, y, z).
///
/// # Errors
/// [`crate::Error::InvalidInput`] for a name that is neither, or that the robot does not
/// have (as [`Parameter::parse`]); `tension` for a robot with no tendons (it names no
/// column).
///
/// # Examples
/// ```
/// use tdcr::Parameter;
/// let robot = tdcr::cases::case_s();
/// let wrt = tdcr::collocation::sensitivity::columns(&["tension", "tip_force.z"], &robot).unwrap();
/// assert_eq!(wrt.len(), 6);
/// assert_eq!(wrt[5], Parameter::TipForce(2));
/// ```
pub fn columns<S: AsRef<str>>(names: &[S], robot: &Robot) -> Result<Vec<Parameter>> {
    let mut out = Vec::new();
    for name in names {
        let axes = |p: fn(usize) -> Parameter| (0..3).map(p).collect::<Vec<_>>();
        match name.as_ref() {
            "tension" if robot.tendons.is_empty() => {
                return Err(crate::error::invalid(
                    "jacobian columns",
                    "name `tension`, but the robot has no tendons: there is no tension to differentiate by",
                    "leave out `tension`, or give the robot a tendon",
                ));
            }
            "tension" => out.extend((0..robot.tendons.len()).map(Parameter::Tension)),
            "tip_force" => out.extend(axes(Parameter::TipForce)),
            "tip_moment" => out.extend(axes(Parameter::TipMoment)),
            "base_position" => out.extend(axes(Parameter::BasePosition)),
            other => out.push(Parameter::parse(other, robot)?),
        }
    }
    Ok(out)
}

/// The columns of d(tip pose)/dq for the parameters `wrt`, 6 x `wrt.len()`, in the layout of
/// [`super::TipSensitivities`]: tip position x, y, z (m per unit of q), then the tip rotation
/// as a world-frame rotation vector (rad per unit of q). A tension column is
/// `TipSensitivities::tension`'s (zero for a displacement-controlled tendon; with taut
/// displacement-controlled tendons every column holds their pull-ins).
///
/// Costs one Jacobian assembly and factorization, then per column one solve with the
/// stored factors, plus one pass over the mesh for all tension columns together (exact) and
/// two residual evaluations for E, a distributed force, a routing offset or a friction
/// coefficient (differenced).
/// A `displacement.I` column holds the other pull-ins (docs/actuation.md, "Sensitivities").
///
/// # Errors
/// [`crate::Error::InvalidInput`] for a parameter the robot does not have or that is not a
/// column ([`Parameter::LoadScale`]), the pull-in of a tension-controlled tendon, the
/// routing offset of a taut displacement-controlled tendon (its held length moves with
/// it), and as [`Sensitivity::new`].
///
/// # Examples
/// ```
/// use tdcr::Parameter;
/// let robot = tdcr::cases::case_h();
/// let solution = tdcr::solve(&robot, &Default::default()).unwrap();
/// let wrt: Vec<Parameter> = (0..5).map(Parameter::Tension).collect();
/// let j = tdcr::collocation::sensitivity::tip_jacobian(&robot, &solution, &wrt).unwrap();
/// assert_eq!(j.shape(), (6, 5));
/// ```
pub fn tip_jacobian(robot: &Robot, solution: &Solution, wrt: &[Parameter]) -> Result<DMatrix<f64>> {
    // A displacement-controlled tendon's tension is the solved one.
    let solved = robot.with_tensions(&solution.tensions());
    let tips = tension_tips(robot, wrt);
    let mut sens = Sensitivity::with_workspace(&solved, solution, None, None, false, tips)?;
    tip_columns(&mut sens, robot, solution, wrt)
}

/// Whether the tip Jacobian of `robot` in `wrt` takes the tension columns' tips out of the
/// factoring ([`Sensitivity::with_workspace`]'s `tips`): it asks for a tension, and no
/// tendon is displacement-controlled (no pull-ins to hold, no tension that is an unknown).
pub(crate) fn tension_tips(robot: &Robot, wrt: &[Parameter]) -> bool {
    !robot.has_displacement_inputs()
        && wrt
            .iter()
            .any(|p| matches!(p, Parameter::Tension(i) if *i < robot.tendons.len()))
}

/// The positions' columns at the arc lengths `s` (m, each in [0, L]): a 3 `s.len()` x
/// `wrt.len()` matrix whose rows 3 j, 3 j + 1, 3 j + 2 are d p(s_j)/dq, world frame (m per
/// unit of q), the derivative of `solution.at(s_j).p` (module docs).
///
/// # Errors
/// As [`tip_jacobian`]; [`crate::Error::InvalidInput`] for an arc length outside the rod
/// and for a robot with taut displacement-controlled tendons (whose held pull-ins only the
/// tip Jacobian includes).
///
/// # Examples
/// ```
/// use tdcr::Parameter;
/// let robot = tdcr::cases::case_s();
/// let solution = tdcr::solve(&robot, &Default::default()).unwrap();
/// let s = [0.0, 0.1, robot.length()];
/// let j = tdcr::collocation::sensitivity::backbone_jacobian(&robot, &solution, &[Parameter::Tension(0)], &s).unwrap();
/// assert_eq!(j.shape(), (9, 1));
/// assert!(j.rows(0, 3).norm() < 1e-12); // the base is clamped
/// ```
pub fn backbone_jacobian(robot: &Robot, solution: &Solution, wrt: &[Parameter], s: &[f64]) -> Result<DMatrix<f64>> {
    let solved = robot.with_tensions(&solution.tensions());
    let mut sens = Sensitivity::new(&solved, solution)?;
    backbone_columns(&mut sens, robot, solution, wrt, s)
}

/// [`tip_jacobian`] with `sens` linearized at `solution` (for `robot` with the solved tensions).
///
/// # Errors
/// As [`tip_jacobian`].
pub(crate) fn tip_columns(
    sens: &mut Sensitivity,
    robot: &Robot,
    solution: &Solution,
    wrt: &[Parameter],
) -> Result<DMatrix<f64>> {
    check(robot, wrt)?;
    let held = Held::new(sens, robot, solution)?;
    let mut out = DMatrix::zeros(6, wrt.len());
    for (j, p) in wrt.iter().enumerate() {
        held.check(*p)?;
        if let Parameter::Displacement(i) = *p {
            out.set_column(j, &held.pull(pulled(robot, i)?)?);
        } else if let Parameter::Tension(i) = *p
            && robot.tendons[i].displacement().is_none()
        {
            out.set_column(j, &sens.tension_tip(&held, i)?);
        } else if let Some(d) = column(sens, robot, *p)? {
            out.set_column(j, &held.tip(&d, sens)?);
        }
    }
    Ok(out)
}

/// [`backbone_jacobian`] with `sens` linearized at `solution`.
///
/// # Errors
/// As [`backbone_jacobian`].
pub(crate) fn backbone_columns(
    sens: &mut Sensitivity,
    robot: &Robot,
    solution: &Solution,
    wrt: &[Parameter],
    s: &[f64],
) -> Result<DMatrix<f64>> {
    check(robot, wrt)?;
    let length = robot.length();
    if let Some((i, v)) = s
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && (0.0..=length).contains(*v)))
    {
        return Err(invalid(
            format!("s[{i}]"),
            format!("is {v} m, outside the rod [0, {length}] m"),
            "give arc lengths from 0 (base) to the rod length (tip)",
        ));
    }
    if Held::new(sens, robot, solution)?.holds() {
        return Err(invalid(
            "robot.tendons",
            "include taut displacement-controlled tendons, whose held pull-ins the backbone Jacobian does not include",
            "use the tip Jacobian (which holds them), or give those tendons tensions",
        ));
    }
    let mut out = DMatrix::zeros(3 * s.len(), wrt.len());
    for (c, p) in wrt.iter().enumerate() {
        let Some(d) = column(sens, robot, *p)? else {
            continue;
        };
        for (j, &sj) in s.iter().enumerate() {
            out.fixed_view_mut::<3, 1>(3 * j, c)
                .copy_from(&position_derivative(solution, &d, sj));
        }
    }
    Ok(out)
}

/// Tendon `i` when it is displacement-controlled (its pull-in a column), else
/// [`crate::Error::InvalidInput`].
pub(super) fn pulled(robot: &Robot, i: usize) -> Result<usize> {
    if robot.tendons[i].displacement().is_some() {
        Ok(i)
    } else {
        Err(invalid(
            format!("displacement.{}", i + 1),
            format!("has no derivative: tendon {} is tension-controlled", i + 1),
            format!("give tendon {} a displacement (pull-in) to differentiate in it", i + 1),
        ))
    }
}

/// Checks every parameter against `robot` ([`Parameter::check`]).
fn check(robot: &Robot, wrt: &[Parameter]) -> Result<()> {
    wrt.iter().try_for_each(|p| p.check(robot))
}

/// The node derivatives for parameter `p` (checked against `robot`), `None` for a column that
/// is zero (the tension of a displacement-controlled tendon, which its pull-in sets).
fn column(sens: &mut Sensitivity, robot: &Robot, p: Parameter) -> Result<Option<Vec<NodeDerivative>>> {
    let d = match p {
        Parameter::Tension(i) if robot.tendons[i].displacement().is_some() => return Ok(None),
        Parameter::Tension(i) => sens.tension(i)?,
        Parameter::TipForce(k) => sens.tip_force(k)?,
        Parameter::TipMoment(k) => sens.tip_moment(k)?,
        Parameter::BasePosition(k) => sens.base_position(k)?,
        Parameter::YoungsModulus => {
            let Some(geometry) = built_from_geometry(&sens.robot().rod) else {
                return Err(invalid(
                    "youngs_modulus",
                    "has no derivative here: the rod's section is not the one its geometry gives",
                    "build the rod from its geometry alone (outer_radius, youngs_modulus, poisson_ratio)",
                ));
            };
            youngs_modulus(sens, geometry)?
        }
        Parameter::RoutingOffset(..) | Parameter::DistributedForce(_) | Parameter::Friction(_) => sens.parameter(p)?,
        Parameter::Displacement(_) => {
            return Err(invalid(
                p.to_string(),
                "is not a column of the backbone Jacobian (its pull-in holds the tendon's length, which only the \
                 tip Jacobian includes)",
                "use the tip Jacobian for pull-in columns",
            ));
        }
        Parameter::LoadScale => {
            return Err(invalid(
                p.to_string(),
                "is not a column of the control Jacobian",
                "ask for tension.I, displacement.I, tip_force.x|y|z, tip_moment.x|y|z, base_position.x|y|z, \
                 distributed_force.x|y|z, routing.I.x|y, friction.I or youngs_modulus",
            ));
        }
    };
    Ok(Some(d))
}

/// d p(s)/dq from the node derivatives `d` of `solution`: the derivative of the Hermite
/// interpolant [`Solution::at`] evaluates (module docs).
fn position_derivative(solution: &Solution, d: &[NodeDerivative], s: f64) -> Vector3<f64> {
    let (k, [w0, w0s, w1, w1s]) = solution.interval(s, false);
    let (a, b) = (&solution.nodes[k], &solution.nodes[k + 1]);
    let h = b.s - a.s;
    // d(R v)/dq = omega x (R v) + R dv/dq.
    let rate = |n: &crate::solution::Node, dn: &NodeDerivative| dn.rotation.cross(&(n.R * n.v)) + n.R * dn.v;
    d[k].p * w0 + rate(a, &d[k]) * (w0s * h) + d[k + 1].p * w1 + rate(b, &d[k + 1]) * (w1s * h)
}
