//! A sweep: robots solved in order, each warm-started from the solution of the one before,
//! with the events between steps that a reader of the results should not miss: the tip
//! jumping off the branch it was on (a snap-through at a fold, or a jump to another branch of
//! equilibria), and displacement-controlled tendons going taut or slack (docs/stability.md,
//! "Tracing a branch"). `tdcr sweep` and Python's `tdcr.sweep` both run it.
//!
//! Every collocation step is [`collocation::solve_from`] the previous step's solution, with a
//! fresh Newton workspace: its first Newton iteration evaluates the Jacobian at the warm
//! start, so its stability verdict belongs to the Jacobian of the step's own last Newton
//! step, never to an earlier step's. Shooting steps start cold (shooting takes no warm
//! start).

use crate::collocation;
use crate::error::{Error, Result};
use crate::model::robot::Robot;
use crate::report::PathTaken;
use crate::shooting;
use crate::solution::Solution;
use nalgebra::Vector3;
use std::fmt;

/// A step that moves the tip more than this many times as far as the step before it left
/// the branch it was on, if it also moves it more than [`JUMP_SHARE`] of L: on a smooth
/// branch successive steps of an evenly spaced range move the tip by similar amounts.
const JUMP_RATIO: f64 = 4.0;
/// The least tip motion (share of L) of a jump by [`JUMP_RATIO`]: below 1 % of L a change of
/// pace is the branch's curvature, not a jump.
const JUMP_SHARE: f64 = 0.01;
/// A step that fell back to the load path from rest (no stable state was reachable from the
/// warm start) and moved the tip more than this share of L jumped, whatever the step before.
const PATHED_SHARE: f64 = 0.05;

/// The solver of every step of a sweep, with its options.
#[derive(Clone, Debug)]
pub enum SweepSolver {
    /// Collocation, each step warm-started from the last ([`collocation::solve_from`]).
    Collocation(collocation::Options),
    /// Shooting, each step from its own initial guess ([`shooting::solve`]).
    Shooting(shooting::Options),
}

/// A tendon that went taut or slack between two steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Engagement {
    /// The tendon (from 0).
    pub tendon: usize,
    /// True: it went taut (its solved tension is now positive); false: it went slack.
    pub taut: bool,
}

/// What happened between a step and the one before it.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// Displacement-controlled tendons went taut or slack: the tip's rate changes there
    /// because a tendon engages or lets go, which is not a jump.
    Tendons(Vec<Engagement>),
    /// The tip jumped by `distance` (m): it moved more than four times as far as in the step
    /// before (and more than 1 % of L), or the step fell back to the load path from rest and
    /// moved it more than 5 % of L. A snap-through at a fold, or a jump to another branch.
    Jump {
        /// How far the tip moved in this step (m).
        distance: f64,
    },
}

impl fmt::Display for Event {
    /// `tendon 1 taut; tendon 2 slack`, or `the tip jumps by 798.2 mm: a snap-through
    /// (fold) or another branch`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Tendons(changes) => {
                for (k, c) in changes.iter().enumerate() {
                    let state = if c.taut { "taut" } else { "slack" };
                    write!(f, "{}tendon {} {state}", if k > 0 { "; " } else { "" }, c.tendon + 1)?;
                }
                Ok(())
            }
            Event::Jump { distance } => write!(
                f,
                "the tip jumps by {:.1} mm: a snap-through (fold) or another branch",
                distance * 1e3
            ),
        }
    }
}

/// One solved step of a sweep.
#[derive(Clone, Debug)]
pub struct Step {
    /// The step's solution; its report holds the stability verdict and how the equilibrium
    /// was reached (`report.path`).
    pub solution: Solution,
    /// What happened since the step before, if anything.
    pub event: Option<Event>,
}

