//! Structured elimination of the almost-block-diagonal collocation Jacobian: Gaussian
//! elimination with partial pivoting that only ever touches the staircase.
//!
//! Rows come as [base (6); link 0 (12); ...; link N-1 (12); tip (6)] and node k's 12
//! columns are touched only by the 6 rows left over from the step before (at step 0, the
//! base rows) and by link k. So step k works on an 18 x 24 dense panel: the 6 leftover rows
//! (non-zero in block k only) over the 12 link rows (blocks k and k + 1), eliminates block
//! k's 12 columns choosing pivots among all 18 rows (every row with a non-zero in those
//! columns: this *is* partial pivoting on the whole matrix), keeps the 12 pivot rows for back
//! substitution and passes the other 6 rows on. The last step is a 12 x 12 dense solve of
//! the leftover and tip rows. No fill outside the staircase, about 6 kflop per node (5.4 in the elimination, 0.4 in
//! the back substitution), no
//! allocation after the first factoring.

use std::time::{Duration, Instant};

use crate::collocation::unknowns::{BASE_COLUMNS, BASE_ROWS, NODE, THETA, TIP_COLUMNS, TIP_ROWS, link_row, tip_row};
use crate::simd::avx2_fma;

mod eliminate;

use eliminate::eliminate_fast;

/// Rows carried from one step to the next: at step 0 the base rows; after each step the
/// rows left over once a node's 12 pivots are chosen, as many as there are base rows.
const CARRY: usize = BASE_ROWS;
// The last step solves the carried rows together with the tip rows for the last node.
const _: () = assert!(CARRY + TIP_ROWS == NODE && BASE_COLUMNS == CARRY);
/// Rows of a panel: carried rows plus one link.
const ROWS: usize = CARRY + NODE;
/// Columns of a panel: two nodes, the right-hand side in column 2 NODE, and padding to a
/// multiple of four, so that every row update of [`eliminate::eliminate_fast`] runs in whole 4-lane vectors.
const COLS: usize = 2 * NODE + 4;
/// Columns of the last node's rows: its unknowns, the right-hand side, padding as [`COLS`].
const LAST_COLS: usize = NODE + 4;
/// Right-hand sides [`BlockElimination::factor_with_last`] carries through one elimination.
pub const CARRIED: usize = 8;
/// Columns of its panels: two nodes and [`CARRIED`] right-hand sides.
const WIDE: usize = 2 * NODE + CARRIED;
/// Columns of its last node's rows.
const LAST_WIDE: usize = NODE + CARRIED;
const _: () = assert!(
    COLS.is_multiple_of(4) && LAST_COLS.is_multiple_of(4) && WIDE.is_multiple_of(4) && LAST_WIDE.is_multiple_of(4)
);

/// The row operations of one elimination step, kept so that further right-hand sides can
/// be solved with the same factors.
#[derive(Clone, Copy)]
struct Record {
    /// Row swapped with row c at column c.
    swaps: [usize; NODE],
    /// Multiplier of pivot row c subtracted from row r (rows below c).
    factors: [[f64; ROWS]; NODE],
}

const EMPTY: Record = Record {
    swaps: [0; NODE],
    factors: [[0.0; ROWS]; NODE],
};

/// The working rows of one elimination, `W` columns wide (the last node's rows `LW`), kept
/// between eliminations so that none zeroes them; allocated by the first.
struct Scratch<const W: usize, const LW: usize> {
    /// The panel of a step: the carried rows in rows 0..[`CARRY`], then one link's rows.
    panel: [[f64; W]; ROWS],
    /// The last node's rows: the carried rows, then the tip rows.
    last: [[f64; LW]; NODE],
}

impl<const W: usize, const LW: usize> Scratch<W, LW> {
    /// Zeroed rows, for the first elimination.
    fn zeroed() -> Box<Self> {
        Box::new(Scratch {
            panel: [[0.0; W]; ROWS],
            last: [[0.0; LW]; NODE],
        })
    }
}

