//! Heavily loaded cases where shooting gives up and collocation (with load continuation)
//! still converges, verified by global equilibrium and mesh refinement.

use tdcr::analysis::equilibrium;
use tdcr::collocation::InitialGuess;
use tdcr::{cases, collocation, shooting};

/// A 1 m rod with the prototype's cross-section under its own weight, with a 40 N tendon at
/// 8 mm: curvature about tau r / (E I) = 76 1/m, a coil of about twelve turns.
fn coil() -> tdcr::Robot {
    let mut robot = cases::prototype();
    robot.rod.length = 1.0;
    robot.tendons[0].set_tension(40.0);
    robot
}

#[test]
fn twelve_turn_coil_converges_where_shooting_from_the_unloaded_rod_fails() {
    let robot = coil();
    // Shooting as the field's codes run it, from the unloaded rod, gives up.
    let unloaded = shooting::Options {
        initial_guess: InitialGuess::Unloaded,
        ..Default::default()
    };
    assert!(matches!(
        shooting::solve(&robot, &unloaded),
        Err(tdcr::Error::NotConverged { .. })
    ));
    // Collocation from the same start converges through load continuation.
    let options = |intervals| collocation::Options {
        intervals,
        tolerance: None,
        initial_guess: InitialGuess::Unloaded,
        ..Default::default()
    };
    let coarse = collocation::solve(&robot, &options(256)).unwrap();
    let fine = collocation::solve(&robot, &options(512)).unwrap();
    assert!(fine.report.load_steps > 1, "expected load continuation");
    let change = (fine.tip_position() - coarse.tip_position()).norm();
    eprintln!(
        "coil: tip change 256 -> 512 intervals {change:.2e} m, load steps {}",
        fine.report.load_steps
    );
    // 1e-5 m: at order 4 the 512-interval error is about change / 15; the coil's tip
    // moves centimetres, so this bounds the relative error near 1e-4 at worst
    assert!(change < 1e-5);
    // The default rigid-equilibrium start needs no continuation and lands on the same shape.
    let direct = collocation::solve(&robot, &collocation::Options::fixed(512)).unwrap();
    assert_eq!(direct.report.load_steps, 0);
    // 1e-9 m: the same discrete problem solved to a residual of 1e-11
    assert!((direct.tip_position() - fine.tip_position()).norm() < 1e-9);
    let (ec, ef) = (
        equilibrium::imbalance(&robot, &coarse).max(),
        equilibrium::imbalance(&robot, &fine).max(),
    );
    eprintln!("coil: equilibrium imbalance {ec:.2e} (256), {ef:.2e} (512)");
    // Equilibrium holds to the scheme's discretization error: it must fall like h^4
    // (8x is a margin under 16x) and be small in absolute terms at 512 intervals.
    assert!(ef < ec / 8.0 && ef < 1e-6, "imbalance {ec:.2e} -> {ef:.2e}");
    for sol in [&coarse, &fine] {
        // 1e-12: R is updated on SO(3) through exp, never projected
        assert!(sol.max_orthonormality_error() < 1e-12);
    }
}

#[test]
fn prototype_bent_past_500_degrees() {
    // 20 N on tendon 1 bends the prototype about 9 rad.
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(20.0);
    let a = collocation::solve(&robot, &collocation::Options::fixed(128)).unwrap();
    let b = collocation::solve(&robot, &collocation::Options::fixed(256)).unwrap();
    let angle = a.nodes.iter().map(|n| n.u.norm()).fold(0.0, f64::max) * robot.length();
    assert!(angle > 500f64.to_radians(), "total bend {angle:.2} rad");
    // 1e-8 m: order 4 from 128 to 256 intervals (measured change about 5e-10 m)
    assert!((a.tip_position() - b.tip_position()).norm() < 1e-8);
    // 1e-9: at 256 intervals the discretization error in equilibrium is about 8e-11
    assert!(equilibrium::imbalance(&robot, &b).max() < 1e-9);
}

// The hard-case catalogue of docs/validation.md: each case converges (with continuation if
// needed), verified by adaptive refinement and equilibrium, or fails with a typed error that
// says why.

/// Adaptive to 1e-7 m at the tip; asserts the estimate, equilibrium and orthonormality.
fn converges(robot: &tdcr::Robot) -> tdcr::Solution {
    let tolerance = 1e-7 / robot.length();
    let options = collocation::Options {
        intervals: 64,
        tolerance: Some(tolerance),
        max_intervals: 4096,
        ..Default::default()
    };
    let solution = collocation::solve(robot, &options).unwrap();
    assert_eq!(solution.report.tolerance_met, Some(true));
    assert!(solution.report.error_estimate.unwrap().tip_position <= 1e-7);
    // 1e-6: equilibrium holds to the discretization error of a mesh good to 1e-7 m at the tip
    let e = equilibrium::imbalance(robot, &solution);
    assert!(e.max() < 1e-6, "imbalance {e:?}");
    // 1e-12: R is updated on SO(3) through exp, never projected
    assert!(solution.max_orthonormality_error() < 1e-12);
    solution
}

fn prototype_without_gravity(tension: f64) -> tdcr::Robot {
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    robot.tendons[0].set_tension(tension);
    robot
}

