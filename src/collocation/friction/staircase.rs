//! The bordered Newton system of tendons with friction solved as one almost-block-diagonal
//! system: each node's unknowns are its 12 backbone unknowns followed by the log tensions
//! z_j of the slips whose span holds the node, and each link's rows its 12 backbone rows
//! followed by the capstan (or stick) rows of the slips on it. A capstan row of link k
//! touches only nodes k and k + 1 (psi_x, psi_z), and the backbone rows see the log tensions
//! of their own link's two nodes (F_z) and, at a termination, of its node: so the bordered
//! matrix
//!
//! ```text
//! [ J      F_z   ]
//! [ psi_x  psi_z ]
//! ```
//!
//! reordered node by node has the staircase of the frictionless Jacobian, with panels a few
//! rows and columns wider. The elimination is that of [`crate::collocation::linear::blocks`]
//! with sizes that vary by node: step k works on the rows carried from step k - 1 (6 plus
//! the log tensions of node k) over link k's rows, eliminates node k's columns with partial
//! pivoting over all of them, keeps the pivot rows for back substitution and carries the
//! rest; the last step is the carried rows with the tip rows. One factorization per
//! Jacobian and one replay per right-hand side, with no Schur complement and no iteration:
//! the cost grows with the mesh, not with its square.

use crate::collocation::unknowns::{BASE_ROWS, NODE};
use crate::simd::{all_finite, avx2_fma};

/// The shape of one elimination step and where its row operations and pivot rows are kept
/// in the staircase's buffers ([`Staircase`]: `swaps`, `factors`, `upper`).
#[derive(Clone, Copy, Debug, Default)]
struct Step {
    /// Rows of the panel (carried and new) and its width (this node's columns and the
    /// next node's; for the last step, this node's only).
    rows: usize,
    width: usize,
    /// Columns eliminated: this node's unknowns.
    pivots: usize,
    /// First of its `pivots` swaps: the row swapped with row c at column c.
    swaps_at: usize,
    /// First of its `pivots * rows` multipliers: that of pivot row c subtracted from row
    /// r at c * rows + r (r > c).
    factors_at: usize,
    /// First of its pivot rows, `pivots` x `width`: the upper triangle in the first
    /// `pivots` columns row major, then the other columns (the next node's) transposed,
    /// column by column ([`keep_pivot_rows`]).
    upper_at: usize,
}

/// Which block of the staircase a caller fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Block {
    /// The base rows: 6 x (node 0's columns).
    Base,
    /// Link k's rows (its node k + 1's column count of them) over nodes k and k + 1.
    Link(usize),
    /// The tip rows: 6 x (the last node's columns).
    Tip,
}

/// The factors of one bordered matrix on a mesh whose node n carries `extra[n]` log
/// tensions (`Default`: an empty one, for no mesh, which allocates nothing).
#[derive(Clone, Debug, Default)]
pub(crate) struct Staircase {
    /// Columns of each node: 12 plus its log tensions.
    columns: Vec<usize>,
    /// Each link's elimination step, then the last node's.
    steps: Vec<Step>,
    /// Every step's swaps, multipliers and pivot rows, one buffer each (at the step's
    /// offsets): three allocations per staircase, not three per node.
    swaps: Vec<usize>,
    factors: Vec<f64>,
    upper: Vec<f64>,
    /// Whether the steps hold the factors of a successful [`Staircase::factor`].
    pub(crate) ready: bool,
    /// First unknown of each node in the node-by-node order.
    first: Vec<usize>,
    /// Scratch: the panel of the step in hand, the carried rows, and a solve's right-hand
    /// side, transformed in place into its solution (node by node, as `first`).
    panel: Vec<f64>,
    carry: Vec<f64>,
    transformed: Vec<f64>,
}

impl Staircase {
    /// Whether this is the staircase of a mesh whose node n carries `extra[n]` log-tension
    /// unknowns ([`Staircase::new`]): every buffer and step then has the shape a new one
    /// would have, and a factorization overwrites what its solves read.
    pub(crate) fn fits(&self, extra: &[usize]) -> bool {
        self.columns.len() == extra.len() && self.columns.iter().zip(extra).all(|(&c, &e)| c == NODE + e)
    }

