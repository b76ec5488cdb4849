//! Sweeps and traces: `tdcr::analysis::sweep::sweep` (robots solved in order, with the
//! events between steps) and `tdcr::collocation::trace` (a branch of equilibria in one
//! input), with numpy out.

use crate::boundary;
use crate::convert::number;
use crate::errors::to_py;
use crate::options::Use;
use crate::robot::{PyRobot, Rows};
use crate::solution::PySolution;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use tdcr::analysis::sweep::{Event, Kind, Step, Sweep, SweepSolver};

/// (n, 3) rows of tip positions.
pub(crate) fn tip_rows<'py>(py: Python<'py>, tips: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((tips.len(), 3), |(i, k)| tips[i][k]).into_pyarray(py)
}

/// Step `index` (negative from the end, as Python's) of the `n` solutions of a sweep or a
/// history (`what`), or `IndexError` naming the range.
pub(crate) fn step_item<'py>(
    py: Python<'py>,
    solutions: &Py<PyList>,
    n: usize,
    index: isize,
    what: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let n = n as isize;
    let k = if index < 0 { index + n } else { index };
    if !(0..n).contains(&k) {
        return Err(pyo3::exceptions::PyIndexError::new_err(format!(
            "{what} step {index} out of range: the {what} has {n} steps"
        )));
    }
    solutions.bind(py).get_item(k as usize)
}

/// An event of a sweep or a trace, located to 1e-6 of the range.
#[pyclass(module = "tdcr", name = "Event", frozen, get_all)]
pub struct PyEvent {
    /// `snap`, `bifurcation`, `taut` or `slack` (a sweep); `fold` or `bifurcation` (a trace).
    kind: String,
    /// The swept or traced input's value at the event (None when a sweep holds every input).
    value: Option<f64>,
    /// The input, e.g. `tension.5`.
    parameter: Option<String>,
    /// A sweep's step (from 0) at which the event is reported, the first step past it; None
    /// in a trace.
    step: Option<usize>,
    /// The event in words, as `tdcr sweep`'s `event` column and `tdcr trace` say it.
    text: String,
}

crate::pickle::pickled_fields! {
    PyEvent { kind, value, parameter, step, text }

    fn __repr__(&self) -> String {
        format!("Event({})", self.text)
    }

    fn __str__(&self) -> String {
        self.text.clone()
    }
}

impl PyEvent {
    /// A sweep's event, reported at `step`.
    fn of_sweep(e: &Event, step: usize) -> Self {
        PyEvent {
            kind: e.kind.name().to_string(),
            value: e.value.map(|(_, v)| v),
            parameter: e.value.map(|(p, _)| p.to_string()),
            step: Some(step),
            text: e.to_string(),
        }
    }
}

/// The result of `sweep`: every step's solution and the events located between steps.
/// It is also the sequence of the solutions (`len`, indexing, iteration).
#[pyclass(module = "tdcr", name = "Sweep", frozen)]
pub struct PySweep {
    solutions: Py<PyList>,
    events: Vec<Py<PyEvent>>,
    jumps: Vec<usize>,
    tips: Vec<[f64; 3]>,
}

impl PySweep {
    fn new(py: Python<'_>, steps: Vec<Step>) -> PyResult<Self> {
        let solutions = PyList::empty(py);
        let (mut events, mut jumps, mut tips) = (Vec::new(), Vec::new(), Vec::new());
        for (k, step) in steps.into_iter().enumerate() {
            if step.events.iter().any(|e| matches!(e.kind, Kind::Snap { .. })) {
                jumps.push(k);
            }
            for e in &step.events {
                events.push(Py::new(py, PyEvent::of_sweep(e, k))?);
            }
            let p = step.solution.tip_position();
            tips.push([p.x, p.y, p.z]);
            solutions.append(PySolution {
                solution: step.solution,
            })?;
        }
        Ok(PySweep {
            solutions: solutions.unbind(),
            events,
            jumps,
            tips,
        })
    }
}

