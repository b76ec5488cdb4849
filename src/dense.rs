//! Small dense linear systems: the k x k systems of the tendon tensions (the starting
//! estimate q = (K + C) tau, its correction on the initial guess, the Schur complement of the
//! bordered Newton step), k the number of displacement-controlled tendons, solved in place.

/// Gaussian elimination with partial pivoting on the row-major `n x n` matrix `a`, solving
/// in place into `b`. False for a zero pivot or a non-finite result.
pub(crate) fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for col in 0..n {
        let Some(pivot) = (col..n).max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs())) else {
            return false;
        };
        if a[pivot * n + col] == 0.0 || !a[pivot * n + col].is_finite() {
            return false;
        }
        if pivot != col {
            for c in 0..n {
                a.swap(pivot * n + c, col * n + c);
            }
            b.swap(pivot, col);
        }
        for row in col + 1..n {
            let factor = a[row * n + col] / a[col * n + col];
            for c in col..n {
                a[row * n + c] -= factor * a[col * n + c];
            }
            b[row] -= factor * b[col];
        }
    }
    for row in (0..n).rev() {
        let mut sum = b[row];
        for c in row + 1..n {
            sum -= a[row * n + c] * b[c];
        }
        b[row] = sum / a[row * n + row];
    }
    b.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pivots_and_solves_a_small_system() {
        // A zero leading entry needs the row swap; the solution is x = (1, 2, 3).
        let mut a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 1.0, 2.0, 0.0, 3.0];
        let mut b = vec![7.0, 6.0, 11.0];
        assert!(solve_dense(&mut a, &mut b, 3));
        for (x, want) in b.iter().zip([1.0, 2.0, 3.0]) {
            // 1e-14: three pivots of order 1, rounding only
            assert!((x - want).abs() < 1e-14, "{b:?}");
        }
        let mut singular = vec![1.0, 2.0, 2.0, 4.0];
        let mut rhs = vec![1.0, 2.0];
        assert!(!solve_dense(&mut singular, &mut rhs, 2));
    }
}
