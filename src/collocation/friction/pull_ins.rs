//! Tendons with friction and displacement control (docs/friction.md section 3b): Newton on
//! the held tendons' base-entry tensions around solves with friction at given tensions, each
//! after the first started from the last one's solution ([`solve_near`]).

use super::{Route, refine_with_friction, solve_assessed};
use crate::Robot;
use crate::collocation::{Cache, Options, pipeline};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate;
use crate::model::equations::Model;
use crate::report::{Method, SolveReport};
use crate::solution::Solution;
use std::time::Instant;

/// Solves a robot with friction (validated, with `options` validated) from `near`, the
/// solution with friction of the same robot at nearby base-entry tensions (the last step
/// of [`solve_pull_ins`]' Newton on the tensions): Newton with friction starts from its
/// shape, mesh and log tensions instead of a new frictionless solve. The branch is the one
/// `near` is on (the frictionless start of the loop's first solve chose it); the path and
/// notes of its report carry over, the counts are this solve's.
///
/// # Errors
/// As [`super::solve`].
fn solve_near(robot: &Robot, options: &Options, near: &Solution) -> Result<Solution> {
    let start = Instant::now();
    let s: Vec<f64> = near.nodes.iter().map(|n| n.s).collect();
    let mut z = Vec::new();
    for i in crate::model::friction::slipping(robot) {
        let base = near.tension_at(i, 0.0).filter(|t| *t > 0.0);
        z.push(
            s.iter()
                .map(|&x| match (base, near.tension_at(i, x)) {
                    (Some(b), Some(t)) if t > 0.0 => (t / b).ln(),
                    _ => 0.0,
                })
                .collect(),
        );
    }
    let mut report = SolveReport::new(Method::Collocation);
    report.path = near.report.path.clone();
    report.notes = near.report.notes.clone();
    let mesh = Mesh::from_points(robot, &s)?;
    let x = interpolate(&Model::new(robot), near, &mesh);
    refine_with_friction(
        robot,
        options,
        (mesh, x),
        Some((s, z)),
        (report, false),
        start,
        Route::Frictionless,
    )
}

/// Solves a robot with friction and displacement-controlled tendons (validated, with
/// `options` validated): the frictionless robot at its pull-ins first (the tensions to
/// start from), then Newton on the held tendons' base-entry tensions around solves with
/// friction at given tensions ([`crate::model::pull_in::hold`], docs/friction.md
/// section 3b).
///
/// # Errors
/// As [`super::solve`].
pub(in crate::collocation) fn solve_pull_ins(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
) -> Result<Solution> {
    let start = Instant::now();
    let mut smooth = robot.clone();
    for t in &mut smooth.tendons {
        t.friction = None;
    }
    let first = pipeline::solve_impl(&smooth, options, warm, cache)?;
    // The loop's first solve starts from the frictionless one (which chose the branch), the
    // others from the last solve with friction, at tensions a Newton step or a difference
    // step away.
    let mut near = false;
    let mut solution = crate::model::pull_in::hold(
        robot,
        &first.tensions(),
        Some(&first),
        options.residual_tolerance,
        |r, warm| match (std::mem::replace(&mut near, true), warm) {
            (true, Some(last)) => solve_near(r, options, last),
            _ => solve_assessed(r, options, warm, cache, false),
        },
        slope,
    )?;
    solution.report.timings.total = start.elapsed();
    // The verdict with the pull-ins held (the loop's solves hold tensions and have none).
    crate::collocation::dynamics::pulled::assess_solution(robot, &mut solution);
    Ok(solution)
}

/// dQ/dtau of the `held` tendons at `solution` of `robot` (tension-controlled), row major:
/// the Schur complement S of the derivatives at held pull-ins (docs/friction.md section 3b,
/// "Derivatives at a held pull-in"), from one linearization of the bordered system and one
/// bordered solve per held tendon, in place of one full solve per tendon for a forward
/// difference. None, and the loop differences, where it does not apply: a held tendon at
/// 0 N (left to the differences, though the sensitivities now have its first pull) or a linearization that
/// fails (a singular Jacobian, a solution that is not converged to its limit).
fn slope(robot: &Robot, solution: &Solution, held: &[usize]) -> Option<Vec<f64>> {
    if held.iter().any(|&j| solution.tendons[j].tension <= 0.0) {
        return None;
    }
    let directions = crate::collocation::sensitivity::TensionDirections::new(robot, solution, held.to_vec()).ok()?;
    let s = directions.displacement_by_tension();
    let k = held.len();
    Some((0..k * k).map(|i| s[(i / k, i % k)]).collect())
}
