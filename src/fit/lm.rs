//! The Levenberg-Marquardt core shared by [`calibration`](super::calibration) and
//! [`inverse`](super::inverse) statics: Nielsen's damping update, the gain ratio and the
//! acceptance test, why a fit stopped ([`FitTermination`]) and what each trial step did
//! ([`FitIteration`]).
//!
//! Each fit builds its own damped model (calibration: Marquardt's scaling lambda
//! diag(J^T J); inverse statics: mu I on a box-constrained model) and its own stopping tests;
//! what they share is how a trial step is judged and how the damping then moves:
//!
//! - gain ratio rho = (actual decrease of the cost) / (decrease predicted by the linear
//!   model), `gain_ratio`;
//! - the step is accepted when the prediction is a decrease and rho exceeds the fit's
//!   threshold, `accepts`;
//! - Nielsen's update (`Damping`): on acceptance the damping shrinks by
//!   max(1/3, 1 - (2 rho - 1)^3) and the growth factor resets to 2; on rejection the damping
//!   grows by the growth factor, which doubles (H. B. Nielsen, "Damping parameter in
//!   Marquardt's method", IMM-REP-1999-05; Madsen, Nielsen & Tingleff, "Methods for
//!   non-linear least squares problems", 2004, algorithm 3.16).

use std::fmt;

/// Why a Levenberg-Marquardt fit stopped: a calibration ([`super::calibrate`]) or inverse
/// statics ([`super::solve_tensions`]). Not to be confused with [`crate::Termination`], the
/// forward solve's Newton iteration.
///
/// Calibration stops with `StepTolerance`, `GradientTolerance`, `CostTolerance`,
/// `MaxIterations` or `Stalled`; inverse statics with `Reached`, `Stationary`, `NoProgress`
/// or `MaxIterations`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitTermination {
    /// Calibration, converged: the step fell below the step tolerance.
    StepTolerance,
    /// Calibration, converged: the residual is orthogonal to every Jacobian column within
    /// the gradient tolerance (a stationary point), or zero.
    GradientTolerance,
    /// Calibration, converged: an accepted step lowered the cost by less than the cost
    /// tolerance.
    CostTolerance,
    /// Calibration, not converged: no step lowered the cost, even with the damping at
    /// [`super::calibration::MAX_DAMPING`].
    Stalled,
    /// Inverse statics: the weighted tip error is at or below the tolerance.
    Reached,
    /// Inverse statics: the gradient of the tip error, projected onto the bounds of the
    /// inputs, vanishes (a minimum within the bounds that is not the target).
    Stationary,
    /// Inverse statics: the damped step became negligible, or would lower the tip error by
    /// less than [`super::inverse::PROGRESS_FRACTION`] of the tolerance.
    NoProgress,
    /// Not converged: the iteration limit was reached first.
    MaxIterations,
}

impl FitTermination {
    /// Whether a convergence test passed: the calibration's step, gradient and cost tests,
    /// and inverse statics' `Reached` and `Stationary` (for inverse statics only `Reached`
    /// means the target is reached).
    pub fn converged(&self) -> bool {
        matches!(
            self,
            FitTermination::StepTolerance
                | FitTermination::GradientTolerance
                | FitTermination::CostTolerance
                | FitTermination::Reached
                | FitTermination::Stationary
        )
    }
}

impl fmt::Display for FitTermination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FitTermination::StepTolerance => "converged: the parameter step fell below the step tolerance",
            FitTermination::GradientTolerance => {
                "converged: the residuals are orthogonal to every parameter's effect on the tips (a stationary point)"
            }
            FitTermination::CostTolerance => {
                "converged: the last accepted step lowered the sum of squared tip errors by less than the cost tolerance"
            }
            FitTermination::Stalled => {
                "stalled: no step lowered the sum of squared tip errors even at the largest damping; the parameters may not be identifiable from these experiments"
            }
            FitTermination::Reached => "reached: the weighted tip error is within the tolerance",
            FitTermination::Stationary => {
                "stationary: no change of the inputs within their bounds reduces the tip error to first order"
            }
            FitTermination::NoProgress => {
                "stalled: no step within the bounds promises to reduce the tip error by a meaningful amount"
            }
            FitTermination::MaxIterations => {
                "stopped at the iteration limit before a convergence test passed; raise max_iterations or start closer"
            }
        })
    }
}

