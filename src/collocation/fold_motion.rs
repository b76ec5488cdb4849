//! EXPERIMENT (issue 25, fold14; not for merge): the robot's route at a fold of its load path.
//! With the environment variable `TDCR_FOLD_MOTION=<delta>`, a load path from rest that meets
//! a fold on a stable branch (the robot loaded from rest snaps there) locates the fold
//! (lambda_f, by bisection on the step's arclength as `locate::fold`, keeping the state on
//! the stable side), runs the robot's damped motion (module `relax`) from the fold's state
//! under the load lambda_f + delta (at most 1), and follows the load path on from where it
//! comes to rest to lambda = 1, snapping again at its next fold, at most [`MAX_CHAIN`] times
//! (past that the path goes on as main's does). Main's answer instead is Newton at the full
//! load from the folds' states (module `snap`, [`super::snap::land_from_folds`]). Each
//! landing prints one `fold14:` line on standard error.

use super::homotopy::{Homotopy, Point, tangent};
use super::newton::{Settings, Workspace};
use super::options::Options;
use super::path::{End, Start, correct_to, follow};
use super::relax::relax;
use super::system::System;
use crate::report::SolveReport;
use crate::solution::State;

/// The most motions from folds one solve chains (each followed by a path on from its rest).
pub(super) const MAX_CHAIN: usize = 8;
/// The fold is located to this share of the way (as `locate::LOCATED`).
const LOCATED: f64 = 1e-6;
/// The most bisections of the step that crossed the fold.
const MAX_BISECTIONS: usize = 60;

/// The load past the fold at which the motion runs, from `TDCR_FOLD_MOTION` (None: main's
/// landing).
pub(super) fn delta() -> Option<f64> {
    std::env::var("TDCR_FOLD_MOTION").ok()?.parse::<f64>().ok()
}

/// The fold crossed by the step of arclength `h` from `point` (stable, going forward) to
/// `next`, located, and the stable state where the damped motion from the fold's state comes
/// to rest under the load lambda_f + `delta` (at most 1): (lambda_f, that load, the state),
/// with `system` at that load; None (and `next`'s Jacobian factored again, `system` at its
/// load) when the motion does not come to rest at a stable state.
#[allow(clippy::too_many_arguments)]
pub(super) fn at_fold(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    (point, h): (&Point, f64),
    next: &Point,
    delta: f64,
    settings: &Settings,
    report: &mut SolveReport,
    r: &mut [f64],
) -> Option<(f64, f64, Vec<State>)> {
    let side = point.tl > 0.0;
    let (mut lo, mut hi) = (0.0, h);
    let mut slope = next.tl.abs().max(point.tl.abs());
    // The last located state on the path's side of the fold (stable, before the turn).
    let (mut lf, mut xf) = (point.lambda, point.x.clone());
    for _ in 0..MAX_BISECTIONS {
        if (hi - lo) * slope <= 0.5 * LOCATED {
            break;
        }
        let m = 0.5 * (lo + hi);
        let Some((x, l, _)) = correct_to(system, homotopy, ws, point, m, settings.tolerance, report, r, None) else {
            break;
        };
        homotopy.set(system, l);
        if !ws.linearize(system, &x, report) {
            break;
        }
        let Some((p, _)) = tangent(system, homotopy, ws, x, l, Some((&point.tx, point.tl)), report) else {
            break;
        };
        slope = p.tl.abs();
        if (p.tl > 0.0) == side {
            lo = m;
            (lf, xf) = (l, p.x);
        } else {
            hi = m;
        }
    }
    let load = (lf + delta).min(1.0);
    homotopy.set(system, load);
    let tip = |x: &[State]| x[x.len() - 1].p * 1e3;
    let t = tip(&xf);
    eprintln!("fold14: the fold's state: tip ({:.1}, {:.1}, {:.1}) mm", t.x, t.y, t.z);
    let rested = relax(system, ws, xf, settings, report);
    match rested {
        Some(x) => {
            let t = tip(&x);
            eprintln!(
                "fold14: fold at lambda {lf:.6} (step's next point {:.6}); motion at {load:.6} came to rest at tip ({:.1}, {:.1}, {:.1}) mm, {} iterations so far",
                next.lambda, t.x, t.y, t.z, report.iterations
            );
            Some((lf, load, x))
        }
        None => {
            eprintln!("fold14: fold at lambda {lf:.6}; the motion at {load:.6} did not come to rest at a stable state");
            homotopy.set(system, next.lambda);
            // The path checks the factors at its next step: a failure here is a failed step there.
            let _ = ws.linearize(system, &next.x, report);
            None
        }
    }
}

/// The load path on from `x`, at rest at load factor `load` after the motion from the fold
/// at `lf`, to the full load (the `chain`-th motion of this solve); the path before it
/// (`before`: folds, bifurcations, sides picked, family) is merged into the end, and an end
/// not itself landed or snapped records the fold it came from.
#[allow(clippy::too_many_arguments)]
pub(super) fn onwards(
    system: &mut System,
    ws: &mut Workspace,
    (x, lf, load, chain): (Vec<State>, f64, f64, usize),
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
    before: (Vec<f64>, Vec<f64>, Vec<f64>, bool),
) -> std::result::Result<End, (String, usize)> {
    let (mut folds, mut bifurcations, mut picked, family) = before;
    let mut end = if load >= 1.0 {
        End::landed(x, Vec::new(), Vec::new(), Vec::new(), false, (lf, false))
    } else {
        let followed = follow(
            system,
            ws,
            Start::Resting {
                x: &x,
                lambda: load,
                chain,
            },
            options,
            settings,
            report,
            None,
        );
        if let Err((hint, _)) = &followed {
            eprintln!("fold14: the path on from the rest state failed: {hint}");
        }
        followed?
    };
    let tip = end.x[end.x.len() - 1].p * 1e3;
    eprintln!(
        "fold14: chain {chain}: the path on ends at tip ({:.1}, {:.1}, {:.1}) mm",
        tip.x, tip.y, tip.z
    );
    folds.append(&mut end.folds);
    bifurcations.append(&mut end.bifurcations);
    picked.append(&mut end.picked);
    (end.folds, end.bifurcations, end.picked) = (folds, bifurcations, picked);
    end.family |= family;
    if end.relaxed_from.is_none() && end.snapped_from.is_none() {
        end.snapped_from = Some((lf, false));
    }
    Ok(end)
}
