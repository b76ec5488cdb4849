//! The equilibrium choice (docs/stability.md, "Which equilibrium a solve returns"): Newton's
//! answer from the start stands when it converged cleanly to a stable state;
//! otherwise the Newton homotopy from a warm start, Newton from the cold guess, and the load
//! path from rest are tried in turn, and every answer gets its stability verdict.

use super::linear::LinearSolver;
use super::newton::{self, Settings, Workspace};
use super::options::{Equilibrium, Options};
use super::path;
use super::pipeline::not_converged;
use super::system::System;
use super::{dynamics, neutral, stability};
use crate::error::Result;
use crate::mesh::{guess, spare};
use crate::report::{PathTaken, SolveReport, Stability, Termination};
use crate::solution::State;
use std::time::Instant;

/// A warm start whose predicted Newton step is at most this (max-norm in the scaled unknowns:
/// a tenth of L in position, 0.1 rad in rotation) is near the new equilibrium on its branch:
/// Newton from there converges in a few steps (4-6 in a fine sweep), whatever the residual of
/// the cold guess, which for an upright buckled robot can be smaller (the straight rod nearly
/// balances) and lead to the other, unstable branch.
const NEAR: f64 = 0.1;

/// The Newton workspace factored at the warm start `warm` of a stable state, when the Newton
/// step predicted from it is at most [`NEAR`]: the warm start is kept, and Newton's first
/// step is a chord step on these factors (the step predicted). None otherwise, and then the
/// start is chosen by [`better_start`].
pub(crate) fn near_start(
    system: &System,
    warm: &[State],
    solver: LinearSolver,
    report: &mut SolveReport,
) -> Option<Workspace> {
    let mut ws = Workspace::new(system, solver).ok()?;
    if !ws.linearize(system, warm, report) {
        return None;
    }
    let rhs: Vec<f64> = ws.residual().iter().map(|v| -v).collect();
    let step = ws.solve_again(&rhs)?;
    let size = step.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    (size <= NEAR).then_some(ws)
}

/// Of a warm start and the cold initial guess, the one with the smaller scaled residual. A
/// previous solution for other tensions can be a worse start than the rigid-equilibrium
/// estimate, which is nearly exact for tendon-dominated loading; comparing costs one
/// residual evaluation each.
pub(crate) fn better_start(system: &System, warm: Vec<State>, cold: Vec<State>) -> (Vec<State>, Choose) {
    let mut r = vec![0.0; system.unknowns()];
    let mut norm = |x: &[State]| match system.residual(x, &mut r) {
        Ok(()) => r
            .iter()
            .fold(0.0f64, |m, v| if v.is_nan() { f64::INFINITY } else { m.max(v.abs()) }),
        Err(_) => f64::INFINITY,
    };
    if norm(&cold) < norm(&warm) {
        (cold, Choose::FromCold)
    } else {
        (warm, Choose::FromWarm)
    }
}

/// Whether a mesh's Newton solve chooses the equilibrium ([`choose_equilibrium`]), and from
/// which start.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Choose {
    /// The initial guess.
    FromCold,
    /// A warm start (a solution of a nearby robot).
    FromWarm,
    /// A warm start whose branch the solve keeps to (what a sweep's bisection solves,
    /// [`super::solve_on_branch`]): its load path neither snaps from a bifurcation nor lands
    /// from its folds, so that the bisection sees where that branch ends or loses stability.
    OnBranch,
    /// No choice: a finer mesh warm-started from the chosen equilibrium on the last one.
    No,
    /// As [`Choose::FromCold`] or [`Choose::FromWarm`] (`warm`), except that a direct answer
    /// (step 1 or 3 of docs/stability.md, "Which equilibrium a solve returns": Newton from
    /// the start, cleanly) is accepted without its verdict: the start of a solve with
    /// friction, whose answer's own verdict decides instead and which falls back to the full
    /// choice when that verdict is not `stable` (collocation/friction/mod.rs, docs/friction.md
    /// section 3). Every other step of the choice is unchanged.
    Unassessed {
        /// Whether the start is a warm start.
        warm: bool,
        /// Whether Newton still evaluates the Jacobian at a direct answer
        /// ([`newton::run_ahead`]): the verdict is deferred, not dropped (a tension solve's
        /// first mesh under error control takes it after its error estimate when that mesh
        /// is the last, `pipeline::solve_on_mesh`; docs/stability.md "Which equilibrium a
        /// solve returns").
        ahead: bool,
    },
}

