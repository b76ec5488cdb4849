//! The border rows of tendons with friction in Newton's loop ([`Border`] for [`Capstan`]):
//! the capstan rows and their linearization at the current and trial points, and the
//! bordered matrix's blocks handed to the [`Staircase`] node by node (module docs of
//! [`super`]).

use super::staircase::Block;
use super::*;
use crate::collocation::unknowns::{BASE_COLUMNS, BASE_ROWS, THETA, TIP_COLUMNS, TIP_ROWS};

/// Entries of the Jacobian's base block, then of each link's block, in
/// [`crate::collocation::unknowns::pattern`] order.
const BASE_ENTRIES: usize = BASE_ROWS * BASE_COLUMNS;
const LINK_ENTRIES: usize = NODE * 2 * NODE;

impl Capstan<'_> {
    /// Reads psi_x, psi_z and F_z from the links' evaluations by the system's Jacobian at
    /// `x` (its last evaluation), and the termination rows' columns.
    pub(super) fn read_border(&mut self, x: &[State]) -> Result<(), Termination> {
        self.load(Point::Current);
        let count = self.offsets.len();
        self.psi_z.fill(0.0);
        self.stairs.ready = false;
        let Some(profile) = self.system.friction.as_ref() else {
            return Ok(());
        };
        let last = profile.spans.iter().copied().max().unwrap_or(0);
        for k in 0..last {
            let done = profile.cached(k, |lin| {
                let Some(lin) = lin.filter(|l| l.derivatives) else {
                    return self.system.interval_sites(k).is_none();
                };
                for j in (0..count).filter(|&j| profile.on_link(j, k)) {
                    let row = self.offsets[j] + k;
                    for c in 0..2 * NODE {
                        self.psi_x[row][c] = lin.psi_x[(j, c)];
                    }
                    for l in 0..count {
                        for (side, node) in [(0, k), (1, k + 1)] {
                            if unknown(&self.offsets, &profile.spans, l, node).is_some() {
                                self.psi_z[(row * 2 + side) * count + l] += lin.psi_z[(j, side * count + l)];
                            }
                        }
                    }
                }
                // Kept where the shape is the same (every Jacobian after the first on this
                // mesh): no allocation per link.
                match &mut self.link_z[k] {
                    Some(kept) if kept.shape() == lin.rows_z.shape() => kept.copy_from(&lin.rows_z),
                    slot => *slot = Some(lin.rows_z.clone()),
                }
                true
            });
            if !done {
                return Err(Termination::NonFinite);
            }
        }
        for j in 0..count {
            self.terminations[j] = self.termination_column(j, x).map_err(|_| Termination::NonFinite)?;
        }
        Ok(())
    }
}

