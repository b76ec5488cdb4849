//! Bad input is rejected before any iteration, by every solver, with the right
//! `tdcr::Error` variant and a message that names the field, the value and the fix.

mod common;

use common::try_solve_all;
use nalgebra::{Matrix3, Vector3};
use tdcr::{Error, Loads, Robot, Rod, Routing, Tendon, collocation};

const LENGTH: f64 = 0.2;
const RADIUS: f64 = 5e-4;
const MODULUS: f64 = 200e9;
const POISSON: f64 = 0.3;
const OFFSET: f64 = 0.005;

/// A valid robot: two straight tendons under tension.
fn good() -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, RADIUS, MODULUS, POISSON))
        .with_tendon(Tendon::new(Routing::straight(OFFSET, 0.0), 1.0))
        .with_tendon(Tendon::new(Routing::straight(0.0, OFFSET), 2.0))
}

/// Asserts that validation and every solver return `Error::InvalidInput` for `field`,
/// with every fragment in the message.
fn assert_invalid(robot: &Robot, field: &str, fragments: &[&str]) {
    let mut results = vec![("validate", robot.validate().map(|_| ()))];
    results.extend(try_solve_all(robot).into_iter().map(|(name, r)| (name, r.map(|_| ()))));
    for (name, result) in results {
        match result {
            Err(e @ Error::InvalidInput { .. }) => {
                let Error::InvalidInput { field: got, .. } = &e else {
                    unreachable!()
                };
                assert_eq!(got, field, "{name}: {e}");
                let message = e.to_string();
                assert!(message.contains(&format!("`{field}`")), "{name}: {message}");
                for fragment in fragments {
                    assert!(message.contains(fragment), "{name}: no `{fragment}` in: {message}");
                }
            }
            other => panic!("{name}: expected InvalidInput for {field}, got {other:?}"),
        }
    }
}

#[test]
fn a_good_robot_is_accepted() {
    assert!(good().validate().is_ok());
    for (name, result) in try_solve_all(&good()) {
        assert!(result.is_ok(), "{name}: {result:?}");
    }
}

#[test]
fn bad_length_is_rejected() {
    for length in [f64::NAN, 0.0, -0.1, f64::INFINITY] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(length, RADIUS, MODULUS, POISSON);
        assert_invalid(
            &robot,
            "rod.length",
            &[&format!("is {length}"), "positive, finite length"],
        );
    }
}

#[test]
fn bad_radius_modulus_or_poisson_ratio_is_rejected_by_name() {
    for radius in [0.0, -RADIUS, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, radius, MODULUS, POISSON);
        assert_invalid(&robot, "rod.outer_radius", &["positive, finite value in m"]);
    }
    for modulus in [0.0, -MODULUS, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, RADIUS, modulus, POISSON);
        assert_invalid(&robot, "rod.youngs_modulus", &["positive, finite value in Pa"]);
    }
    for nu in [-1.0, 0.6, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, RADIUS, MODULUS, nu);
        assert_invalid(&robot, "rod.poisson_ratio", &["(-1, 0.5]"]);
    }
    let mut robot = good();
    robot.rod = Rod::tube(LENGTH, RADIUS, RADIUS, MODULUS, POISSON);
    assert_invalid(&robot, "rod.inner_radius", &["below the outer radius"]);
}

#[test]
fn zero_explicit_stiffness_is_rejected() {
    let mut robot = good();
    robot.rod = Rod::new(LENGTH, tdcr::Section::explicit(1e4, 1e4, 0.0, 1e-3, 1e-3));
    assert_invalid(
        &robot,
        "rod.stiffness",
        &["kbt (EIxx, EIyy, GJ)", "positive and finite"],
    );
}

#[test]
fn bad_tension_is_rejected() {
    for tension in [f64::NAN, -1.0, f64::INFINITY] {
        let mut robot = good();
        robot.tendons[1].tension = tension;
        assert_invalid(
            &robot,
            "tendons[1].tension",
            &[&format!("is {tension} N"), "can only pull"],
        );
    }
}

#[test]
fn non_finite_loads_are_rejected() {
    let robot = good().with_loads(Loads::none().with_tip_force(Vector3::new(0.0, f64::NAN, 0.0)));
    assert_invalid(&robot, "loads.tip_force", &["(0, NaN, 0)", "finite number"]);
    let robot = good().with_loads(Loads::none().with_tip_moment(Vector3::new(f64::INFINITY, 0.0, 0.0)));
    assert_invalid(&robot, "loads.tip_moment", &["(inf, 0, 0)", "finite number"]);
    let robot = good().with_loads(Loads::self_weight(f64::NAN, -Vector3::z()));
    assert_invalid(&robot, "loads.distributed_force", &["NaN", "finite number"]);
}

