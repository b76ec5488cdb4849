//! The solution JSON (docs/cli.md, "The solution JSON"), as serde structs: the keys in the
//! order written. The first keys are those `tdcr solve --format json` always wrote (the
//! report, the tip, the samples, the tendons); format 3 added `format`, the counts and
//! timings the report lacked, the Newton history and every node's full state, so that a file
//! reads back to the same `Solution`, bitwise.
#![allow(non_snake_case)] // R, as the paper names it

use crate::analysis::samples::{Sample, bending_angle, node_samples};
use crate::report::{Growth, Stability, Termination};
use crate::{Solution, TendonState};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Deserializer, Serialize};
use std::time::Duration;

/// The `format` of the solution JSON this version writes and reads.
pub const FORMAT: &str = "tdcr-solution-3";

/// An f64 as a JSON number; a non-finite one is written as `null` (JSON has no NaN or
/// infinity), and `null` reads back as NaN.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(transparent)]
pub(crate) struct Num(#[serde(deserialize_with = "nan_for_null")] pub(crate) f64);

fn nan_for_null<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(deserializer)?.unwrap_or(f64::NAN))
}

/// `[x, y, z]`.
pub(crate) type V3 = [Num; 3];
/// A 3x3 matrix as a list of rows.
pub(crate) type M3 = [[Num; 3]; 3];

pub(crate) fn v3(v: &Vector3<f64>) -> V3 {
    [Num(v.x), Num(v.y), Num(v.z)]
}

pub(crate) fn m3(m: &Matrix3<f64>) -> M3 {
    [0, 1, 2].map(|i| [Num(m[(i, 0)]), Num(m[(i, 1)]), Num(m[(i, 2)])])
}

pub(crate) fn vector(v: &V3) -> Vector3<f64> {
    Vector3::new(v[0].0, v[1].0, v[2].0)
}

pub(crate) fn matrix(m: &M3) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| m[i][j].0)
}

