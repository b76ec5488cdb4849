//! The order-6 answer of tight tolerances (docs/numerics.md, "The order-6 answer"): the
//! deferred-corrected solution converges at order 6, its reported estimate is never below
//! the true error (against much finer solves, the analytic elastica, a Kirchhoff rod), tight
//! tolerances need far fewer intervals than order 4, and the default tolerance keeps the
//! order-4 answer.

mod common;

use tdcr::advanced::{deferred, equations::Model, guess, mesh::Mesh, newton, system::System};
use tdcr::collocation::{self, LinearSolver};
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Method, Robot, RodModel, Solution, SolveReport, Termination, cases, so3};

/// Collocation on 4096 intervals (order 4: errors about 1e-15 m on these robots) with
/// Newton to 1e-14: solutions on 2048 and 4096 intervals agree to 5e-14 m.
fn reference(robot: &Robot) -> Solution {
    let options = collocation::Options {
        residual_tolerance: 1e-14,
        ..collocation::Options::fixed(4096)
    };
    collocation::solve(robot, &options).unwrap()
}

/// The order-6 tip on a uniform mesh of `intervals` and its reported estimate (m).
fn order6_tip(robot: &Robot, intervals: usize) -> (Vector3<f64>, f64) {
    let solution = collocation::solve(robot, &collocation::Options::fixed(intervals)).unwrap();
    let (tip, estimate) = order6_on_mesh(robot, &solution, Mesh::uniform(robot, intervals).unwrap(), 1e-11);
    (tip.p, estimate.tip_position)
}

/// Observed orders between consecutive meshes of `meshes`, each error against the
/// reference, checking on the way that no reported estimate is below its error.
fn observed_orders(robot: &Robot, meshes: &[usize]) -> Vec<f64> {
    let tip = reference(robot).tip_position();
    let errors: Vec<f64> = meshes
        .iter()
        .map(|&n| {
            let (p, estimate) = order6_tip(robot, n);
            let error = (p - tip).norm();
            eprintln!("{n} intervals: order-6 tip error {error:.3e} m, estimate {estimate:.3e} m");
            assert!(
                error <= estimate,
                "{n} intervals: error {error:.3e} m above its estimate {estimate:.3e} m"
            );
            error
        })
        .collect();
    errors
        .windows(2)
        .zip(meshes.windows(2))
        .map(|(e, n)| (e[0] / e[1]).ln() / (n[1] as f64 / n[0] as f64).ln())
        .collect()
}

#[test]
fn the_corrected_solution_converges_at_order_6_on_s_and_h() {
    // Meshes where the order-6 error is 100x above the references' rounding (5e-14 m) and
    // the mesh resolves the shape: S from 6, H (a helical tendon) from 16 intervals.
    for (name, robot, meshes) in [
        ("S", cases::case_s(), [6, 8, 11, 16]),
        ("H", cases::case_h(), [16, 22, 32, 45]),
    ] {
        let orders = observed_orders(&robot, &meshes);
        eprintln!("{name}: observed orders {orders:.2?}");
        // 5.5: the goal; order 6 is the scheme's (measured 5.9 to 6.3 here)
        assert!(orders.iter().all(|&q| q >= 5.5), "{name}: observed orders {orders:.2?}");
    }
}

/// The true tip errors of a solve at `tol` (relative to L) against `exact` (position, m;
/// rotation), checked against the report's estimate.
fn honest(name: &str, solution: &Solution, exact: (Vector3<f64>, tdcr::nalgebra::Matrix3<f64>), slack: f64) {
    let e = solution.report.error_estimate.unwrap();
    let dp = (solution.tip_position() - exact.0).norm();
    let dr = so3::log(&(exact.1.transpose() * solution.tip().R)).norm();
    eprintln!(
        "{name}: {} intervals, tip error {dp:.3e} m (estimate {:.3e}), rotation {dr:.3e} rad (estimate {:.3e})",
        solution.report.intervals, e.tip_position, e.tip_rotation
    );
    assert!(
        dp <= e.tip_position + slack,
        "{name}: tip error {dp:.3e} m, estimate {:.3e} m",
        e.tip_position
    );
    assert!(
        dr <= e.tip_rotation + slack,
        "{name}: rotation error {dr:.3e} rad, estimate {:.3e}",
        e.tip_rotation
    );
    assert_eq!(solution.report.tolerance_met, Some(true));
}

