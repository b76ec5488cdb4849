//! Resolved-rate control with the tip Jacobian: move the prototype's tip along a straight
//! line to a goal by updating the four straight tendons' tensions with the damped
//! pseudo-inverse of d(tip position)/d(tension) (`tdcr::collocation::sensitivity`), each
//! forward solve warm-started from the last on a reused solver, then hold the goal until the
//! tip is on it.
//!
//! `cargo run --release --example control_loop`
//!
//! The reference runs along the straight line from the start to a reachable goal in
//! [`TRACKING_STEPS`] steps. The tip of a rod that barely compresses stays on a curved
//! surface, and the straight line between two points of it leaves it, so the tracking error
//! grows mid-way (about 12 mm) and shrinks again near the goal. With the reference at the
//! goal the loop converges like Newton's method: the error falls from millimetres to below
//! [`GOAL_TOLERANCE`] within a few steps, and the example asserts it.
//!
//! Four tendons for three coordinates leave one free direction: pulling all four together
//! compresses the rod, which the tip barely sees. The step's first part, J^T (J J^T +
//! lambda^2 I)^-1 e, has no component along it; the second part moves along it only, back
//! towards the pre-tension, so the co-contraction neither drifts nor biases the tip.

use nalgebra::{DMatrix, DVector, Vector3};
use tdcr::collocation::sensitivity;
use tdcr::{Robot, Solution, cases, collocation};

/// Tension every straight tendon starts from and relaxes towards along the free direction,
/// 1.5 N: enough co-contraction that no tendon runs slack on the way (from 1 N, tendon 4
/// does, the other three cannot steer the tip in every direction, and the error only fell
/// linearly, to 33 um after 20 steps at the goal).
pub const PRETENSION: f64 = 1.5;
/// Steps along the straight line from the start to the goal.
pub const TRACKING_STEPS: u32 = 20;
/// Steps at most with the reference held at the goal.
pub const HOLDING_STEPS: u32 = 20;
/// Tip error (m) at which the loop counts as converged, 1e-5 m: 10 um, a tenth of what the
/// prototype's tip positions were measured to (about 0.1 mm) and a thousand times the
/// forward solve's own tip error at its default tolerance.
pub const GOAL_TOLERANCE: f64 = 1e-5;
/// Damping lambda^2 relative to the largest eigenvalue of J J^T, 1e-4. The smallest
/// eigenvalue belongs to the tip's axial direction (compressing the rod), which the tendons
/// move only by co-contraction: undamped (1e-8) the loop chased the micrometres the straight
/// reference leaves the reachable surface with up to 480 N per tendon. Damping changes no
/// fixed point: the step is zero only where the tip error is.
pub const DAMPING: f64 = 1e-4;
/// Gain of the pull towards the pre-tension along the free direction, per step: half the
/// distance each step, so that the co-contraction settles within a few steps.
pub const RELAXATION: f64 = 0.5;

/// One step of the loop: the tip, the reference it was steered to, its tensions.
pub struct Record {
    /// Step number, 0 the start.
    pub step: u32,
    /// Tip position (m), world frame.
    pub tip: Vector3<f64>,
    /// |reference - tip| (m).
    pub error: f64,
    /// Tensions of the four straight tendons (N).
    pub tensions: [f64; 4],
}

