//! Error control of a history step with a stuck stretch (docs/friction.md section 8, "Error
//! control of stuck steps"): the step is solved again on its mesh with every link split in
//! two, four, ... parts, from the same carried material, until two successive answers agree
//! to the tolerance; the finer one is returned, with their difference as its error estimate.
//! The history's own mesh is a subset of every split mesh, so the material the step leaves
//! is handed back to it at its nodes exactly.

use super::{Carried, Grip, Options, Profile, Result, Robot, StepAnswer, solve_on};
use crate::collocation::refine;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate;
use crate::model::equations::Model;
use crate::report::ErrorEstimate;
use crate::solution::Solution;

/// Most splits of a stuck step's links: 2^6 = 64 parts per link. A stuck stretch's error
/// falls about as h^3 from 32 to 128 intervals and as h beyond, while its stick/slip
/// boundary stays in the link after a node of the history's mesh (docs/friction.md section
/// 8), so 64 parts take a step from 1e-4 L to about 1e-7 L (64 x 16, about 1 000 times); a step that still misses its
/// tolerance (or would need more than `max_intervals`) reports so.
const LEVELS: u32 = 6;

/// Solves the step again on split meshes (module docs) after `answer`, its solution on
/// the history's mesh from the material `before`, within `options.max_intervals` (one split
/// at least); leaves in `carried` (which holds that
/// solve's end state and factors) the finest answer's material at the history's nodes.
///
/// # Errors
/// As [`super::step`], on a split mesh.
pub(super) fn refine(
    robot: &Robot,
    options: &Options,
    carried: &mut Carried,
    before: &Carried,
    answer: StepAnswer,
) -> Result<StepAnswer> {
    let length = robot.length();
    let mut best = answer;
    let mut finest = None;
    let intervals = before.mesh.intervals();
    for level in 1..=LEVELS {
        if intervals << level > options.max_intervals.max(2 * intervals) {
            break;
        }
        let mut fine = split(robot, before, 1 << level, &best.0)?;
        let (next, _) = solve_on(robot, options, &mut fine)?;
        let estimate = difference(&best.0, &next.0);
        best = next;
        let report = &mut best.0.report;
        report.error_estimate = Some(estimate);
        report.tolerance = options.tolerance;
        report.tolerance_met = options.tolerance.map(|tol| refine::meets(&estimate, tol, length));
        finest = Some(fine);
        if report.tolerance_met != Some(false) {
            break;
        }
    }
    if let Some(fine) = finest {
        hand_back(carried, &fine);
    }
    Ok(best)
}

