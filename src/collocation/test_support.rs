//! Set-up that unit tests of several collocation modules share.

use super::linear::LinearSolver;
use super::newton::Workspace;
use super::system::System;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate;
use crate::model::equations::Model;
use crate::report::{Method, SolveReport};
use crate::solution::State;
use crate::{Robot, Solution};

/// The prototype with its four tendons pulled at 0.4, 1.1, 1.8 and 2.5 N: every tendon
/// term of eq. 13 and its linearization at work.
pub(crate) fn pulled_prototype() -> Robot {
    let mut robot = crate::cases::prototype();
    for (i, tendon) in robot.tendons.iter_mut().enumerate().take(4) {
        tendon.set_tension(0.4 + 0.7 * i as f64);
    }
    robot
}

/// The system of `robot` at `solution`'s tensions on `solution`'s own mesh, the solution's
/// states on it, and a workspace (block elimination) that has evaluated and factored the
/// Jacobian there, with the report that counted it.
pub(crate) fn linearized_at<'r>(
    robot: &'r Robot,
    solution: &Solution,
) -> (System<'r>, Vec<State>, Workspace, SolveReport) {
    let points: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mesh = Mesh::from_points(robot, &points).unwrap();
    let mut model = Model::new(robot);
    model.tensions = solution.tensions();
    let x = interpolate(&model, solution, &mesh);
    let system = System::new(model, mesh);
    let mut report = SolveReport::new(Method::Collocation);
    let mut ws = Workspace::new(&system, LinearSolver::Blocks).unwrap();
    assert!(
        ws.linearize(&system, &x, &mut report),
        "the Jacobian at the solution factors"
    );
    (system, x, ws, report)
}
