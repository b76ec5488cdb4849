//! Result files: the solved shape sampled along the backbone, as JSON or CSV (docs/cli.md
//! lists every field and unit). SI units throughout.
#![allow(non_snake_case)]

pub use crate::analysis::samples::{Sample, bending_angle, samples};
use crate::collocation::sensitivity::TipSensitivities;
use crate::io::csv_table::CsvTable;
pub use crate::io::csv_table::number;
use crate::io::json_layout::pretty;
use crate::io::solution_file::format::{Jacobian, Num, SolutionFile, TipJacobian, sample_entry};
use crate::{Parameter, Robot, Solution};
use nalgebra::{DMatrix, Matrix3};

fn rows(R: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [R[(i, 0)], R[(i, 1)], R[(i, 2)]])
}

/// The solution JSON of `tdcr solve --format json` (every key and unit in docs/cli.md, "The
/// solution JSON"): the solve report, the tip pose and wrench, the samples of [`samples`] for
/// `count`, each tendon's tension, pull-in, lengths, slack, end, turns about the backbone
/// over its own length ([`crate::Tendon::turns`]) and path, the tip Jacobians when given,
/// and every node's full state, which [`crate::io::parse_solution`] reads back bitwise.
/// Vectors are `[x, y, z]`, matrices lists of rows; one sample per line.
pub fn json(robot: &Robot, solution: &Solution, count: Option<usize>, jacobian: Option<&TipSensitivities>) -> String {
    let mut file = with_robot(robot, solution, count);
    file.jacobian = jacobian.map(|j| {
        // Rows: tip position (m per unit), then the tip rotation as a world-frame rotation
        // vector (rad per unit); one column per tendon (N of tension, m of pull-in, unit of
        // friction coefficient), force (N) or moment (N m) component.
        let rows = |m: &dyn Fn(usize, usize) -> f64, cols: usize| {
            (0..6).map(|r| (0..cols).map(|c| Num(m(r, c))).collect()).collect()
        };
        Jacobian {
            tension: rows(&|r, c| j.tension[(r, c)], j.tension.ncols()),
            displacement: rows(&|r, c| j.displacement[(r, c)], j.displacement.ncols()),
            friction: rows(&|r, c| j.friction[(r, c)], j.friction.ncols()),
            tip_force: rows(&|r, c| j.tip_force[(r, c)], 3),
            tip_moment: rows(&|r, c| j.tip_moment[(r, c)], 3),
        }
    });
    pretty(&file)
}

/// As [`json`] without the full tip Jacobians, with the columns `tip` (6 x `wrt.len()`,
/// [`crate::collocation::sensitivity::tip_jacobian`]) under `tip_jacobian`: `columns` the
/// parameters' names, `rows` six lists (tip position in m per unit, then the world-frame
/// tip rotation vector in rad per unit), one entry per column.
pub fn json_with_tip_jacobian(
    robot: &Robot,
    solution: &Solution,
    count: Option<usize>,
    wrt: &[Parameter],
    tip: &DMatrix<f64>,
) -> String {
    let mut file = with_robot(robot, solution, count);
    file.tip_jacobian = Some(TipJacobian {
        columns: wrt.iter().map(|p| p.to_string()).collect(),
        rows: (0..tip.nrows())
            .map(|r| (0..tip.ncols()).map(|c| Num(tip[(r, c)])).collect())
            .collect(),
    });
    pretty(&file)
}

/// The solution file of `solution` with what needs the robot: the samples for `count`,
/// each tendon's end and turns.
fn with_robot(robot: &Robot, solution: &Solution, count: Option<usize>) -> SolutionFile {
    let mut file = SolutionFile::new(solution);
    if count.is_some() {
        file.samples = samples(robot, solution, count).iter().map(sample_entry).collect();
    }
    // With friction, every tendon's tension at every sample (null past its end).
    if !friction_tendons(robot).is_empty() {
        for entry in &mut file.samples {
            let s = entry.s.0;
            let at = |i: usize| Num(tension_at_sample(robot, solution, i, s).unwrap_or(f64::NAN));
            entry.tensions = Some((0..robot.tendons.len()).map(at).collect());
        }
    }
    let length = robot.length();
    for (entry, tendon) in file.tendons.iter_mut().zip(&robot.tendons) {
        entry.end = Some(Num(tendon.end(length)));
        // The turns the tendon makes over its own length (null: a custom routing).
        entry.turns = Some(Num(tendon.turns(length)));
    }
    file
}

/// The solution JSON of a solution alone (Python's `Solution.to_json`): the keys of
/// [`json`] that need no robot, with the nodes as the samples and the tendons without `end`
/// and `turns`. [`crate::io::parse_solution`] reads it back bitwise.
pub fn solution_json(solution: &Solution) -> String {
    pretty(&SolutionFile::new(solution))
}

/// The CSV header: arc length, position, internal force and moment, and R row-major.
pub const CSV_HEADER: &str = "s,px,py,pz,nx,ny,nz,mx,my,mz,R11,R12,R13,R21,R22,R23,R31,R32,R33";

/// The samples of `solution` (of `robot`) as CSV: [`CSV_HEADER`], then for each tendon I
/// with friction ([`friction_tendons`]) a column `tension.I`, its tension at the sample
/// ([`tension_at_sample`], blank past its end); one row per sample (SI units, full
/// precision). Without friction the columns are those of [`CSV_HEADER`] alone.
pub fn csv(robot: &Robot, solution: &Solution, samples: &[Sample]) -> String {
    let varying = friction_tendons(robot);
    let heads = varying.iter().map(|&i| Parameter::Tension(i).to_string());
    let mut table = CsvTable::new(CSV_HEADER.split(',').map(str::to_string).chain(heads));
    for x in samples {
        let mut values = vec![x.s];
        values.extend(x.p.iter().chain(x.n.iter()).chain(x.m.iter()));
        values.extend(rows(&x.R).iter().flatten());
        let mut cells: Vec<String> = values.into_iter().map(number).collect();
        cells.extend(
            varying
                .iter()
                .map(|&i| tension_at_sample(robot, solution, i, x.s).map_or_else(String::new, number)),
        );
        table.row(cells);
    }
    table.finish()
}

/// The tendons of `robot` with friction (a positive coefficient), 0-based in file order:
/// those whose tension varies along their path.
pub fn friction_tendons(robot: &Robot) -> Vec<usize> {
    (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].active_friction().is_some())
        .collect()
}

/// The tension (N) of tendon `i` (0-based) at arc length `s` of `solution`
/// ([`Solution::tension_at`], docs/friction.md), `None` past the tendon's end on `robot`
/// (or for a tendon it does not have): the value of the table's `TI/N`, the CSV's
/// `tension.I` and the JSON's `samples[].tensions`.
pub fn tension_at_sample(robot: &Robot, solution: &Solution, i: usize, s: f64) -> Option<f64> {
    let end = robot.tendons.get(i)?.end(robot.length());
    if s > end {
        return None;
    }
    solution.tension_at(i, s)
}
