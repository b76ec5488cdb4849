//! `tdcr.Robot`: a robot and its solver settings, always built by the robot-file parser
//! (`tdcr::io::parse`), whether from TOML text, a file, keyword arguments or a dict, and
//! written back as a robot file for pickling.

use crate::convert::Walk;
use crate::errors::{file_error, invalid, to_py};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::Parameter;
use tdcr::io::{RobotFile, SolverSettings};
use toml::Table;

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
/// docs/friction.md). `model` is the file's `[model]` table: `{"corner_forces": False}`
/// solves the paper's jump conditions, `{"tendons": "point_moment"}` the point-moment tendon
/// model, `{"rod": "kirchhoff"}` the inextensible, unshearable rod.
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
    /// The `[rod]` table as given, for a rod the library's writer cannot write back (one
    /// given by `shear_modulus` keeps no geometry); such a rod never changes afterwards (its
    /// Young's modulus cannot be set or fitted).
    pub given_rod: Option<Table>,
}

/// Parses robot-file text (`name` in messages) into a robot.
pub fn parse(text: &str, name: &str) -> PyResult<PyRobot> {
    let file = tdcr::io::parse(text, name).map_err(|e| file_error(&e))?;
    let given_rod = if file.robot.rod.geometry.is_none() {
        toml::from_str::<Table>(text)
            .ok()
            .and_then(|doc| doc.get("rod").and_then(toml::Value::as_table).cloned())
    } else {
        None
    };
    Ok(PyRobot { file, given_rod })
}

impl PyRobot {
    /// The robot file of this robot, which reads back to the same robot, bitwise: the
    /// library's writer, with the `[rod]` table as given for a rod it cannot write (written
    /// with a stand-in rod of the same length and reference strains, then replaced).
    ///
    /// # Errors
    /// `tdcr.InvalidInput` for a robot no robot file can hold.
    pub fn text(&self) -> PyResult<String> {
        let error = match self.file.to_toml() {
            Ok(text) => return Ok(text),
            Err(e) => e,
        };
        let Some(rod) = &self.given_rod else {
            return Err(to_py(error));
        };
        let mut stand_in = self.file.clone();
        let old = &self.file.robot.rod;
        // Any rod of geometry: its table is replaced below.
        stand_in.robot.rod = tdcr::Rod::tube(old.length, 1e-3, 0.0, 1e9, 0.3);
        stand_in.robot.rod.reference = old.reference.clone();
        let text = stand_in.to_toml().map_err(|_| to_py(error))?;
        let mut doc: Table =
            toml::from_str(&text).map_err(|e| invalid(format!("cannot read back the robot file written: {e}")))?;
        doc.insert("rod".into(), toml::Value::Table(rod.clone()));
        toml::to_string(&doc).map_err(|e| invalid(format!("cannot write the robot file: {e}")))
    }
}

/// A robot of the library with default solver settings, written as its robot file and
/// parsed back, so that it is exactly what `Robot.from_toml(robot.to_toml())` gives (the
/// library's compiled constants can differ from parsed ones in the last bit of a
/// stiffness: the compiler folds `powi` of constants differently).
pub fn from_library(robot: tdcr::Robot) -> PyResult<PyRobot> {
    let file = RobotFile {
        robot,
        solver: SolverSettings::default(),
        disks: None,
    };
    parse(&file.to_toml().map_err(to_py)?, "<tdcr.cases>")
}

/// The robots of a batch or sweep given as one robot and parameter columns (`{name:
/// array}`, names as in `tdcr batch` headers, every array 1-D of one length): row k is the
/// base robot with row k's values set. Rows are built when asked for, so a long batch does
/// not hold all its robots at once; the columns are the caller's float64 arrays themselves
/// (converted only when given as another type), read a chunk of rows at a time with the
/// GIL held ([`Rows::chunk`]), so that a batch holds no copy of its inputs.
pub struct Rows {
    base: tdcr::Robot,
    columns: Vec<(Parameter, Py<PyArray1<f64>>)>,
    count: usize,
}

/// The parameter values of a run of consecutive rows, copied from a batch's columns
/// ([`Rows::chunk`]) for worker threads that run without the GIL.
#[derive(Default)]
pub struct Chunk {
    /// The first row.
    start: usize,
    /// The number of rows.
    len: usize,
    /// Column-major: column c's value of row `start + i` at `c * len + i`.
    values: Vec<f64>,
}

impl Rows {
    /// Reads the columns and checks that the base robot has every parameter.
    pub fn new(base: &PyRobot, parameters: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut columns = Vec::new();
        let mut count = None;
        for (key, value) in parameters.iter() {
            let name: String = key.extract().map_err(|_| invalid("parameter names must be strings"))?;
            let parameter: Parameter = name.parse().map_err(invalid)?;
            parameter.check(&base.file.robot).map_err(to_py)?;
            let values = crate::convert::number_array(&value, &format!("parameter `{name}`"))?;
            let len = values.shape()[0];
            match count {
                Some(n) if n != len => {
                    return Err(invalid(format!(
                        "parameter `{name}` has {len} values but another has {n}: give every parameter one value per row"
                    )));
                }
                _ => count = Some(len),
            }
            columns.push((parameter, values.unbind()));
        }
        Ok(Rows {
            base: base.file.robot.clone(),
            columns,
            count: count.unwrap_or(0),
        })
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.count
    }

