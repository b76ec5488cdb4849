//! Tendon path lengths (docs/actuation.md): the speed |p_i'| of a tendon's path at one
//! arc length and its derivatives, the reference length in the unloaded shape, and the
//! node quadrature that gives the length of a solved path.
//!
//! The path of tendon i is p_i = p + R r_i (eq. 6), so p_i' = R (v + u x r_i + r_i') and
//! its speed is |w_i| with w_i = v + u x r_i + r_i' (body frame; the rotation drops out).
//! Its length from the base to the termination l_i is
//!
//! ```text
//! l_i = integral over [0, l_i] of |v + u x r_i + r_i'| ds.
//! ```
//!
//! On a solution the integrand is known at the nodes. [`NodeQuadrature`] integrates, on
//! every interval, the cubic through the four nearest nodes of the same smooth segment
//! (segments end at breakpoints, where v and u jump): an O(h^5) local and O(h^4) global
//! error, the order of the collocation scheme, with weights on the node values alone, so
//! the length's derivative with respect to the node strains is exact and touches only
//! (v, u) of each node ([`speed_gradient`]).

use crate::model::robot::Robot;
use crate::model::rod::ReferenceStrains;
use crate::model::routing::{Routing, RoutingPoint};
use nalgebra::Vector3;
use std::cell::RefCell;

/// The speed |w| of a tendon path, w = v + u x r + r' (body frame, dimensionless).
pub fn speed(rp: &RoutingPoint, v: &Vector3<f64>, u: &Vector3<f64>) -> f64 {
    (v + u.cross(&rp.r) + rp.r_s).norm()
}

/// The derivatives of [`speed`] with respect to v and u: with t = w / |w|,
/// d|w|/dv = t and d|w|/du = r x t (since d(u x r) = du x r and t . (du x r) = du . (r x t)).
pub fn speed_gradient(rp: &RoutingPoint, v: &Vector3<f64>, u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let w = v + u.cross(&rp.r) + rp.r_s;
    let t = w / w.norm();
    (t, rp.r.cross(&t))
}

/// Gauss-Legendre panels per smooth piece of the reference integral.
const REFERENCE_PANELS: usize = 32;

/// 5-point Gauss-Legendre nodes on [-1, 1] and their weights (exact to degree 9).
const GAUSS5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// The reference length of tendon `i` (m): its path length in the unloaded shape
/// (v = v*, u = u*), by composite 5-point Gauss-Legendre on 32 panels
/// between consecutive breakpoints (order 10: to rounding for the prototype's straight and
/// helical routings, whose speed is constant on a straight rod, and about 1e-12 relative
/// for a precurved rod turning a radian per panel).
pub fn reference_length(robot: &Robot, i: usize) -> f64 {
    reference_length_on(robot, &robot.breakpoints(), i)
}

/// [`reference_length`] with the robot's breakpoints ([`Robot::breakpoints`]) given, for a
/// caller that needs the reference lengths of several tendons (computed once for all).
///
/// The value depends only on the geometry, not on the loads or tensions, so the last few are
/// kept per thread for geometries given by data alone (not by a user function) and
/// returned again for a geometry that is bit for bit the same (a batch of rows that change
/// tensions computes each once).
pub(crate) fn reference_length_on(robot: &Robot, breakpoints: &[f64], i: usize) -> f64 {
    let length = robot.length();
    let tendon = &robot.tendons[i];
    let end = tendon.end(length);
    // The key is built in the thread's scratch buffer: a Vec is allocated only for a new
    // geometry's kept key.
    let (keyed, known) = KNOWN.with_borrow_mut(|KnownLengths { kept, scratch }| {
        if !Geometry::fill(robot, breakpoints, i, scratch) {
            return (false, None);
        }
        (true, kept.iter().find(|(k, _)| k.numbers == *scratch).map(|(_, v)| *v))
    });
    if let Some(value) = known {
        return value;
    }
    let value = gauss_points(breakpoints, end, REFERENCE_PANELS)
        .map(|(s, weight)| {
            let reference = robot.rod.reference_at(s);
            let rp = tendon.routing.at(s, length);
            weight * speed(&rp, &reference.v_star, &reference.u_star)
        })
        .sum();
    if keyed {
        KNOWN.with_borrow_mut(|KnownLengths { kept, scratch }| {
            if kept.len() == KEPT_LENGTHS {
                kept.remove(0);
            }
            kept.push((
                Geometry {
                    numbers: scratch.clone(),
                },
                value,
            ));
        });
    }
    value
}

