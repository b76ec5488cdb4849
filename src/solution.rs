//! The solved shape, shared by all solvers: nodes along the backbone, tendon paths, the tip
//! pose, and evaluation at any arc length with the cubic Hermite interpolant (the natural
//! interpolant of the Hermite-Simpson scheme; 4th-order accurate between nodes).
//!
//! A plain output type: it computes no physics. The solvers fill it from their node states
//! with the mesh layer's `nodes::solution`.
#![allow(non_snake_case)]

use crate::report::SolveReport;
use crate::so3;
use nalgebra::{Matrix3, Vector3};

/// The state at one node. Where the solution jumps (a tendon termination or point load) two
/// nodes share the same s: the first is the left limit, the second the right limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Arc length (m).
    pub s: f64,
    /// Centreline position (m), world frame.
    pub p: Vector3<f64>,
    /// Orientation, body to world.
    pub R: Matrix3<f64>,
    /// Shear/extension strain, body frame (p' = R v).
    pub v: Vector3<f64>,
    /// Curvature/twist, body frame (R' = R hat(u)), rad/m.
    pub u: Vector3<f64>,
    /// dv/ds (1/m).
    pub v_s: Vector3<f64>,
    /// du/ds (rad/m^2).
    pub u_s: Vector3<f64>,
    /// Internal force (N), world frame.
    pub n: Vector3<f64>,
    /// Internal moment (N m), world frame.
    pub m: Vector3<f64>,
}

impl Node {
    /// The node's state (s, p, R, v, u).
    pub fn state(&self) -> State {
        State {
            s: self.s,
            p: self.p,
            R: self.R,
            v: self.v,
            u: self.u,
        }
    }
}

/// The state at an arbitrary arc length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// Arc length (m).
    pub s: f64,
    /// Position (m), world frame.
    pub p: Vector3<f64>,
    /// Orientation, body to world (orthonormal to rounding).
    pub R: Matrix3<f64>,
    /// Shear/extension strain, body frame. In the solvers' own node states of a Kirchhoff
    /// rod, whose strain is v* exactly, this slot is the translational unknown
    /// v* + K_se^-1 n_b, the internal force in strain units
    /// ([`crate::model::equations::Site::strain`], docs/model.md section 4b); a
    /// [`Solution`] always holds the strain.
    pub v: Vector3<f64>,
    /// Curvature/twist, body frame (rad/m).
    pub u: Vector3<f64>,
}

/// What a solution says about one tendon: its tension, its actuator's pull-in, its path
/// length and slack (docs/actuation.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TendonState {
    /// Tension tau_i (N) where the tendon enters the backbone at the base: the input of a
    /// tension-controlled tendon, the solved one of a displacement-controlled tendon (0 when
    /// slack).
    pub tension: f64,
    /// Tension at the termination (N), what the tendon delivers to its attachment: equal to
    /// `tension` without friction, lower when friction holds it back (docs/friction.md).
    pub delivered_tension: f64,
    /// Pull-in q_i of the actuator (m): the input of a displacement-controlled tendon; for a
    /// tension-controlled one the pull-in that holds it taut at its tension,
    /// reference_length - length + stretch.
    pub displacement: f64,
    /// Path length l_i from the base to the termination (m), the integral of |p_i'|.
    pub length: f64,
    /// Path length in the unloaded shape (m), the reference of the pull-in.
    pub reference_length: f64,
    /// Length of tendon the actuator's pull-in has not taken up (m): 0 when taut, > 0 when
    /// a displacement-controlled tendon is slack.
    pub slack: f64,
}

/// A solved robot shape.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Nodes in increasing s, from 0 to L.
    pub nodes: Vec<Node>,
    /// For each tendon, its path p_i(s) = p + R r_i (m, world) at the nodes up to its
    /// termination.
    pub tendon_paths: Vec<Vec<Vector3<f64>>>,
    /// For each tendon, its tension tau_i(s) (N) at the points of its path in
    /// `tendon_paths`: constant without friction, varying along the tendon with it.
    pub tendon_tensions: Vec<Vec<f64>>,
    /// For each tendon, its tension, pull-in, lengths and slack.
    pub tendons: Vec<TendonState>,
    /// How the solve went.
    pub report: SolveReport,
}

