//! `solve_parameters`: a batch of parameter rows reduced to arrays as the rows are solved,
//! with the optional outputs of `tdcr::io::row_outputs` (one meaning with `tdcr batch`'s
//! columns) and a progress line on stderr for runs longer than a second.

use crate::boundary;
use crate::errors::invalid;
use crate::robot::PyRobot;
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2, Array3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use std::time::{Duration, Instant};
use tdcr::io::row_outputs::{RowOutputs, quaternion, tip_error_estimate};

/// What `solve_parameters` keeps of a solved row.
struct Outcome {
    tip: [f64; 3],
    iterations: i64,
    stability: &'static str,
    orientation: [f64; 4],
    error_estimate: f64,
    points: Vec<[f64; 3]>,
}

/// The columns of `solve_parameters`, filled row by row: only the columns asked for, each
/// a flat array (about 34 bytes per row without the optional columns: 10^6 rows take 34
/// MB), failed rows' messages apart.
struct Table {
    outputs: RowOutputs,
    /// Row-major (rows, 3).
    tips: Vec<f64>,
    converged: Vec<bool>,
    iterations: Vec<i64>,
    /// Each row's verdict as an index into `verdicts` (`u8::MAX`: failed).
    stability: Vec<u8>,
    /// The distinct verdicts met.
    verdicts: Vec<&'static str>,
    /// The failed rows and their messages.
    errors: Vec<(usize, String)>,
    /// Row-major (rows, 4), when asked.
    orientation: Vec<f64>,
    error_estimate: Vec<f64>,
    /// Row-major (rows, K, 3), when asked.
    points: Vec<f64>,
}

impl Table {
    fn new(outputs: RowOutputs) -> Self {
        Table {
            outputs,
            tips: Vec::new(),
            converged: Vec::new(),
            iterations: Vec::new(),
            stability: Vec::new(),
            verdicts: Vec::new(),
            errors: Vec::new(),
            orientation: Vec::new(),
            error_estimate: Vec::new(),
            points: Vec::new(),
        }
    }

    /// The rows so far.
    fn len(&self) -> usize {
        self.converged.len()
    }

    /// Appends a row: the outcome, or NaN and the message of a failed one.
    fn push(&mut self, result: Result<Outcome, String>) {
        let k = self.outputs.points;
        match result {
            Ok(o) => {
                self.tips.extend(o.tip);
                self.converged.push(true);
                self.iterations.push(o.iterations);
                let code = match self.verdicts.iter().position(|&v| v == o.stability) {
                    Some(i) => i,
                    None => {
                        self.verdicts.push(o.stability);
                        self.verdicts.len() - 1
                    }
                };
                self.stability.push(u8::try_from(code).unwrap_or(u8::MAX));
                if self.outputs.orientation {
                    self.orientation.extend(o.orientation);
                }
                if self.outputs.error_estimate {
                    self.error_estimate.push(o.error_estimate);
                }
                self.points.extend(o.points.iter().flatten());
            }
            Err(message) => {
                self.errors.push((self.len(), message));
                self.tips.extend([f64::NAN; 3]);
                self.converged.push(false);
                self.iterations.push(-1);
                self.stability.push(u8::MAX);
                if self.outputs.orientation {
                    self.orientation.extend([f64::NAN; 4]);
                }
                if self.outputs.error_estimate {
                    self.error_estimate.push(f64::NAN);
                }
                self.points.extend(std::iter::repeat_n(f64::NAN, 3 * k));
            }
        }
    }

    /// The table as `solve_parameters` returns it (the arrays moved, not copied; the
    /// string lists hold one string object per distinct value).
    fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let n = self.len();
        let shape = |e: numpy::ndarray::ShapeError| invalid(e.to_string());
        let d = PyDict::new(py);
        d.set_item("converged", Array1::from(self.converged).into_pyarray(py))?;
        d.set_item(
            "tip_position",
            Array2::from_shape_vec((n, 3), self.tips)
                .map_err(shape)?
                .into_pyarray(py),
        )?;
        d.set_item("iterations", Array1::from(self.iterations).into_pyarray(py))?;
        let empty = PyString::new(py, "");
        let verdicts: Vec<Bound<'_, PyString>> = self.verdicts.iter().map(|v| PyString::new(py, v)).collect();
        let stability = self
            .stability
            .iter()
            .map(|&c| verdicts.get(usize::from(c)).unwrap_or(&empty).clone());
        d.set_item("stability", PyList::new(py, stability)?)?;
        let mut errors = self.errors.into_iter().peekable();
        let messages = (0..n).map(|i| match errors.next_if(|(row, _)| *row == i) {
            Some((_, message)) => PyString::new(py, &message),
            None => empty.clone(),
        });
        d.set_item("error", PyList::new(py, messages.collect::<Vec<_>>())?)?;
        if self.outputs.orientation {
            let q = Array2::from_shape_vec((n, 4), self.orientation).map_err(shape)?;
            d.set_item("tip_orientation", q.into_pyarray(py))?;
        }
        if self.outputs.error_estimate {
            d.set_item("error_estimate", Array1::from(self.error_estimate).into_pyarray(py))?;
        }
        if self.outputs.points > 0 {
            let k = self.outputs.points;
            let points = Array3::from_shape_vec((n, k, 3), self.points).map_err(shape)?;
            d.set_item("points", points.into_pyarray(py))?;
        }
        Ok(d)
    }
}

