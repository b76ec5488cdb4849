//! What a calibration returns: the fitted parameters with their standard errors, the tip
//! errors before and after (the paper's Table 3), and the work done.

use super::problem::{Fit, Parameters};
use crate::fit::lm::{FitIteration, FitTermination};
use crate::model::robot::Robot;
use nalgebra::Vector3;
use std::time::Duration;

/// Tip-error statistics over a set of experiments, as in the paper's Table 3 (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipErrorStatistics {
    /// Number of experiments.
    pub count: usize,
    /// Mean tip error (m).
    pub mean: f64,
    /// Smallest tip error (m).
    pub min: f64,
    /// Largest tip error (m).
    pub max: f64,
    /// Sample standard deviation (n - 1 in the denominator; 0 for one experiment) (m).
    pub std_dev: f64,
    /// Root mean square (m).
    pub rms: f64,
}

impl TipErrorStatistics {
    /// The statistics of tip errors |p_k - y_k| (m); NaN fields for no errors.
    pub fn of(errors: &[f64]) -> Self {
        let n = errors.len();
        let mean = errors.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        let (min, max) = if n == 0 {
            (f64::NAN, f64::NAN)
        } else {
            errors
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &e| (a.min(e), b.max(e)))
        };
        TipErrorStatistics {
            count: n,
            mean,
            min,
            max,
            std_dev: if n == 0 { f64::NAN } else { var.sqrt() },
            rms: (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt(),
        }
    }
}

/// Wall-clock time of a calibration, split by stage. (Not [`crate::report::Timings`], the
/// forward solve's.)
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CalibrationTimings {
    /// Collocation solves of all experiments.
    pub solves: Duration,
    /// Tip sensitivities (Jacobian columns).
    pub sensitivities: Duration,
    /// Everything, validation included.
    pub total: Duration,
}

/// The result of [`super::calibrate`].
#[derive(Clone, Debug)]
pub struct Calibration {
    /// What was fitted.
    pub fit: Fit,
    /// The parameters the fit started from.
    pub start: Parameters,
    /// The fitted parameters (angles in (-pi, pi]); the others as at the start.
    pub fitted: Parameters,
    /// Standard errors of the fitted parameters, sigma sqrt(diag((J^T J)^-1)) in the same
    /// units, with sigma = [`Calibration::noise_estimate`]; 0 for parameters not fitted.
    /// `None` when there are no more residuals than unknowns or J^T J is singular (as at
    /// beta = +-90 deg).
    pub standard_errors: Option<Parameters>,
    /// Noise estimate sigma = sqrt(S / (3 N - n)) per coordinate (m), N experiments and n
    /// unknowns; NaN when 3 N = n.
    pub noise_estimate: f64,
    /// The robot with the fitted parameters (the robot's own tensions and tip force).
    pub robot: Robot,
    /// Model tip of every experiment at the fitted parameters (m, world).
    pub tips: Vec<Vector3<f64>>,
    /// Model tip minus measured tip of every experiment at the fit (m, world).
    pub residuals: Vec<Vector3<f64>>,
    /// Model tip minus measured tip of every experiment at the start (m, world).
    pub start_residuals: Vec<Vector3<f64>>,
    /// Table 3 statistics of the tip errors at the start.
    pub start_errors: TipErrorStatistics,
    /// Table 3 statistics of the tip errors at the fit.
    pub errors: TipErrorStatistics,
    /// Why the iteration stopped.
    pub termination: FitTermination,
    /// Levenberg-Marquardt iterations (trial steps, accepted or not).
    pub iterations: usize,
    /// Every iteration.
    pub history: Vec<FitIteration>,
    /// Collocation solves (one per experiment per evaluated parameter set).
    pub solves: usize,
    /// Tip sensitivity evaluations (one per experiment per accepted parameter set).
    pub sensitivity_evaluations: usize,
    /// Timings.
    pub timings: CalibrationTimings,
}

impl Calibration {
    /// Whether a convergence test passed ([`FitTermination::converged`]).
    pub fn converged(&self) -> bool {
        self.termination.converged()
    }

    /// The tip error |p_k - y_k| of every experiment at the fit (m).
    pub fn tip_errors(&self) -> Vec<f64> {
        self.residuals.iter().map(|r| r.norm()).collect()
    }

    /// The tip error of every experiment at the start (m).
    pub fn start_tip_errors(&self) -> Vec<f64> {
        self.start_residuals.iter().map(|r| r.norm()).collect()
    }
}