impl Choose {
    /// The choice with direct answers accepted without their verdict
    /// ([`Choose::Unassessed`]), from the same start; `self` for [`Choose::No`] and
    /// [`Choose::OnBranch`] (which no solve with friction starts with).
    pub(crate) fn unassessed(self) -> Choose {
        self.unassessed_with(false)
    }

    /// [`Choose::unassessed`] with Newton's Jacobian at a direct answer still evaluated
    /// when `ahead` ([`Choose::Unassessed`]).
    pub(crate) fn unassessed_with(self, ahead: bool) -> Choose {
        match self {
            Choose::FromCold => Choose::Unassessed { warm: false, ahead },
            Choose::FromWarm => Choose::Unassessed { warm: true, ahead },
            other => other,
        }
    }
}

/// The most Newton iterations of a direct solve that counts as clean: from a guess on the
/// right branch Newton converges in 2-8 (docs/numerics.md); more means it wandered. The
/// direct route of a solve with friction holds its Newton to the same bound
/// (collocation/friction/direct.rs).
pub(crate) const CLEAN_ITERATIONS: usize = 12;

/// Whether Newton went straight to its root: no damped step and few iterations. A damped
/// step means the guess was outside Newton's region of quadratic convergence, where the
/// iteration can cross to another branch of equilibria.
fn clean(history: &[crate::report::Iteration]) -> bool {
    history.len() <= CLEAN_ITERATIONS && history.iter().all(|i| i.damping == 1.0)
}

/// The stability of the equilibrium `x` of `system` ([`stability`]), from the Jacobian at
/// `x`: the one in `ws` when it belongs to `x` ([`Workspace::jacobian_at_iterate`]: `x` is
/// the last iterate, and the Jacobian was evaluated there or within Newton's stopping
/// distance of it), else one evaluated at `x` for the verdict ([`Workspace::verdict_at`]:
/// assembled, not factored). Newton's last Jacobian is evaluated one step before its answer;
/// after one Newton step and chord steps (or chord steps alone, on a cached solve's
/// factors) that is the guess, whose verdict a change of inputs can have made wrong. When
/// `exact` (the end of a load path, whose factors may belong to a point before the end) the
/// Jacobian at `x` is evaluated and factored, so that the error estimate's solve uses it too.
/// A root the conjugate-point test leaves in the neutral zone at the base is decided by
/// module `neutral`'s rule, the one the load path's count follows.
pub(crate) fn stability_of(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    exact: bool,
    report: &mut SolveReport,
) -> Stability {
    if let Some(reason) = stability::non_conservative(&system.model) {
        return linearized_dynamics(system, ws, x, reason, report);
    }
    if !exact && let Some(verdict) = ws.held_verdict() {
        return verdict;
    }
    if exact || !ws.has_factors() {
        if !ws.linearize(system, x, report) {
            return Stability::Unknown {
                reason: "the Jacobian at the solution is singular or not finite".into(),
            };
        }
    } else if !ws.jacobian_at_iterate() {
        let Some(verdict) = ws.verdict_at(system, x, report, |values| neutral::count(values, system)) else {
            return Stability::Unknown {
                reason: "the Jacobian at the solution is not finite".into(),
            };
        };
        return neutral::settle(system, ws, x, verdict, report);
    }
    neutral::verdict(system, ws, x, report)
}

/// The verdict [`stability_of`] would return for the last iterate of `ws` without evaluating
/// anything, when it is already held: conservative loads (`model`), not `exact`, and the
/// workspace's verdict belongs to its Jacobian and that Jacobian to the iterate
/// ([`Workspace::held_verdict`]). The end of a solve asks for the verdict the equilibrium
/// choice has just computed; this spares it building the mesh's [`System`] again.
pub(crate) fn held_stability(model: &crate::model::equations::Model, ws: &Workspace, exact: bool) -> Option<Stability> {
    if exact || stability::non_conservative(model).is_some() {
        return None;
    }
    ws.held_verdict()
}

