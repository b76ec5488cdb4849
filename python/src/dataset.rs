//! `solve_parameters`: a batch of parameter rows reduced to arrays as the rows are solved,
//! with the optional outputs of `tdcr::io::row_outputs` (one meaning with `tdcr batch`'s
//! columns) and a progress line on stderr for runs longer than a second.

use crate::boundary;
use crate::errors::invalid;
use crate::robot::PyRobot;
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySlice, PyString};
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
    /// The delivered tensions of `RowOutputs::delivered`'s tendons (N).
    delivered: Vec<f64>,
}

/// The columns of `solve_parameters`: only the columns asked for, each a numpy array of
/// all the rows allocated before the first row is solved (zeroed pages, which take memory
/// as they are written) and filled as the rows finish, so that nothing is copied or grown
/// on the way (about 34 bytes a row without the optional columns: 10^6 rows take 34 MB,
/// and 16 MB more for the two string lists built at the end).
struct Table<'py> {
    outputs: RowOutputs,
    /// The rows written so far.
    done: usize,
    converged: Bound<'py, PyArray1<bool>>,
    /// (rows, 3).
    tips: Bound<'py, PyArray2<f64>>,
    iterations: Bound<'py, PyArray1<i64>>,
    /// Each row's verdict as an index into `verdicts` (`u8::MAX`: failed).
    stability: Vec<u8>,
    /// The distinct verdicts met.
    verdicts: Vec<&'static str>,
    /// The failed rows and their messages.
    errors: Vec<(usize, String)>,
    /// (rows, 4), when asked.
    orientation: Option<Bound<'py, PyArray2<f64>>>,
    /// (rows,), when asked.
    error_estimate: Option<Bound<'py, PyArray1<f64>>>,
    /// (rows, K, 3), when asked.
    points: Option<Bound<'py, PyArray3<f64>>>,
    /// (rows,) per tendon of `outputs.delivered`.
    delivered: Vec<Bound<'py, PyArray1<f64>>>,
}

impl<'py> Table<'py> {
    /// The columns of `rows` rows.
    fn new(py: Python<'py>, outputs: RowOutputs, rows: usize) -> Self {
        let k = outputs.points;
        Table {
            done: 0,
            converged: PyArray1::zeros(py, rows, false),
            tips: PyArray2::zeros(py, [rows, 3], false),
            iterations: PyArray1::zeros(py, rows, false),
            stability: Vec::with_capacity(rows),
            verdicts: Vec::new(),
            errors: Vec::new(),
            orientation: outputs.orientation.then(|| PyArray2::zeros(py, [rows, 4], false)),
            error_estimate: outputs.error_estimate.then(|| PyArray1::zeros(py, rows, false)),
            points: (k > 0).then(|| PyArray3::zeros(py, [rows, k, 3], false)),
            delivered: outputs
                .delivered
                .iter()
                .map(|_| PyArray1::zeros(py, rows, false))
                .collect(),
            outputs,
        }
    }

    /// Writes the next row: the outcome, or NaN and the message of a failed one.
    fn push(&mut self, result: Result<Outcome, String>) -> PyResult<()> {
        let (i, k, f) = (self.done, self.outputs.points, self.delivered.len());
        let o = result.unwrap_or_else(|message| {
            self.errors.push((i, message));
            Outcome {
                tip: [f64::NAN; 3],
                iterations: -1,
                stability: "",
                orientation: [f64::NAN; 4],
                error_estimate: f64::NAN,
                points: vec![[f64::NAN; 3]; k],
                delivered: vec![f64::NAN; f],
            }
        });
        let solved = o.iterations >= 0;
        self.converged.readwrite().as_slice_mut()?[i] = solved;
        self.tips.readwrite().as_slice_mut()?[3 * i..3 * i + 3].copy_from_slice(&o.tip);
        self.iterations.readwrite().as_slice_mut()?[i] = o.iterations;
        let code = if solved {
            match self.verdicts.iter().position(|&v| v == o.stability) {
                Some(c) => c,
                None => {
                    self.verdicts.push(o.stability);
                    self.verdicts.len() - 1
                }
            }
        } else {
            usize::from(u8::MAX)
        };
        self.stability.push(u8::try_from(code).unwrap_or(u8::MAX));
        if let Some(q) = &self.orientation {
            q.readwrite().as_slice_mut()?[4 * i..4 * i + 4].copy_from_slice(&o.orientation);
        }
        if let Some(e) = &self.error_estimate {
            e.readwrite().as_slice_mut()?[i] = o.error_estimate;
        }
        if let Some(p) = &self.points {
            let mut p = p.readwrite();
            let row = &mut p.as_slice_mut()?[3 * k * i..3 * k * (i + 1)];
            for (out, point) in row.chunks_exact_mut(3).zip(&o.points) {
                out.copy_from_slice(point);
            }
        }
        for (column, &d) in self.delivered.iter().zip(&o.delivered) {
            column.readwrite().as_slice_mut()?[i] = d;
        }
        self.done += 1;
        Ok(())
    }

