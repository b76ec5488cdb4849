//! Arnoldi on J^-1 M for the linearized dynamics' eigenvalues (docs/stability.md, "How it
//! is computed"): the Krylov steps with their Gram-Schmidt, the Ritz values and their
//! residual estimates, and the early stop of a solve's verdict once the modes it rests on
//! have settled.

use super::grows;
use super::hessenberg;
use crate::simd::avx2_fma;
use nalgebra::{Complex, DMatrix};

/// The Arnoldi steps after which a solve's verdict tests whether it may stop ([`settled`]):
/// the verdicts measured settle after 8-12 steps, most after 8 or 9 (docs/stability.md,
/// "How it is computed"); a test costs an eigenvalue problem of that size and the residual
/// estimates of the band, about one and a half steps.
const CHECKS: [usize; 6] = [8, 9, 10, 11, 12, 14];
/// The band of modes an early stop waits for: Ritz values theta = 1 / mu with |theta| at
/// least this fraction of the largest (|mu| within 100 times the lowest mode's, frequencies
/// within 10 times), the modes a divergence (a frequency through zero) or a flutter (two
/// low frequencies coalescing) comes from first.
const WANTED: f64 = 1e-2;
/// An early stop waits until the Ritz values of [`WANTED`] and every growing one have a
/// residual estimate below this fraction of their magnitude: far inside
/// [`super::CONVERGED`], so that a growth rate is the one more steps give, to 1e-8 and
/// better (8e-11 measured).
const SETTLED: f64 = 1e-10;
/// A Ritz value that does not grow also settles when its residual estimate is below this
/// fraction of its magnitude and of its distance to every other Ritz value ([`gap`]):
/// no perturbation of the residual's size then makes its mode grow, unless the eigenvalue's
/// condition number is 5e5 or more (its value is not reported by a solve's verdict). Equal
/// to [`super::CONVERGED`], so that such a value counts as converged.
const SEPARATED: f64 = 1e-6;
/// The steps at which a run with a growing Ritz value in the band may stop ([`settled`]):
/// those of the rule before 2026-12-06 (branch dyn11), which waits for every Ritz value of
/// the band at [`SETTLED`], so that growing verdicts and their rates are that rule's (a
/// flutter near its onset has a rate that is a small difference, which an earlier stop at
/// the same residual estimates leaves to 2e-8 only).
const GROWING_CHECKS: [usize; 3] = [10, 12, 14];

/// A Ritz value theta of J^-1 M (theta = 1 / mu) and its residual estimate.
pub(super) struct Ritz {
    /// theta = 1 / mu.
    pub(super) theta: Complex<f64>,
    /// |h_(m+1,m) y_m|, infinite when not computed.
    pub(super) residual: f64,
}

/// Arnoldi on `operator` (y = J^-1 M z) from a generic start purified by two applications
/// (which removes the components along M's kernel, the infinite mu): the Ritz values and
/// their residual estimates |h_(m+1,m) y_m|. Unless `all`, the run stops at the first of
/// [`CHECKS`] where the Ritz values the verdict rests on have settled ([`settled`]), and
/// goes on to `krylov` steps otherwise. None if a solve fails.
pub(super) fn arnoldi(
    operator: &mut impl FnMut(&[f64], &mut Vec<f64>) -> bool,
    n: usize,
    krylov: usize,
    all: bool,
) -> Option<Vec<Ritz>> {
    let mut q: Vec<f64> = (0..n)
        .map(|i| (i as f64 * 0.618_033_988_749_895).fract() - 0.5)
        .collect();
    let mut next = Vec::with_capacity(n);
    for _ in 0..2 {
        if !operator(&q, &mut next) {
            return None;
        }
        std::mem::swap(&mut q, &mut next);
    }
    let norm = dot(&q, &q).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    q.iter_mut().for_each(|v| *v /= norm);
    let m_max = krylov.min(n);
    let mut basis = vec![q];
    let mut h = DMatrix::<f64>::zeros(m_max + 1, m_max);
    let mut m = 0;
    // The first step at which a test may stop the run ([`settled`]).
    let mut next_check = 0;
    while m < m_max {
        if !operator(&basis[m], &mut next) {
            return None;
        }
        let scale = dot(&next, &next).sqrt();
        orthogonalize(&basis, &mut next, &mut h.as_mut_slice()[m * (m_max + 1)..]);
        let beta = dot(&next, &next).sqrt();
        h[(m + 1, m)] = beta;
        m += 1;
        // An invariant subspace (breakdown at rounding of the step's size): its Ritz
        // values are exact.
        if beta <= 1e-13 * scale || !beta.is_finite() {
            break;
        }
        if !all && m < m_max && m >= next_check && CHECKS.contains(&m) {
            match settled(&h, m) {
                Ok(ritz) => return Some(ritz),
                Err(next) => next_check = next,
            }
        }
        basis.push(next.iter().map(|x| x / beta).collect());
    }
    let (values, largest) = ritz_values(&h, m);
    // Residual estimates cost a complex LU each: unless `all`, only for the Ritz values a
    // verdict rests on, the lowest mode and any that grows ([`grows`]).
    let wanted = |theta: Complex<f64>| all || theta.norm() >= (1.0 - 1e-9) * largest || grows(theta, largest);
    let mut work = Work::new(m);
    Some(
        values
            .iter()
            .map(|&theta| Ritz {
                theta,
                residual: if wanted(theta) {
                    residual(&h, m, theta, &mut work)
                } else {
                    f64::INFINITY
                },
            })
            .collect(),
    )
}

