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
        t.set_tension(t.tension() * factor);
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
        for linear_solver in [LinearSolver::Blocks, LinearSolver::SparseLu] {
            let options = options(intervals, linear_solver);
            let mut solver = Solver::new(options.clone());
            let previous = solver.solve(&scaled(&robot, 0.99)).unwrap();
            let warm = solver.solve_from(&robot, &previous).unwrap();
            let cold = collocation::solve(&robot, &options).unwrap();
            let report = &warm.report;
            // No Newton step; the one Jacobian is the stability verdict's, at the solution
            // (the factors the chord steps used belong to the previous state).
            assert_eq!(report.newton_steps, 0, "{report:?}");
            assert_eq!(report.evaluations.jacobian, 1, "{report:?}");
            assert!(report.history.iter().all(|it| !it.fresh_jacobian), "{report:?}");
            assert!(report.residual <= options.residual_tolerance);
            assert!(tip_gap(&warm, &cold) < SAME_ANSWER, "{:.3e}", tip_gap(&warm, &cold));
        }
    }
}

#[test]
fn a_large_change_falls_back_to_newton_steps() {
    let robot = cases::case_h();
    let options = options(48, LinearSolver::Blocks);
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
    let options = options(16, LinearSolver::Blocks);
    // A guess from elsewhere: the solver's factors belong to another robot's solution.
    let other = collocation::solve(&scaled(&robot, 0.99), &options).unwrap();
    let mut solver = Solver::new(options.clone());
    solver.solve(&scaled(&robot, 0.5)).unwrap();
    let warm = solver.solve_from(&robot, &other).unwrap();
    // Its first step is a Newton step, or (a stable guess whose predicted step is small,
    // docs/numerics.md "Robustness") a chord step on the Jacobian evaluated at the guess
    // itself, then one more Jacobian for the verdict at the solution: never a chord step on
    // the factors of the solver's own last solve.
    let report = &warm.report;
    let fresh_first = report.history.first().is_some_and(|it| it.fresh_jacobian);
    assert!(fresh_first || report.evaluations.jacobian >= 2, "{report:?}");
    let cold = collocation::solve(&robot, &options).unwrap();
    assert!(tip_gap(&warm, &cold) < SAME_ANSWER);
}

