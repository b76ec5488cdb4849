//! Tip sensitivities and inverse statics: `tdcr::tip_sensitivities`,
//! `tdcr::fit::solve_tensions` and `tdcr::fit::solve_displacements` with numpy in and out.

use crate::errors::{invalid, to_py};
use crate::robot::PyRobot;
use crate::solution::PySolution;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::fit::inverse::{InverseOptions, InverseSolution, Target};
use tdcr::nalgebra::{DMatrix, Matrix3, Vector3};

/// A 6 x k matrix as a (6, k) array.
fn rows<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// Derivatives of the tip pose at a solution. Every array has 6 rows: tip position x, y, z
/// (m per unit of the parameter), then the tip rotation as a world-frame rotation vector
/// (rad per unit).
#[pyclass(module = "tdcr", name = "TipSensitivities", frozen)]
pub struct PyTipSensitivities {
    inner: tdcr::TipSensitivities,
}

#[pymethods]
impl PyTipSensitivities {
    /// d(tip pose)/d(tension_i) (per N), shape (6, k), one column per tendon (zero for a
    /// displacement-controlled one: see `displacement`).
    #[getter]
    fn tension<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.inner.tension)
    }

    /// d(tip pose)/d(pull-in q_i) (per m), shape (6, k), one column per tendon: zero for a
    /// tension-controlled or slack tendon. With displacement-controlled tendons every
    /// derivative here holds their pull-ins (their tensions follow).
    #[getter]
    fn displacement<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.inner.displacement)
    }

    /// d(tip pose)/d(tip force) (per N, world frame), shape (6, 3).
    #[getter]
    fn tip_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &DMatrix::from_column_slice(6, 3, self.inner.tip_force.as_slice()))
    }

    /// d(tip pose)/d(tip moment) (per N m, world frame), shape (6, 3).
    #[getter]
    fn tip_moment<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &DMatrix::from_column_slice(6, 3, self.inner.tip_moment.as_slice()))
    }

    /// The tip compliance d(tip pose)/d(tip force, tip moment), shape (6, 6).
    #[getter]
    fn compliance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(
            py,
            &DMatrix::from_column_slice(6, 6, self.inner.compliance().as_slice()),
        )
    }

    /// d(tip pose)/d(base position) (per m), shape (6, 3).
    #[getter]
    fn base_position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(
            py,
            &DMatrix::from_column_slice(6, 3, self.inner.base_position.as_slice()),
        )
    }

    /// d(tip pose)/d(base rotation vector) (per rad, world frame), shape (6, 3).
    #[getter]
    fn base_rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(
            py,
            &DMatrix::from_column_slice(6, 3, self.inner.base_rotation.as_slice()),
        )
    }

    /// d(tip pose)/dE at fixed Poisson's ratio (per Pa), shape (6,); None unless the rod is
    /// built from its geometry.
    #[getter]
    fn youngs_modulus<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner
            .moduli
            .as_ref()
            .map(|m| PyArray1::from_slice(py, m.youngs_modulus.as_slice()))
    }
}

/// The tip sensitivities of `solution`, a collocation solution of `robot`, from one
/// factorization (implicit function theorem). Raises a `tdcr.Error` subclass.
#[pyfunction]
pub fn tip_sensitivities(py: Python<'_>, robot: &PyRobot, solution: &PySolution) -> PyResult<PyTipSensitivities> {
    let (r, s) = (&robot.file.robot, &solution.solution);
    py.detach(|| tdcr::tip_sensitivities(r, s))
        .map(|inner| PyTipSensitivities { inner })
        .map_err(to_py)
}

/// The result of `solve_tensions` and `solve_displacements`.
#[pyclass(module = "tdcr", name = "InverseResult", frozen, get_all)]
pub struct PyInverseResult {
    /// Tension of every tendon (N), shape (k,), file order.
    tensions: Py<PyArray1<f64>>,
    /// Actuator pull-in of every tendon (m), shape (k,), file order.
    displacements: Py<PyArray1<f64>>,
    /// Where each tendon's adjusted input ended up: "inside", "slack", "saturated" (at the
    /// upper bound), "released" (at the lower pull-in bound), "tension_limit" (pull-ins: at
    /// the tension limit) or "held" (not free).
    bounds: Vec<&'static str>,
    /// The forward solution at these inputs.
    solution: Py<PySolution>,
    /// Weighted tip error (m).
    residual: f64,
    /// Tip position error (m).
    position_error: f64,
    /// Tip rotation error (rad) when the target has a rotation, else None.
    orientation_error: Option<f64>,
    /// Whether the target was reached within the tolerance.
    reachable: bool,
    /// Why the iteration stopped, as a sentence.
    termination: String,
    /// Trial steps taken.
    iterations: usize,
    /// Forward solves.
    forward_solves: usize,
    /// A few sentences for a person: reached or how far the tip stayed, and why.
    explanation: String,
}

