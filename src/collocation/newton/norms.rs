//! Newton's max-norms of residuals and steps ([`max_norm`]), taken several times an
//! iteration over every unknown.

use crate::simd::avx2_fma;

/// The max-norm of `v` as [`max_norm_in_order`] gives it, in eight lanes compiled for AVX2
/// where the processor has it ([`avx2_fma!`]): the largest magnitude of finite entries is
/// the same number in any order; with an entry that is not finite (seen as a NaN in the
/// lanes' sums of 0 x) the in-order fold is the answer.
pub(super) fn max_norm(v: &[f64]) -> f64 {
    avx2_fma!(max_norm_lanes(v))
}

/// The larger of two norms, NaN when either is (`f64::max` returns the other operand of a
/// NaN, which would let a step or residual with a NaN entry pass Newton's tests).
pub(super) fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) }
}

/// [`max_norm`]'s lanes.
#[inline(always)]
fn max_norm_lanes(v: &[f64]) -> f64 {
    let mut chunks = v.chunks_exact(8);
    let mut largest = [0.0f64; 8];
    let mut flags = [0.0f64; 8];
    for chunk in &mut chunks {
        for ((m, flag), x) in largest.iter_mut().zip(flags.iter_mut()).zip(chunk) {
            let a = x.abs();
            *m = if a > *m { a } else { *m };
            // 0 x is (signed) zero for a finite x and NaN otherwise, and stays NaN.
            *flag += x * 0.0;
        }
    }
    let rest = chunks.remainder();
    if flags.iter().any(|&f| f != 0.0) || !rest.iter().all(|x| x.is_finite()) {
        return max_norm_in_order(v);
    }
    largest
        .iter()
        .chain(rest)
        .fold(0.0, |m: f64, x| if x.abs() > m { x.abs() } else { m })
}

/// The max-norm of `v` by an in-order fold: NaN when any entry is NaN (`f64::max` alone
/// would drop a NaN met before a later entry, and a residual with a NaN row would pass as
/// converged), infinite when any entry is infinite.
fn max_norm_in_order(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| {
        if m.is_nan() || x.is_nan() {
            f64::NAN
        } else {
            m.max(x.abs())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::{max_norm, max_norm_in_order, nan_max};

    /// The larger of two norms keeps a NaN on either side, and is `f64::max` otherwise.
    #[test]
    fn nan_max_keeps_a_nan_on_either_side() {
        assert!(nan_max(f64::NAN, 1.0).is_nan());
        assert!(nan_max(1.0, f64::NAN).is_nan());
        assert_eq!(nan_max(2.0, 1.0), 2.0);
        assert_eq!(nan_max(1.0, f64::INFINITY), f64::INFINITY);
    }

    /// The lanes give the in-order fold's bits on every length around the lanes' width, with
    /// signed zeros, and with an infinity or a NaN at every position (where the fold's
    /// answer, NaN or not, is returned).
    #[test]
    fn max_norm_gives_the_in_order_folds_bits() {
        for len in 0..27 {
            let v: Vec<f64> = (0..len)
                .map(|i| {
                    if i % 5 == 3 {
                        -0.0
                    } else {
                        ((i * 37 % 11) as f64 - 5.0) * 1.7e-3
                    }
                })
                .collect();
            assert_eq!(max_norm(&v).to_bits(), max_norm_in_order(&v).to_bits(), "length {len}");
            for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
                for at in 0..len {
                    let mut w = v.clone();
                    w[at] = bad;
                    assert_eq!(
                        max_norm(&w).to_bits(),
                        max_norm_in_order(&w).to_bits(),
                        "{bad} at {at} of {len}"
                    );
                    // A NaN anywhere makes the norm NaN, an infinity infinite.
                    assert_eq!(max_norm(&w).is_nan(), bad.is_nan(), "{bad} at {at} of {len}");
                    assert!(bad.is_nan() || max_norm(&w) == f64::INFINITY, "{bad} at {at} of {len}");
                }
            }
        }
    }
}