/// The verdict of the linearized dynamics ([`dynamics::assess`]) for loads that are not
/// conservative (`why`: which load), with the Jacobian at `x` evaluated and factored
/// first: Newton's last Jacobian belongs to the iterate before `x`, which after a single
/// step is the guess, where the internal forces (and with them the load's geometric
/// stiffness) are still zero. A system with tendons with friction keeps an `unknown`
/// verdict here: its capstan rows border the system, and its answer's verdict is
/// `dynamics::friction`'s, on the bordered factors (the equilibrium choice runs on the
/// frictionless robot).
fn linearized_dynamics(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    why: String,
    report: &mut SolveReport,
) -> Stability {
    if system.friction.is_some() {
        return Stability::Unknown { reason: why };
    }
    // The verdict of this state already computed (the equilibrium choice's, asked again at
    // the end of the solve), if nothing moved since.
    if let Some(verdict) = ws.dynamics_verdict() {
        return verdict;
    }
    // The factors of the Jacobian at `x` may be held already (the path's last corrector
    // step evaluated and factored it there, and no step was taken since); or Newton
    // evaluated it at `x` in place of its last residual, keeping eq. 13's factored
    // matrices, and it is only factored here (`newton::run_ahead`); else it is evaluated
    // keeping those matrices, which the mass solves with.
    let kept = if ws.kept_at_iterate() {
        if !ws.factor_kept(report) {
            return Stability::Unknown {
                reason: "the Jacobian at the solution is singular".into(),
            };
        }
        true
    } else {
        let kept = !ws.factors_at_iterate();
        if kept && !ws.linearize_keeping(system, x, report) {
            return Stability::Unknown {
                reason: "the Jacobian at the solution is singular or not finite".into(),
            };
        }
        kept
    };
    let verdict = dynamics::assess(system, x, ws, kept);
    ws.keep_dynamics(verdict.clone());
    verdict
}

/// Newton from `x`, given only the chance to converge cleanly ([`clean`]) unless
/// `nearest`: the converged states, if they are stable ([`acceptable`]) or `nearest`; with
/// `unassessed` ([`Choose::Unassessed`]) a clean answer without its verdict (with Newton's
/// Jacobian at it when `ahead`).
fn direct(
    system: &System,
    ws: &mut Workspace,
    x: &mut Vec<State>,
    (nearest, unassessed, ahead): (bool, bool, bool),
    settings: &Settings,
    report: &mut SolveReport,
) -> (bool, usize) {
    let direct = Settings {
        max_iterations: if nearest {
            settings.max_iterations
        } else {
            settings.max_iterations.min(CLEAN_ITERATIONS)
        },
        stop_when_damped: !nearest,
        ..*settings
    };
    // The verdict below evaluates the plain Jacobian at the answer (`Workspace::verdict_at`,
    // or keeping eq. 13's factored matrices for the linearized dynamics): Newton evaluates
    // it at its last trial point instead of the residual there. An unassessed answer takes
    // no verdict here (its friction verdict is the bordered system's), so it keeps the
    // plain residual, unless its verdict is only deferred (`ahead`).
    let (termination, worst) = if !nearest && (!unassessed || ahead) && plain_verdict(system) {
        newton::run_ahead(system, ws, x, &direct, report)
    } else {
        newton::run(system, ws, x, &direct, report)
    };
    report.termination = termination;
    if termination != Termination::Converged {
        return (false, worst);
    }
    if nearest {
        return (true, worst);
    }
    if !clean(&report.history) {
        return (false, worst);
    }
    if unassessed {
        return (true, worst);
    }
    let t = Instant::now();
    let verdict = stability_of(system, ws, x, false, report);
    report.timings.stability += t.elapsed();
    (acceptable(system, &verdict), worst)
}

/// Whether [`stability_of`] (not `exact`) of a state Newton reached on `system` with `ws`
/// evaluates the plain Jacobian there when the one held is too far (no friction:
/// [`Workspace::verdict_at`] for conservative loads, with the tension columns when the
/// workspace keeps them; [`Workspace::linearize_keeping`] for loads that are not
/// conservative): then Newton may evaluate it at its last trial point instead of the
/// residual ([`newton::run_ahead`], [`Workspace::jacobian_ahead`]).
pub(crate) fn plain_verdict(system: &System) -> bool {
    system.friction.is_none()
}

/// Whether a state with this verdict may be the answer without a path: only a stable one
/// (by the conjugate-point test, or for loads that are not conservative by the linearized
/// dynamics), or, where the loads admit neither verdict (tendons with friction and a
/// non-conservative load), one of unknown stability.
fn acceptable(system: &System, verdict: &Stability) -> bool {
    match verdict {
        Stability::Stable => true,
        Stability::Unstable { .. } | Stability::Growing { .. } => false,
        Stability::Unknown { .. } => stability::non_conservative(&system.model).is_some(),
    }
}

