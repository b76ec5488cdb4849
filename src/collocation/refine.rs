//! Error control: a starting mesh that resolves the initial guess, and the mesh sequence of
//! every solve ([`to_tolerance`], for tension and pull-in inputs alike): re-meshing until the
//! deferred-correction estimate ([`super::estimate`]) meets the tip tolerance, refining at
//! the order of the solution estimated (4, or 6 for the order-6 answer of tight tolerances,
//! [`super::deferred`]).

use super::estimate::Correction;
use super::homotopy::{Homotopy, Point, tangent};
use super::newton::{self, Settings, Workspace};
use super::options::Options;
use super::system::System;
use super::{Cache, Level, interpolate, segment_ends};
use crate::Error;
use crate::error::Result;
use crate::mesh::guess::interpolate_nodes;
use crate::mesh::{Mesh, nodes, spare};
use crate::model::equations::Model;
use crate::model::robot::Robot;
use crate::report::Termination;
use crate::report::{ErrorEstimate, SolveReport};
use crate::solution::State;

/// Largest rotation of the backbone over one interval of a starting mesh, pi/8 rad: the
/// Hermite-Simpson error of an arc grows like (h |u|)^4, and at this angle a coil's first
/// solve is within a few times of the default tolerance, so one re-mesh at most finishes it,
/// while Newton and load continuation see a shape the mesh resolves.
const START_ANGLE: f64 = std::f64::consts::PI / 8.0;

/// Re-meshing aims at this fraction of the tolerance, so that the new mesh meets it despite
/// the estimate's own O(h^6) error and a non-asymptotic coarse mesh.
const TARGET_FRACTION: f64 = 0.8;

/// Each re-mesh has at least this factor more intervals, so refinement ends at the cap in
/// a bounded number of levels even where the error does not yet fall like h^4.
const MIN_GROWTH: f64 = 1.25;

/// Intervals a uniform starting mesh needs so that the initial guess `x0` turns by at most
/// [`START_ANGLE`] over any interval, and at least `floor`.
pub(super) fn start_intervals(robot: &Robot, x0: &[State], floor: usize) -> usize {
    let bending = x0.iter().map(|s| s.u.norm()).fold(0.0, f64::max);
    let needed = (robot.length() * bending / START_ANGLE).ceil();
    if needed.is_finite() {
        floor.max(needed as usize)
    } else {
        floor
    }
}

/// Whether `estimate` meets the relative tolerance `tol` on a rod of length `length` (m).
pub(super) fn meets(estimate: &ErrorEstimate, tol: f64, length: f64) -> bool {
    estimate.tip_position <= tol * length && estimate.tip_rotation <= tol
}

/// The error-controlled mesh sequence of one solve, for every input: `solve` on `mesh` from
/// `x`, then, with a tolerance in `options`, re-meshing until the estimated tip error meets
/// it (relative to L) by [`next_mesh`], each level solved by `solve` again from the last
/// level's solution interpolated onto the finer mesh. A level without an estimate (a singular
/// Jacobian at the solution) ends the sequence: the report then says no estimate.
///
/// `solve` is the input's solve on one mesh (Newton and the equilibrium choice for given
/// tensions, Newton bordered by the unknown tensions for pull-ins), with its error estimate;
/// it stores its workspace in `cache`. It gets `model`, the model the sequence builds each
/// level's guess for the next from, and may set in it what the next mesh starts from (the
/// solved tensions of displacement-controlled tendons). Each mesh counts in
/// `report.meshes`.
///
/// # Errors
/// [`Error::IntervalCap`] when the next level would exceed `options.max_intervals`, or the
/// errors of `solve`.
pub(super) fn to_tolerance<'r>(
    model: &mut Model<'r>,
    mut mesh: Mesh,
    mut x: Vec<State>,
    options: &Options,
    report: &mut SolveReport,
    cache: &mut Cache,
    mut solve: impl FnMut(&mut Model<'r>, Mesh, Vec<State>, &mut SolveReport, &mut Cache) -> Result<Level>,
) -> Result<Level> {
    loop {
        report.meshes += 1;
        let level = solve(model, mesh, x, report, cache)?;
        let (Some(tol), Some(correction)) = (options.tolerance, &level.correction) else {
            return Ok(level);
        };
        let Some(fine) = next_mesh(model.robot, &level.mesh, correction, tol, options)? else {
            return Ok(level);
        };
        // The guess needs the nodes' dense interpolant only, not tendon paths and lengths.
        let ends = segment_ends(&level.mesh);
        let guess = nodes::nodes(model, &level.x, &ends, Some(&correction.node_rates))?;
        x = interpolate_nodes(model, &guess, &fine);
        mesh = fine;
        // The coarser level's buffers go back to the thread's kept ones.
        spare::give(guess);
        spare::give(ends);
        level.release();
    }
}