    /// The table as `solve_parameters` returns it: the arrays themselves (their first
    /// `done` rows, a view, when the run stopped early); the string lists hold one string
    /// object per distinct value.
    fn into_dict(self) -> PyResult<Bound<'py, PyDict>> {
        let py = self.tips.py();
        let n = self.done;
        let full = self.tips.shape()[0] == n;
        let rows = |array: Bound<'py, PyAny>| -> PyResult<Bound<'py, PyAny>> {
            if full {
                Ok(array)
            } else {
                array.get_item(PySlice::new(py, 0, isize::try_from(n).unwrap_or(isize::MAX), 1))
            }
        };
        let d = PyDict::new(py);
        d.set_item("converged", rows(self.converged.into_any())?)?;
        d.set_item("tip_position", rows(self.tips.into_any())?)?;
        d.set_item("iterations", rows(self.iterations.into_any())?)?;
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
        d.set_item("error", PyList::new(py, messages)?)?;
        if let Some(q) = self.orientation {
            d.set_item("tip_orientation", rows(q.into_any())?)?;
        }
        if let Some(e) = self.error_estimate {
            d.set_item("error_estimate", rows(e.into_any())?)?;
        }
        if let Some(p) = self.points {
            d.set_item("points", rows(p.into_any())?)?;
        }
        // The `delivered_I` names of `tdcr batch`: the header's last columns.
        let header = self.outputs.header();
        let names = &header[header.len() - self.delivered.len()..];
        for (name, column) in names.iter().zip(self.delivered) {
            d.set_item(name, rows(column.into_any())?)?;
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
/// adds with `--orientation`, `--error-estimate`, `--points K`; and, for each tendon I with
/// friction in the robot or a `friction.I` parameter, `delivered_I` (M,), the tension it
/// delivers at its termination (N; NaN where failed), as `tdcr batch` writes it. Each solution is reduced to
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
    let (batch, options) = crate::batch_robots("solve_parameters", robot.as_any(), Some(parameters), options)?;
    let outputs = RowOutputs {
        orientation,
        stability: true,
        error_estimate,
        points,
        delivered: batch.tendons_with_friction(),
    };
    outputs
        .check()
        .map_err(|e| invalid(format!("solve_parameters: points={points}: {e}")))?;
    let total = batch.len();
    let mut table = Table::new(py, outputs.clone(), total);
    let mut bar = Progress::new(py, progress)?;
    let run = boundary::rows_with(
        py,
        total,
        |range| batch.chunk(py, range),
        || tdcr::Solver::new(options.clone()),
        |solver, chunk, i| {
            let s = batch.solve(solver, chunk, i)?;
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
                delivered: outputs.delivered_of(&s),
            })
        },
        |i, result| {
            table.push(result.map_err(|failure| failure.to_string()))?;
            bar.update(py, i + 1, total, i + 1 == total)
        },
    );
    match run {
        Ok(()) => table.into_dict(),
        Err(e) => {
            let done = table.done;
            Err(boundary::with_partial(py, e, done, table.into_dict()?.into_any()))
        }
    }
}
