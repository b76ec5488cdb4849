//! Error control of a history step that slides all along and misses its tolerance or has
//! an inflection (docs/friction.md section 8, "Sliding steps at an inflection"): where the backbone's
//! bending changes sign inside a link, a tendon's turning rate kappa = |t'| has a kink
//! (it passes through 0), so its sliding tension, tau' = -+ mu tau kappa, has a jump in its
//! second derivative inside the link: the link's collocation loses its order and the
//! deferred correction, which assumes a smooth answer on each link, misjudges it. The
//! history's mesh, chosen once for the most loaded step, has no node there. The step is
//! solved again on the history's mesh with a node at each such point (located on the last
//! answer), which restores the order and the estimate; while that still misses, on its
//! links cut in 2, 4, ... parts as well. The history's nodes are nodes of every such mesh,
//! so the step's material is handed back to them exactly, as a stuck step's is
//! ([`split`](super::split)).

use super::split::{hand_back, split};
use super::{Carried, Material, Options, Result, Robot, StepAnswer, solve_on};
use crate::solution::Solution;

/// Most levels: level l cuts every link into 2^(l - 1) parts besides the nodes at the
/// inflections; 4 levels are 8 parts per link, a 4096 times smaller error at order 4.
const LEVELS: u32 = 4;

/// Most solves of one level while its inflections move.
const RELOCATE: usize = 4;

/// A point found on a level's answer within this (relative to L) of one it was solved with
/// is that point, moved.
const NEAR: f64 = 1e-4;

/// The half-width of the central difference of a path's unit tangent (relative to L):
/// 1e-7 L leaves an error of its square (the tangent is smooth: only |t'| has a kink) and of
/// rounding, eps / 1e-7, about 1e-9 of the turning, below what a point's place matters by.
const STEP: f64 = 1e-7;

/// An inflection has settled when it moves by less than this (relative to L) between two
/// solves of a level.
const SETTLED: f64 = 1e-8;

/// Solves the sliding step again (module docs) after `answer`, its solution on the
/// history's mesh from the material `before`, which misses its tolerance, within
/// `options.max_intervals`, until a level meets the tolerance; leaves in `carried` the last
/// level's material at the history's nodes, its order-6 material where the level has it.
/// Returns `answer` (and `carried` as it was after it) when no level was solved: the
/// interval cap, or a level that sticks (a refined shape that changes the step's pattern).
/// With a tolerance that answer then says it misses it, whatever its estimate: its estimate
/// does not see the kink that brought it here. Its report counts every solve made.
///
/// # Errors
/// As [`super::step`], on a refined mesh.
pub(super) fn refine(
    robot: &Robot,
    options: &Options,
    carried: &mut Carried,
    before: &Carried,
    answer: StepAnswer,
) -> Result<StepAnswer> {
    let intervals = before.mesh.intervals();
    let links = before.mesh.nodes.len() - 1;
    // The work of every solve of the step, which its answer reports.
    let mut spent = answer.0.report.clone();
    let mut best = answer;
    let mut finest: Option<Carried> = None;
    for level in 1..=LEVELS {
        let mut points = inflections(robot, &best.0);
        let per_link = 1usize << (level - 1);
        if per_link == 1 && points.is_empty() {
            continue;
        }
        // Each history link's parts: the level's, or one more than the points inside it.
        let parts_of = |points: &[f64]| -> Vec<usize> {
            before
                .mesh
                .nodes
                .windows(2)
                .map(|pair| {
                    let inside = points.iter().filter(|&&e| e > pair[0].s && e < pair[1].s).count();
                    per_link.max(inside + 1)
                })
                .collect()
        };
        let cap = options.max_intervals.max(intervals + links);
        if parts_of(&points).iter().sum::<usize>() > cap {
            break;
        }
        // The points are located on the last answer, to its error: solved again from the
        // new answer while they move.
        let mut located = None;
        for _ in 0..RELOCATE {
            // Recomputed on each placing: a point may have moved into another link.
            let parts = parts_of(&points);
            if parts.iter().sum::<usize>() > cap {
                break;
            }
            let mut fine = split(robot, before, &parts, &best.0, &points)?;
            // Slots for the level's order-6 material, which `solve_on` fills.
            fine.corrected = fine
                .grips
                .iter()
                .map(|_| Material {
                    values: vec![f64::NAN; fine.mesh.nodes.len()],
                    kinks: Vec::new(),
                })
                .collect();
            let (next, stuck) = solve_on(robot, options, &mut fine, None)?;
            spent.add_mesh_work(&next.0.report);
            if stuck || next.0.report.error_estimate.is_none() {
                break;
            }
            // Each point moves to the nearest point found on the new answer, nearest pairs
            // first; one that sits on a node may not be seen again (its turning's sign there
            // is rounding's) and stays where it is.
            let found = inflections(robot, &next.0);
            let near = NEAR * robot.length();
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
            // A point found with no partner (a kink the last placing did not have, or one
            // that moved farther than `NEAR`) is placed too, and the level is not settled.
            let unmatched: Vec<f64> = found
                .iter()
                .zip(&found_taken)
                .filter(|(_, t)| !**t)
                .map(|(&g, _)| g)
                .collect();
            let fresh = !unmatched.is_empty();
            points.extend(unmatched);
            points.sort_by(f64::total_cmp);
            let settled = moved <= SETTLED * robot.length() && !fresh;
            located = Some((next, fine));
            if settled {
                break;
            }
        }
        let Some((next, fine)) = located else {
            break;
        };
        // Without a tolerance the node is the whole of it: the levels have nothing to meet.
        let met = next.0.report.tolerance_met == Some(true) || options.tolerance.is_none();
        best = next;
        finest = Some(fine);
        if met {
            break;
        }
    }
    if finest.is_none() && options.tolerance.is_some() {
        best.0.report.tolerance_met = Some(false);
    }
    if let Some(fine) = finest {
        let index = hand_back(carried, &fine, before);
        // The material at its best is the level's deferred-corrected one where it has it.
        for (corrected, order6) in carried.corrected.iter_mut().zip(&fine.corrected) {
            for (value, &n) in corrected.values.iter_mut().zip(&index) {
                if order6.values[n].is_finite() {
                    *value = order6.values[n];
                }
            }
        }
    }
    best.0.report.set_work(&spent);
    Ok(best)
}

