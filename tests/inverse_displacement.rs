//! Inverse statics in actuator space (`solve_displacements`): targets made by forward solves
//! with known pull-ins are recovered from the unactuated robot, agree with the tension-space
//! inverse, an antagonist that must be slack is reported slack at exactly 0 N, a stroke too
//! short leaves the actuator at its bound, and bad bounds are typed errors naming the field.
//!
//! Forward solves use the inverse solver's own options (32 fixed intervals, scaled residual
//! 1e-11), so a target made by a forward solve is exactly reachable on its discretization.

use tdcr::fit::inverse::{Bound, InverseOptions, InverseSolution, Target, solve_displacements, solve_tensions};
use tdcr::fit::lm::FitTermination;
use tdcr::{Error, Robot, Routing, Tendon, cases, collocation};

/// Stroke of the recovery tests (m): 1 cm, above every pull-in used to make the targets.
const STROKE: f64 = 0.01;

fn forward(robot: &Robot, options: &InverseOptions) -> tdcr::Solution {
    collocation::solve(robot, &options.solver).unwrap_or_else(|e| panic!("{e}"))
}

fn run(robot: &Robot, target: &Target, options: &InverseOptions, label: &str) -> InverseSolution {
    let found = solve_displacements(robot, target, options).unwrap_or_else(|e| panic!("{label}: {e}"));
    println!(
        "{label}: residual {:.3e} m, {} iterations, {} forward solves, {} jacobians, pull-ins {:?} m, tensions {:?} N, {:?}: {}",
        found.residual,
        found.iterations,
        found.forward_solves,
        found.jacobians,
        found.displacements,
        found.tensions,
        found.bounds,
        found.termination
    );
    found
}

/// The prototype with the pull-ins (m) on tendons by 0-based index.
fn prototype_pulled(pull_ins: &[(usize, f64)]) -> Robot {
    let mut robot = cases::prototype();
    for &(i, q) in pull_ins {
        robot.tendons[i].set_displacement(q);
    }
    robot
}

/// One actuator: its pull-in is unique and recovered to the tip tolerance over the tip's
/// sensitivity; the tension-space inverse on the same target gives the same tension.
#[test]
fn recovers_one_pull_in_and_agrees_with_the_tension_inverse() {
    let options = InverseOptions {
        free_tendons: Some(vec![1]),
        ..InverseOptions::displacements(0.0, STROKE)
    };
    let truth = 0.003;
    let made = forward(&prototype_pulled(&[(1, truth)]), &options);
    let goal = made.tip_position();
    let found = run(&cases::prototype(), &Target::position(goal), &options, "one pull-in");
    assert!(found.reachable, "{}", found.explain());
    assert!((found.tip_position() - goal).norm() <= options.tolerance);
    // 1e-6 m: the 1e-6 m tip tolerance over a tip sensitivity above 1 m/m (about 25 m/m
    // here: 3 mm of pull-in moves the tip by about 8 cm).
    assert!(
        (found.displacements[1] - truth).abs() <= 1e-6,
        "pull-in {} m against {truth} m",
        found.displacements[1]
    );
    assert_eq!(
        found.bounds,
        vec![Bound::Held, Bound::Inside, Bound::Held, Bound::Held, Bound::Held]
    );
    let by_tension = solve_tensions(
        &cases::prototype(),
        &Target::position(goal),
        &InverseOptions {
            free_tendons: Some(vec![1]),
            ..InverseOptions::new(5.0)
        },
    )
    .unwrap();
    assert!(by_tension.reachable);
    // 1e-3 relative: both tips are within 1e-6 m of the target, and the tip moves about
    // 4 cm per newton at 1.5 N, so the tensions agree to about 1e-4 N.
    let relative = (by_tension.tensions[1] - found.tensions[1]).abs() / made.tensions()[1];
    assert!(
        relative <= 1e-3,
        "tension {} N (pull-ins) vs {} N (tensions), made with {} N",
        found.tensions[1],
        by_tension.tensions[1],
        made.tensions()[1]
    );
}

