//! Displacement-controlled tendons (issue 16, docs/actuation.md): round trips between
//! tension and displacement inputs, slack, d(tip)/d(q), the two solvers on displacement
//! inputs, and bad input.

use nalgebra::Vector3;
use tdcr::{Error, Robot, Routing, Solution, Tendon, cases, collocation, shooting};

/// The robot with every tensioned tendon displacement-controlled at the pull-in `solution`
/// reports for it (tension left at 0, so the solver estimates its start).
fn displaced(robot: &Robot, solution: &Solution) -> Robot {
    let mut out = robot.clone();
    for (t, state) in out.tendons.iter_mut().zip(&solution.tendons) {
        if t.tension() > 0.0 {
            t.set_displacement(state.displacement);
        }
    }
    out
}

/// Solves `robot` with tensions, then with the displacements that solution reports, on
/// the same fixed mesh, and checks tensions and shape agree.
fn round_trip(robot: &Robot) {
    let first = collocation::solve(robot, &Default::default()).unwrap();
    let points: Vec<f64> = first.nodes.iter().map(|n| n.s).collect();
    // The same mesh for both: the round trip compares two solves of one discrete system.
    let same_mesh = collocation::Options {
        mesh: Some(points),
        tolerance: None,
        ..Default::default()
    };
    let second = collocation::solve(&displaced(robot, &first), &same_mesh).unwrap();
    for (i, (a, b)) in first.tendons.iter().zip(&second.tendons).enumerate() {
        // 1e-9 relative: both are the same discrete solution at Newton tolerance 1e-11
        assert!(
            (a.tension - b.tension).abs() <= 1e-9 * a.tension.max(1e-3),
            "tendon {i}: {} N vs {} N",
            a.tension,
            b.tension
        );
    }
    for (a, b) in first.nodes.iter().zip(&second.nodes) {
        // 1e-10 m: as for the tensions (a 1e-9 relative tension error moves the tip ~1e-10 m)
        assert!((a.p - b.p).norm() < 1e-10, "s = {}: {:e} m", a.s, (a.p - b.p).norm());
    }
}

/// A two-segment robot: tendon 1 ends at L/2, the helical tendon 5 at the tip.
fn two_segment() -> Robot {
    let mut robot = cases::prototype();
    robot.tendons[0].set_tension(2.0);
    robot.tendons[0].termination = Some(cases::LENGTH / 2.0);
    robot.tendons[4].set_tension(3.0);
    robot.loads.tip_force = Vector3::new(0.0, 0.0, -0.098);
    robot
}

/// The robot with every tendon elastic: E_t A_t = 2000 N (a 0.5 mm steel wire is about
/// 4e4 N; 2000 N makes the stretch some 3% of the pull-in) and 0.1 m of free length.
fn elastic(mut robot: Robot) -> Robot {
    for t in &mut robot.tendons {
        t.stiffness = Some(2000.0);
        t.free_length = 0.1;
    }
    robot
}

#[test]
fn round_trip_on_case_s() {
    round_trip(&cases::case_s());
    round_trip(&elastic(cases::case_s()));
}

#[test]
fn round_trip_on_case_h() {
    round_trip(&cases::case_h());
    round_trip(&elastic(cases::case_h()));
}

#[test]
fn round_trip_on_a_two_segment_robot() {
    round_trip(&two_segment());
    round_trip(&elastic(two_segment()));
}

#[test]
fn elastic_tendons_need_more_pull_in_for_the_same_tension() {
    let stiff = collocation::solve(&cases::case_s(), &Default::default()).unwrap();
    let soft = collocation::solve(&elastic(cases::case_s()), &Default::default()).unwrap();
    let (a, b) = (&stiff.tendons[0], &soft.tendons[0]);
    // The same tension gives the same shape; the pull-in adds tau (l_ref + free) / (E_t A_t).
    let stretch = 2.94 * (a.reference_length + 0.1) / 2000.0;
    // 1e-12 m: the two differ only by the stretch term, computed from the same lengths
    assert!((b.displacement - a.displacement - stretch).abs() < 1e-12);
}

/// An antagonistic pair at (8 mm, 0) and (-8 mm, 0) on the prototype's rod, without
/// gravity (so that the pair's symmetry is exact).
fn pair(q1: f64, q2: f64) -> Robot {
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    robot.tendons = vec![
        Tendon::pulled(Routing::straight(0.008, 0.0), q1),
        Tendon::pulled(Routing::straight(-0.008, 0.0), q2),
    ];
    robot
}

