//! The Python module `tdcr._native` behind the `tdcr` package (python/pysrc/tdcr): the
//! Rust crate `tdcr` is the one implementation; this crate only converts types (robot files
//! and dicts in, numpy arrays out, errors as exceptions) and calls it. docs/python.md is the
//! walk-through.

mod analysis;
mod boundary;
mod branch;
mod calibration;
mod compare;
mod control;
mod convert;
mod dataset;
mod errors;
mod gradient;
mod history;
mod options;
mod pickle;
mod picture;
mod report;
mod robot;
mod solution;

use convert::type_name;
use errors::invalid;
use numpy::PyArrayMethods;
use options::Use;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use robot::{PyRobot, Rows};
use solution::PySolution;
use tdcr::io::SolverSettings;
use tdcr::{Method, Solution, collocation, shooting};

/// Solves one robot with its settings, warm-started from `warm` (collocation only).
fn run(robot: &tdcr::Robot, s: &SolverSettings, warm: Option<&Solution>) -> tdcr::Result<Solution> {
    match (s.method, warm) {
        (Method::Collocation, None) => tdcr::solve(robot, &s.collocation),
        (Method::Collocation, Some(w)) => tdcr::solve_from(robot, &s.collocation, w),
        (Method::Shooting, _) => shooting::solve(robot, &s.shooting),
    }
}

/// solve(robot, *, method=None, tol=None, intervals=None, max_intervals=None,
/// residual_tolerance=None, max_iterations=None, continuation=None, equilibrium=None,
/// integration_tolerance=None, warm_start=None) -> Solution
///
/// Solves `robot` with its `[solver]` settings changed by the options: `method`
/// ("collocation" or "shooting"), `tol` (the tip tolerance relative to the rod length,
/// default 1e-7: the mesh is chosen until the estimated tip error is at most tol x L and
/// tol rad; `report.error_estimate` holds the estimate), `intervals` (mesh intervals; alone
/// it fixes the mesh, still with an error estimate), `max_intervals`, `residual_tolerance` (scaled
/// Newton residual), `max_iterations`, `continuation` (follow the load path when Newton
/// from the guess fails or ends on an unstable state), `equilibrium` ("load_path", the
/// default: the state reached by loading the robot from rest; or "nearest": Newton's root
/// from the guess or warm start whatever its stability; collocation; `report.stability`
/// and `report.path` say what was found), `integration_tolerance` (shooting), `warm_start` (a Solution of a nearby robot to start
/// Newton from; collocation). The GIL is released while solving.
///
/// Raises `tdcr.InvalidInput` for bad options, `tdcr.NotConverged` (with `.report`),
/// `tdcr.IntervalCap`, `tdcr.Breakdown`, `tdcr.SingularRouting`, with the command line's
/// messages (a failure's `likely_causes`: the robot's implausible scales, also after the
/// message's first line). Warns `tdcr.PlausibilityWarning` for implausible scales and for
/// solved tensions past their limit.
#[pyfunction]
#[pyo3(signature = (robot, *, warm_start=None, **options))]
fn solve(
    py: Python<'_>,
    robot: &PyRobot,
    warm_start: Option<&PySolution>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let settings = options::apply(&robot.file.solver, options, Use::Any("solve"))?;
    if warm_start.is_some() && settings.method != Method::Collocation {
        return Err(invalid(
            "solve: `warm_start` starts collocation's Newton iteration; the shooting method does not use it (leave it out, or use method=\"collocation\")",
        ));
    }
    let (r, warm) = (&robot.file.robot, warm_start.map(|w| &w.solution));
    control::checked_solve(py, r, || run(r, &settings, warm)).map(|solution| PySolution { solution })
}

/// The robots of a batch: a list, or one robot with parameter columns (built row by row).
enum Batch {
    /// Robots given one by one.
    List(Vec<tdcr::Robot>),
    /// One robot and parameter columns.
    Rows(Box<Rows>),
}

impl Batch {
    /// The number of robots.
    fn len(&self) -> usize {
        match self {
            Batch::List(list) => list.len(),
            Batch::Rows(rows) => rows.len(),
        }
    }

    /// The tendons (from 0) with friction in some row of parameter columns, whose delivered
    /// tensions `solve_parameters` keeps (it takes rows only: none for a list).
    fn tendons_with_friction(&self) -> Vec<usize> {
        match self {
            Batch::List(_) => Vec::new(),
            Batch::Rows(rows) => rows.tendons_with_friction(),
        }
    }

