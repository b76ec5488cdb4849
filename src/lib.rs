//! # tdcr: statics of tendon-driven continuum robots
//!
//! The coupled Cosserat-rod / Cosserat-string model of Rucker & Webster ("Mechanics of
//! Continuum Robots with External Loading and General Tendon Routing"; full citation,
//! prototype data and the list of corrections in docs/reference.md), with the
//! corrections of docs/model.md, solved either by sparse collocation (the main solver) or
//! by shooting (an independent cross-check). SI units throughout (m, N, Pa, rad).
//!
//! # Quick start
//! ```
//! use tdcr::nalgebra::Vector3;
//! use tdcr::{Loads, Robot, Rod, Routing, Tendon};
//!
//! // A 0.242 m nitinol-like rod (radius 0.4 mm, E = 210 GPa, Poisson 0.3125) with one
//! // straight tendon 8 mm off the centreline pulled at 3 N, under its own weight.
//! let robot = Robot::new(Rod::solid_circle(0.242, 0.0004, 210e9, 0.3125))
//!     .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 3.0))
//!     .with_loads(Loads::self_weight(0.47, -Vector3::z()));
//! let solution = tdcr::solve(&robot, &Default::default())?;
//! let tip = solution.tip_position();
//! assert!(solution.report.termination == tdcr::Termination::Converged);
//! assert!(tip.norm() < 0.242);
//! // d(tip pose)/d(tension), the tip compliance and more, from one factorization.
//! let sensitivities = tdcr::tip_sensitivities(&robot, &solution)?;
//! assert_eq!(sensitivities.tension.ncols(), 1);
//! # Ok::<(), tdcr::Error>(())
//! ```
//!
//! # Where things are
//! - The robot: [`Robot`] and its parts ([`Rod`], [`Tendon`] with a [`Routing`], [`Loads`]),
//!   all in [`model`]; the paper's prototype and reference cases in [`cases`].
//! - Solving: [`solve`], [`solve_from`], [`solve_batch`] and [`Solver`] (collocation, the main
//!   solver, with its [`collocation::Options`]); [`shooting`] (the cross-check).
//! - Results: [`Solution`] (nodes, tendon paths, tip pose, [`Solution::at`]) with its
//!   [`SolveReport`]; failures are an [`Error`].
//! - Analyses: sensitivities ([`tip_sensitivities`], [`collocation::sensitivity`]), global
//!   equilibrium and model comparisons ([`analysis`]), inverse statics and calibration
//!   ([`fit`]).
//! - Files and pictures: robot files, experiment CSVs and result files ([`io`]), SVG and PNG
//!   plots (`plot`); rotations ([`so3`]).
//!
//! # Features
//! The solver needs none of the optional features; `default-features = false` builds it
//! without clap, resvg and toml. `files`: robot files (TOML: `io::parse`, `io::example`, the
//! problem locator). `plot`: the `plot` module (SVG, PNG through resvg). `cli` (default): the
//! `tdcr` command, with both.
//! - Internals for tests and solver research: [`advanced`].
//!
//! docs/architecture.md in the repository describes the layers and where new code goes.
#![warn(missing_docs)]

pub mod advanced;
pub mod analysis;
pub mod cases;
pub mod collocation;
mod dense;
mod error;
pub mod fit;
pub mod io;
mod mesh;
pub mod model;
#[cfg(feature = "plot")]
pub mod plot;
mod report;
pub mod shooting;
mod simd;
pub mod so3;
mod solution;

pub use collocation::sensitivity::{TipSensitivities, backbone_tension_sensitivity, tip_sensitivities};
pub use collocation::{Solver, solve, solve_batch, solve_from};
pub use error::{Error, Readable, Result};
pub use model::disks::Disks;
pub use model::loads::{Field, Loads, PointLoad};
pub use model::parameter::Parameter;
pub use model::robot::{Robot, RodModel, TendonModel};
pub use model::rod::{Rod, Section, Segment};
pub use model::routing::{Routing, RoutingPoint};
pub use model::tendon::{Actuation, Friction, Motion, Tendon};
pub use nalgebra;
pub use report::{
    ErrorEstimate, Evaluations, Growth, Iteration, Method, PathTaken, SolveReport, Stability, Termination, Timings,
};
pub use solution::{Node, Solution, State, TendonState};

/// The scalar types the model equations accept: f64, and num-dual's dual numbers for exact
/// derivatives.
pub trait Real: nalgebra::RealField + Copy {}
impl<T: nalgebra::RealField + Copy> Real for T {}

/// The README's example is compiled and run as a doctest.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