/// The Ritz values of the first `m` Arnoldi steps (the eigenvalues of the leading m x m
/// block of `h`) and the largest of their magnitudes (the lowest mode's 1 / |mu|).
/// By the double-shift QR iteration on the Hessenberg block ([`hessenberg::eigenvalues`]),
/// or, should it not converge, nalgebra's general Schur form.
fn ritz_values(h: &DMatrix<f64>, m: usize) -> (Vec<Complex<f64>>, f64) {
    let values: Vec<Complex<f64>> = hessenberg::eigenvalues(h, m).unwrap_or_else(|| {
        h.view((0, 0), (m, m))
            .into_owned()
            .complex_eigenvalues()
            .iter()
            .copied()
            .collect()
    });
    let largest = values.iter().map(|t| t.norm()).fold(0.0f64, f64::max);
    (values, largest)
}

/// The residual estimate |h_(m+1,m) y_m| of the Ritz value `theta` of the first `m` steps,
/// with `work` for its buffers.
fn residual(h: &DMatrix<f64>, m: usize, theta: Complex<f64>, work: &mut Work) -> f64 {
    // A real Ritz value (the QR iteration's are exactly real, imaginary part 0) in real
    // arithmetic that forms num-complex's operations on numbers with a zero imaginary part
    // ([`Scalar`]): the same bits, at a quarter of the work.
    let last = if theta.im == 0.0 {
        last_component(h, m, theta.re, &mut work.real)
    } else {
        last_component(h, m, theta, &mut work.complex)
    };
    h[(m, m - 1)] * last
}

/// The buffers of [`last_component`] for an m x m Hessenberg block, allocated once for the
/// residual estimates of one set of Ritz values: for the real Ritz values and the complex
/// ones.
struct Work {
    real: Buffers<f64>,
    complex: Buffers<Complex<f64>>,
}

impl Work {
    /// Buffers for an m x m block.
    fn new(m: usize) -> Self {
        Work {
            real: Buffers::new(m),
            complex: Buffers::new(m),
        }
    }
}

/// [`last_component`]'s buffers in the arithmetic `T`.
struct Buffers<T> {
    /// h - shift I, row major, factored in place.
    a: Vec<T>,
    /// The elimination's multipliers, one per column.
    multipliers: Vec<T>,
    /// Whether rows k and k + 1 were swapped at column k.
    swapped: Vec<bool>,
    /// The inverse iteration's vector.
    y: Vec<T>,
}

impl<T: Scalar> Buffers<T> {
    /// Buffers for an m x m block.
    fn new(m: usize) -> Self {
        Buffers {
            a: vec![T::real(0.0); m * m],
            multipliers: vec![T::real(0.0); m],
            swapped: vec![false; m],
            y: vec![T::real(0.0); m],
        }
    }
}

