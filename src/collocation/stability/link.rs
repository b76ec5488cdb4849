//! One link of the conjugate-point sweep (docs/stability.md, "How it is computed" and
//! "Cost"): the Jacobi fields carried across the link's rows, the bound on the eigenvalues
//! of their Q1 - I, and the fields normalized to (dp, dtheta) block I, in one fixed-size
//! kernel compiled for AVX2 and FMA where the processor has them. The kernel writes into
//! the caller's buffers, so the sweep copies no fields from link to link.

use crate::collocation::unknowns::{NODE, P};
use crate::simd::avx2_fma;

/// The six Jacobi fields at a node: row r is component r of a node's unknowns (dp, dtheta,
/// dv, du), column j field j.
pub(super) type Fields = [[f64; 6]; NODE];

/// A 6 x 6 block, row major.
type Block6 = [[f64; 6]; 6];

/// The columns of a link's rows [A | B] (row major, 12 x 24).
const LINK: usize = 2 * NODE;

/// Width of the elimination's rows: A's 12 columns, the six of -B y, and two of padding, so
/// that every row update runs in whole 4-lane vectors and the right-hand sides fill two.
const W: usize = NODE + 6 + 2;
const _: () = assert!(W.is_multiple_of(4));

/// Unknowns of the position increment, the first columns of A and of B.
const POSITION: usize = 3;
const _: () = assert!(P == 0);

/// The listed constants c written out, one instance of a step per row or column so that
/// every loop in it has constant bounds: `array f(args); c...` is `[f(args, c), ...]`,
/// `all f(args); c...` is `true && f::<c>(args) && ...` (stops at the first false), `each
/// f(args); c...` is `f::<c>(args); ...`.
macro_rules! unrolled {
    (array $f:ident $args:tt; $($c:literal)*) => {
        [$(unrolled!(@last $f $args $c)),*]
    };
    (all $f:ident $args:tt; $($c:literal)*) => {
        true $(&& $f::<$c> $args)*
    };
    (each $f:ident $args:tt; $($c:literal)*) => {
        $($f::<$c> $args;)*
    };
    (@last $f:ident ($($arg:expr),*) $c:literal) => {
        $f($($arg,)* $c)
    };
}

/// What [`advance`] found on one link besides the fields it wrote.
pub(super) struct Link {
    /// The max row sum of the absolute values of Q1 - I, Q1 the (dp, dtheta) block of the
    /// fields at node k: a bound on the eigenvalues of Q1 - I.
    pub(super) bound: f64,
    /// Whether the fields at node k are finite.
    pub(super) finite: bool,
    /// Whether the normalized fields (the fields at node k times Q1^-1) were written: false
    /// when Q1 is singular or its condition number (in max-entry norms) is 1e6 or more.
    /// Below 1e6, Q1 is far enough from singular that its inverse is accurate to about 1e-10
    /// relative.
    pub(super) normalized: bool,
}

/// One link of the sweep, with rows `block` ([A | B], 12 x 24 row major) from the fields
/// `y` at node k + 1 (`identity`: their (dp, dtheta) block is exactly I): writes the fields
/// at node k into `next` (A next = -B y) and, when Q1 is well conditioned ([`Link`]), the
/// fields normalized to (dp, dtheta) block I into `normalized`. On x86-64 with AVX2 and FMA
/// (checked at run time) the arithmetic is compiled for them, else for the baseline. None
/// for a zero pivot. `near_identity`: the bound on Q1 - I below which the fields are
/// normalized by an LU solve ([`NEAR_IDENTITY`] in a verdict; 0 for the inverse on every
/// link, as the tests' reference).
pub(super) fn advance(
    block: &[f64; NODE * LINK],
    y: &Fields,
    identity: bool,
    near_identity: f64,
    next: &mut Fields,
    normalized: &mut Fields,
) -> Option<Link> {
    avx2_fma!(advance_kernel(block, y, identity, near_identity, next, normalized))
}

