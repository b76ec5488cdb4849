//! Adjoint (vector-Jacobian) gradients against the forward sensitivities contracted with
//! the same cotangent (they share every -dF/dq, so they agree to the rounding of the two
//! linear solves), and against finite differences of full solves (the outputs' derivatives
//! and the orientation convention, independently of the linearization).

use nalgebra::{Matrix3, Vector3};
use tdcr::collocation::sensitivity::{Adjoint, Cotangent, NodeDerivative, Sensitivity, rotation_cotangent};
use tdcr::collocation::{self, Options};
use tdcr::{Parameter, Robot, Solution, cases, so3};

/// Fixed 48-interval mesh with Newton driven to its rounding floor, as tests/sensitivity.rs.
fn options() -> Options {
    Options {
        intervals: 48,
        tolerance: None,
        // 1e-12: full solves then differ by rounding only (tests/sensitivity.rs's reason)
        residual_tolerance: 1e-12,
        ..Default::default()
    }
}

/// Case H with a distributed force and the prototype's geometry (so E is a parameter).
fn loaded() -> Robot {
    let mut robot = cases::case_h();
    Parameter::DistributedForce(1).apply(&mut robot, 0.3).unwrap();
    robot.tendons[0].set_tension(1.2);
    robot
}

fn parameters(robot: &Robot) -> Vec<Parameter> {
    let mut names: Vec<String> = (1..=robot.tendons.len()).map(|i| format!("tension.{i}")).collect();
    for axis in ["x", "y", "z"] {
        names.push(format!("tip_force.{axis}"));
        names.push(format!("tip_moment.{axis}"));
        names.push(format!("distributed_force.{axis}"));
    }
    names.extend(["base_position.y", "load_scale"].map(String::from));
    if robot.rod.geometry.is_some() {
        names.push("youngs_modulus".into());
    }
    names.iter().map(|n| Parameter::parse(n, robot).unwrap()).collect()
}

/// A cotangent with every component non-zero and of mixed sign.
fn cotangent(samples: usize) -> Cotangent {
    let v = |k: f64| Vector3::new(0.7 - 0.1 * k, -0.4 + 0.3 * k, 0.9 - 0.2 * k);
    Cotangent {
        tip_position: v(0.0),
        tip_rotation: v(1.5) * 0.05,
        points: (0..samples).map(|j| v(2.0 + j as f64)).collect(),
    }
}

/// dp(s)/dq of the solution's interpolant along the node derivative `d`: Solution::at's
/// position is linear in the node positions, in R and in v, so moving them by the first-
/// order change (R by hat(omega) R, not re-orthonormalized) and differencing is exact to
/// rounding, at any step; the step makes the change about as large as the rod (a change
/// near rounding of the positions, 1e-12 m per Pa for E, would lose digits).
fn point_derivative(solution: &Solution, d: &[NodeDerivative], s: f64) -> Vector3<f64> {
    let length = solution.length();
    let size = d.iter().fold(0.0f64, |m, d| {
        m.max(d.p.norm())
            .max(d.rotation.norm() * length)
            .max(d.v.norm() * length)
    });
    let step = if size > 0.0 { length / size } else { 1.0 };
    let moved = |sign: f64| {
        let sign = sign * step;
        let mut out = solution.clone();
        for (node, d) in out.nodes.iter_mut().zip(d) {
            node.p += d.p * sign;
            node.R += so3::hat(&d.rotation) * node.R * sign;
            node.v += d.v * sign;
        }
        out.at(s).p
    };
    (moved(1.0) - moved(-1.0)) / (2.0 * step)
}

