//! One solve's stages in order: the start (mesh, warm or cold states), Newton and the
//! equilibrium choice on the first mesh, refinement to the tolerance, the error estimate and
//! the stability verdict, and the [`Solution`] built from the node states.

use super::deferred;
use super::equilibrium::{Choose, better_start, choose_equilibrium, held_stability, near_start, stability_of};
use super::estimate;
use super::newton::{self, Settings, Workspace};
use super::options::Options;
use super::refine;
use super::solver::{Cache, Cached};
use super::start::{cold_start, initial_mesh, resolves};
use super::system::System;
use super::unknowns;
use super::workspace;
use crate::error::Result;
use crate::mesh::guess::{self, interpolate};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::{Method, PathTaken, SolveReport, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Robot};
use std::time::Instant;

/// [`solve_impl`] without a cache of its own (what [`super::solve`] and
/// [`super::solve_from`] run): the workspaces come from and go back to this thread's kept
/// ones ([`workspace::spare`]), so that repeated solves skip the setup; nothing else of an
/// earlier solve (its factors, its state) is reused.
///
/// # Errors
/// As [`super::solve`].
pub(crate) fn solve_stateless(robot: &Robot, options: &Options, warm: Option<&Solution>) -> Result<Solution> {
    let mut cache = None;
    let result = solve_impl(robot, options, warm, &mut cache);
    if let Some(c) = cache {
        workspace::keep(c.mesh, c.solver, c.workspace);
    }
    result
}

/// Solves `robot` from `warm` (or cold), reusing what `cache` holds: what [`super::solve`],
/// [`super::solve_from`] and [`super::Solver`] run.
///
/// # Errors
/// As [`super::solve`].
pub(crate) fn solve_impl(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
) -> Result<Solution> {
    robot.validate()?;
    options.validate()?;
    if robot.has_displacement_inputs() && crate::model::friction::any(robot) {
        return super::friction::solve_pull_ins(robot, options, warm, cache);
    }
    if robot.has_displacement_inputs() {
        return super::actuation::solve(robot, options, warm, cache);
    }
    if crate::model::friction::any(robot) {
        return super::friction::solve(robot, options, warm, cache);
    }
    solve_tensions(robot, options, warm, cache, true, false)
}

/// [`solve_stateless`] from `warm`, keeping to the warm start's branch
/// ([`Choose::OnBranch`]): what a sweep's bisection solves ([`super::solve_on_branch`]).
/// Robots with displacement inputs or friction solve as [`super::solve_from`] solves them.
///
/// # Errors
/// As [`super::solve`].
pub(crate) fn solve_on_branch(robot: &Robot, options: &Options, warm: &Solution) -> Result<Solution> {
    if robot.has_displacement_inputs() || crate::model::friction::any(robot) {
        return solve_stateless(robot, options, Some(warm));
    }
    robot.validate()?;
    options.validate()?;
    let mut cache = None;
    let result = solve_tensions(robot, options, Some(warm), &mut cache, true, true);
    if let Some(c) = cache {
        workspace::keep(c.mesh, c.solver, c.workspace);
    }
    result
}

/// The frictionless start of a solve with friction (`robot` validated, without friction):
/// for tension inputs, [`solve_impl`] without the stability verdict of the final mesh,
/// which only the report would carry and the answer with friction replaces (`unknown`).
/// The equilibrium is still chosen on the first mesh with its verdict, so the start is on
/// the branch the frictionless solve would return.
///
/// # Errors
/// As [`super::solve`].
pub(crate) fn solve_start(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
) -> Result<Solution> {
    if robot.has_displacement_inputs() {
        return solve_impl(robot, options, warm, cache);
    }
    solve_tensions(robot, options, warm, cache, false, false)
}

