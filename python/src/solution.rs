//! `tdcr.Solution` and `tdcr.State`: the library's solved shape seen
//! as numpy arrays, and the solution's JSON round trip.

use crate::errors::{invalid, to_py};
use crate::report::{PySolveReport, termination_name};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Solution, TendonState};

/// A 3x3 matrix as a (3, 3) array.
pub fn matrix<'py>(py: Python<'py>, m: &Matrix3<f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((3, 3), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// 3-vectors as an (N, 3) array.
pub fn vectors<'py>(py: Python<'py>, v: impl ExactSizeIterator<Item = Vector3<f64>>) -> Bound<'py, PyArray2<f64>> {
    let n = v.len();
    let flat: Vec<f64> = v.flat_map(|x| [x.x, x.y, x.z]).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((n, 3), flat)
        .expect("n rows of 3")
        .into_pyarray(py)
}

/// A solved shape: the nodes along the backbone (two at every jump: left then right limit),
/// the tendon paths and states, the tip pose, the scheme's interpolant (`at`) and the
/// `report`. Arrays
/// are float64, SI units, world frame unless said otherwise; each access returns a new array.
#[pyclass(module = "tdcr", name = "Solution", frozen)]
#[derive(Clone)]
pub struct PySolution {
    /// The library's solution.
    pub solution: Solution,
}

/// The state at one arc length, from `Solution.at(s)`.
#[pyclass(module = "tdcr", name = "State", frozen, get_all)]
#[allow(non_snake_case)]
pub struct PyState {
    /// Arc length (m).
    s: f64,
    /// Position (m), world frame, (3,).
    p: Py<PyArray1<f64>>,
    /// Orientation, body to world, (3, 3).
    R: Py<PyArray2<f64>>,
    /// Shear/extension strain, body frame, (3,).
    v: Py<PyArray1<f64>>,
    /// Curvature/twist, body frame (rad/m), (3,).
    u: Py<PyArray1<f64>>,
}

crate::pickle::pickled_fields! {
    PyState { s, p, R, v, u }

    fn __repr__(&self) -> String {
        format!("State(s={} m)", self.s)
    }
}

