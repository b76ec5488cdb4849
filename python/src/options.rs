//! Solver options given as keyword arguments, applied over a robot's `[solver]` settings the
//! way the command line applies its flags.

use crate::errors::invalid;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::Method;
use tdcr::collocation::Equilibrium;
use tdcr::io::SolverSettings;

/// The keyword arguments every solving function accepts, for messages.
pub const OPTION_NAMES: &str = "method, tol, intervals, max_intervals, residual_tolerance, max_iterations, continuation, equilibrium, integration_tolerance";

/// The values of the `equilibrium` option, for messages.
pub const EQUILIBRIUM_NAMES: &str = "\"load_path\" or \"nearest\"";

/// Reads the value of the `equilibrium` option; anything but the two names is
/// `tdcr.InvalidInput` naming both.
fn equilibrium(value: &str) -> PyResult<Equilibrium> {
    match value {
        "load_path" => Ok(Equilibrium::LoadPath),
        "nearest" => Ok(Equilibrium::Nearest),
        other => Err(invalid(format!(
            "option `equilibrium` is \"{other}\"; use {EQUILIBRIUM_NAMES} (the state reached by loading from rest, or Newton's root nearest the guess whatever its stability)"
        ))),
    }
}

/// Reads one option; a value of the wrong type is `tdcr.InvalidInput` naming it.
fn get<'py, T: FromPyObjectOwned<'py>>(value: &Bound<'py, PyAny>, name: &str, what: &str) -> PyResult<T> {
    value
        .extract::<T>()
        .map_err(|_| invalid(format!("option `{name}` must be {what}, not {}", type_name(value))))
}

/// The Python type name of `value`, for messages.
pub fn type_name(value: &Bound<'_, PyAny>) -> String {
    value
        .get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// `settings` with the options of `kwargs` applied: `method` ("collocation" or "shooting"),
/// `tol` (tip tolerance for adaptive refinement, relative to the rod length L: position to
/// tol x L, orientation to tol rad), `intervals` (a fixed mesh unless `tol`
/// is given too), `max_intervals`, `residual_tolerance`, `max_iterations`, `continuation`,
/// `equilibrium` ("load_path" or "nearest", collocation), `integration_tolerance`
/// (shooting). Unknown names and wrong types are
/// `tdcr.InvalidInput`; the values are checked by the solvers' own `Options::validate`.
pub fn apply(settings: &SolverSettings, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<SolverSettings> {
    let mut out = settings.clone();
    let Some(kwargs) = kwargs else {
        return Ok(out);
    };
    let (mut intervals, mut tol, mut cap) = (None, None, None);
    for (key, value) in kwargs.iter() {
        let name: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        let c = &mut out.collocation;
        match name.as_str() {
            "method" => {
                out.method = match get::<String>(&value, &name, "a string")?.as_str() {
                    "collocation" => Method::Collocation,
                    "shooting" => Method::Shooting,
                    other => {
                        return Err(invalid(format!(
                            "option `method` is \"{other}\"; use \"collocation\" or \"shooting\""
                        )));
                    }
                }
            }
            "tol" => tol = Some(get::<f64>(&value, &name, "a number (relative to the rod length)")?),
            "intervals" => intervals = Some(get::<usize>(&value, &name, "a whole number >= 1")?),
            "max_intervals" => cap = Some(get::<usize>(&value, &name, "a whole number >= 1")?),
            "residual_tolerance" => {
                let t = get::<f64>(&value, &name, "a number")?;
                c.residual_tolerance = t;
                out.shooting.residual_tolerance = t;
            }
            "max_iterations" => {
                let n = get::<usize>(&value, &name, "a whole number >= 1")?;
                c.max_iterations = n;
                out.shooting.max_iterations = n;
            }
            "continuation" => c.continuation = get::<bool>(&value, &name, "True or False")?,
            "equilibrium" => {
                c.equilibrium = equilibrium(&get::<String>(
                    &value,
                    &name,
                    &format!("a string, {EQUILIBRIUM_NAMES}"),
                )?)?;
            }
            "integration_tolerance" => out.shooting.integration_tolerance = get::<f64>(&value, &name, "a number")?,
            _ => {
                return Err(invalid(format!(
                    "unknown option `{name}`; the options are {OPTION_NAMES}"
                )));
            }
        }
    }
    let c = &mut out.collocation;
    if let Some(n) = cap {
        c.max_intervals = n;
    }
    if let Some(n) = intervals {
        if n == 0 {
            return Err(invalid("option `intervals` is 0; a mesh needs at least 1 interval"));
        }
        c.intervals = n;
        if cap.is_none() {
            c.max_intervals = c.max_intervals.max(n);
        }
        // `intervals` alone means a fixed mesh, even if the file asks for refinement (as
        // the command line's --intervals).
        if tol.is_none() {
            c.tolerance = None;
        }
    }
    if let Some(t) = tol {
        c.tolerance = Some(t);
    }
    out.collocation.validate().map_err(crate::errors::to_py)?;
    Ok(out)
}
