//! Friction on displacement-controlled tendons (docs/friction.md section 3b): the pull-in
//! fixes the base-entry tension through the stretch of the varying tension. Round trips
//! against tension solves, both solvers, global equilibrium, order, slack, mu -> 0.

use tdcr::{Error, Friction, Motion, Robot, cases, collocation, shooting};

fn tight() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

/// The prototype's tendon 1 at 2.94 N (case S) with friction `mu` in `motion`, elastic
/// (E_t A_t = 2000 N, 0.1 m free length: the stretch some 3 % of the pull-in) or rigid.
fn rough_s(mu: f64, motion: Motion, elastic: bool) -> Robot {
    let mut robot = cases::case_s();
    let t = &mut robot.tendons[0];
    t.friction = Some(Friction {
        coefficient: mu,
        motion,
    });
    if elastic {
        t.stiffness = Some(2000.0);
        t.free_length = 0.1;
    }
    robot
}

/// `robot` with tendon `i` driven by the pull-in `q` (m) instead of its tension.
fn pulled(robot: &Robot, i: usize, q: f64) -> Robot {
    let mut r = robot.clone();
    r.tendons[i].set_displacement(q);
    r
}

#[test]
fn a_pull_in_gives_back_the_tension_that_reported_it() {
    for (motion, elastic) in [(Motion::Pull, true), (Motion::Release, true), (Motion::Pull, false)] {
        let robot = rough_s(0.1, motion, elastic);
        let by_tension = tdcr::solve(&robot, &Default::default()).unwrap();
        let q = by_tension.tendons[0].displacement;
        let by_pull_in = tdcr::solve(&pulled(&robot, 0, q), &Default::default()).unwrap();
        let (a, b) = (&by_tension.tendons[0], &by_pull_in.tendons[0]);
        // 1e-9 relative: the brief's consistency bound (Newton on the tension stops at 1e-12 T)
        assert!(
            (b.tension / a.tension - 1.0).abs() < 1e-9,
            "{motion:?} elastic {elastic}: {} N from the pull-in against {} N",
            b.tension,
            a.tension
        );
        assert_eq!(b.displacement, q);
        assert_eq!(b.slack, 0.0);
        assert!(b.delivered_tension < b.tension || motion == Motion::Release);
        let d = (by_pull_in.tip_position() - by_tension.tip_position()).norm();
        // 1e-9 m: the tensions agree to 1e-9 relative and a newton moves the tip ~0.1 m
        assert!(d < 1e-9, "tips differ by {d:.2e} m");
    }
}

#[test]
fn friction_with_a_pull_in_holds_global_equilibrium_and_agrees_with_shooting() {
    for motion in [Motion::Pull, Motion::Release] {
        let robot = pulled(&rough_s(0.1, motion, true), 0, 0.004);
        let c = collocation::solve(&robot, &collocation::Options::fixed(128)).unwrap();
        let sh = shooting::solve(&robot, &tight()).unwrap();
        let d = (c.tip_position() - sh.tip_position()).norm();
        // 1e-8 m: as for tension control (collocation at 128 intervals ~1.4e-9 m, shooting at 1e-12)
        let (a, b) = (&c.tendons[0], &sh.tendons[0]);
        assert!(d < 1e-8, "{motion:?}: tips differ by {d:.3e} m");
        // 1e-8 relative (measured 1.2e-9): shooting's pull-in is the node quadrature over its
        // adaptive steps, resolved to about 1e-12 m of a gap that moves 1.3e-4 m per newton
        assert!(
            (a.tension / b.tension - 1.0).abs() < 1e-8,
            "tensions {} vs {}",
            a.tension,
            b.tension
        );
        let solved = tdcr::solve(&robot, &Default::default()).unwrap();
        for solution in [&solved, &sh] {
            // The balance of the solved tensions (a pull-in's tension is the solve's).
            let tensioned = robot.with_tensions(&solution.tensions());
            let e = tdcr::analysis::equilibrium::imbalance(&tensioned, solution);
            // 1e-8: the bound with tension control (tests/friction.rs)
            assert!(e.max() < 1e-8, "imbalance {e:?}");
        }
        assert!(matches!(solved.report.stability, tdcr::Stability::Unknown { .. }));
    }
}

