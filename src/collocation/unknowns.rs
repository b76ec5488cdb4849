//! The layout of the collocation system, in one place: which unknown and which residual row
//! is where, how a scaled Newton step moves the node states, and the Jacobian's pattern.
//!
//! Unknowns are ordered node by node, [`NODE`] = 12 per node, as four scaled 3-vectors at
//! the offsets [`P`], [`THETA`], [`V`], [`U`]: dp / L, the right rotation increment dtheta
//! (R -> R exp(dtheta)), dv and du L (docs/numerics.md, scaling); dv is the change of the
//! translational coordinate, the strain on a Cosserat rod and the internal force in strain
//! units on a Kirchhoff rod (docs/model.md section 4b). Rows are the
//! [`BASE_ROWS`] = 6 base conditions, then [`NODE`] = 12 per link (an interval's
//! collocation equations or a breakpoint's jump conditions), then the [`TIP_ROWS`] = 6 tip
//! conditions (3 force rows, then 3 moment rows), so the Jacobian is almost block diagonal:
//!
//! ```text
//!            node 0      node 1      node 2            node N
//!          [p R v u ]  [p R v u ]  [p R v u ]        [p R v u ]
//! base   6 [ X X . . ]
//! link 0 12[ X X X X ]  [ X X X X ]
//! link 1 12             [ X X X X ]  [ X X X X ]
//!   ...                                     ...
//! link N-1                                       ... [ X X X X ]
//! tip    6                                           [ . X X X ]
//! ```
//!
//! The base rows depend only on p and R of node 0 ([`BASE_COLUMNS`] = 6), the tip rows on
//! R, v, u of node N (the [`TIP_COLUMNS`] = 9 columns from [`THETA`]); each link block is
//! a dense 12 x 24. [`pattern`] lists the stored entries in assembly order: the base block,
//! the link blocks, the tip block, each row major.

use crate::mesh::Mesh;
use crate::so3;
use crate::solution::State;
use nalgebra::Vector3;

/// Unknowns per node (and rows per link).
pub const NODE: usize = 12;
/// Offset of the position increment dp / L in a node's unknowns.
pub const P: usize = 0;
/// Offset of the rotation increment dtheta (rad, body frame) in a node's unknowns.
pub const THETA: usize = 3;
/// Offset of the strain increment dv in a node's unknowns.
pub const V: usize = 6;
/// Offset of the curvature increment du L in a node's unknowns.
pub const U: usize = 9;
/// Base rows: p(0) = p0, R(0) = R0.
pub const BASE_ROWS: usize = 6;
/// Columns of the base block: p and R of node 0.
pub const BASE_COLUMNS: usize = 6;
/// Tip rows: force balance (3), then moment balance (3).
pub const TIP_ROWS: usize = 6;
/// Columns of the tip block: R, v and u of the last node (from [`THETA`]).
pub const TIP_COLUMNS: usize = NODE - THETA;

/// Number of unknowns (= rows) on a mesh of `nodes` nodes.
pub fn unknowns(nodes: usize) -> usize {
    nodes * NODE
}

/// First row of link k (the interval or jump between nodes k and k + 1).
pub fn link_row(k: usize) -> usize {
    BASE_ROWS + k * NODE
}

/// First of the tip rows on a mesh of `nodes` nodes (its 3 force rows, then 3 moment rows).
pub fn tip_row(nodes: usize) -> usize {
    link_row(nodes - 1)
}

/// Stored non-zeros of the Jacobian on `mesh`: the base block, one 12 x 24 block per link
/// and the tip block; the length of [`pattern`].
pub fn nonzeros(mesh: &Mesh) -> usize {
    BASE_ROWS * BASE_COLUMNS + (mesh.nodes.len() - 1) * NODE * 2 * NODE + TIP_ROWS * TIP_COLUMNS
}

/// The (row, column) pattern of the Jacobian in assembly order.
pub fn pattern(mesh: &Mesh) -> Vec<(usize, usize)> {
    let nodes = mesh.nodes.len();
    let links = nodes - 1;
    let mut out = Vec::with_capacity(nonzeros(mesh));
    for r in 0..BASE_ROWS {
        for c in 0..BASE_COLUMNS {
            out.push((r, c));
        }
    }
    for k in 0..links {
        for r in 0..NODE {
            for c in 0..2 * NODE {
                out.push((link_row(k) + r, k * NODE + c));
            }
        }
    }
    let (row0, col0) = (tip_row(nodes), (nodes - 1) * NODE);
    for r in 0..TIP_ROWS {
        for c in THETA..NODE {
            out.push((row0 + r, col0 + c));
        }
    }
    out
}

/// Arc length a residual row belongs to: 0 for the base rows, L for the tip rows, the
/// middle of its link otherwise.
pub fn row_position(mesh: &Mesh, length: f64, row: usize) -> f64 {
    let nodes = mesh.nodes.len();
    if row < BASE_ROWS {
        0.0
    } else if row >= tip_row(nodes) {
        length
    } else {
        let k = (row - BASE_ROWS) / NODE;
        0.5 * (mesh.nodes[k].s + mesh.nodes[k + 1].s)
    }
}

/// The unscaled increments of node k in the scaled vector `dx`: (dp in m, dtheta in rad,
/// dv, du in rad/m).
pub fn node_increments(dx: &[f64], k: usize, length: f64) -> [Vector3<f64>; 4] {
    let part = |i: usize| Vector3::new(dx[k * NODE + i], dx[k * NODE + i + 1], dx[k * NODE + i + 2]);
    [part(P) * length, part(THETA), part(V), part(U) / length]
}

/// The states `x` moved by `alpha` times the scaled Newton step `step`
/// (p += L dp, R = R exp(dtheta), v += dv, u += du / L), written into `out`.
pub fn retract(x: &[State], step: &[f64], alpha: f64, length: f64, out: &mut Vec<State>) {
    out.clear();
    for (k, s) in x.iter().enumerate() {
        let d = |i: usize| Vector3::new(step[k * NODE + i], step[k * NODE + i + 1], step[k * NODE + i + 2]) * alpha;
        out.push(State {
            s: s.s,
            p: s.p + d(P) * length,
            R: s.R * so3::exp(&d(THETA)),
            v: s.v + d(V),
            u: s.u + d(U) / length,
        });
    }
}
