//! Resolved-rate control with the tip Jacobian: move the prototype's tip along a straight
//! line by updating the four straight tendons' tensions with the pseudo-inverse of
//! d(tip position)/d(tension) (`tdcr::collocation::sensitivity`), each forward solve warm-started from the
//! last on a reused solver.
//!
//! `cargo run --release --example control_loop`
//!
//! The reference runs along the straight line to a reachable goal; mid-way the line leaves
//! the surface the tip can reach with four tendons, so the tracking error grows there (about
//! 12 mm) and shrinks again near the goal, where one tendon runs slack at zero tension.

use nalgebra::{DMatrix, DVector, Vector3};
use tdcr::collocation::sensitivity;
use tdcr::{cases, collocation};

/// Tension every straight tendon starts from (N).
const PRETENSION: f64 = 1.0;

fn main() -> Result<(), tdcr::Error> {
    let mut robot = cases::prototype();
    // The helix stays slack; the four straight tendons steer from a common pre-tension.
    for t in robot.tendons[..4].iter_mut() {
        t.tension = PRETENSION;
    }
    let mut solver = collocation::Solver::new(collocation::Options::default());
    let mut solution = solver.solve(&robot)?;
    let start = solution.tip_position();
    // A goal the robot can reach: the tip under other tensions.
    let mut other = robot.clone();
    for (t, tension) in other.tendons[..4].iter_mut().zip([0.2, 2.5, 1.5, 0.4]) {
        t.tension = tension;
    }
    let goal: Vector3<f64> = collocation::solve(&other, &collocation::Options::default())?.tip_position();
    println!("step  tip x, y, z (mm)            error (mm)  tensions (N)");
    for step in 0..=20 {
        // The reference moves along the straight line from start to goal in 20 steps.
        let reference = start + (goal - start) * (f64::from(step) / 20.0);
        let tip = solution.tip_position();
        let tensions: Vec<String> = robot.tendons[..4].iter().map(|t| format!("{:.3}", t.tension)).collect();
        println!(
            "{step:>4}  ({:7.2}, {:7.2}, {:7.2})  {:>10.4}  {}",
            tip.x * 1e3,
            tip.y * 1e3,
            tip.z * 1e3,
            (reference - tip).norm() * 1e3,
            tensions.join(" ")
        );
        if step == 20 {
            break;
        }
        let next = start + (goal - start) * (f64::from(step + 1) / 20.0);
        // d(tip position)/d(tension) of the four straight tendons: the top 3 x 4 block.
        let jacobian = sensitivity::tip_sensitivities(&robot, &solution)?.tension;
        let j = DMatrix::from_fn(3, 4, |r, c| jacobian[(r, c)]);
        let error = DVector::from_column_slice((next - tip).as_slice());
        // Damped least squares: damping 1e-4 of trace(J^T J) keeps steps finite near singular
        // poses; in the null space (all tendons pulling together only compresses the rod)
        // the tensions relax towards zero, so co-contraction does not grow without bound.
        // Regularized least squares: track the reference and, with a small weight, stay near
        // the pre-tension (all four tendons pulling together only compresses the rod, a
        // direction the tip barely sees, so without this the tensions would drift upwards).
        let jt = j.transpose();
        let jtj = &jt * &j;
        let weight = 1e-3 * jtj.trace() / 4.0;
        let current = DVector::from_iterator(4, robot.tendons[..4].iter().map(|t| t.tension));
        let rhs = &jt * error - (current - DVector::from_element(4, PRETENSION)) * weight;
        let Some(dtau) = (jtj + DMatrix::identity(4, 4) * weight).lu().solve(&rhs) else {
            break;
        };
        for (t, d) in robot.tendons[..4].iter_mut().zip(dtau.iter()) {
            // A string can only pull.
            t.tension = (t.tension + d).max(0.0);
        }
        solution = solver.solve_from(&robot, &solution)?;
    }
    Ok(())
}
