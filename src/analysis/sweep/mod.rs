//! A sweep: the steps of [`Ranges`] solved in order, each warm-started from the solution of
//! the one before, with the events between steps located where they happen: the tip
//! snapping off the branch it was on (at a fold), the stability changing without a jump (a
//! bifurcation), and displacement-controlled tendons going taut or slack (docs/stability.md,
//! "Tracing a branch"). `tdcr sweep` and Python's `tdcr.sweep` both run it.
//!
//! A collocation step after a stable one first continues that branch: `solve_on_branch`
//! from the previous solution, in 1, 2 or 4 sub-steps, each starting on the cold solve's
//! mesh, kept when it is stable and does not jump (a symmetric column past its buckling load
//! keeps its plane). Otherwise the step is [`collocation::solve_from`] the previous step's
//! solution (which keeps a stable warm start whose predicted Newton step is small). Each
//! step has a fresh workspace, so its stability verdict is its own. When a step changes what the last step was (a
//! tendon's engagement, the number of unstable directions, or the tip jumped), the change
//! is located by bisection on the inputs between the two steps (module `locate`): each
//! bisection point is solved from the last point before the change, keeping to its branch
//! (`collocation::solve_on_branch`: no snap from a bifurcation, no landing from a fold),
//! until the bracket is
//! [`LOCATED`] of the sweep's range wide; the event is reported at the bracket's middle.
//! The step is then solved again from the state just past the event, so the branch a sweep
//! follows does not depend on its step size. Shooting steps start cold (shooting takes no
//! warm start).

mod locate;
pub mod ranges;

pub use ranges::{Input, Ranges};

use crate::collocation;
use crate::error::{Error, Result};
use crate::model::robot::Robot;
use crate::report::{PathTaken, Stability};
use crate::shooting;
use crate::solution::Solution;
use nalgebra::Vector3;
use std::fmt;

/// A step that moves the tip more than this many times as far (per unit of the inputs) as
/// the step before it may have left the branch it was on, if it also moves it more than
/// [`JUMP_SHARE`] of L: on a smooth branch successive steps move the tip at similar paces.
/// Bisection then decides.
const JUMP_RATIO: f64 = 4.0;
/// A located jump moves the tip more than this share of L across a bracket [`LOCATED`] of
/// the range wide, which no smooth branch does (it would move 1e4 L over the range); below
/// 1 % of L a change of pace is the branch's curvature, not a jump.
const JUMP_SHARE: f64 = 0.01;
/// A step that fell back to the load path from rest (no stable state was reachable from the
/// warm start) and moved the tip more than this share of L may have jumped, whatever the
/// step before.
const PATHED_SHARE: f64 = 0.05;
/// Events are located to this share of the sweep's range (the bracket's width; the value
/// reported is its middle).
pub const LOCATED: f64 = 1e-6;
/// The most equal sub-steps [`Sweep::continued`] splits a step into (1, 2, then 4): a
/// step too long for Newton from the last state (the buckled column's tip moves 0.23 L
/// between 1.03 and 1.12 P_cr) is reached in pieces before the sweep gives up its branch.
const CONTINUED_PIECES: usize = 4;
/// The most events located within one step (a step that crosses more is reported with
/// these, the rest merged into the step's state).
const MAX_EVENTS: usize = 8;

/// The solver of every step of a sweep, with its options.
#[derive(Clone, Debug)]
pub enum SweepSolver {
    /// Collocation, each step warm-started from the last ([`collocation::solve_from`]).
    Collocation(collocation::Options),
    /// Shooting, each step from its own initial guess ([`shooting::solve`]).
    Shooting(shooting::Options),
}

/// What happened at an event.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// The tip jumped by `distance` (m) off the branch it was on: the branch turned back (a
    /// fold) and the robot snapped through to another state.
    Snap {
        /// How far the tip jumped across the located bracket (m).
        distance: f64,
    },
    /// The state's instability changed without a jump (its number of unstable directions,
    /// or a growing mode of the linearized dynamics appeared or went): the branch crossed a
    /// bifurcation.
    Bifurcation {
        /// The instability before.
        before: Instability,
        /// The instability after.
        after: Instability,
    },
    /// A displacement-controlled tendon (from 0) went taut (its solved tension became positive).
    Taut(usize),
    /// A displacement-controlled tendon (from 0) went slack.
    Slack(usize),
}

