//! Locating an event between two solved points of a sweep by bisection on the inputs: each
//! middle point is solved from the last point before the change (warm, so it stays on that
//! branch while the branch exists) and replaces the end of the bracket it agrees with, until
//! the bracket is [`LOCATED`] of the range wide (about 20 solves for a step of a tenth of
//! the range). Whatever still differs across the final bracket is the event; a change that
//! does not survive (a fast but smooth stretch taken for a jump) is none.

use super::{Event, JUMP_SHARE, Kind, LOCATED, Mark, Sweep};

impl Sweep<'_> {
    /// Narrows the bracket from `left` (before the change) to `right` (after it) to
    /// [`LOCATED`] of the range, returning its ends; `jump` tells that the tip may have
    /// jumped (a point then belongs to the left unless it moved the tip more than half as
    /// far as the right end did, and more than [`JUMP_SHARE`] of L). None when no robot
    /// can be built between them.
    pub(super) fn locate(&self, mut left: Mark, mut right: Mark, jump: bool) -> Option<(Mark, Mark)> {
        let width = LOCATED * (self.ranges.steps().max(2) - 1) as f64;
        let length = right.solution.nodes.last().map_or(0.0, |n| n.s);
        // Bisection halves the bracket: 60 halvings take any step below 1e-18 of it, so
        // the width is reached first.
        for _ in 0..60 {
            if right.t - left.t <= width {
                break;
            }
            let t = 0.5 * (left.t + right.t);
            let robot = self.ranges.robot(t).ok()?;
            let Ok(solution) = self.solve(&robot, Some(&left.solution)) else {
                // No state reached from the left one: the branch it was on has ended.
                right.t = t;
                continue;
            };
            let middle = Mark::new(t, &robot, solution);
            let moved = (middle.tip() - left.tip()).norm();
            let far = jump && moved > 0.5 * (right.tip() - left.tip()).norm() && moved > JUMP_SHARE * length;
            if far || middle.taut != left.taut || middle.unstable != left.unstable {
                right = middle;
            } else {
                left = middle;
            }
        }
        Some((left, right))
    }

    /// The events across a located bracket `before` to `after`: tendons going taut or
    /// slack, a snap (the tip moved more than [`JUMP_SHARE`] of L across it), else a change
    /// of the unstable directions (a bifurcation). Each is at the bracket's middle.
    pub(super) fn events(&self, before: &Mark, after: &Mark) -> Vec<Event> {
        let at = 0.5 * (before.t + after.t);
        let value = self.ranges.swept().map(|(i, input)| (input, self.ranges.value(i, at)));
        let event = |kind| Event {
            kind,
            at,
            value,
            located: true,
        };
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