/// The target of `function` from a (3,) position and an optional (3, 3) rotation.
fn target(function: &str, position: Vec<f64>, rotation: Option<Vec<Vec<f64>>>) -> PyResult<Target> {
    let [x, y, z] = position[..] else {
        return Err(invalid(format!(
            "{function}: position has {} values, not 3",
            position.len()
        )));
    };
    let position = Vector3::new(x, y, z);
    match rotation {
        None => Ok(Target::position(position)),
        Some(r) => {
            if r.len() != 3 || r.iter().any(|row| row.len() != 3) {
                return Err(invalid(format!("{function}: rotation must be a (3, 3) matrix")));
            }
            Ok(Target::pose(position, Matrix3::from_fn(|i, j| r[i][j])))
        }
    }
}

/// The forward solver's settings of inverse statics: the robot file's and `options`, on a
/// fixed mesh unless `tol` asks otherwise (as the library's inverse statics: every
/// iteration then solves the same discretization).
fn forward_options(robot: &PyRobot, options: Option<&Bound<'_, PyDict>>) -> PyResult<tdcr::collocation::Options> {
    let mut settings = crate::options::apply(&robot.file.solver, options)?;
    if !options.is_some_and(|o| o.contains("tol").unwrap_or(false)) {
        settings.collocation.tolerance = None;
    }
    Ok(settings.collocation)
}

/// Runs `inverse` on `robot` and converts its result.
fn run_inverse(
    py: Python<'_>,
    robot: &PyRobot,
    target: Target,
    options: InverseOptions,
    inverse: fn(&tdcr::Robot, &Target, &InverseOptions) -> tdcr::Result<InverseSolution>,
) -> PyResult<PyInverseResult> {
    let r = &robot.file.robot;
    let out = py.detach(|| inverse(r, &target, &options)).map_err(to_py)?;
    let bounds = out
        .bounds
        .iter()
        .map(|b| match b {
            tdcr::fit::Bound::Inside => "inside",
            tdcr::fit::Bound::Slack => "slack",
            tdcr::fit::Bound::Saturated => "saturated",
            tdcr::fit::Bound::Released => "released",
            tdcr::fit::Bound::TensionLimit => "tension_limit",
            tdcr::fit::Bound::Held => "held",
        })
        .collect();
    Ok(PyInverseResult {
        tensions: PyArray1::from_slice(py, &out.tensions).unbind(),
        displacements: PyArray1::from_slice(py, &out.displacements).unbind(),
        bounds,
        solution: Py::new(
            py,
            PySolution {
                solution: out.solution.clone(),
            },
        )?,
        residual: out.residual,
        position_error: out.position_error,
        orientation_error: out.orientation_error,
        reachable: out.reachable,
        termination: out.termination.to_string(),
        iterations: out.iterations,
        forward_solves: out.forward_solves,
        explanation: out.explain(),
    })
}

