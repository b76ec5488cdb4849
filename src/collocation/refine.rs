//! Adaptive mesh refinement to a tip tolerance, guided by per-interval defect estimates.

use super::options::Options;
use super::residual;
use super::system::System;
use super::{Cache, interpolate, segment_ends, solve_on_mesh};
use crate::Error;
use crate::error::Result;
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::SolveReport;
use crate::solution::State;

/// Refines `mesh` (on which `x` is converged) until the estimated tip position error is at
/// most `tol` (m): each level bisects the intervals whose defect estimate is within three
/// orders of magnitude of the worst and re-solves warm-started from the coarser solution.
/// Returns the final mesh and states; the estimate is in `report.tip_error_estimate`.
///
/// # Errors
/// [`Error::IntervalCap`] when the next level would exceed `options.max_intervals`, or the
/// errors of a failed solve on a finer mesh.
pub(super) fn to_tolerance(
    model: &Model,
    mut mesh: Mesh,
    mut x: Vec<State>,
    tol: f64,
    options: &Options,
    report: &mut SolveReport,
    cache: &mut Cache,
) -> Result<(Mesh, Vec<State>)> {
    loop {
        let sys = System::new(*model, mesh.clone());
        let errors = interval_errors(&sys, &x)?;
        let worst = errors.iter().copied().fold(0.0, f64::max);
        // Split every interval within three orders of magnitude of the worst one: the
        // rest cannot matter at the next level.
        let split: Vec<bool> = errors.iter().map(|&e| e > 1e-3 * worst).collect();
        let all = (0..mesh.nodes.len() - 1).all(|k| mesh.is_jump(k) || split[k]);
        let fine = mesh.bisected(&split);
        if fine.intervals() > options.max_intervals {
            return Err(Error::IntervalCap {
                cap: options.max_intervals,
                estimate: report.tip_error_estimate,
                tolerance: tol,
            });
        }
        let guess = nodes::solution(model, &x, &segment_ends(&mesh), report.clone())?;
        let xf = solve_on_mesh(
            model,
            fine.clone(),
            interpolate(&guess, &fine),
            false,
            options,
            report,
            cache,
        )?;
        let change = (xf[xf.len() - 1].p - x[x.len() - 1].p).norm();
        // Order 4: halving every interval cuts the error 16-fold, so the finer error is
        // about change / 15; with partial splitting use the change itself (conservative).
        let estimate = if all { change / 15.0 } else { change };
        report.tip_error_estimate = Some(estimate);
        mesh = fine;
        x = xf;
        if estimate <= tol {
            break;
        }
    }
    Ok((mesh, x))
}

/// Estimated discretization error of each link (0 for jumps): the interval length times the
/// largest scaled defect of the cubic interpolant at s_k + h/4 and s_k + 3h/4 (the defect
/// vanishes at the collocation points 0, 1/2, 1), in the dimensionless units of the residual.
///
/// # Errors
/// A model breakdown at the solution (cannot happen for a converged one).
pub fn interval_errors(system: &System, x: &[State]) -> Result<Vec<f64>> {
    let model = &system.model;
    (0..x.len() - 1)
        .map(|k| {
            let Some(sites) = system.interval_sites(k) else {
                return Ok(0.0);
            };
            let h = sites.end.s - sites.start.s;
            let seg = system.mesh.nodes[k].segment_end;
            let mut worst: f64 = 0.0;
            for t in [0.25, 0.75] {
                let site = model.site(sites.start.s + t * h);
                let d = residual::defect(model, sites, &site, seg, &x[k], &x[k + 1], t)?;
                worst = worst.max(d.amax());
            }
            Ok(worst * h / model.robot.length())
        })
        .collect()
}