    /// The staircase of a mesh whose node n carries `extra[n]` log-tension unknowns
    /// (`extra[0]` must be 0: the log tensions are 0 at the base).
    pub(crate) fn new(extra: &[usize]) -> Self {
        // The right-hand side is laid out in block order from row 0 (`solve`).
        debug_assert!(extra.first().is_none_or(|&e| e == 0), "log tensions at the base");
        let columns: Vec<usize> = extra.iter().map(|e| NODE + e).collect();
        let widest = columns.iter().copied().max().unwrap_or(NODE);
        let first = columns
            .iter()
            .scan(0, |acc, c| {
                let at = *acc;
                *acc += c;
                Some(at)
            })
            .collect();
        let total = columns.iter().sum();
        // Each step's shape and offsets (the same for every factorization on this mesh):
        // step k has columns[k] - 6 carried rows (6 at the base) over the next node's rows,
        // and columns[k] pivots.
        let links = columns.len() - 1;
        let (mut swaps_at, mut factors_at, mut upper_at) = (0, 0, 0);
        let steps = (0..=links)
            .map(|k| {
                let (pivots, width, new_rows) = if k < links {
                    (columns[k], columns[k] + columns[k + 1], columns[k + 1])
                } else {
                    (columns[k], columns[k], BASE_ROWS)
                };
                let rows = columns[k] - NODE + BASE_ROWS + new_rows;
                let step = Step {
                    rows,
                    width,
                    pivots,
                    swaps_at,
                    factors_at,
                    upper_at,
                };
                swaps_at += pivots;
                factors_at += pivots * rows;
                upper_at += pivots * width;
                step
            })
            .collect();
        // A panel has at most 2 widest rows (carried and new) and 2 widest columns.
        Staircase {
            steps,
            swaps: zeroed(swaps_at),
            factors: zeroed(factors_at),
            upper: zeroed(upper_at),
            columns,
            ready: false,
            first,
            panel: vec![0.0; 4 * widest * widest],
            carry: vec![0.0; widest * widest],
            transformed: vec![0.0; total],
        }
    }

    /// Rows and columns of `block`.
    #[cfg(test)]
    pub(crate) fn shape(&self, block: Block) -> (usize, usize) {
        match block {
            Block::Base => (BASE_ROWS, self.columns[0]),
            Block::Link(k) => (self.columns[k + 1], self.columns[k] + self.columns[k + 1]),
            Block::Tip => (BASE_ROWS, self.columns[self.columns.len() - 1]),
        }
    }

    /// Factors the matrix whose blocks `fill` writes (row major into a zeroed slice of the
    /// block's `Staircase::shape`). False on a zero or non-finite pivot. On x86-64 with
    /// AVX2 and FMA (checked at run time) compiled for them, as the solve: the same
    /// operations in the same order, so the same bits.
    pub(crate) fn factor(&mut self, fill: impl FnMut(Block, &mut [f64])) -> bool {
        avx2_fma!(self.factor_kernel(fill))
    }

    /// [`Staircase::factor`]'s operations: step by step, the panel of the carried rows over
    /// the new ones, eliminated ([`factor_step`]), with the shapes of the links inside a
    /// span of no, one or two tendons with friction known at compile time.
    #[inline(always)]
    fn factor_kernel(&mut self, mut fill: impl FnMut(Block, &mut [f64])) -> bool {
        self.ready = false;
        let links = self.columns.len() - 1;
        // The carried rows start as the base rows over node 0.
        let c0 = self.columns[0];
        self.carry[..BASE_ROWS * c0].fill(0.0);
        fill(Block::Base, &mut self.carry[..BASE_ROWS * c0]);
        for (k, step) in self.steps.iter().enumerate() {
            let (block, new_rows) = if k < links {
                (Block::Link(k), self.columns[k + 1])
            } else {
                (Block::Tip, BASE_ROWS)
            };
            let this = Panel {
                panel: &mut self.panel[..step.rows * step.width],
                carry: &mut self.carry,
                carried: step.rows - new_rows,
                swaps: &mut self.swaps[step.swaps_at..step.swaps_at + step.pivots],
                factors: &mut self.factors[step.factors_at..step.factors_at + step.pivots * step.rows],
                upper: &mut self.upper[step.upper_at..step.upper_at + step.pivots * step.width],
            };
            // The caller's `fill` inlined into the step (compiled for AVX2 with it): as a call
            // it was compiled for the baseline.
            let ok = match (step.rows, step.width, step.pivots) {
                (18, 24, 12) => factor_step::<18, 24, 12>(
                    this,
                    #[inline(always)]
                    |rows| fill(block, rows),
                ),
                (20, 26, 13) => factor_step::<20, 26, 13>(
                    this,
                    #[inline(always)]
                    |rows| fill(block, rows),
                ),
                (22, 28, 14) => factor_step::<22, 28, 14>(
                    this,
                    #[inline(always)]
                    |rows| fill(block, rows),
                ),
                _ => factor_step_any(this, step, |rows| fill(block, rows)),
            };
            if !ok {
                return false;
            }
        }
        self.ready = true;
        true
    }