/// The arithmetic of [`last_component`]: complex, or real for a real Ritz value. The real
/// operations are num-complex's on numbers whose imaginary parts are zero, written out: a
/// product a c (its a c - 0 0), a quotient (a c) / (c c) (its (a c + 0 0) / (c c + 0 0)),
/// |a| for the 1-norm and the modulus (hypot(a, 0) = |a|), a^2 for the squared modulus.
/// So every nonzero value is the complex run's bit for bit; a zero may differ in its sign
/// (the complex run adds signed zero products of the imaginary parts), which neither a
/// pivot's choice (by modulus), a zero test, a sum with a nonzero value nor the squared
/// modulus sees, so the estimate is the same (unit test
/// `real_estimates_are_the_complex_ones_bit_for_bit`).
trait Scalar: Copy + PartialEq + std::ops::Add<Output = Self> + std::ops::Sub<Output = Self> + std::ops::SubAssign {
    /// The number x (+ 0 i).
    fn real(x: f64) -> Self;
    /// self * other.
    fn times(self, other: Self) -> Self;
    /// self / other.
    fn over(self, other: Self) -> Self;
    /// |re| + |im|.
    fn l1(self) -> f64;
    /// re^2 + im^2.
    fn square(self) -> f64;
    /// The modulus.
    fn modulus(self) -> f64;
    /// self / x for a real x.
    fn scaled(self, x: f64) -> Self;
}

impl Scalar for Complex<f64> {
    fn real(x: f64) -> Self {
        Complex::new(x, 0.0)
    }
    fn times(self, other: Self) -> Self {
        self * other
    }
    fn over(self, other: Self) -> Self {
        self / other
    }
    fn l1(self) -> f64 {
        self.l1_norm()
    }
    fn square(self) -> f64 {
        self.norm_sqr()
    }
    fn modulus(self) -> f64 {
        self.norm()
    }
    fn scaled(self, x: f64) -> Self {
        self / x
    }
}

impl Scalar for f64 {
    fn real(x: f64) -> Self {
        x
    }
    fn times(self, other: Self) -> Self {
        self * other
    }
    fn over(self, other: Self) -> Self {
        (self * other) / (other * other)
    }
    fn l1(self) -> f64 {
        self.abs()
    }
    fn square(self) -> f64 {
        self * self
    }
    fn modulus(self) -> f64 {
        self.abs()
    }
    fn scaled(self, x: f64) -> Self {
        self / x
    }
}

/// The Ritz values after `m` steps if the run may stop there: every finite one within
/// [`WANTED`] of the lowest mode (largest |theta|) and every one that grows has settled, and
/// the run has reached past the band (a finite Ritz value below it: the band's modes, which
/// shift-invert makes dominant, normally enter the Krylov space before any below them:
/// observed on every verdict measured, not a bound; docs/stability.md). When one of
/// them grows, the run stops only at [`GROWING_CHECKS`] and when every one of the band and
/// every growing one has a residual estimate below [`SETTLED`] of its magnitude (its rate is
/// then the one more steps give, to 1e-8 and better). When none grows, a value settles when
/// its residual estimate is below [`SEPARATED`] of both its magnitude and its distance to
/// the nearest other Ritz value ([`gap`]), or below [`SETTLED`] of its magnitude. Further steps then add modes above the band and refine
/// these, but change no verdict. The others get an infinite residual. Err at the first one that has not settled (tested from
/// the lowest mode up, which settles first), with the step of the next test ([`next_test`]).
fn settled(h: &DMatrix<f64>, m: usize) -> Result<Vec<Ritz>, usize> {
    let (values, largest) = ritz_values(h, m);
    if largest == 0.0 {
        return Err(m + 1);
    }
    let finite = |theta: Complex<f64>| theta.norm() > 1e-9 * largest;
    if !values
        .iter()
        .any(|&theta| finite(theta) && theta.norm() < WANTED * largest)
    {
        return Err(m + 1);
    }
    // With a growing value, the rule of [`GROWING_CHECKS`].
    let any_growing = values.iter().any(|&theta| finite(theta) && grows(theta, largest));
    let next_growing = GROWING_CHECKS.into_iter().find(|&c| c > m).unwrap_or(usize::MAX);
    if any_growing && !GROWING_CHECKS.contains(&m) {
        return Err(next_growing);
    }
    let mut ritz: Vec<Ritz> = values
        .iter()
        .map(|&theta| Ritz {
            theta,
            residual: f64::INFINITY,
        })
        .collect();
    ritz.sort_by(|a, b| b.theta.norm().total_cmp(&a.theta.norm()));
    let mut work = Work::new(m);
    for i in 0..ritz.len() {
        let theta = ritz[i].theta;
        let size = theta.norm();
        let growing = grows(theta, largest);
        if !finite(theta) || !(size >= WANTED * largest || growing) {
            continue;
        }
        let residual = residual(h, m, theta, &mut work);
        ritz[i].residual = residual;
        let bound = if any_growing {
            SETTLED * size
        } else {
            (SETTLED * size).max(SEPARATED * size.min(gap(&ritz, i)))
        };
        if residual > bound || residual.is_nan() {
            return Err(if any_growing {
                next_growing
            } else {
                next_test(m, residual / bound)
            });
        }
    }
    Ok(ritz)
}

