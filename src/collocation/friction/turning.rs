//! Where a tendon's path stops turning (docs/friction.md section 8, "honest18" and
//! "honest19"): where the backbone's bending reverses inside a link, each tendon's turning
//! t' (t the unit tangent of its path) passes through 0, so its turning rate kappa = |t'|
//! has a kink (a V) and the sliding tension, tau' = -+ mu tau kappa, a jump in its second
//! derivative. A collocation link that holds such a point loses its order and its deferred
//! correction misjudges it; a node there restores both. This module finds the points on a
//! solution and moves points already placed to where a new solution puts them: what the
//! full-slip refinement ([`super::kinks`]) and a history's sliding steps
//! (`history/inflection.rs`) share.

use crate::Robot;
use crate::solution::Solution;
use nalgebra::{Vector2, Vector3};

/// The half-width of the central difference of a path's unit tangent (relative to L):
/// 1e-7 L leaves an error of its square (the tangent is smooth: only |t'| has a kink) and of
/// rounding, eps / 1e-7, about 1e-9 of the turning, below what a point's place matters by.
const STEP: f64 = 1e-7;

/// A point where t' reverses is a kink only where its turning |t'| there is below this
/// share of its larger one at the link's ends: a planar bend's is rounding's (below 1e-7
/// measured), a V rounded over at most 1e-3 of the link, whose rounding the node leaves
/// unresolved by about the square of that share. A path that turns in 3-D may reverse t'
/// with |t'| far from 0 (0.02 to 0.8 of the ends' on random loads of the prototype), a
/// rounded V or no V at all: a node there misleads the estimate (a random load's error
/// was 1.16 times its estimate with one, 0.90 without) and is not placed.
const KINK: f64 = 1e-3;

/// A point found on a new answer within this (relative to L) of one placed before is that
/// point, moved.
pub(super) const NEAR: f64 = 1e-4;

/// A point has settled when it moves by less than this (relative to L) between two solves.
pub(super) const SETTLED: f64 = 1e-8;

/// The links between consecutive bending curvatures (u_x, u_y) of `bending` (one per node)
/// over which the bending reverses (their dot product is not positive), on a rod of length
/// `length` that is not straight to within a total turning of 1e-8 rad there (a column
/// below or at its buckling load, bent only by rounding, has no kink worth a node).
pub(super) fn reversed(bending: &[Vector3<f64>], length: f64) -> Vec<bool> {
    let straight = 1e-8 / length;
    let planar = |u: &Vector3<f64>| Vector2::new(u.x, u.y);
    bending
        .windows(2)
        .map(|w| {
            let (a, b) = (planar(&w[0]), planar(&w[1]));
            a.dot(&b) <= 0.0 && a.norm().max(b.norm()) > straight
        })
        .collect()
}

/// Where the path of a tendon with friction of `robot` stops turning inside a link of
/// `solution` (within a segment and the tendon's span, where the tendon is loaded): where
/// its turning t' (t the path's unit tangent, p_i' = R (v + u x r_i + r_i')) reverses
/// between two nodes, the point where its component along t' at the first node changes
/// sign, by bisection on the solution's interpolant to the resolution of s (t' by a
/// central difference, [`STEP`]), if its turning nearly vanishes there ([`KINK`]); points
/// of several tendons closer than 1e-9 of their link are one, at their mean. Only links
/// near a reversal of the backbone's bending ([`reversed`]) are looked at. A tendon's
/// turning rate kappa = |t'| passes through 0 there, with a kink, in a planar bend.
pub(super) fn inflections(robot: &Robot, solution: &Solution) -> Vec<f64> {
    kinks(robot, solution).into_iter().map(|kink| kink.at).collect()
}

/// The most a kink left inside a link can move an answer (docs/friction.md section 8,
/// "kinks20"), to first order in the tension's error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Effect {
    /// On the tip position (m).
    pub(super) tip: f64,
    /// On the tip rotation (rad).
    pub(super) rotation: f64,
    /// On a tendon's tension, relative.
    pub(super) tension: f64,
}

impl Effect {
    /// The sum of two effects (they add along the tendons).
    pub(super) fn plus(self, other: Effect) -> Effect {
        Effect {
            tip: self.tip + other.tip,
            rotation: self.rotation + other.rotation,
            tension: self.tension + other.tension,
        }
    }
}

