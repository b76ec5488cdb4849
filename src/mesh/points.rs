//! A tendon's routing points (r, r', r'') at a mesh's nodes, as a solution's tendon path and
//! tendon length read them (module `nodes`): evaluated once for both, and for a helical
//! routing kept per thread for the next solutions on the same nodes (the rows of a batch, the
//! steps of a sweep, repeated solves), since they depend only on the routing, the rod length
//! and the nodes' arc lengths, not on the state.

use crate::model::routing::{Routing, RoutingPoint};
use std::cell::RefCell;

/// How many tables of routing points a thread keeps ([`with_points`]): a few helical tendons
/// on the meshes of a solve and of its neighbours.
const KEPT_TABLES: usize = 8;

/// A kept table: the helix (radius, turns, phase) and rod length as bits, the nodes' arc
/// lengths and the routing points there.
struct Table {
    helix: [u64; 4],
    s: Vec<f64>,
    points: Vec<RoutingPoint>,
}

thread_local! {
    /// Tables built on this thread, least recently used first.
    static KNOWN: RefCell<Vec<Table>> = const { RefCell::new(Vec::new()) };
}

/// A tendon's routing points at nodes 0, 1, ... of a mesh ([`with_points`]).
pub(crate) enum Points<'a> {
    /// A straight routing: one point for every node.
    Constant(RoutingPoint),
    /// A helical routing: the point at every node.
    Table(&'a [RoutingPoint]),
    /// A user routing (not comparable, so not kept): evaluated at every call, at the nodes'
    /// arc lengths, on a rod of this length.
    Custom(&'a Routing, &'a [f64], f64),
}

impl Points<'_> {
    /// The routing point at node `k`: [`Routing::at`] at its arc length, bit for bit.
    #[inline(always)]
    pub(crate) fn at(&self, k: usize) -> RoutingPoint {
        match *self {
            Points::Constant(point) => point,
            Points::Table(points) => points[k],
            Points::Custom(routing, s, length) => routing.at(s[k], length),
        }
    }
}

/// `f` of the routing points of `routing` on a rod of `length` (m) at the nodes' arc lengths
/// `s` (m). A helical routing's table is kept per thread and lent again for bit for bit the
/// same helix, length and `s`; it is taken out of the thread's list while `f` runs and kept
/// again as the most recently used (the oldest's buffers are reused when the list is full).
pub(crate) fn with_points<T>(routing: &Routing, length: f64, s: &[f64], f: impl FnOnce(&Points) -> T) -> T {
    let helix = match *routing {
        Routing::Straight { .. } => return f(&Points::Constant(routing.at(0.0, length))),
        Routing::Custom(_) => return f(&Points::Custom(routing, s, length)),
        Routing::Helical { radius, turns, phase } => {
            [radius.to_bits(), turns.to_bits(), phase.to_bits(), length.to_bits()]
        }
    };
    let same = |t: &Table| {
        t.helix == helix && t.s.len() == s.len() && t.s.iter().zip(s).all(|(a, b)| a.to_bits() == b.to_bits())
    };
    let known = KNOWN.with(|known| {
        let mut known = known.borrow_mut();
        match known.iter().position(same) {
            Some(at) => Ok(known.remove(at)),
            None if known.len() >= KEPT_TABLES => Err(Some(known.remove(0))),
            None => Err(None),
        }
    });
    let table = known.unwrap_or_else(|old| {
        let mut table = old.unwrap_or(Table {
            helix,
            s: Vec::new(),
            points: Vec::new(),
        });
        table.helix = helix;
        table.s.clear();
        table.s.extend_from_slice(s);
        table.points.clear();
        table.points.extend(s.iter().map(|&sk| routing.at(sk, length)));
        table
    });
    let value = f(&Points::Table(&table.points));
    // A thread being torn down keeps nothing.
    let _ = KNOWN.try_with(|known| {
        let mut known = known.borrow_mut();
        if known.len() >= KEPT_TABLES {
            known.remove(0);
        }
        known.push(table);
    });
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The points of every routing are `Routing::at`'s bit for bit, kept or not, and a kept
    /// table is lent only for the same helix, length and nodes: one unit in the last place of
    /// a node's arc length or of the phase, or fewer nodes, gets a table of its own.
    #[test]
    fn points_are_those_of_the_routing_at_the_same_nodes_only() {
        let length = 0.242;
        let s: Vec<f64> = (0..=32).map(|k| length * k as f64 / 32.0).collect();
        let helix = Routing::helical(0.008, 1.0, 0.3);
        let custom = Routing::custom(|s, l| Routing::helical(0.004, 2.0, 0.0).at(s, l));
        let bits = |p: RoutingPoint| [p.r, p.r_s, p.r_ss].map(|v| v.map(f64::to_bits));
        let kept = || KNOWN.with(|known| known.borrow().len());
        // Whether `routing`'s points at `s` came from a table, and how many tables are kept.
        let check = |routing: &Routing, s: &[f64]| {
            let table = with_points(routing, length, s, |points| {
                for (k, &sk) in s.iter().enumerate() {
                    assert_eq!(bits(points.at(k)), bits(routing.at(sk, length)), "node {k}");
                }
                matches!(points, Points::Table(_))
            });
            (table, kept())
        };
        // A fresh thread (each test has its own) keeps nothing yet.
        assert_eq!(kept(), 0);
        for routing in [Routing::straight(0.008, -0.002), custom] {
            assert_eq!(check(&routing, &s), (false, 0));
        }
        // Built, then lent (twice): one table.
        for _ in 0..3 {
            assert_eq!(check(&helix, &s), (true, 1));
        }
        let mut moved = s.clone();
        moved[7] = f64::from_bits(moved[7].to_bits() + 1);
        assert_eq!(check(&helix, &moved), (true, 2));
        let turned = Routing::helical(0.008, 1.0, f64::from_bits(0.3f64.to_bits() + 1));
        assert_eq!(check(&turned, &s), (true, 3));
        assert_eq!(check(&helix, &s[..20]), (true, 4));
        assert_eq!(check(&helix, &s), (true, 4));
        // More tables than are kept: the oldest's buffers are reused, the points unchanged.
        for n in 0..2 * KEPT_TABLES {
            assert_eq!(check(&helix, &s[..n + 2]).1, (n + 5).min(KEPT_TABLES));
        }
    }
}