    /// The inputs of the rows `range` for [`Batch::solve`] without the GIL (parameter
    /// columns: their values copied; a list: nothing).
    fn chunk(&self, py: Python<'_>, range: std::ops::Range<usize>) -> robot::Chunk {
        match self {
            Batch::List(_) => robot::Chunk::default(),
            Batch::Rows(rows) => rows.chunk(py, range),
        }
    }

    /// Solves robot `i` (one of `chunk`'s rows) by collocation with `solver` (its options;
    /// its workspace reused from the rows it solved before): bitwise `tdcr::solve`'s answer,
    /// as `tdcr batch` (`tdcr::collocation::solve_rows`) solves a row.
    fn solve(&self, solver: &mut tdcr::Solver, chunk: &robot::Chunk, i: usize) -> tdcr::Result<Solution> {
        match self {
            Batch::List(list) => solver.solve(&list[i]),
            Batch::Rows(rows) => solver.solve(&rows.robot(chunk, i)?),
        }
    }
}

/// The robots of a batch (a list of robots, or one robot with parameter arrays: one robot
/// per row) and the one set of collocation options for all of them; `function` names the
/// caller in messages.
fn batch_robots(
    function: &str,
    robots: &Bound<'_, PyAny>,
    parameters: Option<&Bound<'_, PyDict>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Batch, collocation::Options)> {
    let (batch, settings) = if let Ok(base) = robots.cast::<PyRobot>() {
        let base = base.get();
        let Some(parameters) = parameters else {
            return Err(invalid(format!(
                "{function}: give a list of robots, or one robot with `parameters` (a dict of arrays)"
            )));
        };
        (
            Batch::Rows(Box::new(Rows::new(base, parameters)?)),
            options::apply(&base.file.solver, options, Use::Collocation(function))?,
        )
    } else {
        if parameters.is_some() {
            return Err(invalid(format!("{function}: `parameters` needs one robot, not a list")));
        }
        let mut list = Vec::new();
        let mut settings: Option<SolverSettings> = None;
        let items = robots.try_iter().map_err(|_| {
            invalid(format!(
                "{function}: give a list of tdcr.Robot, not {}",
                type_name(robots)
            ))
        })?;
        for (i, item) in items.enumerate() {
            let item = item?;
            let r = item
                .cast::<PyRobot>()
                .map_err(|_| invalid(format!("{function}: item {i} is not a tdcr.Robot")))?;
            let s = options::apply(&r.get().file.solver, options, Use::Collocation(function))?;
            if let Some(first) = &settings
                && (first.collocation != s.collocation || first.method != s.method)
            {
                return Err(invalid(format!(
                    "{function}: robot {i} has other [solver] settings than robot 0; a batch solves every robot with one set of options"
                )));
            }
            settings.get_or_insert(s);
            list.push(r.get().file.robot.clone());
        }
        (Batch::List(list), settings.unwrap_or_default())
    };
    if settings.method != Method::Collocation {
        return Err(invalid(format!(
            "{function} solves by collocation; use method=\"collocation\""
        )));
    }
    Ok((batch, settings.collocation))
}

