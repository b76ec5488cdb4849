//! The 6x6 matrix M of eq. 13 factored once per point by its 3x3 blocks (docs/model.md,
//! sections 4 and 4b): block elimination for the Cosserat rod's SPD M and the Kirchhoff
//! rod's block-triangular M, LU where rounding makes the SPD test fail.
#![allow(non_snake_case)]

use nalgebra::{LU, Matrix3, Matrix6, SMatrix, U6};

/// The inverse of a symmetric positive definite 3x3 matrix by its adjugate, or None when a
/// leading principal minor is not positive (not SPD, singular or NaN: by Sylvester's
/// criterion exactly when a Cholesky factorization would meet a non-positive pivot).
fn spd_inverse3(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let c00 = a[(1, 1)] * a[(2, 2)] - a[(1, 2)] * a[(1, 2)];
    let c01 = a[(0, 2)] * a[(1, 2)] - a[(0, 1)] * a[(2, 2)];
    let c02 = a[(0, 1)] * a[(1, 2)] - a[(0, 2)] * a[(1, 1)];
    let minor2 = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(0, 1)];
    let det = a[(0, 0)] * c00 + a[(0, 1)] * c01 + a[(0, 2)] * c02;
    // `!(x > 0)` also rejects NaN.
    if !(a[(0, 0)] > 0.0 && minor2 > 0.0 && det > 0.0 && det.is_finite()) {
        return None;
    }
    let c11 = a[(0, 0)] * a[(2, 2)] - a[(0, 2)] * a[(0, 2)];
    let c12 = a[(0, 2)] * a[(0, 1)] - a[(0, 0)] * a[(1, 2)];
    let inv = 1.0 / det;
    Some(Matrix3::new(c00, c01, c02, c01, c11, c12, c02, c12, minor2) * inv)
}

/// The 3x3 block of `M` at row `r`, column `c`, copied entry by entry: `into_owned()` of a
/// view stayed a call to nalgebra's allocator (about 120 instructions) in the interval
/// Jacobian's AVX2 build, two per point (docs/benchmarks.md, "The interval block (row14)").
#[inline(always)]
fn block3(M: &Matrix6<f64>, r: usize, c: usize) -> Matrix3<f64> {
    Matrix3::new(
        M[(r, c)],
        M[(r, c + 1)],
        M[(r, c + 2)],
        M[(r + 1, c)],
        M[(r + 1, c + 1)],
        M[(r + 1, c + 2)],
        M[(r + 2, c)],
        M[(r + 2, c + 1)],
        M[(r + 2, c + 2)],
    )
}

/// M = [P, G; rho G^T, Q] (3x3 blocks, P and Q symmetric; rho = 1, M symmetric positive
/// definite, on a Cosserat rod, rho = 0, M block triangular, on a Kirchhoff rod) factored by
/// block elimination: P^-1, W = P^-1 G and the inverse of the Schur complement
/// S = Q - rho G^T P^-1 G, each 3x3 inverse by its adjugate. For rho = 1, M is SPD exactly
/// when P and S are, so this succeeds exactly when a Cholesky factorization would (up to
/// rounding). It has
/// two independent divisions and no square roots on its dependency chain; replacing a 6x6
/// Cholesky written out for the fixed size (six dependent square roots) by it took a warm
/// solve of case H from 256 to 203 us on the development machine.
#[derive(Clone)]
pub(super) struct Schur6 {
    P_inv: Matrix3<f64>,
    G: Matrix3<f64>,
    W: Matrix3<f64>,
    S_inv: Matrix3<f64>,
    /// rho = 1 (true) or 0.
    coupled: bool,
}

impl Schur6 {
    /// Factors M (reads its upper-left, upper-right and lower-right blocks; the lower-left
    /// is G^T when `coupled`, else 0); None when P or S is not SPD.
    #[inline(always)]
    fn new(M: &Matrix6<f64>, coupled: bool) -> Option<Self> {
        let P_inv = spd_inverse3(&block3(M, 0, 0))?;
        let G = block3(M, 0, 3);
        let W = P_inv * G;
        let S_inv = if coupled {
            let S = M.fixed_view::<3, 3>(3, 3) - G.tr_mul(&W);
            // S is symmetric; average out the rounding of the product.
            spd_inverse3(&((S + S.transpose()) * 0.5))?
        } else {
            spd_inverse3(&block3(M, 3, 3))?
        };
        Some(Schur6 {
            P_inv,
            G,
            W,
            S_inv,
            coupled,
        })
    }

