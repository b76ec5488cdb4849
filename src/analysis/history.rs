//! A quasi-static load history with stick/slip friction (docs/friction.md section 8): the
//! steps of [`Ranges`] solved in order, each from the tendon state the step before left
//! (which material of every tendon with friction sits where, and how stretched), so that
//! each stretch of tendon slides in, slides out or sticks as Coulomb's law says. Pulling a
//! tendon and letting it back out then follows two different branches: the hysteresis loop.
//! `tdcr sweep --history` and Python's `tdcr.history` both run it.
//!
//! The first step starts from rest: the tendons installed unstretched on the unloaded rod.
//! All steps share one mesh, the one the default full-slip `pull` solve picks for the step
//! with the most tension on the tendons with friction, so that the material carried from
//! step to step sits on the same nodes.
//!
//! ```
//! use tdcr::analysis::history::{history, Contact};
//! use tdcr::analysis::sweep::{Input, Ranges};
//! use tdcr::{Friction, Parameter};
//! let mut robot = tdcr::cases::case_s();
//! robot.tendons[0].friction = Some(Friction::pull(0.1));
//! robot.tendons[0].stiffness = Some(2000.0);
//! let up = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), vec![0.0, 1.0, 2.0, 3.0, 4.0])]).unwrap();
//! let result = history(&up.up_down(), &Default::default()).unwrap();
//! assert!(result.failure.is_none());
//! // Letting the tendon out from 4 N to 3 N leaves part of it stuck.
//! let back = &result.steps[5];
//! assert!(back.zones[0].zones.iter().any(|z| z.contact == Contact::Stick));
//! ```

use super::sweep::{Input, Ranges};
use crate::collocation::{self, friction};
use crate::error::{Error, Result, invalid};
use crate::solution::Solution;

pub use crate::collocation::friction::Contact;

/// A stretch of a tendon with one contact during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zone {
    /// Where it starts (m, arc length of the backbone).
    pub start: f64,
    /// Where it ends (m).
    pub end: f64,
    /// How the tendon moves there during the step.
    pub contact: Contact,
}

/// The zones of one tendon with friction, from its base entry to its termination.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonZones {
    /// The tendon (index in the robot, from 0).
    pub tendon: usize,
    /// Its zones in order.
    pub zones: Vec<Zone>,
}

/// One solved step of a history.
#[derive(Clone, Debug)]
pub struct HistoryStep {
    /// The solution, with the tension along every tendon ([`Solution::tendon_tensions`]).
    pub solution: Solution,
    /// The stick/slip zones of each tendon with friction.
    pub zones: Vec<TendonZones>,
}

/// The result of [`history`]: the steps solved, in order, and the failure that ended the
/// history early, if one did.
#[derive(Debug)]
pub struct HistoryResult {
    /// The steps solved, up to the first failure.
    pub steps: Vec<HistoryStep>,
    /// The step (from 0) that failed and its error; `None` when every step solved.
    pub failure: Option<(usize, Error)>,
}

/// Solves the steps of `ranges` as a history with stick/slip friction (module docs), by
/// collocation with `options`, stopping at the first step that fails
/// ([`HistoryResult::failure`]). The friction coefficients are the tendons'; their
/// `motion` is not used (the history decides where each tendon slides, and which way).
///
/// # Errors
/// Before any step: invalid options or robots, no tendon with friction, or a pull-in input
/// (a history drives the tendons with friction by their tensions); the first step's
/// mesh-choosing solve failing.
pub fn history(ranges: &Ranges, options: &collocation::Options) -> Result<HistoryResult> {
    options.validate()?;
    if let Some((input, _)) = ranges
        .inputs()
        .iter()
        .find(|(i, _)| matches!(i, Input::Displacement(_)))
    {
        return Err(invalid(
            format!("{input}"),
            "a history drives the tendons by their tensions, not by pull-ins",
            "vary the tension of the tendon (tension.N) instead",
        ));
    }
    let robots = (0..ranges.steps())
        .map(|k| ranges.robot(k as f64))
        .collect::<Result<Vec<_>>>()?;
    for robot in &robots {
        robot.validate()?;
        if robot.has_displacement_inputs() {
            return Err(invalid(
                "tendons",
                "a history drives the tendons by their tensions, and this robot has a displacement-controlled tendon",
                "give every tendon a tension",
            ));
        }
    }
    if !crate::model::friction::any(&robots[0]) {
        return Err(invalid(
            "tendons",
            "no tendon has friction, so a history has nothing to carry from step to step",
            "give a tendon friction (robot file `friction = 0.1`, command line --friction I=MU), or run a plain sweep",
        ));
    }
    let mut carried = friction::history::start(&robots, options)?;
    let mut steps = Vec::with_capacity(robots.len());
    for (k, robot) in robots.iter().enumerate() {
        match friction::history::step(robot, options, &mut carried) {
            Ok((solution, zones)) => steps.push(HistoryStep {
                solution,
                zones: zones
                    .into_iter()
                    .map(|(tendon, list)| TendonZones {
                        tendon,
                        zones: list
                            .into_iter()
                            .map(|(start, end, contact)| Zone { start, end, contact })
                            .collect(),
                    })
                    .collect(),
            }),
            Err(e) => {
                return Ok(HistoryResult {
                    steps,
                    failure: Some((k, e)),
                });
            }
        }
    }
    Ok(HistoryResult { steps, failure: None })
}
