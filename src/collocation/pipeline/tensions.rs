//! A tension solve (every tendon tension-controlled, no friction): the first mesh's
//! equilibrium choice, refinement to the tolerance and the final mesh's verdict, with the
//! provisional route that takes a first mesh's direct answer to the next mesh without its
//! verdict (docs/stability.md, "Which equilibrium a solve returns").

use super::{Level, begin, record_estimate, segment_ends, solve_on_mesh, timed};
use crate::collocation::MAX_ITERATIONS;
use crate::collocation::deferred;
use crate::collocation::equilibrium::{Choose, held_stability, stability_of};
use crate::collocation::options::{Equilibrium, Options};
use crate::collocation::refine;
use crate::collocation::solver::Cache;
use crate::collocation::stability;
use crate::collocation::unknowns;
use crate::error::Result;
use crate::mesh::{nodes, spare};
use crate::model::equations::Model;
use crate::report::{Method, NOT_ASSESSED, PathTaken, SolveReport, Stability};
use crate::solution::Solution;
use crate::{Error, Robot};
use std::time::Instant;

/// [`super::solve_impl`] for a robot (validated, with `options` validated) whose tendons are all
/// tension-controlled and without friction, with the final mesh's stability verdict in the
/// report; with `on_branch`, keeping to the branch of `warm` when the solve starts from it
/// ([`Choose::OnBranch`]).
///
/// Where the first mesh is not the last, its direct answer goes on to the next mesh without
/// its verdict ([`attempt`], `provisional`): the final mesh's verdict decides, and when it is
/// not `stable` (or a later mesh fails) the whole solve runs again with the full
/// choice on the first mesh, whose report then counts both runs (docs/stability.md, "Which
/// equilibrium a solve returns").
///
/// # Errors
/// As [`crate::collocation::solve`].
pub(super) fn solve_tensions(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    on_branch: bool,
) -> Result<Solution> {
    let start = Instant::now();
    let mut provisional = true;
    let mut tried = None;
    loop {
        match attempt(robot, options, warm, cache, on_branch, provisional, start) {
            Attempt::Answer(mut answer) => {
                if let Some(tried) = &tried {
                    match &mut answer {
                        Ok(solution) => solution.report.add_work(tried),
                        Err(Error::NotConverged { report, .. }) => report.add_work(tried),
                        Err(_) => {}
                    }
                }
                return answer;
            }
            Attempt::Again(report) => {
                // The cached states are the provisional answer's: the full run must not take
                // them for its warm start (`begin` reuses factors only for the cached ones).
                if let Some(last) = cache.as_mut().and_then(|c| c.last.take()) {
                    spare::give(last);
                }
                tried = Some(report);
                provisional = false;
            }
        }
    }
}

/// What one run of [`attempt`] gave: the answer, or the report of a provisional route that
/// did not end `stable` (the solve runs again with the full choice).
enum Attempt {
    /// The solve's answer (or its error).
    Answer(Result<Solution>),
    /// The report of the provisional route, whose work the full run's report counts.
    Again(SolveReport),
}

