//! The robot and its pointwise physics: plain data (rod, tendon routings, tendons, loads,
//! the robot) validated once, and eq. 13 (corrected, docs/model.md) with its exact
//! linearization.

pub mod disks;
pub(crate) mod equations;
pub mod friction;
pub mod length;
pub(crate) mod linearize;
pub mod loads;
pub mod parameter;
mod plausibility;
pub(crate) mod pull_in;
pub mod robot;
pub mod rod;
pub mod routing;
pub mod scales;
mod tangential;
pub mod tendon;
pub(crate) mod tension_guess;
