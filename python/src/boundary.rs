//! How every call into the library runs: with the GIL released, any panic caught and raised
//! as `tdcr.Error` ("internal error, please report"), parallel work on this process's own
//! thread pool (rebuilt in a child made by fork, where the parent's pool threads do not
//! exist), and long work cut into chunks of about 0.1 s between which the GIL is taken back
//! to run Python's signal handlers, so that Ctrl-C stops it with `KeyboardInterrupt`.

use crate::errors::{Error as PyTdcrError, to_py_with};
use pyo3::prelude::*;
use std::any::Any;
use std::fmt;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The work between two looks at Python's signals: short enough that Ctrl-C stops a call
/// well within half a second, long enough that taking the GIL back costs nothing measurable
/// (a few microseconds per chunk).
pub const CHUNK_TIME: Duration = Duration::from_millis(100);

/// What a row of a batch (or a whole call) ended with when it did not give a result.
#[derive(Debug)]
pub enum Failure {
    /// The library's error.
    Library(tdcr::Error),
    /// A panic of the library: a bug, reported as `tdcr.Error` with its message.
    Panic(String),
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Library(e) => write!(f, "{}", tdcr::io::user_message(e, tdcr::io::Front::Python)),
            Failure::Panic(message) => write!(f, "{}", internal_message(message)),
        }
    }
}

impl From<tdcr::Error> for Failure {
    fn from(e: tdcr::Error) -> Self {
        Failure::Library(e)
    }
}

impl Failure {
    /// The exception: the library error's class, or `tdcr.Error` for a panic.
    pub fn into_py(self) -> PyErr {
        self.prefixed("")
    }

    /// The exception with its message after `prefix` (when not empty).
    fn prefixed(self, prefix: &str) -> PyErr {
        match self {
            Failure::Library(e) => to_py_with(e, prefix),
            Failure::Panic(message) if prefix.is_empty() => PyTdcrError::new_err(internal_message(&message)),
            Failure::Panic(message) => PyTdcrError::new_err(format!("{prefix}: {}", internal_message(&message))),
        }
    }

    /// The exception of row `index` of a batch, its message after `prefix` (when not
    /// empty), with `index` set.
    pub fn into_py_at(self, py: Python<'_>, prefix: &str, index: usize) -> PyErr {
        let err = self.prefixed(prefix);
        // Attributes of a fresh exception instance can always be set.
        let _ = err.value(py).setattr("index", index);
        err
    }
}

/// The message of a panic as users see it.
fn internal_message(panic: &str) -> String {
    format!("internal error, please report (with the input that caused it) at the tdcr issue tracker: {panic}")
}

/// The text of a panic's payload.
fn panic_text(payload: Box<dyn Any + Send>) -> String {
    match payload.downcast::<String>() {
        Ok(s) => *s,
        Err(payload) => payload
            .downcast_ref::<&str>()
            .map_or_else(|| "a panic without a message".to_string(), |s| (*s).to_string()),
    }
}

/// `f()`, with a panic as [`Failure::Panic`] (the library's state is not shared between
/// calls, so nothing is left half-changed).
pub fn caught<T>(f: impl FnOnce() -> tdcr::Result<T>) -> Result<T, Failure> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(result) => result.map_err(Failure::Library),
        Err(payload) => Err(Failure::Panic(panic_text(payload))),
    }
}

/// `f()` with the GIL released and panics caught, its error raised as the matching
/// exception.
pub fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> tdcr::Result<T> + Send) -> PyResult<T> {
    py.detach(|| caught(f)).map_err(Failure::into_py)
}

/// This process's thread pool and the process it was built in.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// The thread pool of this process (as many threads as rayon's global pool would have:
/// `RAYON_NUM_THREADS` or the cores), built on first use in each process: a child made by
/// fork has the parent's pool in memory but not its threads, so a pool used there would wait
/// forever.
pub fn pool() -> PyResult<Arc<rayon::ThreadPool>> {
    let pid = std::process::id();
    // A poisoned lock only means a thread panicked while holding it; the value is whole.
    let mut slot = POOL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    match slot.as_ref() {
        Some((owner, pool)) if *owner == pid => Ok(Arc::clone(pool)),
        _ => {
            let pool = Arc::new(
                rayon::ThreadPoolBuilder::new()
                    .thread_name(|i| format!("tdcr-{i}"))
                    .build()
                    .map_err(|e| PyTdcrError::new_err(format!("cannot start the thread pool: {e}")))?,
            );
            // The parent's pool is not dropped in a child: dropping it would signal threads
            // that do not exist here.
            if let Some(stale) = slot.replace((pid, Arc::clone(&pool))) {
                std::mem::forget(stale);
            }
            Ok(pool)
        }
    }
}

/// Runs `job` for rows `0..count` in parallel on this process's pool, in chunks of about
/// [`CHUNK_TIME`], giving each row's result to `sink` in row order with the GIL held;
/// between chunks Python's signal handlers run. An error of `sink` (say, at the first
/// failed row) stops the run: every row given to `sink` is finished, and no row after the
/// chunk is started.
///
/// # Errors
/// The exception of a signal handler (`KeyboardInterrupt` for Ctrl-C) and `sink`'s errors.
pub fn rows<T: Send>(
    py: Python<'_>,
    count: usize,
    job: impl Fn(usize) -> Result<T, Failure> + Sync,
    sink: impl FnMut(usize, Result<T, Failure>) -> PyResult<()>,
) -> PyResult<()> {
    rows_with(py, count, |_| (), || (), |(), (), row| job(row), sink)
}