    /// Solves the factored system for the right-hand side that `rhs` writes whole into a
    /// slice of the unknowns' length, block after block: the base rows, each link's rows
    /// ([`Block::Link`]: its node k + 1's column count of them) in link order, the tip rows.
    /// The solution is left node by node in [`Staircase::solution`]. False without factors
    /// (then `rhs` is not called) or for a value that is not finite. On x86-64 with AVX2 and
    /// FMA (checked at run time) compiled for them, as the frictionless `solve_again` is: the
    /// same operations in the same order (Rust does not fuse a product and a sum into an
    /// FMA), so the same bits.
    pub(crate) fn solve(&mut self, rhs: impl FnOnce(&mut [f64])) -> bool {
        avx2_fma!(self.solve_kernel(rhs))
    }

    /// The solution of the last [`Staircase::solve`] with factors, node by node: node n's
    /// columns (its 12 unknowns, then its log tensions) after those of the nodes before it.
    pub(crate) fn solution(&self) -> &[f64] {
        &self.transformed
    }

    /// [`Staircase::solve`]'s operations, in place in one buffer of the unknowns' length:
    /// step k's rows occupy its positions `first[k]..` (the rows it carries on are where
    /// step k + 1's rows begin, so nothing is copied between steps); after the replay its
    /// pivot rows' values stay there, and the back substitution overwrites them with node
    /// k's unknowns. Step k's new rows (link k's, or the tip's) begin where the rows it
    /// carries end, at `first[k] + columns[k] - 6` = `first[k + 1] - 6`, right after link
    /// k - 1's rows (the base rows, 6 of them, for link 0), and no step writes past its own
    /// rows: so the right-hand side is written whole before the replay, in block order.
    #[inline(always)]
    fn solve_kernel(&mut self, rhs: impl FnOnce(&mut [f64])) -> bool {
        if !self.ready {
            return false;
        }
        let w = &mut self.transformed[..];
        rhs(w);
        for (k, step) in self.steps.iter().enumerate() {
            let at = self.first[k];
            let rows = &mut w[at..at + step.rows];
            let swaps = &self.swaps[step.swaps_at..step.swaps_at + step.pivots];
            let factors = &self.factors[step.factors_at..step.factors_at + step.pivots * step.rows];
            replay(step, (swaps, factors), rows);
        }
        // Back substitution from the last node: x_k from step k's pivot rows given x_k+1,
        // with the shapes of the steps inside a span known at compile time (the same sums
        // in the same order).
        for (k, step) in self.steps.iter().enumerate().rev() {
            let (head, tail) = w.split_at_mut(self.first[k] + step.pivots);
            let x = &mut head[self.first[k]..];
            let next = &tail[..step.width - step.pivots];
            let upper = &self.upper[step.upper_at..step.upper_at + step.pivots * step.width];
            match (step.pivots, next.len()) {
                (12, 12) => back_substitute::<12, 12>(upper, x, next),
                (13, 13) => back_substitute::<13, 13>(upper, x, next),
                (14, 14) => back_substitute::<14, 14>(upper, x, next),
                _ => back_substitute_any(upper, x, next),
            }
        }
        all_finite(w)
    }
}

/// One elimination step's buffers: its panel, the carried rows (in: this node's columns of
/// the rows carried from the step before, `carried` of them; out: the next node's columns
/// of the rows this step carries on, row by row), and where its swaps, multipliers and
/// pivot rows are kept.
struct Panel<'a> {
    panel: &'a mut [f64],
    carry: &'a mut [f64],
    carried: usize,
    swaps: &'a mut [usize],
    factors: &'a mut [f64],
    upper: &'a mut [f64],
}

