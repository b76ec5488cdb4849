//! `tdcr.SolveReport`: what a solve did (iterations, path, stability, error estimate,
//! notes), as Python values.

use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::{SolveReport, Stability, Termination};

/// What a solve did.
#[pyclass(module = "tdcr", name = "SolveReport", frozen)]
#[derive(Clone)]
pub struct PySolveReport {
    /// The library's report.
    pub report: SolveReport,
}

/// The short name of a termination, e.g. `converged`, `max_iterations`.
pub fn termination_name(t: Termination) -> &'static str {
    match t {
        Termination::Converged => "converged",
        Termination::MaxIterations => "max_iterations",
        Termination::LineSearchFailed => "line_search_failed",
        Termination::SingularJacobian => "singular_jacobian",
        Termination::NonFinite => "non_finite",
        Termination::ZonesUnsettled => "zones_unsettled",
    }
}

/// The details of a stability verdict: unstable directions (0 when stable, None when
/// unknown), the conjugate point's arc length (m, when unstable) and the reason (when
/// unknown).
fn stability_parts(stability: &Stability) -> (Option<usize>, Option<f64>, Option<&str>) {
    match stability {
        Stability::Stable => (Some(0), None, None),
        Stability::Unstable {
            directions,
            conjugate_point,
        } => (Some(*directions), Some(*conjugate_point), None),
        Stability::Unknown { reason } => (None, None, Some(reason)),
        Stability::Growing { .. } => (None, None, None),
    }
}

/// How an unstable state of non-conservative loads grows: ("divergence" or "flutter", the
/// growth rate in 1/s, the flutter frequency in Hz or None); None for any other verdict.
fn growth_parts(stability: &Stability) -> Option<(&'static str, f64, Option<f64>)> {
    match stability {
        Stability::Growing { growth, rate } => Some((
            growth.name(),
            *rate,
            match growth {
                tdcr::Growth::Flutter { frequency } => Some(*frequency),
                tdcr::Growth::Divergence => None,
            },
        )),
        _ => None,
    }
}

