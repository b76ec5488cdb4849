//! The end of a path that could not be followed to lambda = 1 (it stalled, or went round a
//! family of equilibria at nearly constant lambda, as the swing round the vertical of a
//! hanging robot whose tendon and lateral load nearly balance, until its steps ran out): the
//! robot snaps at a fold it passed, to a stable state (docs/stability.md, "A path that
//! cannot be followed to the end lands from its folds").

use super::newton::{self, Settings, Workspace};
use super::path::index;
use super::system::System;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// Newton on `system` (set to lambda = 1 by the caller) from the states at the folds passed,
/// `fold_states` (load factor and states), the latest first, damped steps allowed and at
/// most the solve's iterations each: the first converged state with no unstable direction
/// and the load factor of its fold, or None. A damped Newton can cross to another branch,
/// which is the point here (the robot snaps), and the stability test keeps only a state the
/// robot can rest in.
pub(super) fn land_from_folds(
    system: &mut System,
    ws: &mut Workspace,
    fold_states: &[(f64, Vec<State>)],
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(f64, Vec<State>)> {
    let land = Settings {
        reuse_factors: false,
        stop_when_damped: false,
        max_iterations: settings.max_iterations,
        ..*settings
    };
    for (lambda, x) in fold_states.iter().rev() {
        // A fold passed before the mesh was refined has states on the coarser mesh.
        if x.len() != system.mesh.nodes.len() {
            continue;
        }
        let mut landed = x.clone();
        let (term, _) = newton::run(system, ws, &mut landed, &land, report);
        if term == Termination::Converged
            && ws.linearize(system, &landed, report)
            && index(system, ws, report) == Some(0)
        {
            report.termination = term;
            return Some((*lambda, landed));
        }
    }
    None
}