crate::pickle::pickled_fields! {
    PySweep { solutions, events, jumps, tips }

    /// The solutions, one per step solved, in order.
    #[getter]
    fn solutions(&self, py: Python<'_>) -> Py<PyList> {
        self.solutions.clone_ref(py)
    }

    /// The events located between the steps, in order (`Event`: `kind` `snap`,
    /// `bifurcation`, `taut` or `slack`, the input's `value` there, the `step` it is
    /// reported at, the `text` of `tdcr sweep`'s `event` column).
    #[getter]
    fn events(&self, py: Python<'_>) -> Vec<Py<PyEvent>> {
        self.events.iter().map(|e| e.clone_ref(py)).collect()
    }

    /// The steps (from 0) reached by a snap: the tip jumped off the branch it was on.
    #[getter]
    fn jumps(&self) -> Vec<usize> {
        self.jumps.clone()
    }

    /// Tip positions (m, world frame), shape (n, 3).
    #[getter]
    fn tip_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        tip_rows(py, &self.tips)
    }

    fn __len__(&self) -> usize {
        self.tips.len()
    }

    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        step_item(py, &self.solutions, self.tips.len(), index, "sweep")
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyIterator>> {
        self.solutions.bind(py).try_iter()
    }
}

/// sweep(robot, parameters, **options) -> Sweep
///
/// Solves the rows of `parameters` (a dict of 1-D arrays, names as `solve_batch`) in
/// order with the library's sweep, as `tdcr sweep` does: each step warm-started from the
/// last (`tdcr::solve_from`, so every step's stability verdict is its own), and the events
/// between steps located to 1e-6 of the range by bisection (a snap off the branch, a
/// bifurcation, displacement-controlled tendons going taut or slack); collocation. A failure is raised with `index` set to its row and
/// `partial` to the `Sweep` of the rows before it. Ctrl-C stops it within about 0.1 s
/// with `KeyboardInterrupt`, whose `completed` and `partial` say the same of the rows
/// finished.
#[pyfunction]
#[pyo3(signature = (robot, parameters, **options))]
pub fn sweep(
    py: Python<'_>,
    robot: &PyRobot,
    parameters: &Bound<'_, PyDict>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySweep> {
    let settings = crate::options::apply(&robot.file.solver, options, Use::Collocation("sweep"))?;
    let rows = Rows::new(robot, parameters)?;
    if rows.len() == 0 {
        return PySweep::new(py, Vec::new());
    }
    let ranges = rows.ranges(py)?;
    let mut sweep = Sweep::new(&ranges, SweepSolver::Collocation(settings.collocation), None);
    let mut steps = Vec::new();
    let mut failure = None;
    let run = boundary::steps(py, || match boundary::caught(|| sweep.step().transpose()) {
        Ok(Some(step)) => {
            steps.push(step);
            true
        }
        Ok(None) => false,
        Err(e) => {
            failure = Some((steps.len(), e));
            false
        }
    });
    let done = steps.len();
    let result = PySweep::new(py, steps)?;
    if let Err(e) = run {
        return Err(boundary::with_partial(py, e, done, Bound::new(py, result)?.into_any()));
    }
    match failure {
        None => Ok(result),
        Some((i, e)) => {
            let err = e.into_py_at(py, "", i);
            err.value(py).setattr("partial", Py::new(py, result)?)?;
            Err(err)
        }
    }
}

