//! A named scalar input of a robot, the one vocabulary of every front end: what a sweep or a
//! trace varies, a column of a `tdcr batch` table, a key of the Python package's parameter
//! dicts. Setting a parameter means the same everywhere ([`Parameter::apply`]), and a trace,
//! which sets it on the model instead of the robot (`Model::parameter`), gives the same
//! physics (docs/parameters.md).
//!
//! | name | meaning | unit |
//! | --- | --- | --- |
//! | `tension.I` | tendon I's tension (I from 1, file order); the tendon becomes tension-controlled | N |
//! | `tip_force.x\|y\|z` | a component of the tip force, world frame | N |
//! | `tip_moment.x\|y\|z` | a component of the tip moment, world frame | N m |
//! | `base_position.x\|y\|z` | a component of the base position, world frame | m |
//! | `distributed_force.x\|y\|z` | a component of the distributed force, made that constant along the whole rod (the other components keep their profile) | N/m |
//! | `load_scale` | a factor on every tension, pull-in and external load (1: the robot as given) | - |
//! | `youngs_modulus` | E of a rod built from its geometry, at fixed Poisson's ratio (G follows) | Pa |
//! | `displacement.I` | tendon I's actuator pull-in; the tendon becomes displacement-controlled | m |
//! | `routing.I.x\|y` | the body-frame offset x or y of tendon I's straight routing | m |
//! | `friction.I` | tendon I's friction coefficient mu in its channels, its motion kept (`pull` when it had none) | - |
//!
//! ```
//! use tdcr::Parameter;
//! let mut robot = tdcr::cases::prototype();
//! let p: Parameter = "tension.5".parse().unwrap();
//! p.apply(&mut robot, 4.91).unwrap();
//! assert_eq!(robot.tendons[4].tension(), 4.91);
//! assert_eq!(p.to_string(), "tension.5");
//! ```

use super::loads::Field;
use super::robot::Robot;
use super::rod::Rod;
use super::routing::Routing;
use super::tendon::Actuation;
use crate::error::{Result, invalid};
use nalgebra::Vector3;
use std::fmt;
use std::str::FromStr;

/// A scalar input of a robot (module docs for the names and their meaning).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// The tension (N) of tendon i (index from 0; named `tension.{i + 1}`). Setting it makes
    /// the tendon tension-controlled.
    Tension(usize),
    /// Component 0, 1, 2 (x, y, z) of the tip force (N, world frame).
    TipForce(usize),
    /// Component of the tip moment (N m, world frame).
    TipMoment(usize),
    /// Component of the base position (m, world frame).
    BasePosition(usize),
    /// Component of the distributed force f_e (N/m, world frame), set to the same value at
    /// every s; the other components keep their profile along the rod.
    DistributedForce(usize),
    /// A factor on every tension, actuator pull-in and external load (1 is the robot as
    /// given, 0 the unloaded robot), the load path's parameter.
    LoadScale,
    /// Young's modulus E (Pa) of a rod built from its geometry, at fixed Poisson's ratio
    /// (G follows).
    YoungsModulus,
    /// The actuator pull-in q (m) of tendon i (index from 0; named `displacement.{i + 1}`).
    /// Setting it makes the tendon displacement-controlled (its tension is solved for).
    Displacement(usize),
    /// Component 0 or 1 (x, y) of the body-frame offset (m) of tendon i's straight routing
    /// (named `routing.{i + 1}.x|y`).
    RoutingOffset(usize, usize),
    /// The friction coefficient mu of tendon i in its channels (index from 0; named
    /// `friction.{i + 1}`). Setting it keeps the tendon's motion (`pull` when it had no
    /// friction).
    Friction(usize),
}

/// The names [`Parameter`] accepts, for messages.
pub const NAMES: &str = "tension.I (I = 1, 2, ...), tip_force.x|y|z, tip_moment.x|y|z, base_position.x|y|z, \
                         distributed_force.x|y|z, load_scale, youngs_modulus, displacement.I, routing.I.x|y, \
                         friction.I";

const AXES: [&str; 3] = ["x", "y", "z"];

