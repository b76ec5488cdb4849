//! `tdcr sweep --history`: the sweep's steps solved as a load history with stick/slip
//! friction (`tdcr::analysis::history`): each step starts from the tendon state the last
//! one left. CSV out, one row per step in order, with the stick/slip zones; optionally the
//! hysteresis loop (the tip's displacement, the bending angle or a tip coordinate against
//! the swept input) as a picture.

use std::path::Path;
use tdcr::analysis::history::{HistoryStep, LoopAxis, directions, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::io::csv_table::CsvTable;
use tdcr::io::{number, output};
use tdcr::plot::{Chart, Segment, significant};

use crate::failure::{Failure, emit, message, note, picture_format, solver_failure, with_likely_causes, write_file};

/// What `--history` asks for: the ranges up and back down, or the swept input's values in
/// the order given.
#[derive(Clone, Debug, PartialEq)]
pub enum History {
    /// `up-down`: every range from its START to its STOP and back.
    UpDown,
    /// `V1,V2,...`: the values of the swept input, in order.
    Values(Vec<f64>),
}

/// Parses `--history`: `up-down` or a comma-separated list of finite numbers.
pub fn parse_history(text: &str) -> Result<History, String> {
    const GIVE: &str = "give `up-down` or the input's values in order, e.g. 0,2,4.91,2,0";
    if text == "up-down" {
        return Ok(History::UpDown);
    }
    if text.trim().is_empty() {
        return Err(format!("--history is empty: {GIVE}"));
    }
    let values = text
        .split(',')
        .enumerate()
        .map(|(k, v)| match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ if v.trim().is_empty() => Err(format!("value {} of --history {text} is empty: {GIVE}", k + 1)),
            _ => Err(format!("`{v}` in --history {text} is not a finite number: {GIVE}")),
        })
        .collect::<Result<Vec<f64>, String>>()?;
    Ok(History::Values(values))
}

/// Parses `--loop-y`: one of [`LoopAxis::NAMES`].
pub fn parse_loop_axis(text: &str) -> Result<LoopAxis, String> {
    LoopAxis::parse(text).map_err(|e| format!("--loop-y: {}", message(&e)))
}

/// The history's steps from the sweep's `ranges`: up and down, or the swept input (the
/// first that changes, else the only one given) at the listed values with every other input
/// at its first value.
pub fn steps(ranges: &Ranges, base: &tdcr::Robot, history: &History) -> Result<Ranges, Failure> {
    match history {
        History::UpDown => Ok(ranges.up_down()),
        History::Values(values) => {
            // With several inputs and none a range, which one the list is for is a guess.
            if ranges.swept().is_none() && ranges.inputs().len() > 1 {
                let given: Vec<String> = ranges.inputs().iter().map(|(input, _)| input.to_string()).collect();
                return Err(Failure::Input(format!(
                    "--history lists values for one input, and {} are given as single values: give the one the list \
                     is for as a range (e.g. --param {}=0:1:2, its range only marks it) and the others as single values",
                    given.join(", "),
                    given[given.len() - 1]
                )));
            }
            let swept = ranges.swept().map_or(0, |(i, _)| i);
            let input = ranges.inputs()[swept].0;
            if let (Input::Parameter(tdcr::Parameter::Tension(_)), Some(v)) = (input, values.iter().find(|v| **v < 0.0))
            {
                return Err(Failure::Input(format!(
                    "--history lists {input} = {} N, a negative tension: a tendon can only pull; give tensions >= 0",
                    tdcr::Readable(*v)
                )));
            }
            let held: Vec<String> = ranges
                .inputs()
                .iter()
                .enumerate()
                .filter(|(i, (_, v))| *i != swept && v.len() > 1)
                .map(|(_, (input, v))| format!("{input} at its first value {}", tdcr::Readable(v[0])))
                .collect();
            if !held.is_empty() {
                note(&format!(
                    "warning: --history V1,V2,... lists the values of {} alone; the other ranges are not swept: {} \
                     at every step (give each input its own history run, or `--history up-down` to run every range)",
                    ranges.inputs()[swept].0,
                    held.join(", ")
                ));
            }
            let inputs = ranges
                .inputs()
                .iter()
                .enumerate()
                .map(|(i, (input, v))| (*input, if i == swept { values.clone() } else { vec![v[0]] }))
                .collect();
            Ranges::new(base.clone(), inputs).map_err(|e| Failure::Input(format!("--history: {}", message(&e))))
        }
    }
}