    /// The tendons with friction in some row (from 0), whose delivered tension a row of
    /// `solve_parameters` carries (`tdcr::io::row_outputs`, as `tdcr batch`).
    pub fn tendons_with_friction(&self) -> Vec<usize> {
        let parameters: Vec<Parameter> = self.columns.iter().map(|(p, _)| *p).collect();
        tdcr::io::row_outputs::RowOutputs::tendons_with_friction(&self.base, &parameters)
    }

    /// The rows as the library sweep's ranges (the values between rows interpolated
    /// linearly, where the sweep locates its events).
    ///
    /// # Errors
    /// As `Ranges::new` (not for rows `new` checked).
    pub fn ranges(&self, py: Python<'_>) -> PyResult<tdcr::analysis::sweep::Ranges> {
        let mut inputs = Vec::with_capacity(self.columns.len());
        for (p, values) in &self.columns {
            let values = values.bind(py).readonly().as_array().to_vec();
            inputs.push((tdcr::analysis::sweep::Input::Parameter(*p), values));
        }
        tdcr::analysis::sweep::Ranges::new(self.base.clone(), inputs).map_err(to_py)
    }

    /// The values of rows `range` (within `0..len()`), copied for [`Rows::robot`].
    pub fn chunk(&self, py: Python<'_>, range: std::ops::Range<usize>) -> Chunk {
        let mut values = Vec::with_capacity(self.columns.len() * range.len());
        for (_, column) in &self.columns {
            let column = column.bind(py).readonly();
            let view = column.as_array();
            values.extend(range.clone().map(|row| view[row]));
        }
        Chunk {
            start: range.start,
            len: range.len(),
            values,
        }
    }

    /// The robot of row `row`, one of `chunk`'s rows.
    ///
    /// # Errors
    /// As `Parameter::apply_all` (not for parameters `new` checked).
    pub fn robot(&self, chunk: &Chunk, row: usize) -> tdcr::Result<tdcr::Robot> {
        debug_assert!((chunk.start..chunk.start + chunk.len).contains(&row));
        let i = row - chunk.start;
        let mut robot = self.base.clone();
        let values = self
            .columns
            .iter()
            .enumerate()
            .map(|(c, (p, _))| (*p, chunk.values[c * chunk.len + i]));
        Parameter::apply_all(&mut robot, values)?;
        Ok(robot)
    }
}