/// A sweep in progress: solves one robot after another ([`Sweep::step`]), each from the
/// last solution, and tells the events between them.
///
/// # Examples
/// ```
/// use tdcr::analysis::sweep::{Sweep, SweepSolver};
/// let mut sweep = Sweep::new(SweepSolver::Collocation(Default::default()), None);
/// for tension in [0.0, 1.0, 2.0] {
///     let mut robot = tdcr::cases::case_s();
///     robot.tendons[0].set_tension(tension);
///     let step = sweep.step(&robot).unwrap();
///     assert!(step.event.is_none());
/// }
/// ```
pub struct Sweep {
    solver: SweepSolver,
    /// The warm start of the next step: the last solution, or the sweep's start.
    last: Option<Solution>,
    /// The tip of the last step solved (m).
    tip: Option<Vector3<f64>>,
    /// How far the tip moved in the last step that moved it (m).
    moved: Option<f64>,
    /// Which displacement-controlled tendons (from 0) were taut at the last step.
    taut: Option<Vec<(usize, bool)>>,
}

impl Sweep {
    /// A sweep that solves with `solver`, its first step warm-started from `start` (a
    /// solution of a nearby robot; collocation only) if given.
    pub fn new(solver: SweepSolver, start: Option<Solution>) -> Self {
        Sweep {
            solver,
            last: start,
            tip: None,
            moved: None,
            taut: None,
        }
    }

    /// Solves the next step's `robot` from the last solution, and tells what happened
    /// since the step before.
    ///
    /// # Errors
    /// The solver's errors ([`collocation::solve`], [`shooting::solve`]); the sweep is then
    /// left as it was before the step.
    pub fn step(&mut self, robot: &Robot) -> Result<Step> {
        let solution = match (&self.solver, &self.last) {
            (SweepSolver::Collocation(options), None) => collocation::solve(robot, options)?,
            (SweepSolver::Collocation(options), Some(warm)) => collocation::solve_from(robot, options, warm)?,
            (SweepSolver::Shooting(options), _) => shooting::solve(robot, options)?,
        };
        let event = self.event(robot, &solution);
        self.last = Some(solution.clone());
        Ok(Step { solution, event })
    }

    /// The event of the step that solved `robot` as `solution`, and the state the next
    /// step compares with.
    fn event(&mut self, robot: &Robot, solution: &Solution) -> Option<Event> {
        let tip = solution.tip_position();
        let moved = self.tip.map(|t| (tip - t).norm());
        self.tip = Some(tip);
        // A displacement-controlled tendon that went taut (or slack) since the last step
        // changes how fast the tip moves: an event of its own, not a jump off the branch.
        let taut: Vec<(usize, bool)> = (0..robot.tendons.len())
            .filter(|&i| robot.tendons[i].displacement().is_some())
            .map(|i| (i, solution.tendons[i].tension > 0.0))
            .collect();
        let changes: Vec<Engagement> = match &self.taut {
            Some(before) => taut
                .iter()
                .zip(before)
                .filter(|(now, then)| now.1 != then.1)
                .map(|(now, _)| Engagement {
                    tendon: now.0,
                    taut: now.1,
                })
                .collect(),
            None => Vec::new(),
        };
        self.taut = Some(taut);
        let length = robot.length();
        let pathed = matches!(solution.report.path, PathTaken::LoadPath { .. });
        let jump = match (moved, self.moved) {
            (Some(m), Some(p)) => {
                (m > JUMP_RATIO * p && m > JUMP_SHARE * length) || (pathed && m > PATHED_SHARE * length)
            }
            (Some(m), None) => pathed && m > PATHED_SHARE * length,
            _ => false,
        };
        self.moved = moved.or(self.moved);
        if !changes.is_empty() {
            Some(Event::Tendons(changes))
        } else if jump {
            Some(Event::Jump {
                distance: moved.unwrap_or(0.0),
            })
        } else {
            None
        }
    }
}

/// The result of [`sweep`]: the steps solved, in order, and the failure that ended the
/// sweep early, if one did.
#[derive(Debug)]
pub struct SweepResult {
    /// The steps solved, up to the first failure.
    pub steps: Vec<Step>,
    /// The step (from 0) that failed and its error; `None` when every step solved.
    pub failure: Option<(usize, Error)>,
}