/// How many node quadratures a thread keeps ([`NodeQuadrature::with_kept`]): the meshes of a
/// solve and of its neighbours, with a few tendon ends each.
const KEPT_QUADRATURES: usize = 8;

thread_local! {
    /// Node quadratures built on this thread, least recently used first, with their nodes'
    /// arc lengths and end.
    static KNOWN_QUADRATURES: RefCell<Vec<(Vec<f64>, f64, NodeQuadrature)>> = const { RefCell::new(Vec::new()) };
}

/// How many reference lengths a thread keeps ([`reference_length_on`]).
const KEPT_LENGTHS: usize = 16;

thread_local! {
    /// Reference lengths computed on this thread, and the buffer a lookup's key is built in.
    static KNOWN: RefCell<KnownLengths> = const {
        RefCell::new(KnownLengths {
            kept: Vec::new(),
            scratch: Vec::new(),
        })
    };
}

/// The reference lengths a thread keeps ([`reference_length_on`]).
struct KnownLengths {
    /// Reference lengths computed on this thread, oldest first, with their geometry.
    kept: Vec<(Geometry, f64)>,
    /// The key of the current lookup ([`Geometry::fill`]), kept to spare an allocation.
    scratch: Vec<u64>,
}

/// Everything a reference length depends on, as bits: the rod length, the tendon's end, the
/// breakpoints, its routing and the reference strains. None where the routing or the
/// strains are a user function (two such functions cannot be compared).
#[derive(PartialEq)]
struct Geometry {
    numbers: Vec<u64>,
}

impl Geometry {
    /// Writes the numbers of tendon `i`'s geometry into `numbers` (cleared first); false
    /// where the routing or the reference strains are a user function.
    fn fill(robot: &Robot, breakpoints: &[f64], i: usize, numbers: &mut Vec<u64>) -> bool {
        let length = robot.length();
        let tendon = &robot.tendons[i];
        numbers.clear();
        numbers.extend([length.to_bits(), tendon.end(length).to_bits(), breakpoints.len() as u64]);
        numbers.extend(breakpoints.iter().map(|b| b.to_bits()));
        match tendon.routing {
            Routing::Straight { x, y } => numbers.extend([0, x.to_bits(), y.to_bits()]),
            Routing::Helical { radius, turns, phase } => {
                numbers.extend([1, radius.to_bits(), turns.to_bits(), phase.to_bits()])
            }
            Routing::Custom(_) => return false,
        }
        match &robot.rod.reference {
            ReferenceStrains::Straight => numbers.push(0),
            ReferenceStrains::Constant { v_star, u_star } => {
                numbers.push(1);
                numbers.extend(v_star.iter().chain(u_star.iter()).map(|x| x.to_bits()));
            }
            ReferenceStrains::Segments { ends, u_star } => {
                numbers.extend([2, ends.len() as u64]);
                numbers.extend(ends.iter().map(|x| x.to_bits()));
                numbers.extend(u_star.iter().flat_map(|u| u.iter()).map(|x| x.to_bits()));
            }
            ReferenceStrains::Varying(_) => return false,
        }
        true
    }
}

