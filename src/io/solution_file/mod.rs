//! The solution JSON (docs/cli.md, "The solution JSON"): one format, written by `tdcr solve
//! --format json` ([`crate::io::output::json`], with samples, tendon ends and Jacobians that
//! need the robot) and by Python's `Solution.to_json` ([`crate::io::output::solution_json`]),
//! read back by [`parse_solution`] to the same [`Solution`], bitwise, and by
//! [`read_solution`] as a warm start for a given robot.
//!
//! Reading validates: a text that is not the format, a missing key, a non-finite or
//! decreasing arc length, a non-finite state, a rotation that is not one, a tendon without a
//! path or with more points than nodes, or a report whose parts disagree is an
//! [`crate::Error::InvalidInput`] on `solution`, never a panic.
#![allow(non_snake_case)] // R, as the paper names it

pub(crate) mod format;

use crate::error::{Result, invalid};
use crate::report::{
    ErrorEstimate, Evaluations, Iteration, Method, PathTaken, SolveReport, Stability, Termination, Timings,
};
use crate::solution::{Node, Solution, TendonState};
use crate::{Readable, Robot, so3};
use format::{FORMAT, Num, SolutionFile, V3, matrix, vector};
use nalgebra::Vector3;
use serde::Deserialize;
use serde_json::Value;
use std::time::Duration;

/// Largest |R^T R - I|, |det R - 1| accepted for a node's rotation: the robot file's rule for
/// a base rotation (1e-6), far above the rounding of a solved R (1e-15).
const ROTATION_TOLERANCE: f64 = 1e-6;

fn bad(problem: String) -> crate::Error {
    invalid(
        "solution",
        problem,
        format!("give a solution JSON (format \"{FORMAT}\") that this version of tdcr wrote, unedited"),
    )
}

/// The solution saved in `text`, a solution JSON (docs/cli.md): every node's state, the
/// tendon paths and states and the report, bitwise as written (a non-finite number, written
/// as `null`, reads back as NaN).
///
/// # Errors
/// [`crate::Error::InvalidInput`] on `solution` for text that is not JSON, not this format
/// (an older one included), lacks a key, or is inconsistent: fewer than two nodes, an arc
/// length that is not finite, negative, decreasing, not 0 at the first node or 0 at the last, a non-finite
/// node state or tendon path, a node rotation that is not a rotation, a tendon without a path
/// or with more path points than nodes, a negative or non-finite tension, or report fields
/// that disagree.
///
/// # Examples
/// ```
/// let robot = tdcr::cases::case_s();
/// let solution = tdcr::solve(&robot, &Default::default()).unwrap();
/// let text = tdcr::io::output::solution_json(&solution);
/// let back = tdcr::io::parse_solution(&text).unwrap();
/// assert_eq!(back.nodes, solution.nodes);
/// assert!(tdcr::io::parse_solution("{}").is_err());
/// ```
pub fn parse_solution(text: &str) -> Result<Solution> {
    let value: Value = serde_json::from_str(text).map_err(|e| bad(format!("is not JSON: {e}")))?;
    match value.get("format").map(Value::as_str) {
        Some(Some(FORMAT)) => {}
        Some(Some(old @ ("tdcr-solution-1" | "tdcr-solution-2"))) => {
            return Err(bad(format!(
                "has `format` \"{old}\", written by an older tdcr; this version reads \"{FORMAT}\": solve the robot again"
            )));
        }
        None if value.get("samples").is_some() => {
            return Err(bad(
                "has no `format`: it was written by an older tdcr, without the nodes' strains; solve the robot again"
                    .into(),
            ));
        }
        _ => {
            return Err(bad(format!(
                "has no `format` \"{FORMAT}\": it is not a Solution.to_json text nor the JSON of a solve"
            )));
        }
    }
    let file = SolutionFile::deserialize(value).map_err(|e| bad(format!("is not a complete solution JSON: {e}")))?;
    file.solution()
}

