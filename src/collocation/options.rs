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

/// The default tip tolerance, relative to the rod length: the tip position to 1e-7 L and the
/// tip orientation to 1e-7 rad (0.024 um and 0.1 urad on the paper's 0.242 m prototype),
/// well below any measurement of a continuum robot and far above rounding (about 1e-13 L
/// on these meshes), so the default answer can serve as a reference in benchmarks.
pub const DEFAULT_TOLERANCE: f64 = 1e-7;

/// Which of several equilibria a solve returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Equilibrium {
    /// The state the robot reaches when its loads grow from zero (the load path), which
    /// Newton's answer is checked against: a clean Newton run to a state that is not
    /// unstable stands; otherwise the load path is followed.
    #[default]
    LoadPath,
    /// The equilibrium Newton converges to from the initial guess or warm start, whatever
    /// its stability (reported).
    Nearest,
}

/// Collocation options. By default every solve is error-controlled (the tip to
/// [`DEFAULT_TOLERANCE`]); [`Options::fixed`] solves on a fixed mesh, still with an error
/// estimate in the report. `Options { tolerance: Some(1e-9), ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Mesh intervals (spread over the segments between breakpoints). Without `tolerance`
    /// the mesh is fixed; with it, the fewest intervals of the starting mesh, which gets more
    /// where the initial guess bends sharply. Default 32.
    pub intervals: usize,
    /// Explicit mesh points (m); when given they replace `intervals` (breakpoints, 0 and L
    /// are added). Default `None`.
    pub mesh: Option<Vec<f64>>,
    /// Tip tolerance relative to the rod length (dimensionless): the estimated tip position
    /// error is brought to at most `tolerance` x L and the tip orientation error to at most
    /// `tolerance` rad by re-meshing. `None` solves on the given mesh only (and still
    /// estimates the error). Default `Some(`[`DEFAULT_TOLERANCE`]`)`.
    pub tolerance: Option<f64>,
    /// Cap on intervals: the starting mesh must not exceed it and refinement stops at it.
    /// Default 8192; at most [`MAX_INTERVALS`].
    pub max_intervals: usize,
    /// Newton stops when the scaled residual max-norm is at or below this (dimensionless).
    /// Default 1e-11 (a few hundred times rounding of O(1) scaled quantities).
    pub residual_tolerance: f64,
    /// Newton iterations per Newton run (each mesh; the first try from the guess and the
    /// landing of a load path take at most 12 of them, unless `equilibrium` is
    /// [`Equilibrium::Nearest`] for the first try). Default 30; at most [`MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// Follow a path when Newton from the guess fails or does not end cleanly on a stable
    /// state (or, for loads with no verdict, one of unknown stability): from a warm start the Newton homotopy, else the load path from
    /// the unloaded robot (docs/stability.md). `false` returns Newton's answer from the
    /// guess, whatever its stability, or an error. Default true.
    pub continuation: bool,
    /// Which equilibrium to return. Default [`Equilibrium::LoadPath`].
    pub equilibrium: Equilibrium,
    /// Where Newton starts without a warm start. Default: the rigid-equilibrium estimate.
    pub initial_guess: InitialGuess,
    /// The linear solver for Newton steps. Default: `Blocks` (the structured elimination).
    pub linear_solver: LinearSolver,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            intervals: 32,
            mesh: None,
            tolerance: Some(DEFAULT_TOLERANCE),
            max_intervals: 8192,
            residual_tolerance: 1e-11,
            max_iterations: 30,
            continuation: true,
            equilibrium: Equilibrium::LoadPath,
            initial_guess: InitialGuess::RigidEquilibrium,
            linear_solver: LinearSolver::Blocks,
        }
    }
}

impl Options {
    /// Options for a fixed mesh of `intervals` intervals: no error control (the report
    /// still carries the error estimate), everything else at its default.
    pub fn fixed(intervals: usize) -> Self {
        Options {
            intervals,
            tolerance: None,
            ..Default::default()
        }
    }

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
                format!("is {}", Readable(tol)),
                "give a positive tip tolerance relative to the rod length (1e-7 is the default), or None for a fixed mesh",
            ));
        }
        Ok(())
    }
}
