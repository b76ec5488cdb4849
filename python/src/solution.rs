//! `tdcr.Solution`, `tdcr.SolveReport` and `tdcr.State`: the library's output types seen
//! as numpy arrays, and the solution's JSON round trip.

use crate::errors::invalid;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Value, json};
use std::time::Duration;
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{
    ErrorEstimate, Evaluations, Iteration, Method, Node, Path, Solution, SolveReport, Stability, TendonState,
    Termination, Timings,
};

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

#[pymethods]
impl PyState {
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
    /// `tension` (N: the input of a tension-controlled tendon, the solved one of a
    /// displacement-controlled tendon, 0 when slack), `displacement` (m: the actuator's
    /// pull-in, the input of a displacement-controlled tendon, for a tension-controlled one
    /// the pull-in that holds it taut at its tension), `length` (m, the path length from the
    /// base to the termination), `reference_length` (m, the same in the unloaded shape) and
    /// `slack` (m, 0 when taut). docs/actuation.md has the definitions.
    #[getter]
    fn tendons<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.solution.tendons.iter().map(|t| tendon_dict(py, t)).collect()
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
    fn at(&self, py: Python<'_>, s: f64, left: bool) -> PyResult<PyState> {
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

    /// The whole solution as JSON (every node with its derivatives, the tendon paths and
    /// the report); `Solution.from_json` reads it back to the same solution, bitwise.
    fn to_json(&self) -> String {
        solution_json(&self.solution).to_string()
    }

    /// Reads the JSON of `Solution.to_json`. Raises `tdcr.InvalidInput` naming what is wrong.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let value: Value = serde_json::from_str(text).map_err(|e| invalid(format!("Solution.from_json: {e}")))?;
        Ok(PySolution {
            solution: read_solution(&value).map_err(|e| invalid(format!("Solution.from_json: {e}")))?,
        })
    }

    /// Pickling goes through the JSON.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        Ok((
            slf.get_type().getattr("from_json")?,
            (solution_json(&slf.get().solution).to_string(),),
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
    d.set_item("displacement", t.displacement)?;
    d.set_item("length", t.length)?;
    d.set_item("reference_length", t.reference_length)?;
    d.set_item("slack", t.slack)?;
    Ok(d)
}

/// The short name of a path, its folds and its bifurcations: `direct`, `from_warm_start`
/// or `load_path`.
pub fn path_parts(path: &Path) -> (&'static str, &[f64], &[f64]) {
    match path {
        Path::Direct => ("direct", &[], &[]),
        Path::FromWarmStart { folds, bifurcations } => ("from_warm_start", folds, bifurcations),
        Path::LoadPath { folds, bifurcations } => ("load_path", folds, bifurcations),
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
    }
}

const TERMINATIONS: [Termination; 5] = [
    Termination::Converged,
    Termination::MaxIterations,
    Termination::LineSearchFailed,
    Termination::SingularJacobian,
    Termination::NonFinite,
];

#[pymethods]
impl PySolveReport {
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
    /// "backbone_max_m"}`, or None for shooting.
    #[getter]
    fn error_estimate<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.report
            .error_estimate
            .map(|e| {
                let d = PyDict::new(py);
                d.set_item("tip_position_m", e.tip_position)?;
                d.set_item("tip_rotation_rad", e.tip_rotation)?;
                d.set_item("backbone_max_m", e.backbone_max)?;
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
    /// "conjugate_point_s", "reason"}`: the number of unstable directions (0 when stable,
    /// None when unknown), the arc length of the conjugate point nearest the tip (m; None
    /// unless unstable) and why the verdict is unknown (None otherwise).
    #[getter]
    fn stability_detail<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (directions, conjugate_point, reason) = stability_parts(&self.report.stability);
        let d = PyDict::new(py);
        d.set_item("verdict", self.report.stability.verdict())?;
        d.set_item("unstable_directions", directions)?;
        d.set_item("conjugate_point_s", conjugate_point)?;
        d.set_item("reason", reason)?;
        Ok(d)
    }

    /// How the equilibrium was reached: "direct" (Newton from the guess or warm start),
    /// "from_warm_start" (Newton's residual at the warm start followed to zero) or
    /// "load_path" (the loads followed from the unloaded robot).
    #[getter]
    fn path(&self) -> &'static str {
        path_parts(&self.report.path).0
    }

