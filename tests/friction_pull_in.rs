//! Friction on displacement-controlled tendons (docs/friction.md section 3b): the pull-in
//! fixes the base-entry tension through the stretch of the varying tension. Round trips
//! against tension solves, both solvers, global equilibrium, order, slack, mu -> 0.

use nalgebra::Vector6;
use tdcr::{Friction, Motion, Parameter, Robot, cases, collocation, shooting};

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
        // The verdict with the pull-in held (docs/stability.md, "Tendons with friction").
        assert_eq!(solved.report.stability, tdcr::Stability::Stable, "{motion:?}");
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
    // The pull-in derivatives hold tendon 1 and leave the slack tendon 3 slack (its tension
    // at 0 N with friction has no direction, and needs none): zeros for it.
    let by_pull_in = collocation::sensitivity::displacement_sensitivities(&robot, &solution).unwrap();
    assert_eq!(by_pull_in.tendons, vec![0, 2]);
    assert_eq!(by_pull_in.tip.column(1).norm(), 0.0);
    assert_eq!(
        by_pull_in.tension.row(1).norm() + by_pull_in.tension.column(1).norm(),
        0.0
    );
    let sens = tdcr::tip_sensitivities(&robot, &solution).unwrap();
    let (a, b) = (sens.displacement.column(0), by_pull_in.tip.column(0));
    // 1e-9 relative: the same solves combined in another order
    assert!((a - b).norm() <= 1e-9 * b.norm(), "{a:?} vs {b:?}");
    assert!(b.norm() > 0.0 && by_pull_in.tension[(0, 0)] > 0.0);
}

/// Mesh and Newton settings of the derivative checks: 64 fixed intervals (differences of
/// solves on one mesh) and a residual tolerance of 1e-12, as tests/sensitivity.rs.
fn fixed() -> collocation::Options {
    collocation::Options {
        residual_tolerance: 1e-12,
        ..collocation::Options::fixed(64)
    }
}

/// Tip pose of `robot` (held pull-ins) relative to `reference`'s, from a solve warm-started
/// at it on its mesh: position, then the world-frame rotation vector times L (m).
fn tip_offset(robot: &Robot, reference: &tdcr::Solution) -> Vector6<f64> {
    let solution = collocation::solve_from(robot, &fixed(), reference).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(solution.nodes.len(), reference.nodes.len(), "the mesh must not change");
    let (a, b) = (solution.tip(), reference.tip());
    let w = tdcr::so3::log(&(a.R * b.R.transpose())) * robot.length();
    Vector6::new(a.p.x - b.p.x, a.p.y - b.p.y, a.p.z - b.p.z, w.x, w.y, w.z)
}

/// Asserts the tip column `ift` (rotation rows per rad, weighted by L here) against central
/// differences of held pull-in solves with `perturb` moved by +-h; returns the relative error.
fn check_column(
    what: &str,
    robot: &Robot,
    reference: &tdcr::Solution,
    ift: Vector6<f64>,
    h: f64,
    perturb: impl Fn(&mut Robot, f64),
) -> f64 {
    let at = |d: f64| {
        let mut r = robot.clone();
        perturb(&mut r, d);
        tip_offset(&r, reference)
    };
    let fd = (at(h) - at(-h)) / (2.0 * h);
    let mut ift = ift;
    ift.fixed_rows_mut::<3>(3).scale_mut(robot.length());
    let err = (ift - fd).norm() / fd.norm();
    eprintln!("  {what:<14} |fd| = {:.3e}  relative difference {err:.2e}", fd.norm());
    // 1e-6 relative: the bound, which the solves allow. The held solves stop at a
    // tension step below 1e-12 of its scale and Newton at 1e-12, about 1e-12 m of tip: over
    // the steps used (4 um of pull-in, 2e-4 of mu, 1e-4 of a force) 1e-8 relative or less,
    // and h^2 truncation as small (the differences agree to 1e-7 over 5e-5..1e-3 in mu).
    // Measured 5e-9 to 1.1e-7 (the largest: d tip / d mu of the rigid tendon, whose held
    // path length leaves mu a small effect).
    assert!(err <= 1e-6, "{what}: {ift:?} vs finite differences {fd:?} ({err:.2e})");
    err
}

