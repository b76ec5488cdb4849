//! The collocation solver: the whole robot as one sparse Newton system solved with faer.
//!
//! Stages, in the order data flows (one module each):
//! 1. [`Options`] (`options.rs`), checked by [`Options::validate`]; [`Mesh`]: nodes on
//!    [0, L] with two nodes at every breakpoint.
//! 2. [`unknowns`](crate::advanced::unknowns): the layout of unknowns and rows, the Jacobian's block pattern.
//! 3. [`residual`](crate::advanced::residual) and [`system`](crate::advanced::system): residual rows (base, Hermite-Simpson intervals in
//!    Lie-group local coordinates, jump conditions, tip) and their exact Jacobian (chain
//!    rule through the scheme with the analytic linearization of eq. 13; AD for the few
//!    other blocks).
//! 4. `linear`: the structured elimination of `linear/blocks.rs` (automatic) or faer's
//!    sparse LU (`linear/sparse.rs`); [`newton`](crate::advanced::newton): damped Newton with chord steps on stored factors, every buffer
//!    (and the symbolic LU) built once per mesh.
//! 5. Robustness and the equilibrium choice: rigid-equilibrium initial guess or a warm
//!    start; Newton's answer stands when it converged cleanly to a state that is not
//!    unstable, else a path is followed (`path.rs`: the Newton homotopy from a warm start,
//!    the load path from the unloaded robot); every answer gets a stability verdict
//!    (`stability.rs`, docs/stability.md). Displacement-controlled tendons are solved by
//!    `actuation.rs`.
//! 6. Error control: every converged mesh gets a deferred-correction error estimate
//!    (`estimate.rs`, one order-6 residual and one solve with Newton's factors); by default
//!    (`refine.rs`) the starting mesh resolves the initial guess and the mesh is
//!    re-distributed until the estimated tip error meets the tolerance.
//! 7. [`sensitivity`]: derivatives of the converged solution by the implicit function
//!    theorem, from one factorization.
//!
//! docs/numerics.md documents the scheme (order 4), the scaling, the stopping tests and the
//! load path.

pub(crate) mod actuation;
mod estimate;
pub(crate) mod linear;
pub(crate) mod newton;
mod options;
mod path;
pub(crate) mod refine;
pub(crate) mod residual;
pub mod sensitivity;
pub(crate) mod stability;
pub(crate) mod system;
mod trace;
pub(crate) mod unknowns;

use crate::error::Result;
use crate::error::invalid;
use crate::mesh::guess;
pub use crate::mesh::guess::InitialGuess;
use crate::mesh::{Mesh, nodes, resolution};
use crate::model::equations::Model;
use crate::report::{Method, Path, SolveReport, Stability, Termination};
use crate::solution::{Node, Solution, State};
use crate::{Error, Robot};
pub use linear::LinearSolver;
use newton::{Settings, Workspace};
pub use options::{DEFAULT_TOLERANCE, Equilibrium, MAX_INTERVALS, MAX_ITERATIONS, Options};
use std::time::Instant;
use system::System;
pub use trace::{Trace, TracePoint, trace};

/// Solves `robot` by collocation from the rigid-equilibrium initial guess.
///
/// # Errors
/// Invalid input, [`Error::NotConverged`] (with the report and where the residual is
/// largest), [`Error::IntervalCap`] when refinement cannot meet the tolerance.
///
/// # Examples
/// ```
/// let robot = tdcr::cases::case_s();
/// let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
/// let tip = solution.tip_position();
/// assert!((tip.x - 0.151823122).abs() < 1e-6);
/// ```
pub fn solve(robot: &Robot, options: &Options) -> Result<Solution> {
    solve_impl(robot, options, None, &mut None)
}

/// Solves `robot` starting from a previous solution (of this or a nearby robot), which is
/// interpolated onto the new mesh if the meshes differ.
///
/// # Errors
/// As [`solve`].
pub fn solve_from(robot: &Robot, options: &Options, guess: &Solution) -> Result<Solution> {
    solve_impl(robot, options, Some(guess), &mut None)
}

