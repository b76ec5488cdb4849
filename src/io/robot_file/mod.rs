//! The robot file: each TOML table deserialized on its own with serde (so one bad table does
//! not hide the problems of the next, and unknown keys are rejected), every field checked
//! against its rule, then the [`Robot`] built and checked once more by [`Robot::validate`].
//!
//! This module reads the file and locates its problems (the public entry point [`parse`]);
//! the serde tables are in `tables`, the field rules in `check`, and the [`Robot`] and
//! solver settings are built in `build`.

mod build;
mod check;
mod tables;

use self::build::{build, library_problem, settings};
use self::check::Checker;
use self::tables::{BaseTable, LoadsTable, RodTable, SolverTable, TABLES, TendonTable};
use super::locate::{LazyLocator, Lines};
use super::printable;
use super::{FileError, Problem};
use crate::report::Method;
use crate::{Robot, collocation, shooting};
use serde::de::DeserializeOwned;
use toml::Spanned;
use toml::de::{DeTable, DeValue, ValueDeserializer};

/// Which solver to run and its options: the library defaults, changed by the file's
/// `[solver]` table.
#[derive(Clone, Debug)]
pub struct SolverSettings {
    /// The solver (`method`). Default collocation.
    pub method: Method,
    /// Collocation options (`intervals` (alias `nodes`), `tolerance`, `max_intervals` (alias
    /// `max_nodes`), `residual_tolerance`, `max_iterations`, `continuation`).
    pub collocation: collocation::Options,
    /// Shooting options (`residual_tolerance` -> `tolerance`, `max_iterations`,
    /// `integration_tolerance`).
    pub shooting: shooting::Options,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            method: Method::Collocation,
            collocation: collocation::Options::default(),
            shooting: shooting::Options::default(),
        }
    }
}

/// A robot file that passed every check.
#[derive(Clone, Debug)]
pub struct RobotFile {
    /// The robot, validated.
    pub robot: Robot,
    /// The solver settings of the `[solver]` table, defaults where not given.
    pub solver: SolverSettings,
}

/// Reads a robot file from its text; `file` is the name used in messages.
///
/// # Errors
/// A [`FileError`] listing every problem found: syntax errors (all of them), then for each
/// table a missing field, wrong type or unknown key (the first per table), then every value
/// that breaks its rule, each with line, column and field path. Only a file without such
/// problems is built into a [`Robot`] and checked by [`Robot::validate`].
pub fn parse(text: &str, file: &str) -> Result<RobotFile, FileError> {
    let fail = |mut problems: Vec<Problem>| {
        problems.sort_by_key(|p| p.position.map_or((0, 0), |q| (q.line, q.column)));
        // Keys come from the file: escape control characters so that a quoted key cannot
        // break the one-line-per-problem format or reach the terminal raw.
        for p in &mut problems {
            p.field = printable(&p.field);
            p.message = printable(&p.message);
        }
        FileError {
            file: file.to_string(),
            problems,
        }
    };
    if text.trim().is_empty() {
        return Err(fail(vec![whole_file(
            "is empty: a robot file needs at least a [rod] table (`tdcr example` prints one to start from)",
        )]));
    }
    let lines = Lines::new(text);
    let (root, errors) = DeTable::parse_recoverable(text);
    if !errors.is_empty() {
        let problems = errors
            .iter()
            .map(|e| Problem {
                position: e.span().map(|s| lines.position(s.start)),
                field: String::new(),
                message: format!("is not valid TOML: {}", e.message().trim()),
            })
            .collect();
        return Err(fail(problems));
    }
    let locator = LazyLocator::new(text);
    let mut reader = Reader {
        lines: &lines,
        locator: &locator,
        problems: Vec::new(),
    };
    let tables = reader.tables(root.into_inner());
    let mut problems = reader.problems;
    if !tables.rod_given {
        problems.push(whole_file(
            "has no [rod] table: give at least `length`, `outer_radius`, `youngs_modulus` and \
             `poisson_ratio` (or `shear_modulus`)",
        ));
    }
    // Check every table that could be read, so one bad table does not hide the others.
    let mut check = Checker {
        locator: &locator,
        problems: Vec::new(),
    };
    let length = tables.rod.as_ref().map_or(f64::NAN, |r| r.length);
    if let Some(rod) = &tables.rod {
        check.rod(rod);
    }
    if let Some(base) = &tables.base {
        check.base(base);
    }
    if let Some(loads) = &tables.loads {
        check.loads(loads, length);
    }
    for (i, t) in tables.tendons.iter().enumerate() {
        if let Some(t) = t {
            check.tendon(i, t, length);
        }
    }
    if let Some(solver) = &tables.solver {
        check.solver(solver);
    }
    problems.extend(check.problems);
    let tendons: Option<Vec<TendonTable>> = tables.tendons.into_iter().collect();
    let (Some(rod), Some(tendons), true) = (tables.rod, tendons, problems.is_empty()) else {
        return Err(fail(problems));
    };
    let (base, loads, solver) = (
        tables.base.unwrap_or_default(),
        tables.loads.unwrap_or_default(),
        tables.solver.unwrap_or_default(),
    );
    let robot = build(&rod, &base, &loads, &tendons);
    if let Err(e) = robot.validate() {
        return Err(fail(vec![library_problem(
            locator.get(),
            &e,
            base.euler_xyz_deg.is_some(),
        )]));
    }
    Ok(RobotFile {
        robot,
        solver: settings(&solver),
    })
}

