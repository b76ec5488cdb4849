//! Displacement control of a robot with friction (docs/friction.md, section 3b), for any
//! tension solver: the base-entry tensions of the displacement-controlled tendons are the
//! unknowns that their pull-ins fix.
//!
//! With friction the tension varies along the tendon, so its stretch is the integral of
//! tau_j(s) / (E_t A_t) and the pull-in an actuator has taken up at base-entry tension tau_j
//! is (what [`crate::TendonState::displacement`] reports for a tension-controlled tendon)
//!
//! ```text
//! Q_j(tau) = l_ref_j - l_j + integral over the reference path of tau_j(s) / (E_t A_t) ds
//!            + tau_j(0) L_free / (E_t A_t).
//! ```
//!
//! A pull-in q_j then leaves the gap phi_j = Q_j(tau) - q_j: zero when the tendon is
//! taut, positive when it is slack at tau_j = 0. The complementarity tau_j >= 0, phi_j >= 0,
//! tau_j phi_j = 0 is solved as the collocation solver's displacement control solves it, in
//! the Fischer-Burmeister form psi_j = sqrt(a^2 + b^2) - a - b = 0 with a = tau_j / T_j and
//! b = phi_j / L, here by Newton on the k base-entry tensions around full solves with
//! friction at given tensions (each from the last one's shape): dpsi/dtau has the entries
//! p_j / T_j delta_jm + (q_j / L) dphi_j/dtau_m with (p_j, q_j) = (a / r - 1, b / r - 1),
//! and dphi/dtau by one forward difference per tendon. At convergence the gap is 0 to
//! rounding of the solves, whatever the difference's error, which only slows the
//! contraction (by its relative error, about 1e-6, per step).

use crate::error::{Error, Result};
use crate::model::robot::Robot;
use crate::solution::Solution;

/// Relative step of the forward difference dphi/dtau (of max(tau, T)): the solves resolve
/// the gap to about 1e-13 m, so with phi's scale c T (c >= 1e-6 m/N, T ~ 1 N) the
/// difference is accurate to about 1e-4 relative at this step, and Newton contracts by
/// that factor per step.
const STEP: f64 = 1e-5;

/// Newton steps at most; it takes two or three (the difference's contraction).
const MAX_ITERATIONS: usize = 20;

/// psi below this (1e-10 of L in the gap, of T in the tension) that no longer halves in a
/// step is the solves' resolution, where Newton stops: shooting's adaptive steps resolve
/// the gap to about 1e-12 m and its psi then wanders at a few 1e-12.
const NOISE: f64 = 1e-10;

/// psi at or below this is 0 to rounding (its terms are of order 1), where Newton stops.
const ROUNDING: f64 = 1e-14;

/// Below this psi Newton keeps the last dphi/dtau (a chord step) instead of differencing
/// again: the kept derivative is off by the difference's 1e-4 plus the change of the
/// derivative over the last step (of relative size about psi), so the next psi is below
/// 1e-4 of this one, and the loop saves k solves a step.
const KEEP: f64 = 1e-6;

/// Newton stops when every tension step is below this fraction of its scale T_j: the
/// solves' own resolution of the tensions (phi to 1e-13 m over compliances of 1e-6 m/N or
/// more is 1e-7 N at worst; 1e-12 T is well below the 1e-9 relative the tests ask).
const TENSION_TOLERANCE: f64 = 1e-12;

