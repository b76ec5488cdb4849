//! Python values in: robot tables as TOML, numbers, parameter columns. Every conversion is
//! bounded (nesting depth, containers that contain themselves), refuses booleans where a
//! number is meant, and names the field it was reading in its `tdcr.InvalidInput`.

use crate::errors::invalid;
use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use toml::{Table, Value};

/// The deepest nesting of lists and dicts a robot's tables can need is 4 (`tendon[1].routing`
/// in the tendon list of the document, or a base rotation's rows); 32 leaves room and keeps
/// the conversion's stack use to a few kilobytes, even on a thread with a small stack.
pub const MAX_DEPTH: usize = 32;

/// A walk through nested Python values: the containers open above the current one, to
/// refuse one that contains itself and a nesting deeper than [`MAX_DEPTH`].
#[derive(Default)]
pub struct Walk {
    open: Vec<usize>,
}

impl Walk {
    /// Enters `value` (named `path`), or refuses it.
    fn enter(&mut self, value: &Bound<'_, PyAny>, path: &str) -> PyResult<()> {
        let id = value.as_ptr() as usize;
        if self.open.contains(&id) {
            return Err(invalid(format!(
                "`{path}` contains itself; give numbers, strings, booleans, lists or dicts as in a robot file"
            )));
        }
        if self.open.len() >= MAX_DEPTH {
            return Err(invalid(format!(
                "`{path}` is nested more than {MAX_DEPTH} levels deep; a robot file's tables nest at most 4"
            )));
        }
        self.open.push(id);
        Ok(())
    }

    /// Leaves the container entered last.
    fn leave(&mut self) {
        self.open.pop();
    }

    /// A Python value (numbers, strings, bools, lists, tuples, dicts, numpy arrays) as TOML;
    /// `path` names it in messages.
    pub fn toml(&mut self, value: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
        if value.is_instance_of::<PyBool>() {
            return Ok(Value::Boolean(value.extract()?));
        }
        if value.is_instance_of::<PyInt>() {
            return value.extract().map(Value::Integer).map_err(|_| {
                invalid(format!(
                    "`{path}` is {value}, beyond the 64-bit integers a robot file holds"
                ))
            });
        }
        if value.is_instance_of::<PyFloat>() {
            return Ok(Value::Float(value.extract()?));
        }
        if value.is_instance_of::<PyString>() {
            return Ok(Value::String(value.extract()?));
        }
        self.enter(value, path)?;
        let out = self.container(value, path);
        self.leave();
        out
    }

    /// A dict, list, tuple or numpy value as TOML.
    fn container(&mut self, value: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
        if let Ok(dict) = value.cast::<PyDict>() {
            return Ok(Value::Table(self.table(dict, path)?));
        }
        // The items by index (a subclass's own iterator is not consulted, so it cannot run
        // forever).
        let item_path = |i: usize| format!("{path}[{}]", i + 1);
        if let Ok(list) = value.cast::<PyList>() {
            let items: PyResult<Vec<Value>> = list
                .iter()
                .enumerate()
                .map(|(i, x)| self.toml(&x, &item_path(i)))
                .collect();
            return Ok(Value::Array(items?));
        }
        if let Ok(tuple) = value.cast::<PyTuple>() {
            let items: PyResult<Vec<Value>> = tuple
                .iter()
                .enumerate()
                .map(|(i, x)| self.toml(&x, &item_path(i)))
                .collect();
            return Ok(Value::Array(items?));
        }
        // numpy arrays and scalars: their Python equivalents.
        if value.hasattr("tolist")? {
            let plain = value
                .call_method0("tolist")
                .map_err(|e| invalid(format!("`{path}`: its tolist() failed: {e}")))?;
            return self.toml(&plain, path);
        }
        Err(invalid(format!(
            "`{path}` is a {}; give numbers, strings, booleans, lists or dicts as in a robot file",
            type_name(value)
        )))
    }

