//! The end of a path that could not be followed to lambda = 1 (it stalled, or went round a
//! family of equilibria at nearly constant lambda, as the swing round the vertical of a
//! hanging robot whose tendon and lateral load nearly balance, until its steps ran out): the
//! robot snaps at a fold it passed, to a stable state (docs/stability.md, "A path that
//! cannot be followed to the end lands from its folds"); and the snap at a bifurcation
//! where no stable branch continues the path (docs/stability.md, "Snapping from a
//! bifurcation"); and, where that landing finds no stable state, the robot's own route from
//! the first fold it meets: its damped motion just past the fold, then the load path on
//! (docs/stability.md, "A path that ends unstable after its folds lands from them").

use super::branch::SYMMETRIC_COS;
use super::homotopy::{Homotopy, Point, dot};
use super::locate;
use super::neutral::index;
use super::newton::{self, Settings, Workspace};
use super::options::Options;
use super::path::{BIFURCATION_STEP, End, Start, follow};
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

/// How far past a fold (in load factor) the robot's motion from it runs: the fold's state is
/// an equilibrium at the fold's own load, with a zero eigenvalue, so a motion there does not
/// leave it; a little more load drives it off (measured: 0.001, 0.01 and 0.03 come to rest on
/// branches whose load paths end on the same state, docs/stability.md).
const PAST_FOLD: f64 = 0.01;
/// The most motions from folds one solve chains (each followed by a path on that may snap at
/// a fold again): a bound, so that a solve always ends.
const MAX_CHAIN: usize = 8;

/// The first fold a load path met on a stable branch going forward, where the robot loaded
/// from rest snaps: the point before it, the step `h` that crossed it, the tangent's
/// t_lambda past it, and how many folds, bifurcations and picked sides the path had recorded
/// before it.
pub(super) struct Fold {
    point: Point,
    h: f64,
    next_tl: f64,
    recorded: (usize, usize, usize),
}

impl Fold {
    /// The fold crossed by the step `h` from `point` to a point with tangent t_lambda
    /// `next_tl`, after `recorded` folds, bifurcations and picked sides.
    pub(super) fn new(point: &Point, h: f64, next_tl: f64, recorded: (usize, usize, usize)) -> Fold {
        Fold {
            point: Point {
                x: point.x.clone(),
                lambda: point.lambda,
                tx: point.tx.clone(),
                tl: point.tl,
            },
            h,
            next_tl,
            recorded,
        }
    }
}

/// The robot's route from the first fold of a load path whose landing at the full load
/// found no stable state: the fold located (bisection on the step's arclength as
/// [`locate::fold_bracket`], keeping the last state before the turn), the damped motion (module
/// `relax`) from the fold's state under the load [`PAST_FOLD`] past it, and the load path on
/// from where it comes to rest to lambda = 1 ([`Start::Resting`]), which may snap again
/// (at most [`MAX_CHAIN`] motions). `path`: the folds, bifurcations and picked sides recorded
/// before, the family flag, and why the path landed (as [`End::snapped_from`]); `chain`: the
/// motions this solve ran before. Returns the end, the path before the fold joined to it;
/// None (with `system` at lambda = 1) when the fold's states are on another mesh, the motion
/// does not come to rest at a stable state, or the path on fails or ends unstable on this
/// mesh; the path on's end or failure after it refined the mesh is returned as it is (the
/// states of the path before belong to the old mesh).
#[allow(clippy::too_many_arguments)]
pub(super) fn from_fold(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    fold: Option<&Fold>,
    path: (&[f64], &[f64], &[f64], bool, bool),
    chain: usize,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<std::result::Result<End, (String, usize)>> {
    let fold = fold.filter(|f| chain < MAX_CHAIN && f.point.x.len() == system.mesh.nodes.len())?;
    let nodes = system.mesh.nodes.len();
    let rested = motion_past(system, homotopy, ws, fold, settings, report);
    let Some((lf, load, x)) = rested else {
        homotopy.set(system, 1.0);
        return None;
    };
    let (folds, bifurcations, picked, family, reached) = path;
    let (f, b, p) = fold.recorded;
    let mut end = match load >= 1.0 {
        true => End::reached(x, Vec::new(), Vec::new(), Vec::new(), false),
        false => match follow(
            system,
            ws,
            Start::Resting {
                x: &x,
                lambda: load,
                chain: chain + 1,
            },
            options,
            settings,
            report,
            None,
        ) {
            Ok(end) => end,
            Err(e) if system.mesh.nodes.len() != nodes => return Some(Err(e)),
            Err(_) => {
                homotopy.set(system, 1.0);
                return None;
            }
        },
    };
    // The route counts only where it ends stable (the motion rests stable, the path on may
    // not end so); a mesh the path on refined to keeps its end, as its failure there.
    if system.mesh.nodes.len() == nodes
        && !(ws.linearize(system, &end.x, report) && index(system, ws, &end.x, end.family, report) == Some(0))
    {
        homotopy.set(system, 1.0);
        return None;
    }
    // The robot's route: the path up to the fold it snapped at, then the path on.
    let join = |before: &[f64], n: usize, after: &mut Vec<f64>| {
        let mut all = before[..n.min(before.len())].to_vec();
        all.append(after);
        all
    };
    end.folds = join(folds, f + 1, &mut end.folds);
    end.bifurcations = join(bifurcations, b, &mut end.bifurcations);
    end.picked = join(picked, p, &mut end.picked);
    end.family |= family;
    end.moved_from.insert(0, (lf, reached));
    Some(Ok(end))
}

/// The fold of `fold` located, and the stable state where the damped motion from its state
/// comes to rest under the load [`PAST_FOLD`] past it (at most 1): (the fold's load factor,
/// the motion's, the state), with `system` at the motion's load; None when it does not come
/// to rest at a stable state or the fold was not located.
fn motion_past(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    fold: &Fold,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(f64, f64, Vec<State>)> {
    let point = &fold.point;
    let mut r = vec![0.0; system.unknowns()];
    let bracket = locate::fold_bracket(
        system,
        homotopy,
        ws,
        (point, fold.h),
        fold.next_tl,
        settings,
        report,
        &mut r,
    );
    // A fold not located could lie further than PAST_FOLD past the last state before it.
    if !bracket.located {
        return None;
    }
    // The last state located on the path's side of the fold (before the turn, stable).
    let (lf, xf) = bracket.before.unwrap_or_else(|| (point.lambda, point.x.clone()));
    let load = (lf + PAST_FOLD).min(1.0);
    homotopy.set(system, load);
    let x = relax(system, ws, xf, settings, report)?;
    report.termination = Termination::Converged;
    Some((lf, load, x))
}

/// Whether a path whose count of unstable directions went from `counts.0` to `counts.1` over
/// a step `h` (as the path signs it) snaps there (docs/stability.md, "Snapping from a bifurcation"): on a
/// load path from rest that may leave its branch (`landing`: a cold or warm solve's, not one
/// that keeps to its warm start's branch, [`Start::Rest`]), with the count risen, no family
/// held, and either no switch left (`switching` false) or a step short enough to cross the
/// bifurcation that found no stable branch.
pub(super) fn snaps_here(
    landing: bool,
    counts: (Option<usize>, Option<usize>),
    switching: bool,
    h: f64,
    holds_family: bool,
) -> bool {
    matches!(counts, (Some(a), Some(b)) if b > a) && landing && !holds_family && (!switching || h <= BIFURCATION_STEP)
}
