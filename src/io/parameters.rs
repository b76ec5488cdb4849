//! Named robot parameters, the column names of `tdcr batch` input files and the keys of the
//! Python package's parameter arrays: `tension.I` (tendon I from 1, N), `tip_force.x|y|z`
//! (N, world frame), `tip_moment.x|y|z` (N m, world frame), `base_position.x|y|z` (m, world
//! frame) and `youngs_modulus` (Pa; rods given by `poisson_ratio`, G follows E).
//!
//! ```
//! use tdcr::io::parameters::Parameter;
//! let mut robot = tdcr::cases::prototype();
//! let p: Parameter = "tension.5".parse().unwrap();
//! p.apply(&mut robot, 4.91).unwrap();
//! assert_eq!(robot.tendons[4].tension, 4.91);
//! assert_eq!(p.to_string(), "tension.5");
//! ```

use crate::error::{Result, invalid};
use crate::model::rod::Rod;
use crate::{Error, Robot};
use std::fmt;
use std::str::FromStr;

/// One named scalar of a robot that a batch may set per row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// Tension (N) of the tendon with this 1-based number (file order, as on the command line).
    Tension(usize),
    /// Component 0, 1, 2 (x, y, z) of the tip force (N, world frame).
    TipForce(usize),
    /// Component of the tip moment (N m, world frame).
    TipMoment(usize),
    /// Component of the base position (m, world frame).
    BasePosition(usize),
    /// Young's modulus E (Pa) of a rod built from its geometry and Poisson's ratio.
    YoungsModulus,
}

/// The names [`Parameter`] accepts, for messages.
pub const NAMES: &str =
    "tension.I (I = 1, 2, ...), tip_force.x|y|z, tip_moment.x|y|z, base_position.x|y|z, youngs_modulus";

const AXES: [&str; 3] = ["x", "y", "z"];

/// The name of component `k` (`x`, `y`, `z`; `?` past z).
fn axis(k: usize) -> &'static str {
    AXES.get(k).copied().unwrap_or("?")
}

impl FromStr for Parameter {
    type Err = String;

    /// Parses a name such as `tension.2` or `tip_force.z`; the error says which names exist.
    fn from_str(name: &str) -> std::result::Result<Self, String> {
        let unknown = || format!("unknown parameter `{name}`; the parameters are {NAMES}");
        if name == "youngs_modulus" {
            return Ok(Parameter::YoungsModulus);
        }
        let (head, tail) = name.split_once('.').ok_or_else(unknown)?;
        let axis = || AXES.iter().position(|a| *a == tail).ok_or_else(unknown);
        match head {
            "tension" => match tail.parse::<usize>() {
                Ok(i) if i >= 1 => Ok(Parameter::Tension(i)),
                _ => Err(format!(
                    "parameter `{name}`: the tendon number must be a whole number from 1 (file order)"
                )),
            },
            "tip_force" => Ok(Parameter::TipForce(axis()?)),
            "tip_moment" => Ok(Parameter::TipMoment(axis()?)),
            "base_position" => Ok(Parameter::BasePosition(axis()?)),
            _ => Err(unknown()),
        }
    }
}

impl fmt::Display for Parameter {
    /// The parameter's name, as [`Parameter::from_str`] reads it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Parameter::Tension(i) => write!(f, "tension.{i}"),
            Parameter::TipForce(k) => write!(f, "tip_force.{}", axis(*k)),
            Parameter::TipMoment(k) => write!(f, "tip_moment.{}", axis(*k)),
            Parameter::BasePosition(k) => write!(f, "base_position.{}", axis(*k)),
            Parameter::YoungsModulus => f.write_str("youngs_modulus"),
        }
    }
}