/// Inverse statics: the tensions, each in [0, `max_tension`] (N), that put the tip at
/// `position` (m, (3,)) and, if given, `rotation` ((3, 3), body to world), by bounded
/// Levenberg-Marquardt on the forward solver (`tdcr::fit::solve_tensions`).
/// `free_tendons` lists the 0-based indices of the tendons that may change (default all);
/// `options` are the forward solver's (as `solve`, collocation only); without `tol` the
/// forward solves use a fixed mesh, as the library's inverse statics do.
#[pyfunction]
#[pyo3(signature = (robot, position, rotation=None, *, max_tension, tolerance=1e-6, max_iterations=50, orientation_weight=None, free_tendons=None, **options))]
#[allow(clippy::too_many_arguments)]
pub fn solve_tensions(
    py: Python<'_>,
    robot: &PyRobot,
    position: Vec<f64>,
    rotation: Option<Vec<Vec<f64>>>,
    max_tension: f64,
    tolerance: f64,
    max_iterations: usize,
    orientation_weight: Option<f64>,
    free_tendons: Option<Vec<usize>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyInverseResult> {
    let target = target("solve_tensions", position, rotation)?;
    let options = InverseOptions {
        max_tension,
        tolerance,
        max_iterations,
        orientation_weight,
        solver: forward_options(robot, options)?,
        free_tendons,
        ..Default::default()
    };
    run_inverse(py, robot, target, options, tdcr::fit::solve_tensions)
}

/// Inverse statics in actuator space: the pull-ins, each in [`min_displacement`,
/// `max_displacement`] (m; `min_displacement` defaults to -`max_displacement`), that put the tip at `position` (m, (3,)) and, if given,
/// `rotation` ((3, 3), body to world) (`tdcr::fit::solve_displacements`). The free tendons
/// (`free_tendons`, 0-based, default all) become displacement-controlled, starting from
/// the pull-ins their tensions hold; slack tendons are reported in `bounds`. Tensions stay
/// below 0.9 of each tendon's geometric limit EI / r^2 and below `max_tension` (N) when it
/// is above 0. `options` as `solve_tensions`.
#[pyfunction]
#[pyo3(signature = (robot, position, rotation=None, *, max_displacement, min_displacement=None, max_tension=0.0, tolerance=1e-6, max_iterations=50, orientation_weight=None, free_tendons=None, **options))]
#[allow(clippy::too_many_arguments)]
pub fn solve_displacements(
    py: Python<'_>,
    robot: &PyRobot,
    position: Vec<f64>,
    rotation: Option<Vec<Vec<f64>>>,
    max_displacement: f64,
    min_displacement: Option<f64>,
    max_tension: f64,
    tolerance: f64,
    max_iterations: usize,
    orientation_weight: Option<f64>,
    free_tendons: Option<Vec<usize>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyInverseResult> {
    let target = target("solve_displacements", position, rotation)?;
    let options = InverseOptions {
        // A symmetric stroke unless told: under its own weight the unactuated robot's
        // upper tendons need letting out.
        min_displacement: min_displacement.unwrap_or(-max_displacement),
        max_displacement,
        max_tension,
        tolerance,
        max_iterations,
        orientation_weight,
        solver: forward_options(robot, options)?,
        free_tendons,
    };
    run_inverse(py, robot, target, options, tdcr::fit::solve_displacements)
}

/// The result of `calibrate`.
#[pyclass(module = "tdcr", name = "Calibration", frozen, get_all)]
pub struct PyCalibration {
    /// Names of the fitted unknowns, e.g. `["E", "alpha", "beta", "gamma"]`.
    names: Vec<&'static str>,
    /// Fitted Young's modulus E (Pa).
    youngs_modulus: f64,
    /// Fitted base XYZ Euler angles (deg), (3,).
    euler_deg: Py<PyArray1<f64>>,
    /// Fitted base position (m), (3,).
    base_position: Py<PyArray1<f64>>,
    /// Fitted factor on every tendon offset.
    offset_scale: f64,
    /// The robot with the fitted parameters (and the input robot's solver settings).
    robot: Py<PyRobot>,
    /// Predicted tips of the fitted robot (m), (M, 3).
    tips: Py<PyArray2<f64>>,
    /// |predicted - measured| per measurement (m), (M,).
    tip_errors: Py<PyArray1<f64>>,
    /// RMS of the tip errors (m).
    rms_error: f64,
    /// Largest tip error (m).
    max_error: f64,
    /// Whether the fit converged.
    converged: bool,
    /// Why it stopped, as a sentence.
    termination: String,
    /// Levenberg-Marquardt trial steps.
    iterations: usize,
    /// Forward solves.
    solves: usize,
}

/// (M, 3) rows from a nested sequence; `what` names it in messages.
fn rows3(values: &[Vec<f64>], what: &str) -> PyResult<Vec<Vector3<f64>>> {
    values
        .iter()
        .map(|r| match r[..] {
            [x, y, z] => Ok(Vector3::new(x, y, z)),
            _ => Err(invalid(format!(
                "calibrate: every row of `{what}` needs 3 values, one has {}",
                r.len()
            ))),
        })
        .collect()
}

/// Calibration (`tdcr::fit::calibrate`): fits Young's modulus and the base XYZ Euler angles
/// (by default; `fit` names any of "youngs_modulus", "euler", "base_position",
/// "offset_scale") to measured tips. `tensions` is (M, k) (N, file order), `tip_forces`
/// (M, 3) (N, world frame), `measured_tips` (M, 3) (m). The fit starts from the robot's own
/// parameters; `options` are the forward solver's (as `solve`, collocation), on a fixed
/// mesh (`intervals`; a `tol` is ignored) so that the model tips are smooth in the
/// parameters.
#[pyfunction]
#[pyo3(signature = (robot, tensions, tip_forces, measured_tips, *, fit=None, max_iterations=50, **options))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    robot: &PyRobot,
    tensions: Vec<Vec<f64>>,
    tip_forces: Vec<Vec<f64>>,
    measured_tips: Vec<Vec<f64>>,
    fit: Option<Vec<String>>,
    max_iterations: usize,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyCalibration> {
    use tdcr::fit::calibration::{CalibrationOptions, Fit, Measurement};
    let (forces, tips) = (
        rows3(&tip_forces, "tip_forces")?,
        rows3(&measured_tips, "measured_tips")?,
    );
    if tensions.len() != forces.len() || tips.len() != forces.len() {
        return Err(invalid(format!(
            "calibrate: {} rows of tensions, {} of tip_forces, {} of measured_tips; give one row per measurement",
            tensions.len(),
            forces.len(),
            tips.len()
        )));
    }
    let experiments: Vec<Measurement> = tensions
        .into_iter()
        .zip(forces.into_iter().zip(tips))
        .map(|(tensions, (tip_force, measured_tip))| Measurement {
            tensions,
            tip_force,
            measured_tip,
        })
        .collect();
    let mut chosen = Fit::default();
    if let Some(names) = fit {
        chosen = Fit {
            youngs_modulus: false,
            euler: false,
            base_position: false,
            offset_scale: false,
        };
        for name in names {
            match name.as_str() {
                "youngs_modulus" => chosen.youngs_modulus = true,
                "euler" => chosen.euler = true,
                "base_position" => chosen.base_position = true,
                "offset_scale" => chosen.offset_scale = true,
                other => {
                    return Err(invalid(format!(
                        "calibrate: cannot fit `{other}`; choose from youngs_modulus, euler, base_position, offset_scale"
                    )));
                }
            }
        }
    }
    let defaults = CalibrationOptions::default();
    let mut settings = robot.file.solver.clone();
    settings.collocation.residual_tolerance = defaults.collocation.residual_tolerance;
    let mut settings = crate::options::apply(&settings, options)?;
    // Calibration solves on a fixed mesh (the model tips must be smooth in the parameters),
    // as `tdcr calibrate` does.
    settings.collocation.tolerance = None;
    let calibration_options = CalibrationOptions {
        fit: chosen,
        max_iterations,
        collocation: settings.collocation.clone(),
        ..defaults
    };
    let r = &robot.file.robot;
    let out = py
        .detach(|| tdcr::fit::calibrate(r, &experiments, &calibration_options))
        .map_err(to_py)?;
    let fitted = PyRobot {
        file: tdcr::io::RobotFile {
            robot: out.robot.clone(),
            solver: robot.file.solver.clone(),
            disks: robot.file.disks.clone(),
        },
    };
    let predicted = Array2::from_shape_fn((out.tips.len(), 3), |(i, k)| out.tips[i][k]);
    Ok(PyCalibration {
        names: out.fit.names(),
        youngs_modulus: out.fitted.youngs_modulus,
        euler_deg: PyArray1::from_slice(py, out.fitted.euler_deg().as_slice()).unbind(),
        base_position: PyArray1::from_slice(py, out.fitted.base_position.as_slice()).unbind(),
        offset_scale: out.fitted.offset_scale,
        robot: Py::new(py, fitted)?,
        tips: predicted.into_pyarray(py).unbind(),
        tip_errors: PyArray1::from_vec(py, out.tip_errors()).unbind(),
        rms_error: out.errors.rms,
        max_error: out.errors.max,
        converged: out.converged(),
        termination: out.termination.to_string(),
        iterations: out.iterations,
        solves: out.solves,
    })
}