impl Kind {
    /// `snap`, `bifurcation`, `taut` or `slack`.
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Snap { .. } => "snap",
            Kind::Bifurcation { .. } => "bifurcation",
            Kind::Taut(_) => "taut",
            Kind::Slack(_) => "slack",
        }
    }
}

/// An event between two steps, located.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// What happened.
    pub kind: Kind,
    /// Where, in steps from 0 (fractional: between the steps, to [`LOCATED`] of the range).
    /// A snap to a stable state from an unstable branch is at the loss of stability before
    /// it, which may lie before the step before the one that lists it.
    pub at: f64,
    /// The swept input ([`Ranges::swept`]) and its value at `at`; `None` when every input
    /// is held.
    pub value: Option<(Input, f64)>,
    /// Whether the state before the event was already unstable: the robot had left that
    /// branch at an earlier bifurcation, and the event is where the unstable branch the sweep
    /// followed ends or changes (located by following that branch, whatever its stability).
    pub from_unstable: bool,
}

/// `v` to 7 significant digits (an event is located to 1e-6 of the range), as
/// [`crate::Readable`] prints it.
fn significant(v: f64) -> crate::Readable {
    if !(v.is_finite() && v != 0.0) {
        return crate::Readable(v);
    }
    let digits = 6 - v.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    crate::Readable((v * scale).round() / scale)
}

/// A state's instability as a sweep's events compare it ([`Stability`] without its figures).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Instability {
    /// The number of unstable directions of the second variation (conservative loads; 0:
    /// stable, which a verdict of the linearized dynamics gives too).
    Directions(usize),
    /// A growing mode of the linearized dynamics (loads that are not conservative, friction).
    Growing {
        /// Whether it oscillates (flutter) or not (divergence).
        flutter: bool,
    },
    /// No verdict.
    Unknown,
}

impl Instability {
    /// The instability of a state with the verdict `s`.
    pub fn of(s: &Stability) -> Self {
        match s {
            Stability::Stable => Instability::Directions(0),
            Stability::Unstable { directions, .. } => Instability::Directions(*directions),
            Stability::Growing { growth, .. } => Instability::Growing {
                flutter: matches!(growth, crate::report::Growth::Flutter { .. }),
            },
            Stability::Unknown { .. } => Instability::Unknown,
        }
    }

    /// Whether the energy decreases along some direction (a conservative instability: the
    /// robot leaves the state by buckling or snapping, which the sweep's snaps follow). A
    /// growing mode of the linearized dynamics is not one: damping can hold it.
    pub fn has_unstable_directions(&self) -> bool {
        matches!(self, Instability::Directions(n) if *n > 0)
    }
}

/// `instability` in words.
fn stability_words(instability: Instability) -> String {
    match instability {
        Instability::Directions(0) => "stable".into(),
        Instability::Directions(1) => "unstable (1 direction)".into(),
        Instability::Directions(n) => format!("unstable ({n} directions)"),
        Instability::Growing { flutter: true } => "unstable (flutter: a growing oscillation)".into(),
        Instability::Growing { flutter: false } => "unstable (divergence: a growing mode)".into(),
        Instability::Unknown => "unknown".into(),
    }
}

impl fmt::Display for Event {
    /// `snap at tension.5 = 0.008011677 N: the tip jumps by 361.4 mm`,
    /// `bifurcation at tip_force.z = -0.1778930 N: stable to unstable (2 directions)`, or
    /// `tendon 1 taut at displacement.1 = 0.00206412 m`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let at = match self.value {
            Some((input, v)) => format!(" at {input} = {}", significant(v)),
            None => format!(" at step {:.6}", self.at + 1.0),
        };
        let unit = match self.value {
            Some((input, _)) if !input.unit().is_empty() => format!(" {}", input.unit()),
            _ => String::new(),
        };
        let located = if self.from_unstable {
            " (on an unstable branch the robot had already left)"
        } else {
            ""
        };
        match &self.kind {
            Kind::Snap { distance } if self.from_unstable => write!(
                f,
                "snap{at}{unit}: the sweep leaves the unstable branch it followed (the robot had already left it), the tip jumps by {:.1} mm",
                distance * 1e3
            ),
            Kind::Snap { distance } => write!(f, "snap{at}{unit}: the tip jumps by {:.1} mm", distance * 1e3),
            Kind::Bifurcation { before, after } => write!(
                f,
                "bifurcation{at}{unit}: {} to {}{located}",
                stability_words(*before),
                stability_words(*after)
            ),
            Kind::Taut(i) => write!(f, "tendon {} taut{at}{unit}{located}", i + 1),
            Kind::Slack(i) => write!(f, "tendon {} slack{at}{unit}{located}", i + 1),
        }
    }
}

