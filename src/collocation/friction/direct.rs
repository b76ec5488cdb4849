//! The direct route of a solve with friction (docs/friction.md section 3, "Which start"):
//! Newton with friction from the initial guess moved to the capstan start, on the first
//! mesh the frictionless solve would take, without the frictionless Newton. Its answer is
//! provisional, as the equilibrium choice's direct answer is: it stands only when Newton
//! went straight to it and its verdict is `stable` (the caller, `solve_assessed`, falls
//! back to the full choice on the frictionless robot otherwise).

use super::refine_with_friction;
use crate::Robot;
use crate::collocation::options::{Equilibrium, Options};
use crate::collocation::start::{cold_start, initial_mesh, resolves};
use crate::error::Result;
use crate::mesh::{Mesh, resolution};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport};
use crate::solution::{Solution, State};
use std::f64::consts::PI;
use std::time::Instant;

/// The resolution study's reference point (mesh/resolution.rs, docs/numerics.md
/// "Resolution"): case H's helical tendon of one turn, meshed at this angle of the turn per
/// interval, has a tip error of [`STUDY_ERROR`] L, falling at order 4 below it. Of the
/// study's helices (1 to 100 turns) one turn has the smallest error at a given angle.
const STUDY_ANGLE: f64 = PI / 8.0;

/// The tip error / L of the study's one-turn helix at [`STUDY_ANGLE`] per interval.
const STUDY_ERROR: f64 = 1.8e-5;

/// Whether a solve with friction takes the direct route first: a cold start (a warm one
/// keeps the frictionless start's choice from the warm states), with a verdict (`assess`:
/// the held pull-ins' loop asks for none, so nothing could accept the answer), and the
/// load path's choice with continuation (`nearest`, and a solve without continuation, take
/// Newton's answer from the guess whatever its verdict, through the frictionless start as
/// before).
pub(super) fn applies(options: &Options, warm: Option<&Solution>, assess: bool) -> bool {
    warm.is_none() && assess && options.equilibrium == Equilibrium::LoadPath && options.continuation
}

/// The first mesh of the direct route and the initial guess on it: the frictionless
/// solve's (`smooth`, the robot without friction: its first mesh, [`cold_start`]), or None
/// where that mesh is expected to be refined. There Newton with friction on it would only
/// pick the next mesh and start it, which the frictionless Newton does at less cost (case
/// H: 18.48 M instructions against 17.26 M, docs/benchmarks.md "start18"), so the caller
/// takes the frictionless start instead. Expected to be refined: with a tolerance, a
/// routing or the precurvature turns by more per interval than the resolution study's
/// one-turn helix may for its order-4 error to meet the tolerance (of the loaded tendons
/// only),
/// `STUDY_ANGLE (tol / STUDY_ERROR)^(1/4)` (0.107 rad at the default 1e-7: H's helix turns
/// 0.196 rad per interval of 32). This is a prediction of cost only: either route returns
/// an answer to the tolerance.
///
/// # Errors
/// As [`crate::collocation::solve`] for a mesh that cannot be built or does not resolve the
/// robot (the frictionless solve's errors there).
pub(super) fn first_mesh(smooth: &Robot, options: &Options) -> Result<Option<(Mesh, Vec<State>)>> {
    let mut mesh = initial_mesh(smooth, options, None)?;
    if options.tolerance.is_none() {
        resolves(smooth, options, &mesh)?;
    }
    let model = Model::new(smooth);
    let x = cold_start(&model, options, &mut mesh)?;
    if let Some(tol) = options.tolerance {
        // What turns and bends the backbone: the loaded tendons' routings (an unloaded one
        // pulls nothing) and the precurvature.
        let mut loaded = smooth.clone();
        loaded.tendons.retain(|t| t.tension() > 0.0);
        let longest = mesh.nodes.windows(2).map(|w| w[1].s - w[0].s).fold(0.0, f64::max);
        if resolution::required(&loaded).rate * longest > STUDY_ANGLE * (tol / STUDY_ERROR).powf(0.25) {
            return Ok(None);
        }
    }
    Ok(Some((mesh, x)))
}

/// Newton with friction from `from` ([`first_mesh`]) moved to the capstan start, then the
/// meshes the estimate with friction chooses ([`refine_with_friction`] with `direct`: on
/// the first mesh Newton must converge cleanly). The answer's verdict is the linearized
/// dynamics with the capstan rows; the caller decides whether it stands. `start` is when
/// the solve began.
///
/// # Errors
/// As [`crate::collocation::solve`]; [`crate::Error::NotConverged`] (with the report)
/// where Newton with friction did not converge cleanly on the first mesh or at all on a
/// later one.
pub(super) fn solve(robot: &Robot, options: &Options, from: (Mesh, Vec<State>), start: Instant) -> Result<Solution> {
    let report = SolveReport::new(Method::Collocation);
    refine_with_friction(robot, options, from, None, (report, true), start, true)
}
