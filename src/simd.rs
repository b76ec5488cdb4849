//! Run-time SIMD dispatch: the hot kernels (the interval Jacobian, the linearizations, the
//! block eliminations, the rigid guess, the stability sweep, the Arnoldi orthogonalization,
//! the dynamics' mass quadrature and products) are compiled twice, for the baseline x86-64
//! and with AVX2 and FMA enabled, and [`avx2_fma!`] runs the AVX2 copy on a processor that
//! has the features.
//!
//! Both copies perform the same operations in the same order: Rust does not contract a
//! product and a sum into an FMA, so enabling FMA only lets the compiler use the wider
//! registers and moves, and both copies give the same bits (docs/architecture.md, "Run-time
//! SIMD dispatch in one place").

pub(crate) mod lanes;

#[cfg(target_arch = "x86_64")]
use nalgebra::{ArrayStorage, Const, Matrix, RawStorage, SMatrix};
use std::sync::atomic::{AtomicU8, Ordering};

/// Whether the processor has AVX2 and FMA: detected on the first call, then one load of a
/// cached answer (std's detection tests the two features apart).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2_fma_detected() -> bool {
    /// 0 before the first detection, then 1 without the features, 2 with them.
    static DETECTED: AtomicU8 = AtomicU8::new(0);
    match DETECTED.load(Ordering::Relaxed) {
        0 => {
            let has = std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma");
            DETECTED.store(1 + u8::from(has), Ordering::Relaxed);
            has
        }
        cached => cached == 2,
    }
}

/// Evaluates the call `$kernel` compiled with AVX2 and FMA enabled when
/// [`avx2_fma_detected`], else compiled for the baseline. `$kernel` should call an
/// `#[inline(always)]` function, so that its whole body is compiled into each copy: the
/// AVX2 copy is an always-inlined closure inside a function with the features enabled
/// (`with_avx2_fma`, a symbol in the caller's module in a profile). The closure captures the
/// call's arguments by value (`move`): by reference, the AVX2 copy read them through the
/// caller's stack, a few more instructions a call (docs/benchmarks.md, "tidy17"). Each call
/// site compiles its own pair, so a kernel should be dispatched from one place.
#[cfg(target_arch = "x86_64")]
macro_rules! avx2_fma {
    ($kernel:expr) => {{
        /// Calls `kernel` with AVX2 and FMA enabled.
        #[target_feature(enable = "avx2,fma")]
        fn with_avx2_fma<T>(kernel: impl FnOnce() -> T) -> T {
            kernel()
        }
        /// `kernel` as an `FnOnce` closure: written as an argument of this bound, the closure
        /// is inferred `FnOnce`, so `with_avx2_fma` calls its body and not a `call_once`
        /// shim that is compiled apart, without the features (as through
        /// `std::convert::identity`). An argument too because an attribute on a closure in a
        /// `let` is not stable.
        #[inline(always)]
        fn avx2_fma_once<T>(kernel: impl FnOnce() -> T) -> impl FnOnce() -> T {
            kernel
        }
        if $crate::simd::avx2_fma_detected() {
            let kernel = avx2_fma_once(
                #[inline(always)]
                move || $kernel,
            );
            // SAFETY: the processor has the features `with_avx2_fma` is compiled for, as
            // `avx2_fma_detected()` has just said.
            unsafe { with_avx2_fma(kernel) }
        } else {
            $kernel
        }
    }};
}

/// Evaluates the call `$kernel` (other targets than x86-64: no run-time dispatch).
#[cfg(not(target_arch = "x86_64"))]
macro_rules! avx2_fma {
    ($kernel:expr) => {
        $kernel
    };
}

pub(crate) use avx2_fma;

/// `[e(0), e(1), e(2), e(3)]` for `four!(j => e(j))`: one value per lane built without a
/// closure (`std::array::from_fn`'s closures stayed calls compiled for the baseline, out of
/// an AVX2 kernel, with their results copied; docs/benchmarks.md, "lanes19").
macro_rules! four {
    ($j:ident => $e:expr) => {
        [
            {
                let $j = 0;
                $e
            },
            {
                let $j = 1;
                $e
            },
            {
                let $j = 2;
                $e
            },
            {
                let $j = 3;
                $e
            },
        ]
    };
}

pub(crate) use four;

/// Whether every value of `v` is finite: v * 0 is a zero for a finite v and NaN for an
/// infinite one or a NaN, and a sum of zeros is a zero, so eight partial sums of them (whole
/// vectors, where testing value by value takes a few instructions each) hold a NaN exactly
/// when some value is not finite. Always inlined, so that an AVX2 kernel compiles it for
/// AVX2 too.
#[inline(always)]
pub(crate) fn all_finite(v: &[f64]) -> bool {
    let mut sums = [0.0f64; 8];
    let (chunks, rest) = v.as_chunks::<8>();
    for chunk in chunks {
        for (sum, x) in sums.iter_mut().zip(chunk) {
            *sum += x * 0.0;
        }
    }
    for (sum, x) in sums.iter_mut().zip(rest) {
        *sum += x * 0.0;
    }
    !sums.iter().any(|s| s.is_nan())
}

/// `list` refilled with `f(0)`, .., `f(count - 1)`. Always inlined, so that an AVX2 kernel
/// compiles it for AVX2 too: the friction lane kernel's short per-link lists (one value per
/// tendon with friction), which `clear` with `extend` or `resize` left as calls compiled
/// for the baseline, each several times the cost of its values.
#[inline(always)]
pub(crate) fn refill<T>(list: &mut Vec<T>, count: usize, mut f: impl FnMut(usize) -> T) {
    list.clear();
    list.reserve(count);
    for j in 0..count {
        list.push(f(j));
    }
}