#[test]
fn tight_tolerances_need_far_fewer_intervals_and_report_honest_estimates() {
    // Intervals the order-4 error control took before the order-6 answer (docs/benchmarks.md,
    // "Tight tolerances"): H 267 at 1e-9 L and 844 at 1e-11 L; S 72 and 228.
    for (name, robot, order4) in [("S", cases::case_s(), [72, 228]), ("H", cases::case_h(), [267, 844])] {
        let exact = reference(&robot);
        for (tol, before) in [1e-9, 1e-11].into_iter().zip(order4) {
            let options = collocation::Options {
                tolerance: Some(tol),
                ..Default::default()
            };
            let solution = collocation::solve(&robot, &options).unwrap();
            honest(
                &format!("{name} at {tol:.0e}"),
                &solution,
                (exact.tip_position(), exact.tip().R),
                0.0,
            );
            // Half the order-4 mesh at most: S meets 1e-9 on its 32-interval starting mesh,
            // H takes 40 of 267 and 82 of 844 intervals
            assert!(
                2 * solution.report.intervals <= before,
                "{name} at {tol:.0e}: {} intervals, order 4 took {before}",
                solution.report.intervals
            );
        }
    }
}

#[test]
fn the_estimate_is_above_the_elastica_error() {
    for lambda in [2.0, 10.0] {
        let (robot, exact) = common::elastica_cantilever(lambda);
        let options = collocation::Options {
            tolerance: Some(1e-9),
            ..Default::default()
        };
        let solution = collocation::solve(&robot, &options).unwrap();
        let e = solution.report.error_estimate.unwrap();
        let error = (solution.tip_position() - exact).norm();
        eprintln!(
            "elastica {lambda}: {} intervals, error {error:.3e} m, estimate {:.3e} m",
            solution.report.intervals, e.tip_position
        );
        // 5e-12 m: the elliptic-integral reference is good to 1e-11 relative (0.5 m tip)
        assert!(error <= e.tip_position + 5e-12, "lambda {lambda}: error {error:.3e} m");
        assert!(
            error <= 1e-9 * robot.length(),
            "lambda {lambda}: error {error:.3e} m above the tolerance"
        );
    }
}

#[test]
fn a_kirchhoff_rod_gets_an_honest_order_6_answer() {
    // On a Kirchhoff rod the translational unknown is the force coordinate, not the strain
    // (docs/model.md, section 4b): the order-8 stages must read it through the site.
    let mut robot = cases::case_h();
    robot.rod_model = RodModel::Kirchhoff;
    let exact = reference(&robot);
    let options = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    honest(
        "Kirchhoff H at 1e-10",
        &solution,
        (exact.tip_position(), exact.tip().R),
        0.0,
    );
}

#[test]
fn the_default_tolerance_keeps_the_order_4_answer() {
    // At 1e-7 L the answer is the collocation solution of its final mesh, up to Newton's own
    // stop (1e-11 m: measured 4e-13 m), not the corrected one, which is about its order-4
    // error (5e-9 m) away.
    for robot in [cases::case_s(), cases::case_h()] {
        let solution = collocation::solve(&robot, &collocation::Options::default()).unwrap();
        let fixed = collocation::Options {
            mesh: Some(solution.nodes.iter().map(|n| n.s).collect()),
            tolerance: None,
            ..Default::default()
        };
        let again = collocation::solve(&robot, &fixed).unwrap();
        let gap = (again.tip_position() - solution.tip_position()).norm();
        assert!(
            gap < 1e-11,
            "the default answer moved {gap:.3e} m from the order-4 solution"
        );
    }
}

