//! The robot file: each TOML table deserialized on its own with serde (so one bad table does
//! not hide the problems of the next, and unknown keys are rejected), every field checked
//! against its rule, then the [`Robot`] built and checked once more by [`Robot::validate`].
//!
//! This module reads the file and locates its problems (the public entry point [`parse`]);
//! the serde tables are in `tables`, the field rules in `check`, and the [`Robot`] and
//! solver settings are built in `build`.

mod build;
pub use build::file_field;
mod words;
pub use words::{Front, user_message};
mod check;
mod segments;
mod tables;
mod write;

use self::build::{build, disks, library_problem, model, settings, uniform_rod};
use self::check::Checker;
use self::tables::{
    BaseTable, DisksTable, LoadsTable, ModelTable, RodTable, SegmentTable, SolverTable, TABLES, TendonTable,
};
use super::locate::{LazyLocator, Lines};
use super::printable;
use super::{FileError, Problem};
use crate::report::Method;
use crate::{Disks, Robot, collocation, shooting};
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
    /// The spacer disks of the `[disks]` table, if any: their weights are already among
    /// the robot's point loads (the last ones, [`Disks::point_loads`]); kept to draw them
    /// and to write the table back.
    pub disks: Option<Disks>,
}

impl RobotFile {
    /// What the file gives that has no effect on the solve, one message each (`tdcr check`
    /// and `tdcr solve` print them as warnings; they are not errors): a `free_length` on a
    /// tendon without `stiffness`, and a `motion = "release"` on a tendon without friction.
    /// An inextensible tendon's free length, between the base and the actuator, is there but
    /// does not stretch, so it changes nothing; the free length counts only in the stretch of
    /// an elastic tendon (docs/actuation.md). The motion says which way friction acts, so
    /// without friction it changes nothing (docs/friction.md).
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = Vec::new();
        for (i, t) in self.robot.tendons.iter().enumerate() {
            if t.stiffness.is_none() && t.free_length != 0.0 {
                warnings.push(format!(
                    "`tendon[{}].free_length` is {} m, but the tendon has no `stiffness`, so it is \
                     inextensible and its free length has no effect (only an elastic tendon's free length \
                     stretches); give `stiffness` (E_t A_t, N) to make it elastic, or remove `free_length`",
                    i + 1,
                    crate::Readable(t.free_length)
                ));
            }
            if let Some(f) = t.friction
                && f.coefficient == 0.0
                && f.motion == crate::Motion::Release
            {
                warnings.push(format!(
                    "`tendon[{}].motion` is \"release\", but the tendon has no friction, so the motion has no \
                     effect (it says which way friction acts); give `friction` (e.g. 0.1) to model it, or remove \
                     `motion`",
                    i + 1
                ));
            }
        }
        warnings
    }
}

