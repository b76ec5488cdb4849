//! Bad input is rejected before any iteration, by every solver, with the right
//! `tdcr::Error` variant and a message that names the field, the value and the fix.

mod common;

use common::try_solve_all;
use nalgebra::{Matrix3, Vector3};
use tdcr::{Error, Loads, Robot, Rod, Routing, Tendon, collocation};

const LENGTH: f64 = 0.2;
const RADIUS: f64 = 5e-4;
const MODULUS: f64 = 200e9;
const POISSON: f64 = 0.3;
const OFFSET: f64 = 0.005;

/// A valid robot: two straight tendons under tension.
fn good() -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, RADIUS, MODULUS, POISSON))
        .with_tendon(Tendon::new(Routing::straight(OFFSET, 0.0), 1.0))
        .with_tendon(Tendon::new(Routing::straight(0.0, OFFSET), 2.0))
}

/// Asserts that validation and every solver return `Error::InvalidInput` for `field`,
/// with every fragment in the message.
fn assert_invalid(robot: &Robot, field: &str, fragments: &[&str]) {
    let mut results = vec![("validate", robot.validate().map(|_| ()))];
    results.extend(try_solve_all(robot).into_iter().map(|(name, r)| (name, r.map(|_| ()))));
    for (name, result) in results {
        match result {
            Err(e @ Error::InvalidInput { .. }) => {
                let Error::InvalidInput { field: got, .. } = &e else {
                    unreachable!()
                };
                assert_eq!(got, field, "{name}: {e}");
                let message = e.to_string();
                assert!(message.contains(&format!("`{field}`")), "{name}: {message}");
                for fragment in fragments {
                    assert!(message.contains(fragment), "{name}: no `{fragment}` in: {message}");
                }
            }
            other => panic!("{name}: expected InvalidInput for {field}, got {other:?}"),
        }
    }
}

#[test]
fn a_good_robot_is_accepted() {
    assert!(good().validate().is_ok());
    for (name, result) in try_solve_all(&good()) {
        assert!(result.is_ok(), "{name}: {result:?}");
    }
}

#[test]
fn bad_length_is_rejected() {
    for length in [f64::NAN, 0.0, -0.1, f64::INFINITY] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(length, RADIUS, MODULUS, POISSON);
        assert_invalid(
            &robot,
            "rod.length",
            &[&format!("is {length}"), "positive, finite length"],
        );
    }
}

#[test]
fn bad_radius_modulus_or_poisson_ratio_is_rejected_by_name() {
    for radius in [0.0, -RADIUS, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, radius, MODULUS, POISSON);
        assert_invalid(&robot, "rod.outer_radius", &["positive, finite value in m"]);
    }
    for modulus in [0.0, -MODULUS, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, RADIUS, modulus, POISSON);
        assert_invalid(&robot, "rod.youngs_modulus", &["positive, finite value in Pa"]);
    }
    for nu in [-1.0, 0.6, f64::NAN] {
        let mut robot = good();
        robot.rod = Rod::solid_circle(LENGTH, RADIUS, MODULUS, nu);
        assert_invalid(&robot, "rod.poisson_ratio", &["(-1, 0.5]"]);
    }
    let mut robot = good();
    robot.rod = Rod::tube(LENGTH, RADIUS, RADIUS, MODULUS, POISSON);
    assert_invalid(&robot, "rod.inner_radius", &["below the outer radius"]);
}

#[test]
fn zero_explicit_stiffness_is_rejected() {
    let mut robot = good();
    robot.rod = Rod::new(LENGTH, tdcr::Section::explicit(1e4, 1e4, 0.0, 1e-3, 1e-3));
    assert_invalid(
        &robot,
        "rod.stiffness",
        &["kbt (EIxx, EIyy, GJ)", "positive and finite"],
    );
}

#[test]
fn bad_tension_is_rejected() {
    for tension in [f64::NAN, -1.0, f64::INFINITY] {
        let mut robot = good();
        robot.tendons[1].set_tension(tension);
        assert_invalid(
            &robot,
            "tendons[1].tension",
            &[&format!("is {tension} N"), "can only pull"],
        );
    }
}

