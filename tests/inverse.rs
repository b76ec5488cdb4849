//! Inverse statics on the paper's prototype: targets made by forward solves with known
//! tensions are recovered, an out-of-reach target is reported as such with the right
//! distance, a too-small tension bound leaves the tensions at the bound, and invalid inputs
//! name their field.
//!
//! Every forward solve uses the default collocation options (32 intervals, scaled residual
//! 1e-11), the same as the inverse solver's, so a target made by a forward solve is exactly
//! reachable on the inverse solver's discretization; the tip noise of a solve is about
//! 1e-8 m (tests/sensitivity.rs), well below the 1e-6 m tolerance.

use nalgebra::{DMatrix, Vector3};
use std::time::Instant;
use tdcr::fit::inverse::{Bound, InverseOptions, InverseSolution, Target, solve_tensions};
use tdcr::fit::lm::FitTermination;
use tdcr::{Error, Robot, Solution, cases, collocation};

/// Upper tension bound (N) of the recovery tests: above every tension used to make the
/// targets, about the paper's largest (4.91 N).
const MAX_TENSION: f64 = 5.0;

/// Forward-solve noise on the tip (m): 1e-8 (tests/sensitivity.rs measures 3e-12 at a
/// scaled residual of 1e-12; the default 1e-11 can leave up to about 1e-8).
const SOLVE_NOISE: f64 = 1e-8;

