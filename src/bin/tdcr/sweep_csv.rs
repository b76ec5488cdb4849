//! The CSV of `tdcr sweep` (without `--history`): one row per step with the inputs, the
//! tip, the solver's work and verdict, and each tendon with friction's delivered tension.

use tdcr::io::csv_table::CsvTable;
use tdcr::io::{number, output};
use tdcr::{Parameter, Robot, Solution};

use crate::sweep::{Plan, SweepArgs, at};

/// The CSV table with its header: the tensions of `robot`'s tendons (`tension.I`), the
/// pull-ins of the `--displacement` tendons (`displacement.I`), the `--param` inputs other
/// than tensions (a `--param tension.I` is the `tension.I` column), the results, then each
/// tendon with friction's delivered tension (at its termination), as `sweep --history`
/// gives it. Every input column is named as the parameter it is (`Parameter`'s names).
pub fn header(args: &SweepArgs, plan: &Plan, robot: &Robot) -> CsvTable {
    let mut names = vec!["step".to_string()];
    names.extend((0..robot.tendons.len()).map(|i| Parameter::Tension(i).to_string()));
    names.extend(
        args.displacement
            .iter()
            .map(|(i, _)| Parameter::Displacement(i - 1).to_string()),
    );
    names.extend(columns(plan).map(|(p, _)| p.to_string()));
    names.extend(
        [
            "tip_x",
            "tip_y",
            "tip_z",
            "bending_angle_deg",
            "iterations",
            "load_steps",
            "solve_time",
            "intervals",
            "tip_error_estimate",
            "stability",
            "path",
            "event",
        ]
        .map(String::from),
    );
    names.extend(with_friction(robot).map(|i| format!("delivered_{}", i + 1)));
    CsvTable::new(names)
}

/// The `--param` inputs with a column of their own: all but the tensions, whose values
/// the `tension.I` columns hold (a tension-controlled tendon's solved tension is its input).
fn columns<'p, 'a>(plan: &'p Plan<'a>) -> impl Iterator<Item = &'p (Parameter, &'a Vec<f64>)> + 'p {
    plan.params.iter().filter(|(p, _)| !matches!(p, Parameter::Tension(_)))
}

/// The tendons of `robot` with friction (from 0): a sweep's inputs do not change which.
fn with_friction(robot: &Robot) -> impl Iterator<Item = usize> + '_ {
    robot
        .tendons
        .iter()
        .enumerate()
        .filter(|(_, t)| t.active_friction().is_some())
        .map(|(i, _)| i)
}

/// Appends the CSV row of step `k` (from 0) of a sweep of `robot` (the first step's: its
/// tendons with friction are every step's).
pub fn row(
    csv: &mut CsvTable,
    (args, plan, robot): (&SweepArgs, &Plan, &Robot),
    k: usize,
    solution: &Solution,
    event: &str,
) {
    let tip = solution.tip_position();
    let report = &solution.report;
    let mut fields = vec![(k + 1).to_string()];
    // The solved tensions: the inputs of tension-controlled tendons, the unknowns of
    // displacement-controlled ones.
    fields.extend(solution.tendons.iter().map(|t| number(t.tension)));
    fields.extend(
        args.displacement
            .iter()
            .map(|&(i, _)| number(solution.tendons[i - 1].displacement)),
    );
    // The swept value itself (a load scale is not a property of the scaled robot).
    fields.extend(columns(plan).map(|(_, v)| number(at(v, k))));
    fields.extend([
        number(tip.x),
        number(tip.y),
        number(tip.z),
        number(output::bending_angle(solution).to_degrees()),
        report.iterations.to_string(),
        report.load_steps.to_string(),
        number(report.timings.total.as_secs_f64()),
        report.intervals.to_string(),
        report.error_estimate.map_or(String::new(), |e| number(e.tip_position)),
        report.stability.verdict().to_string(),
        report.path.name().to_string(),
        event.to_string(),
    ]);
    fields.extend(with_friction(robot).map(|i| number(solution.tendons[i].delivered_tension)));
    csv.row(fields);
}