/// Solves the history of `ranges` with `options`, writes the CSV (to `out` or standard
/// output; the steps before a failure too) and the loop's picture (to `plot`, with `y` on
/// its y axis).
pub fn run(
    name: &str,
    ranges: &Ranges,
    options: &tdcr::collocation::Options,
    out: Option<&Path>,
    (plot, y): (Option<&Path>, LoopAxis),
) -> Result<(), Failure> {
    if let Some(path) = plot {
        picture_format(path)?;
    }
    let result = history(ranges, options).map_err(|e| before_any_step(e, ranges))?;
    let swept = ranges.swept().map_or(0, |(i, _)| i);
    let (input, values) = &ranges.inputs()[swept];
    let count = ranges.robot(0.0).map_or(0, |r| r.tendons.len());
    let slipping: Vec<usize> = result
        .steps
        .first()
        .map(|s| s.zones.iter().map(|z| z.tendon).collect())
        .unwrap_or_default();
    let mut csv = header(count, *input, &slipping);
    let directions = directions(ranges);
    for (k, step) in result.steps.iter().enumerate() {
        row(
            &mut csv,
            k,
            directions[k],
            (*input, values[k.min(values.len() - 1)]),
            step,
        );
    }
    let text = csv.finish();
    warn_unstable(name, &result.steps);
    warn_missed(name, &result.steps);
    let stopped = result.failure.as_ref().map(|(k, _)| *k);
    let partial = stopped.map_or(String::new(), |k| format!(" ({})", holds(k, ranges.steps())));
    match out {
        Some(path) => {
            write_file(path, &text, "CSV")?;
            note(&format!("wrote {}{partial}", path.display()));
        }
        None => emit(&text)?,
    }
    if let Some(path) = plot
        && !result.steps.is_empty()
    {
        let chart = picture(
            name,
            (*input, values),
            &result.steps,
            y,
            stopped.map(|k| (k, ranges.steps())),
        );
        let bytes = match picture_format(path)? {
            tdcr::plot::Format::Svg => chart.to_svg().into_bytes(),
            tdcr::plot::Format::Png => {
                chart
                    .to_png(tdcr::plot::PNG_SCALE)
                    .map_err(|e| Failure::Other(format!("cannot draw the hysteresis loop: {e}")))?
                    .data
            }
        };
        write_file(path, bytes, "picture")?;
        note(&format!("wrote {}{partial}", path.display()));
    }
    match result.failure {
        Some((k, e)) => {
            let head = format!("history step {} of {}", k + 1, ranges.steps());
            let failure = match ranges.robot(k as f64) {
                Ok(robot) => with_likely_causes(solver_failure(e), &robot),
                Err(_) => solver_failure(e),
            };
            Err(failure.headed(&head, "the CSV holds only the steps before it"))
        }
        None => Ok(()),
    }
}

/// What the output of a history that stopped at step `k` (from 0) of `steps` holds: the
/// steps before it only.
fn holds(k: usize, steps: usize) -> String {
    match k {
        0 => format!("no step: the history stopped at step 1 of {steps}"),
        1 => format!("step 1 only: the history stopped at step 2 of {steps}"),
        _ => format!("steps 1 to {k} only: the history stopped at step {} of {steps}", k + 1),
    }
}

