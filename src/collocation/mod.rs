//! The collocation solver: the whole robot as one sparse Newton system solved with faer.
//!
//! Stages, in the order data flows:
//! 1. [`Mesh`]: nodes on [0, L] with two nodes at every breakpoint.
//! 2. [`system`]: residual rows (base, Hermite-Simpson intervals in Lie-group local
//!    coordinates, jump conditions, tip) and their exact Jacobian (chain rule through the
//!    scheme with the analytic linearization of eq. 13; AD for the few other blocks).
//! 3. [`newton`]: damped Newton; steps by the structured elimination of [`linear::blocks`] or faer's
//!    sparse LU, every buffer (and the symbolic LU) built once per mesh.
//! 4. Robustness: rigid-equilibrium initial guess or a warm start, and automatic load
//!    continuation when a direct solve fails.
//! 5. Error control: optional adaptive refinement until the tip moves less than a
//!    tolerance, guided by per-interval defect estimates ([`interval_errors`]).
//!
//! docs/numerics.md documents the scheme (order 4), the scaling and the stopping tests.

pub mod linear;
pub mod newton;
mod options;
pub mod residual;
pub mod sensitivity;
pub mod system;
pub mod unknowns;

use crate::error::Result;
use crate::mesh::guess::{self, rigid_estimate};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport, Termination};
use crate::solution::{Node, Solution, State};
use crate::{Error, Robot};
pub use linear::LinearSolver;
use newton::{Settings, Workspace};
pub use options::{MAX_INTERVALS, Options};
use std::time::Instant;
use system::System;

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

fn initial_mesh(robot: &Robot, options: &Options) -> Result<Mesh> {
    match &options.mesh {
        Some(points) => Mesh::from_points(robot, points),
        None => Mesh::uniform(robot, options.intervals),
    }
}

/// Of a warm start and the cold initial guess, the one with the smaller scaled residual. A
/// previous solution for other tensions can be a worse start than the rigid-equilibrium
/// estimate, which is nearly exact for tendon-dominated loading; comparing costs one
/// residual evaluation each.
fn better_start(system: &System, warm: Vec<State>, cold: Vec<State>) -> Vec<State> {
    let mut r = vec![0.0; system.unknowns()];
    let mut norm = |x: &[State]| match system.residual(x, &mut r) {
        Ok(()) => r
            .iter()
            .fold(0.0f64, |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v.abs()) }),
        Err(_) => f64::INFINITY,
    };
    if norm(&cold) < norm(&warm) { cold } else { warm }
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
    let start = Instant::now();
    let model = Model::new(robot);
    let mut report = SolveReport::new(Method::Collocation);
    let mesh = initial_mesh(robot, options)?;
    let warm = warm.map(|g| interpolate(g, &mesh));
    // The cached factors belong to the guess when it is the cached solver's last solution.
    let reuse = match (cache.as_ref(), &warm) {
        (Some(c), Some(w)) => c.mesh == mesh && c.solver == options.linear_solver && c.last.as_ref() == Some(w),
        _ => false,
    };
    let x0 = match warm {
        Some(w) if reuse => w,
        Some(w) => better_start(
            &System::new(model, mesh.clone()),
            w,
            guess::initial(&model, &mesh.nodes, options.initial_guess),
        ),
        None => guess::initial(&model, &mesh.nodes, options.initial_guess),
    };
    let (mut mesh, mut x) = (
        mesh.clone(),
        solve_on_mesh(&model, mesh, x0, reuse, options, &mut report, cache).map_err(|e| timed(e, start))?,
    );
    if let Some(tol) = options.tolerance {
        loop {
            let sys = System::new(model, mesh.clone());
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
                    estimate: report.tip_error_estimate.unwrap_or(f64::NAN),
                    tolerance: tol,
                });
            }
            let guess = nodes::solution(&model, &x, &segment_ends(&mesh), report.clone())?;
            let xf = solve_on_mesh(
                &model,
                fine.clone(),
                interpolate(&guess, &fine),
                false,
                options,
                &mut report,
                cache,
            )
            .map_err(|e| timed(e, start))?;
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
    }
    report.intervals = mesh.intervals();
    report.unknowns = unknowns::unknowns(mesh.nodes.len());
    report.nonzeros = unknowns::nonzeros(&mesh);
    report.timings.total = start.elapsed();
    nodes::solution(&model, &x, &segment_ends(&mesh), report)
}

fn segment_ends(mesh: &Mesh) -> Vec<f64> {
    mesh.nodes.iter().map(|n| n.segment_end).collect()
}

