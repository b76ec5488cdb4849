//! Reading a saved solution back: the JSON of `tdcr solve --format json` (written without
//! `--samples`, so that its samples are the solution's nodes) as a warm start for `sweep
//! --start` or `solve --start`.

use crate::error::{Result, invalid};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport};
use crate::solution::{Solution, State};
use crate::{Readable, Robot};
use nalgebra::{Matrix3, Vector3};
use serde_json::Value;

fn bad(problem: String) -> crate::Error {
    invalid(
        "start",
        problem,
        "give the JSON that `tdcr solve ROBOT --format json` wrote for this robot (without --samples)",
    )
}

fn vector(v: &Value, what: &str) -> Result<Vector3<f64>> {
    let parts: Vec<f64> = v
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default();
    match parts.as_slice() {
        [x, y, z] if parts.iter().all(|c| c.is_finite()) => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(bad(format!("{what} is not three finite numbers"))),
    }
}

fn matrix(v: &Value, what: &str) -> Result<Matrix3<f64>> {
    let rows = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| bad(format!("{what} is not 3 rows")))?;
    let mut m = Matrix3::zeros();
    for (i, row) in rows.iter().enumerate() {
        m.set_row(i, &vector(row, what)?.transpose());
    }
    Ok(m)
}

/// The solution of `robot` saved in `text` (the JSON of `tdcr solve --format json`): its
/// nodes' s, p and R, with v and u recovered from the saved internal wrench n, m by the
/// constitutive law of `robot`'s rod (exact for the robot it was solved for), and the saved
/// tendon tensions (the solved ones of displacement-controlled tendons) when the file has
/// one per tendon.
///
/// # Errors
/// [`crate::Error::InvalidInput`] on `start` for text that is not such JSON, samples that are
/// not a solution's nodes, or a solution of a rod of another length.
#[allow(non_snake_case)] // R, as the paper names it
pub fn read_solution(text: &str, robot: &Robot) -> Result<Solution> {
    let json: Value = serde_json::from_str(text).map_err(|e| bad(format!("is not JSON: {e}")))?;
    let samples = json["samples"]
        .as_array()
        .filter(|s| s.len() >= 2)
        .ok_or_else(|| bad("has no `samples` list of at least two nodes".into()))?;
    // The solved tensions (a displacement-controlled tendon's is an unknown of the solve,
    // and a warm start needs it), when the file has one per tendon.
    let solved = json["tendons"]
        .as_array()
        .filter(|t| t.len() == robot.tendons.len())
        .and_then(|t| {
            t.iter()
                .map(|t| t["tension"].as_f64().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
        })
        .map(|tensions| robot.with_tensions(&tensions));
    let model = Model::new(solved.as_ref().unwrap_or(robot));
    let mut states = Vec::with_capacity(samples.len());
    for (k, sample) in samples.iter().enumerate() {
        let what = |field: &str| format!("samples[{k}].{field}");
        let s = sample["s"]
            .as_f64()
            .filter(|s| s.is_finite())
            .ok_or_else(|| bad(format!("{} is not a number", what("s"))))?;
        let p = vector(&sample["p"], &what("p"))?;
        let R = matrix(&sample["R"], &what("R"))?;
        let (n, m) = (vector(&sample["n"], &what("n"))?, vector(&sample["m"], &what("m"))?);
        let site = model.site(s);
        let (v, u) = model.strains_for_wrench(&site, &(R.transpose() * n), &(R.transpose() * m));
        states.push(State { s, p, R, v, u });
    }
    let length = robot.length();
    let last = states[states.len() - 1].s;
    // 1e-9 L: the JSON's numbers are printed to 17 digits.
    if (last - length).abs() > 1e-9 * length || states[0].s != 0.0 {
        return Err(bad(format!(
            "runs from s = {} m to {} m, but the robot's rod is {} m long",
            Readable(states[0].s),
            Readable(last),
            Readable(length)
        )));
    }
    let points: Vec<f64> = states.iter().map(|x| x.s).collect();
    let mesh = Mesh::from_points(robot, &points)?;
    if mesh.nodes.len() != states.len()
        || mesh
            .nodes
            .iter()
            .zip(&states)
            .any(|(a, b)| (a.s - b.s).abs() > 1e-9 * length)
    {
        return Err(bad(
            "its samples are not a solution's nodes for this robot (written with --samples, or for a robot with other breakpoints)"
                .into(),
        ));
    }
    // The mesh's arc lengths, so that a warm start on the same mesh matches them exactly.
    for (x, node) in states.iter_mut().zip(&mesh.nodes) {
        x.s = node.s;
    }
    let ends: Vec<f64> = mesh.nodes.iter().map(|n| n.segment_end).collect();
    nodes::solution(&model, &states, &ends, None, SolveReport::new(Method::Collocation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saved_solution_reads_back_as_the_same_shape() {
        for robot in [crate::cases::case_s(), crate::cases::case_h()] {
            let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
            let text = crate::io::output::json(&robot, &solution, None, None);
            let back = read_solution(&text, &robot).unwrap();
            assert_eq!(back.nodes.len(), solution.nodes.len());
            for (a, b) in back.nodes.iter().zip(&solution.nodes) {
                // 1e-12: the JSON's 17 significant digits, through K^-1 of the wrench
                assert!((a.p - b.p).norm() < 1e-12 && (a.v - b.v).norm() < 1e-9 && (a.u - b.u).norm() < 1e-7);
            }
            // A warm start from it converges in a step or two, on the same mesh.
            let warm = crate::collocation::solve_from(&robot, &Default::default(), &back).unwrap();
            assert!(warm.report.iterations <= 2, "{}", warm.report.iterations);
        }
        // A displacement-controlled tendon's solved tension comes back with the shape.
        let mut pulled = crate::cases::prototype();
        pulled.tendons[0].set_displacement(0.005);
        let solution = crate::collocation::solve(&pulled, &Default::default()).unwrap();
        let back = read_solution(&crate::io::output::json(&pulled, &solution, None, None), &pulled).unwrap();
        // 1e-12 relative: 17 printed digits
        assert!((back.tendons[0].tension / solution.tendons[0].tension - 1.0).abs() < 1e-12);
        let warm = crate::collocation::solve_from(&pulled, &Default::default(), &back).unwrap();
        assert!(warm.report.iterations <= 2, "{}", warm.report.iterations);
        let robot = crate::cases::case_s();
        let mut longer = robot.clone();
        longer.rod.length = 0.3;
        let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
        let text = crate::io::output::json(&robot, &solution, None, None);
        let e = read_solution(&text, &longer).unwrap_err().to_string();
        assert!(e.contains("0.3 m long"), "{e}");
        assert!(read_solution("{}", &robot).unwrap_err().to_string().contains("samples"));
    }
}