/// All five actuators free, a target made by pulling two tendons: reached from the
/// unactuated robot with every pull-in within the stroke. The three tendons the target did not pull
/// end slack or taut; the tip is what is unique.
#[test]
fn reaches_a_two_actuator_target_with_all_five_free() {
    // Letting out allowed: at rest the rod sags and the upper tendons' paths lengthen.
    let options = InverseOptions::displacements(-STROKE, STROKE);
    let mut made = cases::prototype();
    made.tendons[0].set_tension(1.0);
    made.tendons[3].set_tension(2.5);
    let goal = forward(&made, &options).tip_position();
    let found = run(&cases::prototype(), &Target::position(goal), &options, "five free");
    assert!(found.reachable, "{}", found.explain());
    assert!((found.tip_position() - goal).norm() <= options.tolerance);
    assert!(found.displacements.iter().all(|&q| (-STROKE..=STROKE).contains(&q)));
    assert!(found.tensions.iter().all(|&t| t >= 0.0));
    assert!(found.bounds.iter().all(|&b| b != Bound::Held));
}

/// An antagonistic pair at +-8 mm, weightless: a target bent towards tendon 1 is reached with
/// tendon 2 slack at exactly 0 N, starting with both actuators at 0 (both just taut at 0 N,
/// where the pulling derivatives are one-sided) and free.
#[test]
fn a_pair_reaches_a_bend_with_the_antagonist_slack() {
    let pair = |q1: f64, q2: f64| {
        let mut robot = cases::prototype();
        robot.loads = tdcr::Loads::none();
        robot.tendons = vec![
            Tendon::pulled(Routing::straight(0.008, 0.0), q1),
            Tendon::pulled(Routing::straight(-0.008, 0.0), q2),
        ];
        robot
    };
    let options = InverseOptions::displacements(-STROKE, STROKE);
    let made = forward(&pair(0.004, -0.008), &options);
    assert_eq!(made.tendons[1].tension, 0.0, "the target's antagonist is slack");
    let found = run(
        &pair(0.0, 0.0),
        &Target::position(made.tip_position()),
        &options,
        "pair",
    );
    assert!(found.reachable, "{}", found.explain());
    // The antagonist's pull-in holds it just taut at 0 N: its tension is 0 to the solve's
    // resolution, 1e-10 of its 2.2 N tension scale (tests/actuation.rs).
    assert!(
        found.tensions[1] <= 1e-9,
        "the antagonist must be slack: {} N",
        found.tensions[1]
    );
    assert_eq!(found.bounds, vec![Bound::Inside, Bound::Slack]);
    // As above: 1e-6 m of tip over about 25 m/m.
    assert!(
        (found.displacements[0] - 0.004).abs() <= 1e-6,
        "{:?}",
        found.displacements
    );
    assert!(found.explain().contains("slack (0 N): tendon 2"), "{}", found.explain());
}

/// A stroke shorter than the target needs: the actuator ends at its bound, the target is
/// reported unreachable, and the explanation names the bound.
#[test]
fn a_short_stroke_saturates() {
    let options = InverseOptions {
        free_tendons: Some(vec![1]),
        ..InverseOptions::displacements(0.0, 0.002)
    };
    let goal = forward(&prototype_pulled(&[(1, 0.003)]), &options).tip_position();
    let found = run(&cases::prototype(), &Target::position(goal), &options, "short stroke");
    assert!(!found.reachable);
    assert_eq!(found.termination, FitTermination::Stationary, "{}", found.explain());
    assert_eq!(found.displacements[1], 0.002);
    assert_eq!(found.bounds[1], Bound::Saturated);
    let text = found.explain();
    assert!(
        text.contains("pull-ins in [0, 0.002 m]") && text.contains("at the upper bound 0.002 m: tendon 2"),
        "{text}"
    );
}