/// Where the path of a tendon with friction of `robot` stops turning inside a link of
/// `solution` (within a segment and the tendon's span, where the tendon is loaded): where
/// its turning t' (t the path's unit tangent, p_i' = R (v + u x r_i + r_i')) reverses
/// between two nodes, the point where its component along t' at the first node changes
/// sign, by bisection on the solution's interpolant to the resolution of s (t' by a
/// central difference, [`STEP`]); points of several tendons closer than 1e-9 of their link
/// are one, at their mean. Only links near a reversal of the backbone's bending are
/// looked at. A tendon's turning rate kappa = |t'| passes through 0 there, with a kink, in a
/// planar bend; a reversal without a zero (a path that turns in 3-D) costs only a node.
pub(super) fn inflections(robot: &Robot, solution: &Solution) -> Vec<f64> {
    let length = robot.length();
    let mut found: Vec<(f64, f64)> = Vec::new();
    // Where the segments meet: the nodes listed twice.
    let jumps: Vec<f64> = solution
        .nodes
        .windows(2)
        .filter(|w| w[1].s <= w[0].s)
        .map(|w| w[0].s)
        .collect();
    // The links near a reversal of the backbone's bending (u_x, u_y) between two nodes,
    // within three links of it: a tendon's turning follows the bending, so only there is
    // it worth its interpolated tangents (a history's sliding steps mostly have none). The
    // bending's zero lies about 1e-6 m from the tendons' (section 8, "honest18"), beyond
    // the two nodes a refined step has at the tendons' own, 1e-9 to 4e-8 m apart: one link
    // either side missed them there (error / estimate 1.03).
    let nodes = &solution.nodes;
    let bending = |n: usize| nalgebra::Vector2::new(nodes[n].u.x, nodes[n].u.y);
    // A rod that is straight to within a total turning of 1e-8 rad (a column below or at
    // its buckling load, bent only by rounding) has no kink worth a node.
    let straight = 1e-8 / length;
    let reversed: Vec<bool> = (0..nodes.len().saturating_sub(1))
        .map(|n| bending(n).dot(&bending(n + 1)) <= 0.0 && bending(n).norm().max(bending(n + 1).norm()) > straight)
        .collect();
    let near = |k: usize| reversed[k.saturating_sub(3)..(k + 4).min(reversed.len())].contains(&true);
    for (i, tendon) in robot.tendons.iter().enumerate() {
        if tendon.active_friction().is_none() {
            continue;
        }
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
            found.push((0.5 * (lo + hi), b - a));
        }
    }
    // Points closer than 1e-9 of their link share one node, at their mean; the tendons on
    // opposite sides of a planar bend, a few 1e-8 m apart on the prototype, have one each
    // (one node at their mean leaves about 1 % of such a step's error unseen).
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, usize)> = Vec::new();
    for (at, link) in found {
        match out.last_mut() {
            Some((mean, count)) if at - *mean <= 1e-9 * link => {
                *mean += (at - *mean) / (*count + 1) as f64;
                *count += 1;
            }
            _ => out.push((at, 1)),
        }
    }
    out.into_iter().map(|(at, _)| at).collect()
}