/// a b summed entry by entry as nalgebra's product of fixed-size matrices sums it (its
/// `gemm` by columns, each column an `axcpy` per term: a_i0 b_0j first, then a_ik b_kj
/// added for k = 1, 2, ..), so the same bits. Always inlined, so that an AVX2 kernel
/// compiles it for AVX2 too: nalgebra's products there stayed calls compiled for the
/// baseline.
#[inline(always)]
pub(crate) fn product<const R: usize, const K: usize, const C: usize, SA, SB>(
    a: &Matrix<f64, Const<R>, Const<K>, SA>,
    b: &Matrix<f64, Const<K>, Const<C>, SB>,
) -> SMatrix<f64, R, C>
where
    SA: RawStorage<f64, Const<R>, Const<K>>,
    SB: RawStorage<f64, Const<K>, Const<C>>,
{
    let mut columns = [[0.0; R]; C];
    for (j, column) in columns.iter_mut().enumerate() {
        for (i, entry) in column.iter_mut().enumerate() {
            let mut sum = a[(i, 0)] * b[(0, j)];
            for k in 1..K {
                sum += a[(i, k)] * b[(k, j)];
            }
            *entry = sum;
        }
    }
    SMatrix::from_data(ArrayStorage(columns))
}

/// The fixed-size matrix whose entry (i, c) is `f(i, c)`, as nalgebra's `from_fn` fills
/// it. Always inlined, so that an AVX2 kernel compiles it for AVX2 too: `from_fn` stayed a
/// call compiled for the baseline, its closure called once per entry.
#[inline(always)]
pub(crate) fn filled<const R: usize, const C: usize>(f: impl Fn(usize, usize) -> f64) -> SMatrix<f64, R, C> {
    let mut columns = [[0.0; R]; C];
    for (c, column) in columns.iter_mut().enumerate() {
        for (i, entry) in column.iter_mut().enumerate() {
            *entry = f(i, c);
        }
    }
    SMatrix::from_data(ArrayStorage(columns))
}

#[cfg(test)]
mod tests {
    use super::{all_finite, filled, product, refill};
    use nalgebra::SMatrix;

    /// Finite values (zeros of both signs, the largest and smallest magnitudes among them)
    /// pass; one infinity or NaN fails wherever it is: in a whole chunk of eight or in the
    /// remainder, first or last.
    #[test]
    fn all_finite_finds_every_value_that_is_not() {
        let finite: Vec<f64> = (0..19)
            .map(|i| match i % 5 {
                0 => 0.0,
                1 => -0.0,
                2 => f64::MAX,
                3 => -f64::MIN_POSITIVE,
                _ => i as f64 - 9.5,
            })
            .collect();
        assert!(all_finite(&finite));
        assert!(all_finite(&[]));
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for at in [0, 7, 8, 15, 16, 18] {
                let mut v = finite.clone();
                v[at] = bad;
                assert!(!all_finite(&v), "{bad} at {at}");
            }
        }
    }

    /// `product` gives nalgebra's product bit for bit, on the shapes the friction kernel
    /// multiplies (12 x 12 by 12 x 1, 1 x 9 by 9 x 18, 12 x 1 by 1 x 18, 1 x 3 by 3 x 3)
    /// with entries of mixed signs and magnitudes, where any other order of the sums moves
    /// last bits, and with negative zeros, whose sign a sum started from +0 loses; `filled`
    /// is `from_fn`, and `refill` leaves exactly the values asked for.
    #[test]
    fn the_kernels_products_are_nalgebras_bit_for_bit() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut value = move |i: usize| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let x = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            // Every seventh a negative zero; the rest over ten orders of magnitude.
            if i % 7 == 3 {
                -0.0
            } else {
                x * 10f64.powi((i % 11) as i32 - 5)
            }
        };
        fn same<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>, b: &SMatrix<f64, R, C>) {
            let bits = |m: &SMatrix<f64, R, C>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(a), bits(b));
        }
        let mut counter = 0;
        let mut next = || {
            counter += 1;
            value(counter)
        };
        let a = SMatrix::<f64, 12, 12>::from_fn(|_, _| next());
        let x = SMatrix::<f64, 12, 1>::from_fn(|_, _| next());
        same(&product(&a, &x), &(a * x));
        let row = SMatrix::<f64, 1, 12>::from_fn(|_, _| next());
        let d = SMatrix::<f64, 9, 18>::from_fn(|_, _| next());
        same(
            &product(&row.fixed_columns::<9>(3), &d),
            &(row.fixed_columns::<9>(3) * d),
        );
        same(&product(&row, &x), &(row * x));
        let column = SMatrix::<f64, 12, 1>::from_fn(|_, _| next());
        let dz = SMatrix::<f64, 1, 18>::from_fn(|_, _| next());
        same(&product(&column, &dz), &(column * dz));
        let phi = SMatrix::<f64, 1, 3>::from_fn(|_, _| next());
        let j = SMatrix::<f64, 3, 3>::from_fn(|_, _| next());
        same(&product(&phi, &j), &(phi * j));
        same(&product(&phi, &j.transpose()), &(phi * j.transpose()));
        let f = |i: usize, c: usize| (i as f64 - 2.5) * 0.1 + c as f64;
        same(&filled::<6, 3>(f), &SMatrix::<f64, 6, 3>::from_fn(f));
        let mut list = vec![7.0; 5];
        refill(&mut list, 3, |j| j as f64 * 0.5);
        assert_eq!(list, [0.0, 0.5, 1.0]);
    }
}
