//! The Kirchhoff rod (`RodModel::Kirchhoff`: inextensible and unshearable, v = v* exactly,
//! the internal force a reaction; docs/model.md, "Kirchhoff rods"): an analytic case, the
//! limit of ever stiffer Cosserat rods, the two solvers against each other, the observed
//! order, global equilibrium and sensitivities.

use tdcr::analysis::equilibrium::imbalance;
use tdcr::model::rod::{Section, Stiffness};
use tdcr::nalgebra::Vector3;
use tdcr::{Loads, Robot, Rod, RodModel, Routing, Solution, Tendon, cases, collocation, shooting};

/// `robot` as a Kirchhoff rod.
fn kirchhoff(robot: &Robot) -> Robot {
    let mut out = robot.clone();
    out.rod_model = RodModel::Kirchhoff;
    out
}

/// `robot` (of uniform section) with its shear and extension stiffness GA, EA times `k`.
fn stiffer(robot: &Robot, k: f64) -> Robot {
    let mut out = robot.clone();
    let Stiffness::Uniform(section) = robot.rod.stiffness.clone() else {
        panic!("a uniform section");
    };
    out.rod.stiffness = Stiffness::Uniform(Section {
        kse: section.kse * k,
        ..section
    });
    out
}

/// Collocation to a tip tolerance of `tol` L.
fn to(tol: f64) -> collocation::Options {
    collocation::Options {
        tolerance: Some(tol),
        ..Default::default()
    }
}

/// Shooting at its tightest supported integration tolerance.
fn tight_shooting() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

/// Case H (a helical tendon at 2.94 N under self-weight) with a tip load: the rod is both
/// bent and compressed, and the tip force has a component along the backbone.
fn loaded_helix() -> Robot {
    let mut robot = cases::case_h();
    robot.loads.tip_force = Vector3::new(0.05, -0.03, -0.098);
    robot
}

/// A two-segment robot: one tendon ends at mid-length (jump conditions at a termination),
/// one at the tip, with a point load and a tip force.
fn two_segments() -> Robot {
    let l = cases::LENGTH;
    let mut robot = cases::prototype()
        .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 2.0).ending_at(0.5 * l))
        .with_tendon(Tendon::new(Routing::straight(0.0, 0.008), 1.5));
    robot.loads.tip_force = Vector3::new(0.0, 0.02, -0.05);
    robot.loads.point.push(tdcr::PointLoad {
        s: 0.75 * l,
        force: Vector3::new(0.03, 0.0, 0.0),
        moment: Vector3::zeros(),
    });
    robot
}

fn tip_distance(a: &Solution, b: &Solution) -> f64 {
    (a.tip_position() - b.tip_position()).norm()
}

#[test]
fn kirchhoff_nodes_keep_the_reference_strain() {
    let robot = kirchhoff(&loaded_helix());
    let solution = collocation::solve(&robot, &Default::default()).unwrap();
    for node in &solution.nodes {
        assert_eq!(node.v, Vector3::z(), "s = {}", node.s);
        assert_eq!(node.v_s, Vector3::zeros(), "s = {}", node.s);
    }
    // the force is a reaction, not zero: the tendon compresses the rod
    assert!(solution.nodes[0].n.norm() > 1.0, "{}", solution.nodes[0].n);
}

#[test]
fn stiff_cosserat_rods_converge_to_kirchhoff_as_one_over_the_stiffness() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let reference = collocation::solve(&kirchhoff(&robot), &to(1e-10)).unwrap();
        let mut last: Option<f64> = None;
        for k in [1.0, 10.0, 100.0, 1000.0, 1e4] {
            let stiff = collocation::solve(&stiffer(&robot, k), &to(1e-10));
            let Ok(stiff) = stiff else {
                eprintln!("{name}: k = {k:e}: the Cosserat solve fails: {}", stiff.unwrap_err());
                continue;
            };
            let d = tip_distance(&stiff, &reference);
            eprintln!(
                "{name}: k = {k:e}: |tip - kirchhoff| = {d:.3e} m, k |tip - kirchhoff| = {:.4e} m",
                k * d
            );
            if let Some(prev) = last {
                eprintln!("  ratio {:.4}", prev / d);
            }
            last = Some(d);
        }
    }
}

#[test]
fn collocation_and_shooting_agree_on_kirchhoff_robots() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let robot = kirchhoff(&robot);
        let c = collocation::solve(&robot, &to(1e-10)).unwrap();
        let s = shooting::solve(&robot, &tight_shooting()).unwrap();
        let d = tip_distance(&c, &s);
        eprintln!("{name}: collocation - shooting = {d:.3e} m");
        assert!(d < 1e-8, "{name}: {d:e}");
    }
}

#[test]
fn kirchhoff_solutions_are_in_global_equilibrium() {
    for robot in [loaded_helix(), two_segments()] {
        let robot = kirchhoff(&robot);
        let solution = collocation::solve(&robot, &to(1e-10)).unwrap();
        let e = imbalance(&robot, &solution);
        eprintln!("{e:?}");
    }
}

#[test]
fn observed_order_on_a_kirchhoff_robot() {
    for robot in [loaded_helix(), two_segments()] {
        let robot = kirchhoff(&robot);
        let reference = collocation::solve(&robot, &collocation::Options::fixed(512)).unwrap();
        let errors: Vec<f64> = [8, 16, 32, 64]
            .iter()
            .map(|&n| {
                tip_distance(
                    &collocation::solve(&robot, &collocation::Options::fixed(n)).unwrap(),
                    &reference,
                )
            })
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("errors {errors:?}, orders {orders:?}");
    }
}

#[test]
fn kirchhoff_tip_force_along_the_axis_does_not_stretch() {
    let rod = Rod::solid_circle(0.2, 5e-4, 200e9, 0.3);
    let mut loads = Loads::none();
    loads.tip_force = Vector3::new(0.0, 0.0, 50.0);
    let robot = Robot::new(rod).with_loads(loads);
    let c = collocation::solve(&kirchhoff(&robot), &Default::default()).unwrap();
    let s = shooting::solve(&kirchhoff(&robot), &Default::default()).unwrap();
    let cosserat = collocation::solve(&robot, &Default::default()).unwrap();
    eprintln!(
        "{} {} {} n {}",
        c.tip_position(),
        s.tip_position(),
        cosserat.tip_position(),
        c.nodes[0].n
    );
}
