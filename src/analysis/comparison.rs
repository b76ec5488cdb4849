//! Simpler models, for benchmark comparisons with the coupled model (docs/validation.md):
//!
//! - the point-moment tendon model (Jones et al., cited by the paper) is a switch on the robot,
//!   [`crate::TendonModel::PointMoment`], solved by the same solvers as the coupled model;
//! - the constant-curvature model is closed form: [`constant_curvature`].
#![allow(non_snake_case)]

use crate::error::Result;
use crate::model::robot::Robot;
use crate::so3;
use crate::solution::State;
use nalgebra::Vector3;

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
