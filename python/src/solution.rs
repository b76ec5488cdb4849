//! `tdcr.Solution`, `tdcr.SolveReport` and `tdcr.State`: the library's output types seen
//! as numpy arrays, and the solution's JSON round trip.

use crate::errors::{invalid, to_py};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Solution, SolveReport, Stability, TendonState, Termination};

/// A 3x3 matrix as a (3, 3) array.
pub fn matrix<'py>(py: Python<'py>, m: &Matrix3<f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((3, 3), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// 3-vectors as an (N, 3) array.
pub fn vectors<'py>(py: Python<'py>, v: impl ExactSizeIterator<Item = Vector3<f64>>) -> Bound<'py, PyArray2<f64>> {
    let n = v.len();
    let flat: Vec<f64> = v.flat_map(|x| [x.x, x.y, x.z]).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((n, 3), flat)
        .expect("n rows of 3")
        .into_pyarray(py)
}

/// A solved shape: the nodes along the backbone (two at every jump: left then right limit),
/// the tendon paths and states, the tip pose, the scheme's interpolant (`at`) and the
/// `report`. Arrays
/// are float64, SI units, world frame unless said otherwise; each access returns a new array.
#[pyclass(module = "tdcr", name = "Solution", frozen)]
#[derive(Clone)]
pub struct PySolution {
    /// The library's solution.
    pub solution: Solution,
}

/// The state at one arc length, from `Solution.at(s)`.
#[pyclass(module = "tdcr", name = "State", frozen, get_all)]
#[allow(non_snake_case)]
pub struct PyState {
    /// Arc length (m).
    s: f64,
    /// Position (m), world frame, (3,).
    p: Py<PyArray1<f64>>,
    /// Orientation, body to world, (3, 3).
    R: Py<PyArray2<f64>>,
    /// Shear/extension strain, body frame, (3,).
    v: Py<PyArray1<f64>>,
    /// Curvature/twist, body frame (rad/m), (3,).
    u: Py<PyArray1<f64>>,
}

crate::pickle::pickled_fields! {
    PyState { s, p, R, v, u }

    fn __repr__(&self) -> String {
        format!("State(s={} m)", self.s)
    }
}