/// [`advance`]'s arithmetic, on fixed-size arrays with loops of constant trip counts.
#[inline(always)]
fn advance_kernel(
    block: &[f64; NODE * LINK],
    y: &Fields,
    identity: bool,
    near_identity: f64,
    next: &mut Fields,
    normalized: &mut Fields,
) -> Option<Link> {
    carry(block, y, identity, structured(block), next)?;
    let q1: &Block6 = next[..6].try_into().ok()?;
    // Row sums in increasing column, as `Iterator::sum` adds (from -0.0).
    let mut bound = 0.0f64;
    for (r, row) in q1.iter().enumerate() {
        let mut sum = -0.0f64;
        for (c, v) in row.iter().enumerate() {
            sum += if r == c { (v - 1.0).abs() } else { v.abs() };
        }
        bound = bound.max(sum);
    }
    let written = if bound < near_identity {
        normalize_near_identity(next, normalized);
        true
    } else {
        match inverse6(q1) {
            Some(inv) if largest(q1) * largest(&inv) < 1e6 => {
                normalize(next, &inv, normalized);
                true
            }
            _ => false,
        }
    };
    Some(Link {
        bound,
        finite: finite(next),
        normalized: written,
    })
}

/// Whether every entry of `fields` is finite: 0 x is (signed) zero for a finite x and NaN
/// for an infinite or NaN one, and a sum with a NaN stays NaN (as `workspace::all_finite`).
#[inline(always)]
fn finite(fields: &Fields) -> bool {
    let mut sums = [0.0f64; 6];
    for row in fields {
        for (sum, x) in sums.iter_mut().zip(row) {
            *sum += x * 0.0;
        }
    }
    sums.iter().all(|&sum| sum == 0.0)
}

/// The largest absolute entry of `m` (0 for none; a NaN entry is passed over, as by
/// `f64::max`).
#[inline(always)]
fn largest(m: &Block6) -> f64 {
    let mut lanes = [0.0f64; 6];
    for row in m {
        for (lane, v) in lanes.iter_mut().zip(row) {
            let a = v.abs();
            if a > *lane {
                *lane = a;
            }
        }
    }
    let mut most = 0.0f64;
    for v in lanes {
        if v > most {
            most = v;
        }
    }
    most
}

/// The fields at node k from those at node k + 1 through one link's rows [A | B], A next =
/// -B y: Gaussian elimination with partial pivoting of the 12 x 18 augmented matrix
/// [A | -B y], then back substitution. When `identity`, the (dp, dtheta) block of y is
/// exactly the identity, and B y = B_(p, theta) + B_(v, u) y_(v, u) takes half the products.
///
/// A's position columns are structurally those of the Hermite-Simpson defect's position
/// rows, -I over zeros (docs/stability.md, "Cost"): when they are (checked), the first three
/// pivots are A's -1 on the diagonal, every multiplier below them is zero, and their
/// elimination steps change nothing, so they are skipped (`structured`, [`structured`]), as
/// are row swaps of a pivot already in place; the other operations are those of the full
/// elimination in the same order, so the same bits. None for a zero pivot.
#[inline(always)]
fn carry(block: &[f64; NODE * LINK], y: &Fields, identity: bool, structured: bool, out: &mut Fields) -> Option<()> {
    // The fields' rows padded to two 4-lane vectors; the padding stays zero through the
    // product and the elimination (zero times and minus zero).
    let mut wide = [[0.0f64; 8]; NODE];
    for (w, row) in wide.iter_mut().zip(y) {
        w[..6].copy_from_slice(row);
    }
    // Built row by row as a whole (no zeroing of the matrix first).
    const _: () = assert!(NODE == 12);
    let mut m = unrolled!(array row(block, &wide, identity); 0 1 2 3 4 5 6 7 8 9 10 11);
    let position = structured || unrolled!(all eliminate(&mut m); 0 1 2);
    if !position {
        return None;
    }
    const _: () = assert!(NODE == 12 && POSITION == 3);
    let pivoted = unrolled!(all eliminate(&mut m); 3 4 5 6 7 8 9 10 11);
    if !pivoted {
        return None;
    }
    let mut x = [[0.0f64; 8]; NODE];
    unrolled!(each substitute(&m, &mut x); 11 10 9 8 7 6 5 4 3 2 1 0);
    for (o, row) in out.iter_mut().zip(&x) {
        o.copy_from_slice(&row[..6]);
    }
    Some(())
}

