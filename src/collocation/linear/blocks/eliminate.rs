//! The elimination of one panel of [`super::BlockElimination`]: Gaussian elimination with
//! partial pivoting of a node's 12 columns, two columns a pass.

use super::{NODE, Record};
use crate::simd::avx2_fma;

/// [`eliminate`] compiled for AVX2 and FMA when the processor has them (checked at run
/// time, the result cached: `crate::simd`), else for the baseline x86-64 or other target.
pub(super) fn eliminate_fast<const R: usize, const W: usize, const ALWAYS: usize>(
    rows: &mut [[f64; W]; R],
    record: &mut Record,
) -> bool {
    avx2_fma!(eliminate::<R, W, ALWAYS>(rows, record))
}

/// Gaussian elimination with partial pivoting of the first [`NODE`] columns of `rows` (each
/// `W` wide: the columns to eliminate, further columns, right-hand sides, padding):
/// afterwards rows 0..NODE are upper triangular in those columns and the remaining rows are
/// zero there (up to dead entries, below). The multipliers use the pivot's reciprocal (one
/// division per column, as LAPACK's dgetf2). Columns from `ALWAYS` on (right-hand sides
/// that must see every operation [`super::replay`] would apply) are updated also by a zero
/// multiplier; `ALWAYS = W` for none. Returns false on a zero pivot. The columns go in pairs,
/// each its own instance of [`eliminate_pair`], so that its loops have constant bounds and
/// compile to straight-line vector code.
#[inline(always)]
fn eliminate<const R: usize, const W: usize, const ALWAYS: usize>(
    rows: &mut [[f64; W]; R],
    record: &mut Record,
) -> bool {
    const _: () = assert!(NODE == 12);
    eliminate_pair::<0, R, W, ALWAYS>(rows, record)
        && eliminate_pair::<2, R, W, ALWAYS>(rows, record)
        && eliminate_pair::<4, R, W, ALWAYS>(rows, record)
        && eliminate_pair::<6, R, W, ALWAYS>(rows, record)
        && eliminate_pair::<8, R, W, ALWAYS>(rows, record)
        && eliminate_pair::<10, R, W, ALWAYS>(rows, record)
}

/// The row of the first largest magnitude among `values[from..]` and that magnitude: the
/// row a search that compares each entry with the best one's, read again, would choose
/// (NaN never wins; a NaN at `from` stays).
#[inline(always)]
fn largest_from<const R: usize>(values: &[f64; R], from: usize) -> (usize, f64) {
    let mut best = from;
    let mut largest = values[from].abs();
    for (r, v) in values.iter().enumerate().skip(from + 1) {
        let size = v.abs();
        if size > largest {
            best = r;
            largest = size;
        }
    }
    (best, largest)
}

/// Whether a pivot of magnitude `size` (sign bit clear, as `abs` leaves it) is usable: not
/// zero, finite, not NaN. On the bits: those of the magnitudes 0 < size < infinity are
/// exactly 1..infinity's; compared as floats, LLVM tested the exponent apart (20
/// instructions a column).
#[inline(always)]
fn usable(size: f64) -> bool {
    size.to_bits().wrapping_sub(1) < f64::INFINITY.to_bits() - 1
}

/// Swaps rows `a` < `b` from column `from` on, entry by entry (`rows.swap` went through a
/// copy on the stack).
#[inline(always)]
fn swap_rows<const W: usize>(rows: &mut [[f64; W]], a: usize, b: usize, from: usize) {
    let (head, tail) = rows.split_at_mut(b);
    for (x, y) in head[a][from..].iter_mut().zip(tail[0][from..].iter_mut()) {
        std::mem::swap(x, y);
    }
}