/// The next mesh of refinement after a converged solve on `mesh` with the error estimate
/// `correction`, or `None` when the estimate meets `tol` (relative to L): enough intervals for the error to fall below
/// [`TARGET_FRACTION`] of the tolerance if it falls like h^q (q the estimated solution's
/// order, 4 or 6), distributed so that every interval's local error is about equal.
///
/// # Errors
/// [`Error::IntervalCap`] when no mesh within `options.max_intervals` finer than `mesh` is
/// left to try (the cap is tried before refusing).
pub(super) fn next_mesh(
    robot: &Robot,
    mesh: &Mesh,
    correction: &Correction,
    tol: f64,
    options: &Options,
) -> Result<Option<Mesh>> {
    let Correction { estimate, local, .. } = correction;
    let exponent = 1.0 / f64::from(correction.estimate.order + 1);
    let length = robot.length();
    if meets(estimate, tol, length) {
        return Ok(None);
    }
    let intervals = mesh.intervals();
    let ratio = (estimate.tip_position / (tol * length)).max(estimate.tip_rotation / tol);
    // The error of the estimated solution falls like N^-order (4, or 6 for the order-6
    // answer).
    let order = f64::from(correction.estimate.order);
    let wanted = (intervals as f64 * (ratio / TARGET_FRACTION).powf(1.0 / order)).max(intervals as f64 * MIN_GROWTH);
    let cap = options.max_intervals;
    let refused = || Error::IntervalCap {
        cap,
        estimate: estimate.tip_position,
        tolerance: tol * length,
        rotation_estimate: estimate.tip_rotation,
        rotation_tolerance: tol,
    };
    // The h^4 prediction is not a bound: a mesh of the cap can meet the tolerance where the
    // prediction wants more, so the cap is tried before refusing.
    let mut target = wanted.ceil().min(cap as f64) as usize;
    if target <= intervals {
        return Err(refused());
    }
    // Rounding each segment's share can overshoot the target by a few intervals.
    for _ in 0..4 {
        let fine = equidistributed(robot, mesh, local, exponent, target)?;
        if fine.intervals() <= cap {
            return if fine.intervals() > intervals {
                Ok(Some(fine))
            } else {
                Err(refused())
            };
        }
        target -= (fine.intervals() - cap).min(target - 1);
    }
    Err(refused())
}

/// A mesh of about `target` intervals whose intervals share the local error equally: with
/// local errors e_k ~ C_k h_k^(q + 1) on the current mesh (q the order, `exponent` =
/// 1 / (q + 1): h^5 at order 4, h^7 at order 6), the density of intervals is proportional
/// to e_k^exponent / h_k, so each current interval receives a share of the new intervals
/// proportional to e_k^exponent, spread evenly over it. Segments between breakpoints keep
/// their end points and get at least one interval.
fn equidistributed(robot: &Robot, mesh: &Mesh, local: &[f64], exponent: f64, target: usize) -> Result<Mesh> {
    let mut weights = spare::take(local.len());
    weights.extend(local.iter().map(|e| e.powf(exponent)));
    // No interval starves: at least 1e-3 of the largest weight (an interval whose error is
    // 1e-15 of the worst one still gets a share).
    let floor = 1e-3 * weights.iter().copied().fold(0.0, f64::max);
    let weight = |k: usize| if mesh.is_jump(k) { 0.0 } else { weights[k].max(floor) };
    let total: f64 = (0..local.len()).map(weight).sum();
    let mut points = spare::take(target + 1);
    let mut k = 0;
    while k < local.len() {
        if mesh.is_jump(k) {
            k += 1;
            continue;
        }
        // One segment: links k..end, all intervals.
        let end = (k..local.len()).find(|&j| mesh.is_jump(j)).unwrap_or(local.len());
        let segment: f64 = (k..end).map(weight).sum();
        let count = if total > 0.0 {
            ((target as f64 * segment / total).round() as usize).max(1)
        } else {
            end - k
        };
        // Points at equal shares of the cumulative weight, linear within each interval.
        let step = segment / count as f64;
        let (mut j, mut before) = (k, 0.0);
        for i in 1..count {
            let share = step * i as f64;
            while j + 1 < end && before + weight(j) < share {
                before += weight(j);
                j += 1;
            }
            let (a, b) = (mesh.nodes[j].s, mesh.nodes[j + 1].s);
            let t = if weight(j) > 0.0 {
                ((share - before) / weight(j)).clamp(0.0, 1.0)
            } else {
                0.5
            };
            points.push(a + t * (b - a));
        }
        k = end;
    }
    let fine = Mesh::from_points(robot, &points);
    spare::give(points);
    spare::give(weights);
    fine
}