/// The note of a side picked at a perfectly symmetric bifurcation at load factor `lambda`;
/// `family`: the states returned, when the branch taken was one member of a family of
/// equilibria (a round column's buckled states in every plane, collocation/phase.rs).
fn picked_note(lambda: f64, family: Option<&[State]>) -> String {
    if let Some(x) = family {
        // The bending plane: the tip's displacement across the base axis, in the base frame.
        let (base, tip) = (&x[0], &x[x.len() - 1]);
        let d = base.R.transpose() * (tip.p - base.p);
        let azimuth = d.y.atan2(d.x).to_degrees();
        return format!(
            "the loads are symmetric about the base axis, and the path crossed a bifurcation at {:.1} % of \
             the way where the robot can bend in every plane alike: it took the plane at azimuth {azimuth:.1} \
             deg in the base frame (tip {:.1} mm, {:.1} mm across the base axis along base x, y) and held \
             it; every rotation of this state about the base axis is an equally valid equilibrium, among \
             them its mirror image at azimuth {:.1} deg, and an imperfection selects one",
            100.0 * lambda,
            1e3 * d.x,
            1e3 * d.y,
            if azimuth > 0.0 {
                azimuth - 180.0
            } else {
                azimuth + 180.0
            }
        );
    }
    format!(
        "the path crossed a perfectly symmetric bifurcation at {:.1} % of the way, where nothing \
         prefers a side: it took the branch along the Jacobian's kernel direction; its mirror state \
         (bent the opposite way, along the reversed kernel direction) is equally valid, and an \
         imperfection of the other sign selects it",
        100.0 * lambda
    )
}

/// The note of a path completed by Newton at the full load from the fold at load factor
/// `lambda` (the robot snaps there): `reached`, the path reached the full load on an unstable
/// state after its folds; else it could not be followed to the end.
fn snapped_note((lambda, reached): (f64, bool)) -> String {
    let why = match reached {
        true => "the path reached the full load on an unstable state after its folds",
        false => {
            "the path could not be followed to the full load (it stalled, or went round a family of \
             equilibria at nearly constant load)"
        }
    };
    format!(
        "{why}: the robot snaps at the fold at {:.1} % of the way, and this stable state was reached \
         by Newton at the full load from the state there, not by continuation",
        100.0 * lambda
    )
}

/// The note of a path that snapped at the fold at load factor `lambda`, where the landing
/// from its folds found no stable state (`reached`: as [`snapped_note`]), completed by the
/// robot's damped motion just past the fold and the load path on from where it came to rest.
fn moved_note((lambda, reached): (f64, bool)) -> String {
    let why = match reached {
        true => "the path reached the full load on an unstable state after its folds",
        false => "the path could not be followed to the full load",
    };
    format!(
        "{why}, and Newton at the full load from its folds found no stable state: the robot snaps at \
         the fold at {:.1} % of the way, and this is the state where the load path goes on from \
         the state its damped motion just past the fold comes to rest in",
        100.0 * lambda
    )
}

/// The note of a path that lost stability at the bifurcation at load factor `lambda` with no
/// stable branch it could follow, completed by the robot's damped motion from there;
/// `picked`: the motion started on a side picked (a perfect symmetry).
fn relaxed_note((lambda, picked): (f64, bool)) -> String {
    let side = match picked {
        true => "on a side picked, since the loads prefer neither",
        false => "on the side the load path leaned to",
    };
    format!(
        "the robot loses its stability at the bifurcation at {:.1} % of the way, where the load path \
         finds no stable branch to follow: it snaps there, and this stable state is where its damped \
         motion from there (started along the unstable direction, {side}) comes to rest under the \
         full load, not a state reached by continuation",
        100.0 * lambda
    )
}

/// Newton from `x0`, and the equilibrium choice of docs/stability.md. Newton's answer
/// stands when it converged cleanly to a stable state ([`acceptable`]; or the caller asked
/// for the nearest equilibrium). Otherwise, from a warm start (`choose`: [`Choose::FromWarm`]
/// or [`Choose::OnBranch`]), the Newton homotopy from it ([`path::follow`]), whose end stands
/// if it is stable; then Newton from the cold guess, as above; then the load path from the
/// unloaded robot, which snaps from a bifurcation or lands from a fold unless the solve keeps
/// to its warm start's branch ([`Choose::OnBranch`]). Newton's answer from `x0`, if it
/// converged at all, is the fallback when no path can be followed.
pub(crate) fn choose_equilibrium(
    system: &mut System,
    ws: &mut Workspace,
    x0: Vec<State>,
    choose: Choose,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    let chosen = choose_from(system, ws, &x0, choose, options, settings, report);
    // The start's buffer goes back to the thread's kept ones (Newton iterated on a copy).
    spare::give(x0);
    chosen
}