#[pymethods]
impl PyRobot {
    /// A robot from keyword arguments shaped like a robot file's tables: `rod` (dict),
    /// `tendons` (list of dicts, the file's `[[tendon]]`), `loads`, `base`, `solver`,
    /// `model`, `disks` (dicts), or instead of `rod`, `segments` (list of dicts, the file's
    /// `[[segment]]`). A tendon dict has `routing`, `tension` (N) or `displacement` (m),
    /// and optionally `end` (m) or `end_segment`, `stiffness` (N), `free_length` (m),
    /// `friction` and `motion` (`"pull"` or `"release"`). Raises `tdcr.FileError`
    /// (messages name the field, e.g. `tendon[2].tension`).
    #[new]
    #[pyo3(signature = (rod=None, tendons=None, loads=None, base=None, solver=None, model=None, disks=None, segments=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rod: Option<&Bound<'_, PyAny>>,
        tendons: Option<&Bound<'_, PyAny>>,
        loads: Option<&Bound<'_, PyAny>>,
        base: Option<&Bound<'_, PyAny>>,
        solver: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, PyAny>>,
        disks: Option<&Bound<'_, PyAny>>,
        segments: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut doc = Table::new();
        for (key, value) in [
            ("rod", rod),
            ("segment", segments),
            ("tendon", tendons),
            ("loads", loads),
            ("base", base),
            ("solver", solver),
            ("model", model),
            ("disks", disks),
        ] {
            if let Some(v) = value.filter(|v| !v.is_none()) {
                doc.insert(key.into(), Walk::default().toml(v, key)?);
            }
        }
        parse_table(&doc, "<arguments>")
    }

    /// A robot from a dict of the robot file's tables (`{"rod": {...}, "tendon": [...],
    /// "loads": {...}, "base": {...}, "solver": {...}}`), e.g. `tomllib.load` of a file.
    #[staticmethod]
    fn from_dict(tables: &Bound<'_, PyDict>) -> PyResult<Self> {
        parse_table(&Walk::default().table(tables, "")?, "<dict>")
    }

    /// A robot from robot-file text (TOML, docs/robot-file.md); `name` is the file name in
    /// messages. Raises `tdcr.FileError` listing every problem as the command line does.
    #[staticmethod]
    #[pyo3(signature = (text, name="<string>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Self> {
        parse(text, name)
    }

    /// A robot from a robot file (a regular file of at most 16 MiB, read with the GIL
    /// released). Raises `tdcr.FileError` for a bad file and `tdcr.InvalidInput` when it
    /// cannot be read.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let shown = path.display().to_string();
        let text = py
            .detach(|| read_robot_file(&path))
            .map_err(|e| invalid(format!("cannot read robot file {shown}: {e}")))?;
        parse(&text, &shown)
    }

    /// The robot as robot-file text (TOML) that `Robot.from_toml` reads back to the same
    /// robot, bitwise (a rod given by `shear_modulus` as it was given).
    fn to_toml(&self) -> PyResult<String> {
        self.text()
    }

    /// Pickling goes through the robot file.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let text = slf.get().text()?;
        Ok((slf.get_type().getattr("from_toml")?, (text,)))
    }

    /// A copy with the tensions (N) of all tendons, in file order; every tendon becomes
    /// tension-controlled (a displacement-controlled one drops its `displacement`).
    fn with_tensions(&self, tensions: &Bound<'_, PyAny>) -> PyResult<Self> {
        let tensions = crate::convert::numbers(tensions, "with_tensions: `tensions`")?;
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
    fn with_displacements(&self, displacements: &Bound<'_, PyAny>) -> PyResult<Self> {
        let items = displacements
            .try_iter()
            .map_err(|_| invalid("with_displacements: give a sequence of pull-ins (m) and None, one per tendon"))?;
        let displacements: Vec<Option<f64>> = items
            .enumerate()
            .map(|(i, q)| crate::convert::optional_number(Some(&q?), &format!("with_displacements: item {i}")))
            .collect::<PyResult<_>>()?;
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
    /// `distributed_force.x|y|z`, `load_scale`, `youngs_modulus`, `friction.I`, tendon I's
    /// friction coefficient; docs/parameters.md).
    fn with_parameters(&self, parameters: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut out = self.clone();
        let mut set = Vec::with_capacity(parameters.len());
        for (key, value) in parameters.iter() {
            let name: String = key.extract().map_err(|_| invalid("parameter names must be strings"))?;
            let parameter: Parameter = name.parse().map_err(invalid)?;
            let value = crate::convert::number(&value, &format!("parameter `{name}`"))?;
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

    /// Friction coefficients mu of the tendons with friction in their channels, None for the
    /// others: a list of k entries, file order (docs/friction.md).
    #[getter]
    fn frictions(&self) -> Vec<Option<f64>> {
        self.file
            .robot
            .tendons
            .iter()
            .map(|t| t.friction.map(|f| f.coefficient))
            .collect()
    }

    /// The motion each tendon with friction models in full slip, "pull" or "release", None
    /// for the others: a list of k entries, file order (a load history decides its own).
    #[getter]
    fn motions(&self) -> Vec<Option<&'static str>> {
        self.file
            .robot
            .tendons
            .iter()
            .map(|t| t.friction.map(|f| f.motion.name()))
            .collect()
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

    /// The model variant, as the file's `[model]` table: `corner_forces` (bool), `tendons`
    /// ("coupled" or "point_moment") and `rod` ("cosserat" or "kirchhoff").
    #[getter]
    fn model<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.file.robot;
        let tendons = match r.tendon_model {
            tdcr::TendonModel::Coupled => "coupled",
            tdcr::TendonModel::PointMoment => "point_moment",
        };
        let out = PyDict::new(py);
        out.set_item("corner_forces", r.corner_forces)?;
        out.set_item("tendons", tendons)?;
        let rod = match r.rod_model {
            tdcr::RodModel::Cosserat => "cosserat",
            tdcr::RodModel::Kirchhoff => "kirchhoff",
        };
        out.set_item("rod", rod)?;
        Ok(out)
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

/// The largest robot file read: far above any robot's (a few kilobytes), far below what
/// would exhaust memory (a device such as /dev/zero never ends).
const MAX_FILE_BYTES: u64 = 16 << 20;

/// The text of the robot file at `path`: only a regular file (a FIFO would block until a
/// writer came, a device might never end), at most [`MAX_FILE_BYTES`].
fn read_robot_file(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("it is not a regular file (a directory, FIFO, socket or device)".into());
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!(
            "it has {} bytes, more than the {MAX_FILE_BYTES} a robot file may have",
            meta.len()
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut text = String::new();
    // The file may grow after the check: read one byte past the limit at most.
    file.take(MAX_FILE_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(|e| e.to_string())?;
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(format!(
            "it has more than the {MAX_FILE_BYTES} bytes a robot file may have"
        ));
    }
    Ok(text)
}

/// Parses a TOML table built from Python values.
fn parse_table(doc: &Table, name: &str) -> PyResult<PyRobot> {
    let text = toml::to_string(doc).map_err(|e| invalid(format!("cannot write the robot's tables as TOML: {e}")))?;
    parse(&text, name)
}
