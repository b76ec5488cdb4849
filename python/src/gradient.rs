//! Gradients for PyTorch and JAX: `tdcr.linearize` solves a batch of rows (one robot with
//! parameter columns, as `solve_parameters`) and keeps the solutions; its `vjp` gives the
//! gradient of a loss with respect to the parameter columns from a cotangent on the outputs,
//! by the adjoint of the library (`tdcr::collocation::sensitivity::Adjoint`, one transposed
//! solve per row). The Python modules `tdcr.torch` and `tdcr.jax` wrap it (docs/python.md).

use crate::boundary::{self, Failure};
use crate::convert;
use crate::errors::invalid;
use crate::options::{self, Use};
use crate::robot::{PyRobot, Rows};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::collocation::sensitivity::{Adjoint, Cotangent, rotation_cotangent};
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Parameter, Robot, Solution, collocation};

/// Solved rows ready for gradients: `linearize(robot, parameters, samples=None, **options)`.
///
/// Attributes: `parameter_names` (the columns, in the order of the gradient's columns),
/// `samples` (the arc lengths of the backbone points, m), `tip_position` (M, 3, m),
/// `tip_rotation` (M, 3, 3, body to world), `points` (M, K, 3, m: p at each sample).
/// `vjp(tip_position=None, tip_rotation=None, points=None)` -> (M, P) array: for cotangents
/// dloss/dy of those shapes (None: zero), dloss/dq for each row and parameter column (per N,
/// per Pa, ...). Each call re-linearizes every row (one Jacobian assembly, factorization
/// and transposed solve per row, on all cores).
#[pyclass(module = "tdcr._native", name = "Linearization", frozen)]
pub struct PyLinearization {
    robots: Vec<Robot>,
    solutions: Vec<Solution>,
    parameters: Vec<Parameter>,
    samples: Vec<f64>,
}

/// The cotangent of row `row` from the flat arrays (None: zero).
fn cotangent(
    row: usize,
    samples: usize,
    position: &[f64],
    rotation: &[f64],
    points: &[f64],
    orientation: &Matrix3<f64>,
) -> Cotangent {
    let at3 = |a: &[f64], i: usize| {
        if a.is_empty() {
            Vector3::zeros()
        } else {
            Vector3::from_column_slice(&a[3 * i..3 * i + 3])
        }
    };
    let tip_rotation = if rotation.is_empty() {
        Vector3::zeros()
    } else {
        // Row major (3, 3), as numpy gives it.
        rotation_cotangent(orientation, &Matrix3::from_row_slice(&rotation[9 * row..9 * row + 9]))
    };
    Cotangent {
        tip_position: at3(position, row),
        tip_rotation,
        points: (0..samples).map(|j| at3(points, row * samples + j)).collect(),
    }
}

impl PyLinearization {
    /// A cotangent argument flattened, checked to hold `count` numbers (shape `shape`); empty
    /// for None.
    fn flat(value: Option<&Bound<'_, PyAny>>, name: &str, count: usize, shape: &str) -> PyResult<Vec<f64>> {
        let Some(value) = value.filter(|v| !v.is_none()) else {
            return Ok(Vec::new());
        };
        let np = value.py().import("numpy")?;
        let flat = np.call_method1("ravel", (np.call_method1("asarray", (value, "float64"))?,))?;
        let values = convert::numbers(&flat, &format!("vjp: `{name}`"))?;
        if values.len() != count {
            return Err(invalid(format!(
                "vjp: `{name}` has {} numbers; give an array of shape {shape}",
                values.len()
            )));
        }
        Ok(values)
    }
}

