//! The damped motion of the robot from a state that has lost its stability to the state
//! where it comes to rest (docs/stability.md, "Snapping from a bifurcation").
//!
//! With viscous damping proportional to the rod's mass (a force -c rho A p_t and a moment
//! -c rho J_b w per length, c = 1/s) and no inertia, the collocation residual becomes
//! F(x) + M x_t = 0, M the mass matrix of the linearized dynamics (module `dynamics`). A
//! small motion about an equilibrium then goes as e^(-mu t) along the modes J phi = mu M phi:
//! the stable modes (mu > 0) die out and an unstable one (mu < 0) grows, so the motion
//! started next to a state that has lost its stability leaves it along its unstable mode and
//! comes to rest at a stable state. For conservative loads the energy falls along it.
//!
//! Each time step is one linearly implicit Euler step,
//!
//! ```text
//! (J(x) + M / dt) dx = -F(x),
//! ```
//!
//! pseudo-transient continuation (Kelley and Keyes 1998; for the singular M of a
//! differential-algebraic system, Coffey, Kelley and Keyes 2003). The step dt is controlled
//! so that each step moves the state by at most [`MOVE`] in the normalized norm of the path's
//! steps; a longer step is refused and taken again with a shorter dt. An implicit step longer
//! than 1 / |mu| of the unstable mode can stop on the unstable state, where the motion itself
//! would not: a motion at rest there starts again from it, displaced along its softest
//! direction the way it was moving, with the first, short dt. When the residual
//! is small the state is near rest, and Newton (undamped) finishes; its answer counts only
//! if it has no unstable direction, else the motion goes on from where it was. A state at
//! rest (residual within the solve's tolerance, last step at the rounding floor) is tested
//! as it is: in a nearly neutral valley Newton's line search cannot finish there.

use super::dynamics::Mass;
use super::homotopy::{dot, max_norm};
use super::neutral::index;
use super::newton::{self, Settings, Workspace};
use super::phase::{generic, kernel};
use super::system::System;
use super::unknowns::{NODE, P, THETA};
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// The first time step (s): well below the time of the bending modes of a robot-sized rod
/// (1 / mu, mu of 10 to 1e4 1/s^2 with c = 1/s); the control grows it in a few steps.
const FIRST_DT: f64 = 1e-2;
/// The most a time step may move the state, in the path's normalized norm
/// (|dx|^2 / n, scaled unknowns): a tenth of the longest path step, so that the motion is
/// resolved, not jumped across.
const MOVE: f64 = 0.1;
/// The most a time step may grow dt, per step.
const GROWTH: f64 = 4.0;
/// The most time steps (each one Jacobian and one factorization).
const MAX_STEPS: usize = 600;
/// A residual (scaled max-norm) at which the state is near rest and Newton finishes; tried
/// again only after the residual has fallen tenfold since the last try, or at rest
/// ([`REST_STEP`]).
const NEAR_REST: f64 = 1e-3;
/// A time step this short moves nothing the mass carries (the massless rows alone decide the
/// step): the motion is lost.
const SHORTEST_DT: f64 = 1e-8;
/// The most restarts from an unstable state at rest, and the amplitude of the start along its
/// softest direction (the path's normalized arclength, as the snap's first start).
const MAX_RESTARTS: usize = 3;
const AMPLITUDE: f64 = 0.1;
/// The length of a time step (normalized norm) at rest: the rounding floor of the motion's
/// steps in a nearly neutral valley, where the Jacobian's least singular value amplifies
/// the residual's rounding (measured 1e-11 to 5e-9 on the payload robot of
/// docs/stability.md, "A root at the base"), and far below what the tolerances resolve.
const REST_STEP: f64 = 1e-8;
/// Newton's iterations to finish from near rest (it converges in 2 to 5 from there).
const FINISH_ITERATIONS: usize = 12;