/// Solves `robot` (validated; some displacement-controlled tendons) by `solve`, a solver of
/// robots whose tendons are all tension-controlled (with friction) from a warm start, from
/// the base-entry `start` tensions of every tendon (a frictionless displacement solve's, or
/// a history's last step's) and the `warm` shape. Returns the solution at the tensions that
/// hold the pull-ins, its tendons reporting their pull-in input and slack; the last call of
/// `solve` is the one at those tensions (a history keeps the state it left). A held tendon on
/// the slack side of the complementarity, or on its taut side within `residual_tolerance`
/// (the solves' scaled Newton tolerance) of 0 N in tau / T, gets exactly 0 N: its tension
/// is 0 to the solves' resolution, the rule of the frictionless displacement solve
/// (`collocation::actuation`), so a tendon just taut at its rest pull-in is slack there.
///
/// # Errors
/// What `solve` returns, or [`Error::NotConverged`] when Newton on the tensions does not
/// meet its tolerance in [`MAX_ITERATIONS`] steps.
pub(crate) fn hold(
    robot: &Robot,
    start: &[f64],
    warm: Option<&Solution>,
    residual_tolerance: f64,
    mut solve: impl FnMut(&Robot, Option<&Solution>) -> Result<Solution>,
    mut slope: impl FnMut(&Robot, &Solution, &[usize]) -> Option<Vec<f64>>,
) -> Result<Solution> {
    let held: Vec<usize> = (0..robot.tendons.len())
        .filter(|&j| robot.tendons[j].displacement().is_some())
        .collect();
    let k = held.len();
    let length = robot.length();
    let scale: Vec<f64> = held.iter().map(|&j| robot.tension_scale(j)).collect();
    let target: Vec<f64> = held
        .iter()
        .map(|&j| robot.tendons[j].displacement().unwrap_or(0.0))
        .collect();
    let mut tensions = start.to_vec();
    // One solve at the held tendons' tensions `tau` (clamped at 0: a tendon cannot push)
    // and its gaps phi.
    let mut evaluate =
        |tau: &[f64], tensions: &mut Vec<f64>, warm: Option<&Solution>| -> Result<(Solution, Vec<f64>)> {
            for (&j, &t) in held.iter().zip(tau) {
                tensions[j] = t.max(0.0);
            }
            let solution = solve(&robot.with_tensions(tensions), warm)?;
            let gaps = held
                .iter()
                .zip(&target)
                .map(|(&j, &q)| solution.tendons[j].displacement - q)
                .collect();
            Ok((solution, gaps))
        };
    let mut tau: Vec<f64> = held.iter().map(|&j| tensions[j]).collect();
    let (mut solution, mut gaps) = evaluate(&tau, &mut tensions, warm)?;
    let mut iterations = 0;
    let mut last = f64::INFINITY;
    let mut dphi: Vec<f64> = Vec::new();
    loop {
        let (a, b): (Vec<f64>, Vec<f64>) = (0..k).map(|j| (tau[j] / scale[j], gaps[j] / length)).unzip();
        let psi: Vec<f64> = (0..k).map(|j| a[j].hypot(b[j]) - a[j] - b[j]).collect();
        let size = psi.iter().fold(0.0, |m: f64, p| m.max(p.abs()));
        // Converged: psi is 0, or has stopped falling at the solves' resolution (their
        // gaps carry about 1e-12 m of rounding and stopping noise).
        if size <= ROUNDING || (size < NOISE && size > 0.5 * last) {
            break;
        }
        last = size;
        if iterations == MAX_ITERATIONS {
            let mut report = solution.report.clone();
            report.residual = size;
            return Err(Error::NotConverged {
                method: report.method,
                report: Box::new(report),
                worst_s: 0.0,
                hint: "the tensions that hold the pull-ins with friction were not found: lower the friction \
                       coefficient, or give the tendon a tension instead of a pull-in"
                    .into(),
            });
        }
        iterations += 1;
        // dphi/dtau from the solver's own linearization when it gives one, else by forward
        // differences, each from the current shape; below KEEP the last one is kept (a
        // chord step).
        if size >= KEEP || dphi.is_empty() {
            let mut at = tensions.clone();
            for (&j, &t) in held.iter().zip(&tau) {
                at[j] = t.max(0.0);
            }
            dphi = match slope(&robot.with_tensions(&at), &solution, &held) {
                Some(exact) => exact,
                None => {
                    let mut differences = vec![0.0; k * k];
                    for m in 0..k {
                        let h = STEP * tau[m].max(scale[m]);
                        let mut shifted = tau.clone();
                        shifted[m] = tau[m].max(0.0) + h;
                        let (_, moved) = evaluate(&shifted, &mut tensions, Some(&solution))?;
                        for j in 0..k {
                            differences[j * k + m] = (moved[j] - gaps[j]) / (shifted[m] - tau[m].max(0.0));
                        }
                    }
                    differences
                }
            };
        }
        // The generalized gradient of psi (its element (1/sqrt 2 - 1)(1, 1) at a = b = 0),
        // and the Newton step on the tensions.
        let mut matrix = vec![0.0; k * k];
        for j in 0..k {
            let r = a[j].hypot(b[j]);
            let (p, q) = if r > 0.0 {
                (a[j] / r - 1.0, b[j] / r - 1.0)
            } else {
                (
                    std::f64::consts::FRAC_1_SQRT_2 - 1.0,
                    std::f64::consts::FRAC_1_SQRT_2 - 1.0,
                )
            };
            // At tau_m <= 0 the solve sees 0 N, and dphi is the right derivative there.
            for m in 0..k {
                matrix[j * k + m] = q / length * dphi[j * k + m];
            }
            matrix[j * k + j] += p / scale[j];
        }
        let mut step: Vec<f64> = psi.iter().map(|p| -p).collect();
        if !crate::dense::solve_dense(&mut matrix, &mut step, k) {
            return Err(crate::error::invalid(
                "tendons",
                "have pull-ins whose tensions cannot be told apart with friction (a singular length condition)",
                "give one of the tendons a tension instead of a pull-in",
            ));
        }
        let small = (0..k).all(|j| step[j].abs() <= TENSION_TOLERANCE * scale[j]);
        for j in 0..k {
            tau[j] += step[j];
        }
        (solution, gaps) = evaluate(&tau, &mut tensions, Some(&solution))?;
        if small {
            break;
        }
    }
    // A tendon on the slack side of the complementarity, or just taut (within the
    // tolerance of 0 N), gets exactly 0 N.
    let slack: Vec<bool> = (0..k)
        .map(|j| tau[j] <= residual_tolerance * scale[j] || gaps[j] / length > tau[j] / scale[j])
        .collect();
    if slack.iter().zip(&tau).any(|(&s, &t)| s && t != 0.0) {
        for j in 0..k {
            if slack[j] {
                tau[j] = 0.0;
            }
        }
        (solution, gaps) = evaluate(&tau, &mut tensions, Some(&solution))?;
    }
    for (j, (&i, &q)) in held.iter().zip(&target).enumerate() {
        let state = &mut solution.tendons[i];
        state.displacement = q;
        state.slack = if state.tension > 0.0 { 0.0 } else { gaps[j].max(0.0) };
    }
    Ok(solution)
}