#[test]
fn adjoint_gradient_equals_contracted_forward_sensitivities() {
    for robot in [cases::case_s(), loaded()] {
        let solution = collocation::solve(&robot, &options()).unwrap();
        let length = robot.length();
        // A node, points inside intervals, and the tip.
        let samples = [0.0, 0.31 * length, 0.5 * length, 0.77 * length, length];
        let cot = cotangent(samples.len());
        let params = parameters(&robot);
        let mut adjoint = Adjoint::new(&robot, &solution, &samples).unwrap();
        let gradient = adjoint.gradient(&cot, &params).unwrap();
        let mut forward = Sensitivity::new(&robot, &solution).unwrap();
        for (p, g) in params.iter().zip(&gradient) {
            let d = forward.parameter(*p).unwrap();
            let tip = d.last().unwrap();
            let mut expected = cot.tip_position.dot(&tip.p) + cot.tip_rotation.dot(&tip.rotation);
            let mut magnitude = cot.tip_position.dot(&tip.p).abs() + cot.tip_rotation.dot(&tip.rotation).abs();
            for (&s, pbar) in samples.iter().zip(&cot.points) {
                let term = pbar.dot(&point_derivative(&solution, &d, s));
                expected += term;
                magnitude += term.abs();
            }
            // 1e-10 of the terms' magnitudes: the transposed and the forward solve of the same
            // factors differ by rounding amplified by the condition number (~1e5)
            assert!(
                (g - expected).abs() <= 1e-10 * magnitude,
                "{p}: adjoint {g:.15e}, forward {expected:.15e}"
            );
        }
    }
}

#[test]
fn adjoint_gradient_matches_finite_differences_of_solves() {
    let robot = loaded();
    let samples = [0.4 * robot.length(), robot.length()];
    let cot = cotangent(samples.len());
    // The loss the cotangent is the gradient of at the solution (linear in the outputs).
    let loss = |robot: &Robot, reference: &Matrix3<f64>| {
        let s = collocation::solve(robot, &options()).unwrap();
        let omega = so3::log(&(s.tip().R * reference.transpose()));
        cot.tip_position.dot(&s.tip_position())
            + cot.tip_rotation.dot(&omega)
            + samples
                .iter()
                .zip(&cot.points)
                .map(|(&x, c)| c.dot(&s.at(x).p))
                .sum::<f64>()
    };
    let solution = collocation::solve(&robot, &options()).unwrap();
    let reference = solution.tip().R;
    let mut adjoint = Adjoint::new(&robot, &solution, &samples).unwrap();
    for (name, step) in [
        ("tension.5", 1e-4 * 4.91),
        ("tip_force.x", 1e-5),
        ("youngs_modulus", 1e-4 * 6e10),
    ] {
        let p = Parameter::parse(name, &robot).unwrap();
        let value = p.value(&robot).unwrap();
        let at = |q: f64| loss(&p.applied(&robot, q).unwrap(), &reference);
        let difference = (at(value + step) - at(value - step)) / (2.0 * step);
        let g = adjoint.gradient(&cot, &[p]).unwrap()[0];
        // 1e-6: central differences of full solves at a 1e-4 relative step (truncation ~1e-8,
        // solve noise ~1e-7; tests/sensitivity.rs measures the same bound)
        assert!(
            (g - difference).abs() <= 1e-6 * difference.abs(),
            "{name}: adjoint {g:.10e}, differences {difference:.10e}"
        );
    }
}

#[test]
fn rotation_cotangent_is_the_gradient_on_the_rotation_vector() {
    let r = so3::exp(&Vector3::new(0.3, -0.5, 0.9));
    let r_bar = Matrix3::new(0.2, -1.0, 0.5, 0.7, 0.1, -0.3, 0.4, 0.8, -0.6);
    let omega_bar = rotation_cotangent(&r, &r_bar);
    for axis in 0..3 {
        let h = 1e-6;
        let e = Vector3::ith(axis, h);
        let f = |w: Vector3<f64>| (r_bar.component_mul(&(so3::exp(&w) * r))).sum();
        let difference = (f(e) - f(-e)) / (2.0 * h);
        // 1e-8: central difference at h = 1e-6 (truncation h^2, rounding 1e-16 / h)
        assert!((omega_bar[axis] - difference).abs() < 1e-8, "axis {axis}");
    }
}

