//! The Python module `tdcr._native` behind the `tdcr` package (python/pysrc/tdcr): the
//! Rust crate `tdcr` is the one implementation; this crate only converts types (robot files
//! and dicts in, numpy arrays out, errors as exceptions) and calls it. docs/python.md is the
//! walk-through.

mod analysis;
mod branch;
mod compare;
mod errors;
mod options;
mod robot;
mod solution;

use errors::{invalid, to_py};
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use robot::{PyRobot, robots_of};
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
/// messages.
#[pyfunction]
#[pyo3(signature = (robot, *, warm_start=None, **options))]
fn solve(
    py: Python<'_>,
    robot: &PyRobot,
    warm_start: Option<&PySolution>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PySolution> {
    let settings = options::apply(&robot.file.solver, options)?;
    let (r, warm) = (&robot.file.robot, warm_start.map(|w| &w.solution));
    py.detach(|| run(r, &settings, warm))
        .map(|solution| PySolution { solution })
        .map_err(to_py)
}

/// The robots of a batch: a list of robots, or one robot with parameter arrays (one robot
/// per row), and the one set of collocation options for all of them.
fn batch_robots(
    robots: &Bound<'_, PyAny>,
    parameters: Option<&Bound<'_, PyDict>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(Vec<tdcr::Robot>, collocation::Options)> {
    let (list, settings) = if let Ok(base) = robots.cast::<PyRobot>() {
        let base = base.get();
        let Some(parameters) = parameters else {
            return Err(invalid(
                "solve_batch: give a list of robots, or one robot with `parameters` (a dict of arrays)",
            ));
        };
        (
            robots_of(base, parameters)?,
            options::apply(&base.file.solver, options)?,
        )
    } else {
        if parameters.is_some() {
            return Err(invalid("solve_batch: `parameters` needs one robot, not a list"));
        }
        let mut list = Vec::new();
        let mut settings: Option<SolverSettings> = None;
        for (i, item) in robots.try_iter()?.enumerate() {
            let item = item?;
            let r = item
                .cast::<PyRobot>()
                .map_err(|_| invalid(format!("solve_batch: item {i} is not a tdcr.Robot")))?;
            let s = options::apply(&r.get().file.solver, options)?;
            if let Some(first) = &settings
                && (first.collocation != s.collocation || first.method != s.method)
            {
                return Err(invalid(format!(
                    "solve_batch: robot {i} has other [solver] settings than robot 0; a batch solves every robot with one set of options"
                )));
            }
            settings.get_or_insert(s);
            list.push(r.get().file.robot.clone());
        }
        (list, settings.unwrap_or_default())
    };
    if settings.method != Method::Collocation {
        return Err(invalid("solve_batch solves by collocation; use method=\"collocation\""));
    }
    Ok((list, settings.collocation))
}

/// solve_batch(robots, parameters=None, *, errors="raise", **options) -> list[Solution]
///
/// Solves many robots in parallel on all cores (rayon, through `tdcr::solve_batch`) with the
/// GIL released; results in input order, bitwise identical to solving one by one with
/// `solve`. `robots` is a list of robots, or one robot with `parameters`: a dict of 1-D
/// arrays of one length M, named as `tdcr batch` columns (`tension.1`, `tip_force.z`, ...;
/// one robot per row). Options as `solve` (one set for all robots; collocation). With
/// `errors="raise"` the first failure is raised (its `index` attribute says which robot);
/// with `errors="return"` failed entries are the exception objects.
#[pyfunction]
#[pyo3(signature = (robots, parameters=None, *, errors="raise", **options))]
fn solve_batch(
    py: Python<'_>,
    robots: &Bound<'_, PyAny>,
    parameters: Option<&Bound<'_, PyDict>>,
    errors: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyList>> {
    let raise = match errors {
        "raise" => true,
        "return" => false,
        other => {
            return Err(invalid(format!(
                "solve_batch: errors=\"{other}\"; use \"raise\" or \"return\""
            )));
        }
    };
    let (list, options) = batch_robots(robots, parameters, options)?;
    let results = py.detach(|| tdcr::solve_batch(&list, &options));
    let out = PyList::empty(py);
    for (i, result) in results.into_iter().enumerate() {
        match result {
            Ok(solution) => out.append(PySolution { solution })?,
            Err(e) => {
                let err = to_py(e);
                err.value(py).setattr("index", i)?;
                if raise {
                    return Err(err);
                }
                out.append(err.value(py))?;
            }
        }
    }
    Ok(out.unbind())
}

/// solve_parameters(robot, parameters, **options) -> dict
///
/// `solve_batch(robot, parameters, errors="return", **options)` reduced to arrays, the
/// shape a distributed map wants: `converged` (M,) bool, `tip_position` (M, 3) (NaN where
/// a row failed), `iterations` (M,) int64 (-1 where failed), `stability` (list of M
/// strings: "stable", "unstable" or "unknown", empty where failed), `error` (list of M
/// strings, empty where solved).
#[pyfunction]
#[pyo3(signature = (robot, parameters, **options))]
fn solve_parameters<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyRobot>,
    parameters: &Bound<'py, PyDict>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (list, options) = batch_robots(robot.as_any(), Some(parameters), options)?;
    let results = py.detach(|| tdcr::solve_batch(&list, &options));
    let n = results.len();
    let mut tips = Array2::from_elem((n, 3), f64::NAN);
    let mut converged = Array1::from_elem(n, false);
    let mut iterations = Array1::from_elem(n, -1i64);
    let mut messages = Vec::with_capacity(n);
    let mut stability = Vec::with_capacity(n);
    for (i, result) in results.iter().enumerate() {
        match result {
            Ok(s) => {
                let p = s.tip_position();
                for k in 0..3 {
                    tips[(i, k)] = p[k];
                }
                converged[i] = true;
                iterations[i] = i64::try_from(s.report.iterations).unwrap_or(i64::MAX);
                messages.push(String::new());
                stability.push(s.report.stability.verdict());
            }
            Err(e) => {
                messages.push(e.to_string());
                stability.push("");
            }
        }
    }
    let d = PyDict::new(py);
    d.set_item("converged", converged.into_pyarray(py))?;
    d.set_item("tip_position", tips.into_pyarray(py))?;
    d.set_item("iterations", iterations.into_pyarray(py))?;
    d.set_item("stability", stability)?;
    d.set_item("error", messages)?;
    Ok(d)
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
    m.add_class::<solution::PySolveReport>()?;
    m.add_class::<solution::PyState>()?;
    m.add_class::<analysis::PyTipSensitivities>()?;
    m.add_class::<analysis::PyInverseResult>()?;
    m.add_class::<analysis::PyCalibration>()?;
    m.add_class::<branch::PySweep>()?;
    m.add_class::<branch::PyTrace>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve_batch, m)?)?;
    m.add_function(wrap_pyfunction!(solve_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(branch::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(branch::trace, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::tip_sensitivities, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::solve_tensions, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::solve_displacements, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_function(wrap_pyfunction!(case_s, m)?)?;
    m.add_function(wrap_pyfunction!(case_h, m)?)?;
    m.add_function(wrap_pyfunction!(prototype, m)?)?;
    m.add_function(wrap_pyfunction!(example, m)?)?;
    errors::register(m)?;
    Ok(())
}