impl Solution {
    /// Backbone length (m).
    pub fn length(&self) -> f64 {
        self.nodes.last().map_or(0.0, |n| n.s)
    }

    /// The tension of every tendon (N), solved ones included: what
    /// [`crate::Robot::with_tensions`] takes.
    pub fn tensions(&self) -> Vec<f64> {
        self.tendons.iter().map(|t| t.tension).collect()
    }

    /// The tension (N) of tendon `i` at arc length `s` (clamped to the tendon's span),
    /// between the points of its path interpolated linearly in the logarithm of the tension
    /// (exact where the path turns at a constant rate, as the capstan law makes the tension
    /// exponential in the turning angle there; docs/friction.md). None for a tendon index
    /// out of range.
    pub fn tension_at(&self, i: usize, s: f64) -> Option<f64> {
        let (points, tensions) = self.tension_points(i)?;
        tension_between(&points, tensions, s)
    }

    /// [`Solution::tension_at`] at each arc length of `s`, the path's points found once
    /// (the same values bit for bit).
    pub(crate) fn tensions_at(&self, i: usize, s: impl Iterator<Item = f64>) -> Vec<Option<f64>> {
        match self.tension_points(i) {
            Some((points, tensions)) => s.map(|s| tension_between(&points, tensions, s)).collect(),
            None => s.map(|_| None).collect(),
        }
    }

    /// The arc lengths of the points of tendon `i`'s path (the nodes up to the tendon's end,
    /// one per s) and its tensions there; None for a tendon index out of range.
    fn tension_points(&self, i: usize) -> Option<(Vec<f64>, &[f64])> {
        let tensions = self.tendon_tensions.get(i)?;
        let mut last = f64::NEG_INFINITY;
        let points: Vec<f64> = self
            .nodes
            .iter()
            .map(|n| n.s)
            .filter(|&x| std::mem::replace(&mut last, x) < x)
            .take(tensions.len())
            .collect();
        Some((points, tensions))
    }

    /// The tip node.
    pub fn tip(&self) -> &Node {
        &self.nodes[self.nodes.len() - 1]
    }

    /// The base node.
    pub fn base(&self) -> &Node {
        &self.nodes[0]
    }

    /// Tip position (m), world frame.
    pub fn tip_position(&self) -> Vector3<f64> {
        self.tip().p
    }

    /// The state at arc length `s` (clamped to [0, L]), from the cubic Hermite interpolant
    /// in the local coordinates of the interval (R = R_k exp(theta(s))), so R stays a rotation.
    /// At a jump the right limit is returned.
    pub fn at(&self, s: f64) -> State {
        self.at_limit(s, false)
    }

    /// As [`Solution::at`], choosing the left limit at a jump when `left` is set.
    pub fn at_limit(&self, s: f64, left: bool) -> State {
        at_limit(&self.nodes, s, left)
    }

    /// The interval k (nodes k, k + 1) holding arc length `s` (in [0, L]; the left limit's
    /// interval at a jump when `left` is set) and the cubic Hermite basis weights
    /// (h00, h10, h01, h11) at t = (s - s_k) / h of [`Solution::at`]: y(s) = h00 y_k +
    /// h10 h y'_k + h01 y_k+1 + h11 h y'_k+1.
    pub(crate) fn interval(&self, s: f64, left: bool) -> (usize, [f64; 4]) {
        interval(&self.nodes, s, left)
    }

    /// Largest deviation from orthonormality over all node rotations (0 for exact rotations).
    pub fn max_orthonormality_error(&self) -> f64 {
        self.nodes
            .iter()
            .map(|n| so3::orthonormality_error(&n.R))
            .fold(0.0, f64::max)
    }
}