/// Scratch and factors for one mesh.
pub struct BlockElimination {
    /// Pivot rows of each step, 12 x 25 (block k, block k + 1, right-hand side), row major,
    /// and one more block, whose first rows [`BlockElimination::solve`]'s last step leaves
    /// its carried rows in (it eliminates in place: step k's panel is rows 12 k..12 k + 18
    /// of these blocks); empty until the first factoring.
    pivots: Vec<[[f64; COLS]; NODE]>,
    /// Row operations of each step; empty until the first factoring.
    records: Vec<Record>,
    /// The last node's 12 x 12 upper-triangular rows (right-hand side in column 12, then
    /// padding) and their row operations.
    last: [[f64; LAST_COLS]; NODE],
    last_record: Record,
    /// Number of links.
    links: usize,
    /// The rows of [`BlockElimination::factor_with_last`], kept between factorings (every
    /// entry is written before it is read, so they are not zeroed each time); allocated by
    /// the first.
    wide_scratch: Option<Box<Scratch<WIDE, LAST_WIDE>>>,
    /// The last node's rows of [`BlockElimination::solve`], kept between solves as
    /// `wide_scratch` is.
    last_rows: [[f64; LAST_COLS]; NODE],
    /// The right-hand sides of [`BlockElimination::factor_with_last`] row by row (row r of
    /// every one in `carried_rows[r]`), so that a panel row takes its slots in one copy;
    /// kept between factorings, as the panel.
    carried_rows: Vec<[f64; CARRIED]>,
    /// How many leading slots of `carried_rows` the last factoring wrote (the others are
    /// zero in every row).
    carried_written: usize,
}

impl BlockElimination {
    /// Scratch for a mesh with `nodes` nodes. The per-link factors (about 4.5 kB a link)
    /// are allocated by the first factoring: a workspace whose Jacobian is factored
    /// elsewhere (the staircase of tendons with friction) never zeroes them.
    pub fn new(nodes: usize) -> Self {
        BlockElimination {
            pivots: Vec::new(),
            records: Vec::new(),
            last: [[0.0; LAST_COLS]; NODE],
            last_record: EMPTY,
            links: nodes - 1,
            wide_scratch: None,
            last_rows: [[0.0; LAST_COLS]; NODE],
            carried_rows: Vec::new(),
            carried_written: 0,
        }
    }

    /// Solves J x = rhs where J's values are in the assembly order of
    /// [`crate::collocation::unknowns::pattern`] (base 6 x 6 on p, R of node 0; links 12 x 24 row major;
    /// tip 6 x 9 on R, v, u of the last node). Writes x into `x`. Returns None on a zero
    /// pivot, else the times of the elimination and of the back substitution.
    ///
    /// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, as
    /// [`BlockElimination::factor_with_last`]: the same operations in the same order, the
    /// panels' row copies inlined as 32-byte moves instead of calls to `memcpy`.
    pub fn solve(&mut self, values: &[f64], rhs: &[f64], x: &mut [f64]) -> Option<(Duration, Duration)> {
        avx2_fma!(self.solve_kernel(values, rhs, x))
    }

    /// [`BlockElimination::solve`]'s operations.
    #[inline(always)]
    fn solve_kernel(&mut self, values: &[f64], rhs: &[f64], x: &mut [f64]) -> Option<(Duration, Duration)> {
        let start = Instant::now();
        if !self.eliminate_in_place(values, rhs) {
            return None;
        }
        let eliminated = start.elapsed();
        let start = Instant::now();
        let last = &self.last_rows;
        let n = self.links;
        let rhs_of = |rows: &[[f64; COLS]; NODE]| std::array::from_fn::<f64, NODE, _>(|i| rows[i][2 * NODE]);
        let last_rhs = std::array::from_fn::<f64, NODE, _>(|i| last[i][NODE]);
        back_substitute(last, &last_rhs, &mut x[n * NODE..(n + 1) * NODE], None);
        for k in (0..n).rev() {
            let (head, tail) = x.split_at_mut((k + 1) * NODE);
            back_substitute(
                &self.pivots[k],
                &rhs_of(&self.pivots[k]),
                &mut head[k * NODE..],
                Some(&tail[..NODE]),
            );
        }
        Some((eliminated, start.elapsed()))
    }

    /// Factors J (`values` as [`BlockElimination::solve`] takes them) for later solves, and
    /// gives the last node's 12 unknowns of J x = rhs_j for up to [`CARRIED`] right-hand
    /// sides at once: `rhs` holds them column-major (`count` columns of the unknowns' length)
    /// and `last[j]` gets column j's. The right-hand sides ride in the panels' spare columns
    /// through the elimination, so no zero right-hand side is back-substituted and no row
    /// operation is replayed; every right-hand side sees the operations
    /// [`BlockElimination::solve_again_last`] would replay, in the same order (also the
    /// multipliers that are zero), so the same bits. False on a zero pivot.
    ///
    /// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, as
    /// [`BlockElimination::solve_again`]: the same operations in the same order, the panels'
    /// row copies inlined as 32-byte moves instead of calls to `memcpy`.
    pub fn factor_with_last(&mut self, values: &[f64], rhs: &[f64], count: usize, last: &mut [[f64; NODE]]) -> bool {
        avx2_fma!(self.factor_with_last_kernel(values, rhs, count, last))
    }

