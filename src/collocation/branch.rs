//! Branch switching: where a path would pass from a stable branch onto an unstable one
//! (it crossed a bifurcation, or a step jumped across the sharp turn of a slightly
//! imperfect one), it leaves along the kernel direction of the Jacobian instead
//! (docs/stability.md, "Branch switching").
//!
//! At a bifurcation point the Jacobian J of the equilibrium equations is singular and the
//! branches that leave it are tangent to its kernel; close to one, J has an eigenvalue near
//! zero whose eigenvector phi is that direction, which inverse iteration with the factors of
//! J finds in a few solves. The side is the one the path's own tangent t_x leans to: an
//! imperfection (a small lateral load on a column) gives t_x a component along phi with its
//! sign, and a perfectly symmetric problem none, in which case one side is picked and the
//! report says so. The switching step predicts x + h phi at fixed load and corrects on the
//! hyperplane through the prediction normal to (phi, 0) with the load free, which lands on
//! the branch whose amplitude along phi is h; the path then goes on from there.

use super::homotopy::{Homotopy, Point, dot, tangent};
use super::locate;
use super::neutral::index;
use super::newton::{self, Settings, Workspace};
use super::path::correct;
use super::phase::{Phase, generic, kernel};
use super::system::System;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// Below this |cos| between the path's tangent and the kernel direction the path has no
/// side: a perfect symmetry (the tangent's component along the kernel is rounding, 1e-16
/// relative in a symmetric problem; the smallest imperfection of issue 25's column, 1e-5 of
/// the load, gives 1e-6 and more).
pub(super) const SYMMETRIC_COS: f64 = 1e-9;
/// The switching step's amplitudes along the kernel direction (normalized arclength, as the
/// path's steps): the first, and the shorter retries when its corrector fails.
const SWITCH_STEPS: [f64; 3] = [0.1, 0.03, 0.01];

/// The path after a branch switch.
pub(super) struct Switched {
    /// The first point on the new branch, with its tangent.
    pub point: Point,
    /// Unstable directions there (None: unknown).
    pub unstable: Option<usize>,
    /// Whether the side was picked (a perfect symmetry: nothing preferred one).
    pub picked: bool,
    /// Where the bifurcation's kernel is two-dimensional (the branch taken is one member of
    /// a family of equilibria, module `phase`): the family's direction there, the phase
    /// condition's start, and the direction the branch left along (which orients its
    /// first tangent). None for a simple bifurcation.
    pub family: Option<(Vec<f64>, Vec<f64>)>,
    /// The load factor the switch left from: the located bifurcation when the side was
    /// picked, else the path's point.
    pub at: f64,
}

impl Switched {
    /// Records the switch: a side picked by symmetry is a bifurcation of the path, at the
    /// load factor where it was located, and says so in `picked`.
    pub fn record(&self, bifurcations: &mut Vec<f64>, picked: &mut Vec<f64>) {
        if self.picked {
            bifurcations.push(self.at);
            picked.push(self.at);
        }
    }

    /// After a switch onto this branch: the phase condition that holds it on its family's
    /// member when it is one (module `phase`), with the tangent there taken again with it, and
    /// whether it is. (None, false) for a simple bifurcation or when the directions are not
    /// found (the path then goes on free).
    pub(super) fn hold(
        &mut self,
        system: &mut System,
        homotopy: &Homotopy,
        ws: &mut Workspace,
        report: &mut SolveReport,
    ) -> (Option<Phase>, bool) {
        let Some((c, along)) = self.family.take() else {
            return (None, false);
        };
        let Some(phase) = Phase::at(ws, c, None) else {
            return (None, false);
        };
        // Oriented along the switch (the free tangent there is the family's direction,
        // amplified by the singular Jacobian, and orients nothing).
        let previous = (along.as_slice(), 0.0);
        let Some((point, _)) = phase.tangent(
            system,
            homotopy,
            ws,
            self.point.x.clone(),
            self.point.lambda,
            Some(previous),
            report,
        ) else {
            return (None, false);
        };
        self.point = point;
        (Some(phase), true)
    }
}