/// The solution of `robot` saved in `text` (a solution JSON, as [`parse_solution`] reads
/// it), as a warm start: checked to run from 0 to the robot's length.
///
/// # Errors
/// As [`parse_solution`], and [`crate::Error::InvalidInput`] on `solution` for a solution of
/// a rod of another length.
pub fn read_solution(text: &str, robot: &Robot) -> Result<Solution> {
    let solution = parse_solution(text)?;
    let (length, last) = (robot.length(), solution.length());
    // 1e-9 L: a robot file that spells the length with other digits.
    if (last - length).abs() > 1e-9 * length {
        return Err(bad(format!(
            "runs from s = 0 m to {} m, but the robot's rod is {} m long",
            Readable(last),
            Readable(length)
        )));
    }
    Ok(solution)
}

/// `[x, y, z]` if every component is finite.
fn finite(v: &V3, what: &str) -> Result<Vector3<f64>> {
    let x = vector(v);
    if x.iter().all(|c| c.is_finite()) {
        Ok(x)
    } else {
        Err(bad(format!("{what} = {:?} is not finite", [x.x, x.y, x.z])))
    }
}

/// The termination whose sentence is `text`.
fn termination(text: &str) -> Result<Termination> {
    Termination::ALL
        .into_iter()
        .find(|t| t.to_string() == text)
        .ok_or_else(|| {
            bad(format!(
                "`termination` \"{text}\" is not one of the solver's terminations"
            ))
        })
}

impl SolutionFile {
    /// The solution, checked.
    fn solution(self) -> Result<Solution> {
        if self.nodes.len() < 2 {
            return Err(bad(format!(
                "has {} node(s); a solution has at least 2",
                self.nodes.len()
            )));
        }
        let mut nodes: Vec<Node> = Vec::with_capacity(self.nodes.len());
        for (k, x) in self.nodes.iter().enumerate() {
            let what = |field: &str| format!("nodes[{k}].{field}");
            let s = x.s.0;
            let before = nodes.last().map_or(0.0, |n| n.s);
            if !s.is_finite() || s < before || (k == 0 && s != 0.0) {
                return Err(bad(format!(
                    "{} = {} m: arc lengths run from 0 and never decrease",
                    what("s"),
                    Readable(s)
                )));
            }
            let R = matrix(&x.R);
            let error = so3::orthonormality_error(&R);
            if error.is_nan() || error > ROTATION_TOLERANCE {
                return Err(bad(format!("{} is not a rotation matrix", what("R"))));
            }
            nodes.push(Node {
                s,
                p: finite(&x.p, &what("p"))?,
                R,
                v: finite(&x.v, &what("v"))?,
                u: finite(&x.u, &what("u"))?,
                v_s: finite(&x.v_s, &what("v_s"))?,
                u_s: finite(&x.u_s, &what("u_s"))?,
                n: finite(&x.n, &what("n"))?,
                m: finite(&x.m, &what("m"))?,
            });
        }
        if let Some(last) = nodes.last().filter(|n| n.s <= 0.0) {
            return Err(bad(format!(
                "nodes[{}].s = {} m: the last node is the tip, at the rod's length > 0",
                nodes.len() - 1,
                Readable(last.s)
            )));
        }
        let mut tendon_paths = Vec::with_capacity(self.tendons.len());
        let mut tendon_tensions = Vec::with_capacity(self.tendons.len());
        let mut tendons = Vec::with_capacity(self.tendons.len());
        for (i, t) in self.tendons.iter().enumerate() {
            if t.path.is_empty() || t.path.len() > nodes.len() {
                return Err(bad(format!(
                    "tendons[{i}].path has {} points; a tendon's path has one per node up to its end (1 to {})",
                    t.path.len(),
                    nodes.len()
                )));
            }
            if !t.tension.0.is_finite() || t.tension.0 < 0.0 {
                return Err(bad(format!(
                    "tendons[{i}].tension = {} N: a tension is finite and >= 0",
                    Readable(t.tension.0)
                )));
            }
            let path: Vec<Vector3<f64>> = t
                .path
                .iter()
                .enumerate()
                .map(|(k, p)| finite(p, &format!("tendons[{i}].path[{k}]")))
                .collect::<Result<_>>()?;
            let along: Vec<f64> = match &t.tensions {
                None => vec![t.tension.0; path.len()],
                Some(values) if values.len() == path.len() && values.iter().all(|x| x.0.is_finite() && x.0 >= 0.0) => {
                    values.iter().map(|x| x.0).collect()
                }
                Some(values) => {
                    return Err(bad(format!(
                        "tendons[{i}].tensions has {} entries; a tendon's tensions are one finite value >= 0 N per \
                         point of its path ({})",
                        values.len(),
                        path.len()
                    )));
                }
            };
            let delivered = t.delivered_tension.as_ref().map_or(t.tension.0, |x| x.0);
            if !(delivered.is_finite() && delivered >= 0.0) {
                return Err(bad(format!(
                    "tendons[{i}].delivered_tension = {} N: a tension is finite and >= 0",
                    Readable(delivered)
                )));
            }
            tendon_paths.push(path);
            tendon_tensions.push(along);
            tendons.push(TendonState {
                tension: t.tension.0,
                delivered_tension: delivered,
                displacement: t.displacement.0,
                length: t.length.0,
                reference_length: t.reference_length.0,
                slack: t.slack.0,
            });
        }
        let report = self.report()?;
        Ok(Solution {
            nodes,
            tendon_paths,
            tendon_tensions,
            tendons,
            report,
        })
    }

