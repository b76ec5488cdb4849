//! Where a solve starts: its first mesh, the resolution check of a fixed mesh, and the
//! initial guess of a cold start.

use super::options::Options;
use super::refine;
use crate::Robot;
use crate::error::{Result, invalid};
use crate::mesh::{Mesh, guess, resolution, spare};
use crate::model::equations::Model;
use crate::solution::{Solution, State};

/// The mesh a solve starts on: the explicit points, else (error-controlled, warm-started)
/// the warm start's own mesh, else `options.intervals` uniform intervals.
pub(crate) fn initial_mesh(robot: &Robot, options: &Options, warm: Option<&Solution>) -> Result<Mesh> {
    match (&options.mesh, warm) {
        (Some(points), _) => Mesh::from_points(robot, points),
        (None, Some(guess)) if options.tolerance.is_some() && guess.length() == robot.length() => {
            let mut points = spare::take(guess.nodes.len());
            points.extend(guess.nodes.iter().map(|n| n.s));
            let mesh = Mesh::from_points(robot, &points);
            spare::give(points);
            mesh
        }
        (None, _) => Mesh::uniform(robot, options.intervals),
    }
}

/// Checks that a fixed `mesh` (no tolerance) resolves the robot ([`resolution::required`]):
/// a coarser one would converge to an aliased shape without a sign of it.
///
/// # Errors
/// [`crate::Error::InvalidInput`] on `options.intervals` (`options.mesh` for explicit
/// points) with the intervals that would resolve the robot.
pub(crate) fn resolves(robot: &Robot, options: &Options, mesh: &Mesh) -> Result<()> {
    let need = resolution::required(robot);
    let longest = mesh.nodes.windows(2).map(|w| w[1].s - w[0].s).fold(0.0, f64::max);
    let (field, given, coarse) = match &options.mesh {
        // 1e-9: a uniform mesh of exactly the needed intervals passes despite rounding.
        Some(_) => (
            "options.mesh",
            mesh.intervals(),
            longest > need.longest_interval() * (1.0 + 1e-9),
        ),
        None => (
            "options.intervals",
            options.intervals,
            options.intervals < need.intervals,
        ),
    };
    if !coarse {
        return Ok(());
    }
    let what = match need.feature {
        Some(resolution::Feature::Routing(i)) => format!("the routing of `tendons[{i}]` turns about the backbone"),
        _ => "the rod's precurvature turns".to_string(),
    };
    Err(invalid(
        field,
        format!(
            "is {given} intervals, but {what} by up to {:.2} rad in one of them, and an interval may \
             span at most pi/2 rad (the resolution rule, docs/numerics.md): this mesh cannot resolve \
             the robot and would give an aliased shape; {} intervals resolve it",
            need.rate * longest,
            need.intervals
        ),
        format!(
            "use at least {} intervals, or give a tip tolerance (the option `tolerance`) instead of a fixed mesh",
            need.intervals
        ),
    ))
}

/// The initial guess of a cold start on `mesh` for `model` (a robot's model as
/// [`Model::new`] makes it: the given tensions, full load). With error control and no
/// fixed mesh, the start moves first to a mesh that resolves the initial guess and the
/// routings (the resolution rule), when `mesh` does not.
///
/// # Errors
/// [`crate::Error::InvalidInput`] if the finer mesh cannot be built.
pub(crate) fn cold_start(model: &Model, options: &Options, mesh: &mut Mesh) -> Result<Vec<State>> {
    let robot = model.robot;
    let x0 = guess::initial(model, &mesh.nodes, options.initial_guess);
    if options.tolerance.is_none() || options.mesh.is_some() {
        return Ok(x0);
    }
    let floor = options.intervals.max(resolution::required(robot).intervals);
    let needed = refine::start_intervals(robot, &x0, floor).min(options.max_intervals);
    if needed <= mesh.intervals() {
        return Ok(x0);
    }
    spare::give(x0);
    std::mem::replace(mesh, Mesh::uniform(robot, needed)?).release();
    Ok(guess::initial(model, &mesh.nodes, options.initial_guess))
}