#[test]
fn adjoint_rejects_bad_samples_friction_and_pull_ins_of_tension_inputs() {
    let robot = cases::case_s();
    let solution = collocation::solve(&robot, &options()).unwrap();
    let message = Adjoint::new(&robot, &solution, &[0.5]).err().unwrap().to_string();
    assert!(message.contains("outside the rod"), "{message}");
    let mut adjoint = Adjoint::new(&robot, &solution, &[]).unwrap();
    let message = adjoint
        .gradient(&Cotangent::default(), &[Parameter::Displacement(0)])
        .err()
        .unwrap()
        .to_string();
    assert!(message.contains("tendon 1 is tension-controlled"), "{message}");
    let mut rough = robot.clone();
    rough.tendons[0].friction = Some(tdcr::Friction::pull(0.1));
    let message = Adjoint::new(&rough, &solution, &[]).err().unwrap().to_string();
    assert!(message.contains("has friction"), "{message}");
    let mut adjoint = Adjoint::new(&robot, &solution, &[0.1]).unwrap();
    let message = adjoint.gradient(&Cotangent::default(), &[]).err().unwrap().to_string();
    assert!(message.contains("one cotangent per backbone sample"), "{message}");
}

/// Case S driven by pull-ins: tendon 1 pulled in by 5 mm (taut, its tension solved), tendon
/// 3 let out by 10 mm (slack, held slack), tendon 2 at a tension, with a distributed force.
fn pulled() -> Robot {
    let mut robot = cases::case_s();
    robot.tendons[0].set_displacement(0.005);
    robot.tendons[2].set_displacement(-0.01);
    robot.tendons[1].set_tension(0.4);
    Parameter::DistributedForce(0).apply(&mut robot, 0.2).unwrap();
    robot
}

/// The parameters of [`pulled`]: pull-ins (taut and slack), tensions (of a tension input and
/// of a pulled tendon, whose column is zero), loads, routing offsets and E.
fn pulled_parameters(robot: &Robot) -> Vec<Parameter> {
    [
        "displacement.1",
        "displacement.3",
        "tension.2",
        "tension.1",
        "tip_force.x",
        "tip_moment.y",
        "distributed_force.z",
        "routing.2.x",
        "routing.2.y",
        "youngs_modulus",
    ]
    .iter()
    .map(|n| Parameter::parse(n, robot).unwrap())
    .collect()
}

/// With displacement-controlled tendons the adjoint holds their pull-ins (the bordered
/// system's adjoint): it equals the tip Jacobian (forward sensitivities with the pull-ins
/// held) contracted with a tip cotangent, pull-in and routing columns included.
#[test]
fn adjoint_with_pull_ins_equals_the_contracted_tip_jacobian() {
    // 3e-10: rounding noise, the least accurate entry (routing.2.x) measured 7e-12 to
    // 3.6e-11 of the terms apart as tendon 2's tension moves by a few parts in 1e-9; a
    // wrong term would be off by O(1)
    check_adjoint_with_pull_ins(&pulled(), 3e-10);
}

/// The same on a Kirchhoff rod, whose path lengths do not move with the node coordinate v
/// (the internal force's): the adjoint's length cotangent must leave those slots alone.
#[test]
fn adjoint_with_pull_ins_of_a_kirchhoff_rod_equals_the_contracted_tip_jacobian() {
    let mut robot = pulled();
    robot.rod_model = tdcr::RodModel::Kirchhoff;
    // 1e-9: the routing.2.x entry is this rod's least accurate, its adjoint and forward
    // values measured 3.0e-11 (the Jacobian's end rows by dual numbers) and 1.05e-10 (in
    // closed form, the same derivatives to 8e-16) of the terms apart, and 4.3e-11 to
    // 1.7e-10 as tendon 2's tension moves by a few parts in 1e-9; the other entries below
    // 1e-12: rounding amplified by the bordered Kirchhoff system, not a wrong term (which
    // would be off by O(1)).
    check_adjoint_with_pull_ins(&robot, 1e-9);
}

