//! # tdcr: statics of tendon-driven continuum robots
//!
//! The coupled Cosserat-rod / Cosserat-string model of Rucker & Webster ("Mechanics of
//! Continuum Robots with External Loading and General Tendon Routing"), with the
//! corrections of docs/model.md, solved either by sparse collocation (the main solver) or
//! by shooting (an independent cross-check).
#![warn(missing_docs)]

pub mod calibration;
pub mod cases;
pub mod collocation;
pub mod equations;
pub mod equilibrium;
pub mod error;
pub mod guess;
pub mod inverse;
pub mod io;
pub mod linearize;
pub mod loads;
pub mod mesh;
pub mod models;
pub mod plot;
pub mod report;
pub mod robot;
pub mod rod;
pub mod routing;
pub mod sensitivity;
pub mod shooting;
pub mod so3;
pub mod solution;
pub mod tendon;

pub use error::{Error, Result};
pub use loads::{Field, Loads, PointLoad};
pub use report::{Method, SolveReport, Termination};
pub use robot::{Robot, TendonModel};
pub use rod::{Rod, Section};
pub use routing::{Routing, RoutingPoint};
pub use solution::{Node, Solution, State};
pub use tendon::Tendon;

/// The scalar types the model equations accept: f64, and num-dual's dual numbers for exact
/// derivatives.
pub trait Real: nalgebra::RealField + Copy {}
impl<T: nalgebra::RealField + Copy> Real for T {}

/// The README's example is compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