/// [`solve_impl`] for a robot (validated, with `options` validated) whose tendons are all
/// tension-controlled and without friction; with `verdict`, the final mesh's stability
/// verdict in the report; with `on_branch`, keeping to the branch of `warm` when the solve
/// starts from it ([`Choose::OnBranch`]).
///
/// # Errors
/// As [`super::solve`].
fn solve_tensions(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    verdict: bool,
    on_branch: bool,
) -> Result<Solution> {
    let start = Instant::now();
    let mut model = Model::new(robot);
    let mut report = SolveReport::new(Method::Collocation);
    let mut mesh = initial_mesh(robot, options, warm)?;
    if options.tolerance.is_none() {
        resolves(robot, options, &mesh)?;
    }
    let warm_stable = warm.is_some_and(|g| g.report.stability.is_stable());
    let warm = warm.map(|g| interpolate(&model, g, &mesh));
    // The cached factors belong to the guess when it is the cached solver's last solution.
    let mut reuse = match (cache.as_ref(), &warm) {
        (Some(c), Some(w)) => c.mesh == mesh && c.solver == options.linear_solver && c.last.as_ref() == Some(w),
        _ => false,
    };
    let (x0, choose) = match warm {
        Some(w) if reuse => (w, Choose::FromWarm),
        Some(w) => {
            let system = System::new(model.clone(), mesh.clone());
            // A stable warm start near the answer (by the predicted step) is kept; else the
            // start with the smaller residual.
            let near = warm_stable
                .then(|| near_start(&system, &w, options.linear_solver, &mut report))
                .flatten();
            match near {
                Some(workspace) => {
                    *cache = Some(Cached {
                        mesh: mesh.clone(),
                        solver: options.linear_solver,
                        workspace,
                        last: Some(w.clone()),
                    });
                    reuse = true;
                    (w, Choose::FromWarm)
                }
                None => {
                    let cold = guess::initial(&model, &mesh.nodes, options.initial_guess);
                    better_start(&system, w, cold)
                }
            }
        }
        None => (cold_start(robot, options, &mut mesh)?, Choose::FromCold),
    };
    // A solve started from the cold guess (its residual was the smaller) has no branch to
    // keep to.
    let choose = match choose {
        Choose::FromWarm if on_branch => Choose::OnBranch,
        other => other,
    };
    // The first mesh reuses the factors and chooses the equilibrium; finer ones start from it.
    let mut first = Some((reuse, choose));
    let level = refine::to_tolerance(
        &mut model,
        mesh,
        x0,
        options,
        &mut report,
        cache,
        |model, mesh, x0, report, cache| {
            let (reuse, choose) = first.take().unwrap_or((false, Choose::No));
            solve_on_mesh(model, mesh, x0, reuse, choose, options, report, cache)
        },
    )
    .map_err(|e| timed(e, start))?;
    let Level { mesh, x, correction } = level;
    report.intervals = mesh.intervals();
    report.unknowns = unknowns::unknowns(mesh.nodes.len());
    report.nonzeros = unknowns::nonzeros(&mesh);
    record_estimate(&mut report, correction.as_ref(), options, robot.length());
    if let Some(c) = cache.as_mut().filter(|_| verdict) {
        // The verdict belongs to this solve's state: `stability_of` evaluates the Jacobian at
        // it unless the workspace's is already there (and its verdict, when assessed, is
        // taken without building the system again).
        let direct = matches!(report.path, PathTaken::Direct | PathTaken::Fallback);
        let exact = !direct && !report.history.iter().any(|i| i.fresh_jacobian);
        let t = Instant::now();
        report.stability = match held_stability(&model, &c.workspace, exact) {
            Some(verdict) => verdict,
            None => {
                let system = System::new(model.clone(), mesh.clone());
                stability_of(&system, &mut c.workspace, &x, exact, &mut report)
            }
        };
        report.timings.stability += t.elapsed();
    }
    report.timings.total = start.elapsed();
    let rates = correction.as_ref().map(|c| c.node_rates.as_slice());
    nodes::solution(&model, &x, &segment_ends(&mesh), rates, report)
}

/// Records the final mesh's error estimate in `report`, with the tolerance it was tested
/// against and whether it meets it (rod length `length`).
pub(crate) fn record_estimate(
    report: &mut SolveReport,
    correction: Option<&estimate::Correction>,
    options: &Options,
    length: f64,
) {
    report.error_estimate = correction.map(|c| c.estimate);
    report.tolerance = options.tolerance;
    report.tolerance_met = options
        .tolerance
        .zip(report.error_estimate)
        .map(|(tol, e)| refine::meets(&e, tol, length));
}

/// A converged solve on one mesh: its states and their error estimate.
pub(crate) struct Level {
    pub(crate) mesh: Mesh,
    pub(crate) x: Vec<State>,
    /// `None` where the estimate's linear solve failed.
    pub(crate) correction: Option<estimate::Correction>,
}

