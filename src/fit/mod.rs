//! Fits on top of the forward solve: calibration of model parameters from measured tips and
//! inverse statics (tensions that reach a target tip pose).

pub mod calibration;
pub mod inverse;
