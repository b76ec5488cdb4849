//! The robot file: each TOML table deserialized on its own with serde (so one bad table does
//! not hide the problems of the next, and unknown keys are rejected), every field checked
//! against its rule, then the [`Robot`] built and checked once more by [`Robot::validate`].

use super::locate::{Locator, position};
use super::printable;
use super::{FileError, Problem};
use crate::model::loads::{Field, Loads, PointLoad};
use crate::model::rod::{Rod, Section};
use crate::model::routing::Routing;
use crate::model::tendon::Tendon;
use crate::report::Method;
use crate::{Error, Robot, collocation, shooting, so3};
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::Deserialize;
use serde::de::DeserializeOwned;
use toml::Spanned;
use toml::de::{DeTable, DeValue, ValueDeserializer};

/// A world- or body-frame vector as written in the file, `[x, y, z]`.
type Vec3 = [f64; 3];

/// Largest |R^T R - I|, |det R - 1| accepted for a base rotation (the 1e-6: loose
/// enough for matrices typed with 7 digits).
const ROTATION_TOLERANCE: f64 = 1e-6;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RodTable {
    length: f64,
    outer_radius: f64,
    #[serde(default)]
    inner_radius: f64,
    youngs_modulus: f64,
    poisson_ratio: Option<f64>,
    shear_modulus: Option<f64>,
    precurvature: Option<Vec3>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct BaseTable {
    position: Option<Vec3>,
    rotation: Option<[Vec3; 3]>,
    euler_xyz_deg: Option<Vec3>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LoadsTable {
    distributed_force: Option<Vec3>,
    distributed_moment: Option<Vec3>,
    tip_force: Option<Vec3>,
    tip_moment: Option<Vec3>,
    #[serde(default)]
    point: Vec<PointTable>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PointTable {
    s: f64,
    force: Option<Vec3>,
    moment: Option<Vec3>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TendonTable {
    routing: RoutingTable,
    tension: f64,
    end: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
enum RoutingTable {
    Straight {
        x: f64,
        y: f64,
    },
    Helical {
        radius: f64,
        turns: f64,
        #[serde(default)]
        phase: f64,
    },
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SolverTable {
    method: Option<MethodName>,
    intervals: Option<usize>,
    /// The old name of `intervals`, still accepted.
    nodes: Option<usize>,
    tolerance: Option<f64>,
    max_intervals: Option<usize>,
    /// The old name of `max_intervals`, still accepted.
    max_nodes: Option<usize>,
    residual_tolerance: Option<f64>,
    max_iterations: Option<usize>,
    continuation: Option<bool>,
    integration_tolerance: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "lowercase")]
enum MethodName {
    Collocation,
    Shooting,
}

/// The tables a robot file may have, in the order docs/robot-file.md describes them.
const TABLES: &str = "[rod], [base], [loads], [[tendon]], [solver]";

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
    let (root, errors) = DeTable::parse_recoverable(text);
    if !errors.is_empty() {
        let problems = errors
            .iter()
            .map(|e| Problem {
                position: e.span().map(|s| position(text, s.start)),
                field: String::new(),
                message: format!("is not valid TOML: {}", e.message().trim()),
            })
            .collect();
        return Err(fail(problems));
    }
    let locator = Locator::new(text, root.get_ref());
    let mut reader = Reader {
        text,
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
        return Err(fail(vec![library_problem(&locator, &e, base.euler_xyz_deg.is_some())]));
    }
    Ok(RobotFile {
        robot,
        solver: settings(&solver),
    })
}

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

struct Reader<'a> {
    text: &'a str,
    locator: &'a Locator,
    problems: Vec<Problem>,
}

impl Reader<'_> {
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
                "tendon" => match value.get_ref() {
                    DeValue::Array(items) if items.iter().all(|t| t.get_ref().is_table()) => {
                        for (i, item) in items.iter().enumerate() {
                            let t = self.table(&format!("tendon[{}]", i + 1), item.clone());
                            tables.tendons.push(t);
                        }
                    }
                    _ => self.problems.push(Problem {
                        position: Some(position(self.text, key.span().start)),
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
                        position: Some(position(self.text, key.span().start)),
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
                let at = position(self.text, e.span().unwrap_or(span).start);
                let raw = e.message().trim().replace('\n', " ");
                let message = raw
                    .replace("expected f64", "expected a number")
                    .replace("expected usize", "expected a whole number >= 0");
                // The key the error is at, if it belongs to this table.
                let key = self.locator.key_at(at).filter(|p| p.starts_with(name));
                let parent = |p: &str| p.rfind('.').map_or(name.to_string(), |i| p[..i].to_string());
                let shown = match name.strip_prefix("tendon[") {
                    Some(rest) => format!("[[tendon]] #{}", rest.trim_end_matches(']')),
                    None => format!("[{name}]"),
                };
                // Missing and unknown fields are reported at their table (the key's value
                // when that is a table, else the key's parent): name it.
                let table = match &key {
                    Some(k) if self.locator.is_table(k) => k.clone(),
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

/// A number as TOML spells it (`nan`, `inf`, `-inf` for the non-finite ones).
fn toml_number(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        x.to_string()
    }
}

/// Field-by-field rules; every broken rule is one problem.
struct Checker<'a> {
    locator: &'a Locator,
    problems: Vec<Problem>,
}

impl Checker<'_> {
    fn report(&mut self, field: &str, message: String) {
        self.problems.push(Problem {
            position: self.locator.find(field),
            field: field.to_string(),
            message,
        });
    }

    fn finite(&mut self, field: &str, x: f64, unit: &str) -> bool {
        if x.is_finite() {
            return true;
        }
        self.report(
            field,
            format!("is {}{unit}, but every number must be finite", toml_number(x)),
        );
        false
    }

    fn positive(&mut self, field: &str, x: f64, unit: &str) {
        if self.finite(field, x, unit) && x <= 0.0 {
            self.report(field, format!("is {x}{unit}, but must be positive"));
        }
    }

    fn vector(&mut self, field: &str, v: &Option<Vec3>, unit: &str) {
        if let Some(v) = v {
            for (k, x) in v.iter().enumerate() {
                if !x.is_finite() {
                    let axis = ["x", "y", "z"][k];
                    self.report(
                        field,
                        format!(
                            "has {axis} = {}{unit}, but every number must be finite",
                            toml_number(*x)
                        ),
                    );
                }
            }
        }
    }

    fn rod(&mut self, rod: &RodTable) {
        self.positive("rod.length", rod.length, " m");
        self.positive("rod.outer_radius", rod.outer_radius, " m");
        if self.finite("rod.inner_radius", rod.inner_radius, " m") {
            if rod.inner_radius < 0.0 {
                self.report(
                    "rod.inner_radius",
                    format!("is {} m, but must be >= 0 (0 for a solid rod)", rod.inner_radius),
                );
            } else if rod.outer_radius.is_finite() && rod.inner_radius >= rod.outer_radius {
                self.report(
                    "rod.inner_radius",
                    format!(
                        "is {} m, but must be below the outer radius {} m",
                        rod.inner_radius, rod.outer_radius
                    ),
                );
            }
        }
        self.positive("rod.youngs_modulus", rod.youngs_modulus, " Pa");
        match (rod.poisson_ratio, rod.shear_modulus) {
            (Some(_), Some(_)) => self.report(
                "rod.shear_modulus",
                "is given together with `poisson_ratio`: give one of them".into(),
            ),
            (None, None) => self.report(
                "rod",
                "needs `poisson_ratio` or `shear_modulus` (Pa) for the torsion stiffness G J".into(),
            ),
            (Some(nu), None) => {
                if self.finite("rod.poisson_ratio", nu, "") && !(nu > -1.0 && nu <= 0.5) {
                    self.report("rod.poisson_ratio", format!("is {nu}, but must lie in (-1, 0.5]"));
                }
            }
            (None, Some(g)) => self.positive("rod.shear_modulus", g, " Pa"),
        }
        self.vector("rod.precurvature", &rod.precurvature, " rad/m");
    }

    fn base(&mut self, base: &BaseTable) {
        self.vector("base.position", &base.position, " m");
        if base.rotation.is_some() && base.euler_xyz_deg.is_some() {
            self.report(
                "base.euler_xyz_deg",
                "is given together with `rotation`: give one of them".into(),
            );
            return;
        }
        self.vector("base.euler_xyz_deg", &base.euler_xyz_deg, " deg");
        if let Some(rows) = &base.rotation {
            if rows.iter().flatten().any(|x| !x.is_finite()) {
                self.report(
                    "base.rotation",
                    "has a non-finite entry, but every number must be finite".into(),
                );
                return;
            }
            let error = so3::orthonormality_error(&rotation_from_rows(rows));
            if error > ROTATION_TOLERANCE {
                self.report(
                    "base.rotation",
                    format!(
                        "is not a rotation: |R^T R - I|, |det R - 1| = {error:.2e} > {ROTATION_TOLERANCE:.0e}; \
                         its rows must be orthonormal with determinant +1"
                    ),
                );
            }
        }
    }

    fn loads(&mut self, loads: &LoadsTable, length: f64) {
        self.vector("loads.distributed_force", &loads.distributed_force, " N/m");
        self.vector("loads.distributed_moment", &loads.distributed_moment, " N m/m");
        self.vector("loads.tip_force", &loads.tip_force, " N");
        self.vector("loads.tip_moment", &loads.tip_moment, " N m");
        for (i, p) in loads.point.iter().enumerate() {
            let path = format!("loads.point[{}]", i + 1);
            let s = format!("{path}.s");
            if self.finite(&s, p.s, " m") && length.is_finite() && !(p.s > 0.0 && p.s <= length) {
                self.report(&s, format!("is {} m, but must lie on the rod, in (0, {length}] m", p.s));
            }
            self.vector(&format!("{path}.force"), &p.force, " N");
            self.vector(&format!("{path}.moment"), &p.moment, " N m");
        }
    }

    fn tendon(&mut self, i: usize, t: &TendonTable, length: f64) {
        let path = format!("tendon[{}]", i + 1);
        let tension = format!("{path}.tension");
        if self.finite(&tension, t.tension, " N") && t.tension < 0.0 {
            self.report(
                &tension,
                format!("is {} N, but a tendon can only pull: must be >= 0", t.tension),
            );
        }
        if let Some(end) = t.end {
            let field = format!("{path}.end");
            if self.finite(&field, end, " m") && length.is_finite() {
                if end > length {
                    self.report(
                        &field,
                        format!("is {end} m, past the tip at {length} m: must be at most rod.length"),
                    );
                } else if end <= 0.0 {
                    self.report(&field, format!("is {end} m, but must be above 0 (the base)"));
                }
            }
        }
        let routing = format!("{path}.routing");
        match t.routing {
            RoutingTable::Straight { x, y } => {
                self.finite(&format!("{routing}.x"), x, " m");
                self.finite(&format!("{routing}.y"), y, " m");
            }
            RoutingTable::Helical { radius, turns, phase } => {
                self.positive(&format!("{routing}.radius"), radius, " m");
                self.finite(&format!("{routing}.turns"), turns, "");
                self.finite(&format!("{routing}.phase"), phase, " rad");
            }
        }
    }

    /// A key given under its name or its old name (an alias): the field path and value of
    /// the one given (the new name if both, which is a problem naming both).
    fn renamed(
        &mut self,
        name: &str,
        alias: &str,
        value: Option<usize>,
        old: Option<usize>,
    ) -> Option<(String, usize)> {
        match (value, old) {
            (Some(n), Some(_)) => {
                self.report(
                    &format!("solver.{alias}"),
                    format!("is given together with `{name}`: `{alias}` is its old name; give one of them"),
                );
                Some((format!("solver.{name}"), n))
            }
            (Some(n), None) => Some((format!("solver.{name}"), n)),
            (None, Some(n)) => Some((format!("solver.{alias}"), n)),
            (None, None) => None,
        }
    }

    /// Reports the first rule of the library that `checks` (each the options' `validate()`
    /// with only `field` changed from the defaults) says `field` = `shown` breaks.
    fn library_rule(&mut self, field: &str, shown: &str, checks: &[Result<(), Error>]) -> bool {
        let Some(Err(e)) = checks.iter().find(|c| c.is_err()) else {
            return true;
        };
        let message = match e {
            // A rule about the options as a whole: its hint speaks of the Rust API.
            Error::InvalidInput { field: f, problem, .. } if !f.contains('.') => format!("is {shown}, but {problem}"),
            Error::InvalidInput { problem, hint, .. } => format!("{problem}; {hint}"),
            other => other.to_string(),
        };
        self.report(field, message);
        false
    }

    /// The `[solver]` rules: the library's own (`collocation::Options::validate`,
    /// `shooting::Options::validate`), checked one field at a time from the defaults so
    /// that every broken rule is reported at its key, plus the file's: numbers finite, a
    /// mesh of at least one interval, a key and its old name not both given.
    fn solver(&mut self, solver: &SolverTable) {
        let intervals = self.renamed("intervals", "nodes", solver.intervals, solver.nodes);
        let cap = self.renamed("max_intervals", "max_nodes", solver.max_intervals, solver.max_nodes);
        if let Some((field, 0)) = &intervals {
            self.report(field, "is 0, but the mesh needs at least 1 interval".into());
        }
        let mut finite = |field: &str, x: Option<f64>, unit: &str| x.filter(|&x| self.finite(field, x, unit));
        let tolerance = finite("solver.tolerance", solver.tolerance, " m");
        let residual = finite("solver.residual_tolerance", solver.residual_tolerance, "");
        let integration = finite("solver.integration_tolerance", solver.integration_tolerance, "");
        let c = collocation::Options::default;
        let s = shooting::Options::default;
        if let Some(x) = residual {
            let checks = [
                collocation::Options {
                    residual_tolerance: x,
                    ..c()
                }
                .validate(),
                shooting::Options { tolerance: x, ..s() }.validate(),
            ];
            self.library_rule("solver.residual_tolerance", &x.to_string(), &checks);
        }
        if let Some(n) = solver.max_iterations {
            let checks = [
                collocation::Options {
                    max_iterations: n,
                    ..c()
                }
                .validate(),
                shooting::Options {
                    max_iterations: n,
                    ..s()
                }
                .validate(),
            ];
            self.library_rule("solver.max_iterations", &n.to_string(), &checks);
        }
        if let Some(t) = tolerance {
            let checks = [collocation::Options {
                tolerance: Some(t),
                ..c()
            }
            .validate()];
            self.library_rule("solver.tolerance", &format!("{t} m"), &checks);
        }
        if let Some(x) = integration {
            let checks = [shooting::Options {
                integration_tolerance: x,
                ..s()
            }
            .validate()];
            self.library_rule("solver.integration_tolerance", &x.to_string(), &checks);
        }
        // The cap on its own (with a starting mesh within it), then the starting mesh
        // against the cap: at `intervals` if given, else at the cap that the default breaks.
        let cap_ok = match &cap {
            Some((field, n)) => {
                let checks = [collocation::Options {
                    max_intervals: *n,
                    intervals: c().intervals.min(*n),
                    ..c()
                }
                .validate()];
                self.library_rule(field, &n.to_string(), &checks)
            }
            None => true,
        };
        if cap_ok && !matches!(intervals, Some((_, 0))) {
            let options = collocation::Options {
                intervals: intervals.as_ref().map_or(c().intervals, |i| i.1),
                max_intervals: cap.as_ref().map_or(c().max_intervals, |m| m.1),
                ..c()
            };
            if let Err(Error::InvalidInput { problem, hint, .. }) = options.validate() {
                match (&intervals, &cap) {
                    (Some((field, _)), _) => self.report(field, format!("{problem}; {hint}")),
                    (None, Some((field, n))) => {
                        self.report(field, format!("is {n}: the default `intervals` {problem}; {hint}"));
                    }
                    (None, None) => {}
                }
            }
        }
    }
}

fn rotation_from_rows(r: &[Vec3; 3]) -> Matrix3<f64> {
    Matrix3::new(
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    )
}

/// R = Rx(a) Ry(b) Rz(c), angles in degrees (intrinsic x, then y', then z'').
fn rotation_from_euler(angles: &Vec3) -> Matrix3<f64> {
    let [a, b, c] = angles.map(f64::to_radians);
    (Rotation3::from_axis_angle(&Vector3::x_axis(), a)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), b)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), c))
    .into_inner()
}