/// [`choose_equilibrium`] from the start `x0`.
fn choose_from(
    system: &mut System,
    ws: &mut Workspace,
    x0: &[State],
    choose: Choose,
    options: &Options,
    settings: &Settings,
    report: &mut SolveReport,
) -> Result<Vec<State>> {
    report.unknowns = system.unknowns();
    report.nonzeros = ws.nonzeros();
    report.intervals = system.mesh.intervals();
    let (warm, unassessed, ahead) = match choose {
        Choose::Unassessed { warm, ahead } => (warm, true, ahead),
        _ => (matches!(choose, Choose::FromWarm | Choose::OnBranch), false, false),
    };
    let nearest = options.equilibrium == Equilibrium::Nearest || !options.continuation;
    let mut x = spare::copy(x0);
    let (accept, worst) = direct(system, ws, &mut x, (nearest, unassessed, ahead), settings, report);
    let converged = report.termination == Termination::Converged;
    if accept {
        return Ok(x);
    }
    if !options.continuation {
        return Err(not_converged(
            system,
            report,
            worst,
            "enable load continuation, refine the mesh, or warm-start from a nearby solution",
        ));
    }
    let fallback = converged.then_some(x);
    if warm {
        if let Ok(end) = path::follow(system, ws, path::Start::Warm(x0), options, settings, report, None) {
            let exact = !report.history.iter().any(|i| i.fresh_jacobian);
            let verdict = stability_of(system, ws, &end.x, exact, report);
            if acceptable(system, &verdict) {
                report.notes.extend(
                    end.picked
                        .iter()
                        .map(|&l| picked_note(l, end.family.then_some(&end.x[..]))),
                );
                report.notes.extend(end.moved_from.iter().map(|&m| moved_note(m)));
                report.notes.extend(end.snapped_from.map(snapped_note));
                report.notes.extend(end.relaxed_from.map(relaxed_note));
                report.path = PathTaken::FromWarmStart {
                    folds: end.folds,
                    bifurcations: end.bifurcations,
                };
                return Ok(end.x);
            }
        }
        system.set_factors(1.0, 1.0);
        let mut cold = guess::initial(&system.model, &system.mesh.nodes, options.initial_guess);
        if direct(system, ws, &mut cold, (false, unassessed, ahead), settings, report).0 {
            return Ok(cold);
        }
    }
    let mesh = system.mesh.clone();
    match path::follow(
        system,
        ws,
        path::Start::Rest {
            land: choose != Choose::OnBranch,
        },
        options,
        settings,
        report,
        None,
    ) {
        Ok(end) => {
            report.notes.extend(
                end.picked
                    .iter()
                    .map(|&l| picked_note(l, end.family.then_some(&end.x[..]))),
            );
            report.notes.extend(end.moved_from.iter().map(|&m| moved_note(m)));
            report.notes.extend(end.snapped_from.map(snapped_note));
            report.notes.extend(end.relaxed_from.map(relaxed_note));
            report.path = PathTaken::LoadPath {
                folds: end.folds,
                bifurcations: end.bifurcations,
            };
            report.unknowns = system.unknowns();
            report.nonzeros = ws.nonzeros();
            report.intervals = system.mesh.intervals();
            Ok(end.x)
        }
        // The path is lost: Newton's answer, if it has one, with its verdict.
        Err((hint, row)) => {
            if system.mesh != mesh {
                *system = System::new(system.model.clone(), mesh);
                *ws = Workspace::new(system, options.linear_solver)?;
            }
            system.set_factors(1.0, 1.0);
            let x = match fallback {
                Some(x) => x,
                None => {
                    let mut x = x0.to_vec();
                    let (termination, _) = newton::run(system, ws, &mut x, settings, report);
                    report.termination = termination;
                    if termination != Termination::Converged {
                        return Err(not_converged(system, report, row, &hint));
                    }
                    x
                }
            };
            if !ws.linearize(system, &x, report) {
                return Err(not_converged(system, report, row, &hint));
            }
            report.notes.push(format!(
                "the load path could not be followed ({hint}): this is Newton's root from the guess, \
                 not the state the robot reaches when loaded from rest"
            ));
            report.path = PathTaken::Fallback;
            report.termination = Termination::Converged;
            Ok(x)
        }
    }
}

#[cfg(test)]
mod tests;