    /// Overwrites the rows of `bt` with those of bt M^-T, i.e. solves M X = B for B = bt^T
    /// (P, Q and S are symmetric): with rows (b_v, b_u), w = b_v P^-1,
    /// x_u = (b_u - rho w G) S^-1, x_v = w - x_u W^T.
    ///
    /// Written out on the columns of `bt`, each product entry summed as nalgebra's C x 3 by
    /// 3 x 3 product sums it (the k = 0 term, then the k = 1 and k = 2 terms added in turn)
    /// and each difference taken entry by entry, so the bits of the nalgebra expressions it
    /// replaces; so that it inlines where the caller is compiled for AVX2 (the interval
    /// Jacobian), where nalgebra's `from_fn` and subtraction stayed calls compiled for the
    /// baseline (docs/benchmarks.md, "A batch row: dual lanes, guess sweeps, eq. 13's solve").
    #[inline(always)]
    fn solve_transposed_mut<const C: usize>(&self, bt: &mut SMatrix<f64, C, 6>) {
        let b = bt.as_mut_slice(); // column-major: column c is b[c * C..(c + 1) * C]
        let (P, G, S, W) = (&self.P_inv, &self.G, &self.S_inv, &self.W);
        let mut w = [[0.0; C]; 3];
        for (j, wj) in w.iter_mut().enumerate() {
            for (i, x) in wj.iter_mut().enumerate() {
                *x = b[i] * P[(0, j)] + b[C + i] * P[(1, j)] + b[2 * C + i] * P[(2, j)];
            }
        }
        // y = b_u - rho w G
        let mut y = [[0.0; C]; 3];
        for (j, yj) in y.iter_mut().enumerate() {
            for (i, x) in yj.iter_mut().enumerate() {
                *x = if self.coupled {
                    b[(3 + j) * C + i] - (w[0][i] * G[(0, j)] + w[1][i] * G[(1, j)] + w[2][i] * G[(2, j)])
                } else {
                    b[(3 + j) * C + i]
                };
            }
        }
        let mut x_u = [[0.0; C]; 3];
        for (j, xj) in x_u.iter_mut().enumerate() {
            for (i, x) in xj.iter_mut().enumerate() {
                *x = y[0][i] * S[(0, j)] + y[1][i] * S[(1, j)] + y[2][i] * S[(2, j)];
            }
        }
        for (j, (wj, xj)) in w.iter().zip(&x_u).enumerate() {
            for (i, (wji, xji)) in wj.iter().zip(xj).enumerate() {
                // x_v = w - x_u W^T, (W^T)[(k, j)] = W[(j, k)]
                b[j * C + i] = wji - (x_u[0][i] * W[(j, 0)] + x_u[1][i] * W[(j, 1)] + x_u[2][i] * W[(j, 2)]);
                b[(3 + j) * C + i] = *xji;
            }
        }
    }
}

/// The factorization of M reused for all right-hand sides: block elimination for SPD M, or
/// LU where rounding made M fail the SPD test. Everything
/// is solved in place on transposed right-hand sides, so no 6x9 matrix is moved or wrapped
/// in an `Option`.
#[derive(Clone)]
pub(super) enum Factor {
    Spd(Schur6),
    /// The fallback, computed only when M is not numerically SPD.
    Lu(LU<f64, U6, U6>),
}

impl Factor {
    /// Factors M; `coupled` as in [`Schur6::new`].
    #[inline(always)]
    pub(super) fn new(M: &Matrix6<f64>, coupled: bool) -> Self {
        match Schur6::new(M, coupled) {
            Some(f) => Factor::Spd(f),
            None => Factor::Lu(M.lu()),
        }
    }

