//! Sensitivities to the named parameters of [`Parameter`] (`tension.I`, `tip_force.x`,
//! `youngs_modulus`, ...): the one vocabulary of batches, sweeps and the gradients of
//! `adjoint.rs`. Each name picks how its dF/dq is made: exact for the tip wrench and the
//! base position (module docs of `sensitivity`) and a tension (one pass for every tendon),
//! a central difference of the residual with [`Parameter::apply`] on a clone of the robot
//! otherwise; a pull-in enters no row (control.rs and adjoint.rs hold the tendon's length).

use super::exact::residual_at;
use super::tip::{built_from_geometry, youngs_modulus_direction};
use super::{Difference, NodeDerivative, RELATIVE_STEP, Sensitivity, force_scale};
use crate::error::{Result, invalid};
use crate::model::parameter::Parameter;

impl Sensitivity<'_> {
    /// The derivative of every node state with respect to the named parameter `parameter`
    /// (per unit of it), as [`Parameter::apply`] defines it: a tension's is
    /// [`Sensitivity::tension`], a tip-force component's [`Sensitivity::tip_force`], a
    /// tip-moment component's [`Sensitivity::tip_moment`], a base-position component's
    /// [`Sensitivity::base_position`], `youngs_modulus` (at fixed Poisson's ratio) of a rod
    /// built from its geometry [`Sensitivity::stiffness`] along dk = k / E (exact without
    /// friction), a friction coefficient's [`Sensitivity::friction`]; `distributed_force.*`, `load_scale`, `routing.I.x|y` (and E with friction)
    /// are differenced centrally with steps [`RELATIVE_STEP`] times max(|f|, E I / L^3), 1,
    /// max(|r_I|, L / 100) and E.
    /// `displacement.I` has no such derivative (it enters no row: the pull-in holds the
    /// tendon's length) and is an error here.
    ///
    /// # Errors
    /// As [`Parameter::check`] for a parameter the robot does not have; as
    /// [`Sensitivity::derivative`].
    pub fn parameter(&mut self, parameter: Parameter) -> Result<Vec<NodeDerivative>> {
        self.parameter_rhs(parameter)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::parameter`] into the right-hand side buffer.
    pub(super) fn parameter_rhs(&mut self, parameter: Parameter) -> Result<()> {
        let robot = self.robot();
        parameter.check(robot)?;
        let value = parameter.value(robot)?;
        let step = match parameter {
            Parameter::Tension(i) => return self.tension_rhs(i),
            Parameter::TipForce(axis) => return self.tip_force_rhs(axis),
            Parameter::TipMoment(axis) => return self.tip_moment_rhs(axis),
            Parameter::BasePosition(axis) => return self.base_position_rhs(axis),
            Parameter::Friction(i) => return self.friction_rhs(i),
            // The residual is linear in f_e: any step is exact but for rounding; the scale
            // is that of the tip force over the rod's length.
            Parameter::DistributedForce(_) => RELATIVE_STEP * value.abs().max(force_scale(robot) / robot.length()),
            Parameter::YoungsModulus => match built_from_geometry(&robot.rod) {
                // Exact: the section's stiffnesses move in proportion to E.
                Some(g) if self.exact_stiffness() => return self.stiffness_rhs(&youngs_modulus_direction(g)),
                _ => RELATIVE_STEP * value,
            },
            Parameter::LoadScale => RELATIVE_STEP,
            // An offset's scale: the tendon's distance from the centreline, at least L / 100
            // (the size of offsets on continuum robots: 8 mm on the 242 mm prototype).
            Parameter::RoutingOffset(i, _) => {
                let r = robot.tendons[i].routing.at(0.0, robot.length()).r.norm();
                RELATIVE_STEP * r.max(robot.length() / 100.0)
            }
            Parameter::Displacement(i) => {
                return Err(invalid(
                    parameter.to_string(),
                    format!(
                        "enters no row of the collocation system: tendon {}'s pull-in sets its length, which \
                         holds the tension",
                        i + 1
                    ),
                    "take pull-in derivatives from tip_jacobian or the adjoint gradient (Adjoint::gradient), which \
                     hold the tendon's length",
                ));
            }
        };
        self.differenced_rhs(step, Difference::Central, |system, states, dq, out| {
            residual_at(
                system,
                states,
                &|r: &mut crate::Robot, d: f64| {
                    // `check` above: the parameter exists, so apply cannot fail.
                    let _ = parameter.apply(r, value + d);
                },
                dq,
                out,
            )
        })
    }
}
