//! The comparison models: the point-moment tendon model (a switch on the robot, solved by
//! both solvers) and the closed-form constant-curvature model.

use tdcr::analysis::comparison::constant_curvature;
use tdcr::cases::analytic::arc_about_y;
use tdcr::{Robot, Rod, RodModel, Routing, Tendon, TendonModel, cases, collocation, shooting};

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

/// A two-segment robot shaped like the comparison case of issue 27 (two segments of 0.2 m,
/// six straight tendons at 10 mm, three ending at mid-length), in our own material: a
/// nitinol-like rod of 0.5 mm radius and 50 GPa. `model` is the text of a `[model]` table
/// (or nothing), `tip` the tip force and moment.
fn two_segments(model: &str, tip: ([f64; 3], [f64; 3])) -> String {
    let (force, moment) = tip;
    let mut text = format!(
        "[rod]\nlength = 0.4\nouter_radius = 0.0005\nyoungs_modulus = 50e9\npoisson_ratio = 0.3\n\
         [loads]\ntip_force = {force:?}\ntip_moment = {moment:?}\n{model}\n"
    );
    // Segment 1 at 0, 120, 240 deg (tensions 3, 0, 0 N), segment 2 at 60, 180, 300 deg
    // (1, 0, 0 N): the offsets as a builder would type them, to 1e-12 m.
    let at = |deg: f64| {
        let a = deg.to_radians();
        (
            (0.01 * a.cos() * 1e12).round() / 1e12,
            (0.01 * a.sin() * 1e12).round() / 1e12,
        )
    };
    for (deg, tension, end) in [
        (0.0, 3.0, "end = 0.2\n"),
        (120.0, 0.0, "end = 0.2\n"),
        (240.0, 0.0, "end = 0.2\n"),
        (60.0, 1.0, ""),
        (180.0, 0.0, ""),
        (300.0, 0.0, ""),
    ] {
        let (x, y) = at(deg);
        text += &format!(
            "[[tendon]]\nrouting = {{ kind = \"straight\", x = {x:?}, y = {y:?} }}\ntension = {tension:?}\n{end}"
        );
    }
    text
}

/// The tip of `robot` solved by collocation at the default settings.
fn tip(robot: &Robot) -> (nalgebra::Vector3<f64>, nalgebra::Matrix3<f64>) {
    let s = collocation::solve(robot, &Default::default()).unwrap();
    (s.tip_position(), s.tip().R)
}

#[test]
fn model_table_sets_the_library_switches_bitwise() {
    let loaded = ([0.0, 0.3, -0.2], [0.01, 0.0, 0.0]);
    let plain = tdcr::io::parse(&two_segments("", loaded), "plain.toml").unwrap().robot;
    assert!(plain.corner_forces && plain.tendon_model == TendonModel::Coupled);
    assert_eq!(plain.rod_model, RodModel::Cosserat);
    for (table, set) in [
        (
            "[model]\ncorner_forces = false",
            (|r: &mut Robot| r.corner_forces = false) as fn(&mut Robot),
        ),
        ("[model]\ntendons = \"point_moment\"", |r| {
            r.tendon_model = TendonModel::PointMoment
        }),
        ("[model]\nrod = \"kirchhoff\"", |r| r.rod_model = RodModel::Kirchhoff),
        (
            "[model]\ncorner_forces = true\ntendons = \"coupled\"\nrod = \"cosserat\"",
            |_| {},
        ),
    ] {
        let file = tdcr::io::parse(&two_segments(table, loaded), "model.toml")
            .unwrap()
            .robot;
        let mut rust = plain.clone();
        set(&mut rust);
        assert_eq!(format!("{file:?}"), format!("{rust:?}"), "{table}");
        // Bitwise: the file sets the same switch the Rust field does, nothing else.
        assert_eq!(tip(&file), tip(&rust), "{table}");
    }
}

#[test]
fn the_papers_jump_conditions_differ_from_corner_forces_under_tip_loads() {
    let moved = |tip_load| {
        let paper = tdcr::io::parse(&two_segments("[model]\ncorner_forces = false", tip_load), "paper.toml");
        let corners = tdcr::io::parse(&two_segments("", tip_load), "corners.toml");
        (tip(&paper.unwrap().robot).0 - tip(&corners.unwrap().robot).0).norm()
    };
    let free = moved(([0.0; 3], [0.0; 3]));
    let loaded = moved(([0.0, 0.3, -0.2], [0.01, 0.0, 0.0]));
    eprintln!(
        "paper's jump conditions vs corner forces: tip {:.3e} m apart unloaded, {:.1} um with tip loads",
        free,
        loaded * 1e6
    );
    // 1e-6 m: a thousand times the solvers' agreement (tests/cross_check.rs, 1e-8 m), so the
    // corner forces of the continuing tendons are what moves the tip
    assert!(loaded > 1e-6, "{loaded}");
    // Unloaded, every straight tendon runs along the body z axis on both sides of the
    // termination (u x r_i lies along z, v = v_z e_z: docs/model.md, section 7), so no
    // tangent turns and there is no corner force: the two models agree to rounding (1e-12 m,
    // a few thousand ulps of the 0.4 m rod). Tip loads shear and twist the rod and turn them.
    assert!(free < 1e-12, "{free}");
}

#[test]
fn compare_models_solves_each_variant_as_its_switches_say() {
    use tdcr::analysis::comparison::{SHAPE_SAMPLES, Variant, compare_models};
    let text = two_segments("[model]\ncorner_forces = false", ([0.0, 0.3, -0.2], [0.01, 0.0, 0.0]));
    // The file's own [model] does not matter: each variant sets both switches.
    let robot = tdcr::io::parse(&text, "two.toml").unwrap().robot;
    let options = collocation::Options::default();
    let shapes = compare_models(&robot, &Variant::ALL, |r| collocation::solve(r, &options)).unwrap();
    let names: Vec<&str> = shapes.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "coupled",
            "point_moment",
            "constant_curvature",
            "paper_jumps",
            "kirchhoff"
        ]
    );
    let mut coupled = robot.clone();
    coupled.corner_forces = true;
    let mut point_moment = coupled.clone();
    point_moment.tendon_model = TendonModel::PointMoment;
    let mut kirchhoff = coupled.clone();
    kirchhoff.rod_model = RodModel::Kirchhoff;
    let cc = constant_curvature(&robot, 1).unwrap().last().unwrap().p;
    // Bitwise: the same robots solved with the same options, the same closed form.
    assert_eq!(shapes[0].tip_position(), tip(&coupled).0);
    assert_eq!(shapes[1].tip_position(), tip(&point_moment).0);
    assert_eq!(shapes[3].tip_position(), tip(&robot).0);
    assert_eq!(shapes[4].tip_position(), tip(&kirchhoff).0);
    // 1e-12 m: the closed form evaluated in one step or in many, rounding only
    assert!((shapes[2].tip_position() - cc).norm() < 1e-12);
    assert_eq!(shapes[0].states.len(), SHAPE_SAMPLES + 1);
    assert_eq!((shapes[0].tip_distance, shapes[0].tip_angle), (0.0, 0.0));
    for c in &shapes[1..] {
        assert_eq!(c.tip_distance, (c.tip_position() - shapes[0].tip_position()).norm());
        assert!(c.tip_angle > 0.0, "{}", c.name);
    }
    // The jump conditions move the tip by what the test above measures.
    assert!(
        (shapes[3].tip_distance - 350e-6).abs() < 1e-6,
        "{}",
        shapes[3].tip_distance
    );
}