/// Leaves `point` (on the path of `homotopy`, tangent `point.tx`) along the kernel direction
/// of the Jacobian there, on the side its tangent leans to (or a picked side when it leans
/// to none), and converges the first point of the new branch. None when no switching step
/// converges to a point with at most `unstable_before` unstable directions (those of
/// `point`: the new branch must be as stable as the one the path was on).
#[allow(clippy::too_many_arguments)]
pub(super) fn switch(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: &Point,
    beyond: (&[State], f64),
    unstable_before: usize,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
) -> Option<Switched> {
    homotopy.set(system, point.lambda);
    if !ws.linearize(system, &point.x, report) {
        return None;
    }
    let n = point.tx.len();
    let nf = n as f64;
    // The generic start reaches the whole (near-)kernel; the tangent's start stays in the
    // subspace the path moves in (for an imperfect round column, the imperfection's plane).
    let (any, any_growth) = kernel(ws, generic(n), false, None)?;
    let symmetric = (dot(&any, &point.tx) / nf).abs() < SYMMETRIC_COS;
    let phi = if symmetric {
        any
    } else {
        // The tangent's span must hold a direction nearly as soft as the softest: else the
        // path is not at the turn its tangent leans into (the soft direction is one it does
        // not move in, as the plane of a buckled round column), and it does not switch.
        match kernel(ws, point.tx.clone(), false, None) {
            Some((phi, growth)) if growth >= 0.5 * any_growth => phi,
            _ => return None,
        }
    };
    let side = if symmetric { 1.0 } else { dot(&phi, &point.tx).signum() };
    // A perfect symmetry: the switch starts from the bifurcation itself, located on the
    // branch between `point` and `beyond`, where the kernel is the buckling mode (far before
    // it inverse iteration converges slowly and to a direction that is only near it); the
    // bifurcation is recorded there.
    let mut at = point.lambda;
    let mut from = point.x.clone();
    let (phi, any_growth) =
        match symmetric.then(|| locate::critical(system, homotopy, ws, point, beyond, settings, report)) {
            Some(Some((xc, lc))) => {
                let (kc, growth) = kernel(ws, generic(n), false, None)?;
                (at, from) = (lc, xc);
                (kc, growth)
            }
            Some(None) => {
                homotopy.set(system, point.lambda);
                if !ws.linearize(system, &point.x, report) {
                    return None;
                }
                (phi, any_growth)
            }
            None => (phi, any_growth),
        };
    // A perfect symmetry whose kernel is two-dimensional: the branch along phi is one
    // member of a family, whose direction there starts from the second kernel direction.
    let family = match symmetric {
        true => Phase::second_kernel(ws, &phi, any_growth).map(|c| (c, phi.clone())),
        false => None,
    };
    let phi: Vec<f64> = phi.iter().map(|v| v * side).collect();
    homotopy.set(system, at);
    let along = Point {
        x: from,
        lambda: at,
        tx: phi,
        tl: 0.0,
    };
    for h in SWITCH_STEPS {
        let Some((x, lambda, _)) = correct(system, homotopy, ws, &along, h, settings, report, r, None) else {
            continue;
        };
        if !ws.linearize(system, &x, report) {
            continue;
        }
        let previous = (along.tx.as_slice(), 0.0);
        let Some((next, next_fl)) = tangent(system, homotopy, ws, x, lambda, Some(previous), report) else {
            continue;
        };
        let mut unstable = index(system, ws, &next.x, family.is_some(), report);
        let mut next = Some((next, next_fl));
        if unstable.is_some_and(|k| k > unstable_before) {
            match family {
                // On a family's member the family's own direction is neutral (an exact zero
                // of the second variation, at the base), and the guide's error tips it either
                // way: one direction more is that one.
                Some(_) if unstable == Some(unstable_before + 1) => unstable = Some(unstable_before),
                // A guide's error can tip a nearly neutral direction (the plane of a slightly
                // imperfect round column's bend): the count is confirmed at the point
                // converged to the solve's tolerance.
                Some(_) => {}
                None => {
                    let (p, _) = next.take()?;
                    next = converged(system, homotopy, ws, p, settings, report);
                    unstable = next.as_ref().and_then(|(p, _)| index(system, ws, &p.x, false, report));
                }
            }
        }
        if let Some((next, _)) = next
            && unstable.is_some_and(|k| k <= unstable_before)
        {
            return Some(Switched {
                point: next,
                unstable,
                picked: symmetric,
                family,
                at,
            });
        }
    }
    None
}

/// `point` converged by Newton at its lambda to the solve's tolerance, with its Jacobian
/// factored and its tangent oriented as before (a parameter's path only: Newton solves
/// F = 0, not a Newton homotopy's residual). None if Newton does not converge.
fn converged(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    point: Point,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<(Point, Vec<f64>)> {
    if !matches!(homotopy, Homotopy::Parameter { .. }) {
        return None;
    }
    homotopy.set(system, point.lambda);
    let mut x = point.x;
    let (term, _) = newton::run(system, ws, &mut x, settings, report);
    if term != Termination::Converged || !ws.linearize(system, &x, report) {
        return None;
    }
    let previous = Some((point.tx.as_slice(), point.tl));
    tangent(system, homotopy, ws, x, point.lambda, previous, report)
}
