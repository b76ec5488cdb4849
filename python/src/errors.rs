//! The exceptions: one class per kind of `tdcr::Error`, all under `tdcr.Error`, each carrying
//! the library's message (the Display the command line prints).

use crate::report::PySolveReport;
use pyo3::exceptions::{PyException, PyUserWarning};
use pyo3::prelude::*;
use pyo3::{PyErr, create_exception};

create_exception!(
    tdcr,
    Error,
    PyException,
    "The base class of every tdcr exception; the message says what is wrong and what to try."
);
create_exception!(
    tdcr,
    InvalidInput,
    Error,
    "A robot, an option or a parameter is not acceptable (the command line's exit code 2)."
);
create_exception!(
    tdcr,
    FileError,
    InvalidInput,
    "A robot file (or dict) breaks a rule: one line per problem, `FILE:LINE:COLUMN: `FIELD` MESSAGE`; `problems` lists them."
);
create_exception!(
    tdcr,
    SingularRouting,
    InvalidInput,
    "A tendon's path has (nearly) no tangent, so its force per unit length is undefined."
);
create_exception!(
    tdcr,
    ModelLimit,
    Error,
    "The input is valid but the model cannot answer it: a load history step whose stick/slip pattern the history does not model, an analysis that does not model friction yet (the command line's exit code 4)."
);
create_exception!(
    tdcr,
    Breakdown,
    Error,
    "The model equations broke down numerically at a state the solver visited."
);
create_exception!(
    tdcr,
    NotConverged,
    Error,
    "A solver stopped without meeting its tolerances; `report` is its SolveReport."
);
create_exception!(
    tdcr,
    IntervalCap,
    Error,
    "Adaptive refinement reached `max_intervals` before the tip tolerance was met."
);

create_exception!(
    tdcr,
    PlausibilityWarning,
    PyUserWarning,
    "A robot's scales or loads are far from any tendon robot's (a 200 m rod, a tendon bending the rod past a radian per offset, a solved tension past its limit): the answer may be right but is likely not what was meant."
);

create_exception!(
    tdcr,
    PoorFitWarning,
    PyUserWarning,
    "A calibration converged but does not explain the data: its noise estimate is far above the measurement noise (Calibration.poor_fit says why, with the likely causes)."
);

/// A library error as the matching exception, with the same message.
pub fn to_py(error: tdcr::Error) -> PyErr {
    to_py_with(error, "")
}

/// A library error as the matching exception, its message after `prefix` (say, the row of
/// a batch) when that is not empty.
pub fn to_py_with(error: tdcr::Error, prefix: &str) -> PyErr {
    let text = if prefix.is_empty() {
        message(&error)
    } else {
        format!("{prefix}: {}", message(&error))
    };
    with_text(error, text)
}

/// The library's message, with a field path numbered as in robot files (`tendon[2].tension`
/// for the library's `tendons[1].tension`: tendons and point loads from 1, the numbering
/// of robot files, the command line and `tdcr.FileError`; [`tdcr::io::user_message`]).
fn message(error: &tdcr::Error) -> String {
    tdcr::io::user_message(error, tdcr::io::Front::Python)
}

/// A failure to solve `robot` as its exception, with the robot's implausible scales after
/// the first line as its likely causes (`tdcr::model::scales::likely_causes`, as the
/// command line prints them) and in the exception's `likely_causes` (a list of strings,
/// empty when there are none).
pub fn explained(error: tdcr::Error, robot: &tdcr::Robot) -> PyErr {
    explained_by(error, std::slice::from_ref(robot), "")
}

/// [`explained`] for a failure to solve one of `robots` (a history's steps before any was
/// solved: the likely causes of each, once), its message after `prefix` (when not empty).
pub fn explained_by(error: tdcr::Error, robots: &[tdcr::Robot], prefix: &str) -> PyErr {
    let causes = tdcr::model::scales::likely_causes_of(&error, robots);
    let text = match prefix {
        "" => message(&error),
        _ => format!("{prefix}: {}", message(&error)),
    };
    let text = tdcr::model::scales::with_likely_causes(&text, &causes);
    let err = with_text(error, text);
    Python::attach(|py| {
        let causes: Vec<String> = causes.iter().map(|w| w.to_string()).collect();
        // Setting an attribute on a fresh exception instance cannot fail.
        let _ = err.value(py).setattr("likely_causes", causes);
    });
    err
}

/// Raises `tdcr.PlausibilityWarning` (through Python's `warnings`) for each of `warnings`
/// (the library's plausibility warnings of a robot or its solved tensions).
pub fn warn(py: Python<'_>, warnings: &[tdcr::model::scales::Warning]) -> PyResult<()> {
    let category = py.get_type::<PlausibilityWarning>();
    for w in warnings {
        let text = std::ffi::CString::new(w.to_string()).unwrap_or_default();
        // stacklevel 1: the warning points at the caller's line (the native call).
        PyErr::warn(py, &category, &text, 1)?;
    }
    Ok(())
}

/// The exception of `error`'s class with the message `text`.
fn with_text(error: tdcr::Error, text: String) -> PyErr {
    match error {
        tdcr::Error::InvalidInput { .. } => InvalidInput::new_err(text),
        tdcr::Error::ModelLimit { .. } => ModelLimit::new_err(text),
        tdcr::Error::SingularRouting { .. } => SingularRouting::new_err(text),
        tdcr::Error::Breakdown { .. } => Breakdown::new_err(text),
        tdcr::Error::IntervalCap { .. } => IntervalCap::new_err(text),
        tdcr::Error::NotConverged { report, .. } => {
            let err = NotConverged::new_err(text);
            Python::attach(|py| {
                let value = err.value(py);
                // Setting an attribute on a fresh exception instance cannot fail.
                let _ = value.setattr("report", PySolveReport { report: *report });
            });
            err
        }
    }
}

/// A robot-file error as `tdcr.FileError`, with the command line's message and the problems
/// as `(line, column, field, message)` tuples (line and column `None` when not placed).
pub fn file_error(error: &tdcr::io::FileError) -> PyErr {
    let err = FileError::new_err(error.to_string());
    Python::attach(|py| {
        let problems: Vec<(Option<usize>, Option<usize>, String, String)> = error
            .problems
            .iter()
            .map(|p| {
                (
                    p.position.map(|q| q.line),
                    p.position.map(|q| q.column),
                    p.field.clone(),
                    p.message.clone(),
                )
            })
            .collect();
        let _ = err.value(py).setattr("problems", problems);
    });
    err
}

/// `tdcr.InvalidInput` with `message`.
pub fn invalid(message: impl Into<String>) -> PyErr {
    InvalidInput::new_err(message.into())
}

/// Registers the exception classes in `module`.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = module.py();
    module.add("Error", py.get_type::<Error>())?;
    module.add("InvalidInput", py.get_type::<InvalidInput>())?;
    module.add("FileError", py.get_type::<FileError>())?;
    module.add("SingularRouting", py.get_type::<SingularRouting>())?;
    module.add("ModelLimit", py.get_type::<ModelLimit>())?;
    module.add("Breakdown", py.get_type::<Breakdown>())?;
    module.add("NotConverged", py.get_type::<NotConverged>())?;
    module.add("IntervalCap", py.get_type::<IntervalCap>())?;
    module.add("PlausibilityWarning", py.get_type::<PlausibilityWarning>())?;
    module.add("PoorFitWarning", py.get_type::<PoorFitWarning>())?;
    Ok(())
}