/// Whether A's position columns in the link's rows `block` are -I over zeros, as the
/// Hermite-Simpson defect's and a jump's position rows make them ([`carry`]).
#[inline(always)]
fn structured(block: &[f64; NODE * LINK]) -> bool {
    block
        .chunks_exact(LINK)
        .enumerate()
        .all(|(r, line)| (0..POSITION).all(|c| line[c] == if r == c { -1.0 } else { 0.0 }))
}

/// Row `r` of the augmented matrix [A | -B y] (padded to [`W`]) of the link's rows `block`,
/// from the padded fields `y` (`identity`: their (dp, dtheta) block is exactly I, and B y =
/// B_(p, theta) + B_(v, u) y_(v, u)).
#[inline(always)]
fn row(block: &[f64; NODE * LINK], y: &[[f64; 8]; NODE], identity: bool, r: usize) -> [f64; W] {
    let line = &block[r * LINK..(r + 1) * LINK];
    let mut product = [0.0f64; 8];
    if identity {
        product[..6].copy_from_slice(&line[NODE..NODE + 6]);
        product_rows::<6>(&mut product, &line[NODE..], y);
    } else {
        product_rows::<0>(&mut product, &line[NODE..], y);
    }
    let mut built = [0.0f64; W];
    built[..NODE].copy_from_slice(&line[..NODE]);
    for (x, p) in built[NODE..].iter_mut().zip(&product) {
        *x = -p;
    }
    built
}

/// Adds B's columns `FROM`.. times the fields' rows `FROM`.. to `product`, column after
/// column (`b`: row r of B).
#[inline(always)]
fn product_rows<const FROM: usize>(product: &mut [f64; 8], b: &[f64], y: &[[f64; 8]; NODE]) {
    for c in FROM..NODE {
        let (bc, yc) = (b[c], &y[c]);
        for j in 0..8 {
            product[j] += bc * yc[j];
        }
    }
}

/// Partial pivoting for column C of `m`: the row from C down with the largest |m[r][C]|
/// (the first of equals) swapped into row C. False when that entry is zero (a zero pivot).
#[inline(always)]
fn pivot<const C: usize, const COLS: usize, const ROWS: usize>(m: &mut [[f64; COLS]; ROWS]) -> bool {
    let mut best = C;
    let mut size = m[C][C].abs();
    for (r, row) in m.iter().enumerate().skip(C + 1) {
        let v = row[C].abs();
        if v > size {
            best = r;
            size = v;
        }
    }
    if m[best][C] == 0.0 {
        return false;
    }
    if best != C {
        m.swap(C, best);
    }
    true
}

/// Column `C` of the elimination: the pivot search among rows C.. (the first largest
/// absolute value), the swap, and row r -= f_r * (pivot row) for every row r below C with
/// f_r = m[r][C] / pivot non-zero. The update runs over the columns from C + 1 rounded down
/// to a multiple of four: the columns before C + 1 are dead in the rows below the pivot
/// (left of the diagonal of any later pivot row; the back substitution reads the upper
/// triangle and the right-hand sides). False for a zero pivot.
#[inline(always)]
fn eliminate<const C: usize>(m: &mut [[f64; W]; NODE]) -> bool {
    if !pivot::<C, W, NODE>(m) {
        return false;
    }
    let inv = 1.0 / m[C][C];
    let pivot_row = m[C];
    let start = (C + 1) & !3;
    // Indexed, as blocks.rs's `eliminate_column` (the iterator form's AVX2 build emits an
    // instruction valgrind 3.19 cannot decode).
    #[allow(clippy::needless_range_loop)]
    for r in C + 1..NODE {
        let row = &mut m[r];
        let f = row[C] * inv;
        if f != 0.0 {
            for j in start..W {
                row[j] -= f * pivot_row[j];
            }
        }
    }
    true
}

