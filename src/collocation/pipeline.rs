//! One solve's stages in order: the start (mesh, warm or cold states), Newton and the
//! equilibrium choice on the first mesh, refinement to the tolerance, the error estimate and
//! the stability verdict, and the [`Solution`] built from the node states.

use super::deferred;
use super::equilibrium::{Choose, better_start, choose_equilibrium, near_start, plain_verdict, stability_of};
use super::estimate;
use super::newton::{self, Settings, Workspace};
use super::options::{Equilibrium, Options};
use super::refine;
use super::relax;
use super::solver::{Cache, Cached};
use super::start::{cold_start, initial_mesh, resolves};
use super::system::System;
use super::workspace;
use crate::error::Result;
use crate::mesh::guess::{self, interpolate};
use crate::mesh::{Mesh, nodes, spare};
use crate::model::equations::Model;
use crate::report::{Method, PathTaken, SolveReport, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Robot};
use std::time::Instant;
use tensions::solve_tensions;

mod tensions;

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
    keep_thread(cache);
    result
}

/// Gives a stateless solve's `cache` back to the thread's kept workspaces and buffers.
fn keep_thread(cache: Cache) {
    if let Some(c) = cache {
        workspace::keep(c.mesh, c.solver, c.workspace);
        if let Some(last) = c.last {
            spare::give(last);
        }
    }
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
    solve_tensions(robot, options, warm, cache, false)
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
    let result = solve_tensions(robot, options, Some(warm), &mut cache, true);
    keep_thread(cache);
    result
}

/// Where Newton with friction starts (docs/friction.md section 3): a mesh and node states on
/// it, and the report of the frictionless solve that gave them.
pub(crate) struct Start {
    /// The mesh Newton with friction starts on.
    pub(crate) mesh: Mesh,
    /// The frictionless node states on it.
    pub(crate) x: Vec<State>,
    /// The frictionless solve's report (its counts, timings, path and notes).
    pub(crate) report: SolveReport,
    /// Whether the equilibrium was chosen without a verdict: the direct answer accepted
    /// unassessed ([`Choose::Unassessed`]), which stands only if the answer with friction
    /// built on it is `stable`.
    pub(crate) provisional: bool,
}

/// The frictionless start of a solve with friction (`robot` validated, without friction):
/// for tension inputs, Newton and the equilibrium choice with its verdict on the first mesh
/// and that mesh's error estimate, as [`solve_impl`] begins; with `unassessed`, a direct
/// answer is accepted without its verdict ([`Choose::Unassessed`]: the answer with friction's
/// verdict decides, and [`Start::provisional`] says the caller must fall back to this
/// function without `unassessed` when it is not `stable`). Where the estimate wants a
/// finer mesh, the start is the first mesh's states interpolated onto it: Newton with
/// friction solves on it, and its own estimate refines further, so the frictionless solve
/// is not repeated there, nor its final mesh's verdict (which only its report would carry;
/// the answer with friction reports `unknown`). The equilibrium is still chosen on the
/// first mesh with its verdict, so the start is on the branch the frictionless solve would
/// return. Displacement inputs: the frictionless solve on its final mesh.
///
/// # Errors
/// As [`super::solve`].
pub(crate) fn solve_start(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    unassessed: bool,
) -> Result<Start> {
    if robot.has_displacement_inputs() {
        let solution = solve_impl(robot, options, warm, cache)?;
        let points: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(robot, &points)?;
        let x = interpolate(&Model::new(robot), &solution, &mesh);
        return Ok(Start {
            mesh,
            x,
            report: solution.report,
            provisional: false,
        });
    }
    let start = Instant::now();
    let model = Model::new(robot);
    let mut report = SolveReport::new(Method::Collocation);
    let (mesh, x0, reuse, choose) = begin(robot, options, warm, cache, &model, &mut report, false)?;
    let choose = if unassessed { choose.unassessed() } else { choose };
    report.meshes += 1;
    let level =
        solve_on_mesh(&model, mesh, x0, reuse, choose, options, &mut report, cache).map_err(|e| timed(e, start))?;
    // A direct answer is the only one the choice accepts without a verdict, and only when
    // the verdict would decide (the load path's choice; `nearest` takes Newton's answer
    // whatever its verdict).
    let provisional = unassessed
        && report.path == PathTaken::Direct
        && options.equilibrium == Equilibrium::LoadPath
        && options.continuation;
    let fine = match (options.tolerance, &level.correction) {
        (Some(tol), Some(correction)) => refine::next_mesh(robot, &level.mesh, correction, tol, options)?,
        _ => None,
    };
    let Level { mesh, x, correction } = level;
    let start_here = |mesh, x, mut report: SolveReport| {
        report.timings.total = start.elapsed();
        Ok(Start {
            mesh,
            x,
            report,
            provisional,
        })
    };
    let (Some(fine), Some(correction)) = (fine, correction) else {
        return start_here(mesh, x, report);
    };
    // As refine::to_tolerance interpolates a level onto the next mesh.
    let guess = nodes::nodes(&model, &x, &segment_ends(&mesh), Some(&correction.node_rates))?;
    let x = guess::interpolate_nodes(&model, &guess, &fine);
    start_here(fine, x, report)
}

