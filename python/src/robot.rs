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
/// for an elastic tendon `stiffness` (E_t A_t, N) and `free_length` (m), and `friction`
/// (the coefficient in its channels) with `motion` (`"pull"` or `"release"`,
/// docs/friction.md).
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

/// A robot of the library with default solver settings, written as its robot file and
/// parsed back, so that it is exactly what `Robot.from_toml(robot.to_toml())` gives (the
/// library's compiled constants can differ from parsed ones in the last bit of a
/// stiffness: the compiler folds `powi` of constants differently).
pub fn from_library(robot: tdcr::Robot) -> PyResult<PyRobot> {
    let file = RobotFile {
        robot,
        solver: SolverSettings::default(),
    };
    parse(&file.to_toml().map_err(to_py)?, "<tdcr.cases>")
}

/// Parameter names and their values as read from a dict of equal-length 1-D arrays.
type Columns = Vec<(Parameter, Vec<f64>)>;

/// Reads `{name: array}` (names as in `tdcr batch` headers); every array 1-D of one length.
fn columns(parameters: &Bound<'_, PyDict>) -> PyResult<(Columns, usize)> {
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

/// One robot per row of `parameters` (a dict of equal-length 1-D arrays, [`columns`]):
/// `base` with that row's values set.
pub fn robots_of(base: &PyRobot, parameters: &Bound<'_, PyDict>) -> PyResult<Vec<tdcr::Robot>> {
    let (cols, n) = columns(parameters)?;
    let mut out = Vec::with_capacity(n);
    for row in 0..n {
        let mut robot = base.file.robot.clone();
        Parameter::apply_all(&mut robot, cols.iter().map(|(p, values)| (*p, values[row]))).map_err(to_py)?;
        out.push(robot);
    }
    Ok(out)
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
    /// optionally `end` (m), `stiffness` (N), `free_length` (m), `friction` and `motion`
    /// (`"pull"` or `"release"`). Raises `tdcr.FileError`
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
        self.file.to_toml().map_err(to_py)
    }

    /// Pickling goes through the robot file.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let text = slf.get().file.to_toml().map_err(to_py)?;
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
        let mut set = Vec::with_capacity(parameters.len());
        for (key, value) in parameters.iter() {
            let name: String = key.extract().map_err(|_| invalid("parameter names must be strings"))?;
            let parameter: Parameter = name.parse().map_err(invalid)?;
            let value: f64 = value
                .extract()
                .map_err(|_| invalid(format!("parameter `{name}` must be a number")))?;
            set.push((parameter, value));
        }
        Parameter::apply_all(&mut out.file.robot, set).map_err(to_py)?;
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
