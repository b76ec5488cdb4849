//! The direct route of a solve with friction (docs/friction.md section 3, "Which start"):
//! Newton with friction from the initial guess moved to the capstan start, on the first
//! mesh the frictionless solve would take, without the frictionless Newton. Its answer is
//! provisional, as the equilibrium choice's direct answer is: it stands only when Newton
//! went straight to it and its verdict is `stable` (the caller, `solve_assessed`, falls
//! back to the full choice on the frictionless robot otherwise).

use super::{Route, refine_with_friction};
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
/// "Resolution"), copied from its tables: case H's helical tendon of one turn, meshed at
/// this angle of the turn per interval, has a tip error of [`STUDY_ERROR`] L, falling at
/// order 4 below it. Of the study's helices (1 to 100 turns) one turn has the smallest
/// error at a given angle. That error belongs to case H's loading (its tension and no
/// external load); the rule of [`first_mesh`] built on it is a heuristic calibrated on H.
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
/// loaded tendon's routing or the precurvature turns by more per interval than the
/// resolution study's one-turn helix may for its order-4 error to meet the tolerance,
/// `STUDY_ANGLE (tol / STUDY_ERROR)^(1/4)` (0.107 rad at the default 1e-7: H's helix turns
/// 0.196 rad per interval of 32). This is a heuristic calibrated on case H: it looks at the
/// routings' turning only, not at the tensions or the external loads, and predicts cost
/// only: either route returns an answer to the tolerance.
///
/// # Errors
/// As [`crate::collocation::solve`] for a mesh that cannot be built or does not resolve the
/// robot (the frictionless solve's errors there).
pub(super) fn first_mesh(smooth: &Robot, options: &Options) -> Result<Option<(Mesh, Vec<State>)>> {
    let mut mesh = initial_mesh(smooth, options, None)?;
    if options.tolerance.is_none() {
        resolves(smooth, options, &mesh)?;
    }
    if let Some(tol) = options.tolerance {
        // What turns and bends the backbone: the loaded tendons' routings (an unloaded one
        // pulls nothing) and the precurvature.
        let mut loaded = smooth.clone();
        loaded.tendons.retain(|t| t.tension() > 0.0);
        // Before the cold start, which may only make it finer (a guess that bends more
        // than a starting mesh resolves), and which the frictionless start would repeat.
        let longest = mesh.nodes.windows(2).map(|w| w[1].s - w[0].s).fold(0.0, f64::max);
        if resolution::required(&loaded).rate * longest > STUDY_ANGLE * (tol / STUDY_ERROR).powf(0.25) {
            return Ok(None);
        }
    }
    let x = cold_start(&Model::new(smooth), options, &mut mesh)?;
    Ok(Some((mesh, x)))
}

/// Newton with friction from `from` ([`first_mesh`]) moved to the capstan start, then the
/// meshes the estimate with friction chooses ([`refine_with_friction`] on [`Route::Direct`]:
/// on the first mesh Newton must converge cleanly). The answer's verdict is the linearized
/// dynamics with the capstan rows; the caller decides whether it stands. `start` is when
/// the solve began.
///
/// # Errors
/// As [`crate::collocation::solve`]; [`crate::Error::NotConverged`] (with the report)
/// where Newton with friction did not converge cleanly on the first mesh or at all on a
/// later one.
pub(super) fn solve(robot: &Robot, options: &Options, from: (Mesh, Vec<State>), start: Instant) -> Result<Solution> {
    let report = SolveReport::new(Method::Collocation);
    refine_with_friction(robot, options, from, None, (report, true), start, Route::Direct)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Actuation, Friction, cases};

    /// The frictionless twin of `robot` (its tendons without friction).
    fn smooth(robot: &Robot) -> Robot {
        let mut smooth = robot.clone();
        for t in &mut smooth.tendons {
            t.friction = None;
        }
        smooth
    }

    /// S (straight tendons) takes the direct route on its first mesh of 32 intervals; H,
    /// whose loaded helix turns 0.196 rad per interval there, takes the frictionless start
    /// unless the mesh is fixed; H with the helix unloaded (tendon 1 pulls) takes the
    /// direct route.
    #[test]
    fn the_direct_route_runs_where_the_first_mesh_is_expected_to_be_final() {
        let options = Options::default();
        let (mut s, mut h) = (cases::case_s(), cases::case_h());
        s.tendons[0].friction = Some(Friction::pull(0.1));
        h.tendons[4].friction = Some(Friction::pull(0.1));
        let first = first_mesh(&smooth(&s), &options).unwrap();
        assert_eq!(first.map(|(mesh, _)| mesh.intervals()), Some(32));
        assert!(first_mesh(&smooth(&h), &options).unwrap().is_none());
        let fixed = Options::fixed(32);
        assert!(first_mesh(&smooth(&h), &fixed).unwrap().is_some());
        let mut unloaded = h.clone();
        unloaded.tendons[4].actuation = Actuation::Tension(0.0);
        unloaded.tendons[0].actuation = Actuation::Tension(2.0);
        assert!(first_mesh(&smooth(&unloaded), &options).unwrap().is_some());
    }
}