/// A step on a panel of `R` rows, `W` columns and `P` pivots, all known at compile time
/// (a link's: W - P new rows, R + P - W carried): the panel zeroed with the carried rows'
/// columns copied in, the new rows filled by `fill` (row major, `W` wide), eliminated
/// ([`eliminate_fixed`]), the pivot rows kept ([`keep_pivot_rows`]) and the other rows'
/// next-node columns carried on. The operations of [`factor_step_any`].
#[inline(always)]
fn factor_step<const R: usize, const W: usize, const P: usize>(step: Panel, fill: impl FnOnce(&mut [f64])) -> bool {
    let carried = const { R + P - W };
    debug_assert_eq!(step.carried, carried);
    let (rows, _) = step.panel[..R * W].as_chunks_mut::<W>();
    let rows: &mut [[f64; W]; R] = rows.try_into().expect("R rows of the panel");
    // In: `carried` rows of P columns; out: R - P rows of W - P.
    let carry = &mut step.carry[..(carried * P).max((R - P) * (W - P))];
    // Zeroed with a zero the compiler cannot see: a literal one turns these stores into one
    // memset of the panel (kilobytes), which runs as `rep stosb`, counted byte by byte.
    let zero = std::hint::black_box(0.0);
    for (r, row) in rows.iter_mut().enumerate() {
        *row = [zero; W];
        if r < carried {
            row[..P].copy_from_slice(&carry[r * P..(r + 1) * P]);
        }
    }
    fill(rows[carried..].as_flattened_mut());
    if !eliminate_fixed::<R, W, P>(rows.as_flattened_mut(), (step.swaps, step.factors)) {
        return false;
    }
    keep_pivot_rows(rows.as_flattened(), W, P, step.upper);
    for (r, row) in rows[P..].iter().enumerate() {
        carry[r * (W - P)..(r + 1) * (W - P)].copy_from_slice(&row[P..]);
    }
    true
}

/// [`factor_step`] for any shape (the first link's, the last node's, and links next to
/// where a span begins or ends).
#[inline(always)]
fn factor_step_any(step: Panel, shape: &Step, fill: impl FnOnce(&mut [f64])) -> bool {
    let (rows, width, ck) = (shape.rows, shape.width, shape.pivots);
    let panel = &mut step.panel[..rows * width];
    // Zeroed row by row with the carried rows' copy: a few short stores each, where one
    // memset of the panel (kilobytes) runs as `rep stosb`, byte by byte.
    for (r, row) in panel.chunks_exact_mut(width).enumerate() {
        if r < step.carried {
            row[..ck].copy_from_slice(&step.carry[r * ck..(r + 1) * ck]);
            row[ck..].fill(0.0);
        } else {
            row.fill(0.0);
        }
    }
    fill(&mut panel[step.carried * width..]);
    if !eliminate_any(panel, rows, width, ck, (step.swaps, step.factors)) {
        return false;
    }
    keep_pivot_rows(panel, width, ck, step.upper);
    let next = width - ck;
    for r in 0..rows - ck {
        let from = (ck + r) * width + ck;
        step.carry[r * next..(r + 1) * next].copy_from_slice(&panel[from..from + next]);
    }
    true
}

/// Keeps the `pivots` pivot rows of an eliminated `width`-column `panel` in `upper`: their
/// first `pivots` columns (the upper triangle) row major, then each further column (the
/// next node's) as a run of `pivots` values, so that the back substitution's coupling
/// sums read whole vectors across the rows. Always inlined: with the shape known at
/// compile time ([`factor_step`]) its loops have constant bounds.
#[inline(always)]
fn keep_pivot_rows(panel: &[f64], width: usize, pivots: usize, upper: &mut [f64]) {
    let (triangle, far) = upper[..pivots * width].split_at_mut(pivots * pivots);
    for (i, row) in panel.chunks_exact(width).take(pivots).enumerate() {
        triangle[i * pivots..(i + 1) * pivots].copy_from_slice(&row[..pivots]);
        for (j, &v) in row[pivots..].iter().enumerate() {
            far[j * pivots + i] = v;
        }
    }
}