    /// [`BlockElimination::factor_with_last`]'s operations.
    #[inline(always)]
    fn factor_with_last_kernel(&mut self, values: &[f64], rhs: &[f64], count: usize, last: &mut [[f64; NODE]]) -> bool {
        // The unknowns: one node's 12 a link, and the last node's.
        let n = (self.links + 1) * NODE;
        debug_assert!(count <= CARRIED && last.len() == count && rhs.len() == n * count);
        let mut scratch = self.wide_scratch.take().unwrap_or_else(Scratch::zeroed);
        // The right-hand sides transposed, 0 past the last one, column by column (a
        // contiguous read each): gathering the slots of a panel row from the columns one at
        // a time cost about 60 instructions a row (a bounds check and a branch a slot).
        // Slots past the last one are zeroed only where the last factoring wrote them (new
        // rows come zeroed).
        let mut rows = std::mem::take(&mut self.carried_rows);
        rows.resize(n, [0.0; CARRIED]);
        for j in 0..CARRIED {
            if j < count {
                for (row, v) in rows.iter_mut().zip(&rhs[j * n..(j + 1) * n]) {
                    row[j] = *v;
                }
            } else if j < self.carried_written {
                rows.iter_mut().for_each(|row| row[j] = 0.0);
            }
        }
        self.carried_written = count;
        // Every slot written: the kept panel's old values are never read.
        let eliminated =
            self.eliminate_all::<WIDE, LAST_WIDE, { 2 * NODE }, NODE>(&mut scratch, values, |row, slots| {
                slots.copy_from_slice(&rows[row]);
            });
        self.carried_rows = rows;
        if eliminated {
            let rows = &scratch.last;
            for (j, x) in last.iter_mut().enumerate() {
                let column = std::array::from_fn::<f64, NODE, _>(|i| rows[i][NODE + j]);
                back_substitute(&self.last, &column, x, None);
            }
        }
        self.wide_scratch = Some(scratch);
        eliminated
    }

    /// The elimination of [`BlockElimination::factor_with_last`] in `scratch` (that of
    /// [`BlockElimination::solve`] is [`BlockElimination::eliminate_in_place`]), `W` columns
    /// wide (the last node's rows `LW`), the right-hand sides in columns 2 NODE.. (NODE.. of
    /// the last node's rows) as `slots(row, out)` writes them for each row of J; columns
    /// from `ALWAYS` (`LAST_ALWAYS` in the last node's rows) on take every row operation,
    /// also those whose multiplier is zero. Copies the pivot rows out, keeps the row
    /// operations, and leaves the last node's eliminated rows in `scratch.last`; false on a
    /// zero pivot.
    ///
    /// Every entry of `scratch` it reads is written first (the zeros of the carried rows
    /// included), so the values a former elimination left there never reach the answer,
    /// and nothing is zeroed as a whole: a zeroed local array costs a `memset` a call.
    #[inline(always)]
    fn eliminate_all<const W: usize, const LW: usize, const ALWAYS: usize, const LAST_ALWAYS: usize>(
        &mut self,
        scratch: &mut Scratch<W, LW>,
        values: &[f64],
        mut slots: impl FnMut(usize, &mut [f64]),
    ) -> bool {
        self.allocate();
        let panel = &mut scratch.panel;
        // Carried rows start as the base rows: columns 0..6 of block 0, zero in the rest of
        // the two blocks.
        for (r, row) in panel[..CARRY].iter_mut().enumerate() {
            row[..BASE_COLUMNS].copy_from_slice(&values[r * BASE_COLUMNS..(r + 1) * BASE_COLUMNS]);
            row[BASE_COLUMNS..2 * NODE].fill(0.0);
            slots(r, &mut row[2 * NODE..]);
        }
        let mut at = BASE_ROWS * BASE_COLUMNS;
        for k in 0..self.links {
            // Panel: carried rows (block k only, rows 0..CARRY) over link k's rows (blocks k
            // and k + 1).
            for r in 0..NODE {
                let row = &mut panel[CARRY + r];
                row[..2 * NODE].copy_from_slice(&values[at + r * 2 * NODE..at + (r + 1) * 2 * NODE]);
                slots(link_row(k) + r, &mut row[2 * NODE..]);
            }
            at += NODE * 2 * NODE;
            if !eliminate_fast::<ROWS, W, ALWAYS>(panel, &mut self.records[k]) {
                return false;
            }
            for (kept, row) in self.pivots[k].iter_mut().zip(panel.iter()) {
                kept.copy_from_slice(&row[..COLS]);
            }
            // The rows not chosen as pivots carry block k + 1 forward (shifted to block k,
            // zero in block k + 1) into rows 0..CARRY, the pivot rows being kept.
            let (carried, rest) = panel.split_at_mut(NODE);
            for (row, src) in carried[..CARRY].iter_mut().zip(&rest[..CARRY]) {
                row[..NODE].copy_from_slice(&src[NODE..2 * NODE]);
                row[NODE..2 * NODE].fill(0.0);
                row[2 * NODE..].copy_from_slice(&src[2 * NODE..]);
            }
        }
        let (panel, last) = (&scratch.panel, &mut scratch.last);
        let tip = &values[at..];
        let kept = (&mut self.last, &mut self.last_record);
        eliminate_last::<W, LW, LAST_ALWAYS>(&panel[..CARRY], last, tip, tip_row(self.links + 1), slots, kept)
    }