/// The Newton workspace of the last solve, the mesh and linear solver it was built for,
/// and the states that solve ended at (its factors belong to a Jacobian near them).
struct Cached {
    mesh: Mesh,
    solver: LinearSolver,
    workspace: Workspace,
    last: Option<Vec<State>>,
}

type Cache = Option<Cached>;

/// A collocation solver that keeps its Newton workspace (buffers and, on the sparse path,
/// the pattern and symbolic LU) between solves, so that repeated solves on the same mesh
/// (sweeps, control loops, calibration) skip the setup.
///
/// It also keeps the factors of the last Newton matrix: [`Solver::solve_from`] given the
/// solution this solver just returned (the usual step of a sweep or a control loop) starts
/// with chord steps on those factors, which for a small change of tensions or loads
/// converge without evaluating a new Jacobian.
pub struct Solver {
    /// The options of every solve.
    pub options: Options,
    cache: Cache,
}

impl Solver {
    /// A solver with these options and an empty cache.
    pub fn new(options: Options) -> Self {
        Solver { options, cache: None }
    }

    /// As [`solve`], reusing the workspace of the previous solve when the mesh is the same.
    ///
    /// # Errors
    /// As [`solve`].
    pub fn solve(&mut self, robot: &Robot) -> Result<Solution> {
        solve_impl(robot, &self.options, None, &mut self.cache)
    }

    /// As [`solve_from`], reusing the workspace of the previous solve when the mesh is the
    /// same, and its factors when `guess` is the solution it returned.
    ///
    /// # Errors
    /// As [`solve`].
    pub fn solve_from(&mut self, robot: &Robot, guess: &Solution) -> Result<Solution> {
        solve_impl(robot, &self.options, Some(guess), &mut self.cache)
    }
}

/// The mesh a solve starts on: the explicit points, else (error-controlled, warm-started)
/// the warm start's own mesh, else `options.intervals` uniform intervals.
fn initial_mesh(robot: &Robot, options: &Options, warm: Option<&Solution>) -> Result<Mesh> {
    match (&options.mesh, warm) {
        (Some(points), _) => Mesh::from_points(robot, points),
        (None, Some(guess)) if options.tolerance.is_some() && guess.length() == robot.length() => {
            let points: Vec<f64> = guess.nodes.iter().map(|n| n.s).collect();
            Mesh::from_points(robot, &points)
        }
        (None, _) => Mesh::uniform(robot, options.intervals),
    }
}

/// Checks that the mesh `options` fix resolves `robot` (validated) by the resolution rule
/// (at most pi/2 rad of a routing's turn or of the precurvature per interval, docs/numerics.md
/// "Resolution"): what [`solve`] checks before it iterates, for a caller (such as `tdcr
/// check`) that wants the verdict without solving. Options with a `tolerance` pass: their mesh
/// is only the start of refinement.
///
/// # Errors
/// [`Error::InvalidInput`] on `options.intervals` (`options.mesh` for explicit points) with
/// the intervals that would resolve the robot, or for a mesh that cannot be built.
pub fn check_resolution(robot: &Robot, options: &Options) -> Result<()> {
    if options.tolerance.is_some() {
        return Ok(());
    }
    resolves(robot, options, &initial_mesh(robot, options, None)?)
}