/// `true && eliminate_column::<c, R, W>(..) && ...` over the listed columns c: one instance
/// per column, so that every loop in it has constant bounds (as the frictionless
/// elimination's `eliminate_column`).
macro_rules! eliminate_columns {
    ($panel:ident, $swaps:ident, $factors:ident, $R:ident, $W:ident; $($c:literal)*) => {
        true $(&& eliminate_column::<$c, $R, $W>($panel, $swaps, $factors))*
    };
}

/// [`eliminate_any`] on a panel of `R` rows, `W` columns and `P` pivots (12 to 14), all
/// known at compile time, one instance of [`eliminate_column`] per pivot column.
#[inline(always)]
fn eliminate_fixed<const R: usize, const W: usize, const P: usize>(
    panel: &mut [f64],
    (swaps, factors): Record,
) -> bool {
    const { assert!(P >= 12 && P <= 14 && R > P) };
    let (chunks, _) = panel[..R * W].as_chunks_mut::<W>();
    let panel: &mut [[f64; W]; R] = chunks.try_into().expect("R rows of the panel");
    eliminate_columns!(panel, swaps, factors, R, W; 0 1 2 3 4 5 6 7 8 9 10 11)
        && (P < 13 || eliminate_column::<12, R, W>(panel, swaps, factors))
        && (P < 14 || eliminate_column::<13, R, W>(panel, swaps, factors))
}

/// Column `C` of [`eliminate_fixed`]: the pivot search among rows C.., the swap, and row
/// r -= f_r * (pivot row) for every row r below C, f_r = rows[r][C] / pivot, recorded as
/// [`eliminate_any`] records them. The update of a row runs from column C + 1 rounded
/// down to a multiple of four to the end: the columns left of C are dead (zero in the
/// pivot row, never read in the rows below), so every live column sees the operations of
/// [`eliminate_any`] in the same order, and column C is set to zero as there.
#[inline(always)]
fn eliminate_column<const C: usize, const R: usize, const W: usize>(
    panel: &mut [[f64; W]; R],
    swaps: &mut [usize],
    factors: &mut [f64],
) -> bool {
    // The first row of largest |entry|, the largest kept in hand (not read again through
    // `best`): the same choice, NaN never chosen over a number nor a number over a NaN at C.
    let (mut best, mut largest) = (C, panel[C][C].abs());
    for (r, row) in panel.iter().enumerate().skip(C + 1) {
        let size = row[C].abs();
        if size > largest {
            (best, largest) = (r, size);
        }
    }
    let pivot = panel[best][C];
    if pivot == 0.0 || !pivot.is_finite() {
        return false;
    }
    panel.swap(C, best);
    swaps[C] = best;
    let inverse = 1.0 / pivot;
    let start = (C + 1) & !3;
    let prow = panel[C];
    let factors: &mut [f64; R] = (&mut factors[C * R..(C + 1) * R]).try_into().expect("R multipliers");
    #[allow(clippy::needless_range_loop)]
    for r in C + 1..R {
        let row = &mut panel[r];
        let f = row[C] * inverse;
        factors[r] = f;
        if f != 0.0 {
            for j in start..W {
                row[j] -= f * prow[j];
            }
            row[C] = 0.0;
        }
    }
    true
}

/// Gaussian elimination with partial pivoting of the first `pivots` columns of the
/// `rows` x `width` row-major `panel`, recording the swaps and multipliers in `step`.
/// False on a zero or non-finite pivot.
#[inline(always)]
fn eliminate_any(panel: &mut [f64], rows: usize, width: usize, pivots: usize, (swaps, factors): Record) -> bool {
    for c in 0..pivots {
        let (mut best, mut largest) = (c, panel[c * width + c].abs());
        for r in c + 1..rows {
            let size = panel[r * width + c].abs();
            if size > largest {
                (best, largest) = (r, size);
            }
        }
        let pivot = panel[best * width + c];
        if pivot == 0.0 || !pivot.is_finite() {
            return false;
        }
        if best != c {
            for j in 0..width {
                panel.swap(c * width + j, best * width + j);
            }
        }
        swaps[c] = best;
        let inverse = 1.0 / pivot;
        let (top, below) = panel.split_at_mut((c + 1) * width);
        let prow = &top[c * width + c + 1..(c + 1) * width];
        for (i, row) in below.chunks_exact_mut(width).enumerate() {
            let f = row[c] * inverse;
            factors[c * rows + c + 1 + i] = f;
            if f != 0.0 {
                row[c] = 0.0;
                for (x, p) in row[c + 1..].iter_mut().zip(prow) {
                    *x -= f * p;
                }
            }
        }
    }
    true
}

