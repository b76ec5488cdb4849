//! Pickling and copying of what the module returns and raises. A class pickles as a call of
//! its private static method `_from_state` on a dict of its fields (each field pickles by
//! itself: numbers, strings, numpy arrays, robots, solutions); a solve report as the
//! solution JSON (the one format that holds a whole report), bitwise.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Solution, SolveReport};

/// Field `name` of a pickled state.
///
/// # Errors
/// `tdcr.InvalidInput` for a state without it or with a value of another type (a pickle
/// of another version).
pub fn field<'py, T: FromPyObjectOwned<'py>>(state: &Bound<'py, PyDict>, name: &str) -> PyResult<T> {
    let bad = || {
        crate::errors::invalid(format!(
            "the pickled state lacks a valid `{name}`: it was made by another version of tdcr"
        ))
    };
    state.get_item(name)?.ok_or_else(bad)?.extract::<T>().map_err(|_| bad())
}

/// `#[pymethods]` of a class whose fields all pickle: `__reduce__` (the class's
/// `_from_state` and the dict of the fields), `_from_state`, and the class's other methods
/// (after the fields).
macro_rules! pickled_fields {
    ($ty:ident { $($field:ident),* $(,)? } $($methods:tt)*) => {
        #[pymethods]
        impl $ty {
            /// Pickling and copying go through the fields.
            fn __reduce__<'py>(
                slf: &Bound<'py, Self>,
            ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyDict>,))> {
                let (py, this) = (slf.py(), slf.get());
                let state = pyo3::types::PyDict::new(py);
                $( state.set_item(stringify!($field), &this.$field)?; )*
                Ok((slf.get_type().getattr("_from_state")?, (state,)))
            }

            /// The object of a state `__reduce__` made.
            #[staticmethod]
            fn _from_state(state: &Bound<'_, pyo3::types::PyDict>) -> PyResult<Self> {
                Ok($ty { $( $field: crate::pickle::field(state, stringify!($field))?, )* })
            }

            $($methods)*
        }
    };
}
pub(crate) use pickled_fields;

/// A report as solution JSON text: the report on a rest state of two nodes, s = 0 and 1 m
/// (the format's checks need a rod), no tendons.
pub fn report_text(report: &SolveReport) -> String {
    let node = |s: f64| tdcr::Node {
        s,
        p: Vector3::new(0.0, 0.0, s),
        R: Matrix3::identity(),
        v: Vector3::z(),
        u: Vector3::zeros(),
        v_s: Vector3::zeros(),
        u_s: Vector3::zeros(),
        n: Vector3::zeros(),
        m: Vector3::zeros(),
    };
    tdcr::io::output::solution_json(&Solution {
        nodes: vec![node(0.0), node(1.0)],
        tendon_paths: Vec::new(),
        tendons: Vec::new(),
        report: report.clone(),
    })
}

/// The report in `text`, as [`report_text`] wrote it.
///
/// # Errors
/// `tdcr.InvalidInput` for a text that is not a solution JSON.
pub fn report_from(text: &str) -> PyResult<SolveReport> {
    tdcr::io::parse_solution(text)
        .map(|s| s.report)
        .map_err(crate::errors::to_py)
}
