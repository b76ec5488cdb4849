//! Collocation against the independent shooting solver: both share only the pointwise
//! physics (`equations`), so agreement tests the discretizations and the solvers.

use nalgebra::Vector3;
use tdcr::{cases, collocation, shooting};

fn fine() -> collocation::Options {
    // 128 intervals: the order-4 error on the prototype is about 1.4e-9 m (case H)
    collocation::Options::fixed(128)
}

fn tight() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

#[test]
fn all_table2_configurations_agree_with_shooting() {
    let mut worst: f64 = 0.0;
    for experiment in cases::table2() {
        let robot = experiment.robot();
        let c = collocation::solve(&robot, &fine()).unwrap();
        let s = shooting::solve(&robot, &tight()).unwrap();
        let d = (c.tip_position() - s.tip_position()).norm();
        // 1e-8 m: collocation error ~1.4e-9 m at 128 intervals plus shooting at 1e-12
        assert!(d < 1e-8, "{}: tips differ by {d:.3e} m", experiment.label());
        // 1e-12: R is updated on SO(3) through exp, never projected
        assert!(c.max_orthonormality_error() < 1e-12);
        worst = worst.max(d);
    }
    eprintln!("worst Table 2 tip difference {worst:.3e} m");
}

#[test]
fn reference_tips_are_reproduced() {
    for (robot, tip) in [(cases::case_s(), cases::TIP_S), (cases::case_h(), cases::TIP_H)] {
        let c = collocation::solve(&robot, &fine()).unwrap();
        // 3e-9 m: references agree to ~2e-10 m, collocation error ~1.4e-9 m
        assert!((c.tip_position() - Vector3::from(tip)).norm() < 3e-9);
    }
}

#[test]
fn two_segment_robot_agrees_with_shooting() {
    // Tendon 1 ends at L/2, the helical tendon 5 at L: a jump mid-way, with the corner
    // force of the helix where tendon 1 ends.
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(2.0);
    robot.tendons[0].termination = Some(cases::LENGTH / 2.0);
    robot.tendons[4].set_tension(3.0);
    robot.loads.tip_force = Vector3::new(0.0, 0.0, -0.098);
    for corners in [true, false] {
        robot.corner_forces = corners;
        let c = collocation::solve(&robot, &fine()).unwrap();
        let s = shooting::solve(&robot, &tight()).unwrap();
        let d = (c.tip_position() - s.tip_position()).norm();
        // 1e-8 m: as for Table 2
        assert!(d < 1e-8, "corner forces {corners}: tips differ by {d:.3e} m");
    }
}

#[test]
fn interior_point_load_agrees_with_shooting() {
    let mut robot = cases::case_s();
    robot.loads.point.push(tdcr::PointLoad {
        s: 0.1,
        force: Vector3::new(0.0, 0.05, -0.1),
        moment: Vector3::new(0.001, 0.0, 0.0),
    });
    let c = collocation::solve(&robot, &fine()).unwrap();
    let s = shooting::solve(&robot, &tight()).unwrap();
    // 1e-8 m: as for Table 2
    assert!((c.tip_position() - s.tip_position()).norm() < 1e-8);
}