#[test]
fn a_released_antagonist_goes_slack_and_the_pair_equals_the_single_tendon_solve() {
    let q = 0.004;
    let solved = collocation::solve(&pair(q, -2.0 * q), &Default::default()).unwrap();
    let (pulled, released) = (&solved.tendons[0], &solved.tendons[1]);
    assert!(pulled.tension > 0.0 && pulled.slack == 0.0);
    assert_eq!(released.tension, 0.0, "the released tendon must be slack");
    // 3e-3 m: released by 8 mm while bending lengthens its path by about the 4 mm the
    // other takes up, so about 4 mm of slack remain
    assert!(released.slack > 3e-3, "slack {} m", released.slack);
    // The same robot driven by the pulled tendon's tension alone.
    let mut single = pair(0.0, 0.0);
    single.tendons[0] = Tendon::new(Routing::straight(0.008, 0.0), pulled.tension);
    single.tendons[1] = Tendon::new(Routing::straight(-0.008, 0.0), 0.0);
    let points: Vec<f64> = solved.nodes.iter().map(|n| n.s).collect();
    let same_mesh = collocation::Options {
        mesh: Some(points),
        tolerance: None,
        ..Default::default()
    };
    let reference = collocation::solve(&single, &same_mesh).unwrap();
    // 1e-10 m: the same discrete system at Newton tolerance
    assert!((reference.tip_position() - solved.tip_position()).norm() < 1e-10);
}

#[test]
fn a_pretensioned_pair_stays_taut_for_small_pull_ins() {
    // Both pulled 1 mm in, then one 0.5 mm further and the other 0.5 mm back.
    let (q0, dq) = (0.001, 0.0005);
    let solved = collocation::solve(&pair(q0 + dq, q0 - dq), &Default::default()).unwrap();
    for t in &solved.tendons {
        assert!(t.tension > 0.0 && t.slack == 0.0, "{t:?}");
    }
    assert!(solved.tendons[0].tension > solved.tendons[1].tension);
    // The bend is toward the pulled side (body +x at the base).
    let robot = pair(q0, q0);
    let straight = collocation::solve(&robot, &Default::default()).unwrap();
    let body_x = robot.base_rotation * Vector3::x();
    assert!((solved.tip_position() - straight.tip_position()).dot(&body_x) > 0.0);
}

fn invalid_field(robot: &Robot) -> String {
    match collocation::solve(robot, &Default::default()) {
        Err(Error::InvalidInput { field, .. }) => field,
        other => panic!("expected invalid input, got {other:?}"),
    }
}

#[test]
fn bad_actuation_input_is_a_clear_error() {
    let mut robot = pair(0.001, 0.0);
    robot.tendons[0].free_length = -0.01;
    assert_eq!(invalid_field(&robot), "tendons[0].free_length");
    let mut robot = pair(0.001, 0.0);
    robot.tendons[1].stiffness = Some(0.0);
    assert_eq!(invalid_field(&robot), "tendons[1].stiffness");
    // A pull-in longer than the whole path (0.242 m) no shape can take up.
    assert_eq!(invalid_field(&pair(0.3, 0.0)), "tendons[0].displacement");
    assert_eq!(invalid_field(&pair(f64::NAN, 0.0)), "tendons[0].displacement");
}

#[test]
fn tip_sensitivity_to_pull_ins_matches_central_differences() {
    // Case H's helical tendon and tendon 1 both displacement-controlled.
    let mut robot = cases::case_h();
    robot.tendons[0].set_displacement(0.002);
    robot.tendons[4].set_displacement(0.015);
    let options = collocation::Options::fixed(64);
    let solution = collocation::solve(&robot, &options).unwrap();
    let sens = collocation::sensitivity::displacement_sensitivities(&robot, &solution).unwrap();
    assert_eq!(sens.tendons, vec![0, 4]);
    // 1e-5 m: central differences of full solves on the same mesh err by about h^2 (1e-10
    // relative) plus Newton's 1e-11 residual over h, both far below the 1e-6 checked
    let h = 1e-5;
    for (c, &i) in sens.tendons.iter().enumerate() {
        let solve = |dq: f64| {
            let mut r = robot.clone();
            let q = r.tendons[i].displacement().unwrap();
            r.tendons[i].set_displacement(q + dq);
            collocation::solve_from(&r, &options, &solution).unwrap().tip_position()
        };
        let fd = (solve(h) - solve(-h)) / (2.0 * h);
        let analytic = sens.tip.fixed_view::<3, 1>(0, c).into_owned();
        // 1e-6 relative: the bound; the sensitivity's own error is about 1e-8
        assert!(
            (fd - analytic).norm() <= 1e-6 * fd.norm(),
            "tendon {i}: {fd:?} vs {analytic:?}"
        );
    }
}