#[test]
fn non_finite_loads_are_rejected() {
    let robot = good().with_loads(Loads::none().with_tip_force(Vector3::new(0.0, f64::NAN, 0.0)));
    assert_invalid(&robot, "loads.tip_force", &["(0, NaN, 0)", "finite number"]);
    let robot = good().with_loads(Loads::none().with_tip_moment(Vector3::new(f64::INFINITY, 0.0, 0.0)));
    assert_invalid(&robot, "loads.tip_moment", &["(inf, 0, 0)", "finite number"]);
    let robot = good().with_loads(Loads::self_weight(f64::NAN, -Vector3::z()));
    assert_invalid(&robot, "loads.distributed_force", &["NaN", "finite number"]);
}

#[test]
fn point_load_off_the_rod_is_rejected() {
    for s in [0.0, -0.01, 1.5 * LENGTH, f64::NAN] {
        let mut robot = good();
        robot.loads.point.push(tdcr::PointLoad {
            s,
            force: Vector3::x(),
            moment: Vector3::zeros(),
        });
        assert_invalid(&robot, "loads.point[0].s", &["outside (0, 0.2]"]);
    }
}

#[test]
fn bad_base_pose_is_rejected() {
    let mut nan = Matrix3::identity();
    nan[(1, 2)] = f64::NAN;
    let stretched = Matrix3::identity() * 1.01;
    let sheared = Matrix3::new(1.0, 0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
    let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    for rotation in [nan, stretched, sheared, reflection] {
        let robot = good().with_base(Vector3::zeros(), rotation);
        assert_invalid(
            &robot,
            "base_rotation",
            &["is not a rotation", "orthonormal matrix with determinant +1"],
        );
    }
    let robot = good().with_base(Vector3::new(0.0, f64::NAN, 0.0), Matrix3::identity());
    assert_invalid(&robot, "base_position", &["finite number"]);
}

#[test]
fn termination_outside_the_rod_is_rejected() {
    for end in [0.0, -0.05, LENGTH * 1.001, f64::NAN, f64::INFINITY] {
        let mut robot = good();
        robot.tendons[1] = robot.tendons[1].clone().ending_at(end);
        assert_invalid(
            &robot,
            "tendons[1].termination",
            &[&format!("is s = {end} m, outside (0, 0.2]"), "at most the rod length"],
        );
    }
}

#[test]
fn routing_with_vanishing_tangent_is_rejected() {
    // A straight tendon at (x, 0) on a rod precurved by u* = (0, 1/x, 0): in the unloaded
    // shape its path tangent u* x r + r' + v* = (0, 0, -1) + (0, 0, 1) vanishes everywhere.
    let rod =
        Rod::solid_circle(LENGTH, RADIUS, MODULUS, POISSON).with_precurvature(Vector3::new(0.0, 1.0 / OFFSET, 0.0));
    let robot = Robot::new(rod)
        .with_tendon(Tendon::new(Routing::straight(0.0, OFFSET), 1.0))
        .with_tendon(Tendon::new(Routing::straight(OFFSET, 0.0), 1.0));
    let mut results = vec![("validate", robot.validate().map(|_| ()))];
    results.extend(try_solve_all(&robot).into_iter().map(|(name, r)| (name, r.map(|_| ()))));
    for (name, result) in results {
        match result {
            Err(e @ Error::SingularRouting { tendon: 1, .. }) => {
                let message = e.to_string();
                assert!(
                    message.contains("tendon 2 has a vanishing path tangent"),
                    "{name}: {message}"
                );
                assert!(message.contains("cancel the axial strain"), "{name}: {message}");
            }
            other => panic!("{name}: expected SingularRouting for tendon 1, got {other:?}"),
        }
    }
}

#[test]
fn routing_leaving_the_cross_section_or_not_finite_is_rejected() {
    let mut robot = good();
    robot.tendons[0].routing = Routing::custom(|_, _| tdcr::RoutingPoint {
        r: Vector3::new(OFFSET, 0.0, 1e-3),
        r_s: Vector3::zeros(),
        r_ss: Vector3::zeros(),
    });
    assert_invalid(&robot, "tendons[0].routing", &["has a z component", "z must be 0"]);
    robot.tendons[0].routing = Routing::helical(f64::NAN, 1.0, 0.0);
    assert_invalid(&robot, "tendons[0].routing", &["is not finite", "give finite offsets"]);
}

#[test]
fn meshes_beyond_the_caps_are_bad_input() {
    let robot = good();
    let too_many = collocation::Options::fixed(10_000);
    let err = collocation::solve(&robot, &too_many).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.intervals"),
        "{err}"
    );
    assert!(err.to_string().contains("raise `max_intervals`"));
    let huge = collocation::Options {
        max_intervals: usize::MAX,
        ..Default::default()
    };
    let err = collocation::solve(&robot, &huge).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.max_intervals"),
        "{err}"
    );
}