/// A problem of the whole file, at no line and no field.
fn whole_file(message: &str) -> Problem {
    Problem {
        position: None,
        field: String::new(),
        message: message.to_string(),
    }
}

/// The tables of a file, deserialized but not yet checked.
#[derive(Default)]
struct Tables {
    /// Whether the file has a `rod` key (read or not).
    rod_given: bool,
    rod: Option<RodTable>,
    base: Option<BaseTable>,
    loads: Option<LoadsTable>,
    /// One entry per [[tendon]], `None` where it could not be read.
    tendons: Vec<Option<TendonTable>>,
    solver: Option<SolverTable>,
}

/// Deserializes the tables of a file, each failure one problem at its place in `text`.
struct Reader<'a> {
    lines: &'a Lines<'a>,
    locator: &'a LazyLocator<'a>,
    problems: Vec<Problem>,
}

impl Reader<'_> {
    /// Every table of the file's `root` that could be read; unknown top-level keys are
    /// problems.
    fn tables(&mut self, root: DeTable<'_>) -> Tables {
        let mut tables = Tables::default();
        for (key, value) in root {
            let name = key.get_ref().to_string();
            match name.as_str() {
                "rod" => {
                    tables.rod_given = true;
                    tables.rod = self.table(&name, value);
                }
                "base" => tables.base = self.table(&name, value),
                "loads" => tables.loads = self.table(&name, value),
                "solver" => tables.solver = self.table(&name, value),
                "tendon" => match value.into_inner() {
                    DeValue::Array(items) if items.iter().all(|t| t.get_ref().is_table()) => {
                        for (i, item) in items.into_iter().enumerate() {
                            let t = self.table(&format!("tendon[{}]", i + 1), item);
                            tables.tendons.push(t);
                        }
                    }
                    _ => self.problems.push(Problem {
                        position: Some(self.lines.position(key.span().start)),
                        field: name,
                        message: "must be an array of tables: start each tendon with [[tendon]] \
                                  (double brackets)"
                            .into(),
                    }),
                },
                _ => {
                    let hint = match name.as_str() {
                        "tendons" => "; did you mean [[tendon]]?".to_string(),
                        "load" => "; did you mean [loads]?".to_string(),
                        _ => String::new(),
                    };
                    self.problems.push(Problem {
                        position: Some(self.lines.position(key.span().start)),
                        field: String::new(),
                        message: format!("unknown key `{name}` at the top level; the tables are {TABLES}{hint}"),
                    });
                }
            }
        }
        tables
    }

    /// Deserializes one table; a failure becomes a problem that names the table.
    fn table<T: DeserializeOwned>(&mut self, name: &str, value: Spanned<DeValue<'_>>) -> Option<T> {
        let span = value.span();
        match T::deserialize(ValueDeserializer::from(value)) {
            Ok(t) => Some(t),
            Err(e) => {
                let at = self.lines.position(e.span().unwrap_or(span).start);
                let raw = e.message().trim().replace('\n', " ");
                let message = raw
                    .replace("expected f64", "expected a number")
                    .replace("expected usize", "expected a whole number >= 0");
                // The key the error is at, if it belongs to this table.
                let key = self.locator.get().key_at(at).filter(|p| p.starts_with(name));
                let parent = |p: &str| p.rfind('.').map_or(name.to_string(), |i| p[..i].to_string());
                let shown = match name.strip_prefix("tendon[") {
                    Some(rest) => format!("[[tendon]] #{}", rest.trim_end_matches(']')),
                    None => format!("[{name}]"),
                };
                // Missing and unknown fields are reported at their table (the key's value
                // when that is a table, else the key's parent): name it.
                let table = match &key {
                    Some(k) if self.locator.get().is_table(k) => k.clone(),
                    Some(k) => parent(k),
                    None => name.to_string(),
                };
                let (field, message) = if let Some(missing) = missing_field(&message) {
                    (
                        format!("{table}.{missing}"),
                        format!("is required but missing in {shown}"),
                    )
                } else if message.starts_with("unknown field")
                    || message.starts_with("unknown variant") && key.is_none()
                {
                    (table, format!("in {shown}: {message}"))
                } else {
                    (
                        key.unwrap_or_else(|| name.to_string()),
                        format!("in {shown}: {message}"),
                    )
                };
                self.problems.push(Problem {
                    position: Some(at),
                    field,
                    message,
                });
                None
            }
        }
    }
}

/// The field name of serde's "missing field `x`" message.
fn missing_field(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.split('`').next()
}
