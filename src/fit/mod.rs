//! Fits on top of the forward solve, both by Levenberg-Marquardt on the tip sensitivities of
//! [`crate::collocation::sensitivity`]: calibration of model parameters from measured tips
//! ([`calibration`]) and inverse statics, tensions or actuator pull-ins within bounds that
//! reach a target tip pose ([`inverse`]). They share the damping update, the gain ratio, the acceptance test, why a
//! fit stopped and the record of each trial step ([`lm`]).
//!
//! The data of the paper's calibration (its frame and Table 2 as measurements) are in
//! [`crate::cases`]; the experiments CSV of `tdcr calibrate` is read and written by
//! [`crate::io::experiments`].

pub mod calibration;
pub mod inverse;
pub mod lm;

pub use calibration::{
    Calibration, CalibrationOptions, Fit, Measurement, Parameters, calibrate, calibrate_until, predict,
};
pub use inverse::{Adjusted, Bound, InverseOptions, InverseSolution, Target, solve_displacements, solve_tensions};
pub use lm::{FitIteration, FitTermination};