    /// A dict with string keys as a TOML table (None values left out); `path` names it.
    pub fn table(&mut self, dict: &Bound<'_, PyDict>, path: &str) -> PyResult<Table> {
        let mut out = Table::new();
        for (key, value) in dict.iter() {
            let key: String = key
                .extract()
                .map_err(|_| invalid(format!("`{path}` has a key that is not a string: {key}")))?;
            let inner = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            if !value.is_none() {
                out.insert(key, self.toml(&value, &inner)?);
            }
        }
        Ok(out)
    }
}

/// The Python type name of `value`, for messages.
pub fn type_name(value: &Bound<'_, PyAny>) -> String {
    value
        .get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// Whether `value` is a boolean: Python's `bool` or numpy's `bool_`, which Python would
/// otherwise take as 1 or 0.
fn is_boolean(value: &Bound<'_, PyAny>) -> bool {
    value.is_instance_of::<PyBool>() || type_name(value) == "bool" || type_name(value) == "bool_"
}

/// A number (int, float or numpy scalar; not a boolean) as f64; `what` names it.
pub fn number(value: &Bound<'_, PyAny>, what: &str) -> PyResult<f64> {
    if is_boolean(value) {
        return Err(invalid(format!("{what} must be a number, not a boolean ({value})")));
    }
    value
        .extract::<f64>()
        .map_err(|_| invalid(format!("{what} must be a number, not {}", type_name(value))))
}

/// A whole number >= 0 (not a boolean) as usize; `what` names it, and a negative value or
/// one beyond 64 bits is `tdcr.InvalidInput` naming it (not an `OverflowError`).
pub fn count(value: &Bound<'_, PyAny>, what: &str) -> PyResult<usize> {
    if is_boolean(value) {
        return Err(invalid(format!(
            "{what} must be a whole number, not a boolean ({value})"
        )));
    }
    if !value.is_instance_of::<PyInt>() && !type_name(value).starts_with("int") && !type_name(value).starts_with("uint")
    {
        return Err(invalid(format!(
            "{what} must be a whole number, not {}",
            type_name(value)
        )));
    }
    value.extract::<usize>().map_err(|_| {
        invalid(format!(
            "{what} is {value}; give a whole number from 0 to {}",
            usize::MAX
        ))
    })
}

/// Whether `value` is a boolean or a list or tuple holding one, `depth` levels down.
fn holds_boolean(value: &Bound<'_, PyAny>, depth: usize) -> bool {
    if is_boolean(value) {
        return true;
    }
    let items = match (value.cast::<PyList>(), value.cast::<PyTuple>()) {
        (Ok(list), _) => list.iter().collect::<Vec<_>>(),
        (_, Ok(tuple)) => tuple.iter().collect(),
        _ => return false,
    };
    depth > 0 && items.iter().any(|item| holds_boolean(item, depth - 1))
}

/// `value` as a float64 numpy array of `ndim` dimensions (a list, tuple or array of
/// numbers; not booleans, which numpy would take as 1 and 0); `shape` says what is wanted
/// and `what` names it in messages.
fn float_array<'py>(value: &Bound<'py, PyAny>, ndim: usize, shape: &str, what: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = value.py().import("numpy")?;
    let bad = || invalid(format!("{what} must be {shape} of numbers"));
    let raw = np.call_method1("asarray", (value,)).map_err(|_| bad())?;
    let kind: String = raw.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind == "b" || holds_boolean(value, ndim) {
        return Err(invalid(format!("{what} holds booleans; give numbers")));
    }
    let array = np.call_method1("asarray", (raw, "float64")).map_err(|_| bad())?;
    if array.getattr("ndim")?.extract::<usize>()? != ndim {
        return Err(bad());
    }
    Ok(array)
}

