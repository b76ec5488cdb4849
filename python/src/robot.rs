//! `tdcr.Robot`: a robot and its solver settings, always built by the robot-file parser
//! (`tdcr::io::parse`), whether from TOML text, a file, keyword arguments or a dict, and
//! written back as a robot file for pickling.

use crate::errors::{file_error, invalid, to_py};
use crate::options::type_name;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use tdcr::Parameter;
use tdcr::io::{RobotFile, SolverSettings};
use tdcr::model::rod::{ReferenceStrains, Stiffness};
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Field, Method, Routing};
use toml::{Table, Value};

/// A tendon-driven continuum robot (SI units) with the solver settings of its `[solver]`
/// table; the same fields and rules as a robot file (docs/robot-file.md).
///
/// Build it from keyword arguments shaped like the file's tables::
///
///     robot = tdcr.Robot(
///         rod={"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125},
///         tendons=[{"routing": {"kind": "straight", "x": 0.008, "y": 0.0}, "tension": 2.94}],
///         loads={"distributed_force": [0, 0, -0.47]},
///         base={"position": [0, 0, 0], "euler_xyz_deg": [0, 90, 0]},
///     )
///
/// A tendon dict takes the keys of the file's `[[tendon]]`: `routing`, `tension` (N) or
/// `displacement` (m, the actuator's pull-in; the tension is then solved for), `end` (m),
/// and for an elastic tendon `stiffness` (E_t A_t, N) and `free_length` (m).
///
/// Or build it with `Robot.from_toml(text)`, `Robot.from_file(path)`, `Robot.from_dict(tables)`,
/// `tdcr.cases.case_s()`. Bad input raises `tdcr.FileError` with the command line's
/// messages. Robots are immutable; `with_tensions`, `with_displacements` and
/// `with_parameters` return new ones.
#[pyclass(module = "tdcr", name = "Robot", frozen)]
#[derive(Clone)]
pub struct PyRobot {
    /// The robot and its settings, validated.
    pub file: RobotFile,
}