/// A step's swaps and multipliers, the slices of the staircase's buffers it writes.
type Record<'a> = (&'a mut [usize], &'a mut [f64]);

/// `len` zeros, grown 256 at a time: one memset of kilobytes runs as `rep stosb`, which
/// callgrind counts byte by byte, where short ones are a few vector stores.
fn zeroed<T: Copy + Default>(len: usize) -> Vec<T> {
    let mut out = Vec::with_capacity(len);
    while out.len() < len {
        let next = (out.len() + 256).min(len);
        out.resize(next, T::default());
    }
    out
}

/// The unknowns x of a step's node, `CK` of them, from its pivot rows `upper` (the
/// triangle row major, then the next node's columns transposed: [`Staircase::factor`]),
/// whose right-hand sides `x` holds on entry, and the next node's `N` unknowns `next`:
/// x_i = (rhs_i - sum_j U_i,CK+j next_j - sum_j>i U_ij x_j) / U_ii, each sum in ascending
/// j from -0.0 as [`back_substitute_any`]'s. The coupling sums of all rows run at once
/// over the transposed columns (whole vectors across the rows, each lane the same
/// additions in the same order), the rest row by row.
#[inline(always)]
fn back_substitute<const CK: usize, const N: usize>(upper: &[f64], x: &mut [f64], next: &[f64]) {
    let (triangle, far) = upper[..CK * (CK + N)].split_at(CK * CK);
    let (triangle, _) = triangle.as_chunks::<CK>();
    let (far, _) = far.as_chunks::<CK>();
    let far: &[[f64; CK]; N] = far.try_into().expect("N transposed columns");
    let next: &[f64; N] = next.try_into().expect("N unknowns of the next node");
    let x: &mut [f64; CK] = x.try_into().expect("CK unknowns");
    let mut coupled = [-0.0; CK];
    for (column, b) in far.iter().zip(next) {
        for (sum, a) in coupled.iter_mut().zip(column) {
            *sum += a * b;
        }
    }
    for i in (0..CK).rev() {
        let row = &triangle[i];
        let mut own = -0.0;
        for j in i + 1..CK {
            own += row[j] * x[j];
        }
        x[i] = (x[i] - coupled[i] - own) / row[i];
    }
}

/// [`back_substitute`] for any shape (`x.len()` unknowns, `next.len()` of the next node).
#[inline(always)]
fn back_substitute_any(upper: &[f64], x: &mut [f64], next: &[f64]) {
    let ck = x.len();
    let (triangle, far) = upper.split_at(ck * ck);
    for i in (0..ck).rev() {
        let row = &triangle[i * ck..(i + 1) * ck];
        let coupled: f64 = far.chunks_exact(ck).zip(next).map(|(column, b)| column[i] * b).sum();
        let own: f64 = row[i + 1..].iter().zip(&x[i + 1..]).map(|(a, b)| a * b).sum();
        x[i] = (x[i] - coupled - own) / row[i];
    }
}

/// Applies a step's recorded swaps and eliminations to a right-hand side of its rows: for
/// the panels [`eliminate_fixed`] eliminates, with their shape known at compile time
/// ([`replay_column`]), else [`replay_any`]; the same operations either way.
#[inline(always)]
fn replay(step: &Step, record: (&[usize], &[f64]), v: &mut [f64]) {
    match (step.rows, step.pivots) {
        (18, 12) => replay_fixed::<18, 12>(record, v),
        (20, 13) => replay_fixed::<20, 13>(record, v),
        (22, 14) => replay_fixed::<22, 14>(record, v),
        _ => replay_any(step, record, v),
    }
}