/// Issue 18: an iteration count sizes the iteration history, so both solvers bound it before
/// reserving anything (`usize::MAX` used to panic with a capacity overflow).
#[test]
fn iteration_counts_beyond_the_bound_are_bad_input() {
    let robot = good();
    for n in [collocation::MAX_ITERATIONS + 1, 1 << 32, usize::MAX] {
        let c = collocation::Options {
            max_iterations: n,
            ..Default::default()
        };
        let err = collocation::solve(&robot, &c).unwrap_err();
        assert!(
            matches!(&err, Error::InvalidInput { field, .. } if field == "options.max_iterations"),
            "{err}"
        );
        assert!(
            err.to_string().contains(&format!("is {n}, above the limit of 10000")),
            "{err}"
        );
        let s = tdcr::shooting::Options {
            max_iterations: n,
            ..Default::default()
        };
        let err = tdcr::shooting::solve(&robot, &s).unwrap_err();
        assert!(
            matches!(&err, Error::InvalidInput { field, .. } if field == "shooting.max_iterations"),
            "{err}"
        );
        assert!(err.to_string().contains("above the limit of 10000"), "{err}");
    }
    let at_bound = collocation::Options {
        max_iterations: collocation::MAX_ITERATIONS,
        ..Default::default()
    };
    assert!(at_bound.validate().is_ok());
}

/// A robot of case H with its helical tendon making `turns` turns, pulled.
fn helix(turns: f64) -> Robot {
    let mut robot = tdcr::cases::case_h();
    robot.tendons[4].routing = Routing::helical(tdcr::cases::TENDON_OFFSET, turns, 0.0);
    robot
}

/// Issue 18: 100 helical turns on the default fixed mesh of 32 intervals converged to a tip
/// 18 cm from the answer. A fixed mesh coarser than the resolution rule (pi/2 rad per
/// interval: 4 per turn) is refused with the intervals that resolve it.
#[test]
fn a_fixed_mesh_that_cannot_resolve_the_routing_is_refused() {
    let robot = helix(100.0);
    let err = collocation::solve(&robot, &collocation::Options::fixed(32)).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.intervals"),
        "{err}"
    );
    let message = err.to_string();
    for fragment in [
        "is 32 intervals",
        "the routing of `tendons[4]` turns about the backbone by up to 19.63 rad",
        "at most pi/2 rad",
        "aliased",
        "400 intervals resolve it",
        "give a tip tolerance",
    ] {
        assert!(message.contains(fragment), "no `{fragment}` in: {message}");
    }
    // Explicit mesh points are held to the same rule, at `options.mesh`.
    let points = collocation::Options {
        mesh: Some((0..=100).map(|k| robot.length() * k as f64 / 100.0).collect()),
        tolerance: None,
        max_intervals: 1000,
        ..Default::default()
    };
    let err = collocation::solve(&robot, &points).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "options.mesh"),
        "{err}"
    );
    // The resolving mesh is accepted, and a tolerance lets refinement choose.
    let resolved = collocation::Options::fixed(400);
    assert!(collocation::solve(&robot, &resolved).is_ok());
    // A rod precurved by 4 pi rad needs 8 intervals.
    let bent = Robot::new(
        Rod::solid_circle(LENGTH, RADIUS, MODULUS, POISSON).with_precurvature(Vector3::new(
            0.0,
            4.0 * std::f64::consts::PI / LENGTH,
            0.0,
        )),
    );
    let coarse = collocation::Options::fixed(7);
    let err = collocation::solve(&bent, &coarse).unwrap_err();
    assert!(err.to_string().contains("the rod's precurvature turns"), "{err}");
    assert!(err.to_string().contains("8 intervals resolve it"), "{err}");
}