    /// Where the path turned back (load factors for "load_path", homotopy parameters for
    /// "from_warm_start"; empty for "direct"); past a fold the robot snaps through.
    #[getter]
    fn folds(&self) -> Vec<f64> {
        path_parts(&self.report.path).1.to_vec()
    }

    /// Where the path crossed a bifurcation (the number of unstable directions changed
    /// without a fold); load factors or homotopy parameters as `folds`.
    #[getter]
    fn bifurcations(&self) -> Vec<f64> {
        path_parts(&self.report.path).2.to_vec()
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
        let (path, folds, bifurcations) = path_parts(&r.path);
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
            path_parts(&r.path).0,
            r.timings.total.as_secs_f64() * 1e3
        )
    }
}

fn vec_json(v: &Vector3<f64>) -> Value {
    json!([v.x, v.y, v.z])
}

fn mat_json(m: &Matrix3<f64>) -> Value {
    json!([
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]]
    ])
}

fn nanos(d: Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// The `format` of `Solution.to_json` texts (1 had no tendon states, counts or stability).
const FORMAT: &str = "tdcr-solution-2";

/// The solution as JSON (non-finite numbers as null, read back as NaN).
fn solution_json(solution: &Solution) -> Value {
    let nodes: Vec<Value> = solution
        .nodes
        .iter()
        .map(|n| {
            json!({"s": n.s, "p": vec_json(&n.p), "R": mat_json(&n.R), "v": vec_json(&n.v), "u": vec_json(&n.u),
                   "v_s": vec_json(&n.v_s), "u_s": vec_json(&n.u_s), "n": vec_json(&n.n), "m": vec_json(&n.m)})
        })
        .collect();
    let paths: Vec<Value> = solution
        .tendon_paths
        .iter()
        .map(|p| Value::Array(p.iter().map(vec_json).collect()))
        .collect();
    let r = &solution.report;
    let history: Vec<Value> = r
        .history
        .iter()
        .map(|i| json!({"residual": i.residual, "step": i.step, "damping": i.damping, "fresh_jacobian": i.fresh_jacobian}))
        .collect();
    let tendons: Vec<Value> = solution
        .tendons
        .iter()
        .map(|t| {
            json!({"tension": t.tension, "displacement": t.displacement, "length": t.length,
                   "reference_length": t.reference_length, "slack": t.slack})
        })
        .collect();
    let t = &r.timings;
    let (directions, conjugate_point, reason) = stability_parts(&r.stability);
    let (path, folds, bifurcations) = path_parts(&r.path);
    json!({
        "format": FORMAT,
        "nodes": nodes,
        "tendon_paths": paths,
        "tendons": tendons,
        "report": {
            "method": r.method.to_string(),
            "termination": termination_name(r.termination),
            "iterations": r.iterations,
            "newton_steps": r.newton_steps,
            "chord_steps": r.chord_steps,
            "load_steps": r.load_steps,
            "meshes": r.meshes,
            "history": history,
            "residual": r.residual,
            "evaluations": {"residual": r.evaluations.residual, "jacobian": r.evaluations.jacobian, "equations": r.evaluations.equations},
            "timings_ns": {"assembly": nanos(t.assembly), "factorization": nanos(t.factorization), "solve": nanos(t.solve), "estimate": nanos(t.estimate), "stability": nanos(t.stability), "total": nanos(t.total)},
            "unknowns": r.unknowns,
            "nonzeros": r.nonzeros,
            "intervals": r.intervals,
            "error_estimate": r.error_estimate.map(|e| json!({
                "tip_position_m": e.tip_position, "tip_rotation_rad": e.tip_rotation, "backbone_max_m": e.backbone_max,
            })),
            "tolerance": r.tolerance,
            "tolerance_met": r.tolerance_met,
            "stability": {"verdict": r.stability.verdict(), "unstable_directions": directions, "conjugate_point_s": conjugate_point, "reason": reason},
            "path": {"kind": path, "folds": folds, "bifurcations": bifurcations},
        }
    })
}

fn field<'a>(v: &'a Value, key: &str) -> Result<&'a Value, String> {
    v.get(key).ok_or_else(|| format!("missing `{key}`"))
}