/// The state where the damped motion of `system` (at its current load) from `x` comes to
/// rest, stable (no unstable direction), with its Jacobian factored in `ws`; None when it
/// does not within [`MAX_STEPS`] time steps, or the model breaks down. Under loads that are
/// not conservative the states have no conjugate-point count to accept a rest by, so the
/// motion is not run.
pub(super) fn relax(
    system: &System,
    ws: &mut Workspace,
    mut x: Vec<State>,
    settings: &Settings,
    report: &mut SolveReport,
) -> Option<Vec<State>> {
    if super::stability::non_conservative(&system.model).is_some() {
        return None;
    }
    let n = system.unknowns();
    let nf = n as f64;
    let mut dt = FIRST_DT;
    let mut previous: Vec<f64> = Vec::new();
    let mut rhs = vec![0.0; n];
    let mut next = Vec::with_capacity(x.len());
    let mut tried = f64::INFINITY;
    let mut restarts = 0;
    // The length of the motion's last step, and whether the state at rest has been tried.
    let (mut last_size, mut rest_tried) = (f64::INFINITY, false);
    let finish = Settings {
        reuse_factors: false,
        stop_when_damped: true,
        max_iterations: settings.max_iterations.min(FINISH_ITERATIONS),
        ..*settings
    };
    for _ in 0..MAX_STEPS {
        if dt < SHORTEST_DT {
            return None;
        }
        let mass = Mass::new(system, &x, None).ok()?;
        if !ws.linearize_shifted(system, &x, report, |values| mass.add_to(values, 1.0 / dt)) {
            // A zero pivot: 1 / dt is an eigenvalue of the pencil, take a shorter step.
            dt *= 0.5;
            continue;
        }
        let r = max_norm(ws.residual());
        // At rest: the state meets the solve's residual tolerance and the motion's last step
        // is at the rounding floor. Newton's own test can fail there in a nearly neutral
        // valley (its line search finds no decrease of a residual at rounding), so the state
        // itself is the answer.
        let rest = r <= settings.tolerance && last_size <= REST_STEP;
        if r <= NEAR_REST && (r < 0.1 * tried || (rest && !rest_tried)) {
            tried = r;
            rest_tried = rest;
            let mut y = x.clone();
            let term = match rest {
                true => {
                    report.residual = r;
                    Termination::Converged
                }
                false => newton::run(system, ws, &mut y, &finish, report).0,
            };
            if term == Termination::Converged && ws.linearize(system, &y, report) {
                match index(system, ws, &y, false, report) {
                    Some(0) => return Some(y),
                    // At rest on an unstable state (a large dt lets the implicit step stop
                    // where the motion would not): the motion goes on from it along its
                    // softest direction, the way it was moving.
                    Some(_) if restarts < MAX_RESTARTS && !previous.is_empty() => {
                        let (phi, _) = kernel(ws, generic(n), false, None)?;
                        let side = AMPLITUDE * configuration_dot(&phi, &previous).signum();
                        let step: Vec<f64> = phi.iter().map(|v| v * side).collect();
                        system.retract(&y, &step, 1.0, &mut x);
                        (dt, tried, restarts) = (FIRST_DT, f64::INFINITY, restarts + 1);
                        last_size = f64::INFINITY;
                        previous.clear();
                    }
                    _ => {}
                }
            }
            continue;
        }
        rhs.iter_mut().zip(ws.residual()).for_each(|(q, f)| *q = -f);
        let step = ws.solve_again(&rhs)?.to_vec();
        let size = (dot(&step, &step) / nf).sqrt();
        if !size.is_finite() || size > MOVE {
            dt *= match size.is_finite() {
                true => (0.5 * MOVE / size).max(0.1),
                false => 0.5,
            };
            continue;
        }
        system.retract(&x, &step, 1.0, &mut next);
        std::mem::swap(&mut x, &mut next);
        report.iterations += 1;
        report.newton_steps += 1;
        dt *= (MOVE / size).min(GROWTH);
        last_size = size;
        previous = step;
    }
    None
}

/// The dot product of two scaled steps over the nodes' positions and rotations alone (the
/// configuration, which the motion moves; the strains follow it).
fn configuration_dot(a: &[f64], b: &[f64]) -> f64 {
    a.chunks_exact(NODE)
        .zip(b.chunks_exact(NODE))
        .map(|(a, b)| dot(&a[P..THETA + 3], &b[P..THETA + 3]))
        .sum()
}
