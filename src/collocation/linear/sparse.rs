//! faer's general sparse LU on the collocation Jacobian: the reference linear solver.
//!
//! The pattern, the map from assembly order to storage, the symbolic LU (COLAMD ordering,
//! elimination tree) and the scratch memory are built once per mesh; each factorization
//! refills the values and refactors numerically without allocating. faer reports only
//! structurally singular matrices, so the factorization runs under `catch_unwind` in case a
//! faer version panics on a zero pivot, and callers check every solution for finiteness (a
//! numerically zero pivot shows up as inf/NaN).

use crate::collocation::unknowns::{pattern, unknowns};
use crate::error::{Result, invalid};
use crate::mesh::Mesh;
use faer::col::ColMut;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::{LuSymbolicParams, NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Par};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

/// faer's sparse LU with the pattern, value slots and symbolic factorization of one mesh.
pub(crate) struct SparseLu {
    matrix: SparseColMat<usize, f64>,
    slots: Vec<usize>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    mem: MemBuffer,
}

impl SparseLu {
    /// The pattern, value slots, symbolic LU and scratch for `mesh`.
    pub(crate) fn new(mesh: &Mesh) -> Result<Self> {
        let n = unknowns(mesh.nodes.len());
        let pat = pattern(mesh);
        let triplets: Vec<Triplet<usize, usize, f64>> = pat.iter().map(|&(r, c)| Triplet::new(r, c, 1.0)).collect();
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).map_err(|e| {
            invalid(
                "mesh",
                format!("gives an invalid sparsity pattern ({e:?})"),
                "report this as a bug",
            )
        })?;
        let (cp, ri) = (matrix.symbolic().col_ptr(), matrix.symbolic().row_idx());
        let slots = pat
            .iter()
            .map(|&(r, c)| cp[c] + ri[cp[c]..cp[c + 1]].binary_search(&r).unwrap_or(0))
            .collect();
        // Simplicial LU: no allocation per refactorization (the supernodal path allocates per call).
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_lu(matrix.symbolic(), params)
            .map_err(|e| invalid("mesh", format!("symbolic LU failed ({e:?})"), "report this as a bug"))?;
        let req = symbolic
            .factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq))
            .or(symbolic.solve_transpose_in_place_scratch::<f64>(1, Par::Seq));
        Ok(SparseLu {
            matrix,
            slots,
            symbolic,
            numeric: NumericLu::new(),
            mem: MemBuffer::new(req),
        })
    }

    /// Refills the values, factorizes and solves in place; None on a zero pivot (or a panic
    /// inside faer), else the factorization and solve times.
    pub(crate) fn solve(&mut self, values: &[f64], x: &mut [f64]) -> Option<(Duration, Duration)> {
        for (slot, v) in self.slots.iter().zip(values) {
            self.matrix.val_mut()[*slot] = *v;
        }
        let SparseLu {
            matrix,
            symbolic,
            numeric,
            mem,
            ..
        } = self;
        catch_unwind(AssertUnwindSafe(|| {
            let t = Instant::now();
            let lu = symbolic
                .factorize_numeric_lu(
                    numeric,
                    matrix.as_ref(),
                    Par::Seq,
                    MemStack::new(mem),
                    Default::default(),
                )
                .ok()?;
            let factor_time = t.elapsed();
            let t = Instant::now();
            lu.solve_in_place_with_conj(
                Conj::No,
                ColMut::from_slice_mut(x).as_mat_mut(),
                Par::Seq,
                MemStack::new(mem),
            );
            Some((factor_time, t.elapsed()))
        }))
        .ok()
        .flatten()
    }

    /// Solves in place with the numeric factors of the last successful [`SparseLu::solve`].
    pub(crate) fn solve_again(&mut self, x: &mut [f64]) {
        self.solve_factored(x, false);
    }

    /// Solves J^T y = c in place (`x` holds c, then y) with the numeric factors of the last
    /// successful [`SparseLu::solve`].
    pub(crate) fn solve_transposed(&mut self, x: &mut [f64]) {
        self.solve_factored(x, true);
    }

    /// J x = b, or J^T x = b when `transpose`, in place with the stored factors.
    fn solve_factored(&mut self, x: &mut [f64], transpose: bool) {
        let SparseLu {
            symbolic, numeric, mem, ..
        } = self;
        let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(symbolic, numeric);
        // A panic here would mean no factorization was made: report it as non-finite.
        let solved = catch_unwind(AssertUnwindSafe(|| {
            let rhs = ColMut::from_slice_mut(x).as_mat_mut();
            let stack = MemStack::new(mem);
            if transpose {
                lu.solve_transpose_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
            } else {
                lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
            }
        }));
        if solved.is_err() {
            x.fill(f64::NAN);
        }
    }
}