/// The rule refuses only aliased meshes: one helical turn (case H) on 4 intervals, the
/// coarsest mesh the rule allows, is solved to within 0.6 % of the rod length, and 16 turns
/// on 64 intervals within 3 %, while 3 intervals per turn (refused) are 8 % off for 16 turns
/// (the study in `tdcr::advanced::mesh::resolution`).
#[test]
fn the_coarsest_mesh_the_rule_allows_is_not_aliased() {
    for (turns, intervals, bound) in [(1.0, 4, 0.006), (16.0, 64, 0.03)] {
        let robot = helix(turns);
        let fine = collocation::Options {
            intervals: 64 * turns as usize,
            tolerance: Some(1e-9),
            max_intervals: 100_000,
            ..Default::default()
        };
        let reference = collocation::solve(&robot, &fine).unwrap().tip_position();
        let coarse = collocation::Options::fixed(intervals);
        let tip = collocation::solve(&robot, &coarse).unwrap().tip_position();
        let error = (tip - reference).norm() / robot.length();
        // bound: the study's error at pi/2 rad per interval (5.2e-3 and 2.4e-2), rounded up
        assert!(
            error < bound,
            "{turns} turns on {intervals} intervals: tip error {error:.2e} L"
        );
        let refused = collocation::Options::fixed(intervals - 1);
        assert!(collocation::solve(&robot, &refused).is_err());
    }
}

/// Issue 18: `--intervals 8192 --tol 1e-12` said "estimated tip error of NaN m": every mesh
/// now has its deferred-correction estimate, so the cap names a finite one.
#[test]
fn an_interval_cap_names_a_finite_estimate() {
    let options = collocation::Options {
        intervals: 64,
        max_intervals: 64,
        tolerance: Some(1e-12),
        ..Default::default()
    };
    // Case H on 64 intervals is 1.7e-8 m off, far from 1e-12 L.
    let err = collocation::solve(&tdcr::cases::case_h(), &options).unwrap_err();
    let Error::IntervalCap { cap, estimate, .. } = err else {
        panic!("{err}");
    };
    assert_eq!(cap, 64);
    assert!(estimate.is_finite() && estimate > 0.0, "{estimate}");
    let message = err.to_string();
    assert!(!message.contains("NaN"), "{message}");
    for fragment in [
        "needs more than the cap of 64 intervals",
        "estimated tip position error of",
        "raise `max_intervals`",
    ] {
        assert!(message.contains(fragment), "no `{fragment}` in: {message}");
    }
}

/// Issue 18: extreme values printed as hundreds of digits; messages print them like `%g`.
#[test]
fn extreme_values_print_in_scientific_notation() {
    let mut robot = good();
    robot.tendons[1].set_tension(-1e300);
    assert_invalid(&robot, "tendons[1].tension", &["is -1e300 N"]);
    for (x, shown) in [
        (0.25, "0.25"),
        (-1e300, "-1e300"),
        (1e6, "1e6"),
        (999_999.5, "999999.5"),
        (1e-4, "0.0001"),
        (3e-5, "3e-5"),
        (0.0, "0"),
        (f64::NAN, "NaN"),
    ] {
        assert_eq!(tdcr::Readable(x).to_string(), shown);
    }
}