/// The error estimate of the finer of two answers of a step: their difference. With an
/// order p >= 1 the finer one's error is the difference / (2^p - 1), so this bounds it
/// (at the order 1 observed on fine split levels, about equals it).
fn difference(coarse: &Solution, fine: &Solution) -> ErrorEstimate {
    let (a, b) = (coarse.tip(), fine.tip());
    let cos = (((a.R.transpose() * b.R).trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let backbone_max = fine
        .nodes
        .iter()
        .map(|n| (coarse.at(n.s).p - n.p).norm())
        .fold(0.0, f64::max);
    ErrorEstimate {
        tip_position: (a.p - b.p).norm(),
        tip_rotation: cos.acos(),
        backbone_max,
        order: 2,
    }
}

/// The start of a step on `before`'s mesh with every link cut into `parts` equal links:
/// the carried material (lambda) interpolated at the new nodes ([`cubic`]), each new link
/// with its parent's contact and multiplier, and the states and log tensions of `guess`.
///
/// # Errors
/// An invalid mesh (none: the points lie on the rod).
fn split(robot: &Robot, before: &Carried, parts: usize, guess: &Solution) -> Result<Carried> {
    let nodes = &before.mesh.nodes;
    let mut points = Vec::with_capacity(nodes.len() * parts);
    for pair in nodes.windows(2) {
        let (a, b) = (pair[0].s, pair[1].s);
        points.push(a);
        if b > a {
            points.extend((1..parts).map(|q| a + (b - a) * q as f64 / parts as f64));
        }
    }
    points.push(robot.length());
    let mesh = Mesh::from_points(robot, &points)?;
    let model = Model::new(robot);
    let x = interpolate(&model, guess, &mesh);
    let profile = Profile::new(&model, &mesh);
    let coarse: Vec<f64> = nodes.iter().map(|n| n.s).collect();
    let mut z = profile.z.clone();
    let mut grips = Vec::with_capacity(before.grips.len());
    for (j, old) in before.grips.iter().enumerate() {
        let (i, span, base) = (profile.slipping[j], profile.spans[j], profile.base[j]);
        for (n, value) in z[j].iter_mut().enumerate() {
            let tension = guess.tension_at(i, mesh.nodes[n.min(span)].s).unwrap_or(0.0);
            *value = if base > 0.0 && tension > 0.0 {
                (tension / base).ln()
            } else {
                0.0
            };
        }
        let links = old.contacts.len();
        let parent = |l: usize| (l / parts).min(links.saturating_sub(1));
        let old_span = links;
        grips.push(Grip {
            contacts: (0..span).map(|l| old.contacts[parent(l)]).collect(),
            multipliers: (0..span).map(|l| old.multipliers[parent(l)]).collect(),
            capacities: (0..span).map(|l| old.capacities[parent(l)] / parts as f64).collect(),
            reference: mesh
                .nodes
                .iter()
                .map(|node| cubic(&coarse[..=old_span], &old.reference[..=old_span], node.s))
                .collect(),
        });
    }
    Ok(Carried {
        mesh,
        x,
        z,
        grips,
        solved: false,
        report: before.report.clone(),
        factors: None,
        settled: None,
    })
}

/// The cubic through the four nodes of `s` (increasing, within a tendon's span) nearest
/// to `at`, evaluated there: the carried material between the nodes, to O(h^4) where it
/// is smooth. At a node it is that node's value exactly.
fn cubic(s: &[f64], values: &[f64], at: f64) -> f64 {
    let n = s.len();
    if let Some(k) = s.iter().position(|&x| x == at) {
        return values[k];
    }
    if n < 4 {
        let k = s.iter().rposition(|&x| x <= at).unwrap_or(0).min(n.saturating_sub(2));
        if n < 2 {
            return values[0];
        }
        let t = (at - s[k]) / (s[k + 1] - s[k]);
        return values[k] + t * (values[k + 1] - values[k]);
    }
    let k = s.iter().rposition(|&x| x <= at).unwrap_or(0);
    let lo = k.saturating_sub(1).min(n - 4);
    let stencil = lo..lo + 4;
    stencil
        .clone()
        .map(|a| {
            let weight: f64 = stencil
                .clone()
                .filter(|&b| b != a)
                .map(|b| (at - s[b]) / (s[a] - s[b]))
                .product();
            weight * values[a]
        })
        .sum()
}

/// Hands the material `fine` holds after its step back to the history's mesh in
/// `carried`: the node states, log tensions and carried material at the history's nodes,
/// which are nodes of the split mesh (matched by arc length and segment), so exactly.
fn hand_back(carried: &mut Carried, fine: &Carried) {
    let index: Vec<usize> = carried
        .mesh
        .nodes
        .iter()
        .map(|node| {
            fine.mesh
                .nodes
                .iter()
                .position(|f| f.s == node.s && f.segment_end == node.segment_end)
                .expect("the history's nodes are nodes of every split mesh")
        })
        .collect();
    carried.settled.clone_from(&fine.settled);
    carried.x = index.iter().map(|&n| fine.x[n]).collect();
    for (j, z) in carried.z.iter_mut().enumerate() {
        *z = index.iter().map(|&n| fine.z[j][n]).collect();
    }
    for (grip, f) in carried.grips.iter_mut().zip(&fine.grips) {
        grip.reference = index.iter().map(|&n| f.reference[n]).collect();
    }
}