    /// The first factoring's allocation of the factors, zeroed.
    fn allocate(&mut self) {
        if self.pivots.len() != self.links + 1 {
            self.pivots = vec![[[0.0; COLS]; NODE]; self.links + 1];
            self.records = vec![EMPTY; self.links];
        }
    }

    /// [`BlockElimination::eliminate_all`] for [`BlockElimination::solve`]'s one right-hand
    /// side, in place: step k's panel is rows 12 k..12 k + 18 of `pivots`, its carried rows
    /// those the step before left below its pivot rows, so the pivot rows stay where the
    /// elimination leaves them and are not copied. Every entry it reads is written first, as
    /// in [`BlockElimination::eliminate_all`], except the padding columns past the
    /// right-hand side: they hold whatever a former elimination left there (zeros, NaN from
    /// 0 x inf, a carried right-hand side of [`BlockElimination::factor_with_last`]), which
    /// the row operations read but no live column does, so it never reaches the answer.
    #[inline(always)]
    fn eliminate_in_place(&mut self, values: &[f64], rhs: &[f64]) -> bool {
        self.allocate();
        let rows = self.pivots.as_flattened_mut();
        for (r, row) in rows[..CARRY].iter_mut().enumerate() {
            row[..BASE_COLUMNS].copy_from_slice(&values[r * BASE_COLUMNS..(r + 1) * BASE_COLUMNS]);
            row[BASE_COLUMNS..2 * NODE].fill(0.0);
            row[2 * NODE] = rhs[r];
        }
        let mut at = BASE_ROWS * BASE_COLUMNS;
        for k in 0..self.links {
            let Some(panel) = rows[k * NODE..].first_chunk_mut::<ROWS>() else {
                unreachable!("pivots hold links + 1 blocks of {NODE} rows, so {ROWS} from block k");
            };
            for r in 0..NODE {
                let row = &mut panel[CARRY + r];
                row[..2 * NODE].copy_from_slice(&values[at + r * 2 * NODE..at + (r + 1) * 2 * NODE]);
                row[2 * NODE] = rhs[link_row(k) + r];
            }
            at += NODE * 2 * NODE;
            if !eliminate_fast::<ROWS, COLS, COLS>(panel, &mut self.records[k]) {
                return false;
            }
            // The rows not chosen as pivots carry block k + 1 forward in place (shifted to
            // block k, zero in block k + 1; the right-hand side stays in its column).
            for row in &mut panel[NODE..] {
                row.copy_within(NODE..2 * NODE, 0);
                row[NODE..2 * NODE].fill(0.0);
            }
        }
        let carried = &self.pivots[self.links][..CARRY];
        let kept = (&mut self.last, &mut self.last_record);
        let tip = (&values[at..], tip_row(self.links + 1));
        eliminate_last::<COLS, LAST_COLS, LAST_COLS>(
            carried,
            &mut self.last_rows,
            tip.0,
            tip.1,
            |row, slots| slots[0] = rhs[row],
            kept,
        )
    }

    /// Solves J x = rhs with the factors of the last successful [`BlockElimination::solve`]:
    /// the recorded row operations on the new right-hand side, then back substitution.
    /// About a tenth of the cost of a solve. On x86-64 with AVX2 and FMA (checked at run
    /// time) compiled for them: the same operations in the same order (Rust does not fuse a
    /// product and a sum into an FMA), so the same bits, in wider registers.
    pub fn solve_again(&self, rhs: &[f64], x: &mut [f64]) {
        avx2_fma!(self.solve_again_kernel(rhs, x));
    }