/// The change of the four tensions that moves the tip by `error` (m) at the current
/// `solution` of `robot`: damped pseudo-inverse in the three directions the tip sees, a pull
/// towards [`PRETENSION`] in the one it does not.
fn tension_step(robot: &Robot, solution: &Solution, error: &Vector3<f64>) -> Result<DVector<f64>, tdcr::Error> {
    let jacobian = sensitivity::tip_sensitivities(robot, solution)?.tension;
    // d(tip position)/d(tension) of the four straight tendons: the top 3 x 4 block.
    let j = DMatrix::from_fn(3, 4, |r, c| jacobian[(r, c)]);
    let jjt = &j * j.transpose();
    let lambda2 = DAMPING * jjt.symmetric_eigenvalues().amax();
    let e = DVector::from_column_slice(error.as_slice());
    let Some(y) = (jjt + DMatrix::identity(3, 3) * lambda2)
        .cholesky()
        .map(|c| c.solve(&e))
    else {
        return Ok(DVector::zeros(4));
    };
    let tracking = j.transpose() * y;
    // The free direction: the right singular vector of J's zero singular value.
    let svd = j.transpose().svd(true, false);
    let free = match (svd.u, svd.singular_values.argmin()) {
        (Some(u), (k, _)) => u.column(k).into_owned(),
        (None, _) => DVector::zeros(4),
    };
    let current = DVector::from_iterator(4, robot.tendons[..4].iter().map(|t| t.tension()));
    let relax = &free * (free.dot(&(current - DVector::from_element(4, PRETENSION))) * -RELAXATION);
    Ok(tracking + relax)
}

/// Runs the loop: [`TRACKING_STEPS`] along the line to the goal, then up to
/// [`HOLDING_STEPS`] at the goal until the tip error is below [`GOAL_TOLERANCE`]. Returns
/// every step.
pub fn run() -> Result<Vec<Record>, tdcr::Error> {
    let mut robot = cases::prototype();
    // The helix stays slack; the four straight tendons steer from a common pre-tension.
    for t in robot.tendons[..4].iter_mut() {
        t.set_tension(PRETENSION);
    }
    let mut solver = collocation::Solver::new(collocation::Options::default());
    let mut solution = solver.solve(&robot)?;
    let start = solution.tip_position();
    // A goal the robot can reach: the tip under other tensions.
    let mut other = robot.clone();
    for (t, tension) in other.tendons[..4].iter_mut().zip([0.2, 2.5, 1.5, 0.4]) {
        t.set_tension(tension);
    }
    let goal: Vector3<f64> = collocation::solve(&other, &collocation::Options::default())?.tip_position();
    let reference =
        |step: u32| start + (goal - start) * (f64::from(step.min(TRACKING_STEPS)) / f64::from(TRACKING_STEPS));
    let mut records = Vec::new();
    for step in 0..=TRACKING_STEPS + HOLDING_STEPS {
        let tip = solution.tip_position();
        let error = (reference(step) - tip).norm();
        let mut tensions = [0.0; 4];
        for (x, t) in tensions.iter_mut().zip(&robot.tendons) {
            *x = t.tension();
        }
        records.push(Record {
            step,
            tip,
            error,
            tensions,
        });
        if step >= TRACKING_STEPS && error < GOAL_TOLERANCE || step == TRACKING_STEPS + HOLDING_STEPS {
            break;
        }
        let dtau = tension_step(&robot, &solution, &(reference(step + 1) - tip))?;
        for (t, d) in robot.tendons[..4].iter_mut().zip(dtau.iter()) {
            // A string can only pull.
            t.set_tension((t.tension() + d).max(0.0));
        }
        solution = solver.solve_from(&robot, &solution)?;
    }
    Ok(records)
}

fn main() -> Result<(), tdcr::Error> {
    let records = run()?;
    println!("step  tip x, y, z (mm)            error (mm)  tensions (N)");
    for r in &records {
        let tensions: Vec<String> = r.tensions.iter().map(|t| format!("{t:.3}")).collect();
        println!(
            "{:>4}  ({:7.2}, {:7.2}, {:7.2})  {:>10.6}  {}{}",
            r.step,
            r.tip.x * 1e3,
            r.tip.y * 1e3,
            r.tip.z * 1e3,
            r.error * 1e3,
            tensions.join(" "),
            if r.step == TRACKING_STEPS {
                "   <- reference at the goal"
            } else {
                ""
            }
        );
    }
    let last = records.last().map_or(f64::INFINITY, |r| r.error);
    assert!(
        last < GOAL_TOLERANCE,
        "the loop ended {last:.3e} m from the goal, above {GOAL_TOLERANCE:e} m"
    );
    println!("converged: {:.2e} m from the goal", last);
    Ok(())
}