/// The first mesh of a tension solve and the states Newton starts from on it: the warm
/// start interpolated (kept when it is the cached solver's last solution, or a stable one
/// near the answer, or always with `keep_warm`), or the cold start; whether the cached
/// factors are reused, and how the equilibrium is chosen there.
///
/// `keep_warm` is a sweep's solve on the branch of its warm start
/// ([`super::solve_on_branch`]): the cold guess is not compared with it, since a smaller
/// residual does not make it a state of that branch (the straight column past Euler's load
/// is an exact equilibrium, residual zero, of another branch than the buckled warm start;
/// docs/stability.md, "col25").
///
/// # Errors
/// As [`super::solve`].
fn begin(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    model: &Model,
    report: &mut SolveReport,
    keep_warm: bool,
) -> Result<(Mesh, Vec<State>, bool, Choose)> {
    let mut mesh = initial_mesh(robot, options, warm)?;
    if options.tolerance.is_none() {
        resolves(robot, options, &mesh)?;
    }
    let warm_stable = warm.is_some_and(|g| g.report.stability.is_stable());
    let warm = warm.map(|g| interpolate(model, g, &mesh));
    // The cached factors belong to the guess when it is the cached solver's last solution.
    let mut reuse = match (cache.as_ref(), &warm) {
        (Some(c), Some(w)) => c.mesh == mesh && c.solver == options.linear_solver && c.last.as_ref() == Some(w),
        _ => false,
    };
    let (x0, choose) = match warm {
        Some(w) if reuse || keep_warm => (w, Choose::FromWarm),
        Some(w) => {
            let system = System::new(model.clone(), mesh.clone());
            // A stable warm start near the answer (by the predicted step) is kept; else the
            // start with the smaller residual.
            let near = warm_stable
                .then(|| near_start(&system, &w, options.linear_solver, report))
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
                    let cold = guess::initial(model, &mesh.nodes, options.initial_guess);
                    better_start(&system, w, cold)
                }
            }
        }
        None => (cold_start(model, options, &mut mesh)?, Choose::FromCold),
    };
    Ok((mesh, x0, reuse, choose))
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

impl Level {
    /// Gives the level's buffers (mesh, states, the estimate's) back to the thread's kept
    /// ones ([`spare`]) when the solve is done with them.
    pub(crate) fn release(self) {
        self.mesh.release();
        spare::give(self.x);
        if let Some(c) = self.correction {
            c.release();
        }
    }
}

/// The end of the segment (between breakpoints) of every node, as [`nodes::solution`] wants,
/// in a buffer the thread kept ([`spare`]).
pub(crate) fn segment_ends(mesh: &Mesh) -> Vec<f64> {
    let mut ends = spare::take(mesh.nodes.len());
    ends.extend(mesh.nodes.iter().map(|n| n.segment_end));
    ends
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
    // The cached mesh and last states' buffers are kept for the cache this solve leaves,
    // and the system is built in the workspace's buffers; a new mesh's workspace keeps the
    // tension columns if the cached one did (a Solver's `keep_tension_columns`).
    let tension_columns = cache.as_ref().is_some_and(|c| c.workspace.keeps_tension_columns());
    let found = match cache.take() {
        Some(c) if c.mesh == mesh && c.solver == options.linear_solver => Some((c.workspace, c.mesh, c.last)),
        other => {
            if let Some(c) = other {
                workspace::keep(c.mesh, c.solver, c.workspace);
                if let Some(last) = c.last {
                    spare::give(last);
                }
            }
            workspace::spare(&mesh, options.linear_solver).map(|(kept, ws)| (ws, kept, None))
        }
    };
    let (mut system, mut workspace, kept) = match found {
        Some((mut ws, kept_mesh, last)) => (ws.system(model, mesh), ws, Some((kept_mesh, last))),
        None => {
            let system = System::new(model.clone(), mesh);
            let ws = Workspace::new(&system, options.linear_solver)?;
            (system, ws, None)
        }
    };
    workspace.keep_tension_columns(tension_columns);
    let mut result = match choose {
        Choose::No => newton_only(&system, &mut workspace, x0, options, &settings, report),
        _ => choose_equilibrium(&mut system, &mut workspace, x0, choose, options, &settings, report),
    };
    let mut correction = result
        .as_mut()
        .ok()
        .and_then(|x| estimate_at(&system, &mut workspace, x, options, report));
    // A direct answer whose verdict was deferred ([`Choose::Unassessed`] with Newton's
    // Jacobian at it) takes it here when this mesh is the last (the estimate meets the
    // tolerance, or there is none), from that Jacobian as the choice would have; on a mesh
    // that is not the last it is never taken (the final mesh's decides, `attempt`).
    if let (Choose::Unassessed { ahead: true, .. }, Ok(x)) = (choose, result.as_mut())
        && report.path == PathTaken::Direct
        && last_mesh(options, correction.as_ref(), system.model.robot.length())
    {
        let factors_held = workspace.factors_at_iterate();
        let t = Instant::now();
        stability_of(&system, &mut workspace, x, false, report);
        report.timings.stability += t.elapsed();
        // A root in the neutral zone settled by linearizing at x (`neutral::settle`)
        // replaced the factors and the residual the estimate read; the choice takes the
        // verdict before the estimate, whose estimate reads those: estimated again, so the
        // bits are the choice's.
        if !factors_held && workspace.factors_at_iterate() {
            if let Some(c) = correction.take() {
                c.release();
            }
            correction = estimate_at(&system, &mut workspace, x, options, report);
        }
    }
    // A load path that re-meshed left a system and workspace of another mesh: then the
    // cache gets that mesh, not the kept one.
    let (cached_mesh, mut last) = match kept {
        Some((kept_mesh, last)) if kept_mesh == system.mesh => (kept_mesh, last),
        other => {
            if let Some((kept_mesh, last)) = other {
                kept_mesh.release();
                if let Some(last) = last {
                    spare::give(last);
                }
            }
            (system.mesh.clone(), None)
        }
    };
    match (result.as_ref(), last.as_mut()) {
        (Ok(x), Some(last)) => last.clone_from(x),
        (Ok(x), None) => last = Some(spare::copy(x)),
        (Err(_), _) => last = None,
    }
    let mesh = workspace.keep_system(system);
    *cache = Some(Cached {
        mesh: cached_mesh,
        solver: options.linear_solver,
        workspace,
        last,
    });
    result.map(|x| Level { mesh, x, correction })
}