/// One solved step of a sweep.
#[derive(Clone, Debug)]
pub struct Step {
    /// The step's solution; its report holds the stability verdict and how the equilibrium
    /// was reached (`report.path`).
    pub solution: Solution,
    /// The events located since the step before, in order.
    pub events: Vec<Event>,
}

/// Which displacement-controlled tendons (from 0) are taut in `solution` of `robot`.
fn taut(robot: &Robot, solution: &Solution) -> Vec<(usize, bool)> {
    (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].displacement().is_some())
        .map(|i| (i, solution.tendons[i].tension > 0.0))
        .collect()
}

/// A solved point of a sweep: where (in steps), its state and what an event compares.
#[derive(Clone)]
struct Mark {
    t: f64,
    solution: Solution,
    taut: Vec<(usize, bool)>,
    unstable: Instability,
}

impl Mark {
    fn new(t: f64, robot: &Robot, solution: Solution) -> Self {
        Mark {
            t,
            taut: taut(robot, &solution),
            unstable: Instability::of(&solution.report.stability),
            solution,
        }
    }

    fn tip(&self) -> Vector3<f64> {
        self.solution.tip_position()
    }
}

/// A sweep in progress: solves the steps of its [`Ranges`] one after another
/// ([`Sweep::step`]), each from the last solution, and locates the events between them.
///
/// # Examples
/// ```
/// use tdcr::analysis::sweep::{Input, Ranges, Sweep, SweepSolver};
/// use tdcr::Parameter;
/// let ranges = Ranges::new(tdcr::cases::case_s(), vec![(Input::Parameter(Parameter::Tension(0)), vec![0.0, 1.0, 2.0])]).unwrap();
/// let mut sweep = Sweep::new(&ranges, SweepSolver::Collocation(Default::default()), None);
/// while let Some(step) = sweep.step() {
///     assert!(step.unwrap().events.is_empty());
/// }
/// ```
pub struct Sweep<'r> {
    ranges: &'r Ranges,
    solver: SweepSolver,
    /// The next step to solve.
    next: usize,
    /// The warm start of the first step, if given.
    start: Option<Solution>,
    /// The last point solved (a step, or the state just past an event).
    last: Option<Mark>,
    /// How far the tip moved per step over the last stretch without an event (m).
    pace: Option<f64>,
    /// Where (in steps) the states the sweep followed last lost their stability, and the
    /// tip just before (m): while the sweep is on an unstable branch, a stable state it
    /// lands on again is where the robot went from there.
    lost: Option<(f64, Vector3<f64>)>,
}

impl<'r> Sweep<'r> {
    /// A sweep of `ranges` that solves with `solver`, its first step warm-started from
    /// `start` (a solution of a nearby robot; collocation only) if given.
    pub fn new(ranges: &'r Ranges, solver: SweepSolver, start: Option<Solution>) -> Self {
        Sweep {
            ranges,
            solver,
            next: 0,
            start,
            last: None,
            pace: None,
            lost: None,
        }
    }

    /// The number of steps solved so far.
    pub fn solved(&self) -> usize {
        self.next
    }

    /// Solves `robot` by Newton from `warm` alone, whatever the stability of the state it
    /// reaches (collocation; shooting solves as [`Sweep::solve`]): the state on the branch
    /// of `warm`, when Newton reaches it.
    fn follow(&self, robot: &Robot, warm: &Solution) -> Result<Solution> {
        match &self.solver {
            SweepSolver::Collocation(options) => {
                let options = collocation::Options {
                    equilibrium: collocation::Equilibrium::Nearest,
                    continuation: false,
                    ..options.clone()
                };
                collocation::solve_from(robot, &options, warm)
            }
            SweepSolver::Shooting(options) => shooting::solve(robot, options),
        }
    }

    /// Solves `robot` from `warm` keeping to its branch (collocation: a load path from rest
    /// that loses stability or cannot be followed does not snap, `collocation::solve_on_branch`;
    /// shooting solves as [`Sweep::solve`]): a bisection point's state on the branch of the
    /// last point before the change.
    fn on_branch(&self, robot: &Robot, warm: &Solution) -> Result<Solution> {
        match &self.solver {
            SweepSolver::Collocation(options) => collocation::solve_on_branch(robot, options, warm),
            SweepSolver::Shooting(options) => shooting::solve(robot, options),
        }
    }

