//! Analyses of solved shapes: the global equilibrium check, the shape sampled at output arc
//! lengths with its internal wrenches, and simpler models to compare with.

pub mod comparison;
pub mod equilibrium;
pub mod samples;