/// Every held-pull-in column with friction on `robot` (tendon `i` pulled in `q` with
/// friction): d tip / d pull-in, d tip / d mu, d tip / d tip force z, and d tip / d tension
/// of the tension-controlled tendon `other`, against central differences of held solves.
fn check_held(name: &str, robot: &Robot, i: usize, other: usize) {
    let reference = collocation::solve(robot, &fixed()).unwrap();
    assert!(reference.tendons[i].tension > 0.0 && reference.tendons[i].slack == 0.0);
    let sens = tdcr::tip_sensitivities(robot, &reference).unwrap();
    eprintln!("{name}: {:.4} N held", reference.tendons[i].tension);
    let pull = sens.displacement.fixed_view::<6, 1>(0, i).into_owned();
    check_column("pull-in", robot, &reference, pull, 4e-6, |r, d| {
        let q = r.tendons[i].displacement().unwrap();
        r.tendons[i].set_displacement(q + d);
    });
    let mu = robot.tendons[i].friction.unwrap().coefficient;
    let by_mu = sens.friction.fixed_view::<6, 1>(0, i).into_owned();
    check_column("friction", robot, &reference, by_mu, 2e-4, |r, d| {
        if let Some(f) = &mut r.tendons[i].friction {
            f.coefficient = mu + d;
        }
    });
    let by_force = sens.tip_force.fixed_view::<6, 1>(0, 2).into_owned();
    check_column("tip force z", robot, &reference, by_force, 1e-4 * 0.1, |r, d| {
        r.loads.tip_force.z += d
    });
    let tension = robot.tendons[other].tension();
    let by_tension = sens.tension.fixed_view::<6, 1>(0, other).into_owned();
    check_column("tension", robot, &reference, by_tension, 1e-4 * tension, |r, d| {
        r.tendons[other].set_tension(tension + d)
    });
    // The control Jacobian's columns are tip_sensitivities' (the same right-hand sides).
    let wrt = [
        Parameter::Displacement(i),
        Parameter::TipForce(2),
        Parameter::Tension(other),
    ];
    let j = collocation::sensitivity::tip_jacobian(robot, &reference, &wrt).unwrap();
    let columns: [Vector6<f64>; 3] = [
        sens.displacement.fixed_view::<6, 1>(0, i).into_owned(),
        sens.tip_force.fixed_view::<6, 1>(0, 2).into_owned(),
        sens.tension.fixed_view::<6, 1>(0, other).into_owned(),
    ];
    for (c, want) in columns.iter().enumerate() {
        // 1e-12 relative: the same solves, bit for bit but for the order of sums
        assert!((j.column(c) - want).norm() <= 1e-12 * want.norm(), "column {c}");
    }
    // The pull-in columns of displacement_sensitivities are the same solves.
    let by_pull_in = collocation::sensitivity::displacement_sensitivities(robot, &reference).unwrap();
    let c = by_pull_in.tendons.iter().position(|&t| t == i).unwrap();
    let (a, b) = (sens.displacement.column(i), by_pull_in.tip.column(c));
    // 1e-9 relative: the same solves combined in another order
    assert!((a - b).norm() <= 1e-9 * b.norm(), "{a:?} vs {b:?}");
}

/// Derivatives at held pull-ins with friction (docs/friction.md section 3b): the base
/// tension follows a parameter so that the pull-in Q (path length and stretch of the
/// varying tension) stays held. The prototype's tendon 1 (E_t A_t = 2000 N, 0.1 m free)
/// pulled 4 mm with tendon 2 at 1 N, mu 0.05 and 0.1, pull and release.
#[test]
fn held_pull_in_derivatives_with_friction_match_central_differences() {
    for mu in [0.05, 0.1] {
        for motion in [Motion::Pull, Motion::Release] {
            let mut robot = pulled(&rough_s(mu, motion, true), 0, 0.012);
            robot.tendons[1].set_tension(1.0);
            check_held(&format!("case S, mu = {mu}, {motion:?}"), &robot, 0, 1);
        }
    }
    // A rigid tendon: the pull-in is the path length alone (no stretch), 6 mm.
    let mut robot = pulled(&rough_s(0.1, Motion::Pull, false), 0, 0.006);
    robot.tendons[1].set_tension(1.0);
    check_held("case S, mu = 0.1, rigid", &robot, 0, 1);
    // The Kirchhoff rod: the paths do not move with the node coordinate v (the force's).
    let mut robot = pulled(&rough_s(0.1, Motion::Pull, true), 0, 0.012);
    robot.tendons[1].set_tension(1.0);
    robot.rod_model = tdcr::RodModel::Kirchhoff;
    check_held("case S, mu = 0.1, Kirchhoff rod", &robot, 0, 1);
}

/// As above on case H's helical tendon (tendon 5, elastic, with friction) held at 15 mm,
/// tendon 1 at its tension: the helix's own turning enters the profile and the stretch.
#[test]
fn held_pull_in_derivatives_with_friction_on_a_helix() {
    for mu in [0.05, 0.1] {
        for motion in [Motion::Pull, Motion::Release] {
            let mut robot = cases::case_h();
            let t = &mut robot.tendons[4];
            t.friction = Some(Friction {
                coefficient: mu,
                motion,
            });
            t.stiffness = Some(2000.0);
            t.free_length = 0.1;
            robot.tendons[0].set_tension(1.0);
            let robot = pulled(&robot, 4, 0.015);
            check_held(&format!("case H, mu = {mu}, {motion:?}"), &robot, 4, 0);
        }
    }
}