/// solve_batch(robots, parameters=None, *, errors="raise", **options) -> list[Solution]
///
/// Solves many robots in parallel on all cores (this process's thread pool) with the GIL
/// released; results in input order, bitwise identical to solving one by one with
/// `solve`. `robots` is a list of robots, or one robot with `parameters`: a dict of 1-D
/// arrays of one length M, named as `tdcr batch` columns (`tension.1`, `tip_force.z`, ...;
/// one robot per row). Options as `solve` (one set for all robots; collocation). With
/// `errors="raise"` the batch stops at the first failure and raises it, its message
/// starting with the row and its `index` attribute set to it; with `errors="return"` failed
/// entries are the exception objects. Rows are solved in chunks of about 0.1 s; Ctrl-C
/// between them raises `KeyboardInterrupt` with `completed` (the rows finished, from
/// the first) and `partial` (their list).
#[pyfunction]
#[pyo3(signature = (robots, parameters=None, *, errors="raise", **options))]
fn solve_batch(
    py: Python<'_>,
    robots: &Bound<'_, PyAny>,
    parameters: Option<&Bound<'_, PyDict>>,
    errors: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyList>> {
    let raise = raise_errors("solve_batch", errors)?;
    let (batch, options) = batch_robots("solve_batch", robots, parameters, options)?;
    let mut out: Vec<Py<PyAny>> = Vec::with_capacity(batch.len());
    let run = boundary::rows_with(
        py,
        batch.len(),
        |range| batch.chunk(py, range),
        || tdcr::Solver::new(options.clone()),
        |solver, chunk, i| Ok(batch.solve(solver, chunk, i)?),
        |i, result| {
            match result {
                Ok(solution) => out.push(Py::new(py, PySolution { solution })?.into_any()),
                Err(failure) => {
                    if raise {
                        return Err(failure.into_py_at(py, &format!("solve_batch: row {i} (from 0)"), i));
                    }
                    let err = failure.into_py_at(py, "", i);
                    out.push(err.value(py).clone().into_any().unbind());
                }
            }
            Ok(())
        },
    );
    match run {
        Ok(()) => Ok(PyList::new(py, out)?.unbind()),
        Err(e) => {
            let done = out.len();
            Err(boundary::with_partial(py, e, done, PyList::new(py, out)?.into_any()))
        }
    }
}

/// The `errors` argument of a batch: true for "raise", false for "return".
fn raise_errors(function: &str, errors: &str) -> PyResult<bool> {
    match errors {
        "raise" => Ok(true),
        "return" => Ok(false),
        other => Err(invalid(format!(
            "{function}: errors=\"{other}\"; use \"raise\" or \"return\""
        ))),
    }
}

/// Reference case S: the paper's prototype, tendon 1 at 2.94 N, no tip load
/// (`tdcr::cases::case_s`), read back through its robot file like every Python robot.
#[pyfunction]
fn case_s() -> PyResult<PyRobot> {
    robot::from_library(tdcr::cases::case_s())
}

/// Reference case H: helical tendon 5 at 4.91 N, tip force 0.196 N along -z
/// (`tdcr::cases::case_h`), read back through its robot file like every Python robot.
#[pyfunction]
fn case_h() -> PyResult<PyRobot> {
    robot::from_library(tdcr::cases::case_h())
}

/// The paper's prototype with all five tendons slack (`tdcr::cases::prototype`), read
/// back through its robot file like every Python robot.
#[pyfunction]
fn prototype() -> PyResult<PyRobot> {
    robot::from_library(tdcr::cases::prototype())
}

/// The commented example robot file (the text of `tdcr example`).
#[pyfunction]
fn example() -> String {
    tdcr::io::example()
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("TIP_S", tdcr::cases::TIP_S)?;
    m.add("TIP_H", tdcr::cases::TIP_H)?;
    m.add_class::<PyRobot>()?;
    m.add_class::<PySolution>()?;
    m.add_class::<report::PySolveReport>()?;
    m.add_class::<solution::PyState>()?;
    m.add_class::<analysis::PyTipSensitivities>()?;
    m.add_class::<analysis::PyInverseResult>()?;
    m.add_class::<calibration::PyCalibration>()?;
    m.add_class::<branch::PySweep>()?;
    m.add_class::<branch::PyTrace>()?;
    m.add_class::<history::PyHistory>()?;
    m.add_class::<gradient::PyLinearization>()?;
    m.add_class::<control::PySolver>()?;
    m.add_class::<branch::PyEvent>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve_batch, m)?)?;
    m.add_function(wrap_pyfunction!(dataset::solve_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(branch::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(history::history, m)?)?;
    m.add_function(wrap_pyfunction!(branch::trace, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::tip_sensitivities, m)?)?;
    m.add_function(wrap_pyfunction!(gradient::linearize, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::solve_tensions, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::solve_displacements, m)?)?;
    m.add_function(wrap_pyfunction!(calibration::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_function(wrap_pyfunction!(picture::figure, m)?)?;
    m.add_function(wrap_pyfunction!(case_s, m)?)?;
    m.add_function(wrap_pyfunction!(case_h, m)?)?;
    m.add_function(wrap_pyfunction!(prototype, m)?)?;
    m.add_function(wrap_pyfunction!(example, m)?)?;
    errors::register(m)?;
    // NumPy's C API and rust-numpy's borrow checking now, while importing: looked up on
    // first use instead, an interrupt arriving during that lookup made it panic ("Failed to
    // access NumPy array API capsule").
    let empty = numpy::PyArray1::<f64>::zeros(m.py(), 0, false);
    drop(empty.readonly());
    Ok(())
}