/// The result of `trace`: the points of a branch of equilibria in the order the branch
/// passes them.
#[pyclass(module = "tdcr", name = "Trace", frozen, get_all)]
pub struct PyTrace {
    /// The input traced, e.g. `tension.1`.
    parameter: String,
    /// Its value at every point (N, N/m, or the load scale), shape (n,).
    values: Py<PyArray1<f64>>,
    /// Tip positions (m, world frame), shape (n, 3).
    tip_positions: Py<PyArray2<f64>>,
    /// Unstable directions at every point: 0 stable, more unstable, None unknown.
    unstable_directions: Vec<Option<usize>>,
    /// "stable", "unstable" or "unknown" at every point.
    stability: Vec<String>,
    /// Whether the branch turns back at each point (a fold).
    fold: Vec<bool>,
    /// Parameter values of the folds, located to 1e-6 of the range.
    folds: Vec<f64>,
    /// Parameter values where the number of unstable directions changed without a fold,
    /// located to 1e-6 of the range.
    bifurcations: Vec<f64>,
    /// The folds and bifurcations in the order the branch passes them (`Event`: `kind`
    /// `fold` or `bifurcation`, `value` located to 1e-6 of the range).
    events: Vec<Py<PyEvent>>,
    /// None when the branch reached the last value (or turned back past the first); else
    /// why it stopped (the points up to there are kept).
    stopped: Option<String>,
    /// Iterations (Newton and chord) of the whole trace, the start's solve included.
    iterations: usize,
}

crate::pickle::pickled_fields! {
    PyTrace {
        parameter, values, tip_positions, unstable_directions, stability, fold, folds,
        bifurcations, events, stopped, iterations,
    }
}

/// trace(robot, parameter, start, stop, **options) -> Trace
///
/// Follows the branch of equilibria through the default solve's state at `parameter` =
/// `start` as it goes to `stop`, through folds, with the stability of every point
/// (`tdcr::collocation::trace`, as `tdcr trace`). `parameter` is `tension.I` (I from 1),
/// `tip_force.x|y|z`, `distributed_force.x|y|z` or `load_scale`; options as `solve`
/// (collocation). The GIL is released while tracing; Ctrl-C stops it before the next
/// continuation step with `KeyboardInterrupt`, whose `completed` is the number of points
/// and `partial` the `Trace` so far.
#[pyfunction]
#[pyo3(signature = (robot, parameter, start, stop, **options))]
pub fn trace(
    py: Python<'_>,
    robot: &PyRobot,
    parameter: &str,
    start: &Bound<'_, PyAny>,
    stop: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyTrace> {
    let (start, stop) = (number(start, "trace: `start`")?, number(stop, "trace: `stop`")?);
    let settings = crate::options::apply(&robot.file.solver, options, Use::Collocation("trace"))?;
    let r = &robot.file.robot;
    let p = tdcr::Parameter::parse(parameter, r).map_err(to_py)?;
    let (t, signal) = boundary::stoppable(py, |asked| {
        tdcr::collocation::trace_until(r, p, start, stop, &settings.collocation, asked)
    })?;
    let tips: Vec<[f64; 3]> = t.points.iter().map(|q| q.tip_position.into()).collect();
    let values: Vec<f64> = t.points.iter().map(|q| q.value).collect();
    let values_len = values.len();
    let name = t.parameter.to_string();
    let events = t
        .events
        .iter()
        .map(|e| {
            let text = format!("{} at {name} = {}", e.kind(), tdcr::Readable(e.value()));
            Py::new(
                py,
                PyEvent {
                    kind: e.kind().to_string(),
                    value: Some(e.value()),
                    parameter: Some(name.clone()),
                    step: None,
                    text,
                },
            )
        })
        .collect::<PyResult<Vec<_>>>()?;
    let result = PyTrace {
        parameter: t.parameter.to_string(),
        values: PyArray1::from_vec(py, values).unbind(),
        tip_positions: tip_rows(py, &tips).unbind(),
        unstable_directions: t.points.iter().map(|q| q.unstable_directions).collect(),
        stability: t.points.iter().map(|q| q.verdict().to_string()).collect(),
        fold: t.points.iter().map(|q| q.fold).collect(),
        folds: t.folds,
        bifurcations: t.bifurcations,
        events,
        stopped: t.stopped,
        iterations: t.report.iterations,
    };
    match signal {
        None => Ok(result),
        Some(e) => {
            let done = values_len;
            Err(boundary::with_partial(py, e, done, Bound::new(py, result)?.into_any()))
        }
    }
}