/// Row `R` of the back substitution: x[R] = (rhs_R - sum over k > R of m[R][k] x[k]) /
/// m[R][R], the sum in increasing k, on the padded rows.
#[inline(always)]
fn substitute<const R: usize>(m: &[[f64; W]; NODE], x: &mut [[f64; 8]; NODE]) {
    let row = &m[R];
    let mut v = [0.0f64; 8];
    v.copy_from_slice(&row[NODE..]);
    for k in R + 1..NODE {
        let a = row[k];
        for (s, o) in v.iter_mut().zip(&x[k]) {
            *s -= a * o;
        }
    }
    let d = row[R];
    for (o, s) in x[R].iter_mut().zip(&v) {
        *o = s / d;
    }
}

/// The inverse of the 6 x 6 matrix `q` by Gauss-Jordan elimination with partial pivoting;
/// None for a zero pivot.
#[inline(always)]
fn inverse6(q: &Block6) -> Option<Block6> {
    // Rows [q | I], reduced to [I | q^-1].
    let mut a = [[0.0f64; 12]; 6];
    for (r, row) in a.iter_mut().enumerate() {
        row[..6].copy_from_slice(&q[r]);
        row[6 + r] = 1.0;
    }
    let reduced = unrolled!(all jordan(&mut a); 0 1 2 3 4 5);
    if !reduced {
        return None;
    }
    let mut inv = [[0.0f64; 6]; 6];
    for (row, reduced_row) in inv.iter_mut().zip(&a) {
        row.copy_from_slice(&reduced_row[6..]);
    }
    Some(inv)
}

/// Column `C` of [`inverse6`]'s Gauss-Jordan elimination: the pivot search among rows C..,
/// the swap, the pivot row scaled by the pivot's reciprocal, and row r -= f_r * (pivot row)
/// for every other row with f_r = a[r][C] non-zero, over the columns from C + 1 rounded
/// down to a multiple of four (the columns up to C are not read again: later steps read
/// their own columns, the result the right half). False for a zero pivot.
#[inline(always)]
fn jordan<const C: usize>(a: &mut [[f64; 12]; 6]) -> bool {
    if !pivot::<C, 12, 6>(a) {
        return false;
    }
    let p = 1.0 / a[C][C];
    for x in a[C].iter_mut() {
        *x *= p;
    }
    let pivot_row = a[C];
    let start = (C + 1) & !3;
    #[allow(clippy::needless_range_loop)]
    for r in 0..6 {
        let f = a[r][C];
        if r != C && f != 0.0 {
            let row = &mut a[r];
            for j in start..12 {
                row[j] -= f * pivot_row[j];
            }
        }
    }
    true
}

/// The bound on Q1 - I below which [`advance`] normalizes the fields by an LU solve without
/// pivoting ([`normalize_near_identity`]) instead of Q1's inverse. With b the max row sum of
/// |Q1 - I| below 1/2, Q1 is strictly diagonally dominant by rows, Gaussian elimination
/// without pivoting is stable on it (its growth factor is at most 2), and
/// ||Q1^-1||_inf <= 1 / (1 - b) < 2: its condition number in max-entry norms is below
/// 6 (1 + b) / (1 - b) < 18, far below the 1e6 at which the fields are orthonormalized
/// instead, so the path taken is the one the inverse's test would take.
pub(super) const NEAR_IDENTITY: f64 = 0.5;

/// The fields `next` normalized as [`normalize`] does, when the max row sum of |Q1 - I| is
/// below [`NEAR_IDENTITY`]: X = W Q1^-1 for the (dv, du) block W, from X Q1 = W row by row,
/// with Q1 = L U factored without pivoting (x L U = w: z U = w by columns, then x L = z),
/// written to `out` with the identity set exactly. About half the arithmetic of the
/// Gauss-Jordan inverse and the product; the normalized fields differ from theirs by
/// rounding (a unit test keeps them within 1e-13 relative).
#[inline(always)]
fn normalize_near_identity(next: &Fields, out: &mut Fields) {
    // Q1's rows padded to two 4-lane vectors, reduced in place to U (zeros below the
    // diagonal), the multipliers of L in `lower` (zeros on and above its diagonal).
    let mut upper = [[0.0f64; 8]; 6];
    for (w, row) in upper.iter_mut().zip(&next[..6]) {
        w[..6].copy_from_slice(row);
    }
    let mut lower = [[0.0f64; 8]; 6];
    unrolled!(each factor(&mut upper, &mut lower); 0 1 2 3 4);
    for (j, row) in out[..6].iter_mut().enumerate() {
        *row = [0.0; 6];
        row[j] = 1.0;
    }
    for (o, w) in out[6..].iter_mut().zip(&next[6..]) {
        let mut z = [0.0f64; 8];
        z[..6].copy_from_slice(w);
        let mut x = [0.0f64; 8];
        unrolled!(each forward(&upper, &mut z, &mut x); 0 1 2 3 4 5);
        unrolled!(each backward(&lower, &mut x); 5 4 3 2 1);
        o.copy_from_slice(&x[..6]);
    }
}

