//! The eigenvalues of a small real upper Hessenberg matrix (the Arnoldi run's Ritz values,
//! docs/stability.md, "How it is computed") by the Francis double-shift QR iteration
//! without vectors (Wilkinson and Reinsch's hqr, in the form of Press et al., Numerical
//! Recipes, section 11.6). nalgebra's general Schur form first reduces the matrix to
//! Hessenberg form, which an Arnoldi matrix already is, and accumulates its work in
//! dynamic matrices; this works on the m x m block in place.

use nalgebra::{Complex, DMatrix};

/// Iterations allowed for one eigenvalue (or pair) before giving up, as hqr's.
const MAX_ITERATIONS: usize = 30;

/// The eigenvalues of the leading `m` x `m` block of the upper Hessenberg `h` (entries
/// below the subdiagonal are not read), in no particular order; None when an eigenvalue
/// has not separated after [`MAX_ITERATIONS`] double-shift steps.
pub(super) fn eigenvalues(h: &DMatrix<f64>, m: usize) -> Option<Vec<Complex<f64>>> {
    // a[i][j], row major, the Hessenberg part copied.
    let mut a = vec![0.0; m * m];
    let mut norm = 0.0;
    for i in 0..m {
        for j in i.saturating_sub(1)..m {
            a[i * m + j] = h[(i, j)];
            norm += h[(i, j)].abs();
        }
    }
    let at = |i: usize, j: usize| i * m + j;
    let mut values = vec![Complex::new(0.0, 0.0); m];
    // The exceptional shifts' sum, subtracted from the diagonal.
    let mut t = 0.0;
    let mut nn = m as isize - 1;
    while nn >= 0 {
        let n = nn as usize;
        let mut iterations = 0;
        loop {
            // The last negligible subdiagonal entry at or above row n: the active block
            // is rows l..=n.
            let mut l = n;
            while l >= 1 {
                let mut s = a[at(l - 1, l - 1)].abs() + a[at(l, l)].abs();
                if s == 0.0 {
                    s = norm;
                }
                if a[at(l, l - 1)].abs() + s == s {
                    a[at(l, l - 1)] = 0.0;
                    break;
                }
                l -= 1;
            }
            let mut x = a[at(n, n)];
            if l == n {
                // One eigenvalue separated.
                values[n] = Complex::new(x + t, 0.0);
                nn -= 1;
                break;
            }
            let mut y = a[at(n - 1, n - 1)];
            let mut w = a[at(n, n - 1)] * a[at(n - 1, n)];
            if l == n - 1 {
                // Two separated: the 2 x 2 block's eigenvalues.
                let p = 0.5 * (y - x);
                let q = p * p + w;
                let z = q.abs().sqrt();
                x += t;
                if q >= 0.0 {
                    let z = p + z.copysign(p);
                    let second = if z != 0.0 { x - w / z } else { x + z };
                    values[n - 1] = Complex::new(x + z, 0.0);
                    values[n] = Complex::new(second, 0.0);
                } else {
                    values[n - 1] = Complex::new(x + p, -z);
                    values[n] = Complex::new(x + p, z);
                }
                nn -= 2;
                break;
            }
            if iterations == MAX_ITERATIONS {
                return None;
            }
            if iterations == 10 || iterations == 20 {
                // Exceptional shift, for the rare cycles of the standard one.
                t += x;
                for i in 0..=n {
                    a[at(i, i)] -= x;
                }
                let s = a[at(n, n - 1)].abs() + a[at(n - 1, n - 2)].abs();
                x = 0.75 * s;
                y = x;
                w = -0.4375 * s * s;
            }
            iterations += 1;
            // Two consecutive small subdiagonal entries: the double step starts at row k0.
            let (mut p, mut q, mut r): (f64, f64, f64);
            let mut k0 = n - 2;
            loop {
                let z = a[at(k0, k0)];
                let (rr, ss) = (x - z, y - z);
                p = (rr * ss - w) / a[at(k0 + 1, k0)] + a[at(k0, k0 + 1)];
                q = a[at(k0 + 1, k0 + 1)] - z - rr - ss;
                r = a[at(k0 + 2, k0 + 1)];
                let s = p.abs() + q.abs() + r.abs();
                p /= s;
                q /= s;
                r /= s;
                if k0 == l {
                    break;
                }
                let u = a[at(k0, k0 - 1)].abs() * (q.abs() + r.abs());
                let v = p.abs() * (a[at(k0 - 1, k0 - 1)].abs() + z.abs() + a[at(k0 + 1, k0 + 1)].abs());
                if u + v == v {
                    break;
                }
                k0 -= 1;
            }
            for i in k0 + 2..=n {
                a[at(i, i - 2)] = 0.0;
                if i != k0 + 2 {
                    a[at(i, i - 3)] = 0.0;
                }
            }
            // The double QR step on rows l..=n and columns k0..=n.
            let mut k = k0;
            while k < n {
                if k != k0 {
                    p = a[at(k, k - 1)];
                    q = a[at(k + 1, k - 1)];
                    r = if k != n - 1 { a[at(k + 2, k - 1)] } else { 0.0 };
                    x = p.abs() + q.abs() + r.abs();
                    if x != 0.0 {
                        p /= x;
                        q /= x;
                        r /= x;
                    }
                }
                let s = (p * p + q * q + r * r).sqrt().copysign(p);
                if s != 0.0 {
                    if k == k0 {
                        if l != k0 {
                            a[at(k, k - 1)] = -a[at(k, k - 1)];
                        }
                    } else {
                        a[at(k, k - 1)] = -s * x;
                    }
                    p += s;
                    x = p / s;
                    y = q / s;
                    let z = r / s;
                    q /= p;
                    r /= p;
                    for j in k..=n {
                        let mut p = a[at(k, j)] + q * a[at(k + 1, j)];
                        if k != n - 1 {
                            p += r * a[at(k + 2, j)];
                            a[at(k + 2, j)] -= p * z;
                        }
                        a[at(k + 1, j)] -= p * y;
                        a[at(k, j)] -= p * x;
                    }
                    for i in l..=n.min(k + 3) {
                        let mut p = x * a[at(i, k)] + y * a[at(i, k + 1)];
                        if k != n - 1 {
                            p += z * a[at(i, k + 2)];
                            a[at(i, k + 2)] -= p * r;
                        }
                        a[at(i, k + 1)] -= p * q;
                        a[at(i, k)] -= p;
                    }
                }
                k += 1;
            }
        }
    }
    Some(values)
}

