//! Parameter tables, the input of `tdcr batch`: a CSV file whose header names
//! [`Parameter`]s (`tension.1`, `tip_force.z`, ...; the one vocabulary of
//! [`crate::model::parameter`]) with one row of numbers per robot, or JSON lines, one object
//! of parameters per line (a row sets only the parameters it names). Every problem says its
//! file, line and column.
//!
//! ```
//! let table = tdcr::io::parameters::read("rows.csv", "tension.1,tip_force.z\n2.94,-0.1\n").unwrap();
//! let robot = table.robot(&table.row(0), &tdcr::cases::prototype()).unwrap();
//! assert_eq!((robot.tendons[0].tension(), robot.loads.tip_force.z), (2.94, -0.1));
//! ```

use super::Position;
use super::{FileError, Problem};
use crate::model::parameter::{NAMES, Parameter};
use crate::{Result, Robot};

/// One row of a parameter table.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Its number among the rows, from 0.
    pub index: usize,
    /// The line of the file it came from, from 1.
    pub line: usize,
    /// The value of each of the table's parameters, in its order (`None`: a JSON line that
    /// does not name it).
    pub values: Vec<Option<f64>>,
}

/// A parameter table: the parameters in column order and the rows, kept compact (8 bytes
/// per value and row, so a table of 10^6 rows of four parameters holds 40 MB); [`Table::row`]
/// gives a row as a [`Row`].
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The parameters, each once.
    pub parameters: Vec<Parameter>,
    /// The values, row after row, one per parameter; NaN where a JSON line does not name
    /// the parameter (a value read is always finite).
    values: Vec<f64>,
    /// The line of each row in the file, from 1.
    lines: Vec<usize>,
}

impl Table {
    /// The number of rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// Row `index` (from 0, in file order).
    ///
    /// # Panics
    /// If `index >= self.len()`.
    pub fn row(&self, index: usize) -> Row {
        let n = self.parameters.len();
        Row {
            index,
            line: self.lines[index],
            values: self.values[index * n..(index + 1) * n]
                .iter()
                .map(|&x| (!x.is_nan()).then_some(x))
                .collect(),
        }
    }

    /// The rows, in file order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = Row> + '_ {
        (0..self.len()).map(|i| self.row(i))
    }

    /// Appends a row (`values`, one per parameter) read at `line`.
    fn push(&mut self, line: usize, values: impl IntoIterator<Item = Option<f64>>) {
        self.values.extend(values.into_iter().map(|x| x.unwrap_or(f64::NAN)));
        self.lines.push(line);
    }

    /// `base` with `row`'s values set ([`Parameter::apply_all`]: `load_scale` last) and
    /// validated.
    ///
    /// # Errors
    /// As [`Parameter::apply`] and [`Robot::validate`].
    pub fn robot(&self, row: &Row, base: &Robot) -> Result<Robot> {
        let robot = self.robot_unchecked(row, base)?;
        robot.validate()?;
        Ok(robot)
    }

    /// [`Table::robot`] without [`Robot::validate`], for a row whose robot `Table::robot`
    /// has already accepted (`tdcr batch` checks every row before its first solve, and a
    /// solve validates its robot again).
    ///
    /// # Errors
    /// As [`Parameter::apply`].
    pub fn robot_unchecked(&self, row: &Row, base: &Robot) -> Result<Robot> {
        let mut robot = base.clone();
        let values = self.parameters.iter().zip(&row.values);
        Parameter::apply_all(&mut robot, values.filter_map(|(&p, x)| x.map(|x| (p, x))))?;
        Ok(robot)
    }
}

/// Reads the table `text` of the file `file`: JSON lines when its name ends in `.jsonl` or
/// `.ndjson`, else CSV.
///
/// # Errors
/// A [`FileError`] with the first problem's line and column (from 1): an unknown or repeated
/// parameter, a row with the wrong number of fields, a value that is not a finite number, a
/// negative tension or a modulus <= 0.
pub fn read(file: &str, text: &str) -> Result<Table, FileError> {
    if file.ends_with(".jsonl") || file.ends_with(".ndjson") {
        read_jsonl(file, text)
    } else {
        read_csv(file, text)
    }
}

/// A problem at `line:column` of `file`.
fn at(file: &str, line: usize, column: usize, message: impl Into<String>) -> FileError {
    FileError {
        file: file.to_string(),
        problems: vec![Problem {
            position: Some(Position { line, column }),
            field: String::new(),
            message: message.into(),
        }],
    }
}

