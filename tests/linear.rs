//! The structured block elimination against faer's sparse LU, and singular matrices reported
//! as such by both (never a panic, never a non-finite step).

use tdcr::advanced::equations::Model;
use tdcr::advanced::guess::rigid_estimate;
use tdcr::advanced::mesh::Mesh;
use tdcr::advanced::newton::Workspace;
use tdcr::advanced::system::System;
use tdcr::advanced::unknowns::pattern;
use tdcr::collocation::LinearSolver;
use tdcr::collocation::{self, Options};
use tdcr::{PointLoad, cases};

/// A robot with a breakpoint (tendon ending mid-way) and an interior point load, so jump
/// blocks are part of the matrix.
fn two_segment() -> tdcr::Robot {
    let mut robot = cases::case_h();
    robot.tendons[0].set_tension(1.0);
    robot.tendons[0].termination = Some(0.1);
    robot.loads.point.push(PointLoad {
        s: 0.17,
        force: nalgebra::Vector3::new(0.0, 0.02, 0.0),
        moment: nalgebra::Vector3::zeros(),
    });
    robot
}

fn jacobian(robot: &tdcr::Robot, intervals: usize) -> (System<'_>, Vec<f64>, Vec<f64>) {
    let model = Model::new(robot);
    let system = System::new(model.clone(), Mesh::uniform(robot, intervals).unwrap());
    let x = rigid_estimate(&model, &system.mesh.nodes);
    let mut values = vec![0.0; pattern(&system.mesh).len()];
    let mut residual = vec![0.0; system.unknowns()];
    system.jacobian(&x, &mut residual, &mut values).unwrap();
    (system, values, residual)
}

#[test]
fn block_elimination_matches_sparse_lu() {
    for robot in [cases::case_s(), cases::case_h(), two_segment()] {
        let (system, values, rhs) = jacobian(&robot, 24);
        let mut blocks = Workspace::new(&system, LinearSolver::Blocks).unwrap();
        let mut sparse = Workspace::new(&system, LinearSolver::SparseLu).unwrap();
        let a = blocks.solve_linear(&values, &rhs).unwrap().to_vec();
        let b = sparse.solve_linear(&values, &rhs).unwrap().to_vec();
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        // 1e-10: both are backward stable; the Jacobian's condition number (~1e5) times
        // rounding bounds their difference
        assert!(
            diff <= 1e-10 * scale,
            "solutions differ by {diff:.3e} (scale {scale:.3e})"
        );
    }
}

#[test]
fn full_solves_agree_between_linear_solvers() {
    let robot = two_segment();
    let a = collocation::solve(&robot, &Options::fixed(48)).unwrap();
    let b = collocation::solve(
        &robot,
        &Options {
            intervals: 48,
            tolerance: None,
            linear_solver: LinearSolver::SparseLu,
            ..Default::default()
        },
    )
    .unwrap();
    // 1e-12 m: the same discrete problem solved to a residual of 1e-11 by either solver
    assert!((a.tip_position() - b.tip_position()).norm() < 1e-12);
}

#[test]
fn singular_matrix_is_reported_not_panicked() {
    let robot = cases::case_h();
    let (system, mut values, rhs) = jacobian(&robot, 8);
    // Zero every entry of column 20 (node 1's v_z): structurally present, numerically singular.
    for (v, &(_, c)) in values.iter_mut().zip(&pattern(&system.mesh)) {
        if c == 20 {
            *v = 0.0;
        }
    }
    for solver in [LinearSolver::Blocks, LinearSolver::SparseLu] {
        let mut ws = Workspace::new(&system, solver).unwrap();
        assert!(
            ws.solve_linear(&values, &rhs).is_none(),
            "{solver:?} accepted a singular matrix"
        );
    }
}

#[test]
fn solving_again_with_stored_factors_matches_a_fresh_solve() {
    let robot = two_segment();
    let (system, values, rhs) = jacobian(&robot, 16);
    let other: Vec<f64> = (0..rhs.len()).map(|i| ((i as f64) * 0.37).sin()).collect();
    for solver in [LinearSolver::Blocks, LinearSolver::SparseLu] {
        let mut ws = Workspace::new(&system, solver).unwrap();
        let fresh = ws.solve_linear(&values, &other).unwrap().to_vec();
        ws.solve_linear(&values, &rhs).unwrap();
        let again = ws.solve_again(&other).unwrap().to_vec();
        let scale = fresh.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff = fresh.iter().zip(&again).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // 1e-12: the same factors and operations; only the order of rounding differs
        assert!(diff <= 1e-12 * scale, "{solver:?}: {diff:.3e} of {scale:.3e}");
    }
}

#[test]
fn transposed_solves_match_the_dense_transpose() {
    for robot in [cases::case_s(), cases::case_h(), two_segment()] {
        let (system, values, rhs) = jacobian(&robot, 24);
        let n = system.unknowns();
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
        for (&(r, c), v) in pattern(&system.mesh).iter().zip(&values) {
            dense[(r, c)] += v;
        }
        // A right-hand side with every entry non-zero, unlike the residual's pattern.
        let c: Vec<f64> = (0..n)
            .map(|i| rhs[i] + ((i * 7919) % 13) as f64 * 1e-2 - 0.06)
            .collect();
        let reference = dense
            .transpose()
            .lu()
            .solve(&nalgebra::DVector::from_column_slice(&c))
            .unwrap();
        let scale = reference.amax();
        for kind in [LinearSolver::Blocks, LinearSolver::SparseLu] {
            let mut workspace = Workspace::new(&system, kind).unwrap();
            assert!(workspace.solve_linear(&values, &rhs).is_some());
            let y = workspace.solve_transposed(&c).unwrap();
            let diff = y
                .iter()
                .zip(reference.iter())
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            // 1e-10: backward-stable solves of a system with condition number ~1e5 (as above)
            assert!(
                diff <= 1e-10 * scale,
                "{kind:?}: J^T y = c off by {diff:.3e} (scale {scale:.3e})"
            );
        }
    }
}
