//! Heavily loaded cases where shooting gives up and collocation (with load continuation)
//! still converges, verified by global equilibrium and mesh refinement.

use tdcr::guess::InitialGuess;
use tdcr::{cases, collocation, equilibrium, shooting};

/// A 1 m rod with the prototype's cross-section under its own weight, with a 40 N tendon at
/// 8 mm: curvature about tau r / (E I) = 76 1/m, a coil of about twelve turns.
fn coil() -> tdcr::Robot {
    let mut robot = cases::prototype();
    robot.rod.length = 1.0;
    robot.tendons[0].tension = 40.0;
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
    let direct = collocation::solve(
        &robot,
        &collocation::Options {
            intervals: 512,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(direct.report.load_steps, 1);
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
    robot.tendons[0].tension = 20.0;
    let a = collocation::solve(
        &robot,
        &collocation::Options {
            intervals: 128,
            ..Default::default()
        },
    )
    .unwrap();
    let b = collocation::solve(
        &robot,
        &collocation::Options {
            intervals: 256,
            ..Default::default()
        },
    )
    .unwrap();
    let angle = a.nodes.iter().map(|n| n.u.norm()).fold(0.0, f64::max) * robot.length();
    assert!(angle > 500f64.to_radians(), "total bend {angle:.2} rad");
    // 1e-8 m: order 4 from 128 to 256 intervals (measured change about 5e-10 m)
    assert!((a.tip_position() - b.tip_position()).norm() < 1e-8);
    // 1e-9: at 256 intervals the discretization error in equilibrium is about 8e-11
    assert!(equilibrium::imbalance(&robot, &b).max() < 1e-9);
}
