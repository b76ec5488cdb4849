//! Arnoldi on J^-1 M for the linearized dynamics' eigenvalues (docs/stability.md, "How it
//! is computed"): the Krylov steps with their Gram-Schmidt, the Ritz values and their
//! residual estimates, and the early stop of a solve's verdict once the modes it rests on
//! have settled.

use super::grows;
use super::hessenberg;
use nalgebra::{Complex, DMatrix};

/// The Arnoldi steps after which a solve's verdict tests whether it may stop ([`settled`]):
/// the lowest modes of the robots measured settle after 10-12 steps (docs/stability.md,
/// "How it is computed"); a test costs an eigenvalue problem of that size, a fraction of a
/// step.
const CHECKS: [usize; 3] = [10, 12, 14];
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
        if !all
            && m < m_max
            && CHECKS.contains(&m)
            && let Some(ritz) = settled(&h, m)
        {
            return Some(ritz);
        }
        basis.push(next.iter().map(|x| x / beta).collect());
    }
    let (values, largest) = ritz_values(&h, m);
    // Residual estimates cost a complex LU each: unless `all`, only for the Ritz values a
    // verdict rests on, the lowest mode and any that grows ([`grows`]).
    let wanted = |theta: Complex<f64>| all || theta.norm() >= (1.0 - 1e-9) * largest || grows(theta, largest);
    Some(
        values
            .iter()
            .map(|&theta| Ritz {
                theta,
                residual: if wanted(theta) {
                    residual(&h, m, theta)
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

/// The residual estimate |h_(m+1,m) y_m| of the Ritz value `theta` of the first `m` steps.
fn residual(h: &DMatrix<f64>, m: usize, theta: Complex<f64>) -> f64 {
    h[(m, m - 1)] * last_component(h, m, theta)
}

/// The Ritz values after `m` steps if the run may stop there: every finite one within
/// [`WANTED`] of the lowest mode (largest |theta|) and every one that grows has a residual
/// estimate below [`SETTLED`] of its magnitude, so that further steps add modes above the
/// band and refine these below the rounding of a growth rate, but change no verdict. The
/// others get an infinite residual; None at the first one that has not settled (tested
/// from the lowest mode up, which settles first).
fn settled(h: &DMatrix<f64>, m: usize) -> Option<Vec<Ritz>> {
    let (values, largest) = ritz_values(h, m);
    if largest == 0.0 {
        return None;
    }
    let mut ritz: Vec<Ritz> = values
        .iter()
        .map(|&theta| Ritz {
            theta,
            residual: f64::INFINITY,
        })
        .collect();
    ritz.sort_by(|a, b| b.theta.norm().total_cmp(&a.theta.norm()));
    for r in ritz.iter_mut() {
        let size = r.theta.norm();
        if size > 1e-9 * largest && (size >= WANTED * largest || grows(r.theta, largest)) {
            r.residual = residual(h, m, r.theta);
            if r.residual > SETTLED * size {
                return None;
            }
        }
    }
    Some(ritz)
}

/// |y_m| of the unit eigenvector y of the leading m x m block of the upper Hessenberg `h`
/// for its eigenvalue `theta`, by two steps of inverse iteration with a shift moved off
/// theta by rounding's size. The LU with partial pivoting uses the Hessenberg form: below
/// the diagonal, column k has a nonzero only in row k + 1, so the pivot is row k or k + 1
/// and each elimination updates one row (O(m^2), where a dense LU costs O(m^3)).
fn last_component(h: &DMatrix<f64>, m: usize, theta: Complex<f64>) -> f64 {
    let mut scale = 0.0f64;
    for j in 0..m {
        for i in 0..m.min(j + 2) {
            scale = scale.max(h[(i, j)].abs());
        }
    }
    let shift = theta + Complex::new(1e-12 * scale.max(f64::MIN_POSITIVE), 0.0);
    // a = h - shift I, row-major, factored in place into U (and the multipliers).
    let mut a: Vec<Complex<f64>> = (0..m * m)
        .map(|k| {
            let (i, j) = (k / m, k % m);
            let v = Complex::new(if i <= j + 1 { h[(i, j)] } else { 0.0 }, 0.0);
            if i == j { v - shift } else { v }
        })
        .collect();
    let mut multipliers = vec![Complex::new(0.0, 0.0); m];
    let mut swapped = vec![false; m];
    for k in 0..m - 1 {
        let (top, below) = (k * m + k, (k + 1) * m + k);
        if a[below].l1_norm() > a[top].l1_norm() {
            // Rows k and k + 1 have no nonzeros left of column k.
            for j in k..m {
                a.swap(k * m + j, (k + 1) * m + j);
            }
            swapped[k] = true;
        }
        if a[top] == Complex::new(0.0, 0.0) {
            return 0.0;
        }
        let f = a[below] / a[top];
        multipliers[k] = f;
        a[below] = Complex::new(0.0, 0.0);
        for j in k + 1..m {
            let u = a[k * m + j];
            a[(k + 1) * m + j] -= f * u;
        }
    }
    if a[m * m - 1] == Complex::new(0.0, 0.0) {
        return 0.0;
    }
    let mut y: Vec<Complex<f64>> = (0..m).map(|i| Complex::new(1.0 + 0.1 * i as f64, 0.0)).collect();
    for _ in 0..2 {
        for k in 0..m - 1 {
            if swapped[k] {
                y.swap(k, k + 1);
            }
            let v = y[k];
            y[k + 1] -= multipliers[k] * v;
        }
        for i in (0..m).rev() {
            let mut v = y[i];
            for j in i + 1..m {
                v -= a[i * m + j] * y[j];
            }
            y[i] = v / a[i * m + i];
        }
        let norm = y.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return f64::INFINITY;
        }
        y.iter_mut().for_each(|v| *v /= norm);
    }
    y[m - 1].norm()
}

/// Modified Gram-Schmidt of `next` against the orthonormal `basis`, twice (the second pass
/// restores orthogonality lost to rounding when the new vector is nearly in the span),
/// adding the coefficients to `column`. On x86-64 with AVX2 and FMA (checked at run time)
/// compiled for them: the same operations in the same order (Rust does not fuse a product
/// and a sum into an FMA), so the same bits, in wider registers.
fn orthogonalize(basis: &[Vec<f64>], next: &mut [f64], column: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the processor supports the features the function is compiled for.
        return unsafe { orthogonalize_avx2(basis, next, column) };
    }
    orthogonalize_kernel(basis, next, column);
}

/// [`orthogonalize_kernel`] with AVX2 and FMA enabled.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn orthogonalize_avx2(basis: &[Vec<f64>], next: &mut [f64], column: &mut [f64]) {
    orthogonalize_kernel(basis, next, column);
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