fn vector(v: &Option<Vec3>) -> Vector3<f64> {
    v.map_or_else(Vector3::zeros, Vector3::from)
}

fn build(rod: &RodTable, base: &BaseTable, loads: &LoadsTable, tendons: &[TendonTable]) -> Robot {
    let mut backbone = match (rod.poisson_ratio, rod.shear_modulus) {
        (Some(nu), _) => Rod::tube(rod.length, rod.outer_radius, rod.inner_radius, rod.youngs_modulus, nu),
        (None, g) => {
            let g = g.unwrap_or(f64::NAN);
            Rod::new(
                rod.length,
                Section::tube(rod.outer_radius, rod.inner_radius, rod.youngs_modulus, g),
            )
        }
    };
    if let Some(u) = rod.precurvature {
        backbone = backbone.with_precurvature(Vector3::from(u));
    }
    let rotation = match (&base.rotation, &base.euler_xyz_deg) {
        (Some(rows), _) => rotation_from_rows(rows),
        (None, Some(angles)) => rotation_from_euler(angles),
        (None, None) => Matrix3::identity(),
    };
    let loads = Loads {
        distributed_force: Field::Constant(vector(&loads.distributed_force)),
        distributed_moment: Field::Constant(vector(&loads.distributed_moment)),
        tip_force: vector(&loads.tip_force),
        tip_moment: vector(&loads.tip_moment),
        point: loads
            .point
            .iter()
            .map(|p| PointLoad {
                s: p.s,
                force: vector(&p.force),
                moment: vector(&p.moment),
            })
            .collect(),
    };
    let mut robot = Robot::new(backbone)
        .with_loads(loads)
        .with_base(vector(&base.position), rotation);
    for t in tendons {
        let routing = match t.routing {
            RoutingTable::Straight { x, y } => Routing::straight(x, y),
            RoutingTable::Helical { radius, turns, phase } => Routing::helical(radius, turns, phase),
        };
        let mut tendon = Tendon::new(routing, t.tension);
        tendon.termination = t.end;
        robot = robot.with_tendon(tendon);
    }
    robot
}