    /// Solves `robot` from `warm` (if any) with the sweep's solver.
    fn solve(&self, robot: &Robot, warm: Option<&Solution>) -> Result<Solution> {
        match (&self.solver, warm) {
            (SweepSolver::Collocation(options), None) => collocation::solve(robot, options),
            (SweepSolver::Collocation(options), Some(warm)) => collocation::solve_from(robot, options, warm),
            (SweepSolver::Shooting(options), _) => shooting::solve(robot, options),
        }
    }

    /// Solves the next step from the last solution and locates the events since the step
    /// before; `None` after the last step.
    ///
    /// # Errors
    /// The solver's errors ([`collocation::solve`], [`shooting::solve`]) for the step itself;
    /// the sweep is then left as it was before the step. A failed solve while locating an
    /// event only narrows the bracket.
    pub fn step(&mut self) -> Option<Result<Step>> {
        let k = self.next;
        if k >= self.ranges.steps() {
            return None;
        }
        Some(self.solve_step(k))
    }

    fn solve_step(&mut self, k: usize) -> Result<Step> {
        let t = k as f64;
        let robot = self.ranges.robot(t)?;
        let warm = self.last.as_ref().map(|m| &m.solution).or(self.start.as_ref());
        let mut right = match self.continued(&robot, t) {
            Some(right) => right,
            None => Mark::new(t, &robot, self.solve(&robot, warm)?),
        };
        let mut events = Vec::new();
        if let Some(mut left) = self.last.clone() {
            for _ in 0..MAX_EVENTS {
                let jump = self.jumped(&left, &right);
                if !jump && left.taut == right.taut && left.unstable == right.unstable {
                    break;
                }
                // A stable state reached by a jump from an unstable branch is where the
                // robot went when the states it was on lost their stability: the snap is
                // at that (located) loss, not where the sweep happened to find the state.
                if jump
                    && left.unstable.has_unstable_directions()
                    && right.unstable == Instability::Directions(0)
                    && let Some((at, tip)) = self.lost
                {
                    let landed = self.landing(at, &right, tip);
                    events.push(self.event(
                        Kind::Snap {
                            distance: (landed - tip).norm(),
                        },
                        at,
                        false,
                    ));
                    break;
                }
                let Some((before, after)) = self.locate(left.clone(), right.clone()) else {
                    break;
                };
                let found = self.events(&before, &after);
                if found.is_empty() {
                    break;
                }
                // A snap whose first landing is left again at once (a state the solve from
                // the branch's end reached, unstable itself) is one snap, not two.
                let width = LOCATED * (self.ranges.steps().max(2) - 1) as f64;
                let again = |e: &Event| {
                    events.last().is_some_and(|last: &Event| {
                        last.kind.name() == e.kind.name() && (e.at - last.at).abs() <= 4.0 * width
                    })
                };
                let found: Vec<Event> = found.into_iter().filter(|e| !again(e)).collect();
                if before.unstable == Instability::Directions(0) && after.unstable.has_unstable_directions() {
                    self.lost = Some((0.5 * (before.t + after.t), before.tip()));
                }
                events.extend(found);
                // The step again from just past the event: the branch it reaches does not
                // depend on where the step before was.
                right = if after.t == t {
                    after.clone()
                } else {
                    Mark::new(t, &robot, self.solve(&robot, Some(&after.solution))?)
                };
                self.pace = None;
                left = after;
            }
            let span = t - left.t;
            if span > 0.0 {
                self.pace = Some((right.tip() - left.tip()).norm() / span);
            }
        }
        if right.unstable == Instability::Directions(0) {
            self.lost = None;
        }
        self.last = Some(right.clone());
        self.next += 1;
        Ok(Step {
            solution: right.solution,
            events,
        })
    }