/// The step of the next early-stop test after one at step `m` that found a residual estimate
/// `far` times its bound: a residual estimate was observed to fall by a hundredfold per step
/// at most (about shift-invert's ratio of |mu| at the band's edge, [`WANTED`]), so it is
/// expected to need log10(far) / 2 more steps, rounded up, and no test is made before then
/// (a faster fall costs only the steps skipped, not the verdict: the run stops only where
/// [`settled`] holds). Rounded down, a test would come a step early whenever log10(far) / 2
/// is not a whole number, and fail unless the estimate fell faster than assumed
/// (docs/stability.md). A next test beyond the last of the fixed checks sends the run to its
/// full Krylov steps: more work, the same verdict.
fn next_test(m: usize, far: f64) -> usize {
    let steps = if far.is_finite() {
        (far.log10() / 2.0).ceil()
    } else {
        1.0
    };
    m + (steps as usize).max(1)
}

/// The distance of the Ritz value `ritz[i]` to the nearest other one. A value that does not
/// grow settles when its residual estimate is below [`SEPARATED`] of both its magnitude and
/// this distance: theta is an exact eigenvalue of J^-1 M perturbed by a matrix of norm the
/// residual, and its mode stops being a vibration only if the eigenvalue moves through
/// infinity (mu through zero: a distance of |theta| at least) or meets another one to leave
/// the real axis as a pair (half their distance at least): a movement of at least
/// 1 / (2 [`SEPARATED`]) times the perturbation (docs/stability.md, "How it is computed").
fn gap(ritz: &[Ritz], i: usize) -> f64 {
    let theta = ritz[i].theta;
    ritz.iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .map(|(_, r)| (r.theta - theta).norm())
        .fold(f64::INFINITY, f64::min)
}

/// |y_m| of the unit eigenvector y of the leading m x m block of the upper Hessenberg `h`
/// for its eigenvalue `theta`, by two steps of inverse iteration with a shift moved off
/// theta by rounding's size. The LU with partial pivoting uses the Hessenberg form: below
/// the diagonal, column k has a nonzero only in row k + 1, so the pivot is row k or k + 1
/// and each elimination updates one row (O(m^2), where a dense LU costs O(m^3)).
fn last_component<T: Scalar>(h: &DMatrix<f64>, m: usize, theta: T, work: &mut Buffers<T>) -> f64 {
    let mut scale = 0.0f64;
    for j in 0..m {
        for i in 0..m.min(j + 2) {
            scale = scale.max(h[(i, j)].abs());
        }
    }
    let shift = theta + T::real(1e-12 * scale.max(f64::MIN_POSITIVE));
    let zero = T::real(0.0);
    let Buffers {
        a,
        multipliers,
        swapped,
        y,
    } = work;
    // a = h - shift I, row-major, factored in place into U (and the multipliers).
    for i in 0..m {
        for j in 0..m {
            let v = T::real(if i <= j + 1 { h[(i, j)] } else { 0.0 });
            a[i * m + j] = if i == j { v - shift } else { v };
        }
    }
    multipliers.fill(zero);
    swapped.fill(false);
    for k in 0..m - 1 {
        let (top, below) = (k * m + k, (k + 1) * m + k);
        if a[below].l1() > a[top].l1() {
            // Rows k and k + 1 have no nonzeros left of column k.
            for j in k..m {
                a.swap(k * m + j, (k + 1) * m + j);
            }
            swapped[k] = true;
        }
        if a[top] == zero {
            return 0.0;
        }
        let f = a[below].over(a[top]);
        multipliers[k] = f;
        a[below] = zero;
        for j in k + 1..m {
            let u = a[k * m + j];
            a[(k + 1) * m + j] -= f.times(u);
        }
    }
    if a[m * m - 1] == zero {
        return 0.0;
    }
    for (i, v) in y.iter_mut().enumerate() {
        *v = T::real(1.0 + 0.1 * i as f64);
    }
    for _ in 0..2 {
        for k in 0..m - 1 {
            if swapped[k] {
                y.swap(k, k + 1);
            }
            let v = y[k];
            y[k + 1] -= multipliers[k].times(v);
        }
        for i in (0..m).rev() {
            let mut v = y[i];
            for j in i + 1..m {
                v -= a[i * m + j].times(y[j]);
            }
            y[i] = v.over(a[i * m + i]);
        }
        let norm = y.iter().map(|v| v.square()).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return f64::INFINITY;
        }
        y.iter_mut().for_each(|v| *v = v.scaled(norm));
    }
    y[m - 1].modulus()
}

