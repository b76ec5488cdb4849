//! Analyses of solved shapes: the global equilibrium check and simpler models to compare
//! with.

pub mod comparison;
pub mod equilibrium;
