//! The starting tensions of displacement-controlled tendons (docs/actuation.md, "The
//! start"): the small-deflection estimate both solvers begin from.
//!
//! A tendon given a pull-in q_j has an unknown tension. In the unloaded, straight-ish shape
//! the pull-ins respond linearly to the tensions through the pull-in compliance K of
//! [`length::pull_in_compliance`] plus each tendon's own stretch C = diag(c_j):
//! q = (K + C) tau. Solving that, with the tendons that would have to push held at 0 N,
//! gives tensions close enough for Newton to start from; collocation then corrects them
//! once on its initial guess, shooting starts from them as they are.

use crate::dense::solve_dense;
use crate::model::length;
use crate::model::robot::Robot;
use crate::solution::Solution;

/// Sets the starting tension of every displacement-controlled tendon of `robot`: the warm
/// start's, else the one given (when every such tendon has one), else the small-deflection
/// estimate: the tensions that produce the pull-ins through the compliance K of
/// [`length::pull_in_compliance`] plus the tendons' own stretch, q = (K + C) tau, with the
/// tendons that would push left at 0 and the rest solved again (a few passes at most).
/// Returns whether it estimated them (the collocation solve then corrects the estimate on its
/// initial guess).
pub(crate) fn starting_tensions(robot: &mut Robot, warm: Option<&Solution>) -> bool {
    let displaced: Vec<usize> = (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].displacement().is_some())
        .collect();
    if let Some(w) = warm
        && w.tendons.len() == robot.tendons.len()
    {
        for &i in &displaced {
            robot.tendons[i].hold_tension(w.tendons[i].tension);
        }
        return false;
    }
    if displaced.iter().all(|&i| robot.tendons[i].tension() > 0.0) {
        return false;
    }
    let n = robot.tendons.len();
    let compliance = length::pull_in_compliance(robot);
    let mut active: Vec<usize> = displaced.clone();
    for &i in &displaced {
        robot.tendons[i].hold_tension(0.0);
    }
    while !active.is_empty() {
        let mut a = pull_in_matrix(robot, &compliance, &active);
        let b: Vec<f64> = active
            .iter()
            .map(|&j| {
                let inactive = (0..n).filter(|m| !active.contains(m));
                robot.tendons[j].displacement().unwrap_or(0.0)
                    - inactive
                        .map(|m| compliance[j * n + m] * robot.tendons[m].tension())
                        .sum::<f64>()
            })
            .collect();
        let mut tau = b;
        if !solve_dense(&mut a, &mut tau, active.len()) {
            // A tendon on the neutral axis of an inextensible rod: start at 0.
            break;
        };
        let pushing: Vec<usize> = active
            .iter()
            .zip(tau.iter())
            .filter(|&(_, &t)| t < 0.0)
            .map(|(&j, _)| j)
            .collect();
        for (&j, &t) in active.iter().zip(tau.iter()) {
            robot.tendons[j].hold_tension(t.max(0.0));
        }
        if pushing.is_empty() {
            break;
        }
        active.retain(|j| !pushing.contains(j));
        for &j in &pushing {
            robot.tendons[j].hold_tension(0.0);
        }
    }
    true
}

/// K + C restricted to the tendons `active` (row major, m/N): the pull-in of each per newton
/// of each in the small-deflection estimate, with `compliance` the full K of
/// [`length::pull_in_compliance`] and C the tendons' own stretch c_j on the diagonal.
fn pull_in_matrix(robot: &Robot, compliance: &[f64], active: &[usize]) -> Vec<f64> {
    let n = robot.tendons.len();
    let mut a = Vec::with_capacity(active.len() * active.len());
    for &j in active {
        let stretch = robot.tendons[j].compliance(length::reference_length(robot, j));
        a.extend(
            active
                .iter()
                .map(|&m| compliance[j * n + m] + if m == j { stretch } else { 0.0 }),
        );
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;

    /// Small pull-ins give the tensions whose small-deflection pull-ins are those pull-ins:
    /// q = (K + C) tau holds for the estimate (one antagonist slack, held at 0 N).
    #[test]
    fn estimate_reproduces_the_pull_ins_it_was_given() {
        let mut robot = cases::case_s();
        robot.tendons[0].set_displacement(1e-4);
        assert!(starting_tensions(&mut robot, None));
        let tau = robot.tendons[0].tension();
        assert!(tau > 0.0, "{tau} N");
        let k = length::pull_in_compliance(&robot);
        let c = robot.tendons[0].compliance(length::reference_length(&robot, 0));
        // 1e-12 relative: one elimination of a 1 x 1 system, rounding only
        assert!(((k[0] + c) * tau - 1e-4).abs() < 1e-12 * 1e-4, "{} m", (k[0] + c) * tau);
    }

    /// Given tensions on every displacement-controlled tendon are kept, not estimated.
    #[test]
    fn given_tensions_are_kept() {
        let mut robot = cases::case_s();
        robot.tendons[0].actuation = crate::Actuation::PullIn {
            displacement: 1e-4,
            start: Some(2.0),
        };
        assert!(!starting_tensions(&mut robot, None));
        assert_eq!(robot.tendons[0].tension(), 2.0);
    }
}