/// The whole file.
#[derive(Serialize, Deserialize)]
pub(crate) struct SolutionFile {
    /// Whether Newton converged (the termination is `Converged`).
    pub converged: bool,
    /// `collocation` or `shooting`.
    pub method: String,
    /// The termination as a sentence (its `Display`).
    pub termination: String,
    pub iterations: usize,
    pub counts: Counts,
    pub load_steps: usize,
    pub stability: StabilityEntry,
    pub residual: Num,
    pub intervals: usize,
    /// `error_estimate.tip_position_m`, or null.
    pub tip_error_estimate: Num,
    pub error_estimate: Option<Estimate>,
    pub tolerance: Option<f64>,
    pub tolerance_met: Option<bool>,
    /// The report's notes (what the solve did that its counts do not say, e.g. friction
    /// coefficients followed from 0); absent when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Total solve time (s).
    pub solve_time: f64,
    pub bending_angle_deg: Num,
    pub tip: Tip,
    /// The nodes, or evenly spaced samples (`tdcr solve --samples`).
    pub samples: Vec<SampleEntry>,
    pub tendons: Vec<TendonEntry>,
    /// The tip Jacobians (`tdcr solve --jacobian`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jacobian: Option<Jacobian>,
    /// Chosen columns of the tip Jacobian (`tdcr solve --jacobian=COLUMNS`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip_jacobian: Option<TipJacobian>,
    /// [`FORMAT`].
    pub format: String,
    pub unknowns: usize,
    pub nonzeros: usize,
    pub history: Vec<Step>,
    pub timings_ns: TimingsEntry,
    pub nodes: Vec<NodeEntry>,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Counts {
    pub newton_steps: usize,
    pub chord_steps: usize,
    pub jacobian_evaluations: usize,
    pub residual_evaluations: usize,
    pub load_steps: usize,
    pub meshes: usize,
    pub equation_evaluations: usize,
}

/// The stability verdict with its details, and how the equilibrium was reached.
#[derive(Serialize, Deserialize)]
pub(crate) struct StabilityEntry {
    /// `stable`, `unstable` or `unknown`.
    pub verdict: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unstable_directions: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conjugate_point_s: Option<Num>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// `divergence` or `flutter`: how an unstable state of non-conservative loads grows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth: Option<String>,
    /// Its growth rate (1/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth_rate: Option<Num>,
    /// A flutter's frequency (Hz).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flutter_frequency: Option<Num>,
    /// `direct`, `from_warm_start`, `load_path` or `fallback`.
    pub path: String,
    pub folds: Vec<Num>,
    pub bifurcations: Vec<Num>,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Estimate {
    pub tip_position_m: Num,
    pub tip_rotation_rad: Num,
    pub backbone_max_m: Num,
    /// The order of the answer estimated (4, or 6 at tight tolerances); files written
    /// before it existed hold order-4 answers.
    #[serde(default = "order_four")]
    pub order: u32,
}

/// The order of an estimate read from a file that does not name it.
fn order_four() -> u32 {
    4
}

#[derive(Serialize, Deserialize)]
pub(crate) struct Tip {
    pub position: V3,
    pub rotation: M3,
    pub force: V3,
    pub moment: V3,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct SampleEntry {
    pub s: Num,
    pub p: V3,
    pub R: M3,
    pub n: V3,
    pub m: V3,
    /// With friction (`tdcr solve --format json` of a robot with a tendon with friction):
    /// every tendon's tension at s (N, null past its end); absent otherwise and in older
    /// files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tensions: Option<Vec<Num>>,
}

#[derive(Serialize, Deserialize)]
pub(crate) struct TendonEntry {
    pub tension: Num,
    /// The tension at the termination (N); absent in files written before friction: the
    /// tension.
    #[serde(default)]
    pub delivered_tension: Option<Num>,
    pub displacement: Num,
    pub length: Num,
    pub reference_length: Num,
    pub slack: Num,
    /// Where the tendon ends (m; written when the robot is known).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<Num>,
    /// Its turns about the backbone (null for a custom routing; written when the robot is
    /// known).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turns: Option<Num>,
    /// Its path at the nodes up to its end (m, world frame).
    pub path: Vec<V3>,
    /// Its tension at the points of `path` (N); absent in files written before friction:
    /// the tension everywhere.
    #[serde(default)]
    pub tensions: Option<Vec<Num>>,
}

/// Six rows (tip position, tip rotation vector), one column per input.
#[derive(Serialize, Deserialize)]
pub(crate) struct Jacobian {
    pub tension: Vec<Vec<Num>>,
    pub displacement: Vec<Vec<Num>>,
    /// Per friction coefficient, one column per tendon (zero without friction); absent in
    /// files written before it.
    #[serde(default)]
    pub friction: Vec<Vec<Num>>,
    pub tip_force: Vec<Vec<Num>>,
    pub tip_moment: Vec<Vec<Num>>,
}

/// Chosen columns of the tip Jacobian: the parameters' names and six rows (tip position,
/// tip rotation vector), one column per name.
#[derive(Serialize, Deserialize)]
pub(crate) struct TipJacobian {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<Num>>,
}

/// One Newton iteration of the report's history.
#[derive(Serialize, Deserialize)]
pub(crate) struct Step {
    pub residual: Num,
    pub step: Num,
    pub damping: Num,
    pub fresh_jacobian: bool,
}

/// The report's timings in whole nanoseconds (exact, unlike seconds as a float).
#[derive(Serialize, Deserialize)]
pub(crate) struct TimingsEntry {
    pub assembly: u64,
    pub factorization: u64,
    pub solve: u64,
    pub estimate: u64,
    pub stability: u64,
    pub total: u64,
}

/// A node's full state.
#[derive(Serialize, Deserialize)]
pub(crate) struct NodeEntry {
    pub s: Num,
    pub p: V3,
    pub R: M3,
    pub v: V3,
    pub u: V3,
    pub v_s: V3,
    pub u_s: V3,
    pub n: V3,
    pub m: V3,
}

pub(crate) fn sample_entry(x: &Sample) -> SampleEntry {
    SampleEntry {
        s: Num(x.s),
        p: v3(&x.p),
        R: m3(&x.R),
        n: v3(&x.n),
        m: v3(&x.m),
        tensions: None,
    }
}

fn nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

impl SolutionFile {
    /// Everything `solution` holds, with its nodes as the samples and the tendons without
    /// the robot's `end` and `turns` (`crate::io::output::json` adds what needs the robot).
    pub(crate) fn new(solution: &Solution) -> SolutionFile {
        let report = &solution.report;
        let tip = solution.tip();
        let (unstable_directions, conjugate_point_s, reason) = match &report.stability {
            Stability::Stable => (None, None, None),
            Stability::Unstable {
                directions,
                conjugate_point,
            } => (Some(*directions), Some(Num(*conjugate_point)), None),
            Stability::Unknown { reason } => (None, None, Some(reason.clone())),
            Stability::Growing { .. } => (None, None, None),
        };
        let (growth, growth_rate, flutter_frequency) = match &report.stability {
            Stability::Growing { growth, rate } => (
                Some(growth.name().to_string()),
                Some(Num(*rate)),
                match growth {
                    Growth::Flutter { frequency } => Some(Num(*frequency)),
                    Growth::Divergence => None,
                },
            ),
            _ => (None, None, None),
        };
        let (path, folds, bifurcations) = (report.path.name(), report.path.folds(), report.path.bifurcations());
        let numbers = |x: &[f64]| x.iter().map(|&x| Num(x)).collect();
        let t = &report.timings;
        SolutionFile {
            converged: report.termination == Termination::Converged,
            method: report.method.to_string(),
            termination: report.termination.to_string(),
            iterations: report.iterations,
            counts: Counts {
                newton_steps: report.newton_steps,
                chord_steps: report.chord_steps,
                jacobian_evaluations: report.evaluations.jacobian,
                residual_evaluations: report.evaluations.residual,
                load_steps: report.load_steps,
                meshes: report.meshes,
                equation_evaluations: report.evaluations.equations,
            },
            load_steps: report.load_steps,
            stability: StabilityEntry {
                verdict: report.stability.verdict().into(),
                unstable_directions,
                conjugate_point_s,
                reason,
                growth,
                growth_rate,
                flutter_frequency,
                path: path.into(),
                folds: numbers(folds),
                bifurcations: numbers(bifurcations),
            },
            residual: Num(report.residual),
            intervals: report.intervals,
            tip_error_estimate: Num(report.error_estimate.map_or(f64::NAN, |e| e.tip_position)),
            error_estimate: report.error_estimate.map(|e| Estimate {
                tip_position_m: Num(e.tip_position),
                tip_rotation_rad: Num(e.tip_rotation),
                backbone_max_m: Num(e.backbone_max),
                order: e.order,
            }),
            tolerance: report.tolerance,
            tolerance_met: report.tolerance_met,
            notes: report.notes.clone(),
            solve_time: t.total.as_secs_f64(),
            bending_angle_deg: Num(bending_angle(solution).to_degrees()),
            tip: Tip {
                position: v3(&tip.p),
                rotation: m3(&tip.R),
                force: v3(&tip.n),
                moment: v3(&tip.m),
            },
            samples: node_samples(solution).iter().map(sample_entry).collect(),
            tendons: solution
                .tendons
                .iter()
                .zip(&solution.tendon_paths)
                .zip(&solution.tendon_tensions)
                .map(|((state, path), tensions)| tendon_entry(state, path, tensions))
                .collect(),
            jacobian: None,
            tip_jacobian: None,
            format: FORMAT.into(),
            unknowns: report.unknowns,
            nonzeros: report.nonzeros,
            history: report
                .history
                .iter()
                .map(|i| Step {
                    residual: Num(i.residual),
                    step: Num(i.step),
                    damping: Num(i.damping),
                    fresh_jacobian: i.fresh_jacobian,
                })
                .collect(),
            timings_ns: TimingsEntry {
                assembly: nanos(t.assembly),
                factorization: nanos(t.factorization),
                solve: nanos(t.solve),
                estimate: nanos(t.estimate),
                stability: nanos(t.stability),
                total: nanos(t.total),
            },
            nodes: solution
                .nodes
                .iter()
                .map(|n| NodeEntry {
                    s: Num(n.s),
                    p: v3(&n.p),
                    R: m3(&n.R),
                    v: v3(&n.v),
                    u: v3(&n.u),
                    v_s: v3(&n.v_s),
                    u_s: v3(&n.u_s),
                    n: v3(&n.n),
                    m: v3(&n.m),
                })
                .collect(),
        }
    }
}

fn tendon_entry(state: &TendonState, path: &[Vector3<f64>], tensions: &[f64]) -> TendonEntry {
    TendonEntry {
        tension: Num(state.tension),
        delivered_tension: Some(Num(state.delivered_tension)),
        displacement: Num(state.displacement),
        length: Num(state.length),
        reference_length: Num(state.reference_length),
        slack: Num(state.slack),
        end: None,
        turns: None,
        path: path.iter().map(v3).collect(),
        tensions: Some(tensions.iter().map(|&t| Num(t)).collect()),
    }
}