#[test]
fn friction_with_a_pull_in_converges_at_order_four() {
    let robot = pulled(&rough_s(0.1, Motion::Pull, true), 0, 0.004);
    // A fine collocation solve as the reference: shooting's pull-in carries the quadrature
    // error of its adaptive steps (about 1e-9 relative in the tension); 512 intervals are
    // 4096 times closer than 64.
    let reference = collocation::solve(&robot, &collocation::Options::fixed(512)).unwrap();
    let error = |intervals: usize| {
        let c = collocation::solve(&robot, &collocation::Options::fixed(intervals)).unwrap();
        (
            (c.tip_position() - reference.tip_position()).norm(),
            (c.tendons[0].tension - reference.tendons[0].tension).abs(),
        )
    };
    let (e16, e32, e64, e128) = (error(16), error(32), error(64), error(128));
    let order = (e16.0 / e32.0).log2();
    // 3.7..4.5: the bound with tension control (h^4 with the pre-asymptotic drift of 16 -> 32)
    assert!(
        (3.7..4.5).contains(&order),
        "tip order {order:.2} ({:.2e} -> {:.2e})",
        e16.0,
        e32.0
    );
    let order = (e64.1 / e128.1).log2();
    // 3.5..4.5 from 64 to 128 intervals (measured 3.79): the pull-in's node quadrature
    // approaches h^4 slowly, as without friction (ratios 10.9, 6.4, 11.6, 14.0 from 8 to
    // 128 intervals for mu = 0; 12.7, 6.1, 11.5, 13.9 for mu = 0.1)
    assert!(
        (3.5..4.5).contains(&order),
        "tension order {order:.2} ({:.2e} -> {:.2e})",
        e64.1,
        e128.1
    );
}

#[test]
fn vanishing_friction_is_todays_displacement_control() {
    let smooth = pulled(&rough_s(0.0, Motion::Pull, true), 0, 0.004);
    let mut frictionless = smooth.clone();
    frictionless.tendons[0].friction = None;
    let want = tdcr::solve(&frictionless, &Default::default()).unwrap();
    // mu = 0 is the frictionless tendon, solved by the same code.
    let zero = tdcr::solve(&smooth, &Default::default()).unwrap();
    assert_eq!(zero.tip_position(), want.tip_position());
    // mu = 1e-12 takes the friction path (Newton on the tension around solves with
    // friction), on the mesh the frictionless solve chose: its tip moves by about
    // mu theta of the tip's 0.1 m per newton, 1e-13 m.
    let points: Vec<f64> = want.nodes.iter().map(|n| n.s).collect();
    let options = collocation::Options {
        mesh: Some(points),
        tolerance: None,
        residual_tolerance: 1e-14,
        ..Default::default()
    };
    let want = collocation::solve(&frictionless, &options).unwrap();
    let tiny = pulled(&rough_s(1e-12, Motion::Pull, true), 0, 0.004);
    let got = collocation::solve(&tiny, &options).unwrap();
    let d = (got.tip_position() - want.tip_position()).norm();
    // 1e-12 m: the friction effect at 1e-12 is ~1e-13 m and the solves are resolved below
    assert!(d < 1e-12, "tip moved by {d:.2e} m");
    assert!((got.tendons[0].tension / want.tendons[0].tension - 1.0).abs() < 1e-10);
}

#[test]
fn a_pull_in_short_of_the_slack_leaves_the_tendon_slack() {
    // Tendon 1 pulled in 4 mm and tendon 3 (opposite) with friction let out 10 mm: the
    // bending lengthens tendon 3's path by about 4 mm, less than it was let out, so it is slack.
    let mut robot = pulled(&rough_s(0.1, Motion::Pull, true), 0, 0.004);
    robot.tendons[2].set_displacement(-0.01);
    robot.tendons[2].friction = Some(Friction::pull(0.1));
    let solution = tdcr::solve(&robot, &Default::default()).unwrap();
    let t = &solution.tendons[2];
    assert_eq!(t.tension, 0.0);
    assert!(t.slack > 0.0, "slack {}", t.slack);
    assert!(solution.tendons[0].tension > 0.0);
    // Tendon 3 loads nothing: the same shape as without it.
    let mut alone = robot.clone();
    alone.tendons[2] = cases::case_s().tendons[2].clone();
    let want = tdcr::solve(&alone, &Default::default()).unwrap();
    let d = (solution.tip_position() - want.tip_position()).norm();
    // 1e-9 m: the two solves meet the default tolerance on different meshes
    assert!(d < 1e-9, "tips differ by {d:.2e} m");
}

#[test]
fn held_pull_in_derivatives_with_friction_are_refused() {
    let robot = pulled(&rough_s(0.1, Motion::Pull, true), 0, 0.004);
    let solution = tdcr::solve(&robot, &Default::default()).unwrap();
    match tdcr::tip_sensitivities(&robot, &solution) {
        Err(Error::InvalidInput { field, hint, .. }) => {
            assert_eq!(field, "tendons[0].displacement");
            assert!(hint.contains("tension"), "{hint}");
        }
        other => panic!("expected a refusal, got {:?}", other.map(|_| ())),
    }
}