/// The name of component `k` (`x`, `y`, `z`; `?` past z).
fn axis(k: usize) -> &'static str {
    AXES.get(k).copied().unwrap_or("?")
}

impl FromStr for Parameter {
    type Err = String;

    /// Parses a name such as `tension.2` or `tip_force.z`, whatever the robot; the error
    /// says which names exist. [`Parameter::parse`] also checks the name against a robot.
    fn from_str(name: &str) -> std::result::Result<Self, String> {
        let unknown = || format!("unknown parameter `{name}`; the parameters are {NAMES}");
        match name {
            "youngs_modulus" => return Ok(Parameter::YoungsModulus),
            "load_scale" => return Ok(Parameter::LoadScale),
            _ => {}
        }
        let (head, tail) = name.split_once('.').ok_or_else(unknown)?;
        let axis = || AXES.iter().position(|a| *a == tail).ok_or_else(unknown);
        // Canonical numbers only (`tension.01` and `tension.+1` are not names).
        let tendon = |number: &str| match number.parse::<usize>() {
            Ok(i) if i >= 1 && number == i.to_string() => Ok(i - 1),
            _ => Err(format!(
                "parameter `{name}`: the tendon number must be a whole number from 1 (file order)"
            )),
        };
        match head {
            "tension" => Ok(Parameter::Tension(tendon(tail)?)),
            "displacement" => Ok(Parameter::Displacement(tendon(tail)?)),
            "friction" => Ok(Parameter::Friction(tendon(tail)?)),
            "routing" => {
                let (number, component) = tail.split_once('.').ok_or_else(unknown)?;
                let axis = AXES[..2].iter().position(|a| *a == component).ok_or_else(unknown)?;
                Ok(Parameter::RoutingOffset(tendon(number)?, axis))
            }
            "tip_force" => Ok(Parameter::TipForce(axis()?)),
            "tip_moment" => Ok(Parameter::TipMoment(axis()?)),
            "base_position" => Ok(Parameter::BasePosition(axis()?)),
            "distributed_force" => Ok(Parameter::DistributedForce(axis()?)),
            _ => Err(unknown()),
        }
    }
}

impl fmt::Display for Parameter {
    /// The parameter's name, as [`Parameter::from_str`] reads it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Parameter::Tension(i) => write!(f, "tension.{}", i + 1),
            Parameter::TipForce(k) => write!(f, "tip_force.{}", axis(k)),
            Parameter::TipMoment(k) => write!(f, "tip_moment.{}", axis(k)),
            Parameter::BasePosition(k) => write!(f, "base_position.{}", axis(k)),
            Parameter::DistributedForce(k) => write!(f, "distributed_force.{}", axis(k)),
            Parameter::LoadScale => f.write_str("load_scale"),
            Parameter::YoungsModulus => f.write_str("youngs_modulus"),
            Parameter::Displacement(i) => write!(f, "displacement.{}", i + 1),
            Parameter::RoutingOffset(i, k) => write!(f, "routing.{}.{}", i + 1, axis(k)),
            Parameter::Friction(i) => write!(f, "friction.{}", i + 1),
        }
    }
}

impl Parameter {
    /// Parses a name ([`Parameter::from_str`]) and checks that `robot` has it
    /// ([`Parameter::check`]).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the text and the accepted names, a tendon
    /// number past the robot's tendons, or `youngs_modulus` on a rod without geometry.
    pub fn parse(text: &str, robot: &Robot) -> Result<Self> {
        let p: Parameter = text.parse().map_err(|e: String| {
            // An unknown name's message lists the names already (said once, not twice).
            let hint = if e.contains(NAMES) {
                "check the name's spelling against them".to_string()
            } else {
                format!("name one of {NAMES}")
            };
            invalid("parameter", e, hint)
        })?;
        p.check(robot)?;
        Ok(p)
    }