/// [`replay`] on `R` rows with `P` pivots (12 to 14), one instance of [`replay_column`]
/// per pivot column.
#[inline(always)]
fn replay_fixed<const R: usize, const P: usize>((swaps, factors): (&[usize], &[f64]), v: &mut [f64]) {
    const { assert!(P >= 12 && P <= 14 && R > P) };
    let v: &mut [f64; R] = (&mut v[..R]).try_into().expect("R rows");
    let (swaps, factors) = (&swaps[..P], &factors[..P * R]);
    macro_rules! replay_columns {
        ($($c:literal)*) => {
            $(replay_column::<$c, R>(swaps, factors, v);)*
        };
    }
    replay_columns!(0 1 2 3 4 5 6 7 8 9 10 11);
    if P > 12 {
        replay_column::<12, R>(swaps, factors, v);
    }
    if P > 13 {
        replay_column::<13, R>(swaps, factors, v);
    }
}

/// Column `C` of [`replay_fixed`]: the swap, then row r -= f_r * (pivot row's value) for
/// the rows below C, as [`replay_any`] does.
#[inline(always)]
fn replay_column<const C: usize, const R: usize>(swaps: &[usize], factors: &[f64], v: &mut [f64; R]) {
    v.swap(C, swaps[C]);
    let pivot = v[C];
    if pivot != 0.0 {
        let factors: &[f64; R] = factors[C * R..(C + 1) * R].try_into().expect("R multipliers");
        for r in C + 1..R {
            v[r] -= factors[r] * pivot;
        }
    }
}