/// A progress line on stderr (rows done, rows/s, time left) for a run past a second.
struct Progress {
    start: Instant,
    last: Option<Instant>,
    enabled: bool,
}

impl Progress {
    /// Runs shorter than this show nothing.
    const DELAY: Duration = Duration::from_secs(1);
    /// The line is rewritten at most this often.
    const EVERY: Duration = Duration::from_millis(500);

    /// `progress`: True (shown), False (never), None (shown when stderr is a terminal).
    fn new(py: Python<'_>, progress: Option<bool>) -> PyResult<Self> {
        let enabled = match progress {
            Some(on) => on,
            None => py
                .import("sys")?
                .getattr("stderr")?
                .call_method0("isatty")?
                .extract()
                .unwrap_or(false),
        };
        Ok(Progress {
            start: Instant::now(),
            last: None,
            enabled,
        })
    }

    fn update(&mut self, py: Python<'_>, done: usize, total: usize, finished: bool) -> PyResult<()> {
        let elapsed = self.start.elapsed();
        if !self.enabled || elapsed < Self::DELAY || self.last.is_some_and(|t| t.elapsed() < Self::EVERY) && !finished {
            return Ok(());
        }
        if finished && self.last.is_none() {
            return Ok(());
        }
        self.last = Some(Instant::now());
        let seconds = elapsed.as_secs_f64();
        let rate = done as f64 / seconds;
        let left = if rate > 0.0 {
            total.saturating_sub(done) as f64 / rate
        } else {
            0.0
        };
        let end = if finished { "\n" } else { "" };
        let line = format!(
            "\rsolve_parameters: {done}/{total} rows, {seconds:.1} s, {rate:.0} rows/s, {left:.0} s left {end}"
        );
        let stderr = py.import("sys")?.getattr("stderr")?;
        stderr.call_method1("write", (line,))?;
        stderr.call_method0("flush")?;
        Ok(())
    }
}

/// solve_parameters(robot, parameters, *, orientation=False, error_estimate=False,
/// points=0, progress=None, **options) -> dict
///
/// `solve_batch(robot, parameters, errors="return", **options)` reduced to arrays, the
/// shape a distributed map wants: `converged` (M,) bool, `tip_position` (M, 3) (NaN where
/// a row failed), `iterations` (M,) int64 (-1 where failed), `stability` (list of M
/// strings: "stable", "unstable" or "unknown", empty where failed), `error` (list of M
/// strings, empty where solved); with `orientation=True` also `tip_orientation` (M, 4), the
/// tip's unit quaternion (w, x, y, z), w >= 0; with `error_estimate=True` `error_estimate`
/// (M,), the estimated tip position error (m; NaN without one); with `points=K` (0 or >= 2)
/// `points` (M, K, 3), backbone points at s = j L / (K - 1) (m): the columns `tdcr batch`
/// adds with `--orientation`, `--error-estimate`, `--points K`. Each solution is reduced to
/// its row as soon as it is solved, so memory does not grow with M beyond the arrays.
/// `progress`: a line on stderr with rows/s and the time left, for runs past a second (None:
/// when stderr is a terminal). Ctrl-C raises `KeyboardInterrupt` with `completed` and
/// `partial` (this dict for the finished rows).
#[pyfunction]
#[pyo3(signature = (robot, parameters, *, orientation=false, error_estimate=false, points=0, progress=None, **options))]
#[allow(clippy::too_many_arguments)]
pub fn solve_parameters<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyRobot>,
    parameters: &Bound<'py, PyDict>,
    orientation: bool,
    error_estimate: bool,
    points: usize,
    progress: Option<bool>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let outputs = RowOutputs {
        orientation,
        stability: true,
        error_estimate,
        points,
    };
    outputs
        .check()
        .map_err(|e| invalid(format!("solve_parameters: points={points}: {e}")))?;
    let (batch, options) = crate::batch_robots("solve_parameters", robot.as_any(), Some(parameters), options)?;
    let mut table = Table::new(outputs);
    let mut bar = Progress::new(py, progress)?;
    let total = batch.len();
    let run = boundary::rows_with(
        py,
        total,
        || tdcr::Solver::new(options.clone()),
        |solver, i| {
            let s = batch.solve(solver, i)?;
            let p = s.tip_position();
            Ok(Outcome {
                tip: [p.x, p.y, p.z],
                iterations: i64::try_from(s.report.iterations).unwrap_or(i64::MAX),
                stability: s.report.stability.verdict(),
                orientation: if orientation {
                    quaternion(&s.tip().R)
                } else {
                    [f64::NAN; 4]
                },
                error_estimate: tip_error_estimate(&s),
                points: outputs.points_of(&s).iter().map(|p| [p.x, p.y, p.z]).collect(),
            })
        },
        |i, result| {
            table.push(result.map_err(|failure| failure.to_string()));
            bar.update(py, i + 1, total, i + 1 == total)
        },
    );
    match run {
        Ok(()) => table.into_dict(py),
        Err(e) => {
            let done = table.len();
            Err(boundary::with_partial(py, e, done, table.into_dict(py)?.into_any()))
        }
    }
}
