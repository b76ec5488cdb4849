//! A conjugate point in the neutral zone at the base (docs/stability.md, "A root at the
//! base"): the one rule that decides it, for the verdict of an answer
//! (`equilibrium::stability_of`, through [`verdict`] and [`settle`]) and for the count a path
//! follows ([`index`]) alike.
//!
//! The conjugate-point test ([`stability::count`]) leaves out a root of det Q within
//! `stability::NEUTRAL` of the base. Such a root is either the rounding of an exact zero of
//! the second variation (the neutral direction of a perfectly round buckled column, which
//! turns its plane at no cost) or an unstable direction that has just appeared (the payload
//! robot's swing round the vertical, whose conjugate point leaves the base slowly); its
//! position cannot tell the two apart, the lowest mode of the linearized dynamics can. Only
//! a state with such a root pays for the modes.

use super::dynamics;
use super::newton::Workspace;
use super::stability::{self, NeutralRoots};
use super::system::System;
use crate::mesh::spare;
use crate::report::{SolveReport, Stability};
use crate::solution::State;

/// The lowest vibration mode's mu (1/s^2) that counts as negative, as a fraction of the
/// rod's bending scale EI / (rho A L^4) ([`dynamics::bending_scale`]): the exact zero of a
/// round buckled column comes out within 1.4e-11 of it (rounding, either sign), the payload
/// robot's swing at 1.7794 mN, 0.1 uN past its loss of stability at 1.7793 mN, at -4.3e-6
/// (docs/stability.md).
const NEUTRAL_MODE: f64 = 1e-8;

/// Unstable directions at `x`, whose Jacobian `ws` holds (evaluated at `x`), the count the
/// paths follow (`path`, `branch`, `locate`, `snap`, `relax`): None when unknown. A root in
/// the neutral zone is decided as in an answer's [`verdict`], so that a path loses stability
/// where the verdict says it does; on a family's branch (`family`, module `phase`) such a
/// root is the family's own direction and is left out undecided (the count there is guarded
/// by `path::neutral`; the verdict of the path's end decides it).
pub(super) fn index(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    family: bool,
    report: &mut SolveReport,
) -> Option<usize> {
    if stability::non_conservative(&system.model).is_some() {
        return None;
    }
    let t = std::time::Instant::now();
    let mut verdict = ws.verdict_counted(|values| count(values, system));
    report.timings.stability += t.elapsed();
    if !family {
        verdict = settle(system, ws, x, verdict, report);
    }
    match verdict {
        Stability::Stable => Some(0),
        Stability::Unstable { directions, .. } => Some(directions),
        Stability::Growing { .. } | Stability::Unknown { .. } => None,
    }
}

/// The conjugate-point verdict of the Jacobian of `system` at `x` that `ws` holds (its
/// values evaluated at `x`), a root in the neutral zone decided ([`settle`]). Assessed once
/// per Jacobian: a verdict already held is returned as it is.
pub(super) fn verdict(system: &System, ws: &mut Workspace, x: &[State], report: &mut SolveReport) -> Stability {
    let verdict = ws.verdict_counted(|values| count(values, system));
    settle(system, ws, x, verdict, report)
}

/// [`stability::count`] of the Jacobian `values` of `system`, with the nodes' arc lengths
/// in a buffer kept by the thread ([`spare`]).
pub(super) fn count(values: &[f64], system: &System) -> (Stability, Option<NeutralRoots>) {
    let mut s = spare::take(system.mesh.nodes.len());
    s.extend(system.mesh.nodes.iter().map(|n| n.s));
    let verdict = stability::count(values, &s);
    spare::give(s);
    verdict
}

/// The conjugate-point `verdict` of `x` (the one `ws` holds), decided where it left out a
/// root in the neutral zone at the base ([`Workspace::neutral_root`]): the lowest mode of the
/// linearized dynamics ([`dynamics::lowest`]) with mu below -[`NEUTRAL_MODE`] times the
/// rod's bending scale makes the roots left out of a `stable` verdict unstable directions
/// (all of them: a straight round column's come in pairs); otherwise they are neutral
/// directions and the verdict stands. An `unstable` verdict stands as it is: the lowest mode
/// alone cannot tell a root left out from a direction already counted. The decision
/// replaces the verdict held.
///
/// Only such a state pays for the modes (the Jacobian factored at `x` when its factors are
/// not there, and Arnoldi's solves with them); a state whose modes cannot be computed keeps
/// `verdict`, as before the rule.
pub(super) fn settle(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    verdict: Stability,
    report: &mut SolveReport,
) -> Stability {
    let Some((dropped, root)) = ws.neutral_root() else {
        return verdict;
    };
    if !ws.factors_at_iterate() && !ws.linearize(system, x, report) {
        return verdict;
    }
    let t = std::time::Instant::now();
    let lowest = dynamics::lowest(system, x, ws);
    report.timings.stability += t.elapsed();
    let negative = lowest.is_some_and(|mu| mu.re < -NEUTRAL_MODE * dynamics::bending_scale(system));
    let settled = match verdict {
        Stability::Stable if negative => Stability::Unstable {
            directions: dropped,
            conjugate_point: root,
        },
        // An unstable verdict stands: its negative mode may be a direction it already counts.
        other => other,
    };
    ws.settle_verdict(settled.clone());
    settled
}