#[pymethods]
impl PySolution {
    /// Arc lengths of the nodes (m), shape (N,), non-decreasing from 0 to L.
    #[getter]
    fn s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let s: Vec<f64> = self.solution.nodes.iter().map(|n| n.s).collect();
        PyArray1::from_vec(py, s)
    }

    /// Centreline positions (m), shape (N, 3).
    #[getter]
    fn p<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.p))
    }

    /// Orientations, body to world, shape (N, 3, 3).
    #[getter]
    #[allow(non_snake_case)]
    fn R<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let nodes = &self.solution.nodes;
        Array3::from_shape_fn((nodes.len(), 3, 3), |(k, i, j)| nodes[k].R[(i, j)]).into_pyarray(py)
    }

    /// Shear/extension strains v (body frame, dimensionless), shape (N, 3).
    #[getter]
    fn v<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.v))
    }

    /// Curvature/twist u (body frame, rad/m), shape (N, 3).
    #[getter]
    fn u<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.u))
    }

    /// Internal forces n (N, world frame), shape (N, 3).
    #[getter]
    fn n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.n))
    }

    /// Internal moments m (N m, world frame), shape (N, 3).
    #[getter]
    fn m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.m))
    }

    /// Each tendon's path p + R r_i (m, world frame) at the nodes up to its end: a list of
    /// (N_i, 3) arrays, file order.
    #[getter]
    fn tendon_paths<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray2<f64>>> {
        self.solution
            .tendon_paths
            .iter()
            .map(|path| vectors(py, path.iter().copied()))
            .collect()
    }

    /// What the solution says about each tendon, file order: a list of dicts with
    /// `tension` (N, at the base entry: the input of a tension-controlled tendon, the solved
    /// one of a displacement-controlled tendon, 0 when slack), `delivered_tension` (N, at the
    /// termination: lower than `tension` when friction holds the tendon back,
    /// docs/friction.md), `displacement` (m: the actuator's
    /// pull-in, the input of a displacement-controlled tendon, for a tension-controlled one
    /// the pull-in that holds it taut at its tension), `length` (m, the path length from the
    /// base to the termination), `reference_length` (m, the same in the unloaded shape) and
    /// `slack` (m, 0 when taut). docs/actuation.md has the definitions.
    #[getter]
    fn tendons<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.solution.tendons.iter().map(|t| tendon_dict(py, t)).collect()
    }

    /// Each tendon's tension (N) at the points of its path (`tendon_paths`), file order:
    /// constant without friction, varying along the tendon with it (docs/friction.md).
    #[getter]
    fn tendon_tensions<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray1<f64>>> {
        self.solution
            .tendon_tensions
            .iter()
            .map(|t| PyArray1::from_slice(py, t))
            .collect()
    }

    /// Tendon tensions (N), shape (k,), file order (the `tension` of `tendons`).
    #[getter]
    fn tensions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.solution.tensions())
    }

    /// Tip position (m), shape (3,).
    #[getter]
    fn tip_position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.solution.tip_position().as_slice())
    }

    /// Tip orientation, body to world, shape (3, 3).
    #[getter]
    fn tip_rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.solution.tip().R)
    }

    /// Backbone length L (m).
    #[getter]
    fn length(&self) -> f64 {
        self.solution.length()
    }

    /// How the solve went (a `SolveReport`).
    #[getter]
    fn report(&self) -> PySolveReport {
        PySolveReport {
            report: self.solution.report.clone(),
        }
    }

    /// The state (s, p, R, v, u) at arc length `s` (m, clamped to [0, L]) from the scheme's
    /// cubic Hermite interpolant on SO(3); at a jump the right limit (`left=True`: the left).
    #[pyo3(signature = (s, left=false))]
    fn at(&self, py: Python<'_>, s: &Bound<'_, PyAny>, left: bool) -> PyResult<PyState> {
        let s = crate::convert::number(s, "Solution.at: `s`")?;
        if !s.is_finite() {
            return Err(invalid(format!("Solution.at: s = {s} m is not finite")));
        }
        let x = self.solution.at_limit(s, left);
        Ok(PyState {
            s: x.s,
            p: PyArray1::from_slice(py, x.p.as_slice()).unbind(),
            R: matrix(py, &x.R).unbind(),
            v: PyArray1::from_slice(py, x.v.as_slice()).unbind(),
            u: PyArray1::from_slice(py, x.u.as_slice()).unbind(),
        })
    }

    /// The tension (N) of tendon `i` (from 0, as `tendons`) at arc length `s` (m, clamped to
    /// the tendon's span): between the points of its path interpolated linearly in the
    /// logarithm of the tension, exact where the path turns at a constant rate
    /// (`tdcr::Solution::tension_at`, docs/friction.md). Without friction, its tension.
    fn tension_at(&self, i: &Bound<'_, PyAny>, s: &Bound<'_, PyAny>) -> PyResult<f64> {
        let i = crate::convert::count(i, "Solution.tension_at: `i`")?;
        let s = crate::convert::number(s, "Solution.tension_at: `s`")?;
        if !s.is_finite() {
            return Err(invalid(format!("Solution.tension_at: s = {s} m is not finite")));
        }
        let k = self.solution.tendons.len();
        if i >= k {
            return Err(invalid(format!(
                "Solution.tension_at: i = {i}, but the solution has {k} tendon(s), numbered 0 to {} as in `tendons`",
                k.saturating_sub(1)
            )));
        }
        // None only for a tendon without path points: its one tension is the answer.
        Ok(self
            .solution
            .tension_at(i, s)
            .unwrap_or(self.solution.tendons[i].tension))
    }

    /// plot(ax=None, *, tendons=True, label=None) -> Axes
    ///
    /// Draws the shape with matplotlib (the `plot` extra): `tdcr.plot(self, ...)`.
    #[pyo3(signature = (ax=None, **kwargs))]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<&Bound<'py, PyAny>>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let plot = slf.py().import("tdcr.plotting")?.getattr("plot")?;
        plot.call((slf, ax), kwargs)
    }

    /// The whole solution as the solution JSON of `tdcr solve --format json` (every node
    /// with its derivatives, the tendon paths and states, the report; docs/cli.md), without
    /// the keys that need the robot (`end`, `turns`, `jacobian`); `Solution.from_json` reads
    /// it back to the same solution, bitwise.
    fn to_json(&self) -> String {
        tdcr::io::output::solution_json(&self.solution)
    }

    /// Reads a solution JSON: `Solution.to_json`'s or the file `tdcr solve --format json`
    /// wrote. Raises `tdcr.InvalidInput` naming what is wrong.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Ok(PySolution {
            solution: tdcr::io::parse_solution(text).map_err(to_py)?,
        })
    }

    /// Pickling goes through the JSON.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        Ok((
            slf.get_type().getattr("from_json")?,
            (tdcr::io::output::solution_json(&slf.get().solution),),
        ))
    }

    fn __repr__(&self) -> String {
        let p = self.solution.tip_position();
        format!(
            "Solution(nodes={}, tip=[{:.9}, {:.9}, {:.9}] m, {}, {})",
            self.solution.nodes.len(),
            p.x,
            p.y,
            p.z,
            termination_name(self.solution.report.termination),
            self.solution.report.stability.verdict()
        )
    }
}

/// A tendon state as the dict of `Solution.tendons`.
fn tendon_dict<'py>(py: Python<'py>, t: &TendonState) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("tension", t.tension)?;
    d.set_item("delivered_tension", t.delivered_tension)?;
    d.set_item("displacement", t.displacement)?;
    d.set_item("length", t.length)?;
    d.set_item("reference_length", t.reference_length)?;
    d.set_item("slack", t.slack)?;
    Ok(d)
}