#[test]
fn warm_solves_at_a_tight_tolerance_report_honest_estimates() {
    // A Solver that has just solved the robot at 0.99 times the tension starts chord steps on
    // that solve's factors: the order-6 answer and its estimate use them too.
    for (name, robot) in [("S", cases::case_s()), ("H", cases::case_h())] {
        let exact = reference(&robot);
        for tol in [1e-9, 1e-11] {
            let options = collocation::Options {
                tolerance: Some(tol),
                ..Default::default()
            };
            let mut previous = robot.clone();
            for t in previous.tendons.iter_mut() {
                t.set_tension(0.99 * t.tension());
            }
            let mut solver = collocation::Solver::new(options);
            let guess = solver.solve(&previous).unwrap();
            let solution = solver.solve_from(&robot, &guess).unwrap();
            honest(
                &format!("{name} warm at {tol:.0e}"),
                &solution,
                (exact.tip_position(), exact.tip().R),
                0.0,
            );
        }
    }
}

/// An order-6 answer has sensitivities (docs/numerics.md, "The order-6 answer": those of the
/// order-4 system at x6). Case H at 1e-9 L: its order-6 answer leaves an order-4 residual
/// of 6.7e-7, which the sensitivities' guard (1e-8) refused before it checked an order-6
/// answer's order-6 residual (5e-11). Its tension columns against central differences of
/// order-6 answers on the same mesh (the taut tendons), and a Solver's tension Jacobian.
#[test]
fn sensitivities_of_an_order_6_answer_match_differences_of_order_6_answers() {
    let robot = cases::case_h();
    let options = collocation::Options {
        tolerance: Some(1e-9),
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    assert_eq!(solution.report.error_estimate.unwrap().order, 6);
    let sensitivities = collocation::sensitivity::tip_sensitivities(&robot, &solution).unwrap();
    // A Solver's Jacobian of its own order-6 answer (its workspace holds factors that the
    // order-6 chord steps have left behind) is the same.
    let mut solver = collocation::Solver::new(options.clone());
    let answer = solver.solve(&robot).unwrap();
    let tensions: Vec<tdcr::Parameter> = (0..robot.tendons.len()).map(tdcr::Parameter::Tension).collect();
    let j = solver.tip_jacobian(&robot, &answer, &tensions).unwrap();
    // 1e-12: the same Jacobian and solves; only the factoring workspace differs (rounding).
    assert!((&j - &sensitivities.tension).amax() <= 1e-12 * sensitivities.tension.amax());
    let on_mesh = collocation::Options {
        mesh: Some(solution.nodes.iter().map(|n| n.s).collect()),
        ..options
    };
    // The taut tendons (a slack one's derivative is one-sided).
    for i in (0..robot.tendons.len()).filter(|&i| robot.tendons[i].tension() > 0.0) {
        let t = robot.tendons[i].tension();
        let h = 1e-4 * t;
        let tip = |dt: f64| {
            let mut r = robot.clone();
            r.tendons[i].set_tension(t + dt);
            let s = collocation::solve(&r, &on_mesh).unwrap();
            // The same mesh and the same kind of answer, or the difference means nothing.
            assert_eq!(s.report.intervals, solution.report.intervals);
            assert_eq!(s.report.error_estimate.unwrap().order, 6);
            s.tip_position()
        };
        let difference = (tip(h) - tip(-h)) / (2.0 * h);
        let column = sensitivities.tension.fixed_view::<3, 1>(0, i).into_owned();
        let error = (difference - column).norm() / column.norm();
        eprintln!(
            "tendon {i}: |d tip/d tension| {:.4e} m/N, relative difference {error:.2e}",
            column.norm()
        );
        // 1e-5: the sensitivities are the order-4 system's, which differ from the derivative
        // of the order-6 answers by the order-4 discretization error: measured 1.7e-6 to
        // 2.4e-6 for steps of 1e-5 to 1e-3 of the tension (so not the differencing's).
        assert!(error <= 1e-5, "tendon {i}: relative difference {error:.2e}");
    }
}

/// Robot 550 of the 600-robot property run at 1e-10 L (tests/properties.rs,
/// `tight_tolerances_on_six_hundred_random_robots`): its solve follows the load path; its tip
/// error was about twice its reported estimate until the stages kept their strain's last
/// place (docs/numerics.md, "Why the estimate was low on some random robots").
fn path_robot() -> Robot {
    let path = "tests/data/order6-miss-path.toml";
    tdcr::io::parse(&std::fs::read_to_string(path).unwrap(), path)
        .unwrap()
        .robot
}

/// [`path_robot`] and its default solve at 1e-10 L (the 600-robot run's tolerance).
fn path_answer() -> (Robot, Solution) {
    let robot = path_robot();
    let options = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    (robot, solution)
}

/// The load path's answer at a tight tolerance is the order-6 answer of its mesh, not a state
/// the path left short of it: Newton from the answer on the same mesh to 1e-12, one more full
/// Newton step and the deferred correction give the same tip. So robot 550's excess error
/// (before the stages kept their strains' low part) was not the path's stop, its Jacobian or
/// its chord steps.
#[test]
fn a_load_path_answer_is_the_order_6_answer_of_its_mesh() {
    let (robot, solution) = path_answer();
    let length = robot.length();
    // The case this test is for: an answer of the load path.
    assert!(solution.report.load_steps > 0, "{:?}", solution.report.path);
    let mut points: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    points.dedup();
    let system = System::new(Model::new(&robot), Mesh::from_points(&robot, &points).unwrap());
    assert_eq!(system.mesh.intervals(), solution.report.intervals);
    let mut ws = newton::Workspace::new(&system, LinearSolver::Blocks).unwrap();
    let mut x = guess::interpolate(&system.model, &solution, &system.mesh);
    let mut settings = newton::Settings {
        tolerance: 1e-12,
        max_iterations: 30,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = SolveReport::new(Method::Collocation);
    let (termination, _) = newton::run(&system, &mut ws, &mut x, &settings, &mut report);
    assert_eq!(termination, Termination::Converged);
    // One more full Newton step at the converged state (tolerance 0 never stops it).
    let before = x.last().unwrap().p;
    settings.tolerance = 0.0;
    settings.max_iterations = 1;
    newton::run(&system, &mut ws, &mut x, &settings, &mut report);
    let newton_step = (x.last().unwrap().p - before).norm() / length;
    let (x6, _) = deferred::corrected(&system, &mut ws, &x, &mut report).unwrap().unwrap();
    let apart = (x6.last().unwrap().p - solution.tip_position()).norm() / length;
    let estimate = solution.report.error_estimate.unwrap().tip_position / length;
    eprintln!(
        "last Newton step moved the tip {newton_step:.3e} L; answers apart {apart:.3e} L; estimate {estimate:.3e} L"
    );
    // Measured 1.4e-15 L apart (the order-4 tip moved 1.5e-13 L in the extra step) against
    // a reported estimate of 7.6e-13 L: a tenth of the estimate is room for rounding and
    // still far below it.
    assert!(apart <= 0.1 * estimate, "{apart:.3e} L");
}

/// Robot 550's reported estimate at 1e-10 L is not below its true error beyond what the
/// references resolve, measured as tests/properties.rs measures it (against the answer
/// re-solved on 32x its mesh, less that reference's distance from 16x): 1.97 before the
/// stages of the order-6 defect and the order-8 estimate kept their strains' low part
/// (docs/numerics.md, "Why the estimate was low on some random robots").
#[test]
fn the_load_path_robot_gets_an_estimate_not_below_its_error() {
    let (robot, solution) = path_answer();
    let length = robot.length();
    let refined = |k: usize| common::on_split_mesh(&robot, &solution, k).unwrap();
    let (reference, check) = (refined(32), refined(16));
    let e = solution.report.error_estimate.unwrap();
    let position = |a: &Solution| (a.tip_position() - reference.tip_position()).norm();
    let rotation = |a: &Solution| so3::log(&(a.tip().R.transpose() * reference.tip().R)).norm();
    let beyond = [
        (position(&solution) - position(&check)) / e.tip_position,
        (rotation(&solution) - rotation(&check)) / e.tip_rotation,
    ];
    eprintln!(
        "true {:.3e} L (reference {:.3e}), {:.3e} rad ({:.3e}); estimate {:.3e} L, {:.3e} rad; beyond {beyond:.3?}",
        position(&solution) / length,
        position(&check) / length,
        rotation(&solution),
        rotation(&check),
        e.tip_position / length,
        e.tip_rotation
    );
    // The property's bound (tests/properties.rs): never above 1.
    assert!(beyond.iter().all(|&b| b <= 1.0), "{beyond:.3?}");
}

/// On uniform meshes robot 550's order-6 answer converges at order 6 down to errors of
/// 6e-11 L: its excess error at 1e-10 L (about 4e-12 L before the stages kept their
/// strains' low part) was not a lost order of the scheme.
#[test]
fn the_load_path_robot_converges_at_order_6() {
    let robot = path_robot();
    let tip = reference(&robot).tip_position();
    let meshes = [32, 40, 48, 64, 80];
    let errors: Vec<f64> = meshes
        .iter()
        .map(|&n| (order6_tip(&robot, n).0 - tip).norm() / robot.length())
        .collect();
    let orders: Vec<f64> = errors
        .windows(2)
        .zip(meshes.windows(2))
        .map(|(e, n)| (e[0] / e[1]).ln() / (n[1] as f64 / n[0] as f64).ln())
        .collect();
    let shown: Vec<String> = errors.iter().map(|e| format!("{e:.3e}")).collect();
    eprintln!("errors {shown:?} L, observed orders {orders:.2?}");
    // 5.5 as for S and H above (measured 5.7 to 6.3 here)
    assert!(orders.iter().all(|&q| q >= 5.5), "observed orders {orders:.2?}");
}

/// A slender rod (L / r = 2800) with self weight, a tip force and two helical tendons of 1.1
/// and -1.8 turns (tests/data/est14-guess-miss.toml, a robot of the 60-robot property run),
/// whose order-8 estimate was half its error at 1e-10 L until the sweeps of the order-8
/// residual treated both end points alike (docs/numerics.md, "An estimate low on a slender
/// rod: the sweeps' one-sided stages").
fn slender_helices() -> Robot {
    let path = "tests/data/est14-guess-miss.toml";
    tdcr::io::parse(&std::fs::read_to_string(path).unwrap(), path)
        .unwrap()
        .robot
}

/// The order-6 answer on the mesh through `points` (Newton to 1e-12 from `from` on it first)
/// and its reported estimate.
fn order6_on(robot: &Robot, from: &Solution, points: &[f64]) -> (tdcr::State, tdcr::ErrorEstimate) {
    order6_on_mesh(robot, from, Mesh::from_points(robot, points).unwrap(), 1e-12)
}

/// The order-6 tip state on `mesh` (Newton to `tolerance` from `from` on it first) and its
/// reported estimate.
fn order6_on_mesh(robot: &Robot, from: &Solution, mesh: Mesh, tolerance: f64) -> (tdcr::State, tdcr::ErrorEstimate) {
    let system = System::new(Model::new(robot), mesh);
    let mut ws = newton::Workspace::new(&system, LinearSolver::Blocks).unwrap();
    let mut x = guess::interpolate(&system.model, from, &system.mesh);
    let settings = newton::Settings {
        tolerance,
        max_iterations: 30,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = SolveReport::new(Method::Collocation);
    let (termination, _) = newton::run(&system, &mut ws, &mut x, &settings, &mut report);
    assert_eq!(termination, Termination::Converged);
    let (x6, estimate) = deferred::corrected(&system, &mut ws, &x, &mut report).unwrap().unwrap();
    (*x6.last().unwrap(), estimate)
}

/// `points` with every interval split into `k`.
fn split(points: &[f64], k: usize) -> Vec<f64> {
    let mut s: Vec<f64> = points
        .windows(2)
        .flat_map(|w| (0..k).map(move |i| w[0] + i as f64 / k as f64 * (w[1] - w[0])))
        .collect();
    s.push(*points.last().unwrap());
    s
}

/// A pair of errors, for messages.
fn sci(v: [f64; 2]) -> String {
    format!("[{:.3e}, {:.3e}]", v[0], v[1])
}

/// Position (relative to L) and rotation (rad) between two poses (p, R).
fn apart(a: (Vector3<f64>, Matrix3<f64>), b: &tdcr::State, length: f64) -> [f64; 2] {
    [(a.0 - b.p).norm() / length, so3::log(&(a.1.transpose() * b.R)).norm()]
}

/// On uniform meshes of the slender rod the order-8 estimate follows the order-6 answer's
/// error (against the order-6 answer on 4x the mesh, whose error is 4^6 times smaller):
/// error / raw estimate was 1.07, 1.88 and 3.5 on 100, 141 and 200 intervals while the
/// sweeps integrated from y0 alone (the estimate fell at order 7.6 where the error falls at
/// order 6).
#[test]
fn the_order_8_estimate_follows_the_error_on_a_slender_rod_with_two_helices() {
    let robot = slender_helices();
    let length = robot.length();
    for n in [100, 141, 200] {
        let solution = collocation::solve(&robot, &collocation::Options::fixed(n)).unwrap();
        let points: Vec<f64> = (0..=n).map(|k| length * k as f64 / n as f64).collect();
        let (tip, estimate) = order6_on(&robot, &solution, &points);
        let (reference, _) = order6_on(&robot, &solution, &split(&points, 4));
        // The estimate before its safety factor and its rounding term (L, rad).
        let raw = [
            (estimate.tip_position / length - deferred::ROUNDING) / deferred::SAFETY,
            (estimate.tip_rotation - deferred::ROUNDING) / deferred::SAFETY,
        ];
        let error = apart((tip.p, tip.R), &reference, length);
        let ratio = [error[0] / raw[0], error[1] / raw[1]];
        let (error_s, raw_s) = (sci(error), sci(raw));
        eprintln!("{n} intervals: error {error_s}, raw estimate {raw_s}, error / raw {ratio:.3?}");
        // 0.9 to 1.1: measured 0.99 to 1.01 (asymptotically exact; the reference's own error
        // is 1/4096 of the answer's)
        assert!(
            ratio.iter().all(|r| (0.9..=1.1).contains(r)),
            "{n} intervals: {ratio:.3?}"
        );
    }
}

/// At 1e-10 L the slender rod's reported estimate is above its error against the order-6
/// answers on 2x and 4x the answer's mesh (which agree to far less than that error): true /
/// reported was 1.14 (4.32e-11 L against 3.78e-11 L) while the sweeps integrated from y0
/// alone.
#[test]
fn the_slender_rod_with_two_helices_gets_an_estimate_above_its_error_at_1e_10() {
    let robot = slender_helices();
    let length = robot.length();
    let options = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    let mut points: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    points.dedup();
    let (twice, _) = order6_on(&robot, &solution, &split(&points, 2));
    let (reference, _) = order6_on(&robot, &solution, &split(&points, 4));
    let e = solution.report.error_estimate.unwrap();
    let error = apart((solution.tip_position(), solution.tip().R), &reference, length);
    let uncertainty = apart((twice.p, twice.R), &reference, length);
    let reported = [e.tip_position / length, e.tip_rotation];
    let (error_s, uncertainty_s, reported_s) = (sci(error), sci(uncertainty), sci(reported));
    eprintln!(
        "{} intervals: error {error_s} (2x vs 4x {uncertainty_s}), reported {reported_s}",
        solution.report.intervals
    );
    // The reference resolves the error: 2x and 4x agree to a tenth of it (measured 7e-13 L
    // against 4e-11 L before the fix).
    assert!(uncertainty[0] <= 0.1 * error[0].max(1e-12), "{uncertainty_s}");
    // The rule of issue 29: the reported estimate is never below the true error.
    assert!(
        error[0] + uncertainty[0] <= reported[0] && error[1] + uncertainty[1] <= reported[1],
        "error {error_s} (+{uncertainty_s}) against {reported_s}"
    );
}
