//! The solver's internals, for tests, benchmarks and solver research: the model equations
//! and their linearization, meshes and initial guesses, the collocation system, its layout,
//! Newton and the linear solvers. Everyday use needs none of this (the crate root and the
//! layer modules are the surface); names and signatures here may change between versions.
//!
//! # Examples
//! One Newton solve of case S on a 16-interval mesh, by hand:
//! ```
//! use tdcr::advanced::{equations::Model, guess, mesh::Mesh, newton, system::System};
//! use tdcr::collocation::LinearSolver;
//!
//! let robot = tdcr::cases::case_s();
//! let mesh = Mesh::uniform(&robot, 16)?;
//! let system = System::new(Model::new(&robot), mesh);
//! let mut workspace = newton::Workspace::new(&system, LinearSolver::Blocks)?;
//! let mut x = guess::rigid_estimate(&system.model, &system.mesh.nodes);
//! let settings = newton::Settings { tolerance: 1e-11, max_iterations: 30, reuse_factors: false, stop_when_damped: false };
//! let mut report = tdcr::SolveReport::new(tdcr::Method::Collocation);
//! let (termination, _) = newton::run(&system, &mut workspace, &mut x, &settings, &mut report);
//! assert_eq!(termination, tdcr::Termination::Converged);
//! # Ok::<(), tdcr::Error>(())
//! ```

/// Pointwise physics: eq. 13 (corrected), tendon pulls and point wrenches, internal wrench.
pub mod equations {
    pub use crate::model::equations::*;
}

/// Eq. 13 in f64 and its exact linearization.
pub mod linearize {
    pub use crate::model::linearize::*;
}

/// Collocation meshes: nodes with two nodes at every breakpoint.
pub mod mesh {
    pub use crate::mesh::resolution::{self, Feature, MAX_ANGLE, Resolution, required};
    pub use crate::mesh::{Mesh, MeshNode};
}

/// Initial guesses on mesh nodes: the rigid-equilibrium estimate and the unloaded shape.
pub mod guess {
    pub use crate::mesh::guess::*;
}

/// The layout of the collocation system: unknowns, rows, the Jacobian's block pattern.
pub mod unknowns {
    pub use crate::collocation::unknowns::*;
}

/// The collocation system on one mesh: residual, exact Jacobian, and the order-6 residual
/// of the error estimate.
pub mod system {
    pub use crate::collocation::system::*;
}

/// The order-6 answer of tight tolerances: the deferred-corrected solution on one mesh with
/// its estimate (docs/numerics.md, "The order-6 answer").
pub mod deferred {
    pub use crate::collocation::deferred::{ROUNDING, SAFETY, corrected};
}

/// The residual blocks (base, intervals, jumps, tip).
pub mod residual {
    pub use crate::collocation::residual::*;
}

/// Damped Newton with chord steps, and its workspace.
pub mod newton {
    pub use crate::collocation::newton::*;
}