    /// [`BlockElimination::solve_again`]'s operations.
    #[inline(always)]
    fn solve_again_kernel(&self, rhs: &[f64], x: &mut [f64]) {
        let n = self.links;
        // Transformed right-hand sides of each step's pivot rows, stored in x until used.
        let last = self.replay_all(rhs, |k, pivot_rows| {
            x[k * NODE..(k + 1) * NODE].copy_from_slice(pivot_rows)
        });
        back_substitute(&self.last, &last, &mut x[n * NODE..(n + 1) * NODE], None);
        for k in (0..n).rev() {
            let (head, tail) = x.split_at_mut((k + 1) * NODE);
            let step_rhs: [f64; NODE] = std::array::from_fn(|i| head[k * NODE + i]);
            back_substitute(&self.pivots[k], &step_rhs, &mut head[k * NODE..], Some(&tail[..NODE]));
        }
    }

    /// The last node's 12 unknowns of J x = rhs with the stored factors: as
    /// [`BlockElimination::solve_again`] without the back substitution through the other
    /// nodes (the last node is the first it solves), for the derivatives of the tip alone.
    pub fn solve_again_last(&self, rhs: &[f64]) -> [f64; NODE] {
        let last = self.replay_all(rhs, |_, _| {});
        let mut x = [0.0; NODE];
        back_substitute(&self.last, &last, &mut x, None);
        x
    }

    /// The recorded row operations of every step on `rhs`: gives each step's transformed
    /// pivot rows to `pivot_rows(k, rows)` and returns the last node's transformed rows.
    /// Always inlined, so that the AVX2 copy of [`BlockElimination::solve_again`] runs it compiled for
    /// AVX2 too (as a call it was compiled for the baseline).
    #[inline(always)]
    fn replay_all(&self, rhs: &[f64], mut pivot_rows: impl FnMut(usize, &[f64])) -> [f64; NODE] {
        let n = self.links;
        let mut carry = [0.0; CARRY];
        carry.copy_from_slice(&rhs[..CARRY]);
        let mut transformed = [0.0; ROWS];
        for k in 0..n {
            transformed[..CARRY].copy_from_slice(&carry);
            transformed[CARRY..].copy_from_slice(&rhs[link_row(k)..link_row(k + 1)]);
            replay(&self.records[k], &mut transformed);
            pivot_rows(k, &transformed[..NODE]);
            carry.copy_from_slice(&transformed[NODE..]);
        }
        let mut last = [0.0; NODE];
        last[..CARRY].copy_from_slice(&carry);
        last[CARRY..].copy_from_slice(&rhs[tip_row(n + 1)..]);
        replay(&self.last_record, &mut last);
        last
    }
}

impl BlockElimination {
    /// Solves J^T y = c with the factors of the last successful [`BlockElimination::solve`]
    /// (the adjoint solve of the sensitivities, `collocation/sensitivity/adjoint.rs`).
    ///
    /// The elimination wrote J = M^-1 U: M the recorded row operations (swaps and
    /// multipliers, step by step), U block upper bidiagonal with step k's pivot rows
    /// [A_k B_k] in block row k (A_k 12 x 12 upper triangular, B_k the coupling to node
    /// k + 1) and the last node's A_n. So J^T = U^T M^-T: first U^T w = c by forward
    /// substitution over the blocks, A_k^T w_k = c_k - B_{k-1}^T w_{k-1}; then y = M^T w,
    /// the row operations transposed and run backwards (each step maps its 6 carried rows
    /// and 12 link rows to 12 pivot rows and 6 carried rows; its transpose maps them back).
    /// The same cost as [`BlockElimination::solve_again`]; compiled for AVX2 and FMA as it
    /// is (the same bits).
    pub fn solve_transposed(&self, c: &[f64], y: &mut [f64]) {
        avx2_fma!(self.solve_transposed_kernel(c, y));
    }