/// A 1-D sequence of numbers (list, tuple, numpy array; no booleans) as f64 values; `what`
/// names it.
pub fn numbers(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    Ok(number_array(value, what)?.readonly().as_array().to_vec())
}

/// As [`numbers`], as a float64 array: the value itself when it is one (not copied), else
/// its conversion.
pub fn number_array<'py>(value: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    Ok(float_array(value, 1, "a 1-D sequence", what)?.cast_into::<numpy::PyArray1<f64>>()?)
}

/// [`number`] of an optional value (None stays None).
pub fn optional_number(value: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<f64>> {
    value.filter(|v| !v.is_none()).map(|v| number(v, what)).transpose()
}

/// A sequence of whole numbers >= 0 (no booleans); `what` names it.
pub fn counts(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<usize>> {
    let items = value.try_iter().map_err(|_| {
        invalid(format!(
            "{what} must be a sequence of whole numbers, not {}",
            type_name(value)
        ))
    })?;
    items
        .enumerate()
        .map(|(i, item)| count(&item?, &format!("{what}[{i}]")))
        .collect()
}

/// A 2-D nested sequence or array of numbers (no booleans), every row `width` long when
/// given; `what` names it.
pub fn table_of(value: &Bound<'_, PyAny>, what: &str, width: Option<usize>) -> PyResult<Vec<Vec<f64>>> {
    let shape = width.map_or("(M, k)".to_string(), |w| format!("(M, {w})"));
    let array = float_array(value, 2, &format!("a {shape} array"), what)?;
    let view: numpy::PyReadonlyArray2<f64> = array.extract()?;
    let view = view.as_array();
    if let Some(w) = width
        && view.ncols() != w
    {
        return Err(invalid(format!(
            "{what} has rows of {} values; give {shape}",
            view.ncols()
        )));
    }
    Ok(view.rows().into_iter().map(|r| r.to_vec()).collect())
}

/// `calibrate`'s `motions` for `rows` measurements: each "pull", "release" or None (the
/// robot's own motion); all None when not given.
pub fn motions(motions: Option<Vec<Option<String>>>, rows: usize) -> PyResult<Vec<Option<tdcr::Motion>>> {
    let Some(motions) = motions else {
        return Ok(vec![None; rows]);
    };
    if motions.len() != rows {
        return Err(invalid(format!(
            "calibrate: {} motions for {rows} measurements; give one per measurement (\"pull\", \"release\" or None)",
            motions.len()
        )));
    }
    motions
        .into_iter()
        .enumerate()
        .map(|(k, m)| match m.as_deref().map(str::trim) {
            None => Ok(None),
            Some(name) => tdcr::Motion::from_name(name).map(Some).ok_or_else(|| {
                invalid(format!(
                    "calibrate: motions[{k}] is \"{name}\"; give {} or None (the robot's motion)",
                    tdcr::Motion::CHOICES
                ))
            }),
        })
        .collect()
}

/// The standard errors `se` of a calibration's fitted unknowns as a dict keyed by their
/// names (`Fit::names`: `E`, `alpha`, ..., `mu`), in the units of `Calibration`'s attributes:
/// E in Pa, the Euler angles in deg (as `euler_deg`), the base position in m.
pub fn standard_errors(
    py: Python<'_>,
    fit: &tdcr::fit::calibration::Fit,
    se: &tdcr::fit::calibration::Parameters,
) -> PyResult<Py<PyDict>> {
    let out = PyDict::new(py);
    for name in fit.names() {
        let value = match name {
            "E" => se.youngs_modulus,
            "alpha" => se.euler_deg().x,
            "beta" => se.euler_deg().y,
            "gamma" => se.euler_deg().z,
            "x0" => se.base_position.x,
            "y0" => se.base_position.y,
            "z0" => se.base_position.z,
            "offset_scale" => se.offset_scale,
            "mu" => se.friction,
            _ => f64::NAN,
        };
        out.set_item(name, value)?;
    }
    Ok(out.unbind())
}
