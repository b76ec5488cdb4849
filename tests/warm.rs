//! Warm starts through `collocation::Solver`: after a small change, chord steps on the
//! stored factors of the previous solve converge without a new Jacobian; after a large one,
//! or from a guess the factors do not belong to, the solve falls back to Newton steps and
//! still gives the cold answer.

use tdcr::collocation::{self, LinearSolver, Options, Solver};
use tdcr::{Robot, Solution, cases};

/// Both solves stop below the residual tolerance 1e-11 (dimensionless), which moves the tip
/// by about L x 1e-11 = 2.4e-12 m; 1e-10 m leaves room for the conditioning of the system.
const SAME_ANSWER: f64 = 1e-10;

fn scaled(robot: &Robot, factor: f64) -> Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.tension *= factor;
    }
    r
}

fn options(intervals: usize, linear_solver: LinearSolver) -> Options {
    Options {
        intervals,
        tolerance: None,
        linear_solver,
        ..Default::default()
    }
}

fn tip_gap(a: &Solution, b: &Solution) -> f64 {
    (a.tip_position() - b.tip_position()).norm()
}

#[test]
fn a_one_percent_change_needs_no_new_jacobian() {
    for (robot, intervals) in [(cases::case_s(), 16), (cases::case_h(), 48)] {
        for linear_solver in [LinearSolver::Auto, LinearSolver::SparseLu] {
            let options = options(intervals, linear_solver);
            let mut solver = Solver::new(options.clone());
            let previous = solver.solve(&scaled(&robot, 0.99)).unwrap();
            let warm = solver.solve_from(&robot, &previous).unwrap();
            let cold = collocation::solve(&robot, &options).unwrap();
            let report = &warm.report;
            assert_eq!(report.evaluations.jacobian, 0, "{report:?}");
            assert!(report.history.iter().all(|it| !it.fresh_jacobian), "{report:?}");
            assert!(report.residual <= options.residual_tolerance);
            assert!(tip_gap(&warm, &cold) < SAME_ANSWER, "{:.3e}", tip_gap(&warm, &cold));
        }
    }
}

#[test]
fn a_large_change_falls_back_to_newton_steps() {
    let robot = cases::case_h();
    let options = options(48, LinearSolver::Auto);
    let mut solver = Solver::new(options.clone());
    let previous = solver.solve(&scaled(&robot, 0.3)).unwrap();
    let mut pulled = robot.clone();
    pulled.loads.tip_force.z *= 3.0;
    let warm = solver.solve_from(&pulled, &previous).unwrap();
    let cold = collocation::solve(&pulled, &options).unwrap();
    assert!(warm.report.evaluations.jacobian >= 1, "{:?}", warm.report);
    assert!(tip_gap(&warm, &cold) < SAME_ANSWER, "{:.3e}", tip_gap(&warm, &cold));
}

#[test]
fn factors_are_reused_only_for_the_solvers_own_last_solution() {
    let robot = cases::case_s();
    let options = options(16, LinearSolver::Auto);
    // A guess from elsewhere: the solver's factors belong to another robot's solution.
    let other = collocation::solve(&scaled(&robot, 0.99), &options).unwrap();
    let mut solver = Solver::new(options.clone());
    solver.solve(&scaled(&robot, 0.5)).unwrap();
    let warm = solver.solve_from(&robot, &other).unwrap();
    assert!(warm.report.evaluations.jacobian >= 1, "{:?}", warm.report);
    assert!(warm.report.history.first().is_some_and(|it| it.fresh_jacobian));
    let cold = collocation::solve(&robot, &options).unwrap();
    assert!(tip_gap(&warm, &cold) < SAME_ANSWER);
}

#[test]
fn a_warm_sweep_is_reproducible_bit_for_bit() {
    let robot = cases::case_h();
    let sweep = || {
        let mut solver = Solver::new(options(48, LinearSolver::Auto));
        let mut last = solver.solve(&scaled(&robot, 0.5)).unwrap();
        let mut tips = Vec::new();
        for k in 1..=10 {
            last = solver
                .solve_from(&scaled(&robot, 0.5 + 0.05 * k as f64), &last)
                .unwrap();
            tips.push(last.tip_position().map(f64::to_bits));
        }
        tips
    };
    assert_eq!(sweep(), sweep());
}