    /// The solve report, checked.
    fn report(&self) -> Result<SolveReport> {
        let method = match self.method.as_str() {
            "collocation" => Method::Collocation,
            "shooting" => Method::Shooting,
            other => {
                return Err(bad(format!(
                    "`method` \"{other}\" is not \"collocation\" or \"shooting\""
                )));
            }
        };
        let mut report = SolveReport::new(method);
        report.termination = termination(&self.termination)?;
        if self.converged != (report.termination == Termination::Converged) {
            return Err(bad(format!(
                "says `converged` {} but `termination` \"{}\"",
                self.converged, self.termination
            )));
        }
        let c = &self.counts;
        if c.load_steps != self.load_steps {
            return Err(bad(format!(
                "has `load_steps` {} but `counts.load_steps` {}",
                self.load_steps, c.load_steps
            )));
        }
        report.iterations = self.iterations;
        report.newton_steps = c.newton_steps;
        report.chord_steps = c.chord_steps;
        report.load_steps = c.load_steps;
        report.meshes = c.meshes;
        report.history = self
            .history
            .iter()
            .map(|i| Iteration {
                residual: i.residual.0,
                step: i.step.0,
                damping: i.damping.0,
                fresh_jacobian: i.fresh_jacobian,
            })
            .collect();
        report.residual = self.residual.0;
        report.evaluations = Evaluations {
            residual: c.residual_evaluations,
            jacobian: c.jacobian_evaluations,
            equations: c.equation_evaluations,
        };
        let t = &self.timings_ns;
        report.timings = Timings {
            assembly: Duration::from_nanos(t.assembly),
            factorization: Duration::from_nanos(t.factorization),
            solve: Duration::from_nanos(t.solve),
            estimate: Duration::from_nanos(t.estimate),
            stability: Duration::from_nanos(t.stability),
            total: Duration::from_nanos(t.total),
        };
        report.unknowns = self.unknowns;
        report.nonzeros = self.nonzeros;
        report.notes = self.notes.clone();
        report.intervals = self.intervals;
        report.error_estimate = self.error_estimate.as_ref().map(|e| ErrorEstimate {
            tip_position: e.tip_position_m.0,
            tip_rotation: e.tip_rotation_rad.0,
            backbone_max: e.backbone_max_m.0,
            order: e.order,
        });
        report.tolerance = self.tolerance;
        report.tolerance_met = self.tolerance_met;
        report.stability = self.stability()?;
        report.path = self.path()?;
        Ok(report)
    }