/// A Python value (numbers, strings, bools, lists, tuples, dicts, numpy arrays) as TOML;
/// `path` names it in messages.
fn to_toml(value: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    if value.is_instance_of::<PyBool>() {
        return Ok(Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        return Ok(Value::Integer(value.extract()?));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(Value::String(value.extract()?));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        return Ok(Value::Table(table(dict, path)?));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: PyResult<Vec<Value>> = value
            .try_iter()?
            .enumerate()
            .map(|(i, item)| to_toml(&item?, &format!("{path}[{}]", i + 1)))
            .collect();
        return Ok(Value::Array(items?));
    }
    // numpy arrays and scalars: their Python equivalents.
    if value.hasattr("tolist")? {
        return to_toml(&value.call_method0("tolist")?, path);
    }
    Err(invalid(format!(
        "`{path}` is a {}; give numbers, strings, booleans, lists or dicts as in a robot file",
        type_name(value)
    )))
}

/// A dict with string keys as a TOML table.
fn table(dict: &Bound<'_, PyDict>, path: &str) -> PyResult<Table> {
    let mut out = Table::new();
    for (key, value) in dict.iter() {
        let key: String = key
            .extract()
            .map_err(|_| invalid(format!("`{path}` has a key that is not a string: {key}")))?;
        let inner = if path.is_empty() {
            key.clone()
        } else {
            format!("{path}.{key}")
        };
        if !value.is_none() {
            out.insert(key, to_toml(&value, &inner)?);
        }
    }
    Ok(out)
}

/// Parses robot-file text (`name` in messages) into a robot.
pub fn parse(text: &str, name: &str) -> PyResult<PyRobot> {
    tdcr::io::parse(text, name)
        .map(|file| PyRobot { file })
        .map_err(|e| file_error(&e))
}

fn vector(v: &Vector3<f64>) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

fn rows(r: &Matrix3<f64>) -> Value {
    Value::Array(
        (0..3)
            .map(|i| vector(&Vector3::new(r[(i, 0)], r[(i, 1)], r[(i, 2)])))
            .collect(),
    )
}

fn constant(field: &Field, name: &str) -> PyResult<Vector3<f64>> {
    match field {
        Field::Constant(v) => Ok(*v),
        Field::Varying(_) => Err(invalid(format!(
            "`loads.{name}` varies along the rod, which a robot file cannot hold"
        ))),
    }
}

/// The robot file of `file`: every value written so that parsing it gives the same robot
/// bitwise (TOML floats are written in their shortest round-trip form).
pub fn document(file: &RobotFile) -> PyResult<String> {
    let robot = &file.robot;
    let rod = &robot.rod;
    let cannot = |what: &str| invalid(format!("this robot cannot be written as a robot file: {what}"));
    let (Some(g), Stiffness::Uniform(_)) = (rod.geometry, &rod.stiffness) else {
        return Err(cannot(
            "its rod is not given by `outer_radius`, `youngs_modulus` and `poisson_ratio` (a rod given by `shear_modulus` keeps no geometry)",
        ));
    };
    let mut rod_table = Table::new();
    rod_table.insert("length".into(), Value::Float(rod.length));
    rod_table.insert("outer_radius".into(), Value::Float(g.outer_radius));
    rod_table.insert("inner_radius".into(), Value::Float(g.inner_radius));
    rod_table.insert("youngs_modulus".into(), Value::Float(g.youngs_modulus));
    rod_table.insert("poisson_ratio".into(), Value::Float(g.poisson_ratio));
    match &rod.reference {
        ReferenceStrains::Straight => {}
        ReferenceStrains::Constant { v_star, u_star } if *v_star == Vector3::z() => {
            rod_table.insert("precurvature".into(), vector(u_star));
        }
        _ => return Err(cannot("its reference strains are not a constant precurvature")),
    }
    let mut base = Table::new();
    base.insert("position".into(), vector(&robot.base_position));
    base.insert("rotation".into(), rows(&robot.base_rotation));
    let loads_in = &robot.loads;
    let mut loads = Table::new();
    loads.insert(
        "distributed_force".into(),
        vector(&constant(&loads_in.distributed_force, "distributed_force")?),
    );
    loads.insert(
        "distributed_moment".into(),
        vector(&constant(&loads_in.distributed_moment, "distributed_moment")?),
    );
    loads.insert("tip_force".into(), vector(&loads_in.tip_force));
    loads.insert("tip_moment".into(), vector(&loads_in.tip_moment));
    let points = loads_in
        .point
        .iter()
        .map(|p| {
            let mut t = Table::new();
            t.insert("s".into(), Value::Float(p.s));
            t.insert("force".into(), vector(&p.force));
            t.insert("moment".into(), vector(&p.moment));
            Value::Table(t)
        })
        .collect();
    loads.insert("point".into(), Value::Array(points));
    let mut tendons = Vec::new();
    for (i, t) in robot.tendons.iter().enumerate() {
        let mut routing = Table::new();
        match t.routing {
            Routing::Straight { x, y } => {
                routing.insert("kind".into(), Value::String("straight".into()));
                routing.insert("x".into(), Value::Float(x));
                routing.insert("y".into(), Value::Float(y));
            }
            Routing::Helical { radius, turns, phase } => {
                routing.insert("kind".into(), Value::String("helical".into()));
                routing.insert("radius".into(), Value::Float(radius));
                routing.insert("turns".into(), Value::Float(turns));
                routing.insert("phase".into(), Value::Float(phase));
            }
            Routing::Custom(_) => return Err(cannot(&format!("tendon {} has a custom routing", i + 1))),
        }
        let mut tendon = Table::new();
        tendon.insert("routing".into(), Value::Table(routing));
        match t.displacement() {
            None => {
                tendon.insert("tension".into(), Value::Float(t.tension()));
            }
            // The file gives a displacement-controlled tendon no starting tension (the
            // parser sets 0: the solver estimates it), so only 0 is written exactly.
            Some(_) if t.tension() != 0.0 => {
                return Err(cannot(&format!(
                    "tendon {} is displacement-controlled with a starting tension of {} N, which a robot file cannot hold (set its tension with `with_tensions` to make it tension-controlled)",
                    i + 1,
                    t.tension()
                )));
            }
            Some(q) => {
                tendon.insert("displacement".into(), Value::Float(q));
            }
        }
        if let Some(end) = t.termination {
            tendon.insert("end".into(), Value::Float(end));
        }
        if let Some(k) = t.stiffness {
            tendon.insert("stiffness".into(), Value::Float(k));
        }
        if t.free_length != 0.0 {
            tendon.insert("free_length".into(), Value::Float(t.free_length));
        }
        tendons.push(Value::Table(tendon));
    }
    let mut doc = Table::new();
    doc.insert("rod".into(), Value::Table(rod_table));
    doc.insert("base".into(), Value::Table(base));
    doc.insert("loads".into(), Value::Table(loads));
    if !tendons.is_empty() {
        doc.insert("tendon".into(), Value::Array(tendons));
    }
    doc.insert("solver".into(), Value::Table(solver_table(&file.solver)));
    toml::to_string(&doc).map_err(|e| invalid(format!("cannot write the robot file: {e}")))
}

/// The `[solver]` table of `s`: every key, except `residual_tolerance` and `max_iterations`
/// where both solvers keep their own defaults (the file sets both at once).
fn solver_table(s: &SolverSettings) -> Table {
    let defaults = SolverSettings::default();
    let (c, d) = (&s.collocation, &defaults.collocation);
    let mut t = Table::new();
    let method = if s.method == Method::Shooting {
        "shooting"
    } else {
        "collocation"
    };
    t.insert("method".into(), Value::String(method.into()));
    t.insert("intervals".into(), Value::Integer(c.intervals as i64));
    if let Some(tol) = c.tolerance {
        t.insert("tolerance".into(), Value::Float(tol));
    }
    t.insert("max_intervals".into(), Value::Integer(c.max_intervals as i64));
    if c.residual_tolerance != d.residual_tolerance || s.shooting.tolerance != defaults.shooting.tolerance {
        t.insert("residual_tolerance".into(), Value::Float(c.residual_tolerance));
    }
    if c.max_iterations != d.max_iterations || s.shooting.max_iterations != defaults.shooting.max_iterations {
        t.insert("max_iterations".into(), Value::Integer(c.max_iterations as i64));
    }
    t.insert("continuation".into(), Value::Boolean(c.continuation));
    t.insert(
        "equilibrium".into(),
        Value::String(crate::options::equilibrium_name(c.equilibrium).into()),
    );
    t.insert(
        "integration_tolerance".into(),
        Value::Float(s.shooting.integration_tolerance),
    );
    t
}

/// A robot of the library with default solver settings, written as its robot file and
/// parsed back, so that it is exactly what `Robot.from_toml(robot.to_toml())` gives (the
/// library's compiled constants can differ from parsed ones in the last bit of a
/// stiffness: the compiler folds `powi` of constants differently).
pub fn from_library(robot: tdcr::Robot) -> PyResult<PyRobot> {
    let file = RobotFile {
        robot,
        solver: SolverSettings::default(),
    };
    parse(&document(&file)?, "<tdcr.cases>")
}

impl PyRobot {
    /// Sets `parameter` (`tension.1`, `tip_force.z`, ...) of this robot to `value`.
    pub fn set(&mut self, parameter: &Parameter, value: f64) -> PyResult<()> {
        parameter.apply(&mut self.file.robot, value).map_err(to_py)
    }
}

/// Parameter names and their values as read from a dict of equal-length 1-D arrays.
pub type Columns = Vec<(Parameter, Vec<f64>)>;

/// Reads `{name: array}` (names as in `tdcr batch` headers); every array 1-D of one length.
pub fn columns(parameters: &Bound<'_, PyDict>) -> PyResult<(Columns, usize)> {
    let mut out = Vec::new();
    let mut rows = None;
    for (key, value) in parameters.iter() {
        let name: String = key.extract().map_err(|_| invalid("parameter names must be strings"))?;
        let parameter: Parameter = name.parse().map_err(invalid)?;
        let array = numpy_column(&value, &name)?;
        match rows {
            Some(n) if n != array.len() => {
                return Err(invalid(format!(
                    "parameter `{name}` has {} values but another has {n}: give every parameter one value per row",
                    array.len()
                )));
            }
            _ => rows = Some(array.len()),
        }
        out.push((parameter, array));
    }
    Ok((out, rows.unwrap_or(0)))
}

/// A 1-D sequence of numbers (numpy array, list, tuple) as f64 values.
fn numpy_column(value: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let np = value.py().import("numpy")?;
    let array = np
        .call_method1("asarray", (value, "float64"))
        .map_err(|_| invalid(format!("parameter `{name}` must be a 1-D array of numbers")))?;
    let view: PyReadonlyArray1<f64> = array
        .extract()
        .map_err(|_| invalid(format!("parameter `{name}` must be a 1-D array of numbers")))?;
    Ok(view.as_array().to_vec())
}

#[pymethods]
impl PyRobot {
    /// A robot from keyword arguments shaped like a robot file's tables: `rod` (dict),
    /// `tendons` (list of dicts, the file's `[[tendon]]`), `loads`, `base`, `solver`
    /// (dicts). A tendon dict has `routing`, `tension` (N) or `displacement` (m), and
    /// optionally `end` (m), `stiffness` (N) and `free_length` (m). Raises `tdcr.FileError`
    /// (messages name the field, e.g. `tendon[2].tension`).
    #[new]
    #[pyo3(signature = (rod, tendons=None, loads=None, base=None, solver=None))]
    fn new(
        rod: &Bound<'_, PyAny>,
        tendons: Option<&Bound<'_, PyAny>>,
        loads: Option<&Bound<'_, PyAny>>,
        base: Option<&Bound<'_, PyAny>>,
        solver: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut doc = Table::new();
        for (key, value) in [
            ("rod", Some(rod)),
            ("tendon", tendons),
            ("loads", loads),
            ("base", base),
            ("solver", solver),
        ] {
            if let Some(v) = value.filter(|v| !v.is_none()) {
                doc.insert(key.into(), to_toml(v, key)?);
            }
        }
        parse_table(&doc, "<arguments>")
    }

    /// A robot from a dict of the robot file's tables (`{"rod": {...}, "tendon": [...],
    /// "loads": {...}, "base": {...}, "solver": {...}}`), e.g. `tomllib.load` of a file.
    #[staticmethod]
    fn from_dict(tables: &Bound<'_, PyDict>) -> PyResult<Self> {
        parse_table(&table(tables, "")?, "<dict>")
    }

    /// A robot from robot-file text (TOML, docs/robot-file.md); `name` is the file name in
    /// messages. Raises `tdcr.FileError` listing every problem as the command line does.
    #[staticmethod]
    #[pyo3(signature = (text, name="<string>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Self> {
        parse(text, name)
    }

    /// A robot from a robot file. Raises `tdcr.FileError` for a bad file and
    /// `tdcr.InvalidInput` when it cannot be read.
    #[staticmethod]
    fn from_file(path: std::path::PathBuf) -> PyResult<Self> {
        let shown = path.display().to_string();
        let text =
            std::fs::read_to_string(&path).map_err(|e| invalid(format!("cannot read robot file {shown}: {e}")))?;
        parse(&text, &shown)
    }

    /// The robot as robot-file text (TOML) that `Robot.from_toml` reads back to the same
    /// robot, bitwise. Raises `tdcr.InvalidInput` for a rod given by `shear_modulus`.
    fn to_toml(&self) -> PyResult<String> {
        document(&self.file)
    }

    /// Pickling goes through the robot file.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let text = document(&slf.get().file)?;
        Ok((slf.get_type().getattr("from_toml")?, (text,)))
    }

    /// A copy with the tensions (N) of all tendons, in file order; every tendon becomes
    /// tension-controlled (a displacement-controlled one drops its `displacement`).
    fn with_tensions(&self, tensions: Vec<f64>) -> PyResult<Self> {
        let count = self.file.robot.tendons.len();
        if tensions.len() != count {
            return Err(invalid(format!(
                "with_tensions got {} tension(s) for a robot with {count} tendon(s)",
                tensions.len()
            )));
        }
        let mut out = self.clone();
        for (t, &tau) in out.file.robot.tendons.iter_mut().zip(&tensions) {
            t.set_tension(tau);
        }
        out.file.robot.validate().map_err(to_py)?;
        Ok(out)
    }

    /// A copy with the actuator pull-ins q (m, positive pulls the tendon in) of all
    /// tendons, in file order: a number makes that tendon displacement-controlled (its
    /// tension is solved for, starting from the solver's estimate), None makes it
    /// tension-controlled at its current tension (0 for one that was displacement-controlled).
    /// E.g. `robot.with_displacements([s.tendons[0]["displacement"], None, None])`. Raises
    /// `tdcr.InvalidInput` for a wrong count or a pull-in the model rejects.
    fn with_displacements(&self, displacements: Vec<Option<f64>>) -> PyResult<Self> {
        let count = self.file.robot.tendons.len();
        if displacements.len() != count {
            return Err(invalid(format!(
                "with_displacements got {} displacement(s) for a robot with {count} tendon(s); give None for a tension-controlled tendon",
                displacements.len()
            )));
        }
        let mut out = self.clone();
        for (t, &q) in out.file.robot.tendons.iter_mut().zip(&displacements) {
            match (q, t.displacement()) {
                (Some(q), _) => {
                    t.set_displacement(q);
                }
                (None, Some(_)) => {
                    t.set_tension(0.0);
                }
                (None, None) => {}
            }
        }
        out.file.robot.validate().map_err(to_py)?;
        Ok(out)
    }

    /// A copy with named parameters set, e.g. `{"tension.1": 3.0, "tip_force.z": -0.1}`
    /// (the names of `tdcr batch` headers and of sweeps: `tension.I`, which makes tendon I
    /// tension-controlled, `tip_force.x|y|z`, `tip_moment.x|y|z`, `base_position.x|y|z`,
    /// `distributed_force.x|y|z`, `load_scale`, `youngs_modulus`; docs/parameters.md).
    fn with_parameters(&self, parameters: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut out = self.clone();
        for (key, value) in parameters.iter() {
            let name: String = key.extract().map_err(|_| invalid("parameter names must be strings"))?;
            let parameter: Parameter = name.parse().map_err(invalid)?;
            let value: f64 = value
                .extract()
                .map_err(|_| invalid(format!("parameter `{name}` must be a number")))?;
            out.set(&parameter, value)?;
        }
        out.file.robot.validate().map_err(to_py)?;
        Ok(out)
    }

    /// Rod length L (m).
    #[getter]
    fn length(&self) -> f64 {
        self.file.robot.length()
    }

    /// Number of tendons.
    #[getter]
    fn tendon_count(&self) -> usize {
        self.file.robot.tendons.len()
    }

    /// Tendon tensions (N), shape (k,), file order; for a displacement-controlled tendon
    /// the tension its solve starts from (0: the solver's estimate).
    #[getter]
    fn tensions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t: Vec<f64> = self.file.robot.tendons.iter().map(|t| t.tension()).collect();
        PyArray1::from_vec(py, t)
    }

    /// The actuator pull-ins q (m) of the displacement-controlled tendons, None for the
    /// tension-controlled ones: a list of k entries, file order.
    #[getter]
    fn displacements(&self) -> Vec<Option<f64>> {
        self.file.robot.tendons.iter().map(|t| t.displacement()).collect()
    }

    /// Axial stiffnesses E_t A_t (N) of the elastic tendons, None for the inextensible
    /// ones: a list of k entries, file order.
    #[getter]
    fn tendon_stiffnesses(&self) -> Vec<Option<f64>> {
        self.file.robot.tendons.iter().map(|t| t.stiffness).collect()
    }

    /// Free lengths (m) of tendon between the base and the actuator, shape (k,), file order
    /// (0 unless given; it stretches with the rest of an elastic tendon).
    #[getter]
    fn free_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let l: Vec<f64> = self.file.robot.tendons.iter().map(|t| t.free_length).collect();
        PyArray1::from_vec(py, l)
    }

    /// Tip force (N, world frame), shape (3,).
    #[getter]
    fn tip_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.file.robot.loads.tip_force.as_slice())
    }

    /// Tip moment (N m, world frame), shape (3,).
    #[getter]
    fn tip_moment<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.file.robot.loads.tip_moment.as_slice())
    }

    /// Base position p(0) (m, world frame), shape (3,).
    #[getter]
    fn base_position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.file.robot.base_position.as_slice())
    }

    /// Base rotation R(0), body to world, shape (3, 3).
    #[getter]
    fn base_rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        crate::solution::matrix(py, &self.file.robot.base_rotation)
    }

    /// The solver of the `[solver]` table: "collocation" or "shooting".
    #[getter]
    fn method(&self) -> String {
        self.file.solver.method.to_string()
    }

    fn __repr__(&self) -> String {
        let r = &self.file.robot;
        let inputs: Vec<String> = r
            .tendons
            .iter()
            .map(|t| match t.displacement() {
                None => format!("{} N", t.tension()),
                Some(q) => format!("q={q} m"),
            })
            .collect();
        format!(
            "Robot(length={} m, tendons={}, inputs=[{}], method={})",
            r.length(),
            r.tendons.len(),
            inputs.join(", "),
            self.file.solver.method
        )
    }
}

/// Parses a TOML table built from Python values.
fn parse_table(doc: &Table, name: &str) -> PyResult<PyRobot> {
    let text = toml::to_string(doc).map_err(|e| invalid(format!("cannot write the robot's tables as TOML: {e}")))?;
    parse(&text, name)
}
