//! The comparison models: the point-moment tendon model (a switch on the robot, solved by
//! both solvers) and the closed-form constant-curvature model.

use tdcr::analysis::comparison::constant_curvature;
use tdcr::cases::analytic::arc_about_y;
use tdcr::{Robot, Rod, Routing, Tendon, TendonModel, cases, collocation, shooting};

#[test]
fn point_moment_model_of_one_tendon_is_an_unstretched_arc() {
    let rod = Rod::solid_circle(0.2, 5e-4, 200e9, 0.3);
    let ei = rod.section_at(0.0).section.kbt[1];
    let (offset, tension) = (0.005, 20.0);
    let mut robot = Robot::new(rod).with_tendon(Tendon::new(Routing::straight(offset, 0.0), tension));
    robot.tendon_model = TendonModel::PointMoment;
    let s = collocation::solve(&robot, &collocation::Options::fixed(64)).unwrap();
    // No tendon force on the backbone: no compression, v_z = 1, and curvature tau r / EI.
    let expected = arc_about_y(tension * offset / ei, 0.2, 1.0);
    // 1e-10 m: the arc is exact for this model; order-4 error at 64 intervals is far below
    assert!(
        (s.tip_position() - expected).norm() < 1e-10,
        "{:?} vs {expected:?}",
        s.tip_position()
    );
    let cc = constant_curvature(&robot, 4).unwrap();
    // 1e-10 m: the constant-curvature model is the same arc
    assert!((cc.last().unwrap().p - expected).norm() < 1e-10);
}

#[test]
fn point_moment_model_agrees_between_solvers_under_gravity() {
    for experiment in [cases::table2()[12], cases::table2()[30]] {
        let mut robot = experiment.robot();
        robot.tendon_model = TendonModel::PointMoment;
        let c = collocation::solve(&robot, &collocation::Options::fixed(128)).unwrap();
        let s = shooting::solve(
            &robot,
            &shooting::Options {
                integration_tolerance: 1e-12,
                ..Default::default()
            },
        )
        .unwrap();
        // 1e-8 m: as the coupled model's cross-check (tests/cross_check.rs)
        assert!(
            (c.tip_position() - s.tip_position()).norm() < 1e-8,
            "{}",
            experiment.label()
        );
    }
}

#[test]
fn how_far_the_simpler_models_are_on_the_prototype() {
    let distances = |robot: &Robot| {
        let full = collocation::solve(robot, &Default::default()).unwrap().tip_position();
        let mut pm = robot.clone();
        pm.tendon_model = TendonModel::PointMoment;
        let point_moment = collocation::solve(&pm, &Default::default()).unwrap().tip_position();
        let cc = constant_curvature(robot, 1).unwrap().last().unwrap().p;
        ((point_moment - full).norm(), (cc - full).norm())
    };
    // Case S, a straight tendon: its distributed load is exactly what a point moment at the
    // tip gives, except for the axial compression tau L / EA = 6.8 um; constant curvature
    // ignores the 0.11 N of self weight, which sags the rod by centimetres.
    let (pm, cc) = distances(&cases::case_s());
    eprintln!(
        "case S: point-moment {:.4} mm, constant curvature {:.2} mm from the coupled tip",
        pm * 1e3,
        cc * 1e3
    );
    let compression = 2.94 * cases::LENGTH / cases::prototype().rod.section_at(0.0).section.kse[2];
    // 20 %: the compression is most of the difference; gravity acts on slightly different shapes
    assert!((pm - compression).abs() < 0.2 * compression, "{pm} vs {compression}");
    assert!(cc > 0.01);
    // Case H, a helical tendon: the point-moment model misses the helix's distributed twist
    // and bending along the way and lands millimetres off.
    let (pm, cc) = distances(&cases::case_h());
    eprintln!(
        "case H: point-moment {:.2} mm, constant curvature {:.2} mm from the coupled tip",
        pm * 1e3,
        cc * 1e3
    );
    assert!(pm > 1e-3 && cc > 1e-3, "{pm} {cc}");
}