#[pymethods]
impl PySolution {
    /// Arc lengths of the nodes (m), shape (N,), non-decreasing from 0 to L.
    #[getter]
    fn s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let s: Vec<f64> = self.solution.nodes.iter().map(|n| n.s).collect();
        PyArray1::from_vec(py, s)
    }

    /// Centreline positions (m), shape (N, 3).
    #[getter]
    fn p<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.p))
    }

    /// Orientations, body to world, shape (N, 3, 3).
    #[getter]
    #[allow(non_snake_case)]
    fn R<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let nodes = &self.solution.nodes;
        Array3::from_shape_fn((nodes.len(), 3, 3), |(k, i, j)| nodes[k].R[(i, j)]).into_pyarray(py)
    }

    /// Shear/extension strains v (body frame, dimensionless), shape (N, 3).
    #[getter]
    fn v<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.v))
    }

    /// Curvature/twist u (body frame, rad/m), shape (N, 3).
    #[getter]
    fn u<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.u))
    }

    /// Internal forces n (N, world frame), shape (N, 3).
    #[getter]
    fn n<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.n))
    }

    /// Internal moments m (N m, world frame), shape (N, 3).
    #[getter]
    fn m<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        vectors(py, self.solution.nodes.iter().map(|n| n.m))
    }

    /// Each tendon's path p + R r_i (m, world frame) at the nodes up to its end: a list of
    /// (N_i, 3) arrays, file order.
    #[getter]
    fn tendon_paths<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray2<f64>>> {
        self.solution
            .tendon_paths
            .iter()
            .map(|path| vectors(py, path.iter().copied()))
            .collect()
    }

    /// What the solution says about each tendon, file order: a list of dicts with
    /// `tension` (N, at the base entry: the input of a tension-controlled tendon, the solved
    /// one of a displacement-controlled tendon, 0 when slack), `delivered_tension` (N, at the
    /// termination: lower than `tension` when friction holds the tendon back,
    /// docs/friction.md), `displacement` (m: the actuator's
    /// pull-in, the input of a displacement-controlled tendon, for a tension-controlled one
    /// the pull-in that holds it taut at its tension), `length` (m, the path length from the
    /// base to the termination), `reference_length` (m, the same in the unloaded shape) and
    /// `slack` (m, 0 when taut). docs/actuation.md has the definitions.
    #[getter]
    fn tendons<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.solution.tendons.iter().map(|t| tendon_dict(py, t)).collect()
    }

    /// Each tendon's tension (N) at the points of its path (`tendon_paths`), file order:
    /// constant without friction, varying along the tendon with it (docs/friction.md).
    #[getter]
    fn tendon_tensions<'py>(&self, py: Python<'py>) -> Vec<Bound<'py, PyArray1<f64>>> {
        self.solution
            .tendon_tensions
            .iter()
            .map(|t| PyArray1::from_slice(py, t))
            .collect()
    }

    /// Tendon tensions (N), shape (k,), file order (the `tension` of `tendons`).
    #[getter]
    fn tensions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.solution.tensions())
    }

    /// Tip position (m), shape (3,).
    #[getter]
    fn tip_position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.solution.tip_position().as_slice())
    }

    /// Tip orientation, body to world, shape (3, 3).
    #[getter]
    fn tip_rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.solution.tip().R)
    }

    /// Backbone length L (m).
    #[getter]
    fn length(&self) -> f64 {
        self.solution.length()
    }

    /// How the solve went (a `SolveReport`).
    #[getter]
    fn report(&self) -> PySolveReport {
        PySolveReport {
            report: self.solution.report.clone(),
        }
    }

    /// The state (s, p, R, v, u) at arc length `s` (m, clamped to [0, L]) from the scheme's
    /// cubic Hermite interpolant on SO(3); at a jump the right limit (`left=True`: the left).
    #[pyo3(signature = (s, left=false))]
    fn at(&self, py: Python<'_>, s: &Bound<'_, PyAny>, left: bool) -> PyResult<PyState> {
        let s = crate::convert::number(s, "Solution.at: `s`")?;
        if !s.is_finite() {
            return Err(invalid(format!("Solution.at: s = {s} m is not finite")));
        }
        let x = self.solution.at_limit(s, left);
        Ok(PyState {
            s: x.s,
            p: PyArray1::from_slice(py, x.p.as_slice()).unbind(),
            R: matrix(py, &x.R).unbind(),
            v: PyArray1::from_slice(py, x.v.as_slice()).unbind(),
            u: PyArray1::from_slice(py, x.u.as_slice()).unbind(),
        })
    }

    /// plot(ax=None, *, tendons=True, label=None) -> Axes
    ///
    /// Draws the shape with matplotlib (the `plot` extra): `tdcr.plot(self, ...)`.
    #[pyo3(signature = (ax=None, **kwargs))]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<&Bound<'py, PyAny>>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let plot = slf.py().import("tdcr.plotting")?.getattr("plot")?;
        plot.call((slf, ax), kwargs)
    }

    /// The whole solution as the solution JSON of `tdcr solve --format json` (every node
    /// with its derivatives, the tendon paths and states, the report; docs/cli.md), without
    /// the keys that need the robot (`end`, `turns`, `jacobian`); `Solution.from_json` reads
    /// it back to the same solution, bitwise.
    fn to_json(&self) -> String {
        tdcr::io::output::solution_json(&self.solution)
    }

    /// Reads a solution JSON: `Solution.to_json`'s or the file `tdcr solve --format json`
    /// wrote. Raises `tdcr.InvalidInput` naming what is wrong.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Ok(PySolution {
            solution: tdcr::io::parse_solution(text).map_err(to_py)?,
        })
    }

    /// Pickling goes through the JSON.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        Ok((
            slf.get_type().getattr("from_json")?,
            (tdcr::io::output::solution_json(&slf.get().solution),),
        ))
    }

    fn __repr__(&self) -> String {
        let p = self.solution.tip_position();
        format!(
            "Solution(nodes={}, tip=[{:.9}, {:.9}, {:.9}] m, {}, {})",
            self.solution.nodes.len(),
            p.x,
            p.y,
            p.z,
            termination_name(self.solution.report.termination),
            self.solution.report.stability.verdict()
        )
    }
}

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
    }
}

/// A tendon state as the dict of `Solution.tendons`.
fn tendon_dict<'py>(py: Python<'py>, t: &TendonState) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("tension", t.tension)?;
    d.set_item("delivered_tension", t.delivered_tension)?;
    d.set_item("displacement", t.displacement)?;
    d.set_item("length", t.length)?;
    d.set_item("reference_length", t.reference_length)?;
    d.set_item("slack", t.slack)?;
    Ok(d)
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

    /// Why Newton stopped: "converged", "max_iterations", "line_search_failed",
    /// "singular_jacobian" or "non_finite".
    #[getter]
    fn termination(&self) -> &'static str {
        termination_name(self.report.termination)
    }

    /// The termination as a sentence (as the command line prints it).
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
    /// `termination`, `converged`, `iterations`, `newton_steps`, `chord_steps`,
    /// `load_steps`, `meshes`, `jacobian_evaluations`, `residual_evaluations`, `residual`,
    /// `intervals`, `unknowns`, `tip_error_estimate`, `tolerance`, `tolerance_met`,
    /// `stability`, `unstable_directions`, `conjugate_point_s`, `stability_reason`, `path`,
    /// `folds`, `bifurcations`, and the timings in seconds as `time_assembly`, ...,
    /// `time_total`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.report;
        let d = PyDict::new(py);
        d.set_item("method", r.method.to_string())?;
        d.set_item("termination", termination_name(r.termination))?;
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