/// Newton reserves its iteration history up front: called directly (through
/// `tdcr::advanced`, past `Options::validate`) with `usize::MAX` iterations it reserves at most
/// `MAX_ITERATIONS` records instead of panicking with a capacity overflow.
#[test]
fn newton_called_directly_with_a_huge_limit_does_not_overflow_its_history() {
    use tdcr::advanced::{equations::Model, guess, mesh::Mesh, newton, system::System};
    let robot = tdcr::cases::case_s();
    let system = System::new(Model::new(&robot), Mesh::uniform(&robot, 16).unwrap());
    let mut workspace = newton::Workspace::new(&system, collocation::LinearSolver::Blocks).unwrap();
    let mut x = guess::rigid_estimate(&system.model, &system.mesh.nodes);
    let settings = newton::Settings {
        tolerance: 1e-11,
        max_iterations: usize::MAX,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = tdcr::SolveReport::new(tdcr::Method::Collocation);
    let (termination, _) = newton::run(&system, &mut workspace, &mut x, &settings, &mut report);
    assert_eq!(termination, tdcr::Termination::Converged);
    assert!(report.history.capacity() <= collocation::MAX_ITERATIONS);
}

/// Issue 30: a rod so long that `intervals * length` overflows used to panic with a capacity
/// overflow while building the first mesh; it is now solved (and fails to converge, as a
/// 1e300 m rod does) or refused, never a panic.
#[test]
fn a_rod_of_1e308_m_is_an_error_not_a_panic() {
    let mut robot = good();
    robot.rod.length = 1e308;
    assert!(collocation::solve(&robot, &Default::default()).is_err());
}

/// Issue 30: sensitivities of a solution with another number of tendon states than the
/// robot's tendons (an edited solution JSON) used to index past the end.
#[test]
fn sensitivities_of_a_solution_with_other_tendons_are_bad_input() {
    let robot = good();
    let mut solution = collocation::solve(&robot, &Default::default()).unwrap();
    solution.tendons.clear();
    let err = tdcr::tip_sensitivities(&robot, &solution).unwrap_err();
    assert!(
        matches!(&err, Error::InvalidInput { field, .. } if field == "solution"),
        "{err}"
    );
    assert!(
        err.to_string().contains("has 0 tendon state(s), but the robot has"),
        "{err}"
    );
}

/// Issue 25: shooting exited as bad input ("tendon 0", blaming the routing) on a valid robot
/// whose straight tendon pulls at 99.9 % of the geometric limit EI / r^2, then as a breakdown:
/// its Newton converged, and the optional last step's difference Jacobian perturbed the base
/// strains far enough to fold tendon 1's path, an error that threw the converged answer away.
/// It now solves, and agrees with a tight collocation solve.
#[test]
fn shooting_solves_a_straight_tendon_at_99_9_percent_of_the_geometric_limit() {
    let mut robot = tdcr::cases::prototype();
    robot.loads = tdcr::Loads::none();
    for t in robot.tendons.iter_mut() {
        t.set_tension(0.0);
    }
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    // The prototype's tendons run at 8 mm from the backbone.
    robot.tendons[0].set_tension(0.999 * ei / (0.008 * 0.008));
    assert!(robot.validate().is_ok());
    let shot = tdcr::shooting::solve(&robot, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let options = collocation::Options {
        tolerance: Some(1e-10),
        ..Default::default()
    };
    let reference = collocation::solve(&robot, &options).unwrap();
    let gap = (shot.tip_position() - reference.tip_position()).norm();
    // 1e-9 m: 40 times the reference's tolerance 1e-10 L, room for shooting's integration
    // error (1e-10 on the scaled state) amplified near the limit; measured 1.7e-11 m.
    assert!(gap < 1e-9, "shooting's tip is {gap:e} m from collocation's");
}

/// Issue 25: past where shooting's Newton reaches (99.95 % of the geometric limit) a valid
/// robot is a solver failure, never bad input: exit 3 in the CLI, and any tendon named
/// counts from 1.
#[test]
fn shooting_that_cannot_reach_the_limit_is_a_solver_failure_not_bad_input() {
    let mut robot = tdcr::cases::prototype();
    robot.loads = tdcr::Loads::none();
    for t in robot.tendons.iter_mut() {
        t.set_tension(0.0);
    }
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    robot.tendons[0].set_tension(0.9995 * ei / (0.008 * 0.008));
    assert!(robot.validate().is_ok());
    match tdcr::shooting::solve(&robot, &Default::default()) {
        Ok(_) => {}
        Err(e @ (Error::NotConverged { .. } | Error::Breakdown { .. })) => {
            assert!(!e.to_string().contains("tendon 0"), "{e}");
        }
        Err(other) => panic!("{other:?}"),
    }
}
