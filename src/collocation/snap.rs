//! The end of a path that could not be followed to lambda = 1 (it stalled, or went round a
//! family of equilibria at nearly constant lambda, as the swing round the vertical of a
//! hanging robot whose tendon and lateral load nearly balance, until its steps ran out): the
//! robot snaps at a fold it passed, to a stable state (docs/stability.md, "A path that
//! cannot be followed to the end lands from its folds"); and the snap at a bifurcation
//! where no stable branch continues the path (docs/stability.md, "Snapping from a
//! bifurcation").

use super::branch::SYMMETRIC_COS;
use super::homotopy::{Homotopy, Point, dot};
use super::locate;
use super::neutral::index;
use super::newton::{self, Settings, Workspace};
use super::phase::{Phase, generic, kernel};
use super::relax::relax;
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
            && index(system, ws, &landed, false, report) == Some(0)
        {
            report.termination = term;
            // EXPERIMENT (fold14): which solves land from their folds.
            if std::env::var_os("TDCR_FOLD_TRACE").is_some() {
                let t = landed[landed.len() - 1].p * 1e3;
                eprintln!(
                    "fold14: main landed from the fold at {lambda:.6}: tip ({:.3}, {:.3}, {:.3}) mm",
                    t.x, t.y, t.z
                );
            }
            return Some((*lambda, landed));
        }
    }
    None
}

/// The amplitude of the start of the damped motion along the unstable direction at the
/// bifurcation, in the path's normalized arclength: the first switching step's (module
/// `branch`), large enough that the motion leaves the critical state at once.
const AMPLITUDE: f64 = 0.1;

/// Where the load path of `homotopy` from `point` (tangent `point.tx`, `before` unstable
/// directions) crosses a bifurcation on its way to `beyond` (states and load factor past it,
/// with more unstable directions) and goes on on an unstable branch: the bifurcation located
/// on the branch ([`locate::critical`], else [`locate::past_bifurcation`]), and the stable
/// state where the robot's damped motion comes to rest under the full load (module
/// `relax`), started from the critical state moved along the kernel direction there, on the
/// side the path's tangent leans to, or a picked side when it leans to none (a perfect
/// symmetry). Returns the bifurcation's load factor, whether the side was picked, and that
/// state (with `system` at lambda = 1); None when the kernel is two-dimensional at a perfect
/// symmetry (a family the path holds, module `phase`), a location fails, or the motion does
/// not come to rest at a stable state.
///
/// On None the Jacobian at `beyond` is factored in `ws` again, as the path holds it after
/// the step there (the location and the motion factored others).
pub(super) fn from_bifurcation(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, before): (&Point, Option<usize>),
    beyond: (&[State], f64),
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(f64, bool, Vec<State>)> {
    let snapped = snap_at(system, homotopy, ws, (point, before), beyond, settings, report);
    if snapped.is_none() {
        homotopy.set(system, beyond.1);
        // The path checks the factors at its next step: a failure here is a failed step there.
        let _ = ws.linearize(system, beyond.0, report);
    }
    snapped
}

/// [`from_bifurcation`] but the restored factors.
fn snap_at(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, before): (&Point, Option<usize>),
    beyond: (&[State], f64),
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(f64, bool, Vec<State>)> {
    let n = point.tx.len();
    // The root of the least eigenvalue; where that is not one eigenvalue on both sides (a
    // nearly neutral direction is softer past the crossing), the count's bisection.
    let (xc, lc) = match locate::critical(system, homotopy, ws, point, beyond, settings, report) {
        Some(c) => c,
        None => locate::past_bifurcation(system, homotopy, ws, (point, before), beyond.1, settings, report)?,
    };
    let (phi, growth) = kernel(ws, generic(n), false, None)?;
    let lean = dot(&phi, &point.tx) / n as f64;
    let picked = lean.abs() < SYMMETRIC_COS;
    if picked && Phase::second_kernel(ws, &phi, growth).is_some() {
        return None;
    }
    let side = if picked { AMPLITUDE } else { AMPLITUDE * lean.signum() };
    let step: Vec<f64> = phi.iter().map(|v| v * side).collect();
    let mut start = Vec::with_capacity(xc.len());
    system.retract(&xc, &step, 1.0, &mut start);
    homotopy.set(system, 1.0);
    let x = relax(system, ws, start, settings, report)?;
    report.termination = Termination::Converged;
    Some((lc, picked, x))
}

/// A path after a side picked at a simple symmetric bifurcation crawls when its load factor
/// stays within [`STALL_LAMBDA`] for more than [`STALL_STEPS`] accepted steps: it goes round
/// a family of states at nearly constant load (the bending plane of the gallery's column
/// turning from the imperfection's side to the tendon's, 380 steps within 0.002 of the way
/// at 0.13 N of tension), which the robot swings through, and the path gives up for
/// [`relax_from`].
const STALL_LAMBDA: f64 = 1e-2;
/// See [`STALL_LAMBDA`]: healthy branches gain a percent of the way in a few steps.
const STALL_STEPS: usize = 20;

/// The progress of a path in lambda: the load factor of the last step that moved it more
/// than [`STALL_LAMBDA`] and the steps since.
#[derive(Default)]
pub(super) struct Stall {
    anchor: Option<f64>,
    steps: usize,
}

impl Stall {
    /// Counts an accepted step to load factor `lambda`: whether the path crawls.
    pub(super) fn crawls(&mut self, lambda: f64) -> bool {
        match self.anchor {
            Some(a) if (lambda - a).abs() <= STALL_LAMBDA => self.steps += 1,
            _ => (self.anchor, self.steps) = (Some(lambda), 0),
        }
        self.steps > STALL_STEPS
    }
}

/// The stable state where the robot's damped motion from `x` (the first state past a
/// bifurcation where the path picked a side and then could not reach the full load) comes to
/// rest under the full load (`system` at lambda = 1, module `relax`); None on another mesh
/// than `x`'s or when it does not come to rest at a stable state.
pub(super) fn relax_from(
    system: &System,
    ws: &mut Workspace,
    x: Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<Vec<State>> {
    if x.len() != system.mesh.nodes.len() {
        return None;
    }
    let x = relax(system, ws, x, settings, report)?;
    report.termination = Termination::Converged;
    Some(x)
}