/// A point where the tendons stop turning ([`inflections`]) and what leaving it inside its
/// link could do to the answer (summed over the tendons that share the point).
#[derive(Clone, Copy, Debug)]
pub(super) struct Kink {
    /// Its arc length (m).
    pub(super) at: f64,
    /// The bound on its effect ([`effect`]).
    pub(super) effect: Effect,
}

/// What a link `[a, b]` holding a kink of tendon `i` of `robot` (friction `mu`, largest
/// turning rate `kappa` on the link) can do to `solution`'s answer if no node is placed at
/// the kink (docs/friction.md section 8, "kinks20"). The link adds to the log tension
/// h / 6 mu (kappa_a + 4 kappa_m + kappa_b), a rule with positive weights summing to h, and
/// the exact integral of mu kappa >= 0: both lie in [0, mu h kappa], so the link's error in
/// z (the tension's relative error beyond it) is at most delta = mu h kappa, kink or not. A
/// relative change delta of the tension beyond `a` changes the tendon's moment on each
/// section there by at most delta tau |r| and its axial load by delta tau (tau, |r| the
/// largest tension and offset beyond `a`), so the curvature by delta tau |r| / EI and the
/// strain by delta tau / EA (the smallest stiffnesses beyond `a`), over the tendon's
/// remaining span `end - a`, each with a lever of at most `L - a` to the tip.
fn effect(robot: &Robot, solution: &Solution, i: usize, (a, b): (f64, f64), mu: f64, kappa: f64) -> Effect {
    let length = robot.length();
    let tendon = &robot.tendons[i];
    let end = tendon.end(length);
    let (mut tau, mut offset, mut bending, mut axial) = (0.0_f64, 0.0_f64, f64::INFINITY, f64::INFINITY);
    for (node, &tension) in solution.nodes.iter().zip(&solution.tendon_tensions[i]) {
        if node.s < a || node.s > end {
            continue;
        }
        tau = tau.max(tension.abs());
        offset = offset.max(tendon.routing.at(node.s, length).r.norm());
        let section = robot.rod.section_at(node.s).section;
        bending = bending.min(section.kbt[0].min(section.kbt[1]));
        axial = axial.min(section.kse[2]);
    }
    let delta = mu * (b - a) * kappa;
    let span = (end - a).max(0.0);
    let rotation = delta * tau * offset * span / bending;
    Effect {
        tip: rotation * (length - a) + delta * tau * span / axial,
        rotation,
        tension: delta,
    }
}