fn number(v: &Value, key: &str) -> Result<f64, String> {
    match field(v, key)? {
        Value::Null => Ok(f64::NAN),
        x => x.as_f64().ok_or_else(|| format!("`{key}` is not a number")),
    }
}

fn count(v: &Value, key: &str) -> Result<usize, String> {
    field(v, key)?
        .as_u64()
        .and_then(|x| usize::try_from(x).ok())
        .ok_or_else(|| format!("`{key}` is not a whole number"))
}

fn read_vec(v: &Value, key: &str) -> Result<Vector3<f64>, String> {
    let items = v
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| format!("`{key}` is not [x, y, z]"))?;
    let mut out = Vector3::zeros();
    for (k, item) in items.iter().enumerate() {
        out[k] = match item {
            Value::Null => f64::NAN,
            x => x.as_f64().ok_or_else(|| format!("`{key}` has a non-number"))?,
        };
    }
    Ok(out)
}

fn read_node(v: &Value) -> Result<Node, String> {
    let vec = |key: &str| read_vec(field(v, key)?, key);
    let rows = field(v, "R")?
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or("`R` is not a list of 3 rows")?;
    let mut r = Matrix3::zeros();
    for (i, row) in rows.iter().enumerate() {
        r.set_row(i, &read_vec(row, "R")?.transpose());
    }
    Ok(Node {
        s: number(v, "s")?,
        p: vec("p")?,
        R: r,
        v: vec("v")?,
        u: vec("u")?,
        v_s: vec("v_s")?,
        u_s: vec("u_s")?,
        n: vec("n")?,
        m: vec("m")?,
    })
}

