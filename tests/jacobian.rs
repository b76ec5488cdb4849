//! The collocation Jacobian (forward-mode AD) against central finite differences of the
//! residual at a non-trivial state.

use tdcr::advanced::equations::Model;
use tdcr::advanced::guess::rigid_estimate;
use tdcr::advanced::mesh::Mesh;
use tdcr::advanced::system::System;
use tdcr::advanced::unknowns::pattern;

fn check(robot: &tdcr::Robot, intervals: usize) {
    let model = Model::new(robot);
    let mesh = Mesh::uniform(robot, intervals).unwrap();
    let sys = System::new(model.clone(), mesh);
    // A non-trivial state: the rigid estimate, moved off it by a smooth pseudo-random step.
    let x0 = rigid_estimate(&model, &sys.mesh.nodes);
    let n = sys.unknowns();
    // Amplitudes per unknown (dp/L, dtheta, dv, du L): physical sizes, since strains v carry
    // forces EA (v - v*) and a large dv would make the residual huge and its rounding too.
    let amplitude = [1e-3, 1e-3, 1e-3, 0.05, 0.05, 0.05, 1e-6, 1e-6, 1e-6, 0.1, 0.1, 0.1];
    let wiggle: Vec<f64> = (0..n).map(|i| amplitude[i % 12] * ((i as f64) * 0.7).sin()).collect();
    let mut x = Vec::new();
    sys.retract(&x0, &wiggle, 1.0, &mut x);
    let pat = pattern(&sys.mesh);
    let mut values = vec![0.0; pat.len()];
    let mut r = vec![0.0; n];
    sys.jacobian(&x, &mut r, &mut values).unwrap();
    let mut dense = vec![vec![0.0; n]; n];
    for (&(i, j), v) in pat.iter().zip(&values) {
        dense[i][j] = *v;
    }
    // Central differences with h = 1e-7 in the scaled unknowns: truncation h^2 f''' is
    // largest in the stiff v columns (f''' ~ EA/EI, about 1e-8 here) and rounding is
    // 1e-16 / h ~ 1e-9, while a wrongly seeded or scaled entry would be off by O(1).
    let h: f64 = 1e-7;
    let mut worst: f64 = 0.0;
    let (mut rp, mut rm, mut xp, mut xm) = (vec![0.0; n], vec![0.0; n], Vec::new(), Vec::new());
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = h;
        sys.retract(&x, &e, 1.0, &mut xp);
        sys.retract(&x, &e, -1.0, &mut xm);
        sys.residual(&xp, &mut rp).unwrap();
        sys.residual(&xm, &mut rm).unwrap();
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            let err = (fd - dense[i][j]).abs() / (1.0 + fd.abs());
            worst = worst.max(err);
        }
    }
    // 1e-7: ten times the worst finite-difference error measured (about 1e-8)
    eprintln!("worst relative difference {worst:.2e}");
    assert!(worst < 1e-7, "Jacobian differs from finite differences by {worst:.3e}");
}

#[test]
fn jacobian_matches_finite_differences_straight_tendon_gravity() {
    check(&tdcr::cases::case_s(), 6);
}

#[test]
fn jacobian_matches_finite_differences_helix_tip_load() {
    check(&tdcr::cases::case_h(), 6);
}

#[test]
fn jacobian_matches_finite_differences_two_segments() {
    let mut robot = tdcr::cases::case_h();
    robot.tendons[1].set_tension(1.5);
    robot.tendons[1].termination = Some(0.121);
    robot.loads.point.push(tdcr::PointLoad {
        s: 0.06,
        force: nalgebra::Vector3::new(0.01, 0.02, -0.05),
        moment: nalgebra::Vector3::new(0.001, 0.0, 0.002),
    });
    check(&robot, 6);
}

#[test]
fn jacobian_matches_finite_differences_on_a_kirchhoff_rod() {
    // the translational unknowns carry the internal force (v = v* exactly): the kinematic
    // and tendon rows no longer depend on them
    let mut robot = tdcr::cases::case_h();
    robot.tendons[1].set_tension(1.5);
    robot.tendons[1].termination = Some(0.121);
    robot.loads.tip_force = nalgebra::Vector3::new(0.03, -0.02, -0.08);
    robot.loads.point.push(tdcr::PointLoad {
        s: 0.06,
        force: nalgebra::Vector3::new(0.01, 0.02, -0.05),
        moment: nalgebra::Vector3::new(0.001, 0.0, 0.002),
    });
    robot.rod_model = tdcr::RodModel::Kirchhoff;
    check(&robot, 6);
}