/// Column `K` of [`normalize_near_identity`]'s LU factorization without pivoting: the
/// multiplier l = a[i][K] / a[K][K] of every row i below K into `lower`, row i -= l (row K)
/// on whole vectors (columns left of K hold zeros in both rows, so stay zero), a[i][K] set
/// to an exact zero.
#[inline(always)]
fn factor<const K: usize>(upper: &mut [[f64; 8]; 6], lower: &mut [[f64; 8]; 6]) {
    let pivot_row = upper[K];
    #[allow(clippy::needless_range_loop)]
    for i in K + 1..6 {
        let l = upper[i][K] / pivot_row[K];
        lower[i][K] = l;
        for j in 0..8 {
            upper[i][j] -= l * pivot_row[j];
        }
        upper[i][K] = 0.0;
    }
}

/// Column `C` of z U = w ([`normalize_near_identity`]): x_C = z_C / U[C][C], then z -=
/// x_C (row C of U), which leaves the columns up to C, already read, and changes the later
/// ones.
#[inline(always)]
fn forward<const C: usize>(upper: &[[f64; 8]; 6], z: &mut [f64; 8], x: &mut [f64; 8]) {
    let xc = z[C] / upper[C][C];
    x[C] = xc;
    for (zj, u) in z.iter_mut().zip(&upper[C]) {
        *zj -= xc * u;
    }
}

/// Row `I` of x L = z ([`normalize_near_identity`], x holding z): x_I is final once the rows
/// after it are done; x -= x_I (row I of L), whose entries from I on are zero.
#[inline(always)]
fn backward<const I: usize>(lower: &[[f64; 8]; 6], x: &mut [f64; 8]) {
    let xi = x[I];
    for (xj, l) in x.iter_mut().zip(&lower[I]) {
        *xj -= xi * l;
    }
}