/// The points s and weights of composite 5-point Gauss-Legendre on `panels` equal panels
/// between consecutive points of 0, the `breakpoints` (increasing, [`Robot::breakpoints`])
/// before `end`, and `end` (integrands may jump at breakpoints). Allocates nothing.
fn gauss_points(breakpoints: &[f64], end: f64, panels: usize) -> impl Iterator<Item = (f64, f64)> + '_ {
    let inner = breakpoints.iter().copied().filter(move |&b| b < end);
    let starts = std::iter::once(0.0).chain(inner.clone());
    let ends = inner.chain(std::iter::once(end));
    starts.zip(ends).flat_map(move |(a, b)| {
        let h = (b - a) / panels as f64;
        (0..panels).flat_map(move |k| {
            let mid = a + (k as f64 + 0.5) * h;
            GAUSS5
                .into_iter()
                .map(move |(x, weight)| (mid + 0.5 * h * x, 0.5 * h * weight))
        })
    })
}

/// The pull-in compliance of the unloaded robot (m/N), `k x k` for its k tendons, row
/// major: entry (j, m) is the pull-in of tendon j per newton of tendon m's tension in the
/// small-deflection linearization about the unloaded shape (docs/actuation.md),
///
/// ```text
/// K_jm = integral over [0, min(l_j, l_m)] of t_j . D^-1 t_m + (r_j x t_j) . C^-1 (r_m x t_m) ds,
/// ```
///
/// with t_i the unit tangent of tendon i's reference path: tension tau_m compresses the
/// backbone by D^-1 tau_m t_m and bends it by C^-1 tau_m (r_m x t_m), which shortens path j
/// by t_j . (dv + du x r_j). Symmetric and positive semidefinite; the displacement solve
/// starts from the tensions it predicts.
pub fn pull_in_compliance(robot: &Robot) -> Vec<f64> {
    let length = robot.length();
    let k = robot.tendons.len();
    let mut out = vec![0.0; k * k];
    let mut tangents = vec![(Vector3::zeros(), Vector3::zeros()); k];
    // A starting estimate: a few panels per piece resolve these smooth integrands well enough.
    for (s, weight) in gauss_points(&robot.breakpoints(), length, 8) {
        let reference = robot.rod.reference_at(s);
        let section = robot.rod.section_at(s).section;
        for (i, t) in robot.tendons.iter().enumerate() {
            let rp = t.routing.at(s, length);
            let w = reference.v_star + reference.u_star.cross(&rp.r) + rp.r_s;
            let tangent = w / w.norm();
            tangents[i] = (tangent, rp.r.cross(&tangent));
        }
        for j in 0..k {
            for m in 0..k {
                if s > robot.tendons[j].end(length).min(robot.tendons[m].end(length)) {
                    continue;
                }
                let (tj, bj) = tangents[j];
                let (tm, bm) = tangents[m];
                let integrand = tj.dot(&tm.component_div(&section.kse)) + bj.dot(&bm.component_div(&section.kbt));
                out[j * k + m] += weight * integrand;
            }
        }
    }
    out
}

/// Weights w_k with sum_k w_k f(s_k) ~ integral of f over [0, end] for node arc lengths
/// `s` (increasing; a repeated value is a breakpoint, where f may jump), built once per
/// mesh and tendon.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeQuadrature {
    /// (node index, weight in m), for the nodes on [0, end] that carry weight.
    pub weights: Vec<(usize, f64)>,
}