    /// [`BlockElimination::solve_transposed`]'s operations.
    #[inline(always)]
    fn solve_transposed_kernel(&self, c: &[f64], y: &mut [f64]) {
        let n = self.links;
        // U^T w = c: w_k overwrites y's block k (which holds no row data yet).
        let mut coupling = [0.0; NODE];
        for k in 0..=n {
            let mut sums: [f64; NODE] = std::array::from_fn(|i| c[k * NODE + i] - coupling[i]);
            let w = &mut y[k * NODE..(k + 1) * NODE];
            if k < n {
                forward_substitute(&self.pivots[k], &mut sums, w);
                // B_k^T w_k, subtracted from the next block's right-hand side.
                // A loop, not `array::from_fn`, whose closure was called per entry.
                for (j, b) in coupling.iter_mut().enumerate() {
                    *b = (0..NODE).map(|i| self.pivots[k][i][NODE + j] * w[i]).sum();
                }
            } else {
                forward_substitute(&self.last, &mut sums, w);
            }
        }
        // y = M^T w: the last step first; each step's transpose takes its 12 pivot-row
        // values and the 6 carried rows' adjoints, and gives the 6 rows it was handed
        // (carried, or the base rows at step 0) and its 12 link (or tip) rows.
        let mut last: [f64; NODE] = std::array::from_fn(|i| y[n * NODE + i]);
        replay_transposed(&self.last_record, &mut last);
        let mut carry = [0.0; CARRY];
        carry.copy_from_slice(&last[..CARRY]);
        let tip = tip_row(n + 1);
        y[tip..tip + TIP_ROWS].copy_from_slice(&last[CARRY..]);
        let mut panel = [0.0; ROWS];
        for k in (0..n).rev() {
            panel[..NODE].copy_from_slice(&y[k * NODE..(k + 1) * NODE]);
            panel[NODE..].copy_from_slice(&carry);
            replay_transposed(&self.records[k], &mut panel);
            carry.copy_from_slice(&panel[..CARRY]);
            y[link_row(k)..link_row(k + 1)].copy_from_slice(&panel[CARRY..]);
        }
        y[..CARRY].copy_from_slice(&carry);
    }
}

/// The last step of an elimination: the `carried` rows (block k in columns 0..12, the
/// right-hand sides from column 24) and the tip rows (`tip`: their values, on columns 3..12;
/// `slots` writes the right-hand sides of J's row `tip_row0 + r` as in
/// [`BlockElimination::eliminate_all`]) into `last`, eliminated; keeps its pivot rows and row
/// operations in `kept`. False on a zero pivot.
#[inline(always)]
fn eliminate_last<const W: usize, const LW: usize, const LAST_ALWAYS: usize>(
    carried: &[[f64; W]],
    last: &mut [[f64; LW]; NODE],
    tip: &[f64],
    tip_row0: usize,
    mut slots: impl FnMut(usize, &mut [f64]),
    kept: (&mut [[f64; LAST_COLS]; NODE], &mut Record),
) -> bool {
    for (r, row) in carried.iter().enumerate() {
        last[r][..NODE].copy_from_slice(&row[..NODE]);
        last[r][NODE..NODE + W - 2 * NODE].copy_from_slice(&row[2 * NODE..]);
    }
    for r in 0..TIP_ROWS {
        last[CARRY + r][THETA..NODE].copy_from_slice(&tip[r * TIP_COLUMNS..(r + 1) * TIP_COLUMNS]);
        last[CARRY + r][..THETA].fill(0.0);
        slots(tip_row0 + r, &mut last[CARRY + r][NODE..]);
    }
    if !eliminate_fast::<NODE, LW, LAST_ALWAYS>(last, kept.1) {
        return false;
    }
    for (kept, row) in kept.0.iter_mut().zip(last.iter()) {
        kept.copy_from_slice(&row[..LAST_COLS]);
    }
    true
}

/// The transpose of [`replay`]: the eliminations transposed (pivot row c collects its
/// multipliers' rows) and the swaps, in reverse order.
fn replay_transposed<const N: usize>(record: &Record, v: &mut [f64; N]) {
    for c in (0..NODE).rev() {
        let collected: f64 = v[c + 1..]
            .iter()
            .zip(&record.factors[c][c + 1..])
            .map(|(x, f)| f * x)
            .sum();
        v[c] -= collected;
        v.swap(c, record.swaps[c]);
    }
}

/// Solves A^T w = sums for the upper-triangular first 12 columns A of `rows` (forward
/// substitution; `sums` is consumed).
fn forward_substitute<const W: usize>(rows: &[[f64; W]], sums: &mut [f64; NODE], w: &mut [f64]) {
    for i in 0..NODE {
        w[i] = sums[i] / rows[i][i];
        for j in i + 1..NODE {
            sums[j] -= rows[i][j] * w[i];
        }
    }
}

