//! Pickling and copying of what the module returns and raises. A class pickles as a call of
//! its private static method `_from_state` on a dict of its fields (each field pickles by
//! itself: numbers, strings, numpy arrays, robots, solutions); a solve report as a dict
//! of its fields in plain values, bitwise.

use crate::report::termination_name;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::Duration;
use tdcr::{ErrorEstimate, Evaluations, Iteration, Method, PathTaken, SolveReport, Stability, Termination, Timings};

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

/// A report as a dict of plain values (floats kept bitwise, infinities and NaN signs
/// included, which JSON could not keep).
pub fn report_state<'py>(py: Python<'py>, r: &SolveReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("method", r.method.to_string())?;
    d.set_item("termination", termination_name(r.termination))?;
    let counts = [r.iterations, r.newton_steps, r.chord_steps, r.load_steps, r.meshes];
    d.set_item("counts", counts)?;
    let history: Vec<(f64, f64, f64, bool)> = r
        .history
        .iter()
        .map(|i| (i.residual, i.step, i.damping, i.fresh_jacobian))
        .collect();
    d.set_item("history", history)?;
    d.set_item("residual", r.residual)?;
    let e = &r.evaluations;
    d.set_item("evaluations", [e.residual, e.jacobian, e.equations])?;
    let t = &r.timings;
    let nanos = [t.assembly, t.factorization, t.solve, t.estimate, t.stability, t.total].map(|d| d.as_nanos());
    d.set_item("timings_ns", nanos)?;
    d.set_item("sizes", [r.unknowns, r.nonzeros, r.intervals])?;
    let estimate = r
        .error_estimate
        .map(|e| [e.tip_position, e.tip_rotation, e.backbone_max]);
    d.set_item("error_estimate", estimate)?;
    d.set_item("error_estimate_order", r.error_estimate.map(|e| e.order))?;
    d.set_item("tolerance", r.tolerance)?;
    d.set_item("tolerance_met", r.tolerance_met)?;
    let (directions, conjugate_point, reason) = match &r.stability {
        Stability::Stable => (None, None, None),
        Stability::Unstable {
            directions,
            conjugate_point,
        } => (Some(*directions), Some(*conjugate_point), None),
        Stability::Unknown { reason } => (None, None, Some(reason.clone())),
        Stability::Growing { .. } => (None, None, None),
    };
    d.set_item(
        "stability",
        (r.stability.verdict(), directions, conjugate_point, reason),
    )?;
    if let Stability::Growing { growth, rate } = &r.stability {
        let frequency = match growth {
            tdcr::Growth::Flutter { frequency } => Some(*frequency),
            tdcr::Growth::Divergence => None,
        };
        d.set_item("growth", (growth.name(), *rate, frequency))?;
    }
    d.set_item(
        "path",
        (r.path.name(), r.path.folds().to_vec(), r.path.bifurcations().to_vec()),
    )?;
    d.set_item("notes", r.notes.clone())?;
    Ok(d)
}

/// The report of a dict [`report_state`] made.
///
/// # Errors
/// `tdcr.InvalidInput` for a dict of another version.
pub fn report_from(d: &Bound<'_, PyDict>) -> PyResult<SolveReport> {
    let bad = |what: &str| {
        crate::errors::invalid(format!(
            "the pickled report has an unknown {what}: it was made by another version of tdcr"
        ))
    };
    let method = match field::<String>(d, "method")?.as_str() {
        "collocation" => Method::Collocation,
        "shooting" => Method::Shooting,
        _ => return Err(bad("method")),
    };
    let mut r = SolveReport::new(method);
    let termination: String = field(d, "termination")?;
    r.termination = Termination::ALL
        .into_iter()
        .find(|t| termination_name(*t) == termination)
        .ok_or_else(|| bad("termination"))?;
    [r.iterations, r.newton_steps, r.chord_steps, r.load_steps, r.meshes] = field(d, "counts")?;
    let history: Vec<(f64, f64, f64, bool)> = field(d, "history")?;
    r.history = history
        .into_iter()
        .map(|(residual, step, damping, fresh_jacobian)| Iteration {
            residual,
            step,
            damping,
            fresh_jacobian,
        })
        .collect();
    r.residual = field(d, "residual")?;
    let [residual, jacobian, equations] = field(d, "evaluations")?;
    r.evaluations = Evaluations {
        residual,
        jacobian,
        equations,
    };
    let [assembly, factorization, solve, estimate, stability, total] =
        field::<[u64; 6]>(d, "timings_ns")?.map(Duration::from_nanos);
    r.timings = Timings {
        assembly,
        factorization,
        solve,
        estimate,
        stability,
        total,
    };
    [r.unknowns, r.nonzeros, r.intervals] = field(d, "sizes")?;
    let order: Option<u32> = field(d, "error_estimate_order")?;
    r.error_estimate =
        field::<Option<[f64; 3]>>(d, "error_estimate")?.map(|[tip_position, tip_rotation, backbone_max]| {
            ErrorEstimate {
                tip_position,
                tip_rotation,
                backbone_max,
                order: order.unwrap_or(4),
            }
        });
    r.tolerance = field(d, "tolerance")?;
    r.tolerance_met = field(d, "tolerance_met")?;
    let (verdict, directions, conjugate_point, reason): (String, Option<usize>, Option<f64>, Option<String>) =
        field(d, "stability")?;
    r.stability = match (verdict.as_str(), directions, conjugate_point, reason) {
        ("stable", ..) => Stability::Stable,
        ("unstable", Some(directions), Some(conjugate_point), _) => Stability::Unstable {
            directions,
            conjugate_point,
        },
        ("unknown", _, _, Some(reason)) => Stability::Unknown { reason },
        ("unstable", None, None, _) => {
            let (name, rate, frequency): (String, f64, Option<f64>) = field(d, "growth")?;
            let growth = match (name.as_str(), frequency) {
                ("divergence", _) => tdcr::Growth::Divergence,
                ("flutter", Some(frequency)) => tdcr::Growth::Flutter { frequency },
                _ => return Err(bad("growth")),
            };
            Stability::Growing { growth, rate }
        }
        _ => return Err(bad("stability")),
    };
    let (path, folds, bifurcations): (String, Vec<f64>, Vec<f64>) = field(d, "path")?;
    r.path = PathTaken::from_name(&path, folds, bifurcations).ok_or_else(|| bad("path"))?;
    r.notes = field(d, "notes")?;
    Ok(r)
}