    /// The stability verdict with its details.
    fn stability(&self) -> Result<Stability> {
        let s = &self.stability;
        match (
            s.verdict.as_str(),
            s.unstable_directions,
            s.conjugate_point_s,
            &s.reason,
        ) {
            ("stable", ..) => Ok(Stability::Stable),
            ("unstable", Some(directions), Some(Num(conjugate_point)), _) => Ok(Stability::Unstable {
                directions,
                conjugate_point,
            }),
            ("unknown", _, _, Some(reason)) => Ok(Stability::Unknown { reason: reason.clone() }),
            ("unstable", None, None, _) if s.growth.is_some() => {
                let rate = s.growth_rate.map_or(f64::NAN, |Num(r)| r);
                match (s.growth.as_deref(), s.flutter_frequency) {
                    (Some("divergence"), _) => Ok(Stability::Growing {
                        growth: crate::report::Growth::Divergence,
                        rate,
                    }),
                    (Some("flutter"), Some(Num(frequency))) => Ok(Stability::Growing {
                        growth: crate::report::Growth::Flutter { frequency },
                        rate,
                    }),
                    (growth, _) => Err(bad(format!(
                        "has `stability.growth` {growth:?}: expected \"divergence\", or \"flutter\" with `flutter_frequency`"
                    ))),
                }
            }
            (verdict, ..) => Err(bad(format!(
                "has `stability.verdict` \"{verdict}\" without its details (\"stable\"; \"unstable\" with `unstable_directions` and `conjugate_point_s`, or with `growth` and `growth_rate`; \"unknown\" with `reason`)"
            ))),
        }
    }