/// One Levenberg-Marquardt trial step, accepted or not. Not to be confused with
/// [`crate::report::Iteration`], a Newton step of the forward solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitIteration {
    /// The fit's cost after the step: the trial's if accepted, else unchanged. Calibration:
    /// S = sum of squared tip errors (m^2); inverse statics: F = |e|^2 / 2 (m^2).
    pub cost: f64,
    /// Largest component of the trial step in the fit's unknowns (calibration: the scaled
    /// unknowns, dimensionless; inverse statics: tensions, N).
    pub step: f64,
    /// The damping after the step's update when it was accepted (the next step's), the one
    /// the step was computed with when it was rejected. Calibration: lambda, relative to
    /// diag(J^T J); inverse statics: mu (absolute, the units of J^T J).
    pub damping: f64,
    /// Gain ratio: actual over predicted decrease of the cost (`gain_ratio`; NaN when a
    /// trial solve failed).
    pub gain: f64,
    /// Whether the step was accepted.
    pub accepted: bool,
}

/// The damping of a Levenberg-Marquardt fit and its growth factor on rejection, moved by
/// Nielsen's update (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Damping {
    /// The current damping.
    value: f64,
    /// The factor the damping grows by on the next rejection: 2, doubling on each
    /// consecutive rejection.
    growth: f64,
}

impl Damping {
    /// Starts at `initial` with growth factor 2.
    pub(crate) fn new(initial: f64) -> Self {
        Damping {
            value: initial,
            growth: 2.0,
        }
    }

    /// The current damping.
    pub(crate) fn value(&self) -> f64 {
        self.value
    }

    /// Judges a trial step of largest component `step` and gain ratio `gain` from `cost` to
    /// `trial_cost`: moves the damping (Nielsen's update) and returns the step's record, with
    /// the trial's cost and the updated damping if `accepted`, else the unchanged cost and
    /// the damping the step was computed with.
    pub(crate) fn update(&mut self, accepted: bool, gain: f64, step: f64, cost: f64, trial_cost: f64) -> FitIteration {
        if accepted {
            self.accept(gain);
        }
        let record = FitIteration {
            cost: if accepted { trial_cost } else { cost },
            step,
            damping: self.value,
            gain,
            accepted,
        };
        if !accepted {
            self.reject();
        }
        record
    }

    /// After an accepted step of gain ratio `gain`: shrink by max(1/3, 1 - (2 gain - 1)^3)
    /// and reset the growth factor to 2.
    fn accept(&mut self, gain: f64) {
        self.value *= (1.0 - (2.0 * gain - 1.0).powi(3)).max(1.0 / 3.0);
        self.growth = 2.0;
    }

    /// After a rejected step (or a damped model that could not be solved): grow by the
    /// growth factor, which then doubles.
    pub(crate) fn reject(&mut self) {
        self.value *= self.growth;
        self.growth *= 2.0;
    }
}

/// The gain ratio rho = (cost - trial_cost) / predicted: the actual decrease of the cost
/// over the decrease the linear model predicted (NaN when either is NaN).
pub(crate) fn gain_ratio(cost: f64, trial_cost: f64, predicted: f64) -> f64 {
    (cost - trial_cost) / predicted
}

/// Whether a trial step is accepted: the linear model predicts a decrease and the gain
/// ratio exceeds `min_gain` (a NaN gain, from a failed trial solve, is rejected).
pub(crate) fn accepts(gain: f64, predicted: f64, min_gain: f64) -> bool {
    gain > min_gain && predicted > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nielsen's update: shrink by 3 on a perfect step, not at all at rho = 1/2,
    /// and a growth factor that doubles on consecutive rejections and resets on acceptance.
    #[test]
    fn nielsen_update() {
        let mut d = Damping::new(1.0);
        d.accept(1.0);
        assert_eq!(d.value(), 1.0 / 3.0);
        d.accept(0.5);
        assert_eq!(d.value(), 1.0 / 3.0);
        d.reject();
        d.reject();
        assert_eq!(d.value(), 8.0 / 3.0);
        d.accept(0.5);
        d.reject();
        assert_eq!(d.value(), 16.0 / 3.0);
        let rejected = d.update(false, 0.1, 1e-3, 2.0, 3.0);
        assert_eq!(
            (rejected.cost, rejected.damping, d.value()),
            (2.0, 16.0 / 3.0, 64.0 / 3.0)
        );
        let taken = d.update(true, 1.0, 1e-3, 2.0, 1.0);
        assert_eq!((taken.cost, taken.damping, d.value()), (1.0, 64.0 / 9.0, 64.0 / 9.0));
        assert!(!accepts(f64::NAN, 1.0, 0.0) && !accepts(1.0, 0.0, 0.0) && accepts(1e-3, 1.0, 1e-4));
        assert_eq!(gain_ratio(3.0, 1.0, 4.0), 0.5);
    }
}
