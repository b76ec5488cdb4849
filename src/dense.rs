//! Small dense linear systems: the one Gaussian elimination of the crate, for the k x k
//! systems of k displacement-controlled tendons (the Schur step of the bordered Newton
//! system, the small-deflection starting tensions and their correction,
//! docs/actuation.md). k is a handful, so plain elimination on a caller's buffer is cheaper
//! than a general LU and allocates nothing, which the Newton loop needs.

/// Gaussian elimination with partial pivoting on the row-major `n x n` matrix `a`, solving
/// in place into `b`. False for a zero pivot or a non-finite result.
pub(crate) fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    if n == 1 {
        // The loops below for one unknown (the usual single tendon with friction at a
        // point, solved twice per point): the same division, without their bookkeeping.
        if a[0] == 0.0 || !a[0].is_finite() {
            return false;
        }
        b[0] /= a[0];
        return b[0].is_finite();
    }
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

    /// A system that needs a row swap, solved exactly; a singular one refused.
    #[test]
    fn pivots_and_refuses_a_singular_matrix() {
        // [[0, 2], [3, 1]] x = [4, 5]: x = [1, 2], exact in binary (small integers).
        let mut a = [0.0, 2.0, 3.0, 1.0];
        let mut b = [4.0, 5.0];
        assert!(solve_dense(&mut a, &mut b, 2));
        assert_eq!(b, [1.0, 2.0]);
        let mut singular = [1.0, 2.0, 2.0, 4.0];
        assert!(!solve_dense(&mut singular, &mut [1.0, 1.0], 2));
        assert!(solve_dense(&mut [], &mut [], 0));
    }
}