/// Applies a step's recorded row swaps and eliminations to a right-hand side: column c's
/// swap, then row r -= factor * pivot for every row r below c, column after column. Each
/// column is its own instance of [`replay_column`], so that its loop has constant bounds
/// and compiles to straight-line vector code (the shift-invert solves of the linearized
/// dynamics are mostly this; docs/stability.md, "Cost"): the same operations in the same
/// order as a loop over the columns, so the same bits.
#[inline(always)]
fn replay<const N: usize>(record: &Record, v: &mut [f64; N]) {
    const _: () = assert!(NODE == 12);
    replay_column::<0, N>(record, v);
    replay_column::<1, N>(record, v);
    replay_column::<2, N>(record, v);
    replay_column::<3, N>(record, v);
    replay_column::<4, N>(record, v);
    replay_column::<5, N>(record, v);
    replay_column::<6, N>(record, v);
    replay_column::<7, N>(record, v);
    replay_column::<8, N>(record, v);
    replay_column::<9, N>(record, v);
    replay_column::<10, N>(record, v);
    replay_column::<11, N>(record, v);
}

/// Column `C` of [`replay`]: its swap, then its multipliers on the `N - C - 1` rows below.
#[inline(always)]
fn replay_column<const C: usize, const N: usize>(record: &Record, v: &mut [f64; N]) {
    v.swap(C, record.swaps[C]);
    let pivot = v[C];
    let factors = &record.factors[C];
    for r in C + 1..N {
        v[r] -= factors[r] * pivot;
    }
}

