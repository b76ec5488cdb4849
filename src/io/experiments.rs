//! The experiments CSV of `tdcr calibrate` (docs/calibration.md): one calibration
//! [`Measurement`] per row, tensions, tip force and measured tip in SI units; written
//! exactly by [`to_csv`], read with every problem reported by line, column and name by
//! [`parse_csv`]; both through the `csv` crate.

use super::Position;
use super::csv_table::CsvTable;
use super::{FileError, Problem, printable};
use crate::fit::calibration::Measurement;
use crate::model::tendon::Motion;
use nalgebra::Vector3;

/// The tip-force and measured-tip columns of the experiments CSV, after the tensions: the
/// inputs named as the parameters they set (`tip_force.x`, [`crate::Parameter`]), the
/// measurement as the tip of the output files (`tip_x`) is, with `measured_` for `tip_`.
pub const CSV_VECTOR_COLUMNS: [&str; 6] = [
    "tip_force.x",
    "tip_force.y",
    "tip_force.z",
    "measured_x",
    "measured_y",
    "measured_z",
];

/// The header of an experiments CSV for a robot with `tendons` tendons:
/// `tension.1,...,tension.k,tip_force.x,tip_force.y,tip_force.z,measured_x,measured_y,measured_z`.
/// [`parse_csv`] also reads the inputs' names of earlier versions, `tension_I` and
/// `tip_force_x` ([`current_name`]).
pub fn csv_header(tendons: usize) -> String {
    let mut names: Vec<String> = (0..tendons).map(|i| crate::Parameter::Tension(i).to_string()).collect();
    names.extend(CSV_VECTOR_COLUMNS.iter().map(|s| s.to_string()));
    names.join(",")
}

/// The column name `name` of an experiments CSV in the current spelling: `tension_I`,
/// `tip_force_x`, `tip_force_y` and `tip_force_z` (the names before the inputs took their
/// parameters' names) become `tension.I` and `tip_force.x` ...; every other name is itself.
pub fn current_name(name: &str) -> String {
    for head in ["tension_", "tip_force_"] {
        if let Some(tail) = name.strip_prefix(head)
            && !tail.is_empty()
        {
            return format!("{}.{tail}", &head[..head.len() - 1]);
        }
    }
    name.to_string()
}

/// The hint that follows a bad experiments CSV's `error` for a robot with `tendons`
/// tendons: the header it wants. When a problem is about the optional `motion` column, the
/// header shown ends in it (the file uses it); else the header without it, and that a
/// `motion` column may follow.
pub fn header_hint(tendons: usize, error: &FileError) -> String {
    let head = format!("the header for this robot ({tendons} tendon(s)) is");
    let what = "pull or release per row, for tendons with friction";
    if error.problems.iter().any(|p| p.field == MOTION_COLUMN) {
        format!(
            "{head} {},{MOTION_COLUMN} (`{MOTION_COLUMN}`: {what}; empty, or left out, for none)",
            csv_header(tendons)
        )
    } else {
        format!(
            "{head} {}, with an optional `{MOTION_COLUMN}` column ({what})",
            csv_header(tendons)
        )
    }
}

/// The experiments as CSV (docs/calibration.md): the header of [`csv_header`], then one row
/// per experiment in SI units (N, N, m), numbers written by [`crate::io::number`] to
/// round-trip exactly.
///
/// Precondition: every experiment has the same number of tensions.
pub fn to_csv(experiments: &[Measurement]) -> String {
    let k = experiments.first().map_or(0, |e| e.tensions.len());
    // The motion column only when an experiment gives a motion (docs/calibration.md).
    let motions = experiments.iter().any(|e| e.motion.is_some());
    let mut header: Vec<String> = csv_header(k).split(',').map(str::to_string).collect();
    if motions {
        header.push(MOTION_COLUMN.into());
    }
    let mut table = CsvTable::new(header);
    for e in experiments {
        let mut row: Vec<String> = e
            .tensions
            .iter()
            .chain(e.tip_force.iter())
            .chain(e.measured_tip.iter())
            .map(|&x| crate::io::number(x))
            .collect();
        if motions {
            row.push(e.motion.map_or("", Motion::name).into());
        }
        table.row(row);
    }
    table.finish()
}