/// The points of [`inflections`], each with the bound on its effect ([`effect`]).
pub(super) fn kinks(robot: &Robot, solution: &Solution) -> Vec<Kink> {
    let length = robot.length();
    let mut found: Vec<(f64, f64, Effect)> = Vec::new();
    // Where the segments meet: the nodes listed twice.
    let jumps: Vec<f64> = solution
        .nodes
        .windows(2)
        .filter(|w| w[1].s <= w[0].s)
        .map(|w| w[0].s)
        .collect();
    // The links near a reversal of the backbone's bending between two nodes, within three
    // links of it: a tendon's turning follows the bending, so only there is it worth its
    // interpolated tangents (most solves have none). The bending's zero lies about 1e-6 m
    // from the tendons' (section 8, "honest18"), beyond the two nodes a refined step has at
    // the tendons' own, 1e-9 to 4e-8 m apart: one link either side missed them there
    // (error / estimate 1.03).
    let bending: Vec<Vector3<f64>> = solution.nodes.iter().map(|n| n.u).collect();
    let reversed = reversed(&bending, length);
    if !reversed.contains(&true) {
        return Vec::new();
    }
    let near = |k: usize| reversed[k.saturating_sub(3)..(k + 4).min(reversed.len())].contains(&true);
    for (i, tendon) in robot.tendons.iter().enumerate() {
        let Some(friction) = tendon.active_friction() else {
            continue;
        };
        let end = tendon.end(length);
        let tangent = |s: f64| {
            let state = solution.at(s);
            let rp = tendon.routing.at(s, length);
            let d = state.R * (state.v + state.u.cross(&rp.r) + rp.r_s);
            d / d.norm()
        };
        for (k, pair) in solution.nodes.windows(2).enumerate() {
            let (a, b) = (pair[0].s, pair[1].s);
            if b <= a || b > end || solution.tendon_tensions[i][k] <= 0.0 || !near(k) {
                continue;
            }
            // The segment that holds the link: the interpolant is smooth within it.
            let first = jumps.iter().copied().filter(|&j| j <= a).fold(0.0, f64::max);
            let last = jumps.iter().copied().filter(|&j| j >= b).fold(length, f64::min);
            let turning = |s: f64| {
                let (lo, hi) = ((s - STEP * length).max(first), (s + STEP * length).min(last));
                (tangent(hi) - tangent(lo)) / (hi - lo)
            };
            let along = turning(a);
            if along.dot(&turning(b)) >= 0.0 {
                continue;
            }
            let (mut lo, mut hi) = (a, b);
            while hi - lo > 4.0 * f64::EPSILON * hi {
                let mid = 0.5 * (lo + hi);
                if along.dot(&turning(mid)) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            // A kink only where the turning nearly vanishes ([`KINK`]).
            let at = 0.5 * (lo + hi);
            let ends = turning(a).norm().max(turning(b).norm());
            if turning(at).norm() > KINK * ends {
                continue;
            }
            let kappa = ends.max(turning(0.5 * (a + b)).norm());
            found.push((
                at,
                b - a,
                effect(robot, solution, i, (a, b), friction.coefficient, kappa),
            ));
        }
    }
    // Points closer than 1e-9 of their link share one node, at their mean; the tendons on
    // opposite sides of a planar bend, a few 1e-8 m apart on the prototype, have one each
    // (one node at their mean leaves about 1 % of such a step's error unseen).
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(Kink, usize)> = Vec::new();
    for (at, link, effect) in found {
        match out.last_mut() {
            Some((kink, count)) if at - kink.at <= 1e-9 * link => {
                kink.at += (at - kink.at) / (*count + 1) as f64;
                kink.effect = kink.effect.plus(effect);
                *count += 1;
            }
            _ => out.push((Kink { at, effect }, 1)),
        }
    }
    out.into_iter().map(|(kink, _)| kink).collect()
}

/// Moves each of `points` (placed as nodes of the last solve) to the nearest of `found`
/// (located on the new answer) within `near` (m), nearest pairs first; a point that sits
/// on a node may not be found again (its turning's sign there is rounding's) and stays
/// where it is. A found point with no partner (a kink the last placing did not have, or one
/// that moved farther than `near`) is added. Leaves `points` sorted; returns the largest
/// move (m) and whether a point was added.
pub(super) fn relocate(points: &mut Vec<f64>, found: &[f64], near: f64) -> (f64, bool) {
    let mut pairs: Vec<(f64, usize, usize)> = points
        .iter()
        .enumerate()
        .flat_map(|(p, &e)| found.iter().enumerate().map(move |(f, &g)| ((g - e).abs(), p, f)))
        .filter(|&(d, _, _)| d < near)
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut point_taken, mut found_taken) = (vec![false; points.len()], vec![false; found.len()]);
    let mut moved = 0.0_f64;
    for (d, p, f) in pairs {
        if !point_taken[p] && !found_taken[f] {
            (point_taken[p], found_taken[f]) = (true, true);
            points[p] = found[f];
            moved = moved.max(d);
        }
    }
    let before = points.len();
    points.extend(found.iter().zip(&found_taken).filter(|(_, t)| !**t).map(|(&g, _)| g));
    let fresh = points.len() > before;
    points.sort_by(f64::total_cmp);
    (moved, fresh)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points move to their nearest partners, nearest pairs first; one not found again
    /// stays, one found without a partner is added.
    #[test]
    fn points_move_to_their_nearest_partners() {
        let mut points = vec![0.1, 0.2, 0.5];
        // 0.1 is not found again; 0.2 has two candidates (the nearer wins); 0.3 is new.
        let (moved, fresh) = relocate(&mut points, &[0.2004, 0.2001, 0.3, 0.5], 1e-3);
        assert_eq!(points, vec![0.1, 0.2001, 0.2004, 0.3, 0.5]);
        assert!((moved - 1e-4).abs() < 1e-15, "{moved}");
        assert!(fresh);
        let (moved, fresh) = relocate(&mut points, &[0.1, 0.2001, 0.2004, 0.3, 0.5], 1e-3);
        assert_eq!((moved, fresh), (0.0, false));
    }

    /// A reversal counts only where the rod bends by more than rounding.
    #[test]
    fn a_reversal_needs_a_bend() {
        let u = |x: f64| Vector3::new(x, 0.0, 7.0);
        assert_eq!(reversed(&[u(1.0), u(-1.0), u(-2.0)], 1.0), vec![true, false]);
        // A straight rod whose bending is rounding: no reversal (the twist does not count).
        assert_eq!(reversed(&[u(1e-12), u(-1e-12)], 1.0), vec![false]);
    }
}
