//! Tracing a branch of equilibria in one input ([`Parameter`]) by pseudo-arclength
//! continuation through folds (docs/stability.md, "Tracing a branch"): the start is the
//! default solve at the first value (the load-path equilibrium), then the branch is followed
//! with the stability of every point, until it passes the last value (or turns back past the
//! first).

use super::newton::{Settings, Workspace};
use super::options::Options;
use super::path::{self, Recorded};
use super::system::System;
use super::{MAX_ITERATIONS, solve};
use crate::Robot;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate_nodes;
use crate::model::equations::Model;
use crate::model::parameter::Parameter;
use crate::report::{Method, SolveReport};
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// The longest step of a trace along the normalized arclength: at least about 20 points on
/// a branch that runs straight from the first value to the last.
const TRACE_STEP: f64 = 0.05;

/// One point of a traced branch.
#[derive(Clone, Debug, PartialEq)]
pub struct TracePoint {
    /// The parameter's value (N, N/m, or the load scale).
    pub value: f64,
    /// Tip position (m, world).
    pub tip_position: Vector3<f64>,
    /// Tip orientation R(L).
    pub tip_rotation: Matrix3<f64>,
    /// Unstable directions: 0 stable, more unstable, `None` unknown (non-conservative
    /// loads).
    pub unstable_directions: Option<usize>,
    /// Whether the branch turns back in the parameter here (a fold: loading past it, the
    /// robot snaps through).
    pub fold: bool,
    /// Iterations (Newton and chord) spent along the branch up to this point.
    pub iterations: usize,
}

impl TracePoint {
    /// `stable`, `unstable` or `unknown`, the words of [`crate::Stability::verdict`].
    pub fn verdict(&self) -> &'static str {
        match self.unstable_directions {
            Some(0) => "stable",
            Some(_) => "unstable",
            None => "unknown",
        }
    }
}

/// An event of a traced branch, located to 1e-6 of the traced range (module `locate`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TraceEvent {
    /// The branch turns back in the parameter at this value (loading past it, the robot
    /// snaps through).
    Fold(f64),
    /// The number of unstable directions changes at this value without a fold: the branch
    /// crosses another (Euler's column at P_cr).
    Bifurcation(f64),
}

impl TraceEvent {
    /// `fold` or `bifurcation`.
    pub fn kind(&self) -> &'static str {
        match self {
            TraceEvent::Fold(_) => "fold",
            TraceEvent::Bifurcation(_) => "bifurcation",
        }
    }

    /// The parameter's value there.
    pub fn value(&self) -> f64 {
        match *self {
            TraceEvent::Fold(v) | TraceEvent::Bifurcation(v) => v,
        }
    }
}

/// `folds` and `bifurcations` (each in the order the branch passes them) as one list in
/// that order: the points say which came first (a fold flag, or a change of the unstable
/// directions).
fn in_order(points: &[TracePoint], folds: &[f64], bifurcations: &[f64]) -> Vec<TraceEvent> {
    let (mut f, mut b) = (folds.iter(), bifurcations.iter());
    let mut out = Vec::with_capacity(folds.len() + bifurcations.len());
    for w in points.windows(2) {
        let next = if w[1].fold {
            f.next().map(|&v| TraceEvent::Fold(v))
        } else if w[0].unstable_directions != w[1].unstable_directions {
            b.next().map(|&v| TraceEvent::Bifurcation(v))
        } else {
            None
        };
        out.extend(next);
    }
    out.extend(f.map(|&v| TraceEvent::Fold(v)));
    out.extend(b.map(|&v| TraceEvent::Bifurcation(v)));
    out
}

/// A traced branch.
#[derive(Clone, Debug)]
pub struct Trace {
    /// The input traced.
    pub parameter: Parameter,
    /// Its first and last values.
    pub range: (f64, f64),
    /// The points in the order the branch passes them.
    pub points: Vec<TracePoint>,
    /// Parameter values of the folds, located to 1e-6 of the range.
    pub folds: Vec<f64>,
    /// Parameter values where the number of unstable directions changed without a fold,
    /// located to 1e-6 of the range.
    pub bifurcations: Vec<f64>,
    /// The folds and bifurcations in the order the branch passes them.
    pub events: Vec<TraceEvent>,
    /// `None` when the branch reached the last value or turned back past the first; else
    /// why it stopped (the points up to there are kept).
    pub stopped: Option<String>,
    /// Counts and timings of the whole trace, the start's solve included.
    pub report: SolveReport,
}

/// Traces the branch of `robot`'s equilibria as `parameter` goes from `from` to `to`
/// ([`Trace`]), starting at the equilibrium [`solve`] returns for `from`, on the mesh that
/// solve chose (refined along the way where the shape needs it).
///
/// # Errors
/// [`crate::Error::ModelLimit`] for a robot with friction (a trace does not model it yet).
/// Invalid input (also a displacement-controlled tendon left after setting `parameter`:
/// trace its tension or sweep its pull-in; `youngs_modulus`, which only a sweep varies; a
/// negative tension; a range of two equal or non-finite values), or the start's solve
/// failing ([`solve`]'s errors). A branch that cannot be followed to the end is not an
/// error: [`Trace::stopped`] says why.
pub fn trace(robot: &Robot, parameter: Parameter, from: f64, to: f64, options: &Options) -> Result<Trace> {
    trace_until(robot, parameter, from, to, options, &|| false)
}

