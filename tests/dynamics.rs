//! Stability from the linearized dynamics (docs/stability.md, "Loads that are not
//! conservative"): the cantilever's vibration frequencies, Euler's column by divergence
//! (agreeing with the conjugate-point test), Beck's column by flutter, a dead tip moment.

use nalgebra::Vector3;
use std::f64::consts::PI;
use tdcr::collocation::{self, DENSITY, Equilibrium, Options, vibration};
use tdcr::{Growth, Loads, Robot, Rod, Stability};

/// Issue 25's column: 0.5 m steel rod of radius 1 mm along +z, no gravity.
const LENGTH: f64 = 0.5;
const RADIUS: f64 = 1e-3;
const E: f64 = 200e9;

fn rod() -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, RADIUS, E, 0.3))
}

fn ei() -> f64 {
    E * PI * RADIUS.powi(4) / 4.0
}

fn nearest() -> Options {
    Options {
        equilibrium: Equilibrium::Nearest,
        ..Default::default()
    }
}

#[test]
fn the_unloaded_cantilever_vibrates_at_its_bending_frequencies() {
    let robot = rod();
    // Euler-Bernoulli: omega_k = (beta_k L)^2 sqrt(EI / (rho A L^4)), beta_1 L = 1.87510,
    // beta_2 L = 4.69409; each twice (the two bending planes of the round rod).
    let rho_a = DENSITY * PI * RADIUS * RADIUS;
    let omega = |beta_l: f64| beta_l * beta_l * (ei() / (rho_a * LENGTH.powi(4))).sqrt();
    let mut errors = Vec::new();
    for intervals in [16, 32, 64] {
        let options = Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        let solution = collocation::solve(&robot, &options).unwrap();
        let modes = vibration(&robot, &solution).unwrap();
        assert_eq!(modes.stability, Stability::Stable);
        for m in &modes.eigenvalues {
            // 1e-9: real up to Arnoldi's rounding
            assert!(m.im.abs() <= 1e-9 * m.norm(), "{m}");
        }
        let mu: Vec<f64> = modes.eigenvalues.iter().map(|m| m.re).collect();
        let error = |k: usize, beta_l: f64| (mu[k].sqrt() / omega(beta_l) - 1.0).abs();
        // The two planes give the same frequency (1e-9: rounding).
        assert!((mu[0] / mu[1] - 1.0).abs() < 1e-9 && (mu[2] / mu[3] - 1.0).abs() < 1e-9);
        errors.push([error(0, 1.875_104_07), error(2, 4.694_091_13)]);
    }
    eprintln!("relative frequency errors at 16, 32, 64 intervals: {errors:?}");
    for k in 0..2 {
        // Second order (the mass is interpolated linearly within an interval): halving h
        // divides the error by 4; 3.5 allows for rotary inertia and shear, which shift
        // omega by (r / L)^2 ~ 4e-6 and do not vanish with h.
        assert!(
            errors[0][k] / errors[1][k] > 3.5 && errors[1][k] / errors[2][k] > 3.5,
            "{errors:?}"
        );
    }
    // 1e-3 of the first two frequencies at 64 intervals
    assert!(errors[2][0] < 1e-3 && errors[2][1] < 1e-3, "{errors:?}");
}

/// Clamped-free column under a dead compressive tip load `p` (N).
fn dead_column(p: f64) -> Robot {
    rod().with_loads(Loads::none().with_tip_force(Vector3::new(0.0, 0.0, -p)))
}

#[test]
fn the_dead_load_column_diverges_past_euler_load_as_the_conjugate_point_test_says() {
    let p_cr = PI * PI * ei() / (4.0 * LENGTH * LENGTH);
    for (factor, stable) in [(0.99, true), (1.01, false), (1.5, false)] {
        let robot = dead_column(factor * p_cr);
        let solution = collocation::solve(&robot, &nearest()).unwrap();
        let modes = vibration(&robot, &solution).unwrap();
        assert_eq!(solution.report.stability.is_stable(), stable, "{factor}");
        match (&modes.stability, stable) {
            (Stability::Stable, true) => {}
            (
                Stability::Growing {
                    growth: Growth::Divergence,
                    ..
                },
                false,
            ) => {}
            (other, _) => panic!("{factor} P_cr: {other}"),
        }
    }
}