    /// Overwrites `bt` with (M^-1 bt^T)^T; false when M is singular.
    #[inline(always)]
    pub(super) fn solve_transposed_mut<const C: usize>(&self, bt: &mut SMatrix<f64, C, 6>) -> bool {
        match self {
            Factor::Spd(f) => {
                f.solve_transposed_mut(bt);
                true
            }
            Factor::Lu(lu) => {
                let mut b = bt.transpose();
                let solved = lu.solve_mut(&mut b);
                bt.copy_from(&b.transpose());
                solved
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector6;

    /// Largest relative difference over every column, taken separately on rows 0-2 and
    /// 3-5 (their units differ): |a - b|_inf / |b|_inf per 3-vector.
    fn rel(a: &SMatrix<f64, 6, 9>, b: &SMatrix<f64, 6, 9>) -> f64 {
        let mut worst = 0.0_f64;
        for l in 0..9 {
            for r0 in [0, 3] {
                let (x, y) = (a.fixed_view::<3, 1>(r0, l), b.fixed_view::<3, 1>(r0, l));
                worst = worst.max((x - y).amax() / y.amax().max(f64::MIN_POSITIVE));
            }
        }
        worst
    }

    #[test]
    fn factor_solves_like_nalgebra() {
        let B = SMatrix::<f64, 6, 9>::from_fn(|i, j| ((i * 7 + j * 3) % 5) as f64 - 1.7);
        let N = Matrix6::from_fn(|i, j| ((i * 5 + j * 11) % 7) as f64 * 0.3 - 0.8);
        // SPD with the prototype's spread of scales (GA, EA ~ 1e4-1e5 N, EI ~ 1e-3 N m^2)
        let scale = Vector6::new(4e4, 4e4, 1e5, 4e-3, 4e-3, 3e-3).map(f64::sqrt);
        let spd =
            Matrix6::from_diagonal(&scale) * (N * N.transpose() + Matrix6::identity()) * Matrix6::from_diagonal(&scale);
        // symmetric indefinite: the SPD test fails, the LU fallback solves
        let indefinite = N + N.transpose() - Matrix6::from_diagonal_element(0.1);
        for (M, uses_lu) in [(spd, false), (indefinite, true)] {
            let factor = Factor::new(&M, true);
            assert_eq!(matches!(factor, Factor::Lu(_)), uses_lu);
            let mut Xt = B.transpose();
            assert!(factor.solve_transposed_mut(&mut Xt));
            let reference = M.lu().solve(&B).unwrap();
            // 1e-12: backward-stable solves of a system with condition number below 1e3 after
            // diagonal scaling
            assert!(rel(&Xt.transpose(), &reference) < 1e-12);
        }
        assert!(!Factor::new(&Matrix6::zeros(), true).solve_transposed_mut(&mut B.transpose()));
    }

    #[test]
    fn block_triangular_factor_solves_like_nalgebra() {
        // The Kirchhoff rod's M = [P, G; 0, Q]: P, Q SPD, G anything.
        let B = SMatrix::<f64, 6, 9>::from_fn(|i, j| ((i * 7 + j * 3) % 5) as f64 - 1.7);
        let N = Matrix3::from_fn(|i, j| ((i * 5 + j * 11) % 7) as f64 * 0.3 - 0.8);
        let mut M = Matrix6::zeros();
        M.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::from_diagonal(&nalgebra::Vector3::new(4e4, 4e4, 1e5))));
        M.fixed_view_mut::<3, 3>(0, 3).copy_from(&(N * 0.01));
        M.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(N * N.transpose() * 1e-3 + Matrix3::identity() * 3e-3));
        let factor = Factor::new(&M, false);
        assert!(matches!(factor, Factor::Spd(_)));
        let mut Xt = B.transpose();
        assert!(factor.solve_transposed_mut(&mut Xt));
        let reference = M.lu().solve(&B).unwrap();
        // 1e-12: backward-stable solves of a well-conditioned (after scaling) system
        assert!(rel(&Xt.transpose(), &reference) < 1e-12);
    }
}