fn settings(solver: &SolverTable) -> SolverSettings {
    let mut out = SolverSettings::default();
    if let Some(MethodName::Shooting) = solver.method {
        out.method = Method::Shooting;
    }
    let c = &mut out.collocation;
    c.intervals = solver.intervals.or(solver.nodes).unwrap_or(c.intervals);
    c.tolerance = solver.tolerance;
    c.max_intervals = solver.max_intervals.or(solver.max_nodes).unwrap_or(c.max_intervals);
    c.residual_tolerance = solver.residual_tolerance.unwrap_or(c.residual_tolerance);
    c.max_iterations = solver.max_iterations.unwrap_or(c.max_iterations);
    c.continuation = solver.continuation.unwrap_or(c.continuation);
    let s = &mut out.shooting;
    s.tolerance = solver.residual_tolerance.unwrap_or(s.tolerance);
    s.max_iterations = solver.max_iterations.unwrap_or(s.max_iterations);
    s.integration_tolerance = solver.integration_tolerance.unwrap_or(s.integration_tolerance);
    out
}

/// The file path of a field path of the library (`tendons[0].termination` ->
/// `tendon[1].end`).
pub(crate) fn file_field(field: &str, euler: bool) -> String {
    let renumber = |prefix: &str, to: &str| -> Option<String> {
        let rest = field.strip_prefix(prefix)?;
        let close = rest.find(']')?;
        let index: usize = rest[..close].parse().ok()?;
        let tail = rest[close + 1..].replace(".termination", ".end");
        Some(format!("{to}[{}]{tail}", index + 1))
    };
    if let Some(f) = renumber("tendons[", "tendon").or_else(|| renumber("loads.point[", "loads.point")) {
        return f;
    }
    match field {
        "base_position" => "base.position".into(),
        "base_rotation" if euler => "base.euler_xyz_deg".into(),
        "base_rotation" => "base.rotation".into(),
        "rod.stiffness" => "rod".into(),
        f if f.starts_with("rod.reference") => "rod.precurvature".into(),
        f => f.into(),
    }
}