/// Checks that a fixed `mesh` (no tolerance) resolves the robot ([`resolution::required`]):
/// a coarser one would converge to an aliased shape without a sign of it.
///
/// # Errors
/// [`Error::InvalidInput`] on `options.intervals` (`options.mesh` for explicit points) with
/// the intervals that would resolve the robot.
fn resolves(robot: &Robot, options: &Options, mesh: &Mesh) -> Result<()> {
    let need = resolution::required(robot);
    let longest = mesh.nodes.windows(2).map(|w| w[1].s - w[0].s).fold(0.0, f64::max);
    let (field, given, coarse) = match &options.mesh {
        // 1e-9: a uniform mesh of exactly the needed intervals passes despite rounding.
        Some(_) => (
            "options.mesh",
            mesh.intervals(),
            longest > need.longest_interval() * (1.0 + 1e-9),
        ),
        None => (
            "options.intervals",
            options.intervals,
            options.intervals < need.intervals,
        ),
    };
    if !coarse {
        return Ok(());
    }
    let what = match need.feature {
        Some(resolution::Feature::Routing(i)) => format!("the routing of `tendons[{i}]` turns about the backbone"),
        _ => "the rod's precurvature turns".to_string(),
    };
    Err(invalid(
        field,
        format!(
            "is {given} intervals, but {what} by up to {:.2} rad in one of them, and an interval may \
             span at most pi/2 rad (the resolution rule, docs/numerics.md): this mesh cannot resolve \
             the robot and would give an aliased shape; {} intervals resolve it",
            need.rate * longest,
            need.intervals
        ),
        format!(
            "use at least {} intervals, or give a tip tolerance (`tolerance`, --tol) instead of a fixed mesh",
            need.intervals
        ),
    ))
}

/// Of a warm start and the cold initial guess, the one with the smaller scaled residual. A
/// previous solution for other tensions can be a worse start than the rigid-equilibrium
/// estimate, which is nearly exact for tendon-dominated loading; comparing costs one
/// residual evaluation each.
fn better_start(system: &System, warm: Vec<State>, cold: Vec<State>) -> (Vec<State>, Choose) {
    let mut r = vec![0.0; system.unknowns()];
    let mut norm = |x: &[State]| match system.residual(x, &mut r) {
        Ok(()) => r
            .iter()
            .fold(0.0f64, |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v.abs()) }),
        Err(_) => f64::INFINITY,
    };
    if norm(&cold) < norm(&warm) {
        (cold, Choose::FromCold)
    } else {
        (warm, Choose::FromWarm)
    }
}

/// Whether a mesh's Newton solve chooses the equilibrium ([`choose_equilibrium`]), and from
/// which start.
#[derive(Clone, Copy, PartialEq)]
enum Choose {
    /// The initial guess.
    FromCold,
    /// A warm start (a solution of a nearby robot).
    FromWarm,
    /// No choice: a finer mesh warm-started from the chosen equilibrium on the last one.
    No,
}

/// Node states of `guess` on `mesh` (left limits for the left node of a jump).
fn interpolate(guess: &Solution, mesh: &Mesh) -> Vec<State> {
    let same = guess.nodes.len() == mesh.nodes.len() && guess.nodes.iter().zip(&mesh.nodes).all(|(a, b)| a.s == b.s);
    if same {
        return guess.nodes.iter().map(Node::state).collect();
    }
    (0..mesh.nodes.len())
        .map(|k| {
            let s = mesh.nodes[k].s;
            let left = k + 1 < mesh.nodes.len() && mesh.is_jump(k);
            State {
                s,
                ..guess.at_limit(s, left)
            }
        })
        .collect()
}