/// The optional column of an experiments CSV giving the motion of the tendons with friction
/// in each experiment: `pull` (a loading step), `release` (an unloading step) or empty (the
/// robot's own motion).
pub const MOTION_COLUMN: &str = "motion";

/// At most this many problems are listed for one CSV file: enough to see a pattern.
const MAX_CSV_PROBLEMS: usize = 20;

/// Reads an experiments CSV (docs/calibration.md) for a robot with `tendons` tendons.
///
/// The first line that is neither blank nor a `#` comment is the header: the column names
/// of [`csv_header`] in any order, each once (`tension_I` and `tip_force_x` ... are read as
/// `tension.I` and `tip_force.x` ..., the spelling of earlier versions). Every following non-blank, non-comment line is
/// one experiment with a finite number in every column (tensions >= 0). `file` names the
/// source in messages.
///
/// # Errors
/// A [`FileError`] listing every problem (up to 20) with its line and column (characters,
/// from 1) and the column name: unknown, repeated or missing columns, a row with the wrong
/// number of fields, a value that is not a finite number, a negative tension, no rows.
///
/// # Examples
/// ```
/// let text = "tension.1,tip_force.x,tip_force.y,tip_force.z,measured_x,measured_y,measured_z\n\
///             2.94,0,0,-0.098,0.15,0,-0.16\n";
/// let experiments = tdcr::io::experiments::parse_csv(text, "data.csv", 1).unwrap();
/// assert_eq!(experiments[0].tensions, vec![2.94]);
/// let bad = tdcr::io::experiments::parse_csv(&text.replace("0.15", "x"), "data.csv", 1).unwrap_err();
/// assert!(bad.to_string().starts_with("data.csv:2:17: `measured_x` (column 5)"), "{bad}");
/// ```
pub fn parse_csv(text: &str, file: &str, tendons: usize) -> Result<Vec<Measurement>, FileError> {
    let mut problems = Vec::new();
    let at = |line: usize, column: usize| Some(Position { line, column });
    let mut lines = records(text).into_iter();
    let expected: Vec<String> = csv_header(tendons).split(',').map(str::to_string).collect();
    let Some((header_line, header)) = lines.next() else {
        return Err(FileError {
            file: file.to_string(),
            problems: vec![Problem {
                position: None,
                field: String::new(),
                message: format!("has no header line; start with `{}`", csv_header(tendons)),
            }],
        });
    };
    // Column index -> which value it holds (index into `expected`).
    let mut slots: Vec<Option<usize>> = Vec::new();
    // The column index of the optional motion column.
    let mut motion_column = None;
    // Each column's name as the file spells it, for the messages.
    let mut written: Vec<String> = Vec::new();
    for (column, given) in fields(&header) {
        let given = printable(given.trim());
        let name = current_name(&given);
        let name = name.as_str();
        let slot = expected.iter().position(|e| e == name);
        if name == MOTION_COLUMN {
            if motion_column.is_some() {
                problems.push(Problem {
                    position: at(header_line, column),
                    field: name.into(),
                    message: "is repeated; give each column once".into(),
                });
            }
            motion_column = Some(slots.len());
        } else if slot.is_some() && slots.contains(&slot) {
            problems.push(Problem {
                position: at(header_line, column),
                field: given.clone(),
                message: "is repeated; give each column once".into(),
            });
        } else if slot.is_none() {
            let hint = match name.strip_prefix("tension.").and_then(|i| i.parse::<usize>().ok()) {
                Some(i) => format!("the robot has {tendons} tendon(s), so tension.{i} is not one of its columns"),
                None => format!(
                    "the columns are {} (and an optional {MOTION_COLUMN})",
                    expected.join(",")
                ),
            };
            problems.push(Problem {
                position: at(header_line, column),
                field: given.clone(),
                message: format!("is not a column of the experiments file; {hint}"),
            });
        }
        slots.push(slot);
        written.push(given);
    }
    for (i, name) in expected.iter().enumerate() {
        if !slots.contains(&Some(i)) {
            problems.push(Problem {
                position: at(header_line, 1),
                field: name.clone(),
                message: format!(
                    "is missing from the header; the robot has {tendons} tendon(s), so the header is `{}`",
                    expected.join(",")
                ),
            });
        }
    }
    if !problems.is_empty() {
        return Err(FileError {
            file: file.to_string(),
            problems,
        });
    }
    let mut experiments = Vec::new();
    for (line, row) in lines {
        if problems.len() >= MAX_CSV_PROBLEMS {
            break;
        }
        let cells = fields(&row);
        if cells.len() != slots.len() {
            problems.push(Problem {
                position: at(line, 1),
                field: String::new(),
                message: format!("has {} fields, but the header has {} columns", cells.len(), slots.len()),
            });
            continue;
        }
        let mut values = vec![0.0; expected.len()];
        let mut ok = true;
        let mut motion = None;
        if let Some((column, cell)) = motion_column.map(|c| &cells[c]) {
            match cell.trim() {
                "" => {}
                name => match Motion::from_name(name) {
                    Some(m) => motion = Some(m),
                    None => {
                        ok = false;
                        problems.push(Problem {
                            position: at(line, *column),
                            field: MOTION_COLUMN.into(),
                            message: format!("is `{}`; give {} or leave it empty", printable(name), Motion::CHOICES),
                        });
                    }
                },
            }
        }
        for (index, ((column, cell), slot)) in cells.into_iter().zip(&slots).enumerate() {
            let Some(slot) = *slot else { continue };
            let name = &written[index];
            let cell = cell.trim();
            let problem = match cell.parse::<f64>() {
                Ok(x) if !x.is_finite() => Some(format!("is `{cell}`, not a finite number")),
                Ok(x) if slot < tendons && x < 0.0 => Some(format!(
                    "is {} N: a tendon can only pull (tension >= 0)",
                    crate::Readable(x)
                )),
                Ok(x) => {
                    values[slot] = x;
                    None
                }
                Err(_) => Some(format!(
                    "is `{}`, not a number (SI units: N and m, e.g. 2.94 or -1.5e-3)",
                    printable(cell)
                )),
            };
            if let Some(message) = problem {
                ok = false;
                problems.push(Problem {
                    position: at(line, column),
                    field: name.clone(),
                    message: format!("(column {}) {message}", index + 1),
                });
            }
        }
        if ok {
            let v = |i: usize| Vector3::new(values[tendons + i], values[tendons + i + 1], values[tendons + i + 2]);
            experiments.push(Measurement {
                tensions: values[..tendons].to_vec(),
                tip_force: v(0),
                measured_tip: v(3),
                motion,
            });
        }
    }
    if problems.is_empty() && experiments.is_empty() {
        problems.push(Problem {
            position: None,
            field: String::new(),
            message: "has a header but no experiments; add one row per experiment".into(),
        });
    }
    if problems.is_empty() {
        Ok(experiments)
    } else {
        if problems.len() >= MAX_CSV_PROBLEMS {
            problems.push(Problem {
                position: None,
                field: String::new(),
                message: format!("stopped after {MAX_CSV_PROBLEMS} problems"),
            });
        }
        Err(FileError {
            file: file.to_string(),
            problems,
        })
    }
}