/// The tension at arc length `s` (clamped to the path) of a path with the increasing
/// `points` and the `tensions` there ([`Solution::tension_at`]).
fn tension_between(points: &[f64], tensions: &[f64], s: f64) -> Option<f64> {
    let (first, end) = (*points.first()?, *points.last()?);
    let s = s.clamp(first, end);
    let k = points
        .iter()
        .rposition(|&x| x <= s)?
        .min(points.len().saturating_sub(2));
    if points.len() < 2 || tensions[k] <= 0.0 || tensions[k + 1] <= 0.0 {
        return Some(tensions[k]);
    }
    let t = (s - points[k]) / (points[k + 1] - points[k]);
    Some(tensions[k] * (tensions[k + 1] / tensions[k]).powf(t))
}

/// The state at arc length `s` (m) interpolated between the `nodes` of a solution (what
/// [`Solution::at_limit`] returns), choosing the left limit at a jump when `left` is set.
pub(crate) fn at_limit(nodes: &[Node], s: f64, left: bool) -> State {
    let s = s.clamp(0.0, nodes.last().map_or(0.0, |n| n.s));
    let (k, [h00, h10, h01, h11]) = interval(nodes, s, left);
    let (a, b) = (&nodes[k], &nodes[k + 1]);
    let h = b.s - a.s;
    let herm = |y0: Vector3<f64>, d0: Vector3<f64>, y1: Vector3<f64>, d1: Vector3<f64>| {
        y0 * h00 + d0 * (h10 * h) + y1 * h01 + d1 * (h11 * h)
    };
    let theta1 = so3::log(&(a.R.transpose() * b.R));
    let theta = herm(Vector3::zeros(), a.u, theta1, so3::right_jacobian_inv(&theta1) * b.u);
    State {
        s,
        p: herm(a.p, a.R * a.v, b.p, b.R * b.v),
        R: a.R * so3::exp(&theta),
        v: herm(a.v, a.v_s, b.v, b.v_s),
        u: herm(a.u, a.u_s, b.u, b.u_s),
    }
}

