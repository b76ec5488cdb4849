//! Solver options given as keyword arguments, applied over a robot's `[solver]` settings the
//! way the command line applies its flags.

use crate::convert::{self, type_name};
use crate::errors::invalid;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyString};
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

/// Reads a string option; another type is `tdcr.InvalidInput` naming it.
fn text(value: &Bound<'_, PyAny>, name: &str, what: &str) -> PyResult<String> {
    value
        .cast::<PyString>()
        .map(|s| s.to_string())
        .map_err(|_| invalid(format!("option `{name}` must be {what}, not {}", type_name(value))))
}

/// Which options a function uses, and its name for messages.
#[derive(Clone, Copy)]
pub enum Use<'a> {
    /// Either method's options, as the method chosen uses them (`solve`).
    Any(&'a str),
    /// Collocation's options (batches, sweeps, traces, inverse statics).
    Collocation(&'a str),
    /// Collocation's options on a fixed mesh, without `tol` (calibration).
    FixedMesh(&'a str),
}

/// The options only collocation uses.
const COLLOCATION_ONLY: [&str; 5] = ["tol", "intervals", "max_intervals", "continuation", "equilibrium"];

/// Refuses an option given to a function (or method) that would not use it.
fn check_used(given: &[String], method: Method, usage: Use<'_>) -> PyResult<()> {
    let (function, collocation_only) = match usage {
        Use::Any(f) => (f, false),
        Use::Collocation(f) | Use::FixedMesh(f) => (f, true),
    };
    if collocation_only && method != Method::Collocation {
        return Err(invalid(format!(
            "{function} solves by collocation; method=\"{method}\" is not used (leave `method` out or give \"collocation\")"
        )));
    }
    for name in given {
        let unused = match (name.as_str(), method) {
            ("integration_tolerance", Method::Collocation) => Some("the shooting method's"),
            ("tol", _) if matches!(usage, Use::FixedMesh(_)) => {
                Some("adaptive refinement's, and this function solves on a fixed mesh (give `intervals`)")
            }
            (n, Method::Shooting) if COLLOCATION_ONLY.contains(&n) => Some("collocation's"),
            _ => None,
        };
        if let Some(whose) = unused {
            return Err(invalid(format!(
                "{function}: option `{name}` is {whose}; it would not be used with method=\"{method}\" (leave it out)"
            )));
        }
    }
    Ok(())
}

/// `settings` with the options of `kwargs` applied: `method` ("collocation" or "shooting"),
/// `tol` (tip tolerance for adaptive refinement, relative to the rod length L: position to
/// tol x L, orientation to tol rad), `intervals` (a fixed mesh unless `tol`
/// is given too), `max_intervals`, `residual_tolerance`, `max_iterations`, `continuation`,
/// `equilibrium` ("load_path" or "nearest", collocation), `integration_tolerance`
/// (shooting). Unknown names and wrong types are
/// `tdcr.InvalidInput`; the values are checked by the solvers' own `Options::validate`.
pub fn apply(
    settings: &SolverSettings,
    kwargs: Option<&Bound<'_, PyDict>>,
    usage: Use<'_>,
) -> PyResult<SolverSettings> {
    let mut out = settings.clone();
    let Some(kwargs) = kwargs else {
        return Ok(out);
    };
    let (mut intervals, mut tol, mut cap) = (None, None, None);
    let mut given = Vec::new();
    for (key, value) in kwargs.iter() {
        let name: String = key.extract()?;
        if value.is_none() {
            continue;
        }
        let what = format!("option `{name}`");
        let (number, count) = (|| convert::number(&value, &what), || convert::count(&value, &what));
        let c = &mut out.collocation;
        match name.as_str() {
            "method" => {
                out.method = match text(&value, &name, "a string")?.as_str() {
                    "collocation" => Method::Collocation,
                    "shooting" => Method::Shooting,
                    other => {
                        return Err(invalid(format!(
                            "option `method` is \"{other}\"; use \"collocation\" or \"shooting\""
                        )));
                    }
                }
            }
            "tol" => tol = Some(number()?),
            "intervals" => intervals = Some(count()?),
            "max_intervals" => cap = Some(count()?),
            "residual_tolerance" => {
                let t = number()?;
                c.residual_tolerance = t;
                out.shooting.residual_tolerance = t;
            }
            "max_iterations" => {
                let n = count()?;
                c.max_iterations = n;
                out.shooting.max_iterations = n;
            }
            "continuation" => {
                c.continuation = value
                    .cast::<PyBool>()
                    .map_err(|_| invalid(format!("{what} must be True or False, not {}", type_name(&value))))?
                    .is_true();
            }
            "equilibrium" => {
                c.equilibrium = equilibrium(&text(&value, &name, &format!("a string, {EQUILIBRIUM_NAMES}"))?)?;
            }
            "integration_tolerance" => out.shooting.integration_tolerance = number()?,
            _ => {
                return Err(invalid(format!(
                    "unknown option `{name}`; the options are {OPTION_NAMES}"
                )));
            }
        }
        given.push(name);
    }
    check_used(&given, out.method, usage)?;
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
