//! The verdict belongs to the state it describes (issue 25, item 2).

use super::stability_of;
use crate::collocation::linear::LinearSolver;
use crate::collocation::newton::{self, Settings, Workspace};
use crate::collocation::system::System;
use crate::mesh::Mesh;
use crate::mesh::guess::{self, InitialGuess};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport, Stability, Termination};
use crate::{Loads, Robot, Rod};
use nalgebra::Vector3;
use std::f64::consts::PI;

const LENGTH: f64 = 0.5;

/// The straight steel column of issue 25 (0.5 m, radius 1 mm) under the dead axial tip force
/// `ratio` times Euler's load pi^2 EI / (4 L^2).
fn column(ratio: f64) -> Robot {
    let rod = Rod::solid_circle(LENGTH, 0.001, 200e9, 0.3);
    let ei = rod.section_at(0.0).section.kbt[0];
    let p = ratio * PI * PI * ei / (4.0 * LENGTH * LENGTH);
    Robot::new(rod).with_loads(Loads::none().with_tip_force(Vector3::new(0.0, 0.0, -p)))
}

/// Newton on the column at 1.05 P_cr from the straight column at 0.95 P_cr (stable there):
/// along straight states the equations are linear in the strains, so one Newton step lands on
/// the answer and a chord step confirms it, and the last Jacobian Newton evaluated is the
/// start's. The answer is the straight column past Euler's load, unstable in both bending
/// planes; the start's Jacobian says stable. The verdict must be the answer's.
#[test]
fn the_verdict_after_one_newton_step_is_the_answers_not_the_starts() {
    let (below, above) = (column(0.95), column(1.05));
    let mesh = Mesh::uniform(&above, 16).unwrap();
    let start = guess::initial(&Model::new(&below), &mesh.nodes, InitialGuess::RigidEquilibrium);
    let system = System::new(Model::new(&above), mesh);
    let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
    let mut report = SolveReport::new(Method::Collocation);

    // What the start's own Jacobian says: stable (0.95 P_cr).
    let mut at_start = Workspace::new(&system, LinearSolver::Blocks).unwrap();
    assert!(at_start.linearize(
        &System::new(Model::new(&below), system.mesh.clone()),
        &start,
        &mut report
    ));
    assert_eq!(
        at_start.verdict(|v| crate::collocation::stability::assess(v, &s)),
        Stability::Stable
    );

    let mut ws = Workspace::new(&system, LinearSolver::Blocks).unwrap();
    let mut x = start.clone();
    let settings = Settings {
        tolerance: 1e-12,
        max_iterations: 20,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = SolveReport::new(Method::Collocation);
    let (termination, _) = newton::run(&system, &mut ws, &mut x, &settings, &mut report);
    assert_eq!(termination, Termination::Converged);
    // The case this test is about: the one Jacobian Newton evaluated is the start's.
    assert_eq!(report.newton_steps, 1, "{:?}", report.history);
    assert!(!ws.jacobian_at_iterate());
    let verdict = stability_of(&system, &mut ws, &x, false, &mut report);
    assert!(
        matches!(verdict, Stability::Unstable { directions: 2, .. }),
        "the straight column at 1.05 P_cr buckles in two planes: {verdict:?}"
    );
    // The Jacobian evaluated for it is now the answer's: asking again costs nothing.
    assert!(ws.jacobian_at_iterate());
    let evaluations = report.evaluations.jacobian;
    assert_eq!(stability_of(&system, &mut ws, &x, false, &mut report), verdict);
    assert_eq!(report.evaluations.jacobian, evaluations);
}
