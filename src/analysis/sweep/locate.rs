//! Locating an event between two solved points of a sweep by bisection on the inputs: each
//! middle point is solved from the last point before the change (warm, so it stays on that
//! branch while the branch exists) and replaces the end of the bracket it agrees with, until
//! the bracket is [`LOCATED`] of the range wide (about 20 solves for a step of a tenth of
//! the range). Whatever still differs across the final bracket is the event; a change that
//! does not survive (a fast but smooth stretch taken for a jump) is none.

use super::{Event, JUMP_SHARE, Kind, LOCATED, Mark, Sweep};
use crate::solution::Solution;
use nalgebra::Vector3;

/// The most sub-steps [`Sweep::reach`] splits a bisection step into when following an
/// unstable branch: eight equal pieces of the step before a failure counts as the branch's end
/// (the bisection then narrows on the end itself).
const FOLLOW_STEPS: usize = 8;

impl Sweep<'_> {
    /// Narrows the bracket from `left` (before the change) to `right` (after it) to
    /// [`LOCATED`] of the range, returning its ends. A middle point belongs to the right when
    /// its tendons' tautness or its unstable directions differ from the left end's, or when
    /// it moved the tip from the left end's more than half as far as the right end did and
    /// more than [`JUMP_SHARE`] of L (it left the left end's branch, whether or not the
    /// step's ends told of a jump). None when no robot can be built between them.
    pub(super) fn locate(&self, mut left: Mark, mut right: Mark) -> Option<(Mark, Mark)> {
        let width = LOCATED * (self.ranges.steps().max(2) - 1) as f64;
        let length = right.solution.nodes.last().map_or(0.0, |n| n.s);
        // From an unstable state (the robot left it at an earlier bifurcation, and the solve
        // found no stable state near it) the middle points follow its branch by Newton,
        // whatever their stability: where that branch ends (its fold) or changes is where
        // the sweep leaves it, a point of the branch and not of the step size.
        let unstable = left.unstable.has_unstable_directions();
        // Bisection halves the bracket: 60 halvings take any step below 1e-18 of it, so
        // the width is reached first.
        for _ in 0..60 {
            if right.t - left.t <= width {
                break;
            }
            let t = 0.5 * (left.t + right.t);
            let robot = self.ranges.robot(t).ok()?;
            let reached = if unstable {
                self.reach(&left, t)
            } else {
                self.on_branch(&robot, &left.solution).ok()
            };
            let Some(solution) = reached else {
                // No state reached from the left one: the branch it was on has ended.
                right.t = t;
                continue;
            };
            let middle = Mark::new(t, &robot, solution);
            let moved = (middle.tip() - left.tip()).norm();
            // A middle point far from the left one left its branch (its warm solve found the
            // state the robot snaps to, by the load path from rest): the change is before
            // it, also when the step's ends are near each other (a loss of stability whose
            // step ended on the unstable branch).
            let far = moved > 0.5 * (right.tip() - left.tip()).norm() && moved > JUMP_SHARE * length;
            if far || middle.taut != left.taut || middle.unstable != left.unstable {
                right = middle;
            } else {
                left = middle;
            }
        }
        Some((left, right))
    }

    /// The state at `t` on the branch of `from`, reached by Newton ([`Sweep::follow`]) in
    /// [`FOLLOW_STEPS`] equal sub-steps at most: first in one, then, if Newton fails, in
    /// 2, 4, ... (a branch that exists at `t` but is too far from `from` for one Newton run); `None` when
    /// no sub-division reaches it: the branch has ended (or turned back) before `t`.
    fn reach(&self, from: &Mark, t: f64) -> Option<Solution> {
        let mut pieces = 1;
        while pieces <= FOLLOW_STEPS {
            let mut state = Some(from.solution.clone());
            for k in 1..=pieces {
                let at = from.t + (t - from.t) * k as f64 / pieces as f64;
                state = state.and_then(|last| {
                    let robot = self.ranges.robot(at).ok()?;
                    let next = self.follow(&robot, &last).ok()?;
                    // A Newton run that moved the tip more than JUMP_SHARE of L in one
                    // sub-step left the branch for another state.
                    let moved = (next.tip_position() - last.tip_position()).norm();
                    let length = next.nodes.last().map_or(0.0, |n| n.s);
                    (moved <= JUMP_SHARE * length).then_some(next)
                });
            }
            if state.is_some() {
                return state;
            }
            pieces *= 2;
        }
        None
    }

    /// The tip (m) where the robot lands when it snaps at `at` (in steps) from the state
    /// whose tip was `lost` (m): the state at `at` on the branch of `stable` (a later step's
    /// stable state), reached by Newton from it ([`Sweep::follow`]); where Newton does not
    /// reach that branch (it ends before `at`, or Newton falls back onto the lost state), the
    /// stable state the sweep's solve from `stable` reaches; `stable`'s own tip when neither
    /// leaves the lost state. The branch, not the stable state nearest the loss: where the
    /// lost state swings round the vertical to that branch through a family of stable states
    /// (the payload robot and the gallery's column, whose two planar states lose and gain
    /// their stability a few millionths of the range apart, docs/stability.md "A root at the
    /// base"), the member the robot is on just past the loss depends on where the bracket
    /// ends, the branch it comes to does not.
    pub(super) fn landing(&self, at: f64, stable: &Mark, lost: Vector3<f64>) -> Vector3<f64> {
        let Ok(robot) = self.ranges.robot(at) else {
            return stable.tip();
        };
        let length = stable.solution.nodes.last().map_or(0.0, |n| n.s);
        let left = |s: &Solution| (s.tip_position() - lost).norm() > JUMP_SHARE * length;
        if let Ok(s) = self.follow(&robot, &stable.solution)
            && left(&s)
        {
            return s.tip_position();
        }
        match self.solve(&robot, Some(&stable.solution)) {
            Ok(s) if s.report.stability.is_stable() && left(&s) => s.tip_position(),
            _ => stable.tip(),
        }
    }

    /// An event of `kind` at `at` (in steps), with the swept input's value there.
    pub(super) fn event(&self, kind: Kind, at: f64, from_unstable: bool) -> Event {
        Event {
            kind,
            at,
            value: self.ranges.swept().map(|(i, input)| (input, self.ranges.value(i, at))),
            from_unstable,
        }
    }

    /// The events across a located bracket `before` to `after`: tendons going taut or
    /// slack, a snap (the tip moved more than [`JUMP_SHARE`] of L across it), else a change
    /// of the unstable directions (a bifurcation). Each is at the bracket's middle.
    pub(super) fn events(&self, before: &Mark, after: &Mark) -> Vec<Event> {
        let at = 0.5 * (before.t + after.t);
        let event = |kind| self.event(kind, at, before.unstable.has_unstable_directions());
        let mut out: Vec<Event> = after
            .taut
            .iter()
            .zip(&before.taut)
            .filter(|(now, then)| now.1 != then.1)
            .map(|(now, _)| event(if now.1 { Kind::Taut(now.0) } else { Kind::Slack(now.0) }))
            .collect();
        let length = after.solution.nodes.last().map_or(0.0, |n| n.s);
        let distance = (after.tip() - before.tip()).norm();
        if distance > JUMP_SHARE * length {
            out.push(event(Kind::Snap { distance }));
        } else if before.unstable != after.unstable {
            out.push(event(Kind::Bifurcation {
                before: before.unstable,
                after: after.unstable,
            }));
        }
        out
    }
}