impl Capstan<'_> {
    /// Sets whether the links' evaluations with derivatives keep eq. 13 with friction's
    /// response to the inertia loads for the verdict's mass ([`Profile::keep_responses`]).
    pub(super) fn keep_responses(&self, on: bool) {
        if let Some(profile) = &self.system.friction {
            let robot = self.system.model.robot;
            profile.keep_responses(on.then(|| crate::collocation::dynamics::friction::mass_scale(robot)));
        }
    }

    /// Node n's local column of slip l's log tension, if it has one there.
    fn z_column(&self, n: usize, l: usize) -> Option<usize> {
        self.node_slips[n].iter().position(|&j| j == l).map(|p| NODE + p)
    }

    /// Factors the bordered matrix: the backbone Jacobian `values` (pattern order) with the
    /// border's blocks read by [`Capstan::read_border`]. False on a zero pivot.
    pub(super) fn factor(&mut self, values: &[f64]) -> bool {
        let Some(profile) = self.system.friction.as_ref() else {
            return false;
        };
        let nodes = self.system.mesh.nodes.len();
        let links = nodes - 1;
        let count = self.offsets.len();
        let tip_start = BASE_ENTRIES + links * LINK_ENTRIES;
        let mut stairs = std::mem::take(&mut self.stairs);
        // Inlined into the factorization's steps (compiled for AVX2 with them): as a call
        // it was compiled for the baseline.
        let ok = stairs.factor(
            #[inline(always)]
            |block, out| match block {
                Block::Base => {
                    let width = NODE;
                    for r in 0..BASE_ROWS {
                        out[r * width..r * width + BASE_COLUMNS]
                            .copy_from_slice(&values[r * BASE_COLUMNS..(r + 1) * BASE_COLUMNS]);
                    }
                }
                Block::Link(k) => {
                    let (left, right) = (&self.node_slips[k], &self.node_slips[k + 1]);
                    let ck = NODE + left.len();
                    let width = ck + NODE + right.len();
                    // Node k's log tensions are columns NODE.. of the block, node k + 1's ck + NODE..:
                    // a node's columns in the order of its slips.
                    let sides = [(left, NODE), (right, ck + NODE)];
                    let block = &values[BASE_ENTRIES + k * LINK_ENTRIES..BASE_ENTRIES + (k + 1) * LINK_ENTRIES];
                    let (rows, border_rows) = out.split_at_mut(NODE * width);
                    for (row, values) in rows.chunks_exact_mut(width).zip(block.chunks_exact(2 * NODE)) {
                        let (a, b) = values.split_at(NODE);
                        row[..NODE].copy_from_slice(a);
                        row[ck..ck + NODE].copy_from_slice(b);
                    }
                    // F_z: column (side, slip l) of the link's rows (one entry per cell, so in
                    // any order).
                    if let Some(rz) = &self.link_z[k] {
                        for (side, (slips, first)) in sides.iter().enumerate() {
                            for (p, &l) in slips.iter().enumerate() {
                                // Column-major storage: the column is a run of the slice.
                                let column = &rz.as_slice()[(side * count + l) * NODE..(side * count + l + 1) * NODE];
                                for (row, v) in rows.chunks_exact_mut(width).zip(column) {
                                    row[first + p] += v;
                                }
                            }
                        }
                    }
                    for (j, term) in self.terminations.iter().enumerate() {
                        if let (Some((first, vals)), Some(c)) = (term, self.z_column(k, j))
                            && profile.spans[j] == k
                            && (link_row(k)..link_row(k + 1)).contains(first)
                        {
                            for (i, v) in vals.iter().enumerate() {
                                rows[(first - link_row(k) + i) * width + c] += v;
                            }
                        }
                    }
                    // The capstan rows of the slips on link k (node k + 1's): psi_x over the
                    // two nodes' backbone columns, psi_z over their log tensions (a slip has a
                    // log tension at a node exactly when the node is in its span: `unknown`).
                    for (&j, row) in right.iter().zip(border_rows.chunks_exact_mut(width)) {
                        let global = self.offsets[j] + k;
                        let (a, b) = self.psi_x[global].split_at(NODE);
                        row[..NODE].copy_from_slice(a);
                        row[ck..ck + NODE].copy_from_slice(b);
                        for (side, (slips, first)) in sides.iter().enumerate() {
                            for (p, &l) in slips.iter().enumerate() {
                                row[first + p] += self.psi_z[(global * 2 + side) * count + l];
                            }
                        }
                    }
                }
                Block::Tip => {
                    let width = NODE + self.node_slips[links].len();
                    for r in 0..TIP_ROWS {
                        out[r * width + THETA..r * width + NODE]
                            .copy_from_slice(&values[tip_start + r * TIP_COLUMNS..tip_start + (r + 1) * TIP_COLUMNS]);
                    }
                    for (j, term) in self.terminations.iter().enumerate() {
                        if let (Some((first, vals)), Some(c)) = (term, self.z_column(links, j))
                            && *first == tip_row(nodes)
                        {
                            for (i, v) in vals.iter().enumerate() {
                                out[i * width + c] += v;
                            }
                        }
                    }
                }
            },
        );
        self.stairs = stairs;
        ok
    }

    /// Solves the factored bordered system for the right-hand side (`rhs_x` on the backbone
    /// rows, `rhs_z` on the border's): dx into `dx` (scaled node unknowns), dz into
    /// `border_step`. Returns max |dz|, None without factors or for a value that is not
    /// finite.
    pub(super) fn solve_factored(&mut self, rhs_x: &[f64], rhs_z: &[f64], dx: &mut [f64]) -> Option<f64> {
        if !self.stairs.ready {
            return None;
        }
        let links = self.system.mesh.nodes.len() - 1;
        let (offsets, node_slips) = (&self.offsets, &self.node_slips);
        // The staircase's block order: the base rows, each link's backbone rows followed by
        // the border rows of its node k + 1's slips, the tip rows.
        let ok = self.stairs.solve(|w| {
            w[..BASE_ROWS].copy_from_slice(&rhs_x[..BASE_ROWS]);
            let mut at = BASE_ROWS;
            for k in 0..links {
                w[at..at + NODE].copy_from_slice(&rhs_x[link_row(k)..link_row(k + 1)]);
                at += NODE;
                for &j in &node_slips[k + 1] {
                    w[at] = rhs_z[offsets[j] + k];
                    at += 1;
                }
            }
            w[at..].copy_from_slice(&rhs_x[tip_row(links + 1)..]);
        });
        // The solution node by node: its 12 unknowns, then the log tensions of its slips.
        let dz = &mut self.border_step;
        let mut values = self.stairs.solution();
        for (n, slips) in node_slips.iter().enumerate() {
            let (node, rest) = values.split_at(NODE + slips.len());
            dx[n * NODE..(n + 1) * NODE].copy_from_slice(&node[..NODE]);
            for (a, &j) in slips.iter().enumerate() {
                dz[offsets[j] + n - 1] = node[NODE + a];
            }
            values = rest;
        }
        let norm = dz.iter().fold(0.0, |acc: f64, d| acc.max(d.abs()));
        ok.then_some(norm)
    }
}

