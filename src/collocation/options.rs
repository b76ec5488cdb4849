//! The collocation solver's options: mesh, error control, Newton and the linear solver.

use super::linear::LinearSolver;
use crate::Readable;
use crate::error::{Result, invalid};
use crate::mesh::guess::InitialGuess;

/// The most intervals any mesh may have: memory grows by about 5 kB per interval (Jacobian
/// values and elimination panels), so this is about 0.5 GB.
pub const MAX_INTERVALS: usize = 100_000;

/// The most Newton iterations a solve may be given (`max_iterations` of both solvers): the
/// solvers reserve one history record per allowed iteration, and Newton converges
/// quadratically in a few dozen iterations or not at all, so more only costs memory.
pub const MAX_ITERATIONS: usize = 10_000;

/// Collocation options. `Options { intervals: 64, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Mesh intervals (spread over the segments between breakpoints). Without `tolerance`
    /// the mesh is fixed; with it, this is the starting mesh. Default 32.
    pub intervals: usize,
    /// Explicit mesh points (m); when given they replace `intervals` (breakpoints, 0 and L
    /// are added). Default `None`.
    pub mesh: Option<Vec<f64>>,
    /// Tip position tolerance (m) for adaptive refinement; `None` solves on the given mesh
    /// only. Default `None`.
    pub tolerance: Option<f64>,
    /// Cap on intervals: the starting mesh must not exceed it and refinement stops at it.
    /// Default 8192; at most [`MAX_INTERVALS`].
    pub max_intervals: usize,
    /// Newton stops when the scaled residual max-norm is at or below this (dimensionless).
    /// Default 1e-11 (a few hundred times rounding of O(1) scaled quantities).
    pub residual_tolerance: f64,
    /// Newton iterations per solve (per load step with continuation). Default 30; at most
    /// [`MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// Use load continuation when the direct solve fails. Default true.
    pub continuation: bool,
    /// Where Newton starts without a warm start. Default: the rigid-equilibrium estimate.
    pub initial_guess: InitialGuess,
    /// The linear solver for Newton steps. Default: automatic (the structured elimination).
    pub linear_solver: LinearSolver,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            intervals: 32,
            mesh: None,
            tolerance: None,
            max_intervals: 8192,
            residual_tolerance: 1e-11,
            max_iterations: 30,
            continuation: true,
            initial_guess: InitialGuess::RigidEquilibrium,
            linear_solver: LinearSolver::Auto,
        }
    }
}

impl Options {
    /// Checks the options that do not depend on the robot: positive tolerances, from one to
    /// [`MAX_ITERATIONS`] Newton iterations, the starting mesh within `max_intervals` and that within
    /// [`MAX_INTERVALS`].
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] naming the field (`options.intervals`, ...), its value
    /// and what to try.
    pub fn validate(&self) -> Result<()> {
        if self.residual_tolerance.is_nan() || self.residual_tolerance <= 0.0 || self.max_iterations == 0 {
            return Err(invalid(
                "options",
                "needs residual_tolerance > 0 and max_iterations >= 1",
                "use Options::default() and change single fields",
            ));
        }
        if self.max_iterations > MAX_ITERATIONS {
            return Err(invalid(
                "options.max_iterations",
                format!("is {}, above the limit of {MAX_ITERATIONS}", self.max_iterations),
                "Newton converges in a few dozen iterations or not at all, so more only costs memory; the default is 30",
            ));
        }
        if self.max_intervals > MAX_INTERVALS {
            return Err(invalid(
                "options.max_intervals",
                format!("is {}, above the limit of {MAX_INTERVALS}", self.max_intervals),
                "memory grows by about 5 kB per interval; use a tip tolerance instead of a huge mesh",
            ));
        }
        let requested = self.mesh.as_ref().map_or(self.intervals, Vec::len);
        if requested > self.max_intervals {
            return Err(invalid(
                "options.intervals",
                format!("is {requested}, above `max_intervals` = {}", self.max_intervals),
                format!("raise `max_intervals` (at most {MAX_INTERVALS}) or use fewer intervals"),
            ));
        }
        if let Some(tol) = self.tolerance
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(invalid(
                "options.tolerance",
                format!("is {} m", Readable(tol)),
                "give a positive tip tolerance in m",
            ));
        }
        Ok(())
    }
}