fn read_solution(v: &Value) -> Result<Solution, String> {
    match field(v, "format")?.as_str() {
        Some(FORMAT) => {}
        Some("tdcr-solution-1") => {
            return Err(format!(
                "`format` is \"tdcr-solution-1\", written by an older tdcr without tendon states and stability; this version reads \"{FORMAT}\": solve the robot again"
            ));
        }
        _ => return Err(format!("`format` is not \"{FORMAT}\" (not a Solution.to_json text)")),
    }
    let nodes: Vec<Node> = field(v, "nodes")?
        .as_array()
        .ok_or("`nodes` is not a list")?
        .iter()
        .map(read_node)
        .collect::<Result<_, _>>()?;
    if nodes.len() < 2 {
        return Err(format!("a solution needs at least 2 nodes, got {}", nodes.len()));
    }
    let tendon_paths: Vec<Vec<Vector3<f64>>> = field(v, "tendon_paths")?
        .as_array()
        .ok_or("`tendon_paths` is not a list")?
        .iter()
        .map(|p| {
            p.as_array()
                .ok_or_else(|| "a tendon path is not a list".to_string())?
                .iter()
                .map(|x| read_vec(x, "tendon_paths"))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let tendons: Vec<TendonState> = field(v, "tendons")?
        .as_array()
        .ok_or("`tendons` is not a list")?
        .iter()
        .map(|t| {
            Ok(TendonState {
                tension: number(t, "tension")?,
                displacement: number(t, "displacement")?,
                length: number(t, "length")?,
                reference_length: number(t, "reference_length")?,
                slack: number(t, "slack")?,
            })
        })
        .collect::<Result<_, String>>()?;
    if tendons.len() != tendon_paths.len() {
        return Err(format!(
            "`tendons` has {} entries but `tendon_paths` {}: give one state per tendon",
            tendons.len(),
            tendon_paths.len()
        ));
    }
    let r = field(v, "report")?;
    let method = match field(r, "method")?.as_str() {
        Some("collocation") => Method::Collocation,
        Some("shooting") => Method::Shooting,
        _ => return Err("`report.method` is not \"collocation\" or \"shooting\"".into()),
    };
    let name = field(r, "termination")?.as_str().unwrap_or("");
    let termination = *TERMINATIONS
        .iter()
        .find(|t| termination_name(**t) == name)
        .ok_or_else(|| format!("`report.termination` \"{name}\" is not a termination"))?;
    let history = field(r, "history")?
        .as_array()
        .ok_or("`report.history` is not a list")?
        .iter()
        .map(|i| {
            Ok(Iteration {
                residual: number(i, "residual")?,
                step: number(i, "step")?,
                damping: number(i, "damping")?,
                fresh_jacobian: field(i, "fresh_jacobian")?
                    .as_bool()
                    .ok_or("`fresh_jacobian` is not a bool")?,
            })
        })
        .collect::<Result<_, String>>()?;
    let e = field(r, "evaluations")?;
    let t = field(r, "timings_ns")?;
    let ns = |key: &str| -> Result<Duration, String> {
        field(t, key)?
            .as_u64()
            .map(Duration::from_nanos)
            .ok_or_else(|| format!("`timings_ns.{key}` is not a whole number"))
    };
    let mut report = SolveReport::new(method);
    report.termination = termination;
    report.iterations = count(r, "iterations")?;
    report.newton_steps = count(r, "newton_steps")?;
    report.chord_steps = count(r, "chord_steps")?;
    report.load_steps = count(r, "load_steps")?;
    report.meshes = count(r, "meshes")?;
    report.history = history;
    report.residual = number(r, "residual")?;
    report.evaluations = Evaluations {
        residual: count(e, "residual")?,
        jacobian: count(e, "jacobian")?,
        equations: count(e, "equations")?,
    };
    report.timings = Timings {
        assembly: ns("assembly")?,
        factorization: ns("factorization")?,
        solve: ns("solve")?,
        estimate: ns("estimate")?,
        stability: ns("stability")?,
        total: ns("total")?,
    };
    report.unknowns = count(r, "unknowns")?;
    report.nonzeros = count(r, "nonzeros")?;
    report.intervals = count(r, "intervals")?;
    report.error_estimate = match field(r, "error_estimate")? {
        Value::Null => None,
        e => Some(ErrorEstimate {
            tip_position: number(e, "tip_position_m")?,
            tip_rotation: number(e, "tip_rotation_rad")?,
            backbone_max: number(e, "backbone_max_m")?,
        }),
    };
    report.tolerance = match field(r, "tolerance")? {
        Value::Null => None,
        x => Some(x.as_f64().ok_or("`tolerance` is not a number")?),
    };
    report.tolerance_met = match field(r, "tolerance_met")? {
        Value::Null => None,
        x => Some(x.as_bool().ok_or("`tolerance_met` is not a bool")?),
    };
    report.stability = read_stability(field(r, "stability")?)?;
    report.path = read_path(field(r, "path")?)?;
    Ok(Solution {
        nodes,
        tendon_paths,
        tendons,
        report,
    })
}

/// A list of numbers (null read as NaN).
fn numbers(v: &Value, key: &str) -> Result<Vec<f64>, String> {
    field(v, key)?
        .as_array()
        .ok_or_else(|| format!("`{key}` is not a list"))?
        .iter()
        .map(|x| match x {
            Value::Null => Ok(f64::NAN),
            x => x.as_f64().ok_or_else(|| format!("`{key}` has a non-number")),
        })
        .collect()
}

/// The `report.stability` object of the JSON.
fn read_stability(v: &Value) -> Result<Stability, String> {
    match field(v, "verdict")?.as_str() {
        Some("stable") => Ok(Stability::Stable),
        Some("unstable") => Ok(Stability::Unstable {
            directions: count(v, "unstable_directions")?,
            conjugate_point: number(v, "conjugate_point_s")?,
        }),
        Some("unknown") => Ok(Stability::Unknown {
            reason: field(v, "reason")?
                .as_str()
                .ok_or("`stability.reason` is not a string")?
                .to_string(),
        }),
        _ => Err("`report.stability.verdict` is not \"stable\", \"unstable\" or \"unknown\"".into()),
    }
}

/// The `report.path` object of the JSON.
fn read_path(v: &Value) -> Result<Path, String> {
    let kind = field(v, "kind")?.as_str();
    if kind == Some("direct") {
        return Ok(Path::Direct);
    }
    let (folds, bifurcations) = (numbers(v, "folds")?, numbers(v, "bifurcations")?);
    match kind {
        Some("from_warm_start") => Ok(Path::FromWarmStart { folds, bifurcations }),
        Some("load_path") => Ok(Path::LoadPath { folds, bifurcations }),
        _ => Err("`report.path.kind` is not \"direct\", \"from_warm_start\" or \"load_path\"".into()),
    }
}
