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
/// loaded tendon's routing or the precurvature turns by more per interval than the
/// resolution study's one-turn helix may for its order-4 error to meet the tolerance,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Actuation, Friction, Loads, Rod, Routing, Stability, Tendon, cases};
    use nalgebra::Vector3;

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

    /// Issue 25's column (0.5 m steel rod of radius 1 mm) at 1.2 times Euler's load with a
    /// light straight tendon with friction (0.05 N, mu = 0.1): Newton with friction from the
    /// straight guess goes straight to the nearly straight state, which diverges, so the
    /// direct route's answer does not stand; the solve falls back to the full choice (the
    /// load path to the buckled state, stable) and its report counts the direct run too.
    #[test]
    fn the_fallback_returns_the_load_paths_stable_state_where_the_direct_answer_is_unstable() {
        let (length, radius, e): (f64, f64, f64) = (0.5, 1e-3, 200e9);
        let p_cr = std::f64::consts::PI.powi(3) * e * radius.powi(4) / 4.0 / (4.0 * length * length);
        let p = 1.2 * p_cr;
        let robot = Robot::new(Rod::solid_circle(length, radius, e, 0.3))
            .with_loads(Loads::none().with_tip_force(Vector3::new(1e-6 * p, 0.0, -p)))
            .with_tendon(Tendon::new(Routing::straight(0.8e-3, 0.0), 0.05).with_friction(Friction::pull(0.1)));
        let options = Options::default();
        let from = first_mesh(&smooth(&robot), &options)
            .unwrap()
            .expect("a straight tendon");
        let direct = solve(&robot, &options, from, Instant::now()).unwrap();
        assert!(
            matches!(direct.report.stability, Stability::Growing { .. }),
            "{:?}",
            direct.report.stability
        );
        // The nearly straight state: its tip within 1 mm of the axis (measured 0.17 mm).
        assert!(direct.tip_position().x.abs() < 1e-3, "{}", direct.tip_position());
        let solution = crate::collocation::solve(&robot, &options).unwrap();
        let report = &solution.report;
        assert_eq!(report.stability, Stability::Stable, "{report:?}");
        assert!(matches!(report.path, crate::PathTaken::LoadPath { .. }), "{report:?}");
        // Buckled: the tip 0.32 m off the axis (measured); 50 mm separates it by far.
        assert!(solution.tip_position().x.abs() > 0.05, "{}", solution.tip_position());
        // The direct run's mesh and iterations, and at least the frictionless choice's first
        // mesh and one mesh with friction after it.
        assert!(report.meshes >= direct.report.meshes + 2, "{report:?}");
        assert!(report.iterations > direct.report.iterations, "{report:?}");
    }
}
