//! The linear solvers behind Newton's steps, both for the collocation Jacobian with values
//! in [`crate::collocation::unknowns::pattern`] order: the structured elimination of
//! [`blocks`] (the default) and faer's sparse LU of `sparse` (the general reference path,
//! feature `sparse-lu`). Each keeps its factors, so further right-hand sides cost a re-solve
//! only.

pub mod blocks;
#[cfg(feature = "sparse-lu")]
pub mod sparse;

use crate::collocation::unknowns::NODE;
use crate::error::Result;
use crate::mesh::Mesh;
use blocks::BlockElimination;
#[cfg(feature = "sparse-lu")]
use sparse::SparseLu;
use std::time::Duration;

/// The linear solver behind Newton's steps. Non-exhaustive: the feature `sparse-lu` adds
/// `LinearSolver::SparseLu`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum LinearSolver {
    /// The structured almost-block-diagonal elimination (`collocation/linear/blocks.rs`):
    /// the collocation Jacobian always has that structure, so this is the default.
    #[default]
    Blocks,
    /// faer's general sparse LU (COLAMD ordering, simplicial), the reference path (feature
    /// `sparse-lu`).
    #[cfg(feature = "sparse-lu")]
    SparseLu,
}

/// A linear solver built for one mesh.
pub(crate) enum Linear {
    /// faer's sparse LU.
    #[cfg(feature = "sparse-lu")]
    Sparse(Box<SparseLu>),
    /// The structured elimination.
    Blocks(Box<BlockElimination>),
}

impl Linear {
    /// The solver `kind` with its buffers (and, for the sparse LU, symbolic factors) for `mesh`.
    pub(crate) fn new(mesh: &Mesh, kind: LinearSolver) -> Result<Self> {
        Ok(match kind {
            LinearSolver::Blocks => Linear::Blocks(Box::new(BlockElimination::new(mesh.nodes.len()))),
            #[cfg(feature = "sparse-lu")]
            LinearSolver::SparseLu => Linear::Sparse(Box::new(SparseLu::new(mesh)?)),
        })
    }

    /// Factors the matrix with these `values` and solves J x = rhs. None on a zero pivot,
    /// else the factorization and solve times.
    pub(crate) fn solve(&mut self, values: &[f64], rhs: &[f64], x: &mut [f64]) -> Option<(Duration, Duration)> {
        match self {
            #[cfg(feature = "sparse-lu")]
            Linear::Sparse(lu) => {
                x.copy_from_slice(rhs);
                lu.solve(values, x)
            }
            Linear::Blocks(blocks) => blocks.solve(values, rhs, x),
        }
    }

    /// Factors the matrix with these `values` and gives the last node's unknowns of
    /// J x = rhs_j for the `count` right-hand sides in `rhs` (column-major) into `last`, as
    /// [`BlockElimination::factor_with_last`]: Some(false) on a zero pivot; None (nothing
    /// done) for the sparse LU or more than [`blocks::CARRIED`] right-hand sides.
    pub(crate) fn factor_with_last(
        &mut self,
        values: &[f64],
        rhs: &[f64],
        count: usize,
        last: &mut [[f64; NODE]],
    ) -> Option<bool> {
        match self {
            Linear::Blocks(blocks) if count <= blocks::CARRIED => {
                Some(blocks.factor_with_last(values, rhs, count, last))
            }
            _ => None,
        }
    }

    /// Solves J x = rhs with the factors of the last successful [`Linear::solve`]; the
    /// caller checks x for finiteness.
    pub(crate) fn solve_again(&mut self, rhs: &[f64], x: &mut [f64]) {
        match self {
            Linear::Blocks(blocks) => blocks.solve_again(rhs, x),
            #[cfg(feature = "sparse-lu")]
            Linear::Sparse(lu) => {
                x.copy_from_slice(rhs);
                lu.solve_again(x);
            }
        }
    }

    /// The last node's 12 unknowns of J x = rhs with the factors of the last successful
    /// [`Linear::solve`] (the structured elimination skips the back substitution through
    /// the other nodes); the caller checks them for finiteness. `x` is scratch for the
    /// sparse LU, which solves for every unknown.
    #[cfg_attr(not(feature = "sparse-lu"), allow(unused_variables))]
    pub(crate) fn solve_again_last(&mut self, rhs: &[f64], x: &mut [f64]) -> [f64; NODE] {
        match self {
            Linear::Blocks(blocks) => blocks.solve_again_last(rhs),
            #[cfg(feature = "sparse-lu")]
            Linear::Sparse(lu) => {
                x.copy_from_slice(rhs);
                lu.solve_again(x);
                std::array::from_fn(|i| x[x.len() - NODE + i])
            }
        }
    }

    /// Solves J^T y = c with the factors of the last successful [`Linear::solve`] (the
    /// adjoint solve); the caller checks y for finiteness.
    pub(crate) fn solve_transposed(&mut self, c: &[f64], y: &mut [f64]) {
        match self {
            Linear::Blocks(blocks) => blocks.solve_transposed(c, y),
            #[cfg(feature = "sparse-lu")]
            Linear::Sparse(lu) => {
                y.copy_from_slice(c);
                lu.solve_transposed(y);
            }
        }
    }
}
