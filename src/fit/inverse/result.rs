//! The result of inverse statics and its explanation for a person.

use super::problem::{Adjusted, Target};
use crate::fit::lm::{FitIteration, FitTermination};
use crate::solution::Solution;
use nalgebra::Vector3;

/// Where a tendon's adjusted input ended up relative to its bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// Strictly between the bounds, taut.
    Inside,
    /// At 0 N: slack (for tensions the lower bound; for pull-ins a slack tendon, or one let
    /// out until just taut at 0 N).
    Slack,
    /// At the upper bound: `max_tension`, or the stroke `max_displacement`.
    Saturated,
    /// Pull-ins only: at the lower bound `min_displacement`, taut.
    Released,
    /// Pull-ins only: the tension reached its bound, `max_tension` when set or
    /// [`super::GEOMETRIC_SHARE`] of the tendon's geometric limit EI / r^2.
    TensionLimit,
    /// Not free to change (not in `free_tendons`): the robot's input.
    Held,
}

/// The result of [`super::solve_tensions`] and [`super::solve_displacements`]: the best
/// inputs found, their solved shape, and how close the tip came.
#[derive(Clone, Debug)]
pub struct InverseSolution {
    /// Tension of every tendon (N), in the robot's order: the adjusted or held tensions, and
    /// the solved ones of displacement-controlled tendons.
    pub tensions: Vec<f64>,
    /// Actuator pull-in of every tendon (m), in the robot's order: the adjusted or held
    /// pull-ins, and for tension-controlled tendons the pull-in that holds their tension
    /// ([`crate::TendonState::displacement`]).
    pub displacements: Vec<f64>,
    /// The forward solution at these inputs.
    pub solution: Solution,
    /// Weighted tip error |e| (m): position error and, with a target orientation, the
    /// rotation angle times the orientation weight.
    pub residual: f64,
    /// Tip position error |p_tip - p*| (m).
    pub position_error: f64,
    /// Tip rotation error, the angle of R_tip R*^T (rad), when the target has an orientation.
    pub orientation_error: Option<f64>,
    /// Whether the residual is within the tolerance (only for [`FitTermination::Reached`]).
    pub reachable: bool,
    /// Why the iteration stopped.
    pub termination: FitTermination,
    /// Where each tendon's input sits relative to its bounds.
    pub bounds: Vec<Bound>,
    /// Trial steps taken (accepted and rejected).
    pub iterations: usize,
    /// Forward collocation solves (the start, one more when the start's inputs had to be
    /// clamped into the bounds, and one per trial step).
    pub forward_solves: usize,
    /// Sensitivity evaluations (the start plus one per accepted step, when needed).
    pub jacobians: usize,
    /// Residual (m) at the start and after each accepted step.
    pub history: Vec<f64>,
    /// Every trial step: cost F = |e|^2 / 2 (m^2), largest input change (N or m), damping
    /// mu, gain ratio, whether accepted.
    pub trials: Vec<FitIteration>,
    /// The tolerance the residual was tested against (m).
    pub tolerance: f64,
    /// What was adjusted, within which bounds.
    pub adjusted: Adjusted,
    /// The target.
    pub target: Target,
}

impl InverseSolution {
    /// Achieved tip position (m), world frame.
    pub fn tip_position(&self) -> Vector3<f64> {
        self.solution.tip_position()
    }

    /// A few sentences for a person: whether the target was reached, how far the tip
    /// stayed, why the iteration stopped, which tendons sit at their bounds (numbered from
    /// 1, as on the command line), and, with more free tendons than target coordinates, which
    /// of the many solutions this is (the one reached from the starting inputs, close to
    /// the nearest to them; not the least-norm one).
    pub fn explain(&self) -> String {
        let (lo, hi) = self.adjusted.range();
        let (inputs, unit) = match self.adjusted {
            Adjusted::Tensions { .. } => ("tensions", "N"),
            Adjusted::Displacements { .. } => ("pull-ins", "m"),
        };
        let mut text = if self.reachable {
            format!(
                "target reached: weighted tip error {:.3e} m <= tolerance {:.1e} m after {} iterations",
                self.residual, self.tolerance, self.iterations
            )
        } else {
            let mut t = format!(
                "target unreachable with {inputs} in [{lo}, {hi} {unit}]: the closest tip found is {:.6} m from the \
                 target position (weighted tip error {:.6} m > tolerance {:.1e} m)",
                self.position_error, self.residual, self.tolerance
            );
            if self.termination == FitTermination::MaxIterations {
                t.push_str(&format!(
                    "; not settled after {} iterations, so more iterations may still reach it",
                    self.iterations
                ));
            }
            t
        };
        if let Some(angle) = self.orientation_error {
            text.push_str(&format!("; orientation error {:.4} deg", angle.to_degrees()));
        }
        if !self.reachable {
            text.push_str(&format!("; {}", self.termination));
        }
        let list = |b: Bound| {
            let items: Vec<String> = (0..self.bounds.len())
                .filter(|&i| self.bounds[i] == b)
                // 1-based, as the command line and robot files number tendons.
                .map(|i| format!("tendon {}", i + 1))
                .collect();
            items.join(", ")
        };
        for (bound, what) in [
            (Bound::Saturated, format!("at the upper bound {hi} {unit}")),
            (Bound::Released, format!("at the lower bound {lo} {unit}")),
            (Bound::Slack, "slack (0 N)".to_string()),
            (Bound::TensionLimit, "at the tension limit".to_string()),
        ] {
            let tendons = list(bound);
            if !tendons.is_empty() {
                text.push_str(&format!("; {what}: {tendons}"));
            }
        }
        let free = self.bounds.iter().filter(|&&b| b != Bound::Held).count();
        let coordinates = if self.target.orientation.is_some() { 6 } else { 3 };
        if free > coordinates {
            // What the iteration does (module docs): damped least-squares steps from the
            // starting inputs, each without a component in the null space of the tip
            // Jacobian at its iterate.
            // Both iterate on the tensions, so the steps are smallest in tension.
            text.push_str(&format!(
                "; {free} free tendons for {coordinates} target coordinates, so many {inputs} give this tip: \
                 these are the ones reached from the starting {inputs}, each step the smallest tension change \
                 that makes its progress (no component along changes the tip does not see, such as pulling \
                 opposing tendons together), so they keep the start's co-contraction: close to the solution \
                 nearest the start, not the least-norm tensions (start from lower {inputs} for lower tensions)"
            ));
        }
        if !self.reachable {
            // A tip cannot get farther from the base than the rod is long (tendons only
            // compress it), so this distance bounds the position error from below.
            let distance = (self.target.position - self.solution.base().p).norm();
            let length = self.solution.length();
            if distance > length {
                text.push_str(&format!(
                    "; the target is {distance:.6} m from the base, farther than the rod length {length} m, \
                     so no {inputs} reach it (the position error is at least about {:.6} m)",
                    distance - length
                ));
            }
        }
        text
    }
}