#[pymethods]
impl PySolveReport {
    /// Pickling and copying go through the report's fields (bitwise).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        Ok((
            slf.get_type().getattr("_from_state")?,
            (crate::pickle::report_state(slf.py(), &slf.get().report)?,),
        ))
    }

    /// The report of a state `__reduce__` made.
    #[staticmethod]
    fn _from_state(state: &Bound<'_, PyDict>) -> PyResult<Self> {
        crate::pickle::report_from(state).map(|report| PySolveReport { report })
    }

    /// "collocation" or "shooting".
    #[getter]
    fn method(&self) -> String {
        self.report.method.to_string()
    }

    /// Why Newton stopped, as a sentence: the `termination` of the solution JSON (`tdcr solve
    /// --format json`) and of `InverseResult` and `Calibration`. Until 2026-12-08 this was
    /// the short code, now `termination_code`.
    #[getter]
    fn termination(&self) -> String {
        self.report.termination.to_string()
    }

    /// Why Newton stopped, as a short code for comparisons: "converged", "max_iterations",
    /// "line_search_failed", "singular_jacobian", "non_finite" or "zones_unsettled".
    #[getter]
    fn termination_code(&self) -> &'static str {
        termination_name(self.report.termination)
    }

    /// The same sentence as `termination` (its name before 2026-12-08, kept for code
    /// written then).
    #[getter]
    fn termination_message(&self) -> String {
        self.report.termination.to_string()
    }

    /// Whether the solve converged.
    #[getter]
    fn converged(&self) -> bool {
        self.report.termination == Termination::Converged
    }

    /// Iterations (updates of the state), summed over load steps and meshes:
    /// `newton_steps + chord_steps`.
    #[getter]
    fn iterations(&self) -> usize {
        self.report.iterations
    }

    /// Newton steps: iterations that evaluated and factored a fresh Jacobian.
    #[getter]
    fn newton_steps(&self) -> usize {
        self.report.newton_steps
    }

    /// Chord steps: iterations solved with the factors of an earlier Jacobian.
    #[getter]
    fn chord_steps(&self) -> usize {
        self.report.chord_steps
    }

    /// Jacobian evaluations (`evaluations["jacobian"]`).
    #[getter]
    fn jacobian_evaluations(&self) -> usize {
        self.report.evaluations.jacobian
    }

    /// Continuation steps along the load path (0 for a direct solve, when Newton from the
    /// guess or warm start was enough).
    #[getter]
    fn load_steps(&self) -> usize {
        self.report.load_steps
    }

    /// Meshes solved on (1 without refinement).
    #[getter]
    fn meshes(&self) -> usize {
        self.report.meshes
    }

    /// Final scaled residual max-norm.
    #[getter]
    fn residual(&self) -> f64 {
        self.report.residual
    }

    /// Scaled residual before each step of the last Newton run, shape (iterations,).
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from_iter(self.report.history.iter().map(|i| i.residual)).into_pyarray(py)
    }

    /// Mesh intervals (collocation) or accepted integration steps (shooting).
    #[getter]
    fn intervals(&self) -> usize {
        self.report.intervals
    }

    /// Unknowns of the final system.
    #[getter]
    fn unknowns(&self) -> usize {
        self.report.unknowns
    }

    /// Estimated tip-position discretization error (m): the deferred-correction estimate
    /// every collocation solve carries; None for shooting.
    #[getter]
    fn tip_error_estimate(&self) -> Option<f64> {
        self.report.error_estimate.map(|e| e.tip_position)
    }

    /// The error estimate as a dict `{"tip_position_m", "tip_rotation_rad",
    /// "backbone_max_m", "order"}` (`order`: 4, or 6 for the deferred-corrected answer of
    /// tolerances at or below 1e-8), or None for shooting.
    #[getter]
    fn error_estimate<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.report
            .error_estimate
            .map(|e| {
                let d = PyDict::new(py);
                d.set_item("tip_position_m", e.tip_position)?;
                d.set_item("tip_rotation_rad", e.tip_rotation)?;
                d.set_item("backbone_max_m", e.backbone_max)?;
                d.set_item("order", e.order)?;
                Ok(d)
            })
            .transpose()
    }

    /// The tip tolerance the solve worked to, relative to the rod length; None on a fixed
    /// mesh.
    #[getter]
    fn tolerance(&self) -> Option<f64> {
        self.report.tolerance
    }

    /// Whether the error estimate meets the tolerance; None on a fixed mesh.
    #[getter]
    fn tolerance_met(&self) -> Option<bool> {
        self.report.tolerance_met
    }

    /// The stability verdict of the equilibrium returned: "stable" (a local minimum of
    /// the energy, a state a real robot can rest in), "unstable" (a small disturbance makes
    /// it buckle or snap) or "unknown" (the test does not apply; `stability_detail["reason"]`
    /// says why). docs/stability.md.
    #[getter]
    fn stability(&self) -> &'static str {
        self.report.stability.verdict()
    }

    /// The verdict as a sentence (as the command line prints it).
    #[getter]
    fn stability_message(&self) -> String {
        self.report.stability.to_string()
    }

    /// The verdict with its details: `{"verdict", "unstable_directions",
    /// "conjugate_point_s", "reason", "growth", "growth_rate", "flutter_frequency"}`: the
    /// number of unstable directions (0 when stable, None when unknown or from the
    /// linearized dynamics), the arc length of the conjugate point nearest the tip (m; None
    /// unless unstable by the conjugate-point test), why the verdict is unknown (None
    /// otherwise), and for non-conservative loads' unstable states "divergence" or
    /// "flutter", the growth rate (1/s) and a flutter's frequency (Hz); else None.
    #[getter]
    fn stability_detail<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (directions, conjugate_point, reason) = stability_parts(&self.report.stability);
        let d = PyDict::new(py);
        d.set_item("verdict", self.report.stability.verdict())?;
        d.set_item("unstable_directions", directions)?;
        d.set_item("conjugate_point_s", conjugate_point)?;
        d.set_item("reason", reason)?;
        let growth = growth_parts(&self.report.stability);
        d.set_item("growth", growth.map(|g| g.0))?;
        d.set_item("growth_rate", growth.map(|g| g.1))?;
        d.set_item("flutter_frequency", growth.and_then(|g| g.2))?;
        Ok(d)
    }

    /// How the equilibrium was reached: "direct" (Newton from the guess or warm start),
    /// "from_warm_start" (Newton's residual at the warm start followed to zero),
    /// "load_path" (the loads followed from the unloaded robot) or "fallback" (the load path
    /// could not be followed: Newton's root from the guess, stable or not; `notes` says why).
    #[getter]
    fn path(&self) -> &'static str {
        self.report.path.name()
    }

    /// Where the path turned back (load factors for "load_path", homotopy parameters for
    /// "from_warm_start"; empty for "direct" and "fallback"); past a fold the robot snaps
    /// through.
    #[getter]
    fn folds(&self) -> Vec<f64> {
        self.report.path.folds().to_vec()
    }

    /// Where the path crossed a bifurcation (the number of unstable directions changed
    /// without a fold); load factors or homotopy parameters as `folds`.
    #[getter]
    fn bifurcations(&self) -> Vec<f64> {
        self.report.path.bifurcations().to_vec()
    }

    /// What a user should know about the choice of the answer, one sentence each (the
    /// command line's `note:` lines): a side picked at a symmetric bifurcation and the
    /// mirror state left out, or where the load path stopped before a "fallback".
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.report.notes.clone()
    }

    /// Wall-clock seconds by stage: `assembly`, `factorization`, `solve`, `estimate` (the
    /// error estimate), `stability` (the stability verdict), `total`.
    #[getter]
    fn timings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.report.timings;
        let d = PyDict::new(py);
        d.set_item("assembly", t.assembly.as_secs_f64())?;
        d.set_item("factorization", t.factorization.as_secs_f64())?;
        d.set_item("solve", t.solve.as_secs_f64())?;
        d.set_item("estimate", t.estimate.as_secs_f64())?;
        d.set_item("stability", t.stability.as_secs_f64())?;
        d.set_item("total", t.total.as_secs_f64())?;
        Ok(d)
    }

    /// Evaluation counts: `residual`, `jacobian`, `equations`.
    #[getter]
    fn evaluations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = &self.report.evaluations;
        let d = PyDict::new(py);
        d.set_item("residual", e.residual)?;
        d.set_item("jacobian", e.jacobian)?;
        d.set_item("equations", e.equations)?;
        Ok(d)
    }

    /// The report's scalars as one flat dict (a row for a table of runs): `method`,
    /// `termination` (the sentence), `termination_code`, `converged`, `iterations`, `newton_steps`, `chord_steps`,
    /// `load_steps`, `meshes`, `jacobian_evaluations`, `residual_evaluations`, `residual`,
    /// `intervals`, `unknowns`, `tip_error_estimate`, `tolerance`, `tolerance_met`,
    /// `stability`, `unstable_directions`, `conjugate_point_s`, `stability_reason`, `path`,
    /// `folds`, `bifurcations`, and the timings in seconds as `time_assembly`, ...,
    /// `time_total`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.report;
        let d = PyDict::new(py);
        d.set_item("method", r.method.to_string())?;
        d.set_item("termination", r.termination.to_string())?;
        d.set_item("termination_code", termination_name(r.termination))?;
        d.set_item("converged", r.termination == Termination::Converged)?;
        d.set_item("iterations", r.iterations)?;
        d.set_item("newton_steps", r.newton_steps)?;
        d.set_item("chord_steps", r.chord_steps)?;
        d.set_item("load_steps", r.load_steps)?;
        d.set_item("meshes", r.meshes)?;
        d.set_item("jacobian_evaluations", r.evaluations.jacobian)?;
        d.set_item("residual_evaluations", r.evaluations.residual)?;
        d.set_item("residual", r.residual)?;
        d.set_item("intervals", r.intervals)?;
        d.set_item("unknowns", r.unknowns)?;
        d.set_item("tip_error_estimate", r.error_estimate.map(|e| e.tip_position))?;
        d.set_item("tolerance", r.tolerance)?;
        d.set_item("tolerance_met", r.tolerance_met)?;
        let (directions, conjugate_point, reason) = stability_parts(&r.stability);
        d.set_item("stability", r.stability.verdict())?;
        d.set_item("unstable_directions", directions)?;
        d.set_item("conjugate_point_s", conjugate_point)?;
        d.set_item("stability_reason", reason)?;
        let (path, folds, bifurcations) = (r.path.name(), r.path.folds(), r.path.bifurcations());
        d.set_item("path", path)?;
        d.set_item("folds", folds.to_vec())?;
        d.set_item("bifurcations", bifurcations.to_vec())?;
        let t = &r.timings;
        for (name, time) in [
            ("time_assembly", t.assembly),
            ("time_factorization", t.factorization),
            ("time_solve", t.solve),
            ("time_estimate", t.estimate),
            ("time_stability", t.stability),
            ("time_total", t.total),
        ] {
            d.set_item(name, time.as_secs_f64())?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let r = &self.report;
        format!(
            "SolveReport(method={}, termination={}, iterations={} ({} Newton, {} chord), load_steps={}, meshes={}, residual={:.3e}, stability={}, path={}, total={:.3} ms)",
            r.method,
            termination_name(r.termination),
            r.iterations,
            r.newton_steps,
            r.chord_steps,
            r.load_steps,
            r.meshes,
            r.residual,
            r.stability.verdict(),
            r.path.name(),
            r.timings.total.as_secs_f64() * 1e3
        )
    }
}