    /// Checks that `robot` has this parameter: the tendon exists, the component is x, y or
    /// z, the rod has a geometry for `youngs_modulus`. Its value's range is checked by
    /// [`Robot::validate`].
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the parameter and what to do.
    pub fn check(&self, robot: &Robot) -> Result<()> {
        let count = robot.tendons.len();
        match *self {
            Parameter::Tension(i)
            | Parameter::Displacement(i)
            | Parameter::RoutingOffset(i, _)
            | Parameter::Friction(i)
                if i >= count =>
            {
                Err(invalid(
                    self.to_string(),
                    format!("names tendon {}, but the robot has {count} tendon(s)", i + 1),
                    format!("number the tendons from 1 to {count} in file order"),
                ))
            }
            Parameter::TipForce(k)
            | Parameter::TipMoment(k)
            | Parameter::BasePosition(k)
            | Parameter::DistributedForce(k)
                if k > 2 =>
            {
                Err(invalid(
                    self.to_string(),
                    "names a component past z",
                    "use the components x, y, z (0, 1, 2)",
                ))
            }
            Parameter::RoutingOffset(_, k) if k > 1 => Err(invalid(
                self.to_string(),
                "names a component past y (a routing offset lies in the cross-section)",
                "use the components x, y (0, 1)",
            )),
            Parameter::RoutingOffset(i, _) if !matches!(robot.tendons[i].routing, Routing::Straight { .. }) => {
                Err(invalid(
                    self.to_string(),
                    format!("names tendon {}, whose routing is not straight", i + 1),
                    "give routing offsets of straight routings only (kind = \"straight\")",
                ))
            }
            Parameter::YoungsModulus if robot.rod.geometry.is_none() => Err(invalid(
                "youngs_modulus",
                "cannot be set: the rod was not built from its geometry and Poisson's ratio",
                "give the rod by `outer_radius`, `youngs_modulus` and `poisson_ratio`",
            )),
            _ => Ok(()),
        }
    }

    /// Its value in `robot` (the distributed force at s = 0; 1 for the load scale).
    ///
    /// # Errors
    /// As [`Parameter::check`].
    pub fn value(&self, robot: &Robot) -> Result<f64> {
        self.check(robot)?;
        Ok(match *self {
            Parameter::Tension(i) => robot.tendons[i].tension(),
            Parameter::TipForce(c) => robot.loads.tip_force[c],
            Parameter::TipMoment(c) => robot.loads.tip_moment[c],
            Parameter::BasePosition(c) => robot.base_position[c],
            Parameter::DistributedForce(c) => robot.loads.distributed_force.at(0.0)[c],
            Parameter::LoadScale => 1.0,
            Parameter::YoungsModulus => robot.rod.geometry.map_or(f64::NAN, |g| g.youngs_modulus),
            Parameter::Displacement(i) => robot.tendons[i].displacement().ok_or_else(|| {
                invalid(
                    self.to_string(),
                    format!("has no value: tendon {} is tension-controlled", i + 1),
                    format!("give tendon {} a displacement (pull-in) first", i + 1),
                )
            })?,
            Parameter::RoutingOffset(i, k) => match robot.tendons[i].routing {
                Routing::Straight { x, y } => [x, y][k],
                _ => f64::NAN,
            },
            Parameter::Friction(i) => robot.tendons[i].friction.map_or(0.0, |f| f.coefficient),
        })
    }

    /// Sets this parameter of `robot` to `value` (module docs): a tension makes its tendon
    /// tension-controlled; a distributed force component becomes `value` at every s; a load
    /// scale multiplies every tension, pull-in and load; E rebuilds the rod's section from
    /// its geometry, keeping its reference strains. Only the value's place is checked here
    /// ([`Parameter::check`]); its range is checked by [`Robot::validate`].
    ///
    /// # Errors
    /// As [`Parameter::check`].
    pub fn apply(&self, robot: &mut Robot, value: f64) -> Result<()> {
        self.check(robot)?;
        match *self {
            Parameter::Tension(i) => {
                robot.tendons[i].set_tension(value);
            }
            Parameter::TipForce(c) => robot.loads.tip_force[c] = value,
            Parameter::TipMoment(c) => robot.loads.tip_moment[c] = value,
            Parameter::BasePosition(c) => robot.base_position[c] = value,
            Parameter::DistributedForce(c) => {
                let field = &mut robot.loads.distributed_force;
                *field = match field {
                    Field::Constant(f) => Field::Constant(with_component(*f, c, value)),
                    Field::Varying(g) => {
                        let g = g.clone();
                        Field::Varying(std::sync::Arc::new(move |s| with_component(g(s), c, value)))
                    }
                };
            }
            Parameter::LoadScale => scale_loads(robot, value),
            Parameter::Displacement(i) => robot.tendons[i].set_displacement(value),
            Parameter::RoutingOffset(i, k) => {
                if let Routing::Straight { x, y } = &mut robot.tendons[i].routing {
                    *(if k == 0 { x } else { y }) = value;
                }
            }
            Parameter::Friction(i) => {
                let t = &mut robot.tendons[i];
                let motion = t.friction.map_or(super::tendon::Motion::Pull, |f| f.motion);
                t.friction = Some(super::tendon::Friction {
                    coefficient: value,
                    motion,
                });
            }
            Parameter::YoungsModulus => {
                if let Some(g) = robot.rod.geometry {
                    let reference = robot.rod.reference.clone();
                    robot.rod = Rod::tube(robot.rod.length, g.outer_radius, g.inner_radius, value, g.poisson_ratio);
                    robot.rod.reference = reference;
                }
            }
        }
        Ok(())
    }