/// Solves `robots` in order with [`Sweep`], the first from `start` if given, stopping at the
/// first step that fails ([`SweepResult::failure`]).
pub fn sweep(robots: &[Robot], solver: SweepSolver, start: Option<Solution>) -> SweepResult {
    let mut sweep = Sweep::new(solver, start);
    let mut steps = Vec::with_capacity(robots.len());
    for (k, robot) in robots.iter().enumerate() {
        match sweep.step(robot) {
            Ok(step) => steps.push(step),
            Err(e) => {
                return SweepResult {
                    steps,
                    failure: Some((k, e)),
                };
            }
        }
    }
    SweepResult { steps, failure: None }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Field, Rod, Routing, Tendon};

    /// The prototype's tendon 1 driven by its pull-in: under the rod's weight it is slack up
    /// to about 2.06 mm (tests/cli.rs), so the third of 0, 2, 4, 6 mm finds it taut.
    #[test]
    fn a_tendon_going_taut_is_an_event_not_a_jump() {
        let mut base = crate::cases::case_s();
        base.tendons[0].set_displacement(0.0);
        let robots: Vec<Robot> = [0.0, 0.002, 0.004, 0.006]
            .iter()
            .map(|&q| {
                let mut r = base.clone();
                r.tendons[0].set_displacement(q);
                r
            })
            .collect();
        let out = sweep(&robots, SweepSolver::Collocation(Default::default()), None);
        assert!(out.failure.is_none());
        let events: Vec<Option<String>> = out
            .steps
            .iter()
            .map(|s| s.event.as_ref().map(|e| e.to_string()))
            .collect();
        let taut = Some("tendon 1 taut".to_string());
        assert_eq!(events, vec![None, None, taut, None], "{events:?}");
    }

    /// About twice Euler's load on a 0.5 m rod buckled towards -x by a 10 mN imperfection,
    /// a tendon on the +x side: at 1 N the robot ends bent towards +x (docs/stability.md),
    /// a jump of about 0.8 m that the sweep reports; the steps after it are quiet.
    #[test]
    fn a_snap_through_is_a_jump() {
        let mut base = Robot::new(Rod::tube(0.5, 0.001, 0.0, 200e9, 0.3))
            .with_tendon(Tendon::new(Routing::straight(0.015, 0.0), 0.0));
        base.loads.distributed_force = Field::Constant(Vector3::new(0.0, 0.0, -0.24));
        base.loads.tip_force = Vector3::new(-0.01, 0.0, -3.0);
        let robots: Vec<Robot> = [0.0, 1.0, 2.0]
            .iter()
            .map(|&t| {
                let mut r = base.clone();
                r.tendons[0].set_tension(t);
                r
            })
            .collect();
        let out = sweep(&robots, SweepSolver::Collocation(Default::default()), None);
        assert!(out.failure.is_none());
        let Some(Event::Jump { distance }) = out.steps[1].event else {
            panic!("{:?}", out.steps[1].event);
        };
        // 0.5 to 1 m: the tip crosses from about -x to +x on a 0.5 m rod.
        assert!((0.5..1.0).contains(&distance), "{distance}");
        assert!(out.steps[2].event.is_none());
    }

    /// Euler's column (the prototype's rod along +z, P_cr = pi^2 EI / (4 L^2) = 0.177893 N,
    /// docs/stability.md) loaded past P_cr in a sweep: the straight column that every step
    /// ends on is stable below P_cr and unstable (two directions) above, and each step's
    /// verdict says so, not the verdict of an earlier step's Jacobian.
    #[test]
    fn every_step_has_its_own_stability_verdict() {
        let p_cr = 0.177893;
        let base = Robot::new(Rod::tube(0.242, 0.0004, 0.0, 210e9, 0.3125));
        let robots: Vec<Robot> = [0.9, 0.95, 1.05, 1.1]
            .iter()
            .map(|&f| {
                let mut r = base.clone();
                r.loads.tip_force = Vector3::new(0.0, 0.0, -f * p_cr);
                r
            })
            .collect();
        let options = collocation::Options {
            equilibrium: collocation::Equilibrium::Nearest,
            ..Default::default()
        };
        let out = sweep(&robots, SweepSolver::Collocation(options), None);
        assert!(out.failure.is_none());
        let verdicts: Vec<&str> = out
            .steps
            .iter()
            .map(|s| s.solution.report.stability.verdict())
            .collect();
        assert_eq!(verdicts, ["stable", "stable", "unstable", "unstable"]);
    }
}