/// The hint of a load path that could not move to a finer mesh at `lambda`.
pub(super) fn remesh_hint(lambda: f64) -> String {
    format!(
        "the load path could not move to a finer mesh at {} of the load",
        share(lambda)
    )
}

/// A share `lambda` of a path's way as a percentage with one decimal, or with as many more
/// (up to 6) as it takes not to round a point short of the end up to `100.0 %` (the solve
/// at 99.95 % of the geometric limit stalls at 99.96 % of the way).
pub(super) fn share(lambda: f64) -> String {
    let percent = 100.0 * lambda;
    let mut decimals = 1;
    while decimals < 6 && percent < 100.0 && format!("{percent:.decimals$}") == format!("{:.decimals$}", 100.0) {
        decimals += 1;
    }
    format!("{percent:.decimals$} %")
}

/// The hint of a path that stalled: the furthest share of the way it reached, `furthest`
/// (the path starts at 0 and ends at 1; a corrector step can carry it past 1 without a
/// landing there), and, if it stopped behind that on the way, the point `lambda` it turned
/// back to. A Newton homotopy's path may turn back past its start (lambda < 0, once printed
/// as "-3199.5 % of the way"); such a point is not named.
pub(super) fn stalled_hint(furthest: f64, lambda: f64) -> String {
    let reached = share(furthest);
    let back = if (0.0..furthest).contains(&lambda) && share(lambda) != reached {
        format!(", turned back to {}", share(lambda))
    } else {
        String::new()
    };
    if furthest > 1.0 {
        // Past the end, a share over 100 % is not progress: say that the end was passed.
        return format!(
            "the path went past the end of the way (to {reached}){back} without landing on it: Newton at \
             the end did not converge cleanly from the path's points"
        );
    }
    format!(
        "the path stalled after reaching {reached} of the way{back}: no equilibrium nearby is continuous in the parameter there"
    )
}

/// Moves the path to a uniform mesh of `intervals` intervals at `point`: interpolates the
/// shape ([`interpolate`]), converges Newton there at the same lambda and takes the tangent.
#[allow(clippy::too_many_arguments)]
pub(super) fn remesh(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    intervals: usize,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(Point, Vec<f64>)> {
    let model = system.model.clone();
    let ends: Vec<f64> = system.mesh.nodes.iter().map(|n| n.segment_end).collect();
    let shape = nodes::solution(&model, &point.x, &ends, None, report.clone()).ok()?;
    let mesh = Mesh::uniform(model.robot, intervals).ok()?;
    let mut x = interpolate(&model, &shape, &mesh);
    *system = System::new(model, mesh);
    homotopy.set(system, point.lambda);
    *ws = Workspace::new(system, options.linear_solver).ok()?;
    report.meshes += 1;
    let (term, _) = newton::run(system, ws, &mut x, settings, report);
    if term != Termination::Converged || !ws.linearize(system, &x, report) {
        return None;
    }
    tangent(system, homotopy, ws, x, point.lambda, Some((&[], point.tl)), report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 25: a stalled path's percentages lie in [0, 100] and never round a point short
    /// of the end up to 100.0 %, nor name a turning point equal to the furthest.
    #[test]
    fn a_stalled_path_says_shares_of_its_way() {
        assert_eq!(share(0.5), "50.0 %");
        assert_eq!(share(0.9996), "99.96 %");
        assert_eq!(share(1.0), "100.0 %");
        let text = stalled_hint(0.9996, -31.995);
        assert!(
            text.starts_with("the path stalled after reaching 99.96 % of the way:"),
            "{text}"
        );
        assert_eq!(
            stalled_hint(0.8, 0.5),
            "the path stalled after reaching 80.0 % of the way, turned back to 50.0 %: no equilibrium nearby \
             is continuous in the parameter there"
        );
        assert!(!stalled_hint(0.506, 0.5059).contains("turned back"));
        // The payload robot from rest at 1.78 mN went to 101.9 % and was told "stalled after
        // reaching 101.9 % of the way".
        let past = stalled_hint(1.019, 0.95);
        assert!(
            past.starts_with("the path went past the end of the way (to 101.9 %), turned back to 95.0 % without"),
            "{past}"
        );
    }
}