/// Checks a value's own range (the rest is the robot's validation per row).
fn check_value(parameter: &Parameter, value: f64) -> std::result::Result<(), String> {
    if !value.is_finite() {
        return Err(format!("`{parameter}` is {value}, but every number must be finite"));
    }
    match parameter {
        Parameter::Tension(_) if value < 0.0 => Err(format!(
            "`{parameter}` is {value} N, but a tendon can only pull: must be >= 0"
        )),
        Parameter::YoungsModulus if value <= 0.0 => Err(format!("`{parameter}` is {value} Pa, but must be positive")),
        _ => Ok(()),
    }
}

/// Reads a CSV table (the `csv` crate): a header of parameter names, then one row of
/// numbers per line (blank lines skipped; fields may have spaces around them).
///
/// # Errors
/// As [`read`].
pub fn read_csv(file: &str, text: &str) -> Result<Table, FileError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes());
    // The line (from 1) of the record at a byte offset: the reader's own line count skips
    // blank lines, and its offset can be at the line ends before the record. The newlines
    // are found once, so a table of N rows costs N log N here, not N^2.
    let bytes = text.as_bytes();
    let newlines: Vec<usize> = (0..bytes.len()).filter(|&i| bytes[i] == b'\n').collect();
    let line_at = |byte: u64| {
        let mut start = (byte as usize).min(bytes.len());
        while bytes.get(start).is_some_and(|c| matches!(c, b'\r' | b'\n')) {
            start += 1;
        }
        1 + newlines.partition_point(|&i| i < start)
    };
    // Each record with its line and the column (characters, from 1) where each field's text
    // starts, counted over the unquoted fields and their commas.
    let mut records = reader.records().filter_map(|record| {
        let record = match record {
            Ok(r) => r,
            Err(e) => {
                let line = e.position().map_or(1, |p| line_at(p.byte()));
                return Some(Err(at(file, line, 1, format!("is not CSV: {e}"))));
            }
        };
        let line = record.position().map_or(1, |p| line_at(p.byte()));
        if record.iter().all(|f| f.trim().is_empty()) {
            return None;
        }
        let mut column = 1;
        let fields: Vec<(usize, String)> = record
            .iter()
            .map(|f| {
                let start = column + f.chars().count() - f.trim_start().chars().count();
                column += f.chars().count() + 1;
                (start, f.trim().to_string())
            })
            .collect();
        Some(Ok((line, fields)))
    });
    let Some(header) = records.next() else {
        return Err(FileError {
            file: file.to_string(),
            problems: vec![Problem {
                position: None,
                field: String::new(),
                message: format!("is empty: the first line must name the parameters ({NAMES})"),
            }],
        });
    };
    let (header_line, header) = header?;
    let mut parameters = Vec::new();
    for (column, name) in header {
        let p: Parameter = name.parse().map_err(|e: String| at(file, header_line, column, e))?;
        if parameters.contains(&p) {
            return Err(at(
                file,
                header_line,
                column,
                format!("parameter `{name}` is given twice"),
            ));
        }
        parameters.push(p);
    }
    let mut table = Table {
        parameters,
        values: Vec::new(),
        lines: Vec::new(),
    };
    let parameters = table.parameters.clone();
    for record in records {
        let (line, cells) = record?;
        if cells.len() != parameters.len() {
            return Err(at(
                file,
                line,
                1,
                format!(
                    "has {} fields, but the header names {} parameters",
                    cells.len(),
                    parameters.len()
                ),
            ));
        }
        let mut values = Vec::with_capacity(cells.len());
        for ((column, cell), p) in cells.iter().zip(&parameters) {
            let x: f64 = cell
                .parse()
                .map_err(|_| at(file, line, *column, format!("`{p}` value `{cell}` is not a number")))?;
            check_value(p, x).map_err(|e| at(file, line, *column, e))?;
            values.push(Some(x));
        }
        table.push(line, values);
    }
    Ok(table)
}