/// Beck's column: the clamped rod under a follower compressive tip force `p` (N), which
/// stays tangent to the tip.
fn beck(p: f64) -> Robot {
    rod().with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.0, 0.0, -p)))
}

/// The verdict of Beck's column at P L^2 / EI = `load` on a fixed mesh of `intervals`.
fn beck_verdict(load: f64, intervals: usize) -> Stability {
    let robot = beck(load * ei() / (LENGTH * LENGTH));
    let options = Options {
        intervals,
        tolerance: None,
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    // The follower force keeps the column straight: 1e-12 m, rounding.
    assert!(solution.tip_position().x.abs() < 1e-12 && solution.tip_position().y.abs() < 1e-12);
    let modes = vibration(&robot, &solution).unwrap();
    // The solve's verdict is the vibration's (from fewer Arnoldi steps: rates to 1e-8).
    match (&modes.stability, &solution.report.stability) {
        (Stability::Stable, Stability::Stable) => {}
        (Stability::Growing { growth: a, rate: x }, Stability::Growing { growth: b, rate: y }) => {
            assert_eq!(a.name(), b.name());
            assert!((x / y - 1.0).abs() < 1e-8, "{x} {y}");
        }
        (a, b) => panic!("vibration {a}, solve {b}"),
    }
    modes.stability
}

#[test]
fn becks_column_loses_stability_by_flutter_at_20_05() {
    // The flutter load of Beck's column (Euler-Bernoulli, uniform mass): P L^2 / EI =
    // 20.051. Bisection on the verdict, on 64 intervals.
    let (mut lo, mut hi) = (15.0, 25.0);
    assert!(beck_verdict(lo, 64).is_stable());
    for _ in 0..14 {
        let mid = 0.5 * (lo + hi);
        match beck_verdict(mid, 64) {
            Stability::Stable => lo = mid,
            Stability::Growing {
                growth: Growth::Flutter { .. },
                ..
            } => hi = mid,
            other => panic!("Beck's column at {mid}: {other}"),
        }
    }
    eprintln!("Beck's column flutters at P L^2 / EI = {lo:.5}..{hi:.5}");
    // 1 %: the bound (the mass's O(h^2) interpolation and rotary inertia move it
    // far less, below)
    assert!((0.5 * (lo + hi) / 20.051 - 1.0).abs() < 0.01);
    // No divergence before flutter: the straight column is stable at 19.8 and flutters
    // at 20.3 (1 % either side) with the default mesh, too.
    assert!(beck_verdict(0.99 * 20.051, 16).is_stable());
    assert!(matches!(
        beck_verdict(1.01 * 20.051, 16),
        Stability::Growing {
            growth: Growth::Flutter { .. },
            ..
        }
    ));
}

/// A bent robot under follower tip and distributed loads: collocation against shooting.
#[test]
fn follower_loads_agree_with_shooting() {
    use tdcr::{Routing, Tendon, shooting};
    let mut loads = Loads::none()
        .with_follower_tip_force(Vector3::new(0.3, -0.1, -0.5))
        .with_follower_tip_moment(Vector3::new(0.0, 0.02, 0.005));
    loads.follower_distributed_force = tdcr::Field::Constant(Vector3::new(0.0, 0.4, 0.0));
    let robot = rod()
        .with_tendon(Tendon::new(Routing::straight(0.01, 0.0), 20.0))
        .with_loads(loads);
    // 128 intervals: the order-4 error is then about 1e-9 m (tests/cross_check.rs)
    let c = collocation::solve(&robot, &Options::fixed(128)).unwrap();
    let shooting_options = shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    };
    let s = shooting::solve(&robot, &shooting_options).unwrap();
    let d = (c.tip_position() - s.tip_position()).norm();
    eprintln!("tip {:?}, collocation - shooting {d:e} m", c.tip_position());
    // 1e-8 m: both solvers' tolerances, 1e-10 L and tighter
    assert!(d < 1e-8, "{d}");
    // The tip wrench balances the follower loads at the solution.
    let e = tdcr::analysis::equilibrium::imbalance(&robot, &c);
    // 1e-8: the equilibrium check's tolerance for converged solves
    assert!(e.force < 1e-8 && e.moment < 1e-8, "{e:?}");
}

