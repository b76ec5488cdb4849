//! Load histories with stick/slip friction: `tdcr::analysis::history::history` (each step
//! from the tendon state the last left), with numpy out.

use crate::boundary;
use crate::branch::{step_item, tip_rows};
use crate::errors::{self, invalid};
use crate::options::Use;
use crate::robot::{PyRobot, Rows};
use crate::solution::PySolution;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use tdcr::analysis::history::{HistoryStep, LoopAxis, directions, history_until, tip_displacements};
use tdcr::analysis::sweep::Ranges;

/// One tendon's stick/slip zones at one step: (tendon index from 0, [(start, end,
/// contact), ...]) with the contact `pull`, `release`, `stick` or `slack` (0 N).
type Zones = (usize, Vec<(f64, f64, String)>);

/// The result of `history`: every step's solution and the stick/slip zones of each tendon
/// with friction. It is also the sequence of the solutions (`len`, indexing, iteration).
#[pyclass(module = "tdcr", name = "History", frozen)]
pub struct PyHistory {
    solutions: Py<PyList>,
    zones: Vec<Vec<Zones>>,
    tips: Vec<[f64; 3]>,
    /// Each input's name and its value at every step solved.
    inputs: Vec<(String, Vec<f64>)>,
    /// Each step's direction of the swept input.
    directions: Vec<String>,
    /// The swept input ([`Ranges::swept`], else the first): its index in `inputs` and the
    /// label of its axis with the library's unit ([`tdcr::analysis::sweep::Input::axis_label`]).
    swept: (usize, String),
}

impl PyHistory {
    /// The history of `steps`, the first of `ranges`' steps solved in order.
    fn new(py: Python<'_>, steps: Vec<HistoryStep>, ranges: &Ranges) -> PyResult<Self> {
        let n = steps.len();
        let inputs = ranges
            .inputs()
            .iter()
            .enumerate()
            .map(|(i, (input, _))| (input.to_string(), (0..n).map(|k| ranges.value(i, k as f64)).collect()))
            .collect();
        let directions = directions(ranges).into_iter().take(n).map(String::from).collect();
        let index = ranges.swept().map_or(0, |(i, _)| i);
        let swept = (index, ranges.inputs()[index].0.axis_label());
        let solutions = PyList::empty(py);
        let (mut zones, mut tips) = (Vec::new(), Vec::new());
        for step in steps {
            zones.push(
                step.zones
                    .iter()
                    .map(|t| {
                        let list = t
                            .zones
                            .iter()
                            .map(|z| (z.start, z.end, z.contact.name().to_string()))
                            .collect();
                        (t.tendon, list)
                    })
                    .collect(),
            );
            let p = step.solution.tip_position();
            tips.push([p.x, p.y, p.z]);
            solutions.append(PySolution {
                solution: step.solution,
            })?;
        }
        Ok(PyHistory {
            solutions: solutions.unbind(),
            zones,
            tips,
            inputs,
            directions,
            swept,
        })
    }
}

impl PyHistory {
    /// The steps' solutions (shared, not copied).
    fn library_solutions<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PySolution>>> {
        self.solutions
            .bind(py)
            .iter()
            .map(|item| item.cast_into::<PySolution>().map_err(PyErr::from))
            .collect()
    }
}