impl Parameter {
    /// Sets this parameter of `robot` to `value`. Only the value's place is checked here
    /// (the tendon exists, the rod has a geometry); its range is checked by the solvers'
    /// [`Robot::validate`].
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a tendon number past the last tendon, or `youngs_modulus`
    /// on a rod not built from geometry and Poisson's ratio.
    pub fn apply(&self, robot: &mut Robot, value: f64) -> Result<()> {
        let count = robot.tendons.len();
        let slot = match *self {
            Parameter::Tension(i) => i
                .checked_sub(1)
                .and_then(|k| robot.tendons.get_mut(k))
                .map(|t| &mut t.tension),
            Parameter::TipForce(k) => robot.loads.tip_force.get_mut(k),
            Parameter::TipMoment(k) => robot.loads.tip_moment.get_mut(k),
            Parameter::BasePosition(k) => robot.base_position.get_mut(k),
            Parameter::YoungsModulus => return set_youngs_modulus(robot, value),
        };
        match (slot, self) {
            (Some(x), _) => {
                *x = value;
                Ok(())
            }
            (None, Parameter::Tension(i)) => Err(invalid(
                self.to_string(),
                format!("names tendon {i}, but the robot has {count} tendon(s)"),
                format!("number the tendons from 1 to {count} in file order"),
            )),
            (None, _) => Err(invalid(
                self.to_string(),
                "names a component past z",
                "use the components x, y, z (0, 1, 2)",
            )),
        }
    }
}

/// Rebuilds the rod from its geometry with Young's modulus `e`, keeping its reference
/// strains.
fn set_youngs_modulus(robot: &mut Robot, e: f64) -> Result<(), Error> {
    let Some(g) = robot.rod.geometry else {
        return Err(invalid(
            "youngs_modulus",
            "cannot be set: the rod was not built from its geometry and Poisson's ratio",
            "give the rod by `outer_radius`, `youngs_modulus` and `poisson_ratio`",
        ));
    };
    let reference = robot.rod.reference.clone();
    robot.rod = Rod::tube(robot.rod.length, g.outer_radius, g.inner_radius, e, g.poisson_ratio);
    robot.rod.reference = reference;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_bad_names_list_the_good_ones() {
        for name in [
            "tension.1",
            "tension.12",
            "tip_force.z",
            "tip_moment.x",
            "base_position.y",
            "youngs_modulus",
        ] {
            assert_eq!(name.parse::<Parameter>().unwrap().to_string(), name);
        }
        for bad in ["tension.0", "tension.x", "tip_force.w", "mass", "tip_force"] {
            let e = bad.parse::<Parameter>().unwrap_err();
            assert!(e.contains(bad), "{e}");
        }
        assert!("mass".parse::<Parameter>().unwrap_err().contains(NAMES));
    }

    #[test]
    fn apply_sets_the_field_and_rejects_a_missing_tendon() {
        let mut robot = crate::cases::prototype();
        Parameter::TipForce(2).apply(&mut robot, -0.196).unwrap();
        assert_eq!(robot.loads.tip_force.z, -0.196);
        Parameter::YoungsModulus.apply(&mut robot, 230e9).unwrap();
        assert_eq!(robot.rod.geometry.unwrap().youngs_modulus, 230e9);
        let (a, b) = (
            robot.rod.section_at(0.0).section,
            Rod::solid_circle(0.242, 0.0004, 230e9, 0.3125).section_at(0.0).section,
        );
        // 1e-15: the same formulas; the compiler may fold powi of the constants differently
        // from the run-time powi (last bit).
        assert!((a.kbt - b.kbt).component_div(&b.kbt).amax() < 1e-15);
        assert!((a.kse - b.kse).component_div(&b.kse).amax() < 1e-15);
        let e = Parameter::Tension(6).apply(&mut robot, 1.0).unwrap_err();
        assert!(e.to_string().contains("has 5 tendon(s)"), "{e}");
        // Payloads no name parses to are errors, not panics.
        assert!(Parameter::Tension(0).apply(&mut robot, 1.0).is_err());
        let e = Parameter::TipForce(3).apply(&mut robot, 1.0).unwrap_err();
        assert!(e.to_string().contains("`tip_force.?` names a component past z"), "{e}");
    }
}