impl NodeQuadrature {
    /// The quadrature over [0, `end`] on nodes at arc lengths `s`: on each interval of a
    /// smooth segment, the exact integral of the Lagrange interpolant through the four
    /// nearest nodes of that segment (fewer when the segment has fewer), evaluated by
    /// 2-point Gauss-Legendre (exact for cubics). A node at `end` that starts a new
    /// segment (the right limit at a termination) gets no weight.
    pub fn new(s: &[f64], end: f64) -> Self {
        let mut weights = vec![0.0; s.len()];
        let mut first = 0;
        while first + 1 < s.len() && s[first] < end {
            // One smooth segment: nodes first..=last with increasing s.
            let mut last = first;
            while last + 1 < s.len() && s[last + 1] > s[last] && s[last] < end {
                last += 1;
            }
            for k in first..last {
                let lo = k.saturating_sub(1).max(first).min(last.saturating_sub(3).max(first));
                let hi = (lo + 3).min(last);
                let stencil = lo..=hi;
                let (a, b) = (s[k], s[k + 1]);
                let half = 0.5 * (b - a);
                for g in [-1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt()] {
                    let x = 0.5 * (a + b) + half * g;
                    for j in stencil.clone() {
                        let basis: f64 = stencil
                            .clone()
                            .filter(|&m| m != j)
                            .map(|m| (x - s[m]) / (s[j] - s[m]))
                            .product();
                        weights[j] += half * basis;
                    }
                }
            }
            first = last + 1;
        }
        NodeQuadrature {
            weights: weights.into_iter().enumerate().filter(|&(_, w)| w != 0.0).collect(),
        }
    }

    /// `f` of [`NodeQuadrature::new`], kept per thread: the weights depend only on the
    /// nodes' arc lengths and `end`, so the last few are kept and lent again for bit for bit
    /// the same `s` and `end` (the solutions of one mesh: a batch of rows, a sweep, repeated
    /// solves) instead of the Lagrange weights' divisions. The kept one is taken out of the
    /// thread's list while `f` runs (so that `f` may build others) and kept again as the most
    /// recently used.
    pub(crate) fn with_kept<T>(s: &[f64], end: f64, f: impl FnOnce(&NodeQuadrature) -> T) -> T {
        let same = |(ks, kend, _): &(Vec<f64>, f64, NodeQuadrature)| {
            kend.to_bits() == end.to_bits()
                && ks.len() == s.len()
                && ks.iter().zip(s).all(|(a, b)| a.to_bits() == b.to_bits())
        };
        let known = KNOWN_QUADRATURES.with(|known| {
            let mut known = known.borrow_mut();
            let at = known.iter().position(same)?;
            Some(known.remove(at))
        });
        let entry = known.unwrap_or_else(|| (s.to_vec(), end, NodeQuadrature::new(s, end)));
        let value = f(&entry.2);
        KNOWN_QUADRATURES.with(|known| {
            let mut known = known.borrow_mut();
            if known.len() >= KEPT_QUADRATURES {
                known.remove(0);
            }
            known.push(entry);
        });
        value
    }

