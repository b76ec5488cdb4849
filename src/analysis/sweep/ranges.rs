//! The inputs a sweep varies and their values: step k's robot is the base robot with every
//! input at its k-th value, and between two steps the values are interpolated linearly, so
//! an event can be located between the steps ([`Ranges::robot`] at a fractional step).

use crate::error::{Result, invalid};
use crate::model::parameter::Parameter;
use crate::model::robot::Robot;
use std::fmt;

/// An input a sweep varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// A named input ([`Parameter`]: a tension, a load component, the load scale, E, ...).
    Parameter(Parameter),
    /// The actuator pull-in (m) of tendon i (from 0), which makes it displacement-controlled.
    Displacement(usize),
}

impl Input {
    /// Its unit: that of the parameter, or m for a pull-in.
    pub fn unit(&self) -> &'static str {
        match self {
            Input::Parameter(p) => p.unit(),
            Input::Displacement(_) => "m",
        }
    }

    /// The label of an axis of its values: `tension.1 (N)`, `displacement.2 (m)`, or the
    /// name alone without a unit (`load_scale`): the x axis of a history's hysteresis loop
    /// (`tdcr sweep --history --plot`, Python's `History.loop_x` and `tdcr.plot_history`).
    pub fn axis_label(&self) -> String {
        crate::model::parameter::axis_label(&self.to_string(), self.unit())
    }

    fn apply(&self, robot: &mut Robot, value: f64) -> Result<()> {
        match self {
            Input::Parameter(p) => p.apply(robot, value),
            Input::Displacement(i) => {
                robot.tendons[*i].set_displacement(value);
                Ok(())
            }
        }
    }
}

impl fmt::Display for Input {
    /// `tension.5`, `tip_force.z`, or `displacement.2` (tendon 2's pull-in).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Input::Parameter(p) => write!(f, "{p}"),
            Input::Displacement(i) => write!(f, "displacement.{}", i + 1),
        }
    }
}

/// The steps of a sweep: a base robot and the values of every input it varies, each input
/// with one value per step or one value for all.
#[derive(Clone, Debug)]
pub struct Ranges {
    base: Robot,
    inputs: Vec<(Input, Vec<f64>)>,
    steps: usize,
}

impl Ranges {
    /// The steps of `inputs` on `base`. The inputs are set in the order given, except the
    /// load scale, which is set last (it scales the others, [`Parameter::apply_all`]).
    ///
    /// # Errors
    /// No input with values, inputs with different numbers of values (other than one), a
    /// value that is not finite, or an input the robot does not have (a tendon past the last).
    pub fn new(base: Robot, inputs: Vec<(Input, Vec<f64>)>) -> Result<Self> {
        let steps = inputs.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
        if steps == 0 {
            return Err(invalid(
                "sweep ranges",
                "the sweep has no values",
                "give at least one input with one value per step",
            ));
        }
        for (input, values) in &inputs {
            if values.len() != 1 && values.len() != steps {
                return Err(invalid(
                    format!("{input}"),
                    format!("has {} values but another input has {steps}", values.len()),
                    "give every input one value per step (or one value for all steps)",
                ));
            }
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(invalid(
                    format!("{input}"),
                    format!("has the value {v}"),
                    "give finite values",
                ));
            }
            match input {
                Input::Parameter(p) => p.check(&base)?,
                Input::Displacement(i) if *i >= base.tendons.len() => {
                    let n = base.tendons.len();
                    return Err(invalid(
                        format!("{input}"),
                        format!("tendon {} does not exist: the robot has {n} tendon(s)", i + 1),
                        format!("number the tendons from 1 to {n}, in file order"),
                    ));
                }
                Input::Displacement(_) => {}
            }
        }
        let (mut inputs, scales): (Vec<_>, Vec<_>) = inputs
            .into_iter()
            .partition(|(i, _)| *i != Input::Parameter(Parameter::LoadScale));
        inputs.extend(scales);
        Ok(Ranges { base, inputs, steps })
    }

    /// The same inputs up, then back down: the steps in order and then in reverse without
    /// the last one again (values a, b, c become a, b, c, b, a), the loading and unloading
    /// branches of a history ([`crate::analysis::history`]).
    pub fn up_down(&self) -> Ranges {
        let inputs = self
            .inputs
            .iter()
            .map(|(input, values)| {
                let mut all = values.clone();
                if values.len() > 1 {
                    all.extend(values.iter().rev().skip(1));
                }
                (*input, all)
            })
            .collect();
        let steps = if self.steps > 1 { 2 * self.steps - 1 } else { 1 };
        Ranges {
            base: self.base.clone(),
            inputs,
            steps,
        }
    }

    /// The number of steps.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The inputs and their values, in the order they are set.
    pub fn inputs(&self) -> &[(Input, Vec<f64>)] {
        &self.inputs
    }

    /// The value of input `i` at step `t` (from 0; between steps k and k + 1 the values of
    /// both interpolated linearly, at a whole step exactly its value).
    pub fn value(&self, i: usize, t: f64) -> f64 {
        let v = &self.inputs[i].1;
        if v.len() == 1 {
            return v[0];
        }
        let k = (t.floor().max(0.0) as usize).min(v.len() - 2);
        let frac = t - k as f64;
        if frac == 0.0 {
            v[k]
        } else {
            v[k] + frac * (v[k + 1] - v[k])
        }
    }

    /// The first input whose values change along the sweep (the one an event's value is
    /// given in), with its index; `None` when every input is held.
    pub fn swept(&self) -> Option<(usize, Input)> {
        self.inputs
            .iter()
            .position(|(_, v)| v.iter().any(|x| *x != v[0]))
            .map(|i| (i, self.inputs[i].0))
    }

    /// The robot at step `t` (from 0, fractional between steps).
    ///
    /// # Errors
    /// An input that cannot be set ([`Parameter::apply`]: a negative tension).
    pub fn robot(&self, t: f64) -> Result<Robot> {
        let mut robot = self.base.clone();
        for (i, (input, _)) in self.inputs.iter().enumerate() {
            input.apply(&mut robot, self.value(i, t))?;
        }
        Ok(robot)
    }
}