/// Reads JSON lines: one object `{"tension.1": 2.0, ...}` per non-blank line; a row sets
/// only the parameters it names.
///
/// # Errors
/// As [`read`].
pub fn read_jsonl(file: &str, text: &str) -> Result<Table, FileError> {
    let mut parameters: Vec<Parameter> = Vec::new();
    let mut parsed = Vec::new();
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let object: serde_json::Map<String, serde_json::Value> = serde_json::from_str(line).map_err(|e| {
            at(
                file,
                i + 1,
                e.column().max(1),
                format!("is not a JSON object of parameters: {e}"),
            )
        })?;
        let column_of = |key: &str| {
            line.find(&format!("\"{key}\""))
                .map_or(1, |c| line[..c].chars().count() + 1)
        };
        let mut row = Vec::new();
        for (key, value) in &object {
            let p: Parameter = key.parse().map_err(|e: String| at(file, i + 1, column_of(key), e))?;
            let x = value
                .as_f64()
                .ok_or_else(|| at(file, i + 1, column_of(key), format!("`{key}` is {value}, not a number")))?;
            check_value(&p, x).map_err(|e| at(file, i + 1, column_of(key), e))?;
            if !parameters.contains(&p) {
                parameters.push(p);
            }
            row.push((p, x));
        }
        parsed.push((i + 1, row));
    }
    let mut table = Table {
        parameters,
        values: Vec::new(),
        lines: Vec::new(),
    };
    for (line, row) in parsed {
        let values: Vec<Option<f64>> = (table.parameters.iter())
            .map(|p| row.iter().find(|(q, _)| q == p).map(|(_, x)| *x))
            .collect();
        table.push(line, values);
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_columns_are_counted_from_1_at_the_field() {
        let e = read_csv("t.csv", "tension.1, mass\n").unwrap_err().to_string();
        assert!(e.starts_with("t.csv:1:12: unknown parameter `mass`"), "{e}");
        let e = read_csv("t.csv", "tension.1,tension.2\n1,x\n").unwrap_err().to_string();
        assert!(e.starts_with("t.csv:2:3: `tension.2` value `x`"), "{e}");
        let e = read_csv("t.csv", "tension.1\n\n  \n-1\n").unwrap_err().to_string();
        assert!(e.starts_with("t.csv:4:1: `tension.1` is -1 N"), "{e}");
    }

    /// `load_scale` scales the tension the row sets in either column order (1 N from 2 N at
    /// half scale; exact in binary).
    #[test]
    fn load_scale_applies_last_in_any_column_order() {
        let base = crate::cases::case_s();
        for text in ["tension.1,load_scale\n2,0.5\n", "load_scale,tension.1\n0.5,2\n"] {
            let table = read_csv("t.csv", text).unwrap();
            let robot = table.robot(&table.row(0), &base).unwrap();
            assert_eq!(robot.tendons[0].tension(), 1.0, "{text}");
            assert_eq!(robot.tendons[1].tension(), base.tendons[1].tension() * 0.5, "{text}");
        }
    }

    #[test]
    fn csv_and_json_lines_give_the_same_table() {
        let csv = read("t.csv", "tension.2 , tip_moment.x\r\n\r\n1.5, -0.01\r\n2,0\r\n").unwrap();
        let json = read(
            "t.jsonl",
            "{\"tension.2\": 1.5, \"tip_moment.x\": -0.01}\n\n{\"tension.2\": 2, \"tip_moment.x\": 0}\n",
        )
        .unwrap();
        assert_eq!(csv.parameters, json.parameters);
        assert_eq!(csv.parameters, [Parameter::Tension(1), Parameter::TipMoment(0)]);
        let values = |t: &Table| t.rows().map(|r| r.values).collect::<Vec<_>>();
        assert_eq!(values(&csv), values(&json));
        assert_eq!(csv.row(1).line, 4);
    }

    /// A JSON line that does not name a parameter leaves it unset in its row (stored
    /// compactly as NaN, given back as `None`), and the robot keeps the base's value.
    #[test]
    fn parameters_a_json_line_does_not_name_stay_unset() {
        let table = read("t.jsonl", "{\"tension.1\": 1.5}\n{\"tip_force.z\": -0.1}\n").unwrap();
        assert_eq!(table.len(), 2);
        assert_eq!(table.row(0).values, [Some(1.5), None]);
        assert_eq!(table.row(1).values, [None, Some(-0.1)]);
        let base = crate::cases::case_s();
        let robot = table.robot(&table.row(1), &base).unwrap();
        assert_eq!(robot.tendons[0].tension(), base.tendons[0].tension());
        assert_eq!(robot.loads.tip_force.z, -0.1);
    }
}