crate::pickle::pickled_fields! {
    PyHistory { solutions, zones, tips, inputs, directions, swept }

    /// The solutions, one per step solved, in order.
    #[getter]
    fn solutions(&self, py: Python<'_>) -> Py<PyList> {
        self.solutions.clone_ref(py)
    }

    /// Per step, per tendon with friction, `(tendon, [(start, end, contact), ...])`: the
    /// tendon's index (from 0) and its zones from the base entry to its termination (arc
    /// lengths in m), `contact` one of `pull` (sliding in), `release` (sliding out), `stick`
    /// or `slack` (0 N at the base entry).
    #[getter]
    fn zones(&self) -> Vec<Vec<Zones>> {
        self.zones.clone()
    }

    /// Each input's values at the steps solved, by name (`tension.1`, ...; as `parameters`
    /// gave them, up and back down with `up_down`): a dict of arrays of shape (n,).
    #[getter]
    fn inputs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for (name, values) in &self.inputs {
            out.set_item(name, PyArray1::from_slice(py, values))?;
        }
        Ok(out)
    }

    /// Each step's direction of the swept input (the first that changes): "from_rest" (the
    /// first step, loaded from rest: the full-slip pull solve), then "up", "down", or "held"
    /// (where it did not change), as the command line's CSV.
    #[getter]
    fn directions(&self) -> Vec<String> {
        self.directions.clone()
    }

    /// Tip positions (m, world frame), shape (n, 3).
    #[getter]
    fn tip_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        tip_rows(py, &self.tips)
    }

    /// The tip's displacement from its place at the first step (m), shape (n,): the
    /// distance |p(L)_k - p(L)_0|, the y axis of `plot_history` by default (in mm there).
    #[getter]
    fn tip_displacements<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let solutions = self.library_solutions(py)?;
        Ok(PyArray1::from_vec(py, tip_displacements(solutions.iter().map(|s| &s.get().solution))))
    }

    /// loop_axis(y="tip_displacement") -> (label, values)
    ///
    /// The y axis of the hysteresis loop as `tdcr sweep --history --plot --loop-y Y` draws
    /// it: its label (with the unit) and its value at each step, shape (n,).
    /// `y`: "tip_displacement" (the tip's distance from the first step, mm),
    /// "bending_angle" (deg), or "tip_x", "tip_y", "tip_z" (mm, world frame).
    #[pyo3(signature = (y = "tip_displacement"))]
    fn loop_axis<'py>(&self, py: Python<'py>, y: &str) -> PyResult<(&'static str, Bound<'py, PyArray1<f64>>)> {
        let axis = LoopAxis::parse(y).map_err(|e| invalid(format!("loop_axis: {e}")))?;
        let solutions = self.library_solutions(py)?;
        Ok((
            axis.label(),
            PyArray1::from_vec(py, axis.values(solutions.iter().map(|s| &s.get().solution))),
        ))
    }

    /// loop_x() -> (label, values)
    ///
    /// The x axis of the hysteresis loop as `tdcr sweep --history --plot` draws it: the
    /// swept input (the first that changes, else the first given), its label with the
    /// library's unit (e.g. "tension.1 (N)", "displacement.1 (m)") and its value at each
    /// step, shape (n,).
    fn loop_x<'py>(&self, py: Python<'py>) -> (String, Bound<'py, PyArray1<f64>>) {
        let (index, label) = &self.swept;
        let values = self.inputs.get(*index).map_or(&[][..], |(_, v)| &v[..]);
        (label.clone(), PyArray1::from_slice(py, values))
    }

    fn __len__(&self) -> usize {
        self.tips.len()
    }

    fn __getitem__<'py>(&self, py: Python<'py>, index: isize) -> PyResult<Bound<'py, PyAny>> {
        step_item(py, &self.solutions, self.tips.len(), index, "history")
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyIterator>> {
        self.solutions.bind(py).try_iter()
    }
}

/// history(robot, parameters, up_down=False, **options) -> History
///
/// Solves the rows of `parameters` (a dict of 1-D arrays, names as `sweep`) in order as a
/// load history with stick/slip friction, as `tdcr sweep --history` does: each step from
/// the tendon state the last left, so a tendon let back out sticks where friction holds it
/// (docs/friction.md). With `up_down`, the rows are solved up and then back down (the last
/// row once). Collocation; options as `solve`. No rows raise `tdcr.InvalidInput`; a failed
/// step is raised with `index` set to its row and `partial` to the `History` of the rows
/// before it (with `likely_causes`, as a failed solve's); a failure before any step (the
/// full-slip solve of the most loaded step, which chooses the history's mesh) is raised
/// without `index`.
#[pyfunction]
#[pyo3(signature = (robot, parameters, up_down = false, **options))]
pub fn history(
    py: Python<'_>,
    robot: &PyRobot,
    parameters: &Bound<'_, PyDict>,
    up_down: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyHistory> {
    let settings = crate::options::apply(&robot.file.solver, options, Use::Collocation("history"))?;
    let rows = Rows::new(robot, parameters)?;
    if rows.len() == 0 {
        return Err(invalid(
            "history: `parameters` gives no rows, so there is no step to solve; give each input's values in order, \
             e.g. {\"tension.1\": numpy.linspace(0.0, 4.91, 11)}",
        ));
    }
    let mut ranges = rows.ranges(py)?;
    if up_down {
        ranges = ranges.up_down();
    }
    let options = settings.collocation;
    let robots = || {
        (0..ranges.steps())
            .filter_map(|k| ranges.robot(k as f64).ok())
            .collect::<Vec<_>>()
    };
    // Ctrl-C stops between steps: the steps solved so far are the exception's `partial`.
    let (result, signal) = boundary::stoppable(py, |asked| Ok(history_until(&ranges, &options, asked)))?;
    let result = result.map_err(|e| match e {
        // Before any step: the full-slip solve that chooses the history's mesh.
        e if !matches!(e, tdcr::Error::InvalidInput { .. } | tdcr::Error::ModelLimit { .. }) => errors::explained_by(
            e,
            &robots(),
            "history: no step was solved: the full-slip solve of the most loaded step, which chooses the \
             history's mesh, failed",
        ),
        e => boundary::Failure::Library(e).into_py(),
    })?;
    let completed = result.steps.len();
    let partial = PyHistory::new(py, result.steps, &ranges)?;
    if let Some(e) = signal {
        return Err(boundary::with_partial(
            py,
            e,
            completed,
            Py::new(py, partial)?.into_bound(py).into_any(),
        ));
    }
    match result.failure {
        None => Ok(partial),
        Some((i, e)) => {
            let err = match ranges.robot(i as f64) {
                Ok(robot) => errors::explained(e, &robot),
                Err(_) => boundary::Failure::Library(e).into_py(),
            };
            err.value(py).setattr("index", i)?;
            err.value(py).setattr("partial", Py::new(py, partial)?)?;
            Err(err)
        }
    }
}
