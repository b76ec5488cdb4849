//! [`Solver`]: a collocation solver that keeps its Newton workspace, the mesh it was built
//! for and the factors of its last Newton matrix between solves.

use super::linear::LinearSolver;
use super::newton::Workspace;
use super::options::Options;
use super::pipeline::solve_impl;
use crate::Robot;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::solution::{Solution, State};

/// The Newton workspace of the last solve, the mesh and linear solver it was built for,
/// and the states that solve ended at (its factors belong to a Jacobian near them).
pub(crate) struct Cached {
    pub(crate) mesh: Mesh,
    pub(crate) solver: LinearSolver,
    pub(crate) workspace: Workspace,
    pub(crate) last: Option<Vec<State>>,
}

/// What a solve may reuse from the one before it: nothing, or its [`Cached`] workspace.
pub(crate) type Cache = Option<Cached>;

/// A collocation solver that keeps its Newton workspace (buffers and, on the sparse path,
/// the pattern and symbolic LU) between solves, so that repeated solves on the same mesh
/// (sweeps, control loops, calibration) skip the setup.
///
/// It also keeps the factors of the last Newton matrix: [`Solver::solve_from`] given the
/// solution this solver just returned (the usual step of a control loop) starts with chord
/// steps on those factors, which for a small change of tensions or loads converge without
/// evaluating a new Jacobian for the iteration; the stability verdict then evaluates one at
/// the solution, since the factors belong to the previous state (docs/stability.md, "Which
/// Jacobian").
pub struct Solver {
    /// The options of every solve.
    pub options: Options,
    cache: Cache,
}

impl Solver {
    /// A solver with these options and an empty cache.
    pub fn new(options: Options) -> Self {
        Solver { options, cache: None }
    }

    /// As [`super::solve`], reusing the workspace of the previous solve when the mesh is
    /// the same.
    ///
    /// # Errors
    /// As [`super::solve`].
    pub fn solve(&mut self, robot: &Robot) -> Result<Solution> {
        solve_impl(robot, &self.options, None, &mut self.cache)
    }

    /// As [`super::solve_from`], reusing the workspace of the previous solve when the mesh
    /// is the same, and its factors when `guess` is the solution it returned.
    ///
    /// # Errors
    /// As [`super::solve`].
    pub fn solve_from(&mut self, robot: &Robot, guess: &Solution) -> Result<Solution> {
        solve_impl(robot, &self.options, Some(guess), &mut self.cache)
    }
}