/// Robot r1 of issue 25 (tests/stability.rs): a 0.5 m steel rod of 1 mm radius standing
/// along +z, self weight, tendon 1 at (15 mm, 0) with 15 N, a tip force (0, 0, -3) N, and a
/// dead tip moment `moment` (N m, world frame).
fn r1(moment: Vector3<f64>) -> Robot {
    use tdcr::{Routing, Tendon};
    let mut robot = Robot::new(Rod::solid_circle(0.5, 0.001, 200e9, 0.3)).with_loads(
        Loads::self_weight(0.24, -Vector3::z())
            .with_tip_force(Vector3::new(0.0, 0.0, -3.0))
            .with_tip_moment(moment),
    );
    for (i, (x, y)) in [(0.015, 0.0), (0.0, 0.015), (-0.015, 0.0), (0.0, -0.015)]
        .into_iter()
        .enumerate()
    {
        robot = robot.with_tendon(Tendon::new(Routing::straight(x, y), if i == 0 { 15.0 } else { 0.0 }));
    }
    robot
}

/// The smallest eigenvalue of the symmetric part of the tip compliance d p(L) / d F(L) (m/N).
fn least_compliance(robot: &Robot, solution: &tdcr::Solution) -> f64 {
    let c = tdcr::collocation::sensitivity::tip_sensitivities(robot, solution)
        .unwrap()
        .compliance();
    let block = c.fixed_view::<3, 3>(0, 0).into_owned();
    (0.5 * (block + block.transpose())).symmetric_eigenvalues().min()
}

#[test]
fn a_dead_tip_moment_gets_the_verdict_of_the_tip_compliance_and_of_continuity() {
    // Without a moment the loads are conservative: the load path's state is stable, Newton's
    // nearest (an S-shape against the tendon) unstable (tests/stability.rs).
    let conservative = r1(Vector3::zeros());
    let path = collocation::solve(&conservative, &Default::default()).unwrap();
    let s_shape = collocation::solve(&conservative, &nearest()).unwrap();
    assert!(path.report.stability.is_stable());
    assert!(matches!(s_shape.report.stability, Stability::Unstable { .. }));
    let Stability::Growing {
        rate: conservative_rate,
        ..
    } = vibration(&conservative, &s_shape).unwrap().stability
    else {
        panic!("the S-shape diverges");
    };
    for moment in [
        Vector3::new(0.0, 1e-6, 0.0),
        Vector3::new(1e-4, 0.0, 0.0),
        Vector3::new(0.02, 0.01, 0.0),
    ] {
        let robot = r1(moment);
        for (from, options) in [("load path", Options::default()), ("nearest", nearest())] {
            let solution = collocation::solve(&robot, &options).unwrap();
            let verdict = &solution.report.stability;
            let least = least_compliance(&robot, &solution);
            eprintln!("moment {moment:?} {from}: {verdict}, least compliance {least:.3e} m/N");
            // A negative compliance decides (the tip moves against a force): unstable,
            // by divergence. A stable verdict has no negative compliance beyond rounding
            // (1e-6 m/N against compliances of 1e-2 to 0.4 m/N).
            if least < -1e-6 {
                assert!(
                    matches!(
                        verdict,
                        Stability::Growing {
                            growth: Growth::Divergence,
                            ..
                        }
                    ),
                    "{verdict}"
                );
            } else {
                assert!(verdict.is_stable(), "{verdict}");
            }
            // The default returns the stable state loading from rest reaches: an unstable
            // direct answer sends it down the load path, as for conservative loads.
            if from == "load path" {
                assert!(verdict.is_stable(), "{verdict}");
            }
            // Continuity: a moment of 1e-6 N m barely changes the S-shape's growth rate
            // (1e-3 relative; the moment is 1e-6 of the tip force's moment arm 0.4 m x 3 N).
            if moment.norm() <= 1e-6 && from == "nearest" {
                let Stability::Growing { rate, .. } = verdict else {
                    unreachable!()
                };
                assert!(
                    (rate / conservative_rate - 1.0).abs() < 1e-3,
                    "{rate} against {conservative_rate}"
                );
            }
        }
    }
}