/// With displacement-controlled tendons, `tip_sensitivities` holds their pull-ins: its
/// pull-in columns equal `displacement_sensitivities`, and its tip force and tension columns
/// match central differences of full displacement-controlled solves (the tensions of the
/// held tendons follow).
#[test]
fn tip_sensitivities_hold_the_pull_ins() {
    let mut robot = cases::case_h();
    robot.tendons[0].set_displacement(0.002);
    robot.tendons[4].set_displacement(0.015);
    robot.tendons[1].set_tension(0.5);
    let options = collocation::Options::fixed(64);
    let solution = collocation::solve(&robot, &options).unwrap();
    let sens = tdcr::tip_sensitivities(&robot, &solution).unwrap();
    let by_pull_in = collocation::sensitivity::displacement_sensitivities(&robot, &solution).unwrap();
    for (c, &i) in by_pull_in.tendons.iter().enumerate() {
        let (a, b) = (sens.displacement.column(i), by_pull_in.tip.column(c));
        // 1e-9 relative: the same solves combined in another order
        assert!((a - b).norm() <= 1e-9 * b.norm(), "tendon {i}: {a:?} vs {b:?}");
        assert_eq!(sens.tension.column(i).norm(), 0.0);
    }
    // As above: 1e-5 steps, compared to 1e-6 relative.
    let h = 1e-5;
    let solve = |change: &dyn Fn(&mut Robot)| {
        let mut r = robot.clone();
        change(&mut r);
        collocation::solve_from(&r, &options, &solution).unwrap().tip_position()
    };
    let fd = (solve(&|r| r.loads.tip_force.z += h) - solve(&|r| r.loads.tip_force.z -= h)) / (2.0 * h);
    let analytic = sens.tip_force.fixed_view::<3, 1>(0, 2).into_owned();
    assert!(
        (fd - analytic).norm() <= 1e-6 * fd.norm(),
        "tip force z: {fd:?} vs {analytic:?}"
    );
    let moved = |d: f64| {
        move |r: &mut Robot| {
            let t = &mut r.tendons[1];
            t.set_tension(t.tension() + d)
        }
    };
    let fd = (solve(&moved(h)) - solve(&moved(-h))) / (2.0 * h);
    let analytic = sens.tension.fixed_view::<3, 1>(0, 1).into_owned();
    assert!(
        (fd - analytic).norm() <= 1e-6 * fd.norm(),
        "tension 2: {fd:?} vs {analytic:?}"
    );
}

/// Shooting as tight as it goes: integration at 1e-12 (its supported floor, local errors
/// that sum to about 1e-11 m along the rod) and Newton to 2e-10 (the tip wrench in N and
/// N m / L, and the gaps over L; case H's residual noise floor at this integration
/// tolerance is about 7e-11: at 1e-10 its line search stalled at 1.1e-10 when the
/// displacement input, taken from a collocation solve, moved in its last bits; 2e-10 moves
/// the tip by well under 1e-9 m).
fn tight_shooting() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        residual_tolerance: 2e-10,
        ..Default::default()
    }
}

/// Solves `robot` by both solvers and checks tip and tensions agree.
fn both_solvers_agree(robot: &Robot) -> Solution {
    // 1e-10 m: the collocation error estimate two orders below the 1e-8 m compared
    let options = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let c = collocation::solve(robot, &options).unwrap();
    let s = shooting::solve(robot, &tight_shooting()).unwrap();
    let gap = (c.tip_position() - s.tip_position()).norm();
    // 1e-8 m: the bound; both solutions are accurate to about 1e-10 m
    assert!(gap < 1e-8, "tips differ by {gap:e} m");
    for (i, (a, b)) in c.tendons.iter().zip(&s.tendons).enumerate() {
        // 1e-7 relative (of 1 mN for a slack tendon): tip positions at 1e-10 m of a
        // 0.24 m rod pin the tensions to about 1e-9 relative
        assert!(
            (a.tension - b.tension).abs() <= 1e-7 * a.tension.max(1e-3),
            "tendon {i}: {} N (collocation) vs {} N (shooting)",
            a.tension,
            b.tension
        );
        assert_eq!(
            a.slack > 0.0,
            b.slack > 0.0,
            "tendon {i}: slack {} vs {}",
            a.slack,
            b.slack
        );
    }
    eprintln!(
        "tip gap {gap:e} m; tensions {:?} vs {:?}",
        c.tendons.iter().map(|t| t.tension).collect::<Vec<_>>(),
        s.tendons.iter().map(|t| t.tension).collect::<Vec<_>>()
    );
    s
}

#[test]
fn collocation_and_shooting_agree_on_displacement_inputs() {
    // Case S with tendon 1 pulled by the displacement its 2.94 N gives.
    let s = cases::case_s();
    let tensioned = collocation::solve(&s, &Default::default()).unwrap();
    let solved = both_solvers_agree(&displaced(&s, &tensioned));
    // 1e-6 relative: the pull-in came from a default-tolerance solve (tip to about 1e-7 m),
    // which the tension inherits at about 1e-7 relative
    assert!((solved.tendons[0].tension - 2.94).abs() < 1e-6 * 2.94);
    // Case H with its helical tendon 5 displacement-controlled, the others by tension.
    let mut h = cases::case_h();
    let tensioned = collocation::solve(&h, &Default::default()).unwrap();
    h.tendons[4].set_displacement(tensioned.tendons[4].displacement);
    both_solvers_agree(&h);
    // The antagonistic pair with the released tendon slack.
    let solved = both_solvers_agree(&pair(0.004, -0.008));
    assert_eq!(solved.tendons[1].tension, 0.0);
    assert!(solved.tendons[1].slack > 3e-3, "slack {} m", solved.tendons[1].slack);
}