#[test]
fn a_warm_sweep_is_reproducible_bit_for_bit() {
    let robot = cases::case_h();
    let sweep = || {
        let mut solver = Solver::new(options(48, LinearSolver::Blocks));
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

/// Issue 14: a warm start after a change of the modulus or the base pose takes no more
/// Newton steps than a cold solve of the new robot, after a load change at most one more,
/// and lands on the same state.
#[test]
fn warm_starts_after_any_change_take_no_more_newton_steps_than_cold() {
    // Both parameters exist on these robots (a rod built from its geometry, a tip force).
    let stiffer = |robot: &Robot| {
        tdcr::Parameter::YoungsModulus
            .applied(robot, 1.05 * cases::YOUNGS_MODULUS)
            .unwrap()
    };
    let loaded = |robot: &Robot| {
        tdcr::Parameter::TipForce(2)
            .applied(robot, robot.loads.tip_force.z - 0.05)
            .unwrap()
    };
    let tilted = |robot: &Robot| {
        let mut r = robot.clone();
        r.base_rotation = *tdcr::nalgebra::Rotation3::from_euler_angles(0.0, 0.05, 0.0).matrix() * r.base_rotation;
        r
    };
    type Change<'a> = (&'a str, &'a dyn Fn(&Robot) -> Robot);
    let changes: [Change; 3] = [("E x 1.05", &stiffer), ("tip load", &loaded), ("base", &tilted)];
    for robot in [cases::case_s(), cases::case_h(), cases::prototype()] {
        let before = collocation::solve(&robot, &Default::default()).unwrap();
        for (what, change) in changes {
            let after = change(&robot);
            let cold = collocation::solve(&after, &Default::default()).unwrap();
            let warm = collocation::solve_from(&after, &Default::default(), &before).unwrap();
            // A load change is the one exception, by one step: the cold guess (the rigid
            // equilibrium estimate) carries the new tip load exactly, and the residual that
            // picks between the two starts sees a force change through rows scaled by EA,
            // where it looks small (measured: S and the prototype take 2 Newton steps warm
            // against 1 cold; H 2 and 2).
            let allowed = cold.report.newton_steps + usize::from(what == "tip load");
            assert!(
                warm.report.newton_steps <= allowed,
                "{what}: warm {} Newton steps, cold {}",
                warm.report.newton_steps,
                cold.report.newton_steps
            );
            // 1e-7 m: both error-controlled to 2.4e-8 m on meshes that may differ
            assert!(tip_gap(&warm, &cold) < 1e-7, "{what}: {:.3e}", tip_gap(&warm, &cold));
        }
    }
}

/// The force block of the tip compliance, d p(L) / d F(L), symmetrized: its smallest
/// eigenvalue (negative proves instability for a conservative model).
fn smallest_compliance_eigenvalue(robot: &Robot, solution: &Solution) -> f64 {
    let c = tdcr::collocation::sensitivity::tip_sensitivities(robot, solution)
        .unwrap()
        .compliance();
    let block: nalgebra::Matrix3<f64> = c.fixed_view::<3, 3>(0, 0).into_owned();
    (0.5 * (block + block.transpose())).symmetric_eigenvalues().min()
}

#[test]
fn a_solver_that_converges_by_chord_steps_gives_each_state_its_own_verdict() {
    // Euler's column (the prototype's rod along +z, P_cr = pi^2 EI / (4 L^2) = 0.177893 N)
    // swept past P_cr by one Solver from the equilibrium nearest the guess: the straight
    // column, stable below P_cr and unstable above. The steps past P_cr converge by chord
    // steps on the factors of the step before, which belong to a stable state.
    let p_cr = 0.177893;
    let options = Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    let mut solver = Solver::new(options);
    let mut previous: Option<Solution> = None;
    let mut verdicts = Vec::new();
    for f in [0.9, 0.95, 1.05, 1.1] {
        let mut robot = Robot::new(tdcr::Rod::tube(0.242, 0.0004, 0.0, 210e9, 0.3125));
        robot.loads.tip_force = nalgebra::Vector3::new(0.0, 0.0, -f * p_cr);
        let s = match &previous {
            None => solver.solve(&robot).unwrap(),
            Some(p) => solver.solve_from(&robot, p).unwrap(),
        };
        if f > 1.0 {
            assert_eq!(s.report.newton_steps, 0, "{:?}", s.report);
        }
        // A stable verdict never where the compliance proves instability (1e-9 of the
        // largest compliance, 1/k of the column's bending: rounding)
        if s.report.stability.is_stable() {
            assert!(smallest_compliance_eigenvalue(&robot, &s) > -1e-9, "{f}");
        }
        verdicts.push(s.report.stability.verdict());
        previous = Some(s);
    }
    assert_eq!(verdicts, ["stable", "stable", "unstable", "unstable"]);
}

/// A property robot (tests/properties.rs's generator, case 57 of its fixed seed) whose
/// `load_scale` sweep steps from 30/32 to 31/32. Newton from the warm start is damped at
/// once, and the Newton homotopy from it turns back at a fold (at lambda 0.41) and returns
/// past the warm start: followed on, it wandered to lambda = -25 for the whole 400-step
/// budget (1 162 iterations over 408 load steps) before the load path from rest, where a
/// cold solve takes 43 iterations over 10 load steps. It is now given up below lambda = 0
/// (docs/stability.md, "Warm starts that turn back").
#[test]
fn a_warm_start_whose_homotopy_turns_back_costs_a_few_cold_solves() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/warm-homotopy-fold.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let robot = tdcr::io::parse(&text, path).unwrap().robot;
    let options = Options::default();
    let at = |scale: f64| tdcr::Parameter::LoadScale.applied(&robot, scale).unwrap();
    let warm = collocation::solve(&at(30.0 / 32.0), &options).unwrap();
    let cold = collocation::solve(&at(31.0 / 32.0), &options).unwrap();
    let from = collocation::solve_from(&at(31.0 / 32.0), &options, &warm).unwrap();
    eprintln!(
        "cold: {} iterations, {} load steps; warm: {} iterations, {} load steps ({:?})",
        cold.report.iterations,
        cold.report.load_steps,
        from.report.iterations,
        from.report.load_steps,
        from.report.path
    );
    // The same state: both are the load path's, each within its tolerance (1e-7 L by
    // default) of the exact one.
    assert!(
        tip_gap(&cold, &from) <= 2e-7 * robot.length(),
        "tips {:?} and {:?}",
        cold.tip_position(),
        from.tip_position()
    );
    // The warm attempt (to its fold and back to lambda = 0: 109 iterations over 32 load
    // steps measured) on top of the cold solve's own work (43 over 10): bounded by that
    // attempt with a third to spare, where following the turned-back path took 1 210
    // iterations over 409 load steps.
    assert!(
        from.report.iterations <= cold.report.iterations + 150,
        "{} iterations against {} cold",
        from.report.iterations,
        cold.report.iterations
    );
    assert!(
        from.report.load_steps <= cold.report.load_steps + 45,
        "{} load steps against {} cold",
        from.report.load_steps,
        cold.report.load_steps
    );
}