/// Bad bounds are typed errors naming the field.
#[test]
fn bad_bounds_name_their_field() {
    let goal = Target::position(nalgebra::Vector3::new(0.0, 0.0, 0.2));
    let robot = cases::prototype();
    for (field, options) in [
        ("options.max_displacement", InverseOptions::default()),
        ("options.max_displacement", InverseOptions::displacements(0.0, -0.001)),
        ("options.max_displacement", InverseOptions::displacements(0.0, f64::NAN)),
        (
            "options.min_displacement",
            InverseOptions::displacements(f64::NEG_INFINITY, 0.01),
        ),
        // A stroke beyond the 0.242 m path of an inextensible tendon.
        ("options.max_displacement", InverseOptions::displacements(0.0, 0.3)),
    ] {
        match solve_displacements(&robot, &goal, &options) {
            Err(Error::InvalidInput { field: f, .. }) => assert_eq!(f, field, "{options:?}"),
            other => panic!(
                "{options:?}: expected an error on {field}, got {:?}",
                other.map(|s| s.explain())
            ),
        }
    }
}

/// A stroke that cannot let out the tendons the rod's own weight lengthens: at rest tendon 3
/// needs -2.06 mm; held at 0 it fights tendon 1 at 224 N, past 0.9 of their geometric limit
/// (66 N). A typed error that says so and what to do, not an iteration from that state.
#[test]
fn a_stroke_that_cannot_let_out_is_an_error_that_says_so() {
    let goal = Target::position(nalgebra::Vector3::new(0.2, 0.0, -0.05));
    match solve_displacements(&cases::prototype(), &goal, &InverseOptions::displacements(0.0, STROKE)) {
        Err(Error::InvalidInput { field, problem, hint }) => {
            assert_eq!(field, "options.min_displacement");
            assert!(
                problem.contains("tendon 3") && problem.contains("past its limit"),
                "{problem}"
            );
            assert!(hint.contains("min_displacement = -max_displacement"), "{hint}");
        }
        other => panic!("expected an error, got {:?}", other.map(|s| s.explain())),
    }
}

/// With friction (tendon 2 elastic, mu = 0.1, pull) the pull-in rows of the linearization
/// are dQ/dtau of the varying tension's stretch (docs/friction.md section 3b): a pull-in is
/// recovered, and a stroke too short saturates at its bound.
#[test]
fn recovers_a_pull_in_with_friction_and_saturates_a_short_stroke() {
    let mut rough = cases::prototype();
    let t = &mut rough.tendons[1];
    t.friction = Some(tdcr::Friction::pull(0.1));
    t.stiffness = Some(2000.0);
    t.free_length = 0.1;
    let options = InverseOptions {
        free_tendons: Some(vec![1]),
        ..InverseOptions::displacements(0.0, STROKE)
    };
    let truth = 0.006;
    let mut pulled = rough.clone();
    pulled.tendons[1].set_displacement(truth);
    let goal = forward(&pulled, &options).tip_position();
    let found = run(&rough, &Target::position(goal), &options, "one pull-in with friction");
    assert!(found.reachable, "{}", found.explain());
    assert!((found.tip_position() - goal).norm() <= options.tolerance);
    // 1e-6 m: the 1e-6 m tip tolerance over a tip sensitivity above 1 m/m, as without friction
    assert!(
        (found.displacements[1] - truth).abs() <= 1e-6,
        "pull-in {} m against {truth} m",
        found.displacements[1]
    );
    let short = InverseOptions {
        free_tendons: Some(vec![1]),
        ..InverseOptions::displacements(0.0, 0.004)
    };
    let found = run(&rough, &Target::position(goal), &short, "short stroke with friction");
    assert!(!found.reachable);
    assert_eq!(found.termination, FitTermination::Stationary, "{}", found.explain());
    assert_eq!(found.displacements[1], 0.004);
    assert_eq!(found.bounds[1], Bound::Saturated);
}