/// [`trace`], asking `stop` before every continuation step whether to give up (a front
/// end's Ctrl-C): the points up to there are kept and [`Trace::stopped`] says "stopped on
/// request".
///
/// # Errors
/// As [`trace`].
pub fn trace_until(
    robot: &Robot,
    parameter: Parameter,
    from: f64,
    to: f64,
    options: &Options,
    stop: &dyn Fn() -> bool,
) -> Result<Trace> {
    let clock = Instant::now();
    robot.validate()?;
    options.validate()?;
    crate::model::friction::unsupported(robot, "tracing a branch")?;
    if matches!(
        parameter,
        Parameter::YoungsModulus | Parameter::Displacement(_) | Parameter::RoutingOffset(..) | Parameter::Friction(_)
    ) {
        return Err(crate::error::invalid(
            "parameter",
            format!("`{parameter}` cannot be traced: a trace varies a tension or a load"),
            format!(
                "sweep {} instead (a sweep of `{parameter}` solves each value warm-started from the last)",
                if parameter == Parameter::YoungsModulus {
                    "E"
                } else {
                    "it"
                }
            ),
        ));
    }
    let start = parameter.applied(robot, from)?;
    if let Some(i) = start.tendons.iter().position(|t| t.displacement().is_some()) {
        return Err(crate::error::invalid(
            format!("tendons[{i}].displacement"),
            format!(
                "tendon {} is displacement-controlled: a trace follows tensions and loads (its tension would be a \
                 border the path follower does not carry)",
                i + 1
            ),
            "sweep its pull-in instead (a sweep solves each value warm-started from the last), or trace the \
             tendon's tension (`tension.I` makes it tension-controlled)",
        ));
    }
    if !from.is_finite() || !to.is_finite() || from == to {
        return Err(crate::error::invalid(
            "trace range",
            format!(
                "{parameter} from {} to {}: the range needs two different finite values",
                crate::Readable(from),
                crate::Readable(to)
            ),
            "give two different values for the start and the end of the range",
        ));
    }
    if matches!(parameter, Parameter::Tension(_)) && from.min(to) < 0.0 {
        return Err(crate::error::invalid(
            "trace range",
            format!(
                "{parameter} from {} to {} N: a tendon can only pull",
                crate::Readable(from),
                crate::Readable(to)
            ),
            "give tensions >= 0",
        ));
    }
    let first = solve(&start, options)?;
    let points: Vec<f64> = first.nodes.iter().map(|n| n.s).collect();
    let mesh = Mesh::from_points(robot, &points)?;
    let model = Model::new(robot);
    let x = interpolate_nodes(&model, &first.nodes, &mesh);
    let mut system = System::new(model, mesh);
    let mut ws = Workspace::new(&system, options.linear_solver)?;
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations.min(MAX_ITERATIONS),
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = SolveReport::new(Method::Collocation);
    let mut recorded: Vec<Recorded> = Vec::new();
    let start = path::Start::Trace {
        x: &x,
        parameter,
        from,
        to,
        max_step: TRACE_STEP,
        stop,
    };
    let end = path::follow(
        &mut system,
        &mut ws,
        start,
        options,
        &settings,
        &mut report,
        Some(&mut recorded),
    );
    let value = |lambda: f64| from + lambda * (to - from);
    let (folds, bifurcations, stopped) = match end {
        Ok(end) => (end.folds, end.bifurcations, None),
        Err((hint, _)) => (Vec::new(), Vec::new(), Some(hint)),
    };
    let start_counts = &first.report;
    report.iterations += start_counts.iterations;
    report.newton_steps += start_counts.newton_steps;
    report.chord_steps += start_counts.chord_steps;
    report.meshes += start_counts.meshes;
    report.intervals = system.mesh.intervals();
    report.timings.total = clock.elapsed();
    let points: Vec<TracePoint> = recorded
        .into_iter()
        .map(|r| TracePoint {
            value: value(r.lambda),
            tip_position: r.tip.p,
            tip_rotation: r.tip.R,
            unstable_directions: r.unstable,
            fold: r.fold,
            iterations: r.iterations + start_counts.iterations,
        })
        .collect();
    let folds: Vec<f64> = folds.into_iter().map(value).collect();
    let bifurcations: Vec<f64> = bifurcations.into_iter().map(value).collect();
    Ok(Trace {
        parameter,
        range: (from, to),
        events: in_order(&points, &folds, &bifurcations),
        points,
        folds,
        bifurcations,
        stopped,
        report,
    })
}
