//! Analyses of solved shapes: the global equilibrium check, the shape sampled at output arc
//! lengths with its internal wrenches, simpler models to compare with, and sweeps (robots
//! solved in order, with the events between steps) and load histories with stick/slip
//! friction.

pub mod comparison;
pub mod equilibrium;
pub mod history;
pub mod samples;
pub mod sweep;
