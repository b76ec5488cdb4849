//! The bound-constrained quadratic program of each inverse-statics step, solved exactly by a
//! primal active-set method.
#![allow(non_snake_case)]

use nalgebra::{DMatrix, DVector};

/// Minimizer of d^T H d / 2 + g^T d over lower <= d <= upper (lower <= 0 <= upper), for
/// symmetric positive definite H, by the primal active-set method (Nocedal & Wright,
/// "Numerical Optimization", algorithm 16.3, specialized to bounds): from the feasible
/// d = 0, minimize over the free variables; if that leaves the box, step to the first bound
/// and fix that variable there; otherwise release the fixed variable whose multiplier has
/// the wrong sign, or stop. Each pass solves a Cholesky system of at most n unknowns; the
/// objective decreases strictly, so no working set repeats.
pub(super) fn box_qp(H: &DMatrix<f64>, g: &DVector<f64>, lower: &DVector<f64>, upper: &DVector<f64>) -> DVector<f64> {
    #[derive(Clone, Copy, PartialEq)]
    enum Set {
        Free,
        Lower,
        Upper,
    }
    let n = g.len();
    let mut d = DVector::zeros(n);
    let mut set = vec![Set::Free; n];
    // A working set is never repeated, and each pass adds or releases one bound; 10 (n + 1)
    // passes is far beyond what a handful of tendons needs (a guard, not a tuning knob).
    for _ in 0..10 * (n + 1) {
        let free: Vec<usize> = (0..n).filter(|&i| set[i] == Set::Free).collect();
        if !free.is_empty() {
            // Minimize over the free variables with the fixed ones at their bounds:
            // H_FF x_F = -(g_F + H_FB d_B).
            let m = free.len();
            let mut A = DMatrix::zeros(m, m);
            let mut b = DVector::zeros(m);
            for (a, &i) in free.iter().enumerate() {
                for (c, &j) in free.iter().enumerate() {
                    A[(a, c)] = H[(i, j)];
                }
                b[a] = -g[i]
                    - (0..n)
                        .filter(|&j| set[j] != Set::Free)
                        .map(|j| H[(i, j)] * d[j])
                        .sum::<f64>();
            }
            let Some(chol) = A.cholesky() else {
                return d;
            };
            let x = chol.solve(&b);
            // Longest fraction alpha of the way to x that stays in the box.
            let mut alpha = 1.0;
            let mut block = None;
            for (a, &i) in free.iter().enumerate() {
                let step = x[a] - d[i];
                if x[a] < lower[i] && step < 0.0 {
                    let t = (lower[i] - d[i]) / step;
                    if t < alpha {
                        alpha = t;
                        block = Some((i, Set::Lower));
                    }
                } else if x[a] > upper[i] && step > 0.0 {
                    let t = (upper[i] - d[i]) / step;
                    if t < alpha {
                        alpha = t;
                        block = Some((i, Set::Upper));
                    }
                }
            }
            for (a, &i) in free.iter().enumerate() {
                d[i] += alpha.max(0.0) * (x[a] - d[i]);
                d[i] = d[i].clamp(lower[i], upper[i]);
            }
            if let Some((i, side)) = block {
                d[i] = if side == Set::Lower { lower[i] } else { upper[i] };
                set[i] = side;
                continue;
            }
        }
        // At the minimizer over the current free set: a fixed variable whose gradient
        // points into the box would decrease the objective if released.
        let gradient = H * &d + g;
        let mut release = None;
        let mut worst = 0.0;
        for i in 0..n {
            let push = match set[i] {
                Set::Free => 0.0,
                Set::Lower => -gradient[i],
                Set::Upper => gradient[i],
            };
            if push > worst {
                worst = push;
                release = Some(i);
            }
        }
        match release {
            Some(i) => set[i] = Set::Free,
            None => return d,
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over a fine grid of a 2-D box: the active-set minimizer is no worse.
    #[test]
    fn box_qp_matches_grid_search() {
        let H = DMatrix::from_row_slice(2, 2, &[2.0, 0.9, 0.9, 1.0]);
        let q = |d: &DVector<f64>, g: &DVector<f64>| 0.5 * d.dot(&(&H * d)) + g.dot(d);
        for g in [[3.0, -1.0], [-4.0, -4.0], [0.1, 0.2], [-0.5, 2.0], [5.0, 5.0]] {
            let g = DVector::from_row_slice(&g);
            let (lo, hi) = (
                DVector::from_row_slice(&[-1.0, 0.0]),
                DVector::from_row_slice(&[0.5, 1.5]),
            );
            let d = box_qp(&H, &g, &lo, &hi);
            let mut best = f64::INFINITY;
            for a in 0..=300 {
                for b in 0..=300 {
                    let x = DVector::from_row_slice(&[-1.0 + 1.5 * a as f64 / 300.0, 1.5 * b as f64 / 300.0]);
                    best = best.min(q(&x, &g));
                }
            }
            assert!((0..2).all(|i| d[i] >= lo[i] && d[i] <= hi[i]));
            // The grid spacing 5e-3 leaves the grid minimum up to about 1e-4 above the true one.
            assert!(q(&d, &g) <= best + 1e-12, "g = {g:?}: {} vs grid {best}", q(&d, &g));
            // KKT: the gradient vanishes in free coordinates and points out of the box at
            // active bounds (1e-12: rounding of a 2 x 2 Cholesky solve with O(1) entries).
            let gradient = &H * &d + &g;
            for i in 0..2 {
                let ok = if d[i] == lo[i] {
                    gradient[i] >= -1e-12
                } else if d[i] == hi[i] {
                    gradient[i] <= 1e-12
                } else {
                    gradient[i].abs() <= 1e-12
                };
                assert!(ok, "g = {g:?}: d = {d:?}, gradient = {gradient:?}");
            }
        }
    }
}
