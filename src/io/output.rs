//! Result files: the solved shape sampled along the backbone, as JSON or CSV (docs/cli.md
//! lists every field and unit). SI units throughout.
#![allow(non_snake_case)]

pub use crate::analysis::samples::{Sample, bending_angle, samples};
use crate::collocation::sensitivity::TipSensitivities;
use crate::{Robot, Solution};
use nalgebra::{Matrix3, Vector3};
use std::fmt::Write;

fn rows(R: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [R[(i, 0)], R[(i, 1)], R[(i, 2)]])
}

/// A JSON value with its keys in the order written (serde_json's own map sorts them).
enum Json {
    Null,
    Bool(bool),
    Integer(usize),
    Number(f64),
    Text(String),
    Array(Vec<Json>),
    Object(Vec<(&'static str, Json)>),
}

impl Json {
    fn vector(v: &Vector3<f64>) -> Json {
        Json::Array(v.iter().map(|&x| Json::Number(x)).collect())
    }

    fn matrix(R: &Matrix3<f64>) -> Json {
        Json::Array(
            rows(R)
                .iter()
                .map(|r| Json::Array(r.iter().map(|&x| Json::Number(x)).collect()))
                .collect(),
        )
    }

    fn optional(x: Option<f64>) -> Json {
        // NaN is written as null.
        Json::Number(x.unwrap_or(f64::NAN))
    }

    fn is_scalar(&self) -> bool {
        !matches!(self, Json::Array(_) | Json::Object(_))
    }

    /// Scalars, vectors and 3-row matrices: written on one line.
    fn is_small(&self) -> bool {
        match self {
            Json::Array(items) => {
                items.iter().all(Json::is_scalar)
                    || items.len() <= 3
                        && items
                            .iter()
                            .all(|i| matches!(i, Json::Array(r) if r.iter().all(Json::is_scalar)))
            }
            Json::Object(_) => false,
            _ => true,
        }
    }

    /// Objects inside arrays whose values are all small go on one line (one sample per
    /// line); everything else is indented.
    fn write(&self, out: &mut String, indent: usize, in_array: bool) {
        let pad = |n: usize| " ".repeat(n);
        match self {
            // serde_json formats numbers (shortest round-trip form; NaN, inf as null) and
            // escapes strings; neither can fail.
            Json::Null => out.push_str("null"),
            Json::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Json::Integer(i) => out.push_str(&i.to_string()),
            Json::Number(x) => out.push_str(&serde_json::to_string(x).unwrap_or_else(|_| "null".into())),
            Json::Text(t) => out.push_str(&serde_json::to_string(t).unwrap_or_else(|_| "\"\"".into())),
            Json::Array(items) if items.is_empty() => out.push_str("[]"),
            Json::Array(items) if self.is_small() => {
                out.push('[');
                for (k, item) in items.iter().enumerate() {
                    if k > 0 {
                        out.push_str(", ");
                    }
                    item.write(out, indent, true);
                }
                out.push(']');
            }
            Json::Array(items) => {
                out.push_str("[\n");
                for (k, item) in items.iter().enumerate() {
                    out.push_str(&pad(indent + 2));
                    item.write(out, indent + 2, true);
                    out.push_str(if k + 1 < items.len() { ",\n" } else { "\n" });
                }
                out.push_str(&pad(indent));
                out.push(']');
            }
            Json::Object(fields) if in_array && fields.iter().all(|(_, v)| v.is_small()) => {
                out.push('{');
                for (k, (key, value)) in fields.iter().enumerate() {
                    if k > 0 {
                        out.push_str(", ");
                    }
                    let _ = write!(out, "\"{key}\": ");
                    value.write(out, indent, true);
                }
                out.push('}');
            }
            Json::Object(fields) => {
                out.push_str("{\n");
                for (k, (key, value)) in fields.iter().enumerate() {
                    let _ = write!(out, "{}\"{key}\": ", pad(indent + 2));
                    value.write(out, indent + 2, false);
                    out.push_str(if k + 1 < fields.len() { ",\n" } else { "\n" });
                }
                out.push_str(&pad(indent));
                out.push('}');
            }
        }
    }
}

/// The solution as JSON (every field and unit in docs/cli.md): the solve report, the tip
/// pose and wrench, the samples of [`samples`] for `count`, each tendon's tension, pull-in,
/// lengths, slack, end, turns about the backbone over its own length ([`crate::Tendon::turns`])
/// and path, and the tip Jacobians when given. Vectors are `[x, y, z]`, matrices lists of rows; one sample per line.
pub fn json(robot: &Robot, solution: &Solution, count: Option<usize>, jacobian: Option<&TipSensitivities>) -> String {
    let report = &solution.report;
    let tip = solution.tip();
    let samples = samples(robot, solution, count)
        .iter()
        .map(|x| {
            Json::Object(vec![
                ("s", Json::Number(x.s)),
                ("p", Json::vector(&x.p)),
                ("R", Json::matrix(&x.R)),
                ("n", Json::vector(&x.n)),
                ("m", Json::vector(&x.m)),
            ])
        })
        .collect();
    let tendons = robot
        .tendons
        .iter()
        .zip(&solution.tendon_paths)
        .zip(&solution.tendons)
        .map(|((t, path), state)| {
            Json::Object(vec![
                ("tension", Json::Number(state.tension)),
                ("displacement", Json::Number(state.displacement)),
                ("length", Json::Number(state.length)),
                ("reference_length", Json::Number(state.reference_length)),
                ("slack", Json::Number(state.slack)),
                ("end", Json::Number(t.end(robot.length()))),
                // The turns the tendon makes over its own length.
                ("turns", Json::Number(t.turns(robot.length()))),
                ("path", Json::Array(path.iter().map(Json::vector).collect())),
            ])
        })
        .collect();
    let mut fields = vec![
        (
            "converged",
            Json::Bool(report.termination == crate::Termination::Converged),
        ),
        ("method", Json::Text(report.method.to_string())),
        ("termination", Json::Text(report.termination.to_string())),
        ("iterations", Json::Integer(report.iterations)),
        (
            "counts",
            Json::Object(vec![
                ("newton_steps", Json::Integer(report.newton_steps)),
                ("chord_steps", Json::Integer(report.chord_steps)),
                ("jacobian_evaluations", Json::Integer(report.evaluations.jacobian)),
                ("residual_evaluations", Json::Integer(report.evaluations.residual)),
                ("load_steps", Json::Integer(report.load_steps)),
                ("meshes", Json::Integer(report.meshes)),
            ]),
        ),
        ("load_steps", Json::Integer(report.load_steps)),
        ("stability", stability(report)),
        ("residual", Json::Number(report.residual)),
        ("intervals", Json::Integer(report.intervals)),
        (
            "tip_error_estimate",
            Json::optional(report.error_estimate.map(|e| e.tip_position)),
        ),
        (
            "error_estimate",
            match report.error_estimate {
                Some(e) => Json::Object(vec![
                    ("tip_position_m", Json::Number(e.tip_position)),
                    ("tip_rotation_rad", Json::Number(e.tip_rotation)),
                    ("backbone_max_m", Json::Number(e.backbone_max)),
                ]),
                None => Json::Null,
            },
        ),
        ("tolerance", Json::optional(report.tolerance)),
        ("tolerance_met", report.tolerance_met.map_or(Json::Null, Json::Bool)),
        ("solve_time", Json::Number(report.timings.total.as_secs_f64())),
        ("bending_angle_deg", Json::Number(bending_angle(solution).to_degrees())),
        (
            "tip",
            Json::Object(vec![
                ("position", Json::vector(&tip.p)),
                ("rotation", Json::matrix(&tip.R)),
                ("force", Json::vector(&tip.n)),
                ("moment", Json::vector(&tip.m)),
            ]),
        ),
        ("samples", Json::Array(samples)),
        ("tendons", Json::Array(tendons)),
    ];
    if let Some(j) = jacobian {
        // Rows: tip position (m per unit), then the tip rotation as a world-frame rotation
        // vector (rad per unit); one column per tendon (N of tension, m of pull-in), force (N)
        // or moment (N m) component.
        let rows = |m: &dyn Fn(usize, usize) -> f64, cols: usize| {
            Json::Array(
                (0..6)
                    .map(|r| Json::Array((0..cols).map(|c| Json::Number(m(r, c))).collect()))
                    .collect(),
            )
        };
        fields.push((
            "jacobian",
            Json::Object(vec![
                ("tension", rows(&|r, c| j.tension[(r, c)], j.tension.ncols())),
                (
                    "displacement",
                    rows(&|r, c| j.displacement[(r, c)], j.displacement.ncols()),
                ),
                ("tip_force", rows(&|r, c| j.tip_force[(r, c)], 3)),
                ("tip_moment", rows(&|r, c| j.tip_moment[(r, c)], 3)),
            ]),
        ));
    }
    let out = Json::Object(fields);
    let mut text = String::new();
    out.write(&mut text, 0, false);
    text.push('\n');
    text
}

/// The CSV header: arc length, position, internal force and moment, and R row-major.
pub const CSV_HEADER: &str = "s,px,py,pz,nx,ny,nz,mx,my,mz,R11,R12,R13,R21,R22,R23,R31,R32,R33";

/// The `stability` object: the verdict, its details, and how the equilibrium was reached.
fn stability(report: &crate::SolveReport) -> Json {
    let mut fields = vec![("verdict", Json::Text(report.stability.verdict().into()))];
    match &report.stability {
        crate::Stability::Stable => {}
        crate::Stability::Unstable {
            directions,
            conjugate_point,
        } => {
            fields.push(("unstable_directions", Json::Integer(*directions)));
            fields.push(("conjugate_point_s", Json::Number(*conjugate_point)));
        }
        crate::Stability::Unknown { reason } => fields.push(("reason", Json::Text(reason.clone()))),
    }
    let (path, folds, bifurcations) = match &report.path {
        crate::Path::Direct => ("direct", Vec::new(), Vec::new()),
        crate::Path::FromWarmStart { folds, bifurcations } => ("from_warm_start", folds.clone(), bifurcations.clone()),
        crate::Path::LoadPath { folds, bifurcations } => ("load_path", folds.clone(), bifurcations.clone()),
    };
    let numbers = |v: Vec<f64>| Json::Array(v.into_iter().map(Json::Number).collect());
    fields.push(("path", Json::Text(path.into())));
    fields.push(("folds", numbers(folds)));
    fields.push(("bifurcations", numbers(bifurcations)));
    Json::Object(fields)
}

/// The samples as CSV: [`CSV_HEADER`], then one row per sample (SI units, full precision).
pub fn csv(samples: &[Sample]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for x in samples {
        let mut values = vec![x.s];
        values.extend(x.p.iter().chain(x.n.iter()).chain(x.m.iter()));
        values.extend(rows(&x.R).iter().flatten());
        let line: Vec<String> = values.iter().map(|&v| number(v)).collect();
        let _ = writeln!(out, "{}", line.join(","));
    }
    out
}

/// A number for CSV: the shortest text that reads back to the same f64, in exponent form
/// when it is very small or very large (`1.0844e-28` rather than 28 zeros).
pub fn number(x: f64) -> String {
    let magnitude = x.abs();
    if x != 0.0 && x.is_finite() && !(1e-4..1e15).contains(&magnitude) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}