/// [`replay`] for any shape.
#[inline(always)]
fn replay_any(step: &Step, (swaps, factors): (&[usize], &[f64]), v: &mut [f64]) {
    for c in 0..step.pivots {
        v.swap(c, swaps[c]);
        let pivot = v[c];
        if pivot != 0.0 {
            let factors = &factors[c * step.rows + c + 1..(c + 1) * step.rows];
            for (x, f) in v[c + 1..].iter_mut().zip(factors) {
                *x -= f * pivot;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random generator (no dependency): values in [-1, 1].
    fn generator(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// A random staircase (node 0 plain, nodes 1..=3 with one log tension, node 4 with
    /// none: a span ending before the tip) solved against a dense LU of the same matrix.
    #[test]
    fn staircase_matches_a_dense_solve() {
        dense_check(&[0, 1, 2, 1, 0]);
    }

    /// Spans of one and of two tendons with friction, whose inner links' panels (20 x 26 and
    /// 22 x 28) the compile-time kernels eliminate and replay, and links past a span's end
    /// (18 x 24), against a dense LU.
    #[test]
    fn fixed_panels_match_a_dense_solve() {
        dense_check(&[0, 1, 1, 1, 1]);
        dense_check(&[0, 2, 2, 2, 2, 0]);
        // A span ending halfway: links without log tensions (18 x 24) after it.
        dense_check(&[0, 1, 1, 0, 0, 0]);
    }

    /// The compile-time kernels give the bits of the run-time ones: the multipliers, swaps
    /// and live panel entries (pivot rows from their diagonal on, carried rows right of the
    /// pivots) of one elimination, and a replayed right-hand side, on random panels of the
    /// three shapes.
    #[test]
    fn fixed_kernels_give_the_run_time_bits() {
        let mut random = generator(777);
        for (rows, width, pivots) in [(18, 24, 12), (20, 26, 13), (22, 28, 14)] {
            let panel: Vec<f64> = (0..rows * width).map(|_| random()).collect();
            let (mut fixed, mut any) = (panel.clone(), panel);
            let step = Step {
                rows,
                width,
                pivots,
                ..Step::default()
            };
            let (mut swaps_a, mut swaps_b) = (vec![0; pivots], vec![0; pivots]);
            let (mut factors_a, mut factors_b) = (vec![0.0; pivots * rows], vec![0.0; pivots * rows]);
            let record = (&mut swaps_a[..], &mut factors_a[..]);
            assert!(match pivots {
                12 => eliminate_fixed::<18, 24, 12>(&mut fixed, record),
                13 => eliminate_fixed::<20, 26, 13>(&mut fixed, record),
                _ => eliminate_fixed::<22, 28, 14>(&mut fixed, record),
            });
            assert!(eliminate_any(
                &mut any,
                rows,
                width,
                pivots,
                (&mut swaps_b, &mut factors_b)
            ));
            assert_eq!(swaps_a, swaps_b);
            assert_eq!(factors_a, factors_b);
            for r in 0..rows {
                let live = if r < pivots { r } else { pivots };
                let bits = |p: &[f64]| {
                    p[r * width + live..(r + 1) * width]
                        .iter()
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>()
                };
                assert_eq!(bits(&fixed), bits(&any), "row {r}");
            }
            let v: Vec<f64> = (0..rows).map(|_| random()).collect();
            let (mut u, mut w) = (v.clone(), v);
            replay(&step, (&swaps_a, &factors_a), &mut u);
            replay_any(&step, (&swaps_b, &factors_b), &mut w);
            assert_eq!(
                u.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                w.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
            );
        }
    }

    /// The compile-time back substitution gives the bits of the run-time one, on random
    /// pivot rows of the shapes inside a span (a quarter of their entries and right-hand
    /// sides signed zeros, whose sums' signs depend on the additions' order and start).
    #[test]
    fn fixed_back_substitution_gives_the_run_time_bits() {
        let mut random = generator(4242);
        let mut value = |i: usize| match i % 8 {
            0 => 0.0,
            4 => -0.0,
            _ => random(),
        };
        for (ck, n) in [(12, 12), (13, 13), (14, 14)] {
            let mut upper: Vec<f64> = (0..ck * (ck + n)).map(&mut value).collect();
            // Pivots away from zero, as the elimination leaves them.
            for i in 0..ck {
                upper[i * ck + i] = 1.0 + (i as f64) / 7.0;
            }
            let next: Vec<f64> = (0..n).map(&mut value).collect();
            let rhs: Vec<f64> = (0..ck).map(|i| value(i + 3)).collect();
            let (mut fixed, mut any) = (rhs.clone(), rhs);
            match ck {
                12 => back_substitute::<12, 12>(&upper, &mut fixed, &next),
                13 => back_substitute::<13, 13>(&upper, &mut fixed, &next),
                _ => back_substitute::<14, 14>(&upper, &mut fixed, &next),
            }
            back_substitute_any(&upper, &mut any, &next);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fixed), bits(&any), "{ck} x {n}");
        }
    }

    /// A random staircase whose node n carries `extra[n]` log tensions, factored and solved
    /// against a dense LU of the same matrix.
    fn dense_check(extra: &[usize]) {
        let mut stairs = Staircase::new(extra);
        let columns: Vec<usize> = extra.iter().map(|e| NODE + e).collect();
        let first: Vec<usize> = columns
            .iter()
            .scan(0, |acc, c| {
                let at = *acc;
                *acc += c;
                Some(at)
            })
            .collect();
        let n: usize = columns.iter().sum();
        let mut random = generator(12345);
        let mut dense = vec![0.0; n * n];
        let links = extra.len() - 1;
        let mut row = 0;
        let mut blocks = Vec::new();
        for b in std::iter::once(Block::Base)
            .chain((0..links).map(Block::Link))
            .chain(std::iter::once(Block::Tip))
        {
            let (rows, width) = stairs.shape(b);
            let col0 = match b {
                Block::Base => 0,
                Block::Link(k) => first[k],
                Block::Tip => first[links],
            };
            let values: Vec<f64> = (0..rows * width).map(|_| random()).collect();
            for r in 0..rows {
                for c in 0..width {
                    dense[(row + r) * n + col0 + c] = values[r * width + c];
                }
            }
            blocks.push((b, values));
            row += rows;
        }
        assert_eq!(row, n);
        assert!(stairs.factor(|b, out| {
            let (_, v) = blocks.iter().find(|(x, _)| *x == b).unwrap();
            out.copy_from_slice(v);
        }));
        let rhs: Vec<f64> = (0..n).map(|_| random()).collect();
        // The dense rows are in block order and its columns node by node, as the
        // staircase takes the right-hand side and leaves the solution.
        assert!(stairs.solve(|w| w.copy_from_slice(&rhs)));
        let x = stairs.solution().to_vec();
        let mut a = dense.clone();
        let mut expected = rhs.clone();
        assert!(crate::dense::solve_dense(&mut a, &mut expected, n));
        for (got, want) in x.iter().zip(&expected) {
            // Two pivoted eliminations of a random matrix of 66 to 80 unknowns (condition
            // numbers of a few hundred) agree to rounding times the condition number.
            assert!((got - want).abs() < 1e-10 * (1.0 + want.abs()), "{got} vs {want}");
        }
    }
}