/// One run of [`solve_tensions`] from its `start`: with `provisional`, a direct answer on a
/// first mesh that is not the last goes on without its verdict ([`Choose::Unassessed`] with
/// Newton's Jacobian at the answer still evaluated, so that a first mesh that is the last
/// takes its verdict after its estimate at today's cost, [`solve_on_mesh`]); only a cold or
/// warm start without cached factors, at the load path's choice with continuation, a
/// tolerance above [`deferred::ORDER6_BELOW`] (whose order-6 answer would move the state the
/// verdict is taken at) and conservative loads (the conjugate-point verdict) is provisional.
fn attempt(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    on_branch: bool,
    provisional: bool,
    start: Instant,
) -> Attempt {
    // The model's tensions, the report's "not assessed" and every stage's buffers come from
    // the thread's kept ones (mesh::spare) and go back there, the workspaces from the
    // cache or the thread's kept ones: a repeated solve allocates only what the Solution
    // owns (tests/allocation.rs).
    let mut model = Model::new_in(robot, spare::take(robot.tendons.len()));
    let mut report = SolveReport::new_in(Method::Collocation, spare::note(NOT_ASSESSED));
    // Newton's iterations are recorded without growing the history after this.
    report.history.reserve(options.max_iterations.min(MAX_ITERATIONS));
    let (mesh, x0, reuse, choose) = match begin(robot, options, warm, cache, &model, &mut report, on_branch) {
        Ok(begun) => begun,
        Err(e) => return Attempt::Answer(Err(e)),
    };
    // A solve started from the cold guess (its residual was the smaller) has no branch to
    // keep to; on a branch (`on_branch`) the warm start is always kept (`begin`).
    let choose = match choose {
        Choose::FromWarm if on_branch => Choose::OnBranch,
        other => other,
    };
    let provisional = provisional
        && !reuse
        && matches!(choose, Choose::FromCold | Choose::FromWarm)
        && options.equilibrium == Equilibrium::LoadPath
        && options.continuation
        && options.tolerance.is_some_and(|tol| tol > deferred::ORDER6_BELOW)
        && stability::non_conservative(&model).is_none();
    let choose = if provisional {
        choose.unassessed_with(true)
    } else {
        choose
    };
    // The first mesh reuses the factors and chooses the equilibrium; finer ones start from it.
    let mut first = Some((reuse, choose));
    // Whether the first mesh accepted a direct answer without its verdict: only then can
    // the full choice end elsewhere (a first mesh that fails, or takes the load path, does
    // what the full choice would, and running it again would repeat the same work).
    let mut unassessed = false;
    let level = refine::to_tolerance(
        &mut model,
        mesh,
        x0,
        options,
        &mut report,
        cache,
        |model, mesh, x0, report, cache| match first.take() {
            Some((reuse, choose)) => {
                let level = solve_on_mesh(model, mesh, x0, reuse, choose, options, report, cache);
                unassessed = provisional && level.is_ok() && report.path == PathTaken::Direct;
                level
            }
            None => solve_on_mesh(model, mesh, x0, false, Choose::No, options, report, cache),
        },
    );
    // A direct answer was accepted without its verdict: it stands only if the final
    // mesh's verdict is `stable`.
    let provisional = unassessed;
    let level = match level {
        Ok(level) => level,
        Err(_) if provisional => {
            // The model's tensions and the report's "not assessed" go back to the thread's
            // kept ones, as on the unstable verdict's way below.
            spare::give(model.tensions);
            if let Stability::Unknown { reason } = &mut report.stability {
                spare::give_note(std::mem::take(reason));
            }
            return Attempt::Again(report);
        }
        Err(e) => return Attempt::Answer(Err(timed(e, start))),
    };
    let Level {
        mut mesh,
        x,
        correction,
    } = level;
    report.intervals = mesh.intervals();
    report.unknowns = unknowns::unknowns(mesh.nodes.len());
    report.nonzeros = unknowns::nonzeros(&mesh);
    record_estimate(&mut report, correction.as_ref(), options, robot.length());
    if let Some(c) = cache.as_mut() {
        // The verdict belongs to this solve's state: `stability_of` evaluates the Jacobian at
        // it unless the workspace's is already there (and its verdict, when assessed, is
        // taken without building the system again).
        let direct = matches!(report.path, PathTaken::Direct | PathTaken::Fallback);
        let exact = !direct && !report.history.iter().any(|i| i.fresh_jacobian);
        let t = Instant::now();
        let verdict = match held_stability(&model, &c.workspace, exact) {
            Some(verdict) => verdict,
            None => {
                // The workspace is the final mesh's: its system's buffers are this one's.
                let system = c.workspace.system(&model, mesh);
                let verdict = stability_of(&system, &mut c.workspace, &x, exact, &mut report);
                mesh = c.workspace.keep_system(system);
                verdict
            }
        };
        if let Stability::Unknown { reason } = std::mem::replace(&mut report.stability, verdict) {
            spare::give_note(reason);
        }
        report.timings.stability += t.elapsed();
    }
    if provisional && !report.stability.is_stable() {
        spare::give(model.tensions);
        Level { mesh, x, correction }.release();
        return Attempt::Again(report);
    }
    report.timings.total = start.elapsed();
    let rates = correction.as_ref().map(|c| c.node_rates.as_slice());
    let ends = segment_ends(&mesh);
    let solution = nodes::solution(&model, &x, &ends, rates, report);
    spare::give(ends);
    spare::give(model.tensions);
    Level { mesh, x, correction }.release();
    Attempt::Answer(solution)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Loads, Rod, cases};
    use nalgebra::Vector3;
    use std::f64::consts::PI;

    /// One run of [`attempt`] from a fresh cache, with or without the provisional route.
    fn once(robot: &Robot, provisional: bool) -> Attempt {
        attempt(
            robot,
            &Options::default(),
            None,
            &mut None,
            false,
            provisional,
            Instant::now(),
        )
    }

    /// The node states, verdict, estimate, path and step counts of a solution, bit for bit.
    fn answer(solution: &Solution) -> String {
        let r = &solution.report;
        format!(
            "{:?} {:?} {:?} {:?} {} {} {} {}",
            solution.nodes.iter().map(|n| n.state()).collect::<Vec<_>>(),
            r.stability,
            r.error_estimate,
            r.path,
            r.iterations,
            r.newton_steps,
            r.chord_steps,
            r.meshes
        )
    }

    /// Case H cold: its first mesh (32 intervals) misses the tolerance, so the direct answer
    /// goes on to 85 intervals without the first mesh's verdict; the final verdict is
    /// `stable`, and the answer is the full choice's, bit for bit.
    #[test]
    fn a_provisional_first_mesh_returns_the_full_choices_answer() {
        let robot = cases::case_h();
        let (Attempt::Answer(Ok(provisional)), Attempt::Answer(Ok(full))) = (once(&robot, true), once(&robot, false))
        else {
            panic!("case H solves on either route")
        };
        assert_eq!(provisional.report.meshes, 2, "H re-meshes once");
        assert!(provisional.report.stability.is_stable());
        assert_eq!(answer(&provisional), answer(&full));
    }

    /// A column at 1.5 times Euler's load with a lateral imperfection of 1e-4 of the load:
    /// the direct answer is the nearly straight column, unstable, so the provisional route
    /// does not stand; the solve runs the full choice (the load path to the buckled column)
    /// and returns its answer bit for bit, with both runs' work in its report.
    #[test]
    fn a_provisional_answer_that_is_not_stable_runs_the_full_choice() {
        let rod = Rod::solid_circle(
            cases::LENGTH,
            cases::RADIUS,
            cases::YOUNGS_MODULUS,
            cases::POISSON_RATIO,
        );
        let ei = rod.section_at(0.0).section.kbt[0];
        let p = 1.5 * PI * PI * ei / (4.0 * cases::LENGTH * cases::LENGTH);
        let robot = Robot::new(rod).with_loads(Loads::none().with_tip_force(Vector3::new(1e-4 * p, 0.0, -p)));
        let Attempt::Again(tried) = once(&robot, true) else {
            panic!("the nearly straight column is not stable: the provisional route must not stand")
        };
        assert_eq!(tried.path, PathTaken::Direct);
        let Attempt::Answer(Ok(full)) = once(&robot, false) else {
            panic!("the full choice solves the column")
        };
        assert!(matches!(full.report.path, PathTaken::LoadPath { .. }));
        assert!(full.report.stability.is_stable());
        let solved = solve_tensions(&robot, &Options::default(), None, &mut None, false).unwrap();
        assert_eq!(
            format!("{:?}", solved.nodes.iter().map(|n| n.state()).collect::<Vec<_>>()),
            format!("{:?}", full.nodes.iter().map(|n| n.state()).collect::<Vec<_>>())
        );
        assert_eq!(solved.report.path, full.report.path);
        assert_eq!(solved.report.stability, full.report.stability);
        assert_eq!(solved.report.error_estimate, full.report.error_estimate);
        assert_eq!(solved.report.iterations, full.report.iterations + tried.iterations);
        assert_eq!(solved.report.meshes, full.report.meshes + tried.meshes);
    }

    /// A solve whose first mesh fails (case S at 200 N, far past its tendon's geometric
    /// limit, with two Newton iterations a step: neither the direct answer nor the load
    /// path converges) accepted no answer without its verdict, so it does not run again:
    /// its report counts one run's work, as with the route off.
    #[test]
    fn a_first_mesh_that_fails_is_not_run_again() {
        let robot = cases::case_s().with_tensions(&[0.0, 200.0, 0.0, 0.0, 0.0]);
        let options = Options {
            max_iterations: 2,
            ..Options::default()
        };
        let run = |provisional| attempt(&robot, &options, None, &mut None, false, provisional, Instant::now());
        let iterations = |attempt: Attempt| match attempt {
            Attempt::Answer(Err(Error::NotConverged { report, .. })) => (report.iterations, report.meshes),
            Attempt::Answer(other) => panic!(
                "two iterations a step cannot solve case S at 200 N: {:?}",
                other.map(|s| s.report.path)
            ),
            Attempt::Again(_) => panic!("a first mesh that fails must not be run again"),
        };
        let full = iterations(run(false));
        assert_eq!(iterations(run(true)), full);
        match solve_tensions(&robot, &options, None, &mut None, false) {
            Err(Error::NotConverged { report, .. }) => assert_eq!((report.iterations, report.meshes), full),
            other => panic!(
                "two iterations a step cannot solve case S at 200 N: {:?}",
                other.map(|s| s.report.path)
            ),
        }
    }
}
