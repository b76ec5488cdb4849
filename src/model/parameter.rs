//! A scalar input of a robot that a trace or a sweep varies: one tendon's tension, a
//! component of the tip force or of a uniform distributed force, or a scale on every load.

use super::loads::Field;
use super::robot::Robot;
use crate::error::{Result, invalid};
use std::fmt;

/// A scalar input of a robot, named in text as `tension.I` (I from 1), `tip_force.x|y|z`,
/// `distributed_force.x|y|z`, `load_scale` or `youngs_modulus`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// The tension of tendon i (index from 0), N.
    Tension(usize),
    /// Component (0, 1, 2 for x, y, z) of the tip force, N, world frame.
    TipForce(usize),
    /// Component of the distributed force f_e, N/m, world frame, made uniform.
    DistributedForce(usize),
    /// A factor on every tension, actuator pull-in and external load (1 is the robot as
    /// given), the load path's parameter.
    LoadScale,
    /// Young's modulus E (Pa) of a rod built from its geometry, at fixed Poisson's ratio
    /// (G follows). Sweeps only: a trace varies tensions and loads.
    YoungsModulus,
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl Parameter {
    /// Parses `tension.1`, `tip_force.z`, `distributed_force.z` or `load_scale` for `robot`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the text and the accepted forms, or a tendon
    /// number past the robot's tendons.
    pub fn parse(text: &str, robot: &Robot) -> Result<Self> {
        let accepted = "tension.I (I from 1), tip_force.x|y|z, distributed_force.x|y|z, load_scale or youngs_modulus";
        let bad = |problem: String| invalid("parameter", problem, format!("name one of {accepted}"));
        if text == "load_scale" {
            return Ok(Parameter::LoadScale);
        }
        if text == "youngs_modulus" {
            return match robot.rod.geometry {
                Some(_) => Ok(Parameter::YoungsModulus),
                None => Err(invalid(
                    "parameter",
                    "`youngs_modulus`: the rod's stiffness is given directly, not built from a radius and E",
                    "give the rod by outer_radius, youngs_modulus and poisson_ratio to vary E",
                )),
            };
        }
        let Some((name, part)) = text.split_once('.') else {
            return Err(bad(format!("`{text}` is not a parameter")));
        };
        let axis = || {
            AXES.iter()
                .position(|a| *a == part)
                .ok_or_else(|| bad(format!("`{text}`: `{part}` is not an axis x, y or z")))
        };
        match name {
            "tension" => {
                let count = robot.tendons.len();
                match part.parse::<usize>() {
                    Ok(i) if (1..=count).contains(&i) => Ok(Parameter::Tension(i - 1)),
                    _ => Err(invalid(
                        "parameter",
                        format!("`{text}`: the robot has {count} tendon(s), numbered 1 to {count} in file order"),
                        "name a tendon by its number, e.g. tension.1",
                    )),
                }
            }
            "tip_force" => Ok(Parameter::TipForce(axis()?)),
            "distributed_force" => Ok(Parameter::DistributedForce(axis()?)),
            _ => Err(bad(format!("`{text}` is not a parameter"))),
        }
    }

    /// Its value in `robot` (the distributed force at s = 0).
    pub fn value(&self, robot: &Robot) -> f64 {
        match *self {
            Parameter::Tension(i) => robot.tendons[i].tension,
            Parameter::TipForce(c) => robot.loads.tip_force[c],
            Parameter::DistributedForce(c) => robot.loads.distributed_force.at(0.0)[c],
            Parameter::LoadScale => 1.0,
            Parameter::YoungsModulus => robot.rod.geometry.map_or(f64::NAN, |g| g.youngs_modulus),
        }
    }

    /// `robot` with this parameter set to `value` (a tension makes its tendon
    /// tension-controlled, as `--tension` does; a distributed force becomes uniform, with its
    /// value at s = 0 in the other components; a load scale multiplies every tension,
    /// pull-in and load, so that 0 is the unloaded robot; E rebuilds a uniform rod's section from its geometry, and leaves a
    /// rod without geometry as it is, which [`Parameter::parse`] does not accept).
    pub fn apply(&self, robot: &Robot, value: f64) -> Robot {
        let mut out = robot.clone();
        match *self {
            Parameter::Tension(i) => {
                // As `--tension`: the tendon becomes tension-controlled.
                out.tendons[i].tension = value;
                out.tendons[i].displacement = None;
            }
            Parameter::TipForce(c) => out.loads.tip_force[c] = value,
            Parameter::DistributedForce(c) => {
                let mut f = out.loads.distributed_force.at(0.0);
                f[c] = value;
                out.loads.distributed_force = Field::Constant(f);
            }
            Parameter::LoadScale => {
                for t in &mut out.tendons {
                    t.tension *= value;
                    t.displacement = t.displacement.map(|q| q * value);
                }
                let loads = &mut out.loads;
                let scale = |f: &Field| match f {
                    Field::Constant(v) => Field::Constant(v * value),
                    Field::Varying(g) => {
                        let g = g.clone();
                        Field::Varying(std::sync::Arc::new(move |s| g(s) * value))
                    }
                };
                loads.distributed_force = scale(&loads.distributed_force);
                loads.distributed_moment = scale(&loads.distributed_moment);
                loads.tip_force *= value;
                loads.tip_moment *= value;
                for p in &mut loads.point {
                    p.force *= value;
                    p.moment *= value;
                }
            }
            Parameter::YoungsModulus => {
                if let Some(g) = out.rod.geometry.as_mut() {
                    g.youngs_modulus = value;
                    let shear = super::rod::shear_modulus(value, g.poisson_ratio);
                    out.rod.stiffness = super::rod::Stiffness::Uniform(super::rod::Section::tube(
                        g.outer_radius,
                        g.inner_radius,
                        value,
                        shear,
                    ));
                }
            }
        }
        out
    }

    /// Its unit: N, N/m or none.
    pub fn unit(&self) -> &'static str {
        match self {
            Parameter::Tension(_) | Parameter::TipForce(_) => "N",
            Parameter::DistributedForce(_) => "N/m",
            Parameter::LoadScale => "",
            Parameter::YoungsModulus => "Pa",
        }
    }
}