/// Reads a robot file from its text; `file` is the name used in messages.
///
/// # Errors
/// A [`FileError`] listing every problem found: syntax errors (all of them), then for each
/// table every missing required field and the first wrong type or unknown key (with a
/// did-you-mean for a likely misspelling), then every value
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
    let segmented = !tables.segments.is_empty();
    if !tables.rod_given && !segmented {
        problems.push(whole_file(
            "has no [rod] table: give at least `length`, `outer_radius`, `youngs_modulus` and \
             `poisson_ratio` (or `shear_modulus`), or give the backbone as [[segment]] tables",
        ));
    } else if tables.rod_given && segmented {
        problems.push(whole_file(segments::BOTH));
    }
    // Check every table that could be read, so one bad table does not hide the others.
    let mut check = Checker {
        locator: &locator,
        problems: Vec::new(),
    };
    let length = match &tables.rod {
        Some(r) => r.length,
        None if segmented => segments::length(&tables.segments),
        None => f64::NAN,
    };
    if let Some(rod) = &tables.rod {
        check.rod(rod);
    }
    for (i, g) in tables.segments.iter().enumerate() {
        if let Some(g) = g {
            check.segment(i, g);
        }
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
            check.end_segment(i, t, tables.segments.len());
        }
    }
    if let Some(solver) = &tables.solver {
        check.solver(solver);
    }
    if let Some(d) = &tables.disks {
        check.disks(d, length);
    }
    problems.extend(check.problems);
    let tendons: Option<Vec<TendonTable>> = tables.tendons.into_iter().collect();
    let segment_tables: Option<Vec<SegmentTable>> = tables.segments.into_iter().collect();
    let backbone = match (&tables.rod, segment_tables) {
        (Some(rod), _) => Some(uniform_rod(rod)),
        (None, Some(g)) if !g.is_empty() => Some(segments::rod(&g)),
        _ => None,
    };
    let (Some(backbone), Some(tendons), true) = (backbone, tendons, problems.is_empty()) else {
        return Err(fail(problems));
    };
    let (base, loads, solver) = (
        tables.base.unwrap_or_default(),
        tables.loads.unwrap_or_default(),
        tables.solver.unwrap_or_default(),
    );
    let ends = segments::ends(&backbone);
    let mut robot = build(backbone, &ends, &base, &loads, &tendons);
    model(&mut robot, &tables.model.unwrap_or_default());
    let disks = tables.disks.map(|d| disks(&d, robot.length()));
    if let Some(d) = &disks {
        robot.loads.point.extend(d.point_loads());
    }
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
        disks,
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
    /// One entry per [[segment]], `None` where it could not be read.
    segments: Vec<Option<SegmentTable>>,
    solver: Option<SolverTable>,
    model: Option<ModelTable>,
    disks: Option<DisksTable>,
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
                "model" => tables.model = self.table(&name, value),
                "disks" => tables.disks = self.table(&name, value),
                "tendon" => tables.tendons = self.array(&name, key.span().start, value),
                "segment" => tables.segments = self.array(&name, key.span().start, value),
                _ => {
                    let hint = match name.as_str() {
                        "tendons" => "; did you mean [[tendon]]?".to_string(),
                        "segments" => "; did you mean [[segment]]?".to_string(),
                        "load" => "; did you mean [loads]?".to_string(),
                        _ => match closest(
                            &name,
                            ["rod", "base", "loads", "disks", "model", "solver", "tendon", "segment"].into_iter(),
                        ) {
                            Some(array @ ("tendon" | "segment")) => format!("; did you mean [[{array}]]?"),
                            Some(table) => format!("; did you mean [{table}]?"),
                            None => String::new(),
                        },
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

    /// The tables of the array of tables `name` (`tendon`, `segment`) whose key starts at
    /// byte `at`, each `None` where it could not be read; a value that is not an array of
    /// tables is one problem.
    fn array<T: DeserializeOwned>(&mut self, name: &str, at: usize, value: Spanned<DeValue<'_>>) -> Vec<Option<T>> {
        match value.into_inner() {
            DeValue::Array(items) if items.iter().all(|t| t.get_ref().is_table()) => items
                .into_iter()
                .enumerate()
                .map(|(i, item)| self.table(&format!("{name}[{}]", i + 1), item))
                .collect(),
            _ => {
                self.problems.push(Problem {
                    position: Some(self.lines.position(at)),
                    field: name.to_string(),
                    message: format!("must be an array of tables: start each {name} with [[{name}]] (double brackets)"),
                });
                Vec::new()
            }
        }
    }

    /// Reports every required field missing from table `name` (serde reports only the
    /// first); returns their paths.
    fn missing(&mut self, name: &str, value: &Spanned<DeValue<'_>>) -> Vec<String> {
        let mut found = Vec::new();
        let shown = shown_table(name);
        for (path, at, table) in required_fields(name, value) {
            let position = self.lines.position(at);
            self.problems.push(Problem {
                position: Some(position),
                field: path.clone(),
                message: format!("is required but missing in {shown}{}", near_miss(&path, table)),
            });
            found.push(path);
        }
        // A tendon is driven by `tension` or by `displacement`: one message for neither
        // (the check of the values reports both).
        if let Some(present) = keys(value).filter(|_| name.starts_with("tendon["))
            && !present.contains(&"tension")
            && !present.contains(&"displacement")
        {
            let hint = ["tension", "displacement"]
                .iter()
                .find_map(|f| closest(f, present.iter().copied()).map(|key| (f, key)))
                .map_or(String::new(), |(f, key)| {
                    format!(" (the table has `{key}`: a misspelling of `{f}`?)")
                });
            self.problems.push(Problem {
                position: Some(self.lines.position(value.span().start)),
                field: name.to_string(),
                message: format!(
                    "in {shown} has neither `tension` nor `displacement`{hint}: give `tension` (N) for a \
                     tension-controlled tendon or `displacement` (m, the actuator's pull-in; its tension is \
                     then solved for)"
                ),
            });
        }
        found
    }

    /// Deserializes one table; a failure becomes a problem that names the table.
    fn table<T: DeserializeOwned>(&mut self, name: &str, value: Spanned<DeValue<'_>>) -> Option<T> {
        let span = value.span();
        let missing = self.missing(name, &value);
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
                let shown = shown_table(name);
                // Missing and unknown fields are reported at their table (the key's value
                // when that is a table, else the key's parent): name it.
                let table = match &key {
                    Some(k) if self.locator.get().is_table(k) => k.clone(),
                    Some(k) => parent(k),
                    None => name.to_string(),
                };
                let hint = did_you_mean(&message);
                let (field, message) = if let Some(field) = missing_field(&message) {
                    let path = format!("{table}.{field}");
                    if missing.contains(&path) {
                        // Already reported, with the table's other missing fields.
                        return None;
                    }
                    (path, format!("is required but missing in {shown}"))
                } else if message.starts_with("unknown field")
                    || message.starts_with("unknown variant") && key.is_none()
                {
                    (table, format!("in {shown}: {message}{hint}"))
                } else {
                    (
                        key.unwrap_or_else(|| name.to_string()),
                        format!("in {shown}: {message}{hint}"),
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

/// How messages name table `name`: `[rod]`, `[[tendon]] #2`.
fn shown_table(name: &str) -> String {
    match name.split_once('[') {
        Some((array, rest)) => format!("[[{array}]] #{}", rest.trim_end_matches(']')),
        None => format!("[{name}]"),
    }
}

/// The keys of `value` if it is a table.
fn keys<'a>(value: &'a Spanned<DeValue<'_>>) -> Option<Vec<&'a str>> {
    match value.get_ref() {
        DeValue::Table(t) => Some(t.iter().map(|(k, _)| k.get_ref().as_ref()).collect()),
        _ => None,
    }
}

/// The entry `key` of `value` if it is a table that has it.
fn entry<'a, 'i>(value: &'a Spanned<DeValue<'i>>, key: &str) -> Option<&'a Spanned<DeValue<'i>>> {
    match value.get_ref() {
        DeValue::Table(t) => t.iter().find(|(k, _)| k.get_ref().as_ref() == key).map(|(_, v)| v),
        _ => None,
    }
}

/// The required fields (docs/robot-file.md) missing from table `name` of the file and
/// from its nested tables (a tendon's `routing`, each `[[loads.point]]`): each one's path,
/// the byte offset of the table it is missing from, and that table's keys. Only tables
/// that are tables are looked into; a value of the wrong type is serde's to report.
fn required_fields<'a>(name: &str, value: &'a Spanned<DeValue<'_>>) -> Vec<(String, usize, Vec<&'a str>)> {
    let mut out = Vec::new();
    let mut need = |path: &str, table: &'a Spanned<DeValue<'_>>, fields: &[&str]| {
        if let Some(present) = keys(table) {
            for f in fields.iter().filter(|f| !present.contains(f)) {
                out.push((format!("{path}.{f}"), table.span().start, present.clone()));
            }
        }
    };
    if name == "rod" {
        need(name, value, &["length", "outer_radius", "youngs_modulus"]);
    } else if name.starts_with("segment[") {
        need(name, value, &["length"]);
    } else if name == "loads" {
        if let Some(DeValue::Array(points)) = entry(value, "point").map(|p| p.get_ref()) {
            for (i, p) in points.iter().enumerate() {
                need(&format!("loads.point[{}]", i + 1), p, &["s"]);
            }
        }
    } else if name.starts_with("tendon[") {
        // A tendon is driven by `tension` or by `displacement`: `missing` reports a tendon
        // with neither, the check of the values one with both.
        need(name, value, &["routing"]);
        if let Some(routing) = entry(value, "routing") {
            let path = format!("{name}.routing");
            match entry(routing, "kind").map(|k| k.get_ref()) {
                None => need(&path, routing, &["kind"]),
                // Polar form if it has either polar key: then both are needed, else x and y.
                Some(DeValue::String(kind)) if kind.as_ref() == "straight" => {
                    let polar = keys(routing).is_some_and(|k| k.contains(&"radius") || k.contains(&"angle_deg"));
                    let pair: &[&str] = if polar { &["radius", "angle_deg"] } else { &["x", "y"] };
                    need(&path, routing, pair);
                }
                // `turns_per_rod_length` (or its old name `turns`) is checked with the values.
                Some(DeValue::String(kind)) if kind.as_ref() == "helical" => need(&path, routing, &["radius"]),
                Some(_) => {}
            }
        }
    }
    out
}

/// ` (the table has `x`: a misspelling?)` when a key of `present` is a likely misspelling
/// of the missing field at the end of `path`, else nothing.
fn near_miss(path: &str, present: Vec<&str>) -> String {
    let field = path.rsplit('.').next().unwrap_or(path);
    match closest(field, present.iter().copied()) {
        Some(key) => format!(" (the table has `{key}`: a misspelling?)"),
        None => String::new(),
    }
}

/// `; did you mean `x`?` for serde's "unknown field `a`, expected one of `x`, `y`" (or
/// "unknown variant") when one of the expected names is a likely misspelling of `a`.
fn did_you_mean(message: &str) -> String {
    if !(message.starts_with("unknown field") || message.starts_with("unknown variant")) {
        return String::new();
    }
    // The names are the back-quoted words: the unknown one first, then the expected ones.
    let mut names = message.split('`').skip(1).step_by(2);
    let Some(given) = names.next() else {
        return String::new();
    };
    match closest(given, names) {
        Some(name) => format!("; did you mean `{name}`?"),
        None => String::new(),
    }
}

/// The candidate closest to `given` by edit distance, if it is close enough to be a
/// misspelling: at most a third of the length of `given` in edits, and at least 1 (so
/// `young_modulus` finds `youngs_modulus`, 1 edit, and `lenght` finds `length`, 2), or a
/// candidate that starts with the same 4 or more characters (`helix` finds `helical`).
fn closest<'a>(given: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (given.chars().count() / 3).max(1);
    let stem: String = given.to_lowercase().chars().take(4).collect();
    let same_stem = |c: &str| stem.chars().count() == 4 && c.to_lowercase().starts_with(&stem);
    candidates
        .filter(|c| *c != given)
        .map(|c| (edit_distance(given, c), c))
        .filter(|(d, c)| *d <= limit || same_stem(c))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// Levenshtein distance between `a` and `b` (insertions, deletions and substitutions of
/// one character each count 1; case is ignored).
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.to_lowercase().chars().collect();
    let b: Vec<char> = b.to_lowercase().chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1).min(row[j] + 1).min(diagonal + usize::from(ca != cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

/// The field name of serde's "missing field `x`" message.
fn missing_field(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.split('`').next()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Routing;

    #[test]
    fn edit_distance_counts_single_character_edits() {
        assert_eq!(edit_distance("young_modulus", "youngs_modulus"), 1);
        assert_eq!(edit_distance("lenght", "length"), 2);
        assert_eq!(edit_distance("", "rod"), 3);
        assert_eq!(edit_distance("Rod", "rod"), 0);
        assert_eq!(
            closest("young_modulus", ["youngs_modulus", "length"].into_iter()),
            Some("youngs_modulus")
        );
        // `colour` is nothing like a tendon field: no suggestion.
        assert_eq!(closest("colour", ["routing", "tension", "end"].into_iter()), None);
    }

    /// Issue 17: every missing field of a table is reported, not only the first, each at the
    /// table's line.
    #[test]
    fn every_missing_field_of_a_table_is_reported() {
        let text = "[rod]\npoisson_ratio = 0.3\n\n[[tendon]]\nrouting = { kind = \"straight\" }\n";
        let e = parse(text, "robot.toml").unwrap_err().to_string();
        for line in [
            "robot.toml:1:1: `rod.length` is required but missing in [rod]",
            "robot.toml:1:1: `rod.outer_radius` is required but missing in [rod]",
            "robot.toml:1:1: `rod.youngs_modulus` is required but missing in [rod]",
            "robot.toml:4:1: `tendon[1]` in [[tendon]] #1 has neither `tension` nor `displacement`: give \
             `tension` (N) for a tension-controlled tendon or `displacement` (m, the actuator's pull-in; its \
             tension is then solved for)",
            "`tendon[1].routing.x` is required but missing in [[tendon]] #1",
            "`tendon[1].routing.y` is required but missing in [[tendon]] #1",
        ] {
            assert!(e.contains(line), "`{line}` not in:\n{e}");
        }
    }

    /// Issue 17: a misspelled key gets a did-you-mean, and the field it misspells is
    /// reported missing with a pointer to the misspelling.
    #[test]
    fn misspelled_keys_get_a_suggestion() {
        let text = crate::io::example().replace("youngs_modulus = 210e9", "young_modulus = 210e9");
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("unknown field `young_modulus`") && e.contains("did you mean `youngs_modulus`?"),
            "{e}"
        );
        assert!(
            e.contains(
                "`rod.youngs_modulus` is required but missing in [rod] (the table has `young_modulus`: a misspelling?)"
            ),
            "{e}"
        );
        let text = crate::io::example().replace("kind = \"helical\"", "kind = \"helix\"");
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("unknown variant `helix`") && e.contains("did you mean `helical`?"),
            "{e}"
        );
        let text = format!("{}\n[solvr]\nmethod = \"shooting\"\n", crate::io::example());
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("unknown key `solvr` at the top level") && e.contains("did you mean [solver]?"),
            "{e}"
        );
    }

    /// Issue 27: the `[model]` table's keys and values are checked like every other table's.
    #[test]
    fn model_table_rejects_unknown_keys_and_variants() {
        let text = format!("{}\n[model]\ntendons = \"point-moment\"\n", crate::io::example());
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains(
                "`model.tendons` in [model]: unknown variant `point-moment`, expected `coupled` or `point_moment`"
            ) && e.contains("did you mean `point_moment`?"),
            "{e}"
        );
        let text = format!("{}\n[model]\ncorner_force = false\n", crate::io::example());
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("unknown field `corner_force`") && e.contains("did you mean `corner_forces`?"),
            "{e}"
        );
        let text = format!("{}\n[modl]\n", crate::io::example());
        let e = parse(&text, "robot.toml").unwrap_err().to_string();
        assert!(e.contains("did you mean [model]?"), "{e}");
    }

    /// Issue 27: a tendon placed in polar form is the same robot as one placed at the
    /// exact (x, y); a helix's `angle_deg` is its `phase` in degrees; half pairs, mixed
    /// forms and negative radii are reported at their keys.
    #[test]
    fn polar_placements_read_as_their_exact_offsets() {
        let tendon = |routing: &str| {
            let text = crate::io::example().replacen(
                "routing = { kind = \"straight\", x = 0.008, y = 0.0 }",
                &format!("routing = {{ {routing} }}"),
                1,
            );
            parse(&text, "robot.toml").map(|f| f.robot.tendons[0].routing.clone())
        };
        let debug = |r: Result<Routing, FileError>| format!("{:?}", r.unwrap());
        for (polar, cartesian) in [
            (
                "kind = \"straight\", radius = 0.008, angle_deg = 90",
                "kind = \"straight\", x = 0.0, y = 0.008",
            ),
            (
                "kind = \"straight\", radius = 0.01, angle_deg = 180",
                "kind = \"straight\", x = -0.01, y = 0.0",
            ),
            (
                "kind = \"straight\", radius = 0.01, angle_deg = -90",
                "kind = \"straight\", x = 0.0, y = -0.01",
            ),
            (
                "kind = \"helical\", radius = 0.008, turns_per_rod_length = 1, angle_deg = 90",
                &format!(
                    "kind = \"helical\", radius = 0.008, turns_per_rod_length = 1, phase = {:?}",
                    90f64.to_radians()
                ),
            ),
        ] {
            assert_eq!(debug(tendon(polar)), debug(tendon(cartesian)), "{polar}");
        }
        let at_120 = tendon("kind = \"straight\", radius = 0.01, angle_deg = 120").unwrap();
        assert!(matches!(at_120, Routing::Straight { x, .. } if x == -0.005));
        for (routing, message) in [
            (
                "kind = \"straight\", radius = 0.01",
                "`tendon[1].routing.angle_deg` is required but missing in [[tendon]] #1",
            ),
            (
                "kind = \"straight\", x = 0.01, radius = 0.01, angle_deg = 0",
                "`tendon[1].routing.radius` is given together with `x` or `y`",
            ),
            (
                "kind = \"straight\", radius = -0.01, angle_deg = 0",
                "`tendon[1].routing.radius` is -0.01 m, but a distance from the backbone must be >= 0",
            ),
            (
                "kind = \"helical\", radius = 0.01, turns = 1, phase = 0.1, angle_deg = 5",
                "`tendon[1].routing.angle_deg` is given together with `phase`",
            ),
        ] {
            let e = tendon(routing).unwrap_err().to_string();
            assert!(e.contains(message), "{routing}: {e}");
        }
    }

    /// Issue 17: `turns` is the old name of `turns_per_rod_length`, with the same meaning.
    #[test]
    fn helix_turns_keep_their_old_name() {
        let example = crate::io::example();
        let old = example.replace("turns_per_rod_length = 1.0", "turns = 1.0");
        assert_ne!(old, example, "the example lost its helix");
        let (new, old) = (parse(&example, "new").unwrap(), parse(&old, "old").unwrap());
        for robot in [&new.robot, &old.robot] {
            assert!(matches!(robot.tendons[4].routing, Routing::Helical { turns, .. } if turns == 1.0));
        }
        let both = example.replace("turns_per_rod_length = 1.0", "turns_per_rod_length = 1.0, turns = 1.0");
        let e = parse(&both, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("`tendon[5].routing.turns` is given together with `turns_per_rod_length`"),
            "{e}"
        );
        let none = example.replace("turns_per_rod_length = 1.0, ", "");
        let e = parse(&none, "robot.toml").unwrap_err().to_string();
        assert!(
            e.contains("`tendon[5].routing.turns_per_rod_length` is required but missing"),
            "{e}"
        );
    }
}