/// The adjoint with pull-ins of `robot` against its contracted tip Jacobian, to `tolerance` of
/// the terms' magnitudes.
fn check_adjoint_with_pull_ins(robot: &Robot, tolerance: f64) {
    let robot = robot.clone();
    let solution = collocation::solve(&robot, &options()).unwrap();
    assert!(
        solution.tendons[0].tension > 0.1,
        "tendon 1 is taut: {}",
        solution.tendons[0].tension
    );
    assert_eq!(solution.tendons[2].tension, 0.0, "tendon 3 is slack");
    let params = pulled_parameters(&robot);
    let cot = cotangent(0);
    let mut adjoint = Adjoint::new(&robot, &solution, &[]).unwrap();
    let gradient = adjoint.gradient(&cot, &params).unwrap();
    let j = tdcr::collocation::sensitivity::tip_jacobian(&robot, &solution, &params).unwrap();
    for (c, (p, g)) in params.iter().zip(&gradient).enumerate() {
        let column = j.column(c);
        let terms = (0..3).map(|k| (cot.tip_position[k] * column[k], cot.tip_rotation[k] * column[3 + k]));
        let (expected, magnitude) = terms.fold((0.0, 0.0), |(e, m), (a, b)| (e + a + b, m + a.abs() + b.abs()));
        // `tolerance` of the terms' magnitudes: 1e-10 as
        // adjoint_gradient_equals_contracted_forward_sensitivities (a zero column must give
        // exactly zero).
        assert!(
            (g - expected).abs() <= tolerance * magnitude,
            "{p}: adjoint {g:.15e}, forward {expected:.15e}"
        );
    }
    // The slack pull-in and the pulled tendon's tension have no effect.
    assert_eq!((gradient[1], gradient[3]), (0.0, 0.0));
    // The routing of the taut pulled tendon moves its held length at fixed states: refused.
    let message = adjoint
        .gradient(&cot, &[Parameter::RoutingOffset(0, 0)])
        .err()
        .unwrap()
        .to_string();
    assert!(
        message.contains("tendon 1 is displacement-controlled and taut"),
        "{message}"
    );
}

/// Pull-in and routing-offset gradients against central differences of full solves, with
/// backbone points in the loss: the held pull-ins' multiplier reaches the points too.
#[test]
fn pull_in_and_routing_gradients_match_finite_differences_of_solves() {
    let robot = pulled();
    let samples = [0.3 * robot.length(), 0.8 * robot.length()];
    let cot = cotangent(samples.len());
    let loss = |robot: &Robot, reference: &Matrix3<f64>| {
        let s = collocation::solve(robot, &options()).unwrap();
        let omega = so3::log(&(s.tip().R * reference.transpose()));
        cot.tip_position.dot(&s.tip_position())
            + cot.tip_rotation.dot(&omega)
            + samples
                .iter()
                .zip(&cot.points)
                .map(|(&x, c)| c.dot(&s.at(x).p))
                .sum::<f64>()
    };
    let solution = collocation::solve(&robot, &options()).unwrap();
    let reference = solution.tip().R;
    let mut adjoint = Adjoint::new(&robot, &solution, &samples).unwrap();
    let mut found = Vec::new();
    for (name, step) in [
        ("displacement.1", 1e-4 * 0.005),
        ("routing.2.y", 1e-4 * 0.008),
        ("routing.2.x", 1e-4 * 0.008),
        ("tip_force.z", 1e-5),
    ] {
        let p = Parameter::parse(name, &robot).unwrap();
        let value = p.value(&robot).unwrap();
        let at = |q: f64| loss(&p.applied(&robot, q).unwrap(), &reference);
        let difference = (at(value + step) - at(value - step)) / (2.0 * step);
        let g = adjoint.gradient(&cot, &[p]).unwrap()[0];
        eprintln!("{name}: adjoint {g:.10e}, differences {difference:.10e}");
        found.push((name, g, difference));
    }
    // The routing offset's gradient is a vector: its x component, 1 % of its y component here
    // (tendon 2 lies on body y), is compared at the vector's size.
    let offset = found[1].2.hypot(found[2].2);
    for (k, (name, g, difference)) in found.iter().enumerate() {
        let size = if (1..3).contains(&k) { offset } else { difference.abs() };
        // 1e-6: central differences of full solves at a 1e-4 relative step (truncation ~1e-8,
        // solve noise ~1e-7), as adjoint_gradient_matches_finite_differences_of_solves
        assert!(
            (g - difference).abs() <= 1e-6 * size,
            "{name}: adjoint {g:.10e}, differences {difference:.10e}"
        );
    }
}