/// The records of a CSV text, read by the `csv` crate (quoted fields, CRLF line ends),
/// with the line each starts on (from 1); blank records and `#` comment lines skipped. The
/// comment lines are blanked before the reader sees them, so a quote in a comment cannot
/// open a field that swallows the rows after it. (Text in memory has no read errors: the
/// reader fails only on invalid UTF-8, which a `&str` cannot hold.)
fn records(text: &str) -> Vec<(usize, csv::StringRecord)> {
    let uncommented: String = text
        .split_inclusive('\n')
        .map(|line| {
            // A space, not nothing: the reader skips empty lines without counting them, and
            // a record of one blank field keeps every later record's line number right.
            let text = line.trim_start();
            if text.is_empty() || text.starts_with('#') {
                if line.ends_with('\n') { " \n" } else { " " }
            } else {
                line
            }
        })
        .collect();
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(uncommented.as_bytes())
        .into_records()
        .map_while(Result::ok)
        .map(|r| (r.position().map_or(1, |p| p.line() as usize), r))
        .filter(|(_, r)| r.iter().any(|f| !f.trim().is_empty()))
        .collect()
}

/// The fields of a record with the character column (from 1) where each starts (exact for
/// unquoted fields, which the experiments CSV has).
fn fields(record: &csv::StringRecord) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut column = 1;
    for field in record {
        out.push((column, field));
        column += field.chars().count() + 1;
    }
    out
}