/// As [`rows`], with a state made by `init` for each piece of work a pool thread takes
/// (rayon's `map_init`) and lent to `job` for every row of it: a `tdcr::Solver`, whose
/// workspace is then built once per thread and chunk instead of once per row; and with
/// `prepare(rows)` run with the GIL held before each chunk of rows, its value lent to
/// `job` for the chunk's rows (the chunk's inputs read from Python objects: `Rows::chunk`).
///
/// # Errors
/// As [`rows`].
pub fn rows_with<S, C: Sync, T: Send>(
    py: Python<'_>,
    count: usize,
    mut prepare: impl FnMut(std::ops::Range<usize>) -> C,
    init: impl Fn() -> S + Sync + Send,
    job: impl Fn(&mut S, &C, usize) -> Result<T, Failure> + Sync,
    mut sink: impl FnMut(usize, Result<T, Failure>) -> PyResult<()>,
) -> PyResult<()> {
    use rayon::prelude::*;
    let pool = pool()?;
    let threads = pool.current_num_threads().max(1);
    let (mut start, mut size) = (0, threads);
    while start < count {
        let end = count.min(start + size);
        let chunk = prepare(start..end);
        let began = Instant::now();
        let results: Vec<Result<T, Failure>> = py.detach(|| {
            pool.install(|| {
                (start..end)
                    .into_par_iter()
                    .map_init(&init, |state, row| {
                        match catch_unwind(AssertUnwindSafe(|| job(state, &chunk, row))) {
                            Ok(result) => result,
                            Err(payload) => Err(Failure::Panic(panic_text(payload))),
                        }
                    })
                    .collect()
            })
        });
        let took = began.elapsed().as_secs_f64();
        drop(chunk);
        for (row, result) in (start..end).zip(results) {
            sink(row, result)?;
        }
        py.check_signals()?;
        // The next chunk: as many rows as the last ones took per CHUNK_TIME, at least one
        // per thread, growing at most eightfold (a chunk of fast rows is no guide to slow ones).
        let per_row = took / (end - start) as f64;
        let fit = (CHUNK_TIME.as_secs_f64() / per_row.max(1e-9)) as usize;
        size = fit.clamp(threads, size.saturating_mul(8));
        start = end;
    }
    Ok(())
}

/// Runs `step` with the GIL released until it returns false, taking the GIL back about
/// every [`CHUNK_TIME`] to run Python's signal handlers: for sequential work (a sweep's
/// rows) that must stop on Ctrl-C.
///
/// # Errors
/// The exception of a signal handler (`KeyboardInterrupt` for Ctrl-C).
pub fn steps(py: Python<'_>, mut step: impl FnMut() -> bool + Send) -> PyResult<()> {
    loop {
        let more = py.detach(|| {
            let began = Instant::now();
            loop {
                if !step() {
                    return false;
                }
                if began.elapsed() >= CHUNK_TIME {
                    return true;
                }
            }
        });
        py.check_signals()?;
        if !more {
            return Ok(());
        }
    }
}

/// `f(stop)` on this process's pool in a helper thread, while the calling thread (the GIL
/// released) takes the GIL back about every [`CHUNK_TIME`] to run Python's signal handlers;
/// once one raises, `stop()` returns true for `f`, which is to give up soon. For a library
/// call that asks a stop between chunks of its work (`tdcr::fit::calibrate_until`,
/// `tdcr::collocation::trace_until`). Returns `f`'s result and the signal handler's
/// exception (`KeyboardInterrupt` for Ctrl-C), if one raised, for the caller to raise.
///
/// # Errors
/// `f`'s error (the signal's exception instead when there was one), or `tdcr.Error` for a
/// panic.
pub fn stoppable<T: Send>(
    py: Python<'_>,
    f: impl FnOnce(&dyn Fn() -> bool) -> tdcr::Result<T> + Send,
) -> PyResult<(T, Option<PyErr>)> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::mpsc;
    let pool = pool()?;
    let stop = AtomicBool::new(false);
    let (send, receive) = mpsc::channel();
    std::thread::scope(|scope| {
        scope.spawn(|| {
            let result = caught(|| pool.install(|| f(&|| stop.load(Ordering::Relaxed))));
            // The receiver waits until this arrives.
            let _ = send.send(result);
        });
        let mut signal: Option<PyErr> = None;
        let mut receive = receive;
        loop {
            // The receiver goes into the detached closure and back (it cannot be shared).
            let (back, received) = py.detach(move || {
                let received = receive.recv_timeout(CHUNK_TIME);
                (receive, received)
            });
            receive = back;
            match received {
                Ok(result) => {
                    return match (result, signal) {
                        (Ok(value), signal) => Ok((value, signal)),
                        (Err(_), Some(e)) => Err(e),
                        (Err(failure), None) => Err(failure.into_py()),
                    };
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if signal.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        stop.store(true, Ordering::Relaxed);
                        signal = Some(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyTdcrError::new_err(internal_message(
                        "the worker thread ended without a result",
                    )));
                }
            }
        }
    })
}

/// `error` with `completed` (the rows finished before it) and `partial` (their results) set,
/// when it is an interruption (`KeyboardInterrupt` or another exception of a signal
/// handler, anything that is not a `tdcr.Error`); `error` unchanged otherwise.
pub fn with_partial<'py>(py: Python<'py>, error: PyErr, completed: usize, partial: Bound<'py, PyAny>) -> PyErr {
    if error.is_instance_of::<PyTdcrError>(py) {
        return error;
    }
    let value = error.value(py);
    // Attributes of an exception instance can always be set; a failure would only lose them.
    let _ = value.setattr("completed", completed);
    let _ = value.setattr("partial", partial);
    error
}