    /// The step at `t` (its robot `robot`) continued from the last point's stable state on
    /// its branch (collocation: [`Sweep::on_branch`], which keeps the warm start), when that
    /// reaches a stable state by Newton or by the homotopy from the last state (`direct` or
    /// `from_warm_start`) without a jump ([`Sweep::jumped`]), in one piece or in up to
    /// [`CONTINUED_PIECES`]: the state the robot moves to from where it was. `None` otherwise (no last point, an unstable one, a branch that
    /// ends or loses its stability, shooting), and the step is solved by [`Sweep::solve`].
    ///
    /// Without it, a step of the buckled round column (every plane an equilibrium) lost its
    /// branch: the cold guess, the straight column (an exact equilibrium, unstable past
    /// Euler's load), has the smaller residual and replaced the warm start, and the load path
    /// from rest on the warm start's mesh took another plane (docs/stability.md, "col25").
    fn continued(&self, robot: &Robot, t: f64) -> Option<Mark> {
        let left = self.last.as_ref()?;
        if left.unstable != Instability::Directions(0) || matches!(self.solver, SweepSolver::Shooting(_)) {
            return None;
        }
        let mut pieces = 1;
        while pieces <= CONTINUED_PIECES {
            if let Some(right) = self.continued_in(left, robot, t, pieces) {
                return Some(right);
            }
            pieces *= 2;
        }
        None
    }

    /// [`Sweep::continued`] in `pieces` equal sub-steps from `left` to `t`, each from the
    /// last and each one that must reach a stable state without a jump.
    fn continued_in(&self, left: &Mark, robot: &Robot, t: f64, pieces: usize) -> Option<Mark> {
        let mut last = left.clone();
        for k in 1..=pieces {
            let (at, here) = if k == pieces {
                (t, robot.clone())
            } else {
                let at = left.t + (t - left.t) * k as f64 / pieces as f64;
                (at, self.ranges.robot(at).ok()?)
            };
            let SweepSolver::Collocation(options) = &self.solver else {
                return None;
            };
            let options = fresh_mesh(options, &here)?;
            let solution = collocation::solve_on_branch(&here, &options, &last.solution).ok()?;
            let reached = matches!(
                solution.report.path,
                PathTaken::Direct | PathTaken::FromWarmStart { .. }
            );
            let next = Mark::new(at, &here, solution);
            if !reached || next.unstable != Instability::Directions(0) || self.jumped(&last, &next) {
                return None;
            }
            last = next;
        }
        Some(last)
    }

    /// Whether the tip may have jumped from `left` to `right`: it moved faster than
    /// [`JUMP_RATIO`] times the pace before and more than [`JUMP_SHARE`] of L, or `right`
    /// fell back to the load path and moved it more than [`PATHED_SHARE`] of L.
    fn jumped(&self, left: &Mark, right: &Mark) -> bool {
        let length = right.solution.nodes.last().map_or(0.0, |n| n.s);
        let moved = (right.tip() - left.tip()).norm();
        let span = right.t - left.t;
        let pathed = matches!(right.solution.report.path, PathTaken::LoadPath { .. });
        let faster = self.pace.is_some_and(|p| moved > JUMP_RATIO * p * span);
        (faster && moved > JUMP_SHARE * length) || (pathed && moved > PATHED_SHARE * length)
    }
}

/// `options` with the mesh a cold solve of `robot` starts on (`options.intervals`
/// uniform) where refinement runs and no mesh is given: a continued step starts there
/// instead of on the last state's final mesh, which refinement would only add to (the
/// buckled column's meshes grew to 5 815 intervals over the sweep where a cold solve
/// takes 123-336). None when that mesh cannot be built.
fn fresh_mesh(options: &collocation::Options, robot: &Robot) -> Option<collocation::Options> {
    if options.mesh.is_some() || options.tolerance.is_none() {
        return Some(options.clone());
    }
    let mesh = crate::mesh::Mesh::uniform(robot, options.intervals).ok()?;
    Some(collocation::Options {
        mesh: Some(mesh.nodes.iter().map(|n| n.s).collect()),
        ..options.clone()
    })
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

/// Solves the steps of `ranges` in order with [`Sweep`], the first from `start` if given,
/// stopping at the first step that fails ([`SweepResult::failure`]).
pub fn sweep(ranges: &Ranges, solver: SweepSolver, start: Option<Solution>) -> SweepResult {
    let mut sweep = Sweep::new(ranges, solver, start);
    let mut steps = Vec::with_capacity(ranges.steps());
    while let Some(step) = sweep.step() {
        match step {
            Ok(step) => steps.push(step),
            Err(e) => {
                return SweepResult {
                    failure: Some((steps.len(), e)),
                    steps,
                };
            }
        }
    }
    SweepResult { steps, failure: None }
}

#[cfg(test)]
mod tests;
