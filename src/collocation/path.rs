//! The load path: pseudo-arclength continuation in the load factor lambda (every tension and
//! external load times lambda) from the unloaded robot (lambda = 0) to the robot as given
//! (lambda = 1), the path a robot loaded from rest follows (docs/numerics.md, "Load path").
//!
//! Each step predicts along the tangent of the branch, (dx, dlambda) with
//! J dx + F_lambda dlambda = 0, from the factors of the Jacobian at the last point, and
//! corrects on the bordered system, with a Newton step at the predicted point and chord steps
//! on its factors (module `corrector`)
//!
//! ```text
//! F(x, lambda) = 0,    <t_x, x - x_pred> / n + t_lambda (lambda - lambda_pred) = 0,
//! ```
//!
//! eliminating the one extra unknown by two solves with the same factors (Keller's
//! bordering). A fold in lambda, where the branch turns back, is passed like any other
//! point: t_lambda changes sign there, and the fold is recorded (past it the robot snaps
//! through). The step grows when the corrector converges in a few steps and shrinks on
//! failure; when the shape bends more than the mesh resolves, the path continues on a finer
//! mesh. Near lambda = 1 the last point is predicted onto lambda = 1 and Newton lands there.

use super::branch;
pub(super) use super::corrector::{correct, correct_to};
use super::homotopy::{Homotopy, Point, dot, tangent};
use super::locate;
use super::neutral;
use super::newton::{self, Settings, Workspace};
use super::options::Options;
use super::path_index;
pub(super) use super::path_types::{End, Recorded, Start};
use super::phase::{Phase, generic};
use super::refine;
use super::snap;
use super::stability;
use super::system::System;
use crate::mesh::guess::rigid_estimate;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// The most Newton iterations of the landing at lambda = 1 from the predicted point.
const LANDING_ITERATIONS: usize = 12;
/// Step control: the corrector iterations of an easy step (the most it may take is the
/// corrector's, module `corrector`).
const EASY: usize = 2;
/// The first step and the bounds of the step, in units of the normalized arclength.
const FIRST_STEP: f64 = 0.3;
const MAX_STEP: f64 = 1.0;
/// Below this step the path has stalled: no solution nearby is continuous in the load.
const MIN_STEP: f64 = 1e-5;
/// The most steps along one path (a path of this many steps does not converge in practice).
const MAX_STEPS: usize = 400;
/// Steps from a point fail below this length: the point (a guide corrected to
/// [`PATH_TOLERANCE`](super::corrector::PATH_TOLERANCE)) is converged to the solve's
/// tolerance and its tangent taken again.
/// Near the sharp turn of a slightly imperfect column a guide's state error, amplified by
/// the nearly singular Jacobian, tilts the tangent so that no step from it converges.
const POLISH_BELOW: f64 = 1e-3;
/// A path that tries only steps of at most [`POLISH_BELOW`] this many times since its last
/// longer accepted step crawls instead of following its branch (the buckled family of a perfectly round
/// column, whose Jacobian is singular all along it): it has stalled. Healthy paths recover
/// their step length within a few steps after a turn.
const CRAWL_STEPS: usize = 40;
/// Why a Newton homotopy from a warm start was given up when it turned back past lambda = 0.
const WARM_TURNED_BACK: &str = "the path from the warm start turned back at a fold and returned past the warm start: \
     the warm start is not on a branch that reaches this robot; solve from rest";
/// A step that changes the number of unstable directions without a fold has jumped to
/// another branch near a bifurcation, unless it is this short (in normalized arclength):
/// then the path crosses a bifurcation point itself.
pub(super) const BIFURCATION_STEP: f64 = 1e-3;