    /// Sets every `(parameter, value)` of `values` on `robot` ([`Parameter::apply`]) with
    /// `load_scale` last, whatever its place: a scale applies to the robot the other values
    /// describe. A batch row, a sweep step and Python's `with_parameters` all set their values
    /// this way.
    ///
    /// # Errors
    /// As [`Parameter::check`], for the first parameter that fails.
    pub fn apply_all(robot: &mut Robot, values: impl IntoIterator<Item = (Parameter, f64)>) -> Result<()> {
        let (scales, others): (Vec<_>, Vec<_>) = values.into_iter().partition(|(p, _)| *p == Parameter::LoadScale);
        for (p, value) in others.into_iter().chain(scales) {
            p.apply(robot, value)?;
        }
        Ok(())
    }

    /// A copy of `robot` with this parameter set to `value` ([`Parameter::apply`]).
    ///
    /// # Errors
    /// As [`Parameter::check`].
    pub fn applied(&self, robot: &Robot, value: f64) -> Result<Robot> {
        let mut out = robot.clone();
        self.apply(&mut out, value)?;
        Ok(out)
    }

    /// The label of an axis of this parameter's values: its name with its unit in
    /// parentheses, `tension.1 (N)`, or the name alone without a unit (`load_scale`).
    pub fn axis_label(&self) -> String {
        axis_label(&self.to_string(), self.unit())
    }

    /// Its unit: N, N m, m, N/m, Pa or none.
    pub fn unit(&self) -> &'static str {
        match self {
            Parameter::Tension(_) | Parameter::TipForce(_) => "N",
            Parameter::TipMoment(_) => "N m",
            Parameter::BasePosition(_) | Parameter::Displacement(_) | Parameter::RoutingOffset(..) => "m",
            Parameter::DistributedForce(_) => "N/m",
            Parameter::LoadScale | Parameter::Friction(_) => "",
            Parameter::YoungsModulus => "Pa",
        }
    }

    /// `f` with component `c` replaced by `value` when this is the distributed force's
    /// component c, else `f`: how a trace sets the parameter on the model's sites, the same
    /// meaning [`Parameter::apply`] gives it on the robot.
    pub(crate) fn distributed_force(&self, f: Vector3<f64>, value: f64) -> Vector3<f64> {
        match *self {
            Parameter::DistributedForce(c) => with_component(f, c, value),
            _ => f,
        }
    }
}

/// `name (unit)`, or `name` alone for an empty unit: the label of an axis of an input's
/// values ([`Parameter::axis_label`], [`crate::analysis::sweep::Input::axis_label`]).
pub(crate) fn axis_label(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    }
}

/// `v` with component `c` (0, 1, 2) set to `value`.
fn with_component(mut v: Vector3<f64>, c: usize, value: f64) -> Vector3<f64> {
    v[c] = value;
    v
}