/// Says on standard error which steps of the history miss their tolerance (the estimate
/// above it: a stuck step whose split levels reached the interval cap, or 64 parts per
/// link): a plain solve would fail there, but a history goes on, since its later steps
/// start from this one; the CSV's `tolerance_met` column says which.
fn warn_missed(name: &str, steps: &[HistoryStep]) {
    let missed: Vec<String> = steps
        .iter()
        .enumerate()
        .filter(|(_, s)| s.solution.report.tolerance_met == Some(false))
        .map(|(k, _)| (k + 1).to_string())
        .collect();
    let which = match missed.len() {
        0 => return,
        1 => format!("step {} misses", missed[0]),
        _ => format!("steps {} miss", missed.join(", ")),
    };
    note(&format!(
        "warning: {name}: history {which} the tolerance (the estimate is above it: see the CSV's \
         `tip_error_estimate` and `tolerance_met`); raise `max_intervals` or loosen the tolerance"
    ));
}

/// Says on standard error which steps of the history are unstable (each run of them once,
/// with its first step's verdict): the CSV's `stability` column alone is easy to miss.
fn warn_unstable(name: &str, steps: &[HistoryStep]) {
    let unstable = |k: usize| {
        matches!(
            steps[k].solution.report.stability,
            tdcr::Stability::Unstable { .. } | tdcr::Stability::Growing { .. }
        )
    };
    let mut k = 0;
    while k < steps.len() {
        if !unstable(k) {
            k += 1;
            continue;
        }
        let first = k;
        while k + 1 < steps.len() && unstable(k + 1) {
            k += 1;
        }
        let which = if first == k {
            format!("step {}", first + 1)
        } else {
            format!("steps {} to {}", first + 1, k + 1)
        };
        note(&format!(
            "warning: {name}: history {which} of {}: the equilibrium is {}: a real robot would not stay in it \
             (`tdcr solve` on a step's inputs says more)",
            steps.len(),
            steps[first].solution.report.stability
        ));
        k += 1;
    }
}

/// A failure of the history before any step was solved: bad input (a usage error), or the
/// full-slip solve of the most loaded step, which chooses the history's mesh (a solver
/// failure, exit 3, with its diagnostics and the likely causes the steps' robots give).
fn before_any_step(e: tdcr::Error, ranges: &Ranges) -> Failure {
    let robots: Vec<tdcr::Robot> = (0..ranges.steps())
        .filter_map(|k| ranges.robot(k as f64).ok())
        .collect();
    let causes = tdcr::model::scales::likely_causes_of(&e, &robots);
    match solver_failure(e) {
        Failure::Input(t) => Failure::Input(format!("--history: {t}")),
        Failure::Limit(t) => Failure::Limit(format!("--history: {t}")),
        Failure::NotConverged(t) => Failure::NotConverged(tdcr::model::scales::with_likely_causes(
            &format!("--history: no step was solved: {HEAD_FAILED}: {t}"),
            &causes,
        )),
        Failure::Other(t) => Failure::Other(format!("--history: no step was solved: {HEAD_FAILED}: {t}")),
        Failure::BrokenPipe => Failure::BrokenPipe,
    }
}

/// What fails when a history fails before its first step, other than bad input.
const HEAD_FAILED: &str = "the full-slip solve of the most loaded step, which chooses the history's mesh, failed";

/// The CSV header: the step, its direction, the tensions (`tension.I`), the swept input
/// unless it is a tension (a `tension.I` column holds it already), the tip, and per tendon
/// with friction its delivered tension and zones.
fn header(count: usize, input: Input, slipping: &[usize]) -> CsvTable {
    let mut names = vec!["step".to_string(), "direction".to_string()];
    names.extend((0..count).map(|i| tdcr::Parameter::Tension(i).to_string()));
    if has_column(input) {
        names.push(input.to_string());
    }
    names.extend(["tip_x", "tip_y", "tip_z", "bending_angle_deg"].map(String::from));
    for &i in slipping {
        names.push(format!("delivered_{}", i + 1));
        names.push(format!("zones_{}", i + 1));
    }
    names.extend(
        [
            "iterations",
            "intervals",
            "tip_error_estimate",
            "tolerance_met",
            "stability",
        ]
        .map(String::from),
    );
    CsvTable::new(names)
}