fn forward(robot: &Robot) -> Solution {
    collocation::solve(robot, &Default::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The prototype with the given tensions (N) on tendons by 0-based index.
fn prototype_with(tensions: &[(usize, f64)]) -> Robot {
    let mut robot = cases::prototype();
    for &(i, t) in tensions {
        robot.tendons[i].set_tension(t);
    }
    robot
}

fn run(robot: &Robot, target: &Target, options: &InverseOptions, label: &str) -> InverseSolution {
    let start = Instant::now();
    let found = solve_tensions(robot, target, options).unwrap_or_else(|e| panic!("{label}: {e}"));
    println!(
        "{label}: residual {:.3e} m, {} iterations, {} forward solves, {} jacobians, {:.1} ms, tensions {:?}, {}",
        found.residual,
        found.iterations,
        found.forward_solves,
        found.jacobians,
        start.elapsed().as_secs_f64() * 1e3,
        found.tensions,
        found.termination
    );
    found
}

/// Recovers position-only targets made with two tendons pulled, from all-slack tensions.
/// With five tendons the tensions are not unique, so the tips are compared: the achieved
/// tip, and the tip of a fresh cold forward solve at the recovered tensions.
#[test]
fn recovers_position_targets() {
    let options = InverseOptions::new(MAX_TENSION);
    for truth in [vec![(1, 1.5), (4, 2.0)], vec![(0, 1.0), (3, 2.5)]] {
        let goal = forward(&prototype_with(&truth)).tip_position();
        let found = run(
            &cases::prototype(),
            &Target::position(goal),
            &options,
            &format!("position {truth:?}"),
        );
        assert!(found.reachable, "{}", found.explain());
        assert_eq!(found.termination, FitTermination::Reached);
        assert!(found.explain().contains("target reached"), "{}", found.explain());
        let achieved = (found.tip_position() - goal).norm();
        assert!(achieved <= options.tolerance, "tip {achieved:.3e} m off");
        assert!((found.residual - achieved).abs() <= 1e-15);
        assert!(found.tensions.iter().all(|&t| (0.0..=MAX_TENSION).contains(&t)));
        // A cold solve at the recovered tensions lands within the tolerance plus solve noise.
        let again = forward(&prototype_with(
            &found.tensions.iter().copied().enumerate().collect::<Vec<_>>(),
        ));
        let reproduced = (again.tip_position() - goal).norm();
        assert!(
            reproduced <= options.tolerance + SOLVE_NOISE,
            "reproduced {reproduced:.3e} m off"
        );
        // Iteration counts only as upper bounds: Gauss-Newton from slack takes a handful.
        assert!(found.iterations <= 20, "{} iterations", found.iterations);
    }
}

/// Recovers a full-pose target (position and orientation): six equations, five tensions,
/// exactly reachable because a forward solve made it.
#[test]
fn recovers_pose_target() {
    let options = InverseOptions::new(MAX_TENSION);
    let truth = forward(&prototype_with(&[(1, 1.5), (4, 2.0)]));
    let tip = truth.tip();
    let found = run(
        &cases::prototype(),
        &Target::pose(tip.p, tip.R),
        &options,
        "pose T2 1.5 N + T5 2.0 N",
    );
    assert!(found.reachable, "{}", found.explain());
    assert!(found.position_error <= options.tolerance);
    // The weighted residual bounds the angle times the weight (the rod length, 0.242 m).
    let angle = found.orientation_error.unwrap_or(f64::NAN);
    assert!(angle * cases::LENGTH <= options.tolerance, "angle {angle:.3e} rad");
}

/// A two-tendon robot (the prototype's tendons 1 and 2, straight at 90 degrees) has a
/// unique solution for a position target, so the tensions themselves are recovered. The
/// tension error is bounded by the tip error over the smallest singular value of
/// d(tip)/d(tension): |dtau| <= |dp| / sigma_min with |dp| <= tolerance + noise; twice
/// that allows for the linearization over the (tiny) error.
#[test]
fn recovers_unique_tensions() {
    let mut robot = cases::prototype();
    robot.tendons.truncate(2);
    let truth = [1.2, 2.1];
    let mut loaded = robot.clone();
    for (t, &v) in loaded.tendons.iter_mut().zip(&truth) {
        t.set_tension(v);
    }
    let solution = forward(&loaded);
    let goal = solution.tip_position();
    let options = InverseOptions::new(MAX_TENSION);
    let found = run(&robot, &Target::position(goal), &options, "two tendons");
    assert!(found.reachable, "{}", found.explain());
    let sens = tdcr::collocation::sensitivity::tip_sensitivities(&loaded, &solution).unwrap_or_else(|e| panic!("{e}"));
    let position: DMatrix<f64> = sens.tension.rows(0, 3).into_owned();
    let sigma_min = position.singular_values().min();
    let bound = 2.0 * (options.tolerance + SOLVE_NOISE) / sigma_min;
    for (i, (&got, &want)) in found.tensions.iter().zip(&truth).enumerate() {
        println!("tendon {i}: {got:.9} N vs {want} N (bound {bound:.2e} N, sigma_min {sigma_min:.3e} m/N)");
        assert!((got - want).abs() <= bound, "tendon {i}: {got} N vs {want} N");
    }
}

/// A target 1 m in front of the base (along the rod's base direction, world +x) is out of
/// reach of a 0.242 m rod. The distance from the base minus the rod length, 0.758 m, bounds
/// the tip error from below (tendons only shorten the rod); the best the tendons can do is
/// lift the sagging rod straight, which leaves it within 2 mm of that bound (the residual
/// self-weight sag and the compression, measured below 1 mm).
#[test]
fn reports_unreachable_target() {
    let robot = cases::prototype();
    let target = Target::position(Vector3::new(1.0, 0.0, 0.0));
    let options = InverseOptions::new(MAX_TENSION);
    let found = run(&robot, &target, &options, "1 m away");
    assert!(!found.reachable);
    assert_ne!(found.termination, FitTermination::Reached);
    let lower = 1.0 - cases::LENGTH;
    assert!(
        found.residual >= lower - 1e-9 && found.residual <= lower + 2e-3,
        "residual {} vs bound {lower}",
        found.residual
    );
    // It did its best: far better than the all-slack start (sagging by about 5 cm).
    assert!(found.residual < found.history[0]);
    let text = found.explain();
    println!("{text}");
    assert!(text.contains("unreachable"), "{text}");
    assert!(text.contains("farther than the rod length"), "{text}");
    assert!(text.contains("slack"), "{text}");

    // Behind the base, 0.3 m away: out of reach by at least 0.3 - 0.242 = 0.058 m. The
    // iteration finds a local minimum (the rod would have to curl back), so only the lower
    // bound and the report are asserted.
    let behind = Target::position(Vector3::new(-0.3, 0.0, 0.0));
    let found = run(&robot, &behind, &options, "0.3 m behind");
    assert!(!found.reachable);
    assert!(
        found.residual >= 0.3 - cases::LENGTH - 1e-9,
        "residual {}",
        found.residual
    );
    let text = found.explain();
    println!("{text}");
    assert!(text.contains("unreachable"), "{text}");
}

/// With a bound too small for a target that 3 N on tendon 2 reaches, the tension stops at
/// the bound and the result says so.
#[test]
fn stops_at_tension_bound() {
    let goal = forward(&prototype_with(&[(1, 3.0)])).tip_position();
    let options = InverseOptions {
        max_tension: 1.5,
        ..Default::default()
    };
    let found = run(&cases::prototype(), &Target::position(goal), &options, "bound 1.5 N");
    assert!(!found.reachable);
    assert_eq!(found.tensions[1], 1.5, "{:?}", found.tensions);
    assert_eq!(found.bounds[1], Bound::Saturated);
    assert!(found.tensions.iter().all(|&t| (0.0..=1.5).contains(&t)));
    let text = found.explain();
    println!("{text}");
    assert!(text.contains("unreachable"), "{text}");
    // Tendons are numbered from 1, as on the command line and in robot files.
    assert!(text.contains("at the upper bound 1.5 N: tendon 2"), "{text}");

    // Only tendon 2 free: the other tendons are held slack and the answer is exactly the
    // bound, the closest tip along the one-tendon path.
    let options = InverseOptions {
        free_tendons: Some(vec![1]),
        ..options
    };
    let found = run(
        &cases::prototype(),
        &Target::position(goal),
        &options,
        "bound 1.5 N, tendon 2 only",
    );
    assert!(!found.reachable);
    assert_eq!(found.tensions, vec![0.0, 1.5, 0.0, 0.0, 0.0]);
    assert_eq!(
        found.bounds,
        vec![Bound::Held, Bound::Saturated, Bound::Held, Bound::Held, Bound::Held]
    );
}

/// Starting at the answer costs one forward solve and no step.
#[test]
fn starts_at_answer() {
    let robot = prototype_with(&[(1, 1.5), (4, 2.0)]);
    let goal = forward(&robot).tip_position();
    let found = run(
        &robot,
        &Target::position(goal),
        &InverseOptions::new(MAX_TENSION),
        "at answer",
    );
    assert!(found.reachable);
    assert_eq!((found.iterations, found.forward_solves, found.jacobians), (0, 1, 0));
    assert_eq!(found.tensions, vec![0.0, 1.5, 0.0, 0.0, 2.0]);
}

fn invalid_field(robot: &Robot, target: &Target, options: &InverseOptions) -> (String, String) {
    match solve_tensions(robot, target, options) {
        Err(e @ Error::InvalidInput { .. }) => {
            let Error::InvalidInput { ref field, .. } = e else {
                unreachable!()
            };
            (field.clone(), e.to_string())
        }
        Err(e) => panic!("expected InvalidInput, got {e}"),
        Ok(_) => panic!("expected InvalidInput, got a solution"),
    }
}

#[test]
fn rejects_invalid_inputs() {
    let robot = cases::prototype();
    let good = Target::position(Vector3::new(0.2, 0.0, -0.05));
    let options = InverseOptions::new(MAX_TENSION);
    let cases: Vec<(&str, Target, InverseOptions)> = vec![
        (
            "target.position",
            Target::position(Vector3::new(f64::NAN, 0.0, 0.0)),
            options.clone(),
        ),
        (
            "target.position",
            Target::position(Vector3::new(0.0, f64::INFINITY, 0.0)),
            options.clone(),
        ),
        (
            "target.orientation",
            Target::pose(good.position, nalgebra::Matrix3::identity() * 2.0),
            options.clone(),
        ),
        (
            "target.orientation",
            Target::pose(good.position, -nalgebra::Matrix3::identity()),
            options.clone(),
        ),
        ("options.max_tension", good.clone(), InverseOptions::default()),
        ("options.max_tension", good.clone(), InverseOptions::new(-1.0)),
        ("options.max_tension", good.clone(), InverseOptions::new(f64::INFINITY)),
        (
            "options.tolerance",
            good.clone(),
            InverseOptions {
                tolerance: 0.0,
                ..options.clone()
            },
        ),
        (
            "options.tolerance",
            good.clone(),
            InverseOptions {
                tolerance: f64::NAN,
                ..options.clone()
            },
        ),
        (
            "options.max_iterations",
            good.clone(),
            InverseOptions {
                max_iterations: 0,
                ..options.clone()
            },
        ),
        (
            "options.orientation_weight",
            good.clone(),
            InverseOptions {
                orientation_weight: Some(-0.1),
                ..options.clone()
            },
        ),
        (
            "options.solver.residual_tolerance",
            good.clone(),
            InverseOptions {
                solver: collocation::Options {
                    residual_tolerance: 1e-6,
                    ..Default::default()
                },
                ..options.clone()
            },
        ),
        (
            "options.free_tendons[1]",
            good.clone(),
            InverseOptions {
                free_tendons: Some(vec![0, 5]),
                ..options.clone()
            },
        ),
        (
            "options.free_tendons[2]",
            good.clone(),
            InverseOptions {
                free_tendons: Some(vec![0, 1, 0]),
                ..options.clone()
            },
        ),
        (
            "options.free_tendons",
            good.clone(),
            InverseOptions {
                free_tendons: Some(vec![]),
                ..options.clone()
            },
        ),
    ];
    for (field, target, options) in cases {
        let (got, message) = invalid_field(&robot, &target, &options);
        assert_eq!(got, field, "{message}");
        assert!(message.contains(field), "{message}");
    }
    let (got, message) = invalid_field(&Robot::new(robot.rod.clone()), &good, &options);
    assert_eq!(got, "robot.tendons", "{message}");
    // The robot is validated too: a negative tension on a held tendon names it.
    let mut bad = robot.clone();
    bad.tendons[3].set_tension(-1.0);
    let (got, message) = invalid_field(&bad, &good, &options);
    assert_eq!(got, "tendons[3].tension", "{message}");
}

/// Every termination sentence is distinct and non-empty.
#[test]
fn termination_sentences() {
    let all = [
        FitTermination::Reached,
        FitTermination::Stationary,
        FitTermination::NoProgress,
        FitTermination::MaxIterations,
    ];
    let texts: Vec<String> = all.iter().map(ToString::to_string).collect();
    for (i, t) in texts.iter().enumerate() {
        assert!(t.len() > 20, "{t}");
        assert!(texts[..i].iter().all(|u| u != t));
    }
    assert!(texts[0].starts_with("reached"));
    assert!(texts[3].contains("iteration limit"));
}