/// Multiplies every tension, pull-in and external load of `robot` by `factor`.
fn scale_loads(robot: &mut Robot, factor: f64) {
    for t in &mut robot.tendons {
        t.actuation = match t.actuation {
            Actuation::Tension(tension) => Actuation::Tension(tension * factor),
            Actuation::PullIn { displacement, start } => Actuation::PullIn {
                displacement: displacement * factor,
                start: start.map(|tau| tau * factor),
            },
        };
    }
    let loads = &mut robot.loads;
    let scale = |f: &Field| match f {
        Field::Constant(v) => Field::Constant(v * factor),
        Field::Varying(g) => {
            let g = g.clone();
            Field::Varying(std::sync::Arc::new(move |s| g(s) * factor))
        }
    };
    loads.distributed_force = scale(&loads.distributed_force);
    loads.distributed_moment = scale(&loads.distributed_moment);
    loads.follower_distributed_force = scale(&loads.follower_distributed_force);
    loads.follower_tip_force *= factor;
    loads.follower_tip_moment *= factor;
    loads.tip_force *= factor;
    loads.tip_moment *= factor;
    for p in &mut loads.point {
        p.force *= factor;
        p.moment *= factor;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::equations::{Model, Which};

    /// An axis is labelled with the name and the unit, the name alone without one; a sweep's
    /// pull-in as the parameter of the same name.
    #[test]
    fn axis_labels_carry_the_unit() {
        assert_eq!(Parameter::Tension(0).axis_label(), "tension.1 (N)");
        assert_eq!(Parameter::TipMoment(2).axis_label(), "tip_moment.z (N m)");
        assert_eq!(Parameter::LoadScale.axis_label(), "load_scale");
        let pull_in = crate::analysis::sweep::Input::Displacement(1);
        assert_eq!(pull_in.axis_label(), "displacement.2 (m)");
        assert_eq!(pull_in.axis_label(), Parameter::Displacement(1).axis_label());
    }

    /// Every name round-trips; bad names list the good ones.
    #[test]
    fn names_round_trip_and_bad_names_list_the_good_ones() {
        for name in [
            "tension.1",
            "tension.12",
            "tip_force.z",
            "tip_moment.x",
            "base_position.y",
            "distributed_force.x",
            "load_scale",
            "youngs_modulus",
            "displacement.3",
            "routing.2.y",
            "friction.4",
        ] {
            assert_eq!(name.parse::<Parameter>().unwrap().to_string(), name);
        }
        for bad in [
            "tension.0",
            "tension.x",
            "tension.01",
            "tension.+1",
            "tip_force.w",
            "mass",
            "tip_force",
            "displacement.0",
            "routing.1.z",
            "routing.1",
            "friction.0",
            "friction",
        ] {
            let e = bad.parse::<Parameter>().unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
        assert!("mass".parse::<Parameter>().unwrap_err().contains(NAMES));
        let robot = crate::cases::case_s();
        for bad in ["tension.0", "tension.6", "tip_force.w", "speed", "tip_force"] {
            let e = Parameter::parse(bad, &robot).unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
            // A name that does not parse gets the list of names once (user25:
            // `--jacobian=foo` printed it twice); tension.6 parses, and the robot refuses it.
            let lists = if bad == "tension.6" { 0 } else { 1 };
            assert_eq!(e.matches(NAMES).count(), lists, "{e}");
        }
    }

    /// Apply sets the field (read back by value); a tension makes a displacement-controlled
    /// tendon tension-controlled; the load scale scales tensions, pull-ins and loads.
    #[test]
    fn apply_sets_the_field_and_value_reads_it() {
        let mut robot = crate::cases::case_s();
        robot.tendons[1].set_displacement(0.002);
        for text in [
            "tension.1",
            "tension.2",
            "tip_force.z",
            "tip_moment.y",
            "base_position.x",
            "distributed_force.x",
            "youngs_modulus",
            "displacement.2",
            "displacement.3",
            "routing.1.x",
            "routing.4.y",
            "friction.1",
        ] {
            let p: Parameter = text.parse().unwrap();
            let value = if p == Parameter::YoungsModulus { 105e9 } else { 0.25 };
            assert_eq!(p.value(&p.applied(&robot, value).unwrap()).unwrap(), value, "{p}");
        }
        let held = Parameter::Tension(1).applied(&robot, 1.5).unwrap();
        assert_eq!((held.tendons[1].tension(), held.tendons[1].displacement()), (1.5, None));
        let half = Parameter::LoadScale.applied(&robot, 0.5).unwrap();
        assert_eq!(half.tendons[0].tension(), 0.5 * robot.tendons[0].tension());
        assert_eq!(half.tendons[1].displacement(), Some(0.001));
        assert_eq!(half.loads.tip_force, 0.5 * robot.loads.tip_force);
        let soft = Parameter::YoungsModulus.applied(&robot, 105e9).unwrap();
        let (a, b) = (soft.rod.section_at(0.0).section, robot.rod.section_at(0.0).section);
        // Half of E halves every stiffness (G follows at fixed nu); 1e-12: rounding of the
        // section formulas.
        assert!((a.kbt - 0.5 * b.kbt).norm() < 1e-12 * b.kbt.norm());
        let e = Parameter::Tension(5).apply(&mut robot, 1.0).unwrap_err();
        assert!(
            e.to_string().contains("names tendon 6, but the robot has 5 tendon(s)"),
            "{e}"
        );
        // Payloads no name parses to are errors, not panics.
        let e = Parameter::TipForce(3).apply(&mut robot, 1.0).unwrap_err();
        assert!(e.to_string().contains("`tip_force.?` names a component past z"), "{e}");
        let pulled = Parameter::Displacement(2).applied(&robot, 0.003).unwrap();
        assert_eq!(pulled.tendons[2].displacement(), Some(0.003));
        let e = Parameter::Displacement(0).value(&robot).unwrap_err().to_string();
        assert!(e.contains("tendon 1 is tension-controlled"), "{e}");
        let mut helix = robot.clone();
        helix.tendons[0].routing = Routing::helical(0.008, 1.0, 0.0);
        let e = Parameter::RoutingOffset(0, 0)
            .apply(&mut helix, 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("routing is not straight"), "{e}");
        let mut stiff = robot.clone();
        stiff.rod = Rod::new(robot.length(), robot.rod.section_at(0.0).section);
        assert!(Parameter::YoungsModulus.apply(&mut stiff, 1e9).is_err());
    }

    /// A parameter set on the model (as a trace sets it) and the same parameter set on the
    /// robot (as a sweep, a batch row or Python set it) give the same physics, bitwise: the
    /// sites, the tendons' tensions, the point wrenches and the base, also with a distributed
    /// force that varies along the rod and a displacement-controlled tendon.
    #[test]
    fn model_and_robot_settings_agree_on_every_parameter() {
        let mut robot = crate::cases::case_s();
        robot.loads.distributed_force = Field::Varying(std::sync::Arc::new(|s| Vector3::new(0.1 * s, -0.2, -1.0 - s)));
        robot.tendons[2].set_displacement(0.001);
        let length = robot.length();
        let every = [
            Parameter::Tension(0),
            Parameter::Tension(2),
            Parameter::TipForce(0),
            Parameter::TipForce(2),
            Parameter::TipMoment(1),
            Parameter::BasePosition(2),
            Parameter::DistributedForce(0),
            Parameter::DistributedForce(2),
            Parameter::LoadScale,
        ];
        for p in every {
            let value = 0.37;
            let set = p.applied(&robot, value).unwrap();
            let on_robot = Model::new(&set);
            let mut on_model = Model::new(&robot);
            on_model.set(p, value);
            for s in [0.0, 0.3 * length, length] {
                let (a, b) = (on_robot.site(s), on_model.site(s));
                assert_eq!((a.f_e, a.l_e), (b.f_e, b.l_e), "{p} at s = {s}");
                let tensions = |m: &Model| {
                    m.tendons(s, Which::ActiveTo(s))
                        .map(|(i, t, _)| (i, t))
                        .collect::<Vec<_>>()
                };
                assert_eq!(tensions(&on_robot), tensions(&on_model), "{p} at s = {s}");
                assert_eq!(on_robot.point_wrench(s), on_model.point_wrench(s), "{p} at s = {s}");
            }
            assert_eq!(on_robot.base_position(), on_model.base_position(), "{p}");
        }
    }
}