#[test]
fn point_load_off_the_rod_is_rejected() {
    for s in [0.0, -0.01, 1.5 * LENGTH, f64::NAN] {
        let mut robot = good();
        robot.loads.point.push(tdcr::PointLoad {
            s,
            force: Vector3::x(),
            moment: Vector3::zeros(),
        });
        assert_invalid(&robot, "loads.point[0].s", &["outside (0, 0.2]"]);
    }
}

#[test]
fn bad_base_pose_is_rejected() {
    let mut nan = Matrix3::identity();
    nan[(1, 2)] = f64::NAN;
    let stretched = Matrix3::identity() * 1.01;
    let sheared = Matrix3::new(1.0, 0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    for rotation in [nan, stretched, sheared, reflection] {
        let robot = good().with_base(Vector3::zeros(), rotation);
        assert_invalid(
            &robot,
            "base_rotation",
            &["is not a rotation", "orthonormal matrix with determinant +1"],
        );
    }
    let robot = good().with_base(Vector3::new(0.0, f64::NAN, 0.0), Matrix3::identity());
    assert_invalid(&robot, "base_position", &["finite number"]);
}

#[test]
fn termination_outside_the_rod_is_rejected() {
    for end in [0.0, -0.05, LENGTH * 1.001, f64::NAN, f64::INFINITY] {
        let mut robot = good();
        robot.tendons[1] = robot.tendons[1].clone().ending_at(end);
        assert_invalid(
            &robot,
            "tendons[1].termination",
            &[&format!("is s = {end} m, outside (0, 0.2]"), "at most the rod length"],
        );
    }
}

#[test]
fn routing_with_vanishing_tangent_is_rejected() {
    // A straight tendon at (x, 0) on a rod precurved by u* = (0, 1/x, 0): in the unloaded
    // shape its path tangent u* x r + r' + v* = (0, 0, -1) + (0, 0, 1) vanishes everywhere.
    let rod =
        Rod::solid_circle(LENGTH, RADIUS, MODULUS, POISSON).with_precurvature(Vector3::new(0.0, 1.0 / OFFSET, 0.0));
    let robot = Robot::new(rod)
        .with_tendon(Tendon::new(Routing::straight(0.0, OFFSET), 1.0))
        .with_tendon(Tendon::new(Routing::straight(OFFSET, 0.0), 1.0));
    let mut results = vec![("validate", robot.validate().map(|_| ()))];
    results.extend(try_solve_all(&robot).into_iter().map(|(name, r)| (name, r.map(|_| ()))));
    for (name, result) in results {
        match result {
            Err(e @ Error::SingularRouting { tendon: 1, .. }) => {
                let message = e.to_string();
                assert!(
                    message.contains("tendon 1 has a vanishing path tangent"),
                    "{name}: {message}"
                );
                assert!(message.contains("cancel the axial strain"), "{name}: {message}");
            }
            other => panic!("{name}: expected SingularRouting for tendon 1, got {other:?}"),
        }
    }
}

#[test]
fn routing_leaving_the_cross_section_or_not_finite_is_rejected() {
    let mut robot = good();
    robot.tendons[0].routing = Routing::custom(|_, _| tdcr::RoutingPoint {
        r: Vector3::new(OFFSET, 0.0, 1e-3),
        r_s: Vector3::zeros(),
        r_ss: Vector3::zeros(),
    });
    assert_invalid(&robot, "tendons[0].routing", &["has a z component", "z must be 0"]);
    robot.tendons[0].routing = Routing::helical(f64::NAN, 1.0, 0.0);
    assert_invalid(&robot, "tendons[0].routing", &["is not finite", "give finite offsets"]);
}

#[test]
fn meshes_beyond_the_caps_are_bad_input() {
    let robot = good();
    let too_many = collocation::Options::fixed(10_000);
    let err = collocation::solve(&robot, &too_many).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.intervals"),
        "{err}"
    );
    assert!(err.to_string().contains("raise `max_intervals`"));
    let huge = collocation::Options {
        max_intervals: usize::MAX,
        ..Default::default()
    };
    let err = collocation::solve(&robot, &huge).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.max_intervals"),
        "{err}"
    );
}