/// Columns `C` and C + 1 of [`eliminate`], with the operations of a column-by-column
/// elimination on every live entry in the same order, so the same bits:
///
/// - column C: the pivot search among rows C.., the swap, the multipliers f_r =
///   rows[r][C] / pivot of the rows below, and each row's column C + 1 after its operation
///   (rows[r][C + 1] - f_r pivot row[C + 1], where f_r is not zero), which is all the
///   pivot search of column C + 1 needs;
/// - column C + 1: its pivot search on those values, the swap of two rows that both still
///   lack column C's operation (their multipliers swapped with them), column C's operation
///   on the new pivot row, then for every row r below it the multiplier g_r and both
///   operations in one pass over the row, f_r's then g_r's on each entry (a zero multiplier's
///   only on the columns from `ALWAYS`): each entry of a row is read and written once for
///   the two columns.
///
/// An operation runs over the columns from its column + 1 rounded down to a multiple of four
/// (whole 4-lane vectors; `W` is a multiple of four), and the pass over the rows below
/// C + 1 from C + 2 rounded down: the columns before are dead in those rows, since they
/// lie left of the diagonal of any row that becomes a pivot row later and the rows carried
/// on are read from column [`NODE`] on. Dead entries hold what the skipped operations would
/// have changed, never read. For the same reason a swap leaves the whole 4-lane vectors left
/// of its column where they are: dead in both rows.
#[inline(always)]
fn eliminate_pair<const C: usize, const R: usize, const W: usize, const ALWAYS: usize>(
    rows: &mut [[f64; W]; R],
    record: &mut Record,
) -> bool {
    // Column C.
    let column: [f64; R] = std::array::from_fn(|r| rows[r][C]);
    let (best, largest) = largest_from(&column, C);
    if !usable(largest) {
        return false;
    }
    let pivot = rows[best][C];
    if best != C {
        swap_rows(rows, C, best, C & !3);
    }
    record.swaps[C] = best;
    let inverse = 1.0 / pivot;
    // The pivot rows by reference, the rows below them apart: copies of the pivot rows
    // (the compiler's for `let prow = rows[C]`) went through the stack, 14 instructions a row.
    let (head, below) = rows.split_at_mut(C + 1);
    let prow = &head[C];
    // The rows' multipliers and column C + 1 after column C's operation, by position.
    let mut f = [0.0; R];
    let mut next = [0.0; R];
    // Indexed, not `iter_mut().enumerate().skip(..)`: that form's AVX2 build emits a
    // `vmovq xmm, xmm` valgrind 3.19 cannot decode (docs/benchmarks.md, "Control Jacobian").
    #[allow(clippy::needless_range_loop)]
    for r in C + 1..R {
        let row = &below[r - C - 1];
        let factor = row[C] * inverse;
        record.factors[C][r] = factor;
        f[r] = factor;
        next[r] = if factor != 0.0 {
            row[C + 1] - factor * prow[C + 1]
        } else {
            row[C + 1]
        };
    }
    // Column C + 1.
    let (best, largest) = largest_from(&next, C + 1);
    if !usable(largest) {
        return false;
    }
    let pivot = next[best];
    if best != C + 1 {
        swap_rows(below, 0, best - C - 1, (C + 1) & !3);
        f.swap(C + 1, best);
        next.swap(C + 1, best);
    }
    record.swaps[C + 1] = best;
    let (pivot_row, below) = below.split_at_mut(1);
    let row = &mut pivot_row[0];
    let from = (C + 1) & !3;
    let factor = f[C + 1];
    if factor != 0.0 {
        for j in from..W {
            row[j] -= factor * prow[j];
        }
    } else {
        for j in ALWAYS..W {
            row[j] -= factor * prow[j];
        }
    }
    let inverse = 1.0 / pivot;
    let prow2 = &pivot_row[0];
    let from = (C + 2) & !3;
    #[allow(clippy::needless_range_loop)]
    for r in C + 2..R {
        let factor = f[r];
        let factor2 = next[r] * inverse;
        record.factors[C + 1][r] = factor2;
        let row = &mut below[r - C - 2];
        match (factor != 0.0, factor2 != 0.0) {
            (true, true) => {
                for j in from..W {
                    row[j] = (row[j] - factor * prow[j]) - factor2 * prow2[j];
                }
            }
            (true, false) => {
                for j in from..W {
                    row[j] -= factor * prow[j];
                }
                for j in ALWAYS..W {
                    row[j] -= factor2 * prow2[j];
                }
            }
            (false, true) => {
                for j in ALWAYS..W {
                    row[j] -= factor * prow[j];
                }
                for j in from..W {
                    row[j] -= factor2 * prow2[j];
                }
            }
            (false, false) => {
                for j in ALWAYS..W {
                    row[j] = (row[j] - factor * prow[j]) - factor2 * prow2[j];
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::super::{COLS, EMPTY, LAST_COLS, LAST_WIDE, ROWS, WIDE};
    use super::*;

    /// The column-by-column elimination [`eliminate`] replaced (each column's search, swap
    /// and row operations in turn, column C zeroed in the rows below): the reference its
    /// live entries and records must match bit for bit.
    #[allow(clippy::needless_range_loop)]
    fn eliminate_by_columns<const R: usize, const W: usize, const ALWAYS: usize>(
        rows: &mut [[f64; W]; R],
        record: &mut Record,
    ) -> bool {
        for c in 0..NODE {
            let mut best = c;
            for r in c + 1..R {
                if rows[r][c].abs() > rows[best][c].abs() {
                    best = r;
                }
            }
            let pivot = rows[best][c];
            if pivot == 0.0 || !pivot.is_finite() {
                return false;
            }
            rows.swap(c, best);
            record.swaps[c] = best;
            let inverse = 1.0 / pivot;
            let prow = rows[c];
            for r in c + 1..R {
                let row = &mut rows[r];
                let f = row[c] * inverse;
                record.factors[c][r] = f;
                if f != 0.0 {
                    for j in (c + 1) & !3..W {
                        row[j] -= f * prow[j];
                    }
                    row[c] = 0.0;
                } else {
                    for j in ALWAYS..W {
                        row[j] -= f * prow[j];
                    }
                }
            }
        }
        true
    }

    /// Panels with what the elimination meets: exact zeros where a column has few non-zeros
    /// (as a node's position columns), ties of magnitude, signed zeros, both signs, and
    /// what it refuses or carries through (NaN, infinities); with `ALWAYS` below `W` also
    /// zero multipliers on the right-hand sides.
    fn panels<const R: usize, const W: usize>() -> Vec<[[f64; W]; R]> {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        (0..400)
            .map(|case| {
                let mut rows = [[0.0; W]; R];
                for (r, row) in rows.iter_mut().enumerate() {
                    for (j, v) in row.iter_mut().enumerate() {
                        let u = next();
                        // Sparse first columns in half the cases, a few exact ties and -0.
                        let zero = (case % 2 == 0 && j < 4 && u % 3 != 0) || u % 11 == 0;
                        *v = if zero {
                            if u % 2 == 0 { 0.0 } else { -0.0 }
                        } else if u % 13 == 0 {
                            if r % 2 == 0 { 1.5 } else { -1.5 }
                        } else {
                            (u >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
                        };
                    }
                }
                // In one case of five a NaN or an infinity somewhere: the searches and the
                // skipped operations must treat them as the reference does.
                if case % 5 == 1 {
                    let u = next();
                    let (r, j) = ((u % R as u64) as usize, ((u >> 8) % W as u64) as usize);
                    rows[r][j] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][(u >> 16) as usize % 3];
                }
                rows
            })
            .collect()
    }

    /// Compares [`eliminate`] (as compiled here) with the column-by-column reference on the
    /// live entries: the pivot rows from their diagonal, the other rows from column
    /// [`NODE`], the swaps and the multipliers below each pivot.
    fn matches_the_column_by_column_reference<const R: usize, const W: usize, const ALWAYS: usize>() {
        for (case, panel) in panels::<R, W>().into_iter().enumerate() {
            let (mut paired, mut reference) = (panel, panel);
            let (mut a, mut b) = (EMPTY, EMPTY);
            let ok = eliminate_fast::<R, W, ALWAYS>(&mut paired, &mut a);
            assert_eq!(
                ok,
                eliminate_by_columns::<R, W, ALWAYS>(&mut reference, &mut b),
                "case {case}"
            );
            if !ok {
                continue;
            }
            assert_eq!(a.swaps, b.swaps, "case {case}");
            for c in 0..NODE {
                for r in c + 1..R {
                    assert_eq!(
                        a.factors[c][r].to_bits(),
                        b.factors[c][r].to_bits(),
                        "case {case} factor {c} {r}"
                    );
                }
            }
            for r in 0..R {
                for j in r.min(NODE)..W {
                    assert_eq!(
                        paired[r][j].to_bits(),
                        reference[r][j].to_bits(),
                        "case {case} row {r} column {j}"
                    );
                }
            }
        }
    }

    /// The paired elimination gives the column-by-column elimination's bits, in each shape
    /// it is used: the panels of a solve and of the carried right-hand sides, and the last
    /// node's rows of both.
    #[test]
    fn pairs_give_the_column_by_column_bits() {
        matches_the_column_by_column_reference::<ROWS, COLS, COLS>();
        matches_the_column_by_column_reference::<ROWS, WIDE, { 2 * NODE }>();
        matches_the_column_by_column_reference::<NODE, LAST_COLS, LAST_COLS>();
        matches_the_column_by_column_reference::<NODE, LAST_WIDE, NODE>();
    }
}