fn solve_impl(robot: &Robot, options: &Options, warm: Option<&Solution>, cache: &mut Cache) -> Result<Solution> {
    robot.validate()?;
    options.validate()?;
    if robot.has_displacement_inputs() {
        return actuation::solve(robot, options, warm, cache);
    }
    let start = Instant::now();
    let model = Model::new(robot);
    let mut report = SolveReport::new(Method::Collocation);
    let mut mesh = initial_mesh(robot, options, warm)?;
    if options.tolerance.is_none() {
        resolves(robot, options, &mesh)?;
    }
    let warm = warm.map(|g| interpolate(g, &mesh));
    // The cached factors belong to the guess when it is the cached solver's last solution.
    let reuse = match (cache.as_ref(), &warm) {
        (Some(c), Some(w)) => c.mesh == mesh && c.solver == options.linear_solver && c.last.as_ref() == Some(w),
        _ => false,
    };
    let (x0, choose) = match warm {
        Some(w) if reuse => (w, Choose::FromWarm),
        Some(w) => {
            let cold = guess::initial(&model, &mesh.nodes, options.initial_guess);
            better_start(&System::new(model.clone(), mesh.clone()), w, cold)
        }
        None => (cold_start(robot, options, &mut mesh)?, Choose::FromCold),
    };
    let mut level =
        solve_on_mesh(&model, mesh, x0, reuse, choose, options, &mut report, cache).map_err(|e| timed(e, start))?;
    if let Some(tol) = options.tolerance {
        level = refine::to_tolerance(&model, level, tol, options, &mut report, cache).map_err(|e| timed(e, start))?;
    }
    let Level { mesh, x, correction } = level;
    report.intervals = mesh.intervals();
    report.unknowns = unknowns::unknowns(mesh.nodes.len());
    report.nonzeros = unknowns::nonzeros(&mesh);
    record_estimate(&mut report, correction.as_ref(), options, robot.length());
    if let Some(c) = cache.as_mut() {
        let system = System::new(model.clone(), mesh.clone());
        let exact = report.path != Path::Direct && !report.history.iter().any(|i| i.fresh_jacobian);
        let t = Instant::now();
        report.stability = stability_of(&system, &mut c.workspace, &x, exact, &mut report);
        report.timings.stability += t.elapsed();
    }
    report.timings.total = start.elapsed();
    let rates = correction.as_ref().map(|c| c.node_rates.as_slice());
    nodes::solution(&model, &x, &segment_ends(&mesh), rates, report)
}