impl fmt::Display for Parameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Parameter::Tension(i) => write!(f, "tension.{}", i + 1),
            Parameter::TipForce(c) => write!(f, "tip_force.{}", AXES[c]),
            Parameter::DistributedForce(c) => write!(f, "distributed_force.{}", AXES[c]),
            Parameter::LoadScale => f.write_str("load_scale"),
            Parameter::YoungsModulus => f.write_str("youngs_modulus"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_applies_and_prints_every_form() {
        let robot = crate::cases::case_s();
        for text in [
            "tension.1",
            "tension.5",
            "tip_force.z",
            "distributed_force.x",
            "load_scale",
        ] {
            let p = Parameter::parse(text, &robot).unwrap();
            assert_eq!(p.to_string(), text);
            if p != Parameter::LoadScale {
                assert_eq!(p.value(&p.apply(&robot, 0.25)), 0.25);
            }
            if p == Parameter::YoungsModulus {
                let soft = p.apply(&robot, 105e9);
                // Half of E halves every stiffness (G follows at fixed nu).
                let (a, b) = (soft.rod.section_at(0.0).section, robot.rod.section_at(0.0).section);
                assert!((a.kbt - 0.5 * b.kbt).norm() < 1e-12 * b.kbt.norm());
            }
        }
        let half = Parameter::LoadScale.apply(&robot, 0.5);
        assert_eq!(half.tendons[0].tension, 0.5 * robot.tendons[0].tension);
        let mut pulled = robot.clone();
        pulled.tendons[1].displacement = Some(0.002);
        assert_eq!(
            Parameter::LoadScale.apply(&pulled, 0.5).tendons[1].displacement,
            Some(0.001)
        );
        let held = Parameter::Tension(1).apply(&pulled, 1.5);
        assert_eq!((held.tendons[1].tension, held.tendons[1].displacement), (1.5, None));
        assert_eq!(half.loads.tip_force, 0.5 * robot.loads.tip_force);
        for bad in ["tension.0", "tension.6", "tip_force.w", "speed", "tip_force"] {
            let e = Parameter::parse(bad, &robot).unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
        }
    }
}
