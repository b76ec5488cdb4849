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
use crate::collocation::friction::turning::{NEAR, SETTLED, inflections, relocate};

/// Most levels: level l cuts every link into 2^(l - 1) parts besides the nodes at the
/// inflections; 4 levels are 8 parts per link, a 4096 times smaller error at order 4.
const LEVELS: u32 = 4;

/// Most solves of one level while its inflections move.
const RELOCATE: usize = 4;

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
            // Each point moves to where the new answer puts it; a point found there without a
            // partner (a kink the last placing did not have, or one that moved farther than
            // `NEAR`) is placed too, and the level is not settled.
            let found = inflections(robot, &next.0);
            let (moved, fresh) = relocate(&mut points, &found, NEAR * robot.length());
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
