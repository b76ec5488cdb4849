//! Simpler models, for benchmark comparisons with the coupled model (docs/validation.md):
//!
//! - the point-moment tendon model (Jones et al., cited by the paper) is a switch on the robot,
//!   [`crate::TendonModel::PointMoment`], solved by the same solvers as the coupled model;
//! - the constant-curvature model is closed form: [`constant_curvature`];
//! - the Kirchhoff rod (inextensible and unshearable) is a switch on the robot too,
//!   [`crate::RodModel::Kirchhoff`].
//!
//! [`compare_models`] solves one robot as several of these [`Variant`]s and [`compare`]
//! measures how far each shape's tip is from the first's (`tdcr compare`, `tdcr.compare`).
#![allow(non_snake_case)]

use crate::error::{Result, invalid};
use crate::model::robot::{Robot, RodModel, TendonModel};
use crate::so3;
use crate::solution::{Solution, State};
use nalgebra::{Matrix3, Vector3};

/// Intervals a solved shape is sampled on for a comparison ([`Solution::at`], the scheme's
/// own interpolant), and segments a constant-curvature arc is cut into: enough for a smooth
/// picture of a robot of a few turns.
pub const SHAPE_SAMPLES: usize = 256;

/// One model of the robot in a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// The coupled Cosserat rod/string model with corner forces (the library's default).
    Coupled,
    /// The point-moment tendon model ([`TendonModel::PointMoment`]).
    PointMoment,
    /// The closed-form constant-curvature model ([`constant_curvature`]).
    ConstantCurvature,
    /// The coupled model with the paper's jump conditions (`Robot::corner_forces = false`).
    PaperJumps,
    /// The coupled model on an inextensible, unshearable rod ([`RodModel::Kirchhoff`]).
    Kirchhoff,
}

impl Variant {
    /// Every variant, in the order the docs list them.
    pub const ALL: [Variant; 5] = [
        Variant::Coupled,
        Variant::PointMoment,
        Variant::ConstantCurvature,
        Variant::PaperJumps,
        Variant::Kirchhoff,
    ];

    /// The variant's name, as `tdcr compare --models` and `tdcr.compare` spell it.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Coupled => "coupled",
            Variant::PointMoment => "point_moment",
            Variant::ConstantCurvature => "constant_curvature",
            Variant::PaperJumps => "paper_jumps",
            Variant::Kirchhoff => "kirchhoff",
        }
    }

    /// The variant called `name`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the known variants.
    pub fn from_name(name: &str) -> Result<Variant> {
        Variant::ALL.into_iter().find(|v| v.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Variant::ALL.iter().map(|v| v.name()).collect();
            invalid(
                "models",
                format!("has `{name}`, which is not a model"),
                format!("give some of {}", names.join(", ")),
            )
        })
    }

    /// `robot` with this variant's switches set (all three, whatever the robot had): the
    /// coupled tendon model with or without corner forces, or the point-moment model, on
    /// the Cosserat rod, or the coupled model on the Kirchhoff rod. The constant-curvature
    /// variant is not solved, so it keeps the robot as the coupled one.
    pub fn robot(self, robot: &Robot) -> Robot {
        let mut out = robot.clone();
        out.corner_forces = self != Variant::PaperJumps;
        out.tendon_model = match self {
            Variant::PointMoment => TendonModel::PointMoment,
            _ => TendonModel::Coupled,
        };
        out.rod_model = match self {
            Variant::Kirchhoff => RodModel::Kirchhoff,
            _ => RodModel::Cosserat,
        };
        out
    }
}

/// One shape of a comparison and how far its tip is from the first shape's.
#[derive(Clone, Debug, PartialEq)]
pub struct Compared {
    /// What it is (a [`Variant::name`] or a solver's name).
    pub name: String,
    /// The backbone from base to tip ([`SHAPE_SAMPLES`] intervals of a solved shape).
    pub states: Vec<State>,
    /// Distance of the tip from the first shape's tip (m); 0 for the first.
    pub tip_distance: f64,
    /// Angle of the rotation between the tip frames, |log(R_first(L)^T R(L))| (rad); 0 for
    /// the first.
    pub tip_angle: f64,
}

impl Compared {
    /// The tip position p(L) (m, world frame).
    pub fn tip_position(&self) -> Vector3<f64> {
        self.states.last().map_or_else(Vector3::zeros, |s| s.p)
    }

    /// The tip rotation R(L), body to world.
    pub fn tip_rotation(&self) -> Matrix3<f64> {
        self.states.last().map_or_else(Matrix3::identity, |s| s.R)
    }
}

/// The states of a solved shape at [`SHAPE_SAMPLES`] + 1 evenly spaced arc lengths from the
/// base to the tip, from the solution's interpolant.
pub fn shape(solution: &Solution) -> Vec<State> {
    let length = solution.length();
    (0..=SHAPE_SAMPLES)
        .map(|k| solution.at_limit(length * k as f64 / SHAPE_SAMPLES as f64, k == SHAPE_SAMPLES))
        .collect()
}

/// Named shapes, each with its tip's distance and angle from the first's. Shapes without
/// states are compared as if their tip were at the origin with the identity rotation.
pub fn compare(shapes: Vec<(String, Vec<State>)>) -> Vec<Compared> {
    let mut out: Vec<Compared> = shapes
        .into_iter()
        .map(|(name, states)| Compared {
            name,
            states,
            tip_distance: 0.0,
            tip_angle: 0.0,
        })
        .collect();
    if let Some((first, rest)) = out.split_first_mut() {
        let (p, R) = (first.tip_position(), first.tip_rotation());
        for c in rest {
            c.tip_distance = (c.tip_position() - p).norm();
            c.tip_angle = so3::log(&(R.transpose() * c.tip_rotation())).norm();
        }
    }
    out
}