impl Border for Capstan<'_> {
    /// At the trial point the profile keeps eq. 13 with friction's response to the inertia
    /// loads ([`Profile::keep_responses`]): a Jacobian evaluated there is the one Newton
    /// evaluates ahead at the answer for the verdict ([`newton::run_bordered_ahead`]), whose
    /// mass reads the same points (a residual keeps nothing).
    fn on<R>(&mut self, point: Point, f: impl FnOnce(&System) -> R) -> R {
        self.load(point);
        self.keep_responses(point == Point::Trial);
        f(&self.system)
    }

    fn rows(&mut self, point: Point, x: &[State]) {
        self.load(point);
        let psi = match point {
            Point::Current => &mut self.psi,
            Point::Trial => &mut self.trial_psi,
        };
        // The system's residual at this point and x has just evaluated every link.
        let _ = x;
        if let Some(profile) = self.system.friction.as_ref() {
            capstan_rows(profile, &self.offsets, psi);
        }
    }

    fn residual(&self, point: Point) -> &[f64] {
        match point {
            Point::Current => &self.psi,
            Point::Trial => &self.trial_psi,
        }
    }

    /// Reads the border's blocks ([`Capstan::read_border`]) at `x`, which Newton has just
    /// factored, and factors the bordered matrix with them.
    fn factored(&mut self, x: &[State], at: &mut Linearization, report: &mut SolveReport) -> Result<(), Termination> {
        self.read_border(x)?;
        let t = Instant::now();
        let ok = self.factor(at.values());
        report.timings.factorization += t.elapsed();
        if ok { Ok(()) } else { Err(Termination::SingularJacobian) }
    }

    /// The staircase factors the whole bordered matrix: Newton never factors J alone.
    fn own_factors(&self) -> Option<bool> {
        Some(self.stairs.ready)
    }

    /// The bordered step from the staircase's factors: the backbone rows' right-hand side
    /// is -F (at the current point Newton's residual, at the trial point handed in `a`).
    fn step(
        &mut self,
        point: Point,
        _x: &[State],
        a: &mut [f64],
        at: &mut Linearization,
        report: &mut SolveReport,
    ) -> Option<f64> {
        let t = Instant::now();
        let mut rhs_x = std::mem::take(&mut self.rhs_x);
        match point {
            Point::Current => {
                for (r, f) in rhs_x.iter_mut().zip(at.residual()) {
                    *r = -f;
                }
            }
            Point::Trial => rhs_x.copy_from_slice(a),
        }
        let psi = match point {
            Point::Current => &self.psi,
            Point::Trial => &self.trial_psi,
        };
        for (r, p) in self.rows_in.iter_mut().zip(psi) {
            *r = -p;
        }
        let rows_in = std::mem::take(&mut self.rows_in);
        let norm = self.solve_factored(&rhs_x, &rows_in, a);
        (self.rhs_x, self.rows_in) = (rhs_x, rows_in);
        report.timings.solve += t.elapsed();
        let norm = norm?;
        match point {
            Point::Current => self.dz.copy_from_slice(&self.border_step),
            Point::Trial => self.simplified.copy_from_slice(&self.border_step),
        }
        Some(norm)
    }

    fn trial(&mut self, alpha: f64) {
        for ((t, &z), &d) in self.trial_z.iter_mut().zip(&self.z).zip(&self.dz) {
            *t = z + alpha * d;
        }
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.psi, &mut self.trial_psi);
        self.z.copy_from_slice(&self.trial_z);
    }
}