/// A library validation error as a problem at the line of the field it names.
fn library_problem(locator: &Locator, e: &Error, euler: bool) -> Problem {
    let (field, message) = match e {
        Error::InvalidInput { field, problem, hint } => (file_field(field, euler), format!("{problem}; {hint}")),
        Error::SingularRouting { tendon, .. } => (format!("tendon[{}].routing", tendon + 1), e.to_string()),
        other => (String::new(), other.to_string()),
    };
    Problem {
        position: locator.find(&field),
        field,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_paths_map_to_file_paths() {
        assert_eq!(file_field("tendons[0].termination", false), "tendon[1].end");
        assert_eq!(file_field("tendons[4].tension", false), "tendon[5].tension");
        assert_eq!(file_field("loads.point[2].s", false), "loads.point[3].s");
        assert_eq!(file_field("base_rotation", true), "base.euler_xyz_deg");
        assert_eq!(file_field("rod.length", false), "rod.length");
    }

    #[test]
    fn euler_angles_compose_about_x_then_y_then_z() {
        let r = rotation_from_euler(&[0.0, 90.0, 0.0]);
        let prototype = crate::cases::prototype_base_rotation();
        // 1e-15: cos(pi/2) rounds to 6e-17
        assert!((r - prototype).amax() < 1e-15);
    }
}