/// The end of the segment (between breakpoints) of every node, as [`nodes::solution`] wants.
pub(crate) fn segment_ends(mesh: &Mesh) -> Vec<f64> {
    mesh.nodes.iter().map(|n| n.segment_end).collect()
}

/// Newton on one mesh (starting with chord steps on the cached factors when
/// `reuse_factors`); on the first mesh (`choose`), the equilibrium choice of
/// [`choose_equilibrium`]. Then the error estimate with the factors Newton left.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve_on_mesh(
    model: &Model,
    mesh: Mesh,
    x0: Vec<State>,
    reuse_factors: bool,
    choose: Choose,
    options: &Options,
    report: &mut SolveReport,
    cache: &mut Cache,
) -> Result<Level> {
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors,
        stop_when_damped: false,
    };
    let mut system = System::new(model.clone(), mesh);
    // The cached mesh and last states' buffers are kept for the cache this solve leaves.
    let mut kept = None;
    let mut workspace = match cache.take() {
        Some(c) if c.mesh == system.mesh && c.solver == options.linear_solver => {
            kept = Some((c.mesh, c.last));
            c.workspace
        }
        other => {
            if let Some(c) = other {
                workspace::keep(c.mesh, c.solver, c.workspace);
            }
            match workspace::spare(&system.mesh, options.linear_solver) {
                Some(ws) => ws,
                None => Workspace::new(&system, options.linear_solver)?,
            }
        }
    };
    let mut result = match choose {
        Choose::No => newton_only(&system, &mut workspace, x0, &settings, report),
        _ => choose_equilibrium(&mut system, &mut workspace, x0, choose, options, &settings, report),
    };
    let correction = result.as_mut().ok().and_then(|x| {
        let t = Instant::now();
        // A breakdown at a stage of the order-6 scheme leaves the solution without an estimate.
        // The workspace's residual is the one at x: Newton's last, or a linearization's
        // there (the stability verdict, a path's landing). At a tight tolerance x may become
        // the order-6 solution.
        let phi4 = workspace.residual().to_vec();
        // The node rates that residual's evaluation gave, when it was Newton's (not a
        // Jacobian's): the same values the estimate would evaluate at x.
        let rates = workspace.residual_rates().map(<[_]>::to_vec);
        let c = deferred::estimate(&system, &mut workspace, x, &phi4, rates, options.tolerance, report);
        report.timings.estimate += t.elapsed();
        c
    });
    let (mesh, mut last) = kept.unwrap_or_else(|| (system.mesh.clone(), None));
    match (result.as_ref(), last.as_mut()) {
        (Ok(x), Some(last)) => last.clone_from(x),
        (Ok(x), None) => last = Some(x.clone()),
        (Err(_), _) => last = None,
    }
    *cache = Some(Cached {
        mesh,
        solver: options.linear_solver,
        workspace,
        last,
    });
    result.map(|x| Level {
        mesh: system.mesh,
        x,
        correction,
    })
}

/// Newton from `x0` on a mesh after the first, warm-started from the previous level: the
/// equilibrium is chosen already.
fn newton_only(
    system: &System,
    ws: &mut Workspace,
    x0: Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    let mut x = x0;
    let (termination, worst) = newton::run(system, ws, &mut x, settings, report);
    report.termination = termination;
    if termination == Termination::Converged {
        Ok(x)
    } else {
        Err(not_converged(
            system,
            report,
            worst,
            "refine the mesh or warm-start from a nearby solution",
        ))
    }
}

/// Stamps the total time on the report a non-convergence error carries.
fn timed(mut error: Error, start: Instant) -> Error {
    if let Error::NotConverged { report, .. } = &mut error {
        report.timings.total = start.elapsed();
    }
    error
}

/// The error of a solve that did not converge: its report, where the residual is largest
/// and what to try (`hint`).
pub(crate) fn not_converged(system: &System, report: &SolveReport, worst_row: usize, hint: &str) -> Error {
    Error::NotConverged {
        method: Method::Collocation,
        report: Box::new(report.clone()),
        worst_s: system.row_position(worst_row),
        hint: hint.into(),
    }
}