/// Whether the swept `input` has a column of its own: all but a tension, which is its
/// tendon's `tension.I` column (a tension-controlled tendon's tension is its input).
fn has_column(input: Input) -> bool {
    !matches!(input, Input::Parameter(tdcr::Parameter::Tension(_)))
}

/// Appends the row of step `k` (from 0), with the value of the swept `input` at it.
fn row(csv: &mut CsvTable, k: usize, direction: &str, (input, value): (Input, f64), step: &HistoryStep) {
    let solution = &step.solution;
    let tip = solution.tip_position();
    let mut fields = vec![(k + 1).to_string(), direction.to_string()];
    fields.extend(solution.tendons.iter().map(|t| number(t.tension)));
    if has_column(input) {
        fields.push(number(value));
    }
    fields.extend([
        number(tip.x),
        number(tip.y),
        number(tip.z),
        number(output::bending_angle(solution).to_degrees()),
    ]);
    for zones in &step.zones {
        fields.push(number(solution.tendons[zones.tendon].delivered_tension));
        let list: Vec<String> = zones
            .zones
            .iter()
            .map(|z| format!("{} {}-{}", z.contact.name(), number(z.start), number(z.end)))
            .collect();
        fields.push(list.join(" "));
    }
    let report = &solution.report;
    fields.extend([
        report.iterations.to_string(),
        report.intervals.to_string(),
        report.error_estimate.map_or(String::new(), |e| number(e.tip_position)),
        report.tolerance_met.map_or(String::new(), |met| met.to_string()),
        report.stability.verdict().to_string(),
    ]);
    csv.row(fields);
}

/// The hysteresis loop: `y` (by default the tip's displacement from its place at the first
/// step, mm) against the swept input, rising steps in one colour, falling ones in another;
/// `stopped`, the step (from 0) where the history stopped and its number of steps, for a
/// history that stopped before its end (the title says so).
fn picture(
    name: &str,
    (input, values): (Input, &[f64]),
    steps: &[HistoryStep],
    y: LoopAxis,
    stopped: Option<(usize, usize)>,
) -> Chart {
    let (up, down) = ("#1f5fa8", "#e07b00");
    let value = |k: usize| values[k.min(values.len() - 1)];
    let ys = y.values(steps.iter().map(|s| &s.solution));
    let unit = input.unit();
    let mut chart = Chart {
        title: match stopped {
            None => format!("{name}: hysteresis over a load history of {} steps", steps.len()),
            Some((k, total)) => format!(
                "{name}: hysteresis over a load history that STOPPED at step {} of {total}",
                k + 1
            ),
        },
        subtitle: vec![format!(
            "each step from the tendon state the last left (stick/slip friction); {input} from {} to {} {unit}",
            significant(values.iter().copied().fold(f64::INFINITY, f64::min)),
            significant(values.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
        )],
        x_label: input.axis_label(),
        y_label: y.label().into(),
        ..Default::default()
    };
    for k in 1..steps.len() {
        let rising = value(k) >= value(k - 1);
        chart.segments.push(Segment {
            ends: [(value(k - 1), ys[k - 1]), (value(k), ys[k])],
            dashed: !rising,
            color: if rising { up } else { down }.into(),
        });
    }
    if chart.segments.iter().any(|s| !s.dashed) {
        chart
            .legend
            .push(("loading: the input rises".into(), up.into(), Some(false)));
    }
    if chart.segments.iter().any(|s| s.dashed) {
        chart
            .legend
            .push(("unloading: the input falls".into(), down.into(), Some(true)));
    }
    chart
}