/// The dynamics verdict of a direct solve is computed once: the equilibrium choice asks for
/// the verdict of Newton's answer and the end of the solve asks again for the same state,
/// which gets the kept verdict (one linearization at the answer, not two). It is the
/// verdict `vibration` finds at the returned state from scratch (its kind: the rate comes
/// from a longer Arnoldi run there), default settings, case S under a dead tip moment,
/// cold and warm.
#[test]
fn a_dead_moment_verdict_is_computed_once_per_state() {
    let mut robot = tdcr::cases::case_s();
    robot.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
    let cold = collocation::solve(&robot, &Options::default()).unwrap();
    let mut warm_robot = robot.clone();
    warm_robot.loads.tip_moment *= 1.01;
    let warm = collocation::solve_from(&warm_robot, &Options::default(), &cold).unwrap();
    // The warm start's test of the predicted step linearizes at the start once more.
    for (robot, solution, start) in [(&robot, &cold, 0), (&warm_robot, &warm, 1)] {
        let report = &solution.report;
        assert_eq!(report.path, tdcr::PathTaken::Direct, "{:?}", report.path);
        assert_eq!(
            report.evaluations.jacobian,
            start + report.newton_steps + 1,
            "Newton's Jacobians and one at the answer ({start} at the start)"
        );
        let fresh = vibration(robot, solution).unwrap().stability;
        assert_eq!(
            std::mem::discriminant(&report.stability),
            std::mem::discriminant(&fresh),
            "{:?} against {fresh:?}",
            report.stability
        );
    }
}

/// A solve's verdict stops Arnoldi once the lowest modes have settled (docs/stability.md,
/// "Cost"); `vibration` runs 24 steps. On the prototype with dead tip moments of up to
/// 5 mN m in random directions and random tensions (flutter and stable states, from the
/// load path and Newton's nearest root), both give the same verdict and the same rate.
#[test]
fn an_early_stopped_verdict_is_the_longer_runs() {
    let mut state = 31u64;
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut kinds = [0usize; 2];
    for _ in 0..8 {
        let mut robot = tdcr::cases::prototype();
        for t in robot.tendons.iter_mut() {
            t.set_tension(3.0 * uniform());
        }
        let m = 5e-3 * uniform();
        robot.loads.tip_moment = Vector3::new(m * (uniform() - 0.5), m * (uniform() - 0.5), m * (uniform() - 0.5));
        for options in [Options::default(), nearest()] {
            let solution = collocation::solve(&robot, &options).unwrap();
            let modes = vibration(&robot, &solution).unwrap();
            match (&solution.report.stability, &modes.stability) {
                (Stability::Stable, Stability::Stable) => kinds[0] += 1,
                (Stability::Growing { growth: a, rate: x }, Stability::Growing { growth: b, rate: y }) => {
                    assert_eq!(a.name(), b.name());
                    // Both runs settle the growing pair far below the rounding of a rate
                    // (residual estimates under 1e-10 of the Ritz value): 1e-8 leaves room
                    // for slow flutter, whose rate is a small difference (measured 8e-11).
                    assert!((x / y - 1.0).abs() < 1e-8, "{x} {y}");
                    kinds[1] += 1;
                }
                (a, b) => panic!("solve {a}, vibration {b} (eigenvalues {:?})", &modes.eigenvalues[..4]),
            }
        }
    }
    // Both kinds occur: the comparison is not vacuous.
    assert!(kinds[0] > 0 && kinds[1] > 0, "{kinds:?}");
}