    /// The integral of the node values `f(k)`.
    pub fn integrate(&self, f: impl Fn(usize) -> f64) -> f64 {
        self.weights.iter().map(|&(k, w)| w * f(k)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// A reference length computed on a new thread, whose kept lengths are empty.
    fn fresh(robot: &Robot, i: usize) -> f64 {
        let robot = robot.clone();
        std::thread::spawn(move || reference_length(&robot, i)).join().unwrap()
    }

    /// Kept node quadratures are bit for bit the ones built afresh, and a change of a node's
    /// arc length (by one unit in the last place) or of the end gets its own.
    #[test]
    fn kept_node_quadratures_are_those_of_the_same_nodes_only() {
        let s: Vec<f64> = (0..=16).map(|k| 0.2 * (k as f64 / 16.0).powf(1.3)).collect();
        let built = NodeQuadrature::new(&s, 0.15);
        assert_eq!(NodeQuadrature::with_kept(&s, 0.15, Clone::clone), built);
        assert_eq!(NodeQuadrature::with_kept(&s, 0.15, Clone::clone), built);
        let mut moved = s.clone();
        moved[5] = f64::from_bits(moved[5].to_bits() + 1);
        assert_eq!(
            NodeQuadrature::with_kept(&moved, 0.15, Clone::clone),
            NodeQuadrature::new(&moved, 0.15)
        );
        assert_ne!(NodeQuadrature::with_kept(&moved, 0.15, Clone::clone), built);
        assert_eq!(
            NodeQuadrature::with_kept(&s, 0.2, Clone::clone),
            NodeQuadrature::new(&s, 0.2)
        );
        assert_ne!(NodeQuadrature::with_kept(&s, 0.2, Clone::clone), built);
    }

    #[test]
    fn kept_reference_lengths_are_those_of_the_same_geometry_only() {
        let mut robot = crate::cases::prototype();
        robot.rod.reference = ReferenceStrains::Constant {
            v_star: Vector3::z(),
            u_star: Vector3::new(0.0, 2.0, 0.0),
        };
        // Curved about y, so that tendon 0 (offset along x) is shorter than the rod.
        let first = reference_length(&robot, 0);
        // Kept: bit for bit what a thread without kept lengths computes.
        assert_eq!(reference_length(&robot, 0).to_bits(), first.to_bits());
        assert_eq!(fresh(&robot, 0).to_bits(), first.to_bits());
        // Tensions are not part of the geometry.
        let tension = robot.tendons[0].tension();
        robot.tendons[0].set_tension(tension + 1.0);
        assert_eq!(reference_length(&robot, 0).to_bits(), first.to_bits());
        // Each change of the geometry gives its own length, never a kept one.
        let mut changed = Vec::new();
        let mut offset = robot.clone();
        offset.tendons[0].routing = Routing::straight(0.01, 0.0);
        changed.push(offset);
        let mut curved = robot.clone();
        curved.rod.reference = ReferenceStrains::Constant {
            v_star: Vector3::z(),
            u_star: Vector3::new(0.0, 3.0, 0.0),
        };
        changed.push(curved);
        let mut longer = robot.clone();
        longer.rod.length *= 1.1;
        changed.push(longer);
        for other in &changed {
            let kept_first = reference_length(other, 0);
            assert_ne!(kept_first.to_bits(), first.to_bits());
            assert_eq!(kept_first.to_bits(), fresh(other, 0).to_bits());
        }
        assert_eq!(reference_length(&robot, 0).to_bits(), first.to_bits());
    }

    #[test]
    fn node_quadrature_is_order_four_and_splits_at_jumps() {
        // f = cos on [0, 0.5), 2 + s^3 on [0.5, 1] (a jump at the breakpoint 0.5).
        let f = |s: f64, right: bool| if right { 2.0 + s * s * s } else { s.cos() };
        let exact = 0.5f64.sin() + (2.0 * 0.5 + (1.0 - 0.5f64.powi(4)) / 4.0);
        let error = |n: usize| {
            let mut s: Vec<f64> = (0..=n).map(|k| 0.5 * k as f64 / n as f64).collect();
            s.extend((0..=n).map(|k| 0.5 + 0.5 * k as f64 / n as f64));
            let q = NodeQuadrature::new(&s, 1.0);
            (q.integrate(|k| f(s[k], k > n)) - exact).abs()
        };
        let (coarse, fine) = (error(32), error(64));
        // Order 4: halving h cuts the error 16-fold asymptotically; the one-sided end
        // stencils approach it slowly (7.8 at 8 -> 16 intervals, 12.8 at 16 -> 32), so 12
        // separates order 4 from order 3 (8).
        assert!(coarse / fine > 12.0, "{coarse:e} {fine:e}");
        // 1e-10: the cubic part is exact, the cosine's error at h = 1/128 is about 2e-11.
        assert!(fine < 1e-10, "{fine:e}");
    }

    #[test]
    fn quadrature_stops_at_a_termination_before_the_right_limit() {
        let s = [0.0, 0.25, 0.5, 0.5, 0.75, 1.0];
        let q = NodeQuadrature::new(&s, 0.5);
        // Integral of 1 over [0, 0.5]; the right limit (index 3) and beyond get nothing.
        // 1e-15: exact weights up to rounding.
        assert_relative_eq!(q.integrate(|_| 1.0), 0.5, epsilon = 1e-15);
        assert!(q.weights.iter().all(|&(k, _)| k <= 2));
    }
}