#[test]
fn tension_near_the_routing_geometric_limit() {
    // A straight tendon at r bends the rod to curvature about tau r / EI; at 1/r the bend
    // radius reaches the tendon offset and the tendon path collapses (|p_i'| -> 0): tau = EI / r^2.
    let ei = cases::prototype().rod.section_at(0.0).section.kbt[0];
    let limit = ei / cases::TENDON_OFFSET.powi(2);
    let near = converges(&prototype_without_gravity(0.97 * limit));
    let curvature = near.nodes[near.nodes.len() / 2].u.norm();
    assert!(
        curvature * cases::TENDON_OFFSET > 0.9,
        "curvature {curvature} should approach 1/r"
    );
    // Past the limit there is no solution: a typed error that says where the load path ended.
    let err = collocation::solve(
        &prototype_without_gravity(1.1 * limit),
        &collocation::Options::fixed(64),
    )
    .unwrap_err();
    assert!(matches!(err, tdcr::Error::NotConverged { .. }), "{err}");
    assert!(err.to_string().contains("the path stalled"), "{err}");
}

#[test]
fn one_metre_rod_under_its_own_weight() {
    let mut robot = cases::prototype();
    robot.rod.length = 1.0;
    let s = converges(&robot);
    // It hangs: the tip is far below the base.
    assert!(s.tip_position().z < -0.9);
}

#[test]
fn very_stiff_shear_and_extension() {
    let ei = cases::prototype().rod.section_at(0.0).section.kbt[0];
    let l = cases::LENGTH;
    let mut robot = cases::case_s();
    robot.rod = tdcr::Rod::new(
        l,
        tdcr::Section::explicit(1e8 * ei / (l * l), 1e8 * ei / (l * l), ei, ei, 0.77 * ei),
    );
    let s = converges(&robot);
    // 1e-5 m: the inextensible limit of case S differs from the steel rod by its EA effect
    assert!((s.tip_position() - nalgebra::Vector3::from(cases::TIP_S)).norm() < 1e-5);
}

#[test]
fn nearly_zero_stiffness_fails_with_a_reason() {
    // E = 1 MPa: the self weight is 3e5 times what the rod can carry (w L^3 / EI); a hanging
    // string, which the mesh cannot resolve.
    let mut robot = cases::case_s();
    robot.rod = tdcr::Rod::solid_circle(cases::LENGTH, cases::RADIUS, 1e6, cases::POISSON_RATIO);
    let err = collocation::solve(&robot, &collocation::Options::fixed(64)).unwrap_err();
    assert!(matches!(err, tdcr::Error::NotConverged { .. }), "{err}");
}

#[test]
fn ten_helical_turns() {
    let mut robot = cases::prototype();
    robot.tendons[4] = tdcr::Tendon::new(tdcr::Routing::helical(cases::TENDON_OFFSET, 10.0, 0.0), 4.91);
    converges(&robot);
}

#[test]
fn tendons_ending_a_micrometre_apart_and_next_to_the_base() {
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(2.0);
    robot.tendons[0].termination = Some(0.1);
    robot.tendons[1].set_tension(2.0);
    robot.tendons[1].termination = Some(0.1 + 1e-6);
    converges(&robot);
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(2.0);
    robot.tendons[0].termination = Some(1e-4);
    robot.tendons[4].set_tension(3.0);
    converges(&robot);
}

#[test]
fn compressive_tip_load_beyond_euler_buckling() {
    // Past the Euler load pi^2 EI / (4 L^2) = 0.18 N the nearly straight shape is an
    // unstable equilibrium; the default solve returns the stable, buckled one.
    for force in [0.1, 1.0] {
        let mut robot = tdcr::Robot::new(cases::prototype().rod.clone());
        robot.loads.tip_force = nalgebra::Vector3::new(0.001, 0.0, -force);
        let solution = converges(&robot);
        assert!(
            solution.report.stability.is_stable(),
            "{force} N: {}",
            solution.report.stability
        );
        // Buckled past the Euler load: the tip well off the axis (measured 129.5 mm at 1 N).
        assert_eq!(solution.tip_position().x > 0.05, force > 0.5, "{force} N");
    }
}

/// The band where the field's shooting codes fail: a 0.5 m rod, 1 mm radius, E = 200 GPa,
/// four straight tendons at 15 mm, steel self weight, one tendon pulled.
#[test]
fn till_style_robot_from_15_to_300_newtons() {
    for tension in [15.0, 50.0, 100.0, 150.0, 200.0, 300.0] {
        let rod = tdcr::Rod::solid_circle(0.5, 0.001, 200e9, 0.3);
        let weight = 8000.0 * 9.81 * std::f64::consts::PI * 1e-6;
        let mut robot = tdcr::Robot::new(rod)
            .with_loads(tdcr::Loads::self_weight(weight, -nalgebra::Vector3::z()))
            .with_base(nalgebra::Vector3::zeros(), cases::prototype_base_rotation());
        for k in 0..4 {
            let a = std::f64::consts::FRAC_PI_2 * k as f64;
            let routing = tdcr::Routing::straight(0.015 * a.cos(), 0.015 * a.sin());
            robot = robot.with_tendon(tdcr::Tendon::new(routing, if k == 0 { tension } else { 0.0 }));
        }
        converges(&robot);
        // tdcr's own shooting, started from the unloaded rod as the field's codes are, fails.
        let unloaded = shooting::Options {
            initial_guess: InitialGuess::Unloaded,
            ..Default::default()
        };
        assert!(shooting::solve(&robot, &unloaded).is_err(), "{tension} N");
    }
}