/// The interval k (nodes k, k + 1) holding arc length `s` (in [0, L]; the left limit's
/// interval at a jump when `left` is set) and the cubic Hermite basis weights
/// (h00, h10, h01, h11) at t = (s - s_k) / h of [`Solution::at`]: y(s) = h00 y_k +
/// h10 h y'_k + h01 y_k+1 + h11 h y'_k+1.
pub(crate) fn interval(nodes: &[Node], s: f64, left: bool) -> (usize, [f64; 4]) {
    let inside = |i: usize| {
        let (a, b) = (nodes[i].s, nodes[i + 1].s);
        b > a && if left { a < s && s <= b } else { a <= s && s < b }
    };
    let last = nodes.len() - 2;
    // A mesh's node arc lengths increase (repeated at a jump), so at most one interval of
    // positive length holds s, the one from the last node at or before s (before s for
    // the left limit): found by bisection. Where that one does not hold s (s at or past
    // an end), the search through all of them, which finds none either.
    let before = if left {
        nodes.partition_point(|n| n.s < s)
    } else {
        nodes.partition_point(|n| n.s <= s)
    };
    let k = match before.checked_sub(1).filter(|&i| i <= last && inside(i)) {
        Some(i) => i,
        None => (0..=last)
            .find(|&i| inside(i))
            .unwrap_or(if left || s > 0.0 { last } else { 0 }),
    };
    let t = (s - nodes[k].s) / (nodes[k + 1].s - nodes[k].s);
    let weights = [
        2.0 * t * t * t - 3.0 * t * t + 1.0,
        t * t * t - 2.0 * t * t + t,
        -2.0 * t * t * t + 3.0 * t * t,
        t * t * t - t * t,
    ];
    (k, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node at arc length `s` (the rest zero, identity rotation: `interval` reads s only).
    fn node(s: f64) -> Node {
        Node {
            s,
            p: Vector3::zeros(),
            R: Matrix3::identity(),
            v: Vector3::zeros(),
            u: Vector3::zeros(),
            v_s: Vector3::zeros(),
            u_s: Vector3::zeros(),
            n: Vector3::zeros(),
            m: Vector3::zeros(),
        }
    }

    /// `interval`'s search through every interval in order, as it was before the
    /// bisection: the first interval of positive length holding s.
    fn searched(nodes: &[Node], s: f64, left: bool) -> usize {
        let inside = |i: usize| {
            let (a, b) = (nodes[i].s, nodes[i + 1].s);
            b > a && if left { a < s && s <= b } else { a <= s && s < b }
        };
        let last = nodes.len() - 2;
        (0..=last)
            .find(|&i| inside(i))
            .unwrap_or(if left || s > 0.0 { last } else { 0 })
    }

    /// The bisection finds the interval the search in order finds, with its weights bit for
    /// bit, on meshes with jumps (a repeated arc length, at the start, inside and at the
    /// end) for arc lengths at every node, between nodes, at and past the ends and NaN,
    /// both limits.
    #[test]
    fn the_bisection_finds_the_interval_of_the_search() {
        let meshes: [&[f64]; 4] = [
            &[0.0, 0.1, 0.2, 0.35, 0.5],
            &[0.0, 0.1, 0.2, 0.2, 0.35, 0.5],
            &[0.0, 0.0, 0.1, 0.2, 0.2, 0.2, 0.3, 0.3],
            &[0.0, 0.5],
        ];
        let mut checked = 0;
        for s in meshes {
            let nodes: Vec<Node> = s.iter().map(|&s| node(s)).collect();
            let mut at: Vec<f64> = s.to_vec();
            at.extend(s.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            at.extend(s.windows(2).map(|w| w[0] + 1e-3 * (w[1] - w[0])));
            at.extend([-0.1, 0.7, f64::NAN, 1e-300]);
            for &x in &at {
                for left in [false, true] {
                    let (k, weights) = interval(&nodes, x, left);
                    assert_eq!(k, searched(&nodes, x, left), "{x} left {left} on {s:?}");
                    let (a, b) = (nodes[k].s, nodes[k + 1].s);
                    let t = (x - a) / (b - a);
                    let want = [
                        2.0 * t * t * t - 3.0 * t * t + 1.0,
                        t * t * t - 2.0 * t * t + t,
                        -2.0 * t * t * t + 3.0 * t * t,
                        t * t * t - t * t,
                    ];
                    let bits = |w: &[f64; 4]| w.map(f64::to_bits);
                    assert_eq!(bits(&weights), bits(&want));
                    checked += 1;
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }

    /// The tensions along a path found once ([`Solution::tensions_at`]) are
    /// [`Solution::tension_at`]'s bit for bit, on the prototype with friction on tendon 1 at
    /// 2.94 N.
    #[test]
    fn tensions_along_a_path_are_the_tension_at_each_point() {
        let mut robot = crate::cases::prototype().with_tensions(&[2.94, 0.0, 0.0, 0.0, 0.0]);
        robot.tendons[0].friction = Some(crate::Friction::pull(0.1));
        let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
        let length = robot.length();
        let s: Vec<f64> = (0..=200).map(|k| length * (k as f64 / 180.0 - 0.05)).collect();
        for i in 0..robot.tendons.len() + 1 {
            let along = solution.tensions_at(i, s.iter().copied());
            assert_eq!(along.len(), s.len());
            for (&x, got) in s.iter().zip(along) {
                assert_eq!(got.map(f64::to_bits), solution.tension_at(i, x).map(f64::to_bits));
            }
        }
        // Tendon 1's tension falls along it (pulled in against friction around its bend), so
        // the comparison sees the interpolation, not one value everywhere.
        let t = solution.tensions_at(0, [0.0, 0.5 * length].into_iter());
        assert!(t[0].unwrap() > t[1].unwrap(), "{t:?}");
    }
}
