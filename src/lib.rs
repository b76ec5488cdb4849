//! # tdcr: statics of tendon-driven continuum robots
//!
//! The coupled Cosserat-rod / Cosserat-string model of Rucker & Webster ("Mechanics of
//! Continuum Robots with External Loading and General Tendon Routing"), with the
//! corrections of docs/model.md, solved either by sparse collocation (the main solver) or
//! by shooting (an independent cross-check).
#![warn(missing_docs)]

pub mod analysis;
pub mod cases;
pub mod collocation;
pub mod error;
pub mod fit;
pub mod io;
pub mod mesh;
pub mod model;
pub mod plot;
pub mod report;
pub mod shooting;
pub mod so3;
pub mod solution;

pub use error::{Error, Result};
pub use model::loads::{Field, Loads, PointLoad};
pub use model::robot::{Robot, TendonModel};
pub use model::rod::{Rod, Section};
pub use model::routing::{Routing, RoutingPoint};
pub use model::tendon::Tendon;
pub use report::{Method, SolveReport, Termination};
pub use solution::{Node, Solution, State};

/// The scalar types the model equations accept: f64, and num-dual's dual numbers for exact
/// derivatives.
pub trait Real: nalgebra::RealField + Copy {}
impl<T: nalgebra::RealField + Copy> Real for T {}

/// The README's example is compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