/// The error estimate of `x`, converged on `system`, with the factors and Newton's last
/// residual (and its node rates, when a residual evaluation gave them) that `workspace`
/// holds ([`deferred::estimate`]: at a tight tolerance `x` may become the order-6
/// solution). None where a stage of the order-6 scheme breaks down.
fn estimate_at(
    system: &System,
    workspace: &mut Workspace,
    x: &mut Vec<State>,
    options: &Options,
    report: &mut SolveReport,
) -> Option<estimate::Correction> {
    let t = Instant::now();
    // The workspace's residual is the one at x: Newton's last, or a linearization's there
    // (the stability verdict, a path's landing).
    let phi4 = spare::copy(workspace.residual());
    // The node rates that residual's evaluation gave, when it was Newton's (not a
    // Jacobian's): the same values the estimate would evaluate at x.
    let rates = workspace.residual_rates().map(spare::copy);
    let c = deferred::estimate(system, workspace, x, &phi4, rates, options.tolerance, report);
    spare::give(phi4);
    report.timings.estimate += t.elapsed();
    c
}

/// Whether a mesh with the error estimate `correction` is the last of the solve's mesh
/// sequence ([`refine::to_tolerance`]): no tolerance, no estimate, or one that meets it (rod
/// length `length`).
fn last_mesh(options: &Options, correction: Option<&estimate::Correction>, length: f64) -> bool {
    match (options.tolerance, correction) {
        (Some(tol), Some(c)) => refine::meets(&c.estimate, tol, length),
        _ => true,
    }
}

/// Newton from `x0` on a mesh after the first, warm-started from the previous level: the
/// equilibrium is chosen already.
fn newton_only(
    system: &System,
    ws: &mut Workspace,
    x0: Vec<State>,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    let mut x = x0;
    // A direct solve's verdict is the plain Jacobian's at the answer (not `exact`, at the end
    // of `solve_tensions`): Newton evaluates it at its last trial point, as a direct
    // solve's equilibrium choice does (wasted only when this mesh is refined further).
    let direct = matches!(report.path, PathTaken::Direct | PathTaken::Fallback);
    let (termination, worst) = if direct && plain_verdict(system) {
        newton::run_ahead(system, ws, &mut x, settings, report)
    } else {
        newton::run(system, ws, &mut x, settings, report)
    };
    report.termination = termination;
    if termination == Termination::Converged {
        return Ok(x);
    }
    // The load path's answer (from rest) on a finer mesh, where Newton from the coarser
    // one's does not converge (a stable state in a nearly neutral valley, whose place along
    // it the finer mesh moves): the state where the damped motion from Newton's last
    // iterate comes to rest, stable (docs/stability.md, "A root at the base"). Direct and
    // warm-started answers, and a sweep's bisection on its branch, keep Newton's verdict.
    let from_rest = matches!(report.path, PathTaken::LoadPath { .. });
    let relaxed = match options.equilibrium {
        Equilibrium::LoadPath if from_rest => relax::relax(system, ws, x, settings, report),
        _ => None,
    };
    if let Some(x) = relaxed {
        report.termination = Termination::Converged;
        report.notes.push(format!(
            "Newton on the {}-interval mesh did not converge from the coarser mesh's answer; \
             the answer is the stable state the damped motion from its last iterate came to rest in",
            system.mesh.intervals()
        ));
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