/// Newton on one mesh (starting with chord steps on the cached factors when
/// `reuse_factors`); on failure, load continuation from the unloaded shape.
fn solve_on_mesh(
    model: &Model,
    mesh: Mesh,
    x0: Vec<State>,
    reuse_factors: bool,
    options: &Options,
    report: &mut SolveReport,
    cache: &mut Cache,
) -> Result<Vec<State>> {
    report.meshes += 1;
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors,
    };
    let mut system = System::new(*model, mesh);
    let mut workspace = match cache.take() {
        Some(c) if c.mesh == system.mesh && c.solver == options.linear_solver => c.workspace,
        _ => Workspace::new(&system, options.linear_solver)?,
    };
    let result = newton_with_continuation(&mut system, &mut workspace, x0, options, &settings, report);
    *cache = Some(Cached {
        mesh: system.mesh,
        solver: options.linear_solver,
        workspace,
        last: result.as_ref().ok().cloned(),
    });
    result
}

/// Newton from `x0`; on failure, load continuation (when enabled).
fn newton_with_continuation(
    system: &mut System,
    ws: &mut Workspace,
    x0: Vec<State>,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    report.unknowns = system.unknowns();
    report.nonzeros = ws.nonzeros();
    report.intervals = system.mesh.intervals();
    let mut x = x0;
    report.load_steps += 1;
    let (termination, worst) = newton::run(system, ws, &mut x, settings, report);
    report.termination = termination;
    if termination == Termination::Converged {
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
    continuation(system, ws, settings, report).map_err(|(hint, row)| not_converged(system, report, row, &hint))
}

/// What load continuation ramps.
#[derive(Clone, Copy, PartialEq)]
enum Ramp {
    /// External loads, with the tendons at full tension.
    Loads,
    /// Tensions and external loads together.
    All,
}

/// Load continuation on `system` (whose direct solve failed). First, when the robot has
/// both tendons and external loads, the tensions stay and the external loads are ramped:
/// the tendon-only shape is the one the rigid estimate gets (nearly) right. Failing that,
/// everything is ramped from the unloaded shape. Each step warm-starts from the last; the
/// step halves on failure and grows by half after a success. Returns the states, or a hint
/// and the worst residual row.
fn continuation(
    system: &mut System,
    ws: &mut Workspace,
    settings: &Settings,
    report: &mut SolveReport,
) -> std::result::Result<Vec<State>, (String, usize)> {
    let robot = system.model.robot;
    let loaded = system.model.point_wrench(robot.length()) != Default::default()
        || !robot.loads.point.is_empty()
        || system.mesh.nodes.iter().any(|n| {
            let site = system.model.site(n.s);
            site.f_e != nalgebra::Vector3::zeros() || site.l_e != nalgebra::Vector3::zeros()
        });
    let pulled = robot.tendons.iter().any(|t| t.tension > 0.0);
    let ramps: &[Ramp] = if loaded && pulled {
        &[Ramp::Loads, Ramp::All]
    } else {
        &[Ramp::All]
    };
    let factors = |ramp: Ramp, lambda: f64| {
        if ramp == Ramp::Loads {
            (1.0, lambda)
        } else {
            (lambda, lambda)
        }
    };
    let mut failure = (String::new(), 0);
    for &ramp in ramps {
        let (t, l) = factors(ramp, 0.0);
        system.set_factors(t, l);
        let mut x = rigid_estimate(&system.model, &system.mesh.nodes);
        report.load_steps += 1;
        let (start, row) = newton::run(system, ws, &mut x, settings, report);
        if start != Termination::Converged {
            report.termination = start;
            failure = (
                "the starting problem of load continuation did not converge: refine the mesh".into(),
                row,
            );
            continue;
        }
        // Each load step starts from the last converged one, whose factors are in `ws`.
        let step_settings = Settings {
            reuse_factors: true,
            ..*settings
        };
        let (mut lambda, mut dl): (f64, f64) = (0.0, 0.25);
        while lambda < 1.0 {
            let target = (lambda + dl).min(1.0);
            let (t, l) = factors(ramp, target);
            system.set_factors(t, l);
            let mut trial = x.clone();
            report.load_steps += 1;
            let (term, row) = newton::run(system, ws, &mut trial, &step_settings, report);
            report.termination = term;
            if term == Termination::Converged {
                lambda = target;
                x = trial;
                dl *= 1.5;
            } else {
                dl *= 0.5;
                // 1e-4 of the full load: the solution is not continuous in the load, or
                // there is none nearby (buckling, a tendon losing its tangent).
                if dl < 1e-4 {
                    failure = (
                        format!(
                            "load continuation stalled at {:.1} % of the load; refine the mesh or check for buckling",
                            lambda * 100.0
                        ),
                        row,
                    );
                    break;
                }
            }
        }
        if lambda >= 1.0 {
            return Ok(x);
        }
    }
    Err(failure)
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

/// Solves many independent robots in parallel on rayon's global thread pool, one result per
/// robot in input order. Each solve is the same deterministic computation as [`solve`], so
/// results are bitwise identical to solving them one by one.
pub fn solve_batch(robots: &[Robot], options: &Options) -> Vec<Result<Solution>> {
    use rayon::prelude::*;
    robots.par_iter().map(|robot| solve(robot, options)).collect()
}