/// Solves the upper-triangular pivot rows for this node's 12 unknowns with right-hand side
/// `rhs`, given the next node's (`next`, columns 12..24) when there is one.
///
/// The coupling to the next node and the pivots' reciprocals do not depend on this node's
/// unknowns, so they are computed first, off the substitution's dependency chain.
#[inline(always)]
fn back_substitute<const W: usize>(rows: &[[f64; W]], rhs: &[f64; NODE], x: &mut [f64], next: Option<&[f64]>) {
    let mut sums = *rhs;
    if let Some(next) = next {
        for (sum, row) in sums.iter_mut().zip(rows) {
            *sum -= row[NODE..2 * NODE].iter().zip(next).map(|(a, b)| a * b).sum::<f64>();
        }
    }
    let inverse: [f64; NODE] = std::array::from_fn(|i| 1.0 / rows[i][i]);
    for i in (0..NODE).rev() {
        let row = &rows[i];
        let mut sum = sums[i];
        for j in i + 1..NODE {
            sum -= row[j] * x[j];
        }
        x[i] = sum * inverse[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::system::System;
    use crate::mesh::{Mesh, guess::rigid_estimate};
    use crate::model::equations::Model;

    /// Case H's Jacobian and residual at the rigid estimate on 16 intervals, with its node
    /// count: a Jacobian with every block the elimination meets.
    fn case_h_jacobian() -> (usize, Vec<f64>, Vec<f64>) {
        let robot = crate::cases::case_h();
        let model = Model::new(&robot);
        let system = System::new(model.clone(), Mesh::uniform(&robot, 16).unwrap());
        let x = rigid_estimate(&model, &system.mesh.nodes);
        let mut values = vec![0.0; crate::collocation::unknowns::nonzeros(&system.mesh)];
        let mut residual = vec![0.0; system.unknowns()];
        system.jacobian(&x, &mut residual, &mut values).unwrap();
        (system.mesh.nodes.len(), values, residual)
    }

    /// The AVX2 build of `solve_again` gives the baseline build's bits: the same operations
    /// in the same order (on a processor without AVX2 both are the baseline).
    #[test]
    fn solve_again_gives_the_baseline_bits() {
        let (nodes, values, residual) = case_h_jacobian();
        let n = residual.len();
        let mut lu = BlockElimination::new(nodes);
        let mut step = vec![0.0; n];
        assert!(lu.solve(&values, &residual, &mut step).is_some());
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let (mut fast, mut baseline) = (vec![0.0; n], vec![0.0; n]);
        lu.solve_again(&rhs, &mut fast);
        lu.solve_again_kernel(&rhs, &mut baseline);
        assert!(fast.iter().all(|v| v.is_finite()));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&baseline));
    }

    /// The AVX2 build of `solve` gives the baseline build's bits, and so does an elimination
    /// whose kept rows hold what a refused elimination (an infinite entry in link 2's
    /// rows: NaN and infinities), another Jacobian's and a factoring with carried
    /// right-hand sides left there: every live entry it reads is written first.
    #[test]
    fn solve_gives_the_baseline_bits_whatever_its_rows_held() {
        let (nodes, values, residual) = case_h_jacobian();
        let n = residual.len();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut fresh = BlockElimination::new(nodes);
        let (mut fast, mut baseline) = (vec![0.0; n], vec![0.0; n]);
        assert!(fresh.solve(&values, &residual, &mut fast).is_some());
        assert!(
            BlockElimination::new(nodes)
                .solve_kernel(&values, &residual, &mut baseline)
                .is_some()
        );
        assert!(fast.iter().all(|v| v.is_finite()));
        assert_eq!(bits(&fast), bits(&baseline));
        let mut reused = BlockElimination::new(nodes);
        let mut step = vec![0.0; n];
        let mut refused = values.clone();
        refused[BASE_ROWS * BASE_COLUMNS + 2 * NODE * 2 * NODE + 6] = f64::INFINITY;
        assert!(reused.solve(&refused, &residual, &mut step).is_none());
        let other: Vec<f64> = values
            .iter()
            .enumerate()
            .map(|(i, v)| v * (1.5 + (i as f64).sin()))
            .collect();
        let shifted: Vec<f64> = residual.iter().map(|v| v + 1.0).collect();
        assert!(reused.solve(&other, &shifted, &mut step).is_some());
        assert!(reused.solve(&values, &residual, &mut step).is_some());
        assert_eq!(bits(&step), bits(&fast));
        // A factoring with carried right-hand sides copies them into the kept rows' padding
        // columns, which the in-place elimination of a solve reads but no live column does.
        let carried: Vec<f64> = (0..n * CARRIED).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
        let mut last = vec![[0.0; NODE]; CARRIED];
        assert!(reused.factor_with_last(&other, &carried, CARRIED, &mut last));
        assert!(reused.solve(&values, &residual, &mut step).is_some());
        assert_eq!(bits(&step), bits(&fast));
    }

    /// The AVX2 build of `solve_transposed` gives the baseline build's bits, as
    /// `solve_again`'s does.
    #[test]
    fn solve_transposed_gives_the_baseline_bits() {
        let (nodes, values, residual) = case_h_jacobian();
        let n = residual.len();
        let mut lu = BlockElimination::new(nodes);
        let mut step = vec![0.0; n];
        assert!(lu.solve(&values, &residual, &mut step).is_some());
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let (mut fast, mut baseline) = (vec![0.0; n], vec![0.0; n]);
        lu.solve_transposed(&rhs, &mut fast);
        lu.solve_transposed_kernel(&rhs, &mut baseline);
        assert!(fast.iter().all(|v| v.is_finite()));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&baseline));
    }

    /// Right-hand sides carried through the factoring give the bits of
    /// `solve_again_last` after a plain factoring (signed zeros included: half of each
    /// right-hand side is -0.0, as negated tension columns are where a row does not move),
    /// and leave the same factors; also in an elimination that factored before with more
    /// right-hand sides (its kept panel holding their values).
    #[test]
    fn carried_right_hand_sides_give_the_replayed_bits() {
        let (nodes, values, residual) = case_h_jacobian();
        let n = residual.len();
        let mut plain = BlockElimination::new(nodes);
        let mut step = vec![0.0; n];
        assert!(plain.solve(&values, &vec![0.0; n], &mut step).is_some());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut reused = BlockElimination::new(nodes);
        // Every count the panels carry, none and all of their spare columns included, the
        // most first.
        for count in (0..=CARRIED).rev() {
            let rhs: Vec<f64> = (0..n * count)
                .map(|i| if i % 2 == 0 { -0.0 } else { (i as f64 * 0.37).sin() })
                .collect();
            let mut carried = BlockElimination::new(nodes);
            let mut last = vec![[0.0; NODE]; count];
            assert!(carried.factor_with_last(&values, &rhs, count, &mut last));
            let mut again = vec![[0.0; NODE]; count];
            assert!(reused.factor_with_last(&values, &rhs, count, &mut again));
            for (j, tip) in last.iter().enumerate() {
                let column = &rhs[j * n..(j + 1) * n];
                assert_eq!(bits(tip), bits(&plain.solve_again_last(column)));
                assert_eq!(bits(&again[j]), bits(tip), "{count} carried after more");
            }
            // The factors are the plain factoring's, whatever rode along.
            let column: Vec<f64> = (0..n).map(|i| (i as f64 * 0.21).cos()).collect();
            let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
            plain.solve_again(&column, &mut a);
            carried.solve_again(&column, &mut b);
            assert_eq!(bits(&a), bits(&b), "{count} carried");
            reused.solve_again(&column, &mut b);
            assert_eq!(bits(&a), bits(&b), "{count} carried after more");
        }
    }
}