/// Records the final mesh's error estimate in `report`, with the tolerance it was tested
/// against and whether it meets it (rod length `length`).
fn record_estimate(
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

/// The initial guess of a cold start on `mesh`. With error control and no fixed mesh, the
/// start moves first to a mesh that resolves the initial guess and the routings (the
/// resolution rule), when `mesh` does not.
///
/// # Errors
/// [`Error::InvalidInput`] if the finer mesh cannot be built.
fn cold_start(robot: &Robot, options: &Options, mesh: &mut Mesh) -> Result<Vec<State>> {
    let model = Model::new(robot);
    let x0 = guess::initial(&model, &mesh.nodes, options.initial_guess);
    if options.tolerance.is_none() || options.mesh.is_some() {
        return Ok(x0);
    }
    let floor = options.intervals.max(resolution::required(robot).intervals);
    let needed = refine::start_intervals(robot, &x0, floor).min(options.max_intervals);
    if needed <= mesh.intervals() {
        return Ok(x0);
    }
    *mesh = Mesh::uniform(robot, needed)?;
    Ok(guess::initial(&model, &mesh.nodes, options.initial_guess))
}

/// A converged solve on one mesh: its states and their error estimate.
struct Level {
    mesh: Mesh,
    x: Vec<State>,
    /// `None` where the estimate's linear solve failed.
    correction: Option<estimate::Correction>,
}

fn segment_ends(mesh: &Mesh) -> Vec<f64> {
    mesh.nodes.iter().map(|n| n.segment_end).collect()
}

/// Newton on one mesh (starting with chord steps on the cached factors when
/// `reuse_factors`); on the first mesh (`choose`), the equilibrium choice of
/// [`choose_equilibrium`]. Then the error estimate with the factors Newton left.
#[allow(clippy::too_many_arguments)]
fn solve_on_mesh(
    model: &Model,
    mesh: Mesh,
    x0: Vec<State>,
    reuse_factors: bool,
    choose: Choose,
    options: &Options,
    report: &mut SolveReport,
    cache: &mut Cache,
) -> Result<Level> {
    report.meshes += 1;
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors,
        stop_when_damped: false,
    };
    let mut system = System::new(model.clone(), mesh);
    let mut workspace = match cache.take() {
        Some(c) if c.mesh == system.mesh && c.solver == options.linear_solver => c.workspace,
        _ => Workspace::new(&system, options.linear_solver)?,
    };
    let result = match choose {
        Choose::No => newton_only(&system, &mut workspace, x0, &settings, report),
        _ => {
            let warm = choose == Choose::FromWarm;
            choose_equilibrium(&mut system, &mut workspace, x0, warm, options, &settings, report)
        }
    };
    let correction = result.as_ref().ok().and_then(|x| {
        let t = Instant::now();
        // A breakdown at a stage of the order-6 scheme leaves the solution without an estimate.
        // The workspace's residual is the one at x: Newton's last, or a linearization's
        // there (the stability verdict, a path's landing).
        let phi4 = workspace.residual().to_vec();
        let c = estimate::estimate_with(&system, &mut workspace, x, Some(&phi4))
            .ok()
            .flatten();
        report.timings.estimate += t.elapsed();
        c
    });
    *cache = Some(Cached {
        mesh: system.mesh.clone(),
        solver: options.linear_solver,
        workspace,
        last: result.as_ref().ok().cloned(),
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

/// The most Newton iterations of a direct solve that counts as clean: from a guess on the
/// right branch Newton converges in 2-8 (docs/numerics.md); more means it wandered.
const CLEAN_ITERATIONS: usize = 12;

/// Whether Newton went straight to its root: no damped step and few iterations. A damped
/// step means the guess was outside Newton's region of quadratic convergence, where the
/// iteration can cross to another branch of equilibria.
fn clean(history: &[crate::report::Iteration]) -> bool {
    history.len() <= CLEAN_ITERATIONS && history.iter().all(|i| i.damping == 1.0)
}

/// The stability of the equilibrium `x` of `system` ([`stability`]), from the Jacobian
/// last factored in `ws`: Newton's last (evaluated one step before `x`), or for a solve
/// that converged by chord steps alone the earlier Jacobian those steps used, whose verdict
/// is then reused. A new Jacobian at `x` is evaluated only when `exact` (at the end of a
/// load path, whose last Jacobian may belong to a point before the end).
fn stability_of(system: &System, ws: &mut Workspace, x: &[State], exact: bool, report: &mut SolveReport) -> Stability {
    if let Some(reason) = stability::non_conservative(system.model.robot) {
        return Stability::Unknown { reason };
    }
    if (exact || !ws.has_factors()) && !ws.linearize(system, x, report) {
        return Stability::Unknown {
            reason: "the Jacobian at the solution is singular or not finite".into(),
        };
    }
    let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
    ws.verdict(|values| stability::assess(values, &s))
}

/// Newton from `x`, given only the chance to converge cleanly ([`clean`]) unless
/// `nearest`: the converged states, if they are not unstable (or `nearest`).
fn direct(
    system: &System,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    nearest: bool,
    settings: &Settings,
    report: &mut SolveReport,
) -> (bool, usize) {
    let direct = Settings {
        max_iterations: if nearest {
            settings.max_iterations
        } else {
            settings.max_iterations.min(CLEAN_ITERATIONS)
        },
        stop_when_damped: !nearest,
        ..*settings
    };
    let (termination, worst) = newton::run(system, ws, x, &direct, report);
    report.termination = termination;
    if termination != Termination::Converged {
        return (false, worst);
    }
    if nearest {
        return (true, worst);
    }
    if !clean(&report.history) {
        return (false, worst);
    }
    let t = Instant::now();
    let verdict = stability_of(system, ws, x, false, report);
    report.timings.stability += t.elapsed();
    (!matches!(verdict, Stability::Unstable { .. }), worst)
}

/// Newton from `x0`, and the equilibrium choice of docs/stability.md. Newton's answer
/// stands when it converged cleanly to a state that is not unstable (or the caller asked
/// for the nearest equilibrium). Otherwise, from a warm start (`warm`), the Newton homotopy
/// from it ([`path::follow`]), whose end stands if it is not unstable; then Newton from the
/// cold guess, as above; then the load path from the unloaded robot. Newton's answer from
/// `x0`, if it converged at all, is the fallback when no path can be followed.
fn choose_equilibrium(
    system: &mut System,
    ws: &mut Workspace,
    x0: Vec<State>,
    warm: bool,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    report.unknowns = system.unknowns();
    report.nonzeros = ws.nonzeros();
    report.intervals = system.mesh.intervals();
    let nearest = options.equilibrium == Equilibrium::Nearest || !options.continuation;
    let mut x = x0.clone();
    let (accept, worst) = direct(system, ws, &mut x, nearest, settings, report);
    let converged = report.termination == Termination::Converged;
    if accept {
        return Ok(x);
    }
    if !options.continuation {
        return Err(not_converged(
            system,
            report,
            worst,
            "enable load continuation, refine the mesh, or warm-start from a nearby solution",
        ));
    }
    let fallback = converged.then_some(x);
    if warm {
        if let Ok(end) = path::follow(system, ws, path::Start::Warm(&x0), options, settings, report, None) {
            let exact = !report.history.iter().any(|i| i.fresh_jacobian);
            if !matches!(
                stability_of(system, ws, &end.x, exact, report),
                Stability::Unstable { .. }
            ) {
                report.path = Path::FromWarmStart {
                    folds: end.folds,
                    bifurcations: end.bifurcations,
                };
                return Ok(end.x);
            }
        }
        system.set_factors(1.0, 1.0);
        let mut cold = guess::initial(&system.model, &system.mesh.nodes, options.initial_guess);
        if direct(system, ws, &mut cold, false, settings, report).0 {
            return Ok(cold);
        }
    }
    let mesh = system.mesh.clone();
    match path::follow(system, ws, path::Start::Rest, options, settings, report, None) {
        Ok(end) => {
            report.path = Path::LoadPath {
                folds: end.folds,
                bifurcations: end.bifurcations,
            };
            report.unknowns = system.unknowns();
            report.nonzeros = ws.nonzeros();
            report.intervals = system.mesh.intervals();
            Ok(end.x)
        }
        // The path is lost: Newton's answer, if it has one, with its verdict.
        Err((hint, row)) => {
            if system.mesh != mesh {
                *system = System::new(system.model.clone(), mesh);
                *ws = Workspace::new(system, options.linear_solver)?;
            }
            system.set_factors(1.0, 1.0);
            let x = match fallback {
                Some(x) => x,
                None => {
                    let mut x = x0;
                    let (termination, _) = newton::run(system, ws, &mut x, settings, report);
                    report.termination = termination;
                    if termination != Termination::Converged {
                        return Err(not_converged(system, report, row, &hint));
                    }
                    x
                }
            };
            if !ws.linearize(system, &x, report) {
                return Err(not_converged(system, report, row, &hint));
            }
            report.termination = Termination::Converged;
            Ok(x)
        }
    }
}

/// Stamps the total time on the report a non-convergence error carries.
fn timed(mut error: Error, start: Instant) -> Error {
    if let Error::NotConverged { report, .. } = &mut error {
        report.timings.total = start.elapsed();
    }
    error
}

fn not_converged(system: &System, report: &SolveReport, worst_row: usize, hint: &str) -> Error {
    Error::NotConverged {
        method: Method::Collocation,
        report: Box::new(report.clone()),
        worst_s: system.row_position(worst_row),
        hint: hint.into(),
    }
}

/// Solves many independent robots in parallel on rayon's global thread pool, one result per
/// robot in input order. Each solve is the same deterministic computation as [`solve`], so
/// results are bitwise identical to solving them one by one.
pub fn solve_batch(robots: &[Robot], options: &Options) -> Vec<Result<Solution>> {
    use rayon::prelude::*;
    robots.par_iter().map(|robot| solve(robot, options)).collect()
}