#[pymethods]
impl PyLinearization {
    /// The parameter columns, in the order of the gradient's columns.
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        self.parameters.iter().map(ToString::to_string).collect()
    }

    /// Arc lengths of the sampled backbone points (m).
    #[getter]
    fn samples<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.samples.clone()).into_pyarray(py)
    }

    /// Tip positions (M, 3), m, world frame.
    #[getter]
    fn tip_position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let s = &self.solutions;
        Array2::from_shape_fn((s.len(), 3), |(i, k)| s[i].tip_position()[k]).into_pyarray(py)
    }

    /// Tip orientations (M, 3, 3), body to world.
    #[getter]
    fn tip_rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let s = &self.solutions;
        Array3::from_shape_fn((s.len(), 3, 3), |(i, r, c)| s[i].tip().R[(r, c)]).into_pyarray(py)
    }

    /// Backbone points p(s_j) (M, K, 3), m, world frame (the solution's interpolant).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let (s, x) = (&self.solutions, &self.samples);
        Array3::from_shape_fn((s.len(), x.len(), 3), |(i, j, k)| s[i].at(x[j]).p[k]).into_pyarray(py)
    }

    /// dloss/dq (M, P) for cotangents on the outputs (class docs).
    #[pyo3(signature = (tip_position=None, tip_rotation=None, points=None))]
    fn vjp<'py>(
        &self,
        py: Python<'py>,
        tip_position: Option<&Bound<'py, PyAny>>,
        tip_rotation: Option<&Bound<'py, PyAny>>,
        points: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (m, k) = (self.solutions.len(), self.samples.len());
        let position = Self::flat(tip_position, "tip_position", m * 3, &format!("({m}, 3)"))?;
        let rotation = Self::flat(tip_rotation, "tip_rotation", m * 9, &format!("({m}, 3, 3)"))?;
        let points = Self::flat(points, "points", m * k * 3, &format!("({m}, {k}, 3)"))?;
        let width = self.parameters.len();
        let mut out = Array2::<f64>::zeros((m, width));
        boundary::rows(
            py,
            m,
            |row| {
                let solution = &self.solutions[row];
                let cot = cotangent(row, k, &position, &rotation, &points, &solution.tip().R);
                let mut adjoint = Adjoint::new(&self.robots[row], solution, &self.samples)?;
                Ok(adjoint.gradient(&cot, &self.parameters)?)
            },
            |row, result| {
                let gradient = result.map_err(|f| f.into_py_at(py, &format!("vjp: row {row} (from 0)"), row))?;
                for (j, g) in gradient.into_iter().enumerate() {
                    out[(row, j)] = g;
                }
                Ok(())
            },
        )?;
        Ok(out.into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        format!(
            "Linearization({} rows, parameters {:?}, {} backbone samples)",
            self.solutions.len(),
            self.parameter_names(),
            self.samples.len()
        )
    }
}

/// linearize(robot, parameters, samples=None, **options) -> Linearization
///
/// Solves the rows of `robot` with `parameters` (a dict of 1-D arrays of one length M, named
/// as `tdcr batch` columns: `tension.1`, `displacement.2`, `tip_force.z`,
/// `distributed_force.y`, `youngs_modulus`, `routing.1.x`, ...) on all cores, and keeps the
/// solutions for gradients with respect to those columns (`Linearization.vjp`). `samples`:
/// arc lengths (m) of backbone points to output (default none). Options as `solve_batch`
/// (collocation). Displacement-controlled tendons keep their pull-ins in the gradient (their
/// tensions follow); tendons with friction are refused. Raises the first failed row's
/// error, its message starting with the row.
#[pyfunction]
#[pyo3(signature = (robot, parameters, samples=None, **options))]
pub fn linearize(
    py: Python<'_>,
    robot: &PyRobot,
    parameters: &Bound<'_, PyDict>,
    samples: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyLinearization> {
    let rows = Rows::new(robot, parameters)?;
    let mut names = Vec::new();
    for key in parameters.keys() {
        let name: String = key.extract()?;
        names.push(name.parse::<Parameter>().map_err(invalid)?);
    }
    let settings = options::apply(&robot.file.solver, options, Use::Collocation("linearize"))?;
    let samples = match samples.filter(|s| !s.is_none()) {
        Some(s) => convert::numbers(s, "linearize: `samples`")?,
        None => Vec::new(),
    };
    let length = robot.file.robot.length();
    if let Some(s) = samples.iter().find(|s| !(s.is_finite() && (0.0..=length).contains(*s))) {
        return Err(invalid(format!(
            "linearize: `samples` has the arc length {s} m, outside the rod [0, {length}] m; give arc lengths between 0 and the rod length"
        )));
    }
    let mut robots = Vec::with_capacity(rows.len());
    let mut solutions = Vec::with_capacity(rows.len());
    boundary::rows_with(
        py,
        rows.len(),
        |range| rows.chunk(py, range),
        || (),
        |(), chunk, row| -> Result<(Robot, Solution), Failure> {
            let r = rows.robot(chunk, row)?;
            let s = collocation::solve(&r, &settings.collocation)?;
            Ok((r, s))
        },
        |row, result| {
            let (r, s) = result.map_err(|f| f.into_py_at(py, &format!("linearize: row {row} (from 0)"), row))?;
            robots.push(r);
            solutions.push(s);
            Ok(())
        },
    )?;
    Ok(PyLinearization {
        robots,
        solutions,
        parameters: names,
        samples,
    })
}
