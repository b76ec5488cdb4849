//! Spacer disks (issue 27): the `[disks]` table of a robot file adds each disk's weight as a
//! point force at its position, which the solvers treat as any point load.

use nalgebra::Vector3;
use tdcr::analysis::equilibrium;
use tdcr::{Robot, collocation, shooting};

/// The example robot (case S: the prototype with tendon 1 at 2.94 N, its base turned so the
/// backbone runs along world +x) without its distributed weight, with `table` appended.
fn robot(table: &str) -> Robot {
    let text = tdcr::io::example().replace(
        "distributed_force = [0.0, 0.0, -0.47]",
        "distributed_force = [0.0, 0.0, 0.0]",
    );
    tdcr::io::parse(&format!("{text}\n{table}"), "disks.toml")
        .unwrap()
        .robot
}

/// 12 disks of 5 g evenly spaced, the last at the tip (the prototype's count, heavier disks).
const TWELVE: &str = "[disks]\ncount = 12\nmass = 0.005\ngravity = [0.0, 0.0, -9.81]\nradius = 0.01\n";

#[test]
fn disks_are_their_weights_as_hand_added_point_loads() {
    let with_disks = robot(TWELVE);
    let mut by_hand = String::new();
    for k in 1..=12 {
        // The positions s_k = k L / 12, the last exactly L, as a user would type them.
        let s = if k == 12 { 0.242 } else { 0.242 * k as f64 / 12.0 };
        by_hand += &format!("[[loads.point]]\ns = {s:?}\nforce = {:?}\n", [0.0, 0.0, 0.005 * -9.81]);
    }
    let by_hand = robot(&by_hand);
    assert_eq!(format!("{:?}", with_disks.loads), format!("{:?}", by_hand.loads));
    let (a, b) = (
        collocation::solve(&with_disks, &Default::default()).unwrap(),
        collocation::solve(&by_hand, &Default::default()).unwrap(),
    );
    // Bitwise: the same point loads, in the same order.
    assert_eq!(a.tip_position(), b.tip_position());
}

#[test]
fn the_base_carries_the_disks_weight() {
    let robot = robot(TWELVE);
    let fine = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let solution = collocation::solve(&robot, &fine).unwrap();
    let base = solution.base();
    // The free body s in (0, L]: n(0) = the disks' weight minus the tendon's pull at the base,
    // -tau t_1(0) with t_1(0) = R(0) t^b(0) (docs/model.md, section 6).
    let weight = Vector3::new(0.0, 0.0, -12.0 * 0.005 * 9.81);
    let r = robot.tendons[0].routing.at(0.0, robot.length());
    let t_b = base.u.cross(&r.r) + r.r_s + base.v;
    let pull = base.R * t_b.normalize() * robot.tendons[0].tension();
    // 1e-9 N: on the mesh refined to 1e-10 L (measured 2.8e-11 N; the default 1e-7 L leaves
    // 1.5e-7 N of discretization error in the base force)
    assert!(
        (base.n - (weight - pull)).norm() < 1e-9,
        "{} vs {}",
        base.n,
        weight - pull
    );
    // And the moment balance about p(0), with every disk at its solved position.
    let e = equilibrium::imbalance(&robot, &solution);
    // 1e-9: as tests/analytic.rs's global balance, far below the 0.59 N of disk weight
    assert!(e.max() < 1e-9, "{e:?}");
    // They sag the tip: 5 g disks move case S's tip by millimetres.
    let bare = collocation::solve(&self::robot(""), &Default::default()).unwrap();
    let sag = (solution.tip_position() - bare.tip_position()).norm();
    assert!(sag > 1e-3, "{sag}");
}

#[test]
fn disks_at_given_positions_agree_between_solvers() {
    let robot = robot("[disks]\npositions = [0.05, 0.1, 0.2]\nweight = [0.0, 0.02, -0.05]\n");
    assert_eq!(robot.breakpoints(), vec![0.05, 0.1, 0.2]);
    let c = collocation::solve(&robot, &Default::default()).unwrap();
    let s = shooting::solve(
        &robot,
        &shooting::Options {
            integration_tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap();
    // 1e-8 m: as the coupled model's cross-check (tests/cross_check.rs)
    assert!((c.tip_position() - s.tip_position()).norm() < 1e-8);
}

#[test]
fn bad_disk_tables_name_their_keys() {
    let text = tdcr::io::example();
    for (table, message) in [
        ("count = 3\nmass = 0.01", "`disks.gravity` is required with `mass`"),
        (
            "count = 3\npositions = [0.1]\nweight = [0.0, 0.0, -0.1]",
            "`disks.positions` is given together with `count`",
        ),
        (
            "positions = [0.1, 0.05]\nweight = [0.0, 0.0, -0.1]",
            "give the positions increasing",
        ),
        (
            "positions = [0.3]\nweight = [0.0, 0.0, -0.1]",
            "every disk must lie on the rod, in (0, 0.242] m",
        ),
        (
            "count = 0\nweight = [0.0, 0.0, -0.1]",
            "`disks.count` is 0, but must be from 1 to 10000",
        ),
        ("count = 2", "needs each disk's `mass`"),
        (
            "count = 2\nweight = [0.0, 0.0, -0.1]\ngravity = [0.0, 0.0, -9.81]",
            "is given with `weight`",
        ),
        (
            "count = 2\nmass = -1.0\ngravity = [0.0, 0.0, -9.81]",
            "`disks.mass` is -1 kg, but must be >= 0",
        ),
        (
            "count = 2\nmass = 0.0\ngravity = [0.0, 0.0, -9.81]\nradius = 0.0",
            "`disks.radius` is 0 m",
        ),
    ] {
        let e = tdcr::io::parse(&format!("{text}\n[disks]\n{table}\n"), "robot.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains(message), "{table}: {e}");
    }
}