    /// How the equilibrium was reached.
    fn path(&self) -> Result<PathTaken> {
        let s = &self.stability;
        let numbers = |x: &[Num]| x.iter().map(|x| x.0).collect();
        PathTaken::from_name(&s.path, numbers(&s.folds), numbers(&s.bifurcations)).ok_or_else(|| {
            bad(format!(
                "has `stability.path` \"{}\", not \"direct\", \"from_warm_start\", \"load_path\" or \"fallback\"",
                s.path
            ))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A change to a solution JSON.
    type Edit<'a> = &'a dyn Fn(&mut Value);

    /// Everything a solution holds, compared bitwise (NaN equal to NaN).
    fn assert_same(a: &Solution, b: &Solution) {
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.tendon_paths, b.tendon_paths);
        assert_eq!(a.tendons, b.tendons);
        assert_eq!(format!("{:?}", a.report), format!("{:?}", b.report));
    }

    #[test]
    fn a_saved_solution_reads_back_bitwise_and_warm_starts_in_a_step() {
        let mut pulled = crate::cases::prototype();
        pulled.tendons[0].set_displacement(0.005);
        for robot in [crate::cases::case_s(), crate::cases::case_h(), pulled] {
            let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
            for text in [
                crate::io::output::json(&robot, &solution, None, None),
                crate::io::output::json(&robot, &solution, Some(7), None),
                crate::io::output::solution_json(&solution),
            ] {
                let back = read_solution(&text, &robot).unwrap();
                assert_same(&back, &solution);
                // Written again, the same text.
                assert_eq!(
                    crate::io::output::solution_json(&back),
                    crate::io::output::solution_json(&solution)
                );
            }
            let back = parse_solution(&crate::io::output::json(&robot, &solution, None, None)).unwrap();
            let warm = crate::collocation::solve_from(&robot, &Default::default(), &back).unwrap();
            assert!(warm.report.iterations <= 2, "{}", warm.report.iterations);
        }
    }

    /// The report's notes are written and read back (a solve with friction carries its
    /// verdict's scope); a report without notes writes no `notes` key.
    #[test]
    fn the_reports_notes_read_back() {
        let mut robot = crate::cases::case_s();
        let plain = crate::collocation::solve(&robot, &Default::default()).unwrap();
        assert!(plain.report.notes.is_empty());
        assert!(!crate::io::output::solution_json(&plain).contains("\"notes\""));
        robot.tendons[0].friction = Some(crate::Friction::pull(0.1));
        let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
        assert!(!solution.report.notes.is_empty());
        let back = parse_solution(&crate::io::output::json(&robot, &solution, None, None)).unwrap();
        assert_eq!(back.report.notes, solution.report.notes);
    }

    #[test]
    fn non_finite_report_numbers_are_written_as_null_and_read_as_nan() {
        let robot = crate::cases::case_s();
        let mut solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
        solution.report.residual = f64::NAN;
        solution.report.history[0].step = f64::INFINITY;
        let text = crate::io::output::solution_json(&solution);
        assert!(text.contains("\"residual\": null"), "{text}");
        let back = parse_solution(&text).unwrap();
        assert!(back.report.residual.is_nan());
        // JSON has no infinity: it comes back as NaN, documented in docs/cli.md.
        assert!(back.report.history[0].step.is_nan());
    }

    #[test]
    fn bad_or_inconsistent_files_are_invalid_input_not_panics() {
        let robot = crate::cases::case_s();
        let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
        let text = crate::io::output::solution_json(&solution);
        let value: Value = serde_json::from_str(&text).unwrap();
        let edited = |edit: &dyn Fn(&mut Value)| {
            let mut v = value.clone();
            edit(&mut v);
            parse_solution(&v.to_string()).unwrap_err().to_string()
        };
        let cases: [(Edit, &str); 13] = [
            (
                &|v| {
                    for node in v["nodes"].as_array_mut().unwrap() {
                        node["s"] = 0.0.into();
                    }
                },
                "the last node is the tip",
            ),
            (&|v| v["nodes"][3]["s"] = Value::Null, "nodes[3].s = NaN m"),
            (&|v| v["nodes"][0]["s"] = (-1.0).into(), "nodes[0].s = -1 m"),
            (&|v| v["nodes"][5]["s"] = 0.0.into(), "never decrease"),
            (&|v| v["nodes"][2]["p"][1] = Value::Null, "nodes[2].p"),
            (
                &|v| v["nodes"][2]["R"][0][0] = 2.0.into(),
                "nodes[2].R is not a rotation",
            ),
            (&|v| v["nodes"] = serde_json::json!([]), "has 0 node(s)"),
            (
                &|v| v["tendons"][1]["path"] = serde_json::json!([]),
                "tendons[1].path has 0 points",
            ),
            (
                &|v| v["tendons"][0]["tension"] = (-1.0).into(),
                "tendons[0].tension = -1 N",
            ),
            (
                &|v| v["nodes"][1]["v"] = serde_json::json!([1.0, 2.0]),
                "is not a complete solution JSON",
            ),
            (&|v| v["converged"] = false.into(), "says `converged` false"),
            (
                &|v| v["stability"]["path"] = "other".into(),
                "`stability.path` \"other\"",
            ),
            (&|v| v["format"] = "tdcr-solution-2".into(), "older tdcr"),
        ];
        for (edit, expected) in cases {
            let e = edited(edit);
            assert!(
                e.contains(expected) && e.starts_with("invalid input: `solution`"),
                "{e}"
            );
        }
        let long = vec![value["tendons"][0]["path"][0].clone(); solution.nodes.len() + 1];
        assert!(edited(&|v| v["tendons"][0]["path"] = Value::Array(long.clone())).contains("1 to"));
        assert!(
            parse_solution("{}")
                .unwrap_err()
                .to_string()
                .contains("not a Solution.to_json text")
        );
        assert!(parse_solution("[1,").unwrap_err().to_string().contains("is not JSON"));
        // A file of the CLI before format 3 (no `format`, samples only).
        let old = r#"{"converged": true, "samples": []}"#;
        assert!(parse_solution(old).unwrap_err().to_string().contains("older tdcr"));
        // A solution of another robot (a longer rod) says both lengths.
        let mut longer = robot.clone();
        longer.rod.length = 0.3;
        let e = read_solution(&text, &longer).unwrap_err().to_string();
        assert!(e.contains("0.3 m long"), "{e}");
    }
}