#[cfg(test)]
mod tests {
    use super::eigenvalues;
    use nalgebra::{Complex, DMatrix};

    /// The values sorted by real part, then imaginary part, for comparison.
    fn sorted(mut v: Vec<Complex<f64>>) -> Vec<Complex<f64>> {
        v.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        v
    }

    /// On random Hessenberg matrices of every size the Arnoldi run uses (1 to 24), with
    /// real and complex eigenvalues and a wide spread of magnitudes as shift-invert gives,
    /// the eigenvalues are nalgebra's to rounding (1e-10 of the largest: both are backward
    /// stable, and these matrices' eigenvalues are well conditioned enough for that).
    #[test]
    fn eigenvalues_are_nalgebras() {
        let mut state = 7u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for m in 1..=24 {
            for trial in 0..4 {
                let mut h = DMatrix::<f64>::zeros(m + 1, m);
                for j in 0..m {
                    // Columns scaled from 1 down to 1e-6, as the Ritz values of J^-1 M fall off.
                    let scale = 10f64.powf(-6.0 * j as f64 / m as f64);
                    for i in 0..=(j + 1).min(m) {
                        h[(i, j)] = uniform() * scale;
                    }
                }
                if trial == 3 && m > 1 {
                    // A zero subdiagonal entry: the matrix splits.
                    h[(m / 2, m / 2 - 1)] = 0.0;
                }
                let ours = sorted(eigenvalues(&h, m).expect("converges"));
                let theirs = sorted(
                    h.view((0, 0), (m, m))
                        .into_owned()
                        .complex_eigenvalues()
                        .iter()
                        .copied()
                        .collect(),
                );
                let largest = theirs.iter().map(|v| v.norm()).fold(0.0, f64::max);
                for (a, b) in ours.iter().zip(&theirs) {
                    assert!(
                        (a - b).norm() <= 1e-10 * largest,
                        "m {m} trial {trial}: {a} against {b}"
                    );
                }
            }
        }
    }
}
