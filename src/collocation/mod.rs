//! The collocation solver: the whole robot as one sparse Newton system solved with faer.
//!
//! Stages, in the order data flows (one module each):
//! 1. [`Options`] (`options.rs`), checked by [`Options::validate`]; [`Mesh`](crate::mesh::Mesh): nodes on
//!    [0, L] with two nodes at every breakpoint.
//! 2. [`unknowns`](crate::advanced::unknowns): the layout of unknowns and rows, the Jacobian's block pattern.
//! 3. [`residual`](crate::advanced::residual) and [`system`](crate::advanced::system): residual rows (base, Hermite-Simpson intervals in
//!    Lie-group local coordinates, jump conditions, tip) and their exact Jacobian (chain
//!    rule through the scheme with the analytic linearization of eq. 13; AD for the few
//!    other blocks).
//! 4. `linear`: the structured elimination of `linear/blocks.rs` (automatic) or faer's
//!    sparse LU (`linear/sparse.rs`); [`newton`](crate::advanced::newton): damped Newton with chord steps on stored factors, every buffer
//!    (and the symbolic LU) built once per mesh.
//! 5. Robustness and the equilibrium choice (`start.rs`, `equilibrium.rs`):
//!    rigid-equilibrium initial guess or a warm start; Newton's answer stands when it converged cleanly to a state that is not
//!    unstable, else a path is followed (`path.rs`: the Newton homotopy from a warm start,
//!    the load path from the unloaded robot); every answer gets a stability verdict
//!    (`stability.rs`, docs/stability.md). Displacement-controlled tendons are solved by
//!    `actuation.rs`.
//! 6. Error control: every converged mesh gets a deferred-correction error estimate
//!    (`estimate.rs`, one order-6 residual and one solve with Newton's factors); by default
//!    (`refine.rs`) the starting mesh resolves the initial guess and the mesh is
//!    re-distributed until the estimated tip error meets the tolerance.
//! 7. [`sensitivity`]: derivatives of the converged solution by the implicit function
//!    theorem, from one factorization.
//!
//! `pipeline.rs` runs these stages for one solve; [`Solver`] (`solver.rs`) keeps the
//! workspace between solves; [`solve_batch`] and [`solve_rows`] (`batch.rs`) solve
//! independent rows on all cores with one `Solver` per worker thread; [`trace`] follows a branch of equilibria in one input.
//!
//! docs/numerics.md documents the scheme (order 4), the scaling, the stopping tests and the
//! load path.

pub(crate) mod actuation;
mod batch;
mod branch;
pub(crate) mod constrained;
mod corrector;
pub(crate) mod deferred;
pub(crate) mod dynamics;
mod end_rows;
mod ends;
mod equilibrium;
mod estimate;
pub(crate) mod friction;
mod homotopy;
mod interval_jacobian;
mod interval_kept;
mod interval_lanes;
pub(crate) mod linear;
mod locate;
mod neutral;
pub(crate) mod newton;
mod options;
mod order6;
mod order8;
mod path;
mod path_index;
mod path_types;
mod phase;
mod pipeline;
mod point;
pub(crate) mod refine;
mod relax;
pub(crate) mod residual;
pub mod sensitivity;
mod snap;
mod solver;
pub(crate) mod stability;
mod stage;
mod start;
pub(crate) mod system;
#[cfg(test)]
mod test_support;
mod trace;
pub(crate) mod unknowns;
mod workspace;

use crate::Robot;
use crate::error::Result;
pub use crate::mesh::guess::InitialGuess;
use crate::mesh::guess::interpolate;
use crate::solution::Solution;
pub use batch::{solve_batch, solve_rows};
pub use dynamics::{DENSITY, MODULUS, Vibration, vibration};
pub use linear::LinearSolver;
pub use options::{DEFAULT_TOLERANCE, Equilibrium, MAX_INTERVALS, MAX_ITERATIONS, Options};
use pipeline::{Level, record_estimate, segment_ends, solve_stateless};
pub use solver::Solver;
use solver::{Cache, Cached};
use start::{cold_start, initial_mesh, resolves};
pub use trace::{Trace, TraceEvent, TracePoint, trace, trace_until};

/// Solves `robot` by collocation from the rigid-equilibrium initial guess.
///
/// # Errors
/// Invalid input, [`crate::Error::NotConverged`] (with the report and where the residual is
/// largest), [`crate::Error::IntervalCap`] when refinement cannot meet the tolerance.
///
/// # Examples
/// ```
/// let robot = tdcr::cases::case_s();
/// let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
/// let tip = solution.tip_position();
/// assert!((tip.x - 0.151823122).abs() < 1e-6);
/// ```
pub fn solve(robot: &Robot, options: &Options) -> Result<Solution> {
    solve_stateless(robot, options, None)
}

/// Solves `robot` starting from a previous solution (of this or a nearby robot), which is
/// interpolated onto the new mesh if the meshes differ.
///
/// # Errors
/// As [`solve`].
pub fn solve_from(robot: &Robot, options: &Options, guess: &Solution) -> Result<Solution> {
    solve_stateless(robot, options, Some(guess))
}

/// [`solve_from`], but a solve that starts from `guess` keeps to its branch: where the load
/// path it falls back to loses stability at a bifurcation or cannot be followed to the end,
/// it neither snaps nor lands from a fold, and returns the state on that branch (unstable)
/// or Newton's root (`fallback`). What a sweep's bisection solves (`analysis::sweep`), so that
/// it sees where the branch of the last point before a change ends or loses stability
/// (docs/stability.md, "Snapping from a bifurcation").
///
/// # Errors
/// As [`solve`].
pub(crate) fn solve_on_branch(robot: &Robot, options: &Options, guess: &Solution) -> Result<Solution> {
    pipeline::solve_on_branch(robot, options, guess)
}

/// Checks that the mesh `options` fix resolves `robot` (validated) by the resolution rule
/// (at most pi/2 rad of a routing's turn or of the precurvature per interval, docs/numerics.md
/// "Resolution"): what [`solve`] checks before it iterates, for a caller (such as `tdcr
/// check`) that wants the verdict without solving. Options with a `tolerance` pass: their mesh
/// is only the start of refinement.
///
/// # Errors
/// [`crate::Error::InvalidInput`] on `options.intervals` (`options.mesh` for explicit points) with
/// the intervals that would resolve the robot, or for a mesh that cannot be built.
pub fn check_resolution(robot: &Robot, options: &Options) -> Result<()> {
    if options.tolerance.is_some() {
        return Ok(());
    }
    resolves(robot, options, &initial_mesh(robot, options, None)?)
}