/// `robot` solved as each of `variants` (with `solve`, the caller's solver and options;
/// the constant-curvature variant in closed form), each tip compared with the first's.
///
/// # Errors
/// The first error of `solve` or of [`constant_curvature`].
///
/// # Examples
/// ```
/// use tdcr::analysis::comparison::{Variant, compare_models};
/// let robot = tdcr::cases::case_s();
/// let variants = [Variant::Coupled, Variant::PointMoment];
/// let shapes = compare_models(&robot, &variants, |r| tdcr::collocation::solve(r, &Default::default())).unwrap();
/// // Case S's straight tendon: the point-moment model misses only the compression, microns.
/// assert!(shapes[1].tip_distance < 1e-4);
/// ```
pub fn compare_models(
    robot: &Robot,
    variants: &[Variant],
    solve: impl Fn(&Robot) -> Result<Solution>,
) -> Result<Vec<Compared>> {
    let shapes = variants
        .iter()
        .map(|&v| {
            let states = match v {
                Variant::ConstantCurvature => arcs(robot)?,
                _ => shape(&solve(&v.robot(robot))?),
            };
            Ok((v.name().to_string(), states))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(compare(shapes))
}

/// The constant-curvature shape cut into about [`SHAPE_SAMPLES`] segments over the robot.
fn arcs(robot: &Robot) -> Result<Vec<State>> {
    let segments = robot.breakpoints().len() + 1;
    let mut states = constant_curvature(robot, SHAPE_SAMPLES.div_ceil(segments))?;
    // Each segment's last state is the next one's first: keep one of each pair.
    states.dedup_by(|b, a| a.s == b.s);
    Ok(states)
}

/// Points along each segment used to average a routing's offset.
const OFFSET_SAMPLES: usize = 64;

/// The constant-curvature shape: each segment between tendon terminations is a circular arc
/// (a helix when the moment has a twist component) whose curvature carries the moment of the
/// tendons that reach past it, u = u* + C^-1 sum_i tau_i (e3 x r_i). External loads, shear and
/// extension, and the tendons' distributed loads are ignored; a curved routing acts through
/// its mean offset over the segment. Returns `samples_per_segment + 1` states per segment,
/// the last the tip.
///
/// # Errors
/// Invalid input (see [`Robot::validate`]).
pub fn constant_curvature(robot: &Robot, samples_per_segment: usize) -> Result<Vec<State>> {
    robot.validate()?;
    let length = robot.length();
    let mut p = robot.base_position;
    let mut R = robot.base_rotation;
    let mut start = 0.0;
    let mut out = Vec::new();
    let samples = samples_per_segment.max(1);
    for end in robot.breakpoints().into_iter().chain(std::iter::once(length)) {
        let h = end - start;
        let section = robot.rod.section_at(0.5 * (start + end)).section;
        let reference = robot.rod.reference_at(0.5 * (start + end));
        let mut moment = Vector3::zeros();
        for t in robot.tendons.iter().filter(|t| t.end(length) >= end) {
            let mean: Vector3<f64> = (0..OFFSET_SAMPLES)
                .map(|k| {
                    t.routing
                        .at(start + h * (k as f64 + 0.5) / OFFSET_SAMPLES as f64, length)
                        .r
                })
                .sum::<Vector3<f64>>()
                / OFFSET_SAMPLES as f64;
            moment += Vector3::z().cross(&mean) * t.tension();
        }
        let u = reference.u_star + moment.component_div(&section.kbt);
        for k in 0..=samples {
            let s = h * k as f64 / samples as f64;
            // p = p0 + R0 J_l(u s) e3 s with the left Jacobian J_l = J_r^T (exact for constant u)
            let p_s = p + R * so3::right_jacobian(&(u * s)).transpose() * Vector3::z() * s;
            out.push(State {
                s: start + s,
                p: p_s,
                R: R * so3::exp(&(u * s)),
                v: Vector3::z(),
                u,
            });
        }
        p += R * so3::right_jacobian(&(u * h)).transpose() * Vector3::z() * h;
        R *= so3::exp(&(u * h));
        start = end;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Loads, Rod, Routing, Tendon, collocation};
    use approx::assert_relative_eq;

    #[test]
    fn one_tendon_without_loads_is_the_coupled_inextensible_arc() {
        // Very stiff in extension so the coupled model's arc is the constant-curvature one.
        let section = crate::Section::explicit(1e12, 1e12, 4e-3, 4e-3, 3e-3);
        let robot = Robot::new(Rod::new(0.2, section)).with_tendon(Tendon::new(Routing::straight(0.005, 0.0), 2.0));
        let cc = constant_curvature(&robot, 8).unwrap();
        let coupled = collocation::solve(&robot, &Default::default()).unwrap();
        // 1e-9: the coupled solution is the same arc up to tau/EA = 2e-12 and solver error
        assert_relative_eq!(cc.last().unwrap().p, coupled.tip_position(), epsilon = 1e-9);
    }

    #[test]
    fn arcs_join_continuously_at_terminations() {
        let robot = Robot::new(Rod::solid_circle(0.3, 5e-4, 200e9, 0.3))
            .with_tendon(Tendon::new(Routing::straight(0.004, 0.0), 3.0).ending_at(0.1))
            .with_tendon(Tendon::new(Routing::straight(0.0, 0.004), 2.0))
            .with_loads(Loads::none());
        let shape = constant_curvature(&robot, 4).unwrap();
        assert_eq!(shape.len(), 10);
        // The last state of a segment and the first of the next share a pose.
        assert_relative_eq!(shape[4].p, shape[5].p, epsilon = 1e-15);
        assert_relative_eq!(shape[4].R, shape[5].R, epsilon = 1e-15);
    }
}