/// Modified Gram-Schmidt of `next` against the orthonormal `basis`, twice (the second pass
/// restores orthogonality lost to rounding when the new vector is nearly in the span),
/// adding the coefficients to `column`. On x86-64 with AVX2 and FMA (checked at run time)
/// compiled for them: the same operations in the same order (Rust does not fuse a product
/// and a sum into an FMA), so the same bits, in wider registers.
fn orthogonalize(basis: &[Vec<f64>], next: &mut [f64], column: &mut [f64]) {
    avx2_fma!(orthogonalize_kernel(basis, next, column));
}

/// [`orthogonalize`]'s operations.
#[inline(always)]
fn orthogonalize_kernel(basis: &[Vec<f64>], next: &mut [f64], column: &mut [f64]) {
    for _ in 0..2 {
        for (b, h) in basis.iter().zip(column.iter_mut()) {
            let c = dot(next, b);
            *h += c;
            next.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
        }
    }
}

/// The dot product of `a` and `b` in eight interleaved partial sums (element i goes to sum
/// i mod 8, the sums added pairwise at the end), which the compiler turns into vector
/// instructions; the order is fixed, so the result is the same with and without AVX2.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut sums = [0.0; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            sums[i] += x[i] * y[i];
        }
    }
    for (i, (x, y)) in ra.iter().zip(rb).enumerate() {
        sums[i] += x * y;
    }
    let quads = [
        sums[0] + sums[4],
        sums[1] + sums[5],
        sums[2] + sums[6],
        sums[3] + sums[7],
    ];
    (quads[0] + quads[2]) + (quads[1] + quads[3])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The next test comes after the steps a hundredfold fall per step needs, rounded up:
    /// case H with friction's 302 times its bound after 9 steps waits two steps (it waited
    /// one, and that test failed at 2.3 times); a whole number of hundredfolds waits that
    /// many; a value that is not finite, or barely above its bound, waits one.
    #[test]
    fn the_next_test_waits_for_the_fall_it_needs() {
        assert_eq!(next_test(9, 302.0), 11);
        assert_eq!(next_test(8, 15.5), 9);
        assert_eq!(next_test(8, 1.35), 9);
        assert_eq!(next_test(8, 100.0), 9);
        assert_eq!(next_test(8, 1e4), 10);
        assert_eq!(next_test(8, 1e5), 11);
        assert_eq!(next_test(8, f64::NAN), 9);
        assert_eq!(next_test(8, f64::INFINITY), 9);
    }

    /// The residual estimate of a real Ritz value in real arithmetic is the complex run's
    /// bit for bit, on Hessenberg matrices of Arnoldi's sizes with pivots both ways (rows
    /// of very different scales, as shift-invert's Ritz values have) and at their real
    /// eigenvalues (where the shifted matrix is nearly singular).
    #[test]
    fn real_estimates_are_the_complex_ones_bit_for_bit() {
        let mut seed = 99u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut compared = 0;
        for m in 4..=16 {
            let mut h = DMatrix::<f64>::zeros(m + 1, m);
            for j in 0..m {
                for i in 0..(j + 2).min(m + 1) {
                    h[(i, j)] = random() * 10f64.powi((i % 4) as i32 - 2);
                }
            }
            let (values, _) = ritz_values(&h, m);
            let shifts = values
                .iter()
                .filter(|t| t.im == 0.0)
                .map(|t| t.re)
                .chain([0.3, -1.7, 0.0]);
            let mut work = Work::new(m);
            for theta in shifts {
                let real = last_component(&h, m, theta, &mut work.real);
                let complex = last_component(&h, m, Complex::new(theta, 0.0), &mut work.complex);
                assert_eq!(real.to_bits(), complex.to_bits(), "m = {m}, theta = {theta}");
                compared += 1;
            }
        }
        // Real Ritz values among them, not only the fixed shifts.
        assert!(compared > 3 * 13, "{compared} estimates compared");
    }
}
