//! What a calibration returns: the fitted parameters with their standard errors, the tip
//! errors before and after (the paper's Table 3), and the work done.

use super::problem::{Fit, Parameters};
use crate::fit::lm::{FitIteration, FitTermination};
use crate::model::robot::Robot;
use nalgebra::Vector3;
use std::fmt;
use std::time::Duration;

/// How far above a stated measurement noise (per coordinate) the fit's noise estimate may be
/// before [`Calibration::poor_fit`] warns, 3: for a model that explains the data the estimate
/// matches the noise to within its sampling error (about 1/sqrt(2 (3N - n)), 13 % for the 32
/// experiments of Table 2), so three times it is a misfit, not bad luck.
pub const NOISE_FACTOR: f64 = 3.0;

/// The noise estimate per coordinate, relative to the rod length, above which
/// [`Calibration::poor_fit`] warns when no noise is stated, 1.5 %. The paper's own
/// calibration on real data, with a mean tip error of 4.0 mm (1.7 % of L), corresponds to about
/// 1 % of L per coordinate (a 3-D Gaussian's mean length is 1.596 sigma) and passes; the
/// synthetic Table 2 data fitted in the wrong world frame (gravity along the robot file's
/// -z, the data's along +y) give 2.2 % and are caught.
pub const UNSTATED_NOISE_FRACTION: f64 = 0.015;

/// A calibration whose residuals are far above the measurement noise
/// ([`Calibration::poor_fit`]): the model does not explain the data, so the fitted values
/// are not to be trusted although the iteration converged. `Display` names the figures and
/// the likely causes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoorFit {
    /// The fit's noise estimate per coordinate (m), [`Calibration::noise_estimate`].
    pub noise_estimate: f64,
    /// The measurement noise per coordinate the caller stated (m), if any.
    pub stated_noise: Option<f64>,
    /// The limit it exceeded (m): [`NOISE_FACTOR`] times the stated noise, or
    /// [`UNSTATED_NOISE_FRACTION`] of the rod length.
    pub limit: f64,
    /// Mean tip error at the fit (m).
    pub mean_error: f64,
    /// Rod length L (m).
    pub length: f64,
    /// Whether the robot has a tendon with friction: then rows measured where a tendon
    /// sticks (the first steps after its actuator reverses), which the fit's full-slip
    /// solves cannot describe, are a likely cause too.
    pub friction: bool,
}

impl fmt::Display for PoorFit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mm = |x: f64| x * 1e3;
        write!(
            f,
            "the fit does not explain the data: its noise estimate, {:.3} mm per coordinate (mean tip error \
             {:.3} mm, {:.2} % of the rod length), is above ",
            mm(self.noise_estimate),
            mm(self.mean_error),
            self.mean_error / self.length * 100.0
        )?;
        match self.stated_noise {
            Some(noise) => write!(
                f,
                "{NOISE_FACTOR} x the stated measurement noise of {:.3} mm ({:.3} mm)",
                mm(noise),
                mm(self.limit)
            )?,
            None => write!(
                f,
                "{} % of the rod length ({:.3} mm; no measurement noise was stated)",
                UNSTATED_NOISE_FRACTION * 100.0,
                mm(self.limit)
            )?,
        }
        write!(
            f,
            ", so the fitted values are not trustworthy although the iteration converged. Likely causes: \
             the measurements are in another world frame than the robot file (the robot file's gravity, \
             distributed_force, and base pose must be in the frame of the measurements); a base rotation or \
             position off by more than the fitted parameters can absorb (fit the position too); units (tip \
             positions in mm instead of m, tensions in mN); tension columns in another order than the robot \
             file's tendons"
        )?;
        if self.friction {
            write!(
                f,
                "; rows measured while a tendon with friction sticks (the first steps after its actuator reverses, \
                 as at the start of an unloading branch), which the fit's full-slip solve of each row in its \
                 `motion` cannot describe: keep only the rows that a load history of the same inputs (`tdcr sweep \
                 --history`) shows sliding all along; a wrong `motion` column"
            )?;
        }
        Ok(())
    }
}

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

    /// A warning when the fitted residuals are far above the measurement noise: the noise
    /// estimate per coordinate above [`NOISE_FACTOR`] times `noise` (m per coordinate, the
    /// measurement noise), or, with `noise` `None`, above [`UNSTATED_NOISE_FRACTION`] of the
    /// rod length. `None` when the fit explains the data to that level (or the estimate is
    /// undefined, with no more residuals than unknowns).
    pub fn poor_fit(&self, noise: Option<f64>) -> Option<PoorFit> {
        let length = self.robot.length();
        let limit = match noise {
            Some(sigma) => NOISE_FACTOR * sigma,
            None => UNSTATED_NOISE_FRACTION * length,
        };
        (self.noise_estimate > limit).then_some(PoorFit {
            noise_estimate: self.noise_estimate,
            stated_noise: noise,
            limit,
            mean_error: self.errors.mean,
            length,
            friction: crate::model::friction::any(&self.robot),
        })
    }

    /// The tip error of every experiment at the start (m).
    pub fn start_tip_errors(&self) -> Vec<f64> {
        self.start_residuals.iter().map(|r| r.norm()).collect()
    }
}