/// The fields `next` in the basis where their (dp, dtheta) block is the identity, written to
/// `out`: `next` Q1^-1 with `inv` = Q1^-1, the identity set exactly.
#[inline(always)]
fn normalize(next: &Fields, inv: &Block6, out: &mut Fields) {
    for (j, row) in out[..6].iter_mut().enumerate() {
        *row = [0.0; 6];
        row[j] = 1.0;
    }
    for (o, row) in out[6..].iter_mut().zip(&next[6..]) {
        let mut sum = [0.0f64; 6];
        for (x, inv_row) in row.iter().zip(inv) {
            for (s, v) in sum.iter_mut().zip(inv_row) {
                *s += x * v;
            }
        }
        *o = sum;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Matrix6};

    /// Deterministic entries in [-1, 1) (a linear congruential sequence), for test matrices.
    fn entries(seed: u64, n: usize) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// A link block with a dominant diagonal in A, and fields; with `position`, A's and B's
    /// position columns are those of the collocation equations (-I and I over zeros).
    fn link(seed: u64, position: bool) -> ([f64; NODE * LINK], Fields) {
        let mut block: [f64; NODE * LINK] = entries(seed, NODE * LINK).try_into().unwrap();
        for r in 0..NODE {
            block[r * LINK + r] += 8.0;
            if position {
                for c in 0..POSITION {
                    block[r * LINK + c] = if r == c { -1.0 } else { 0.0 };
                    block[r * LINK + NODE + c] = if r == c { 1.0 } else { 0.0 };
                }
            }
        }
        let y: Fields = std::array::from_fn(|r| entries(100 + seed * 13 + r as u64, 6).try_into().unwrap());
        (block, y)
    }

    /// The fields with their (dp, dtheta) block set to the identity.
    fn with_identity(mut y: Fields) -> Fields {
        for (r, row) in y.iter_mut().take(6).enumerate() {
            *row = std::array::from_fn(|c| if r == c { 1.0 } else { 0.0 });
        }
        y
    }

    /// The fixed-size kernel solves A next = -B y as a generic LU does, with and without the
    /// identity shortcut and the structured position columns: to 1e-12 relative (both are
    /// backward stable on these well-conditioned blocks, whose A has a dominant diagonal; the
    /// difference is rounding).
    #[test]
    fn carry_matches_a_generic_lu() {
        for seed in 1..20 {
            for position in [false, true] {
                let (block, fields) = link(seed, position);
                for identity in [false, true] {
                    let y = if identity { with_identity(fields) } else { fields };
                    let mut got = [[0.0; 6]; NODE];
                    carry(&block, &y, identity, structured(&block), &mut got).expect("a regular block");
                    let a = DMatrix::from_fn(NODE, NODE, |r, c| block[r * LINK + c]);
                    let b = DMatrix::from_fn(NODE, NODE, |r, c| block[r * LINK + NODE + c]);
                    let yy = DMatrix::from_fn(NODE, 6, |r, c| y[r][c]);
                    let want = a.lu().solve(&(-(b * yy))).expect("a regular block");
                    let scale = want.amax();
                    for r in 0..NODE {
                        for c in 0..6 {
                            assert!(
                                (got[r][c] - want[(r, c)]).abs() <= 1e-12 * scale,
                                "seed {seed}, position {position}, ({r}, {c})"
                            );
                        }
                    }
                }
            }
        }
    }

    /// Skipping the position columns' elimination steps gives the full elimination's bits
    /// when A's position columns are -I over zeros, and is taken only then.
    #[test]
    fn the_structured_elimination_gives_the_full_one_bits() {
        let bits = |f: &Fields| f.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        // Seeds 20 to 39: rows 3 to NODE - 1 in reverse order, so A's dominant entries in
        // columns 3+ sit off its diagonal and partial pivoting swaps rows there.
        for seed in 1..40 {
            let (mut block, fields) = link(seed, true);
            if seed >= 20 {
                let mut rows: Vec<[f64; LINK]> = block.chunks_exact(LINK).map(|l| l.try_into().unwrap()).collect();
                rows[POSITION..].reverse();
                for (r, line) in rows.iter().enumerate() {
                    block[r * LINK..(r + 1) * LINK].copy_from_slice(line);
                }
            }
            assert!(structured(&block));
            for identity in [false, true] {
                let y = if identity { with_identity(fields) } else { fields };
                let (mut full, mut skipped) = ([[0.0; 6]; NODE], [[0.0; 6]; NODE]);
                carry(&block, &y, identity, false, &mut full).expect("a regular block");
                carry(&block, &y, identity, true, &mut skipped).expect("a regular block");
                assert_eq!(bits(&full), bits(&skipped), "seed {seed}");
            }
            // One entry off the structure (a zero made 1e-300, the -1 made -1 - eps, or NaN).
            for (r, c, value) in [
                (7, 1, 1e-300),
                (2, 2, -1.0 - f64::EPSILON),
                (4, 0, f64::NAN),
                (1, 1, f64::NAN),
            ] {
                let mut other = block;
                other[r * LINK + c] = value;
                assert!(!structured(&other), "({r}, {c})");
            }
        }
        assert!(!structured(&link(1, false).0));
    }

    /// The 6 x 6 Gauss-Jordan inverse: q q^-1 = I to 1e-13 on well-conditioned matrices
    /// (rounding of a 6 x 6 elimination), None for a singular one.
    #[test]
    fn inverse6_inverts_and_refuses_a_singular_matrix() {
        for seed in 1..20 {
            let v = entries(seed, 36);
            let q: Block6 =
                std::array::from_fn(|r| std::array::from_fn(|c| v[6 * r + c] + if r == c { 4.0 } else { 0.0 }));
            let inv = inverse6(&q).expect("regular");
            let product = Matrix6::from_fn(|r, c| q[r][c]) * Matrix6::from_fn(|r, c| inv[r][c]);
            assert!((product - Matrix6::identity()).amax() <= 1e-13, "seed {seed}");
        }
        let mut singular: Block6 = [[1.0; 6]; 6];
        singular[0][0] = 2.0;
        assert!(inverse6(&singular).is_none());
    }

    /// Near the identity (max row sum of |Q1 - I| up to 0.49) the LU solve without pivoting
    /// gives the normalized fields of the inverse to 1e-13 of their largest entry (both are
    /// backward stable, Q1's condition number is below 18: the difference is rounding), and
    /// the identity block exactly.
    #[test]
    fn the_near_identity_normalization_is_the_inverses() {
        for seed in 1..40 {
            let v = entries(seed, NODE * 6);
            let size = 0.49 * seed as f64 / 39.0;
            let next: Fields = std::array::from_fn(|r| {
                std::array::from_fn(|c| match r < 6 {
                    true => f64::from(u8::from(r == c)) + size / 6.0 * v[6 * r + c],
                    false => 3.0 * v[6 * r + c],
                })
            });
            let q1: &Block6 = next[..6].try_into().unwrap();
            let bound = (0..6)
                .map(|r| {
                    (0..6)
                        .map(|c| (q1[r][c] - f64::from(u8::from(r == c))).abs())
                        .sum::<f64>()
                })
                .fold(0.0, f64::max);
            assert!(bound < NEAR_IDENTITY, "seed {seed}");
            let (mut by_inverse, mut by_lu) = ([[0.0; 6]; NODE], [[0.0; 6]; NODE]);
            normalize(&next, &inverse6(q1).expect("regular"), &mut by_inverse);
            normalize_near_identity(&next, &mut by_lu);
            let scale = by_inverse.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for r in 0..NODE {
                for c in 0..6 {
                    let (a, b) = (by_inverse[r][c], by_lu[r][c]);
                    match r < 6 {
                        true => assert_eq!(a.to_bits(), b.to_bits(), "seed {seed}"),
                        false => assert!((a - b).abs() <= 1e-13 * scale, "seed {seed}: ({r}, {c}) {a} {b}"),
                    }
                }
            }
        }
    }

    /// A link's summary: the bound is the max row sum of |Q1 - I|, the normalized fields have
    /// (dp, dtheta) block I and equal next Q1^-1 to 1e-12 (rounding of the inverse and the
    /// product), and non-finite fields are reported as such.
    #[test]
    fn advance_bounds_normalizes_and_sees_non_finite_fields() {
        for seed in 1..10 {
            let (block, fields) = link(seed, true);
            let y = with_identity(fields);
            let (mut next, mut normalized) = ([[0.0; 6]; NODE], [[0.0; 6]; NODE]);
            let link = advance(&block, &y, true, NEAR_IDENTITY, &mut next, &mut normalized).expect("a regular block");
            assert!(link.finite && link.normalized, "seed {seed}");
            let q1 = Matrix6::from_fn(|r, c| next[r][c]);
            let want = (0..6)
                .map(|r| {
                    (0..6)
                        .map(|c| (q1[(r, c)] - if r == c { 1.0 } else { 0.0 }).abs())
                        .sum::<f64>()
                })
                .fold(0.0, f64::max);
            assert_eq!(link.bound, want);
            let inv = q1.try_inverse().expect("regular");
            for r in 0..NODE {
                for c in 0..6 {
                    let expected = if r < 6 {
                        if r == c { 1.0 } else { 0.0 }
                    } else {
                        (0..6).map(|k| next[r][k] * inv[(k, c)]).sum::<f64>()
                    };
                    assert!(
                        (normalized[r][c] - expected).abs() <= 1e-12 * (1.0 + expected.abs()),
                        "seed {seed}"
                    );
                }
            }
        }
        let (block, fields) = link(3, true);
        let mut y = with_identity(fields);
        y[9][2] = f64::INFINITY;
        let (mut next, mut normalized) = ([[0.0; 6]; NODE], [[0.0; 6]; NODE]);
        let link = advance(&block, &y, true, NEAR_IDENTITY, &mut next, &mut normalized).expect("no zero pivot");
        assert!(!link.finite);
    }
}