/// Follows a path on `system` (whose mesh it may refine, replacing `system` and `ws`) from
/// lambda = 0 to 1 ([`Start`]): the load path from rest, the Newton homotopy from a warm
/// start (on its mesh), or a trace, whose points go to `record`. Returns the end, or a
/// hint and the worst residual row.
pub(super) fn follow(
    system: &mut System,
    ws: &mut Workspace,
    start: Start,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
    mut record: Option<&mut Vec<Recorded>>,
) -> std::result::Result<End, (String, usize)> {
    let robot = system.model.robot;
    let mut max_step = MAX_STEP;
    let mut stop: &dyn Fn() -> bool = &|| false;
    let mut landing = false;
    let (mut lambda0, mut chain) = (0.0, 0);
    let (x, homotopy) = match start {
        Start::Resting { x, lambda, chain: c } => {
            (landing, lambda0, chain) = (true, lambda, c);
            let homotopy = Homotopy::load();
            homotopy.set(system, lambda);
            (x.to_vec(), homotopy)
        }
        Start::Rest { land } => {
            landing = land;
            system.set_factors(0.0, 0.0);
            let mut x = rigid_estimate(&system.model, &system.mesh.nodes);
            let (start, row) = newton::run(system, ws, &mut x, settings, report);
            if start != Termination::Converged {
                report.termination = start;
                return Err(("the unloaded robot did not converge: refine the mesh".into(), row));
            }
            (x, Homotopy::load())
        }
        Start::Warm(x0) => {
            let mut r0 = vec![0.0; system.unknowns()];
            if system.residual(x0, &mut r0).is_err() || !r0.iter().all(|v| v.is_finite()) {
                return Err(("the warm start is not a state the model can evaluate".into(), 0));
            }
            (x0.to_vec(), Homotopy::Newton(r0))
        }
        Start::Trace {
            x,
            parameter,
            from,
            to,
            max_step: m,
            stop: asked,
        } => {
            max_step = m;
            stop = asked;
            let homotopy = Homotopy::Parameter { parameter, from, to };
            homotopy.set(system, 0.0);
            (x.to_vec(), homotopy)
        }
    };
    let tracing = record.is_some();
    // The count compared between points: under loads that are not conservative the
    // conjugate-point count as a label of the branch, which sees folds, real bifurcations and
    // jumps to another branch (module `path_index`); a trace records the verdict's count
    // (unknown for such loads: the label is no verdict).
    let index = |system: &System, ws: &mut Workspace, x: &[State], family, report: &mut SolveReport| {
        if tracing {
            neutral::index(system, ws, x, family, report)
        } else {
            path_index::index(system, ws, x, family, report)
        }
    };
    // A trace records its own branch; every other path leaves a stable branch for a stable
    // one where the branch it is on loses stability (module `branch`). Switching, snapping
    // and landing need states known to be stable, which only the conservative count gives:
    // under other loads the count labels branches and nothing more (they would give up).
    let conservative = stability::non_conservative(&system.model).is_none();
    landing &= conservative;
    let mut switching = !tracing && conservative;
    let mut picked = Vec::new();
    // The phase condition of a family's branch, once the path has taken one (module `phase`).
    let mut phase: Option<Phase> = None;
    let mut family = false;
    if !ws.linearize(system, &x, report) {
        return Err(("the Jacobian at the start of the path is singular".into(), 0));
    }
    let Some((mut point, _)) = tangent(system, &homotopy, ws, x, lambda0, None, report) else {
        return Err(("the path's first tangent is not finite".into(), 0));
    };
    let mut unstable = index(system, ws, &point.x, false, report);
    let mut folds = Vec::new();
    let mut bifurcations = Vec::new();
    // From a warm start the first try is the whole way: predict with the sensitivities
    // (the tangent) to lambda = 1 and land there, a step shortened only if that fails.
    let mut h = match homotopy {
        Homotopy::Parameter { .. } => FIRST_STEP.min(max_step),
        Homotopy::Newton(_) => 1.0 / point.tl.max(1e-3),
    };
    let push = |record: &mut Option<&mut Vec<Recorded>>, p: &Point, unstable, fold, report: &SolveReport| {
        if let Some(r) = record.as_mut() {
            r.push(Recorded {
                lambda: p.lambda,
                tip: p.x[p.x.len() - 1],
                unstable,
                fold,
                iterations: report.iterations,
            });
        }
    };
    push(&mut record, &point, unstable, false, report);
    let mut factored_at_point = true;
    // Whether the point was converged to the solve's tolerance after steps from it failed.
    let mut polished = false;
    // Tries of at most POLISH_BELOW since the last longer accepted step.
    let mut crawl = 0;
    let mut furthest = 0.0f64;
    let mut worst = 0;
    let mut trial: Vec<State> = Vec::with_capacity(system.mesh.nodes.len());
    let mut r = vec![0.0; system.unknowns()];
    // The states at the folds passed, with their load factors: where the path cannot be
    // followed to the end, the robot snaps from one of them ([`snap::land_from_folds`]).
    let mut fold_states: Vec<(f64, Vec<State>)> = Vec::new();
    // The first fold met on a stable branch, where the robot snaps: where the landing from
    // the folds finds no stable state, its own route from there ([`snap::from_fold`]).
    let mut first_fold: Option<snap::Fold> = None;
    // A side picked at a simple symmetric bifurcation (load factor, first state past it), and
    // the path's progress in lambda since (module `snap`, [`snap::Stall`]).
    let mut switched: Option<(f64, Vec<State>)> = None;
    let mut stall = snap::Stall::default();
    for _ in 0..MAX_STEPS {
        if stop() {
            return Err(("stopped on request before the end of the range".into(), 0));
        }
        report.load_steps += 1;
        if h <= POLISH_BELOW {
            crawl += 1;
            if crawl > CRAWL_STEPS {
                break;
            }
        }
        // The last step lands on lambda = 1 by Newton at fixed lambda.
        if point.tl > 0.0 && point.lambda + h * point.tl >= 1.0 {
            let h1 = (1.0 - point.lambda) / point.tl;
            let step: Vec<f64> = point.tx.iter().map(|v| v * h1).collect();
            system.retract(&point.x, &step, 1.0, &mut trial);
            let mut landed = trial.clone();
            homotopy.set(system, 1.0);
            // Newton lands only if it lands cleanly (no damped step): a damped step could
            // cross to another branch.
            let land = Settings {
                reuse_factors: factored_at_point,
                stop_when_damped: true,
                max_iterations: settings.max_iterations.min(LANDING_ITERATIONS),
                ..*settings
            };
            // On a family's branch the landing keeps the phase condition (at lambda = 1: the
            // hyperplane of the tangent (0, 1)); Newton on the free problem then starts
            // from an equilibrium of it (mu = 0 on the family) and only confirms it.
            if let Some(p) = phase.as_ref() {
                let at_one = Point {
                    x: trial.clone(),
                    lambda: 1.0,
                    // The unknowns of the mesh now (the path may have moved to a finer one).
                    tx: vec![0.0; system.unknowns()],
                    tl: 1.0,
                };
                let held = super::corrector::correct_to(
                    system,
                    &homotopy,
                    ws,
                    &at_one,
                    0.0,
                    settings.tolerance,
                    report,
                    &mut r,
                    Some(p),
                );
                if let Some((x, _, _)) = held {
                    landed = x;
                }
            }
            let (term, row) = newton::run(system, ws, &mut landed, &land, report);
            report.termination = term;
            // The landing is a step like any other: if it changes the number of unstable
            // directions it jumped to another branch near a bifurcation (unless it is short).
            let mut landed_unstable = if term == Termination::Converged && ws.linearize(system, &landed, report) {
                index(system, ws, &landed, phase.is_some(), report)
            } else {
                None
            };
            if phase.is_some() {
                landed_unstable = Phase::neutral(unstable, landed_unstable);
            }
            let jumped = matches!((unstable, landed_unstable), (Some(a), Some(b)) if a != b);
            if term == Termination::Converged && !(jumped && h1 > BIFURCATION_STEP) {
                if jumped {
                    bifurcations.push(1.0);
                }
                // A path that reaches the full load on an unstable state after folds: the
                // robot snapped at one of them (docs/stability.md, "A path that ends unstable
                // after its folds lands from them").
                if landing && landed_unstable.is_some_and(|b| b > 0) && !fold_states.is_empty() {
                    if let Some((lambda, x)) = snap::land_from_folds(system, ws, &fold_states, settings, report) {
                        return Ok(End::landed(x, folds, bifurcations, picked, family, (lambda, true)));
                    }
                    let path = (
                        folds.as_slice(),
                        bifurcations.as_slice(),
                        picked.as_slice(),
                        family,
                        true,
                    );
                    let fold = first_fold.as_ref();
                    if let Some(end) =
                        snap::from_fold(system, &homotopy, ws, fold, path, chain, options, settings, report)
                    {
                        return end;
                    }
                    // The landings factored other states: factor this one's again, so that the
                    // verdict read later is its own (it was factored above, so this succeeds).
                    report.termination = term;
                    let _ = ws.linearize(system, &landed, report);
                }
                let end = Point {
                    x: landed.clone(),
                    lambda: 1.0,
                    tx: Vec::new(),
                    tl: 1.0,
                };
                push(&mut record, &end, landed_unstable, false, report);
                return Ok(End::reached(landed, folds, bifurcations, picked, family));
            }
            if let (true, Some(a), Some(b)) = (switching, unstable, landed_unstable)
                && b > a
                && let Some(mut s) = branch::switch(
                    system,
                    &homotopy,
                    ws,
                    &point,
                    (&landed, 1.0),
                    a,
                    settings,
                    report,
                    &mut r,
                )
            {
                s.record(&mut bifurcations, &mut picked);
                push(&mut record, &s.point, s.unstable, false, report);
                switched = (s.picked && s.family.is_none()).then(|| (s.at, s.point.x.clone()));
                (phase, family) = s.hold(system, &homotopy, ws, report);
                (point, unstable) = (s.point, s.unstable);
                (switching, polished, factored_at_point) = (false, false, true);
                h = h1.abs().min(max_step);
                continue;
            }
            if snap::snaps_here(landing, (unstable, landed_unstable), switching, h1, phase.is_some())
                && let Some((at, picked_side, x)) = snap::from_bifurcation(
                    system,
                    &homotopy,
                    ws,
                    (&point, unstable),
                    (&landed, 1.0),
                    settings,
                    report,
                )
            {
                return Ok(End::relaxed(x, folds, bifurcations, picked, family, (at, picked_side)));
            }
            if jumped {
                // Retry shorter from the last point, whose factors are gone.
                h = 0.25 * h1;
                factored_at_point = false;
                continue;
            }
            worst = row;
            factored_at_point = false;
            h = 0.5 * h1;
            if h < MIN_STEP {
                break;
            }
            continue;
        }
        let res = correct(
            system,
            &homotopy,
            ws,
            &point,
            h,
            settings,
            report,
            &mut r,
            phase.as_ref(),
        );
        match res {
            Some((xc, lambda, iterations)) => {
                if !ws.linearize(system, &xc, report) {
                    h *= 0.5;
                    factored_at_point = false;
                    if h < MIN_STEP {
                        break;
                    }
                    continue;
                }
                let previous = (point.tx.as_slice(), point.tl);
                phase = phase.take().and_then(|p| p.refreshed(ws));
                let next = match phase.as_ref() {
                    Some(p) => p.tangent(system, &homotopy, ws, xc, lambda, Some(previous), report),
                    None => tangent(system, &homotopy, ws, xc, lambda, Some(previous), report),
                };
                let Some((mut next, _)) = next else {
                    break;
                };
                let fold = (next.tl > 0.0) != (point.tl > 0.0);
                let mut next_unstable = index(system, ws, &next.x, phase.is_some(), report);
                if phase.is_some() {
                    next_unstable = Phase::neutral(unstable, next_unstable);
                }
                // A guide is converged to PATH_TOLERANCE only, and its error can tip a nearly
                // neutral direction (the plane of a slightly imperfect round column's bend,
                // held by the imperfection alone): a change of the count is confirmed at the
                // point converged to the solve's tolerance before it counts as a jump.
                if !fold
                    && unstable.is_some()
                    && next_unstable.is_some()
                    && next_unstable != unstable
                    && let Some((p, _)) =
                        super::corrector::polish(system, &homotopy, ws, &next, settings, report, &mut phase)
                {
                    next = p;
                    next_unstable = index(system, ws, &next.x, phase.is_some(), report);
                }
                if let (Some(a), Some(b)) = (unstable, next_unstable)
                    && a != b
                    && !fold
                {
                    if switching
                        && b > a
                        && let Some(mut s) = branch::switch(
                            system,
                            &homotopy,
                            ws,
                            &point,
                            (&next.x, lambda),
                            a,
                            settings,
                            report,
                            &mut r,
                        )
                    {
                        s.record(&mut bifurcations, &mut picked);
                        push(&mut record, &s.point, s.unstable, false, report);
                        switched = (s.picked && s.family.is_none()).then(|| (s.at, s.point.x.clone()));
                        (phase, family) = s.hold(system, &homotopy, ws, report);
                        (point, unstable) = (s.point, s.unstable);
                        // One switch per path: the branch taken can keep a nearly neutral
                        // direction (the plane of a round column's bend), whose count rounding
                        // decides, and the path does not leave it along that direction.
                        (switching, polished, factored_at_point) = (false, false, true);
                        furthest = furthest.max(point.lambda);
                        continue;
                    }
                    // A symmetric, simple bifurcation on a load path that may leave its branch where the
                    // path may not switch (it did once) or a step short enough to cross it
                    // found no stable branch: the robot snaps (docs/stability.md, "Snapping
                    // from a bifurcation").
                    if snap::snaps_here(landing, (Some(a), Some(b)), switching, h, phase.is_some())
                        && let Some((at, picked_side, x)) = snap::from_bifurcation(
                            system,
                            &homotopy,
                            ws,
                            (&point, unstable),
                            (&next.x, lambda),
                            settings,
                            report,
                        )
                    {
                        return Ok(End::relaxed(x, folds, bifurcations, picked, family, (at, picked_side)));
                    }
                    if h > BIFURCATION_STEP {
                        // Jumped to another branch: retry shorter.
                        h *= 0.25;
                        factored_at_point = false;
                        continue;
                    }
                    // A trace reports the crossing located, not the first point past it.
                    bifurcations.push(match tracing {
                        true => locate::bifurcation(system, &homotopy, ws, (&point, unstable), &next, settings, report),
                        false => lambda,
                    });
                }
                if fold && landing && first_fold.is_none() && unstable == Some(0) && point.tl > 0.0 {
                    let recorded = (folds.len(), bifurcations.len(), picked.len());
                    first_fold = Some(snap::Fold::new(&point, h, next.tl, recorded));
                }
                unstable = next_unstable;
                if fold && landing {
                    fold_states.push((lambda, next.x.clone()));
                }
                if fold {
                    folds.push(match tracing {
                        true => locate::fold(system, &homotopy, ws, (&point, h), &next, settings, report, &mut r),
                        false => lambda,
                    });
                }
                if next.lambda >= 0.0 {
                    push(&mut record, &next, unstable, fold, report);
                }
                // A trace ends where its branch leaves the range back past the start (that
                // point lies outside the range and is not recorded).
                if tracing && next.lambda < 0.0 {
                    return Ok(End::reached(next.x, folds, bifurcations, picked, family));
                }
                // A Newton homotopy back past its warm start has turned at a fold: its branch
                // does not carry the warm start to the robot (docs/stability.md, "Warm starts
                // that turn back"), and followed further it wanders below lambda = 0.
                if matches!(homotopy, Homotopy::Newton(_)) && next.lambda < 0.0 {
                    return Err((WARM_TURNED_BACK.into(), worst));
                }
                // The angle between successive tangents bounds the next step.
                let cos = (dot(&next.tx, &point.tx) / point.tx.len() as f64 + next.tl * point.tl).clamp(-1.0, 1.0);
                if h > POLISH_BELOW {
                    crawl = 0;
                }
                let grow = match iterations {
                    i if i <= EASY => 2.0,
                    i if i == EASY + 1 => 1.3,
                    _ => 0.8,
                };
                h = (h * grow).min(max_step);
                if cos < 0.9 {
                    h *= 0.5;
                }
                if landing && switched.is_some() && stall.crawls(lambda) {
                    break;
                }
                point = next;
                polished = false;
                furthest = furthest.max(point.lambda);

                factored_at_point = true;
                // A shape the mesh no longer resolves: continue on a finer one (the load
                // path only: a Newton homotopy's F(x0) belongs to its mesh).
                let floor = system.mesh.intervals();
                let needed = refine::start_intervals(robot, &point.x, floor).min(options.max_intervals);
                if matches!(homotopy, Homotopy::Parameter { .. }) && needed as f64 > 1.25 * floor as f64 {
                    match refine::remesh(system, &homotopy, ws, &point, needed, options, settings, report) {
                        Some((p, _)) => {
                            point = p;
                            r = vec![0.0; system.unknowns()];
                            // The family's directions on the new mesh, from a generic start.
                            if phase.is_some() {
                                phase = Phase::at(ws, generic(system.unknowns()), None);
                                let previous = (point.tx.as_slice(), point.tl);
                                let Some(held) = phase.as_ref().and_then(|p| {
                                    p.tangent(
                                        system,
                                        &homotopy,
                                        ws,
                                        point.x.clone(),
                                        point.lambda,
                                        Some(previous),
                                        report,
                                    )
                                }) else {
                                    return Err((refine::remesh_hint(point.lambda), worst));
                                };
                                point = held.0;
                            }
                        }
                        None => return Err((refine::remesh_hint(point.lambda), worst)),
                    }
                }
            }
            None => {
                h *= 0.5;
                factored_at_point = false;
                if !polished
                    && h < POLISH_BELOW
                    && let Some((p, _)) =
                        super::corrector::polish(system, &homotopy, ws, &point, settings, report, &mut phase)
                {
                    point = p;
                    factored_at_point = true;
                    polished = true;
                    h = POLISH_BELOW;
                    continue;
                }
                if h < MIN_STEP {
                    break;
                }
            }
        }
    }
    homotopy.set(system, 1.0);
    if landing
        && let Some((at, x)) = switched
        && let Some(x) = snap::relax_from(system, ws, x, settings, report)
    {
        picked.retain(|&l| l != at);
        return Ok(End {
            relaxed_from: Some((at, true)),
            ..End::reached(x, folds, bifurcations, picked, family)
        });
    }
    if landing && let Some((lambda, x)) = snap::land_from_folds(system, ws, &fold_states, settings, report) {
        return Ok(End::landed(x, folds, bifurcations, picked, family, (lambda, false)));
    }
    let path = (
        folds.as_slice(),
        bifurcations.as_slice(),
        picked.as_slice(),
        family,
        false,
    );
    if landing
        && let Some(end) = snap::from_fold(
            system,
            &homotopy,
            ws,
            first_fold.as_ref(),
            path,
            chain,
            options,
            settings,
            report,
        )
    {
        return end;
    }
    Err((refine::stalled_hint(furthest, point.lambda), worst))
}
