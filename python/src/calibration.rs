//! `calibrate` (`tdcr::fit::calibrate`): fitted parameters with their standard errors, the
//! fit's quality against the measurement noise, numpy in and out.

use crate::boundary;
use crate::convert::{count, number, table_of};
use crate::errors::invalid;
use crate::options::Use;
use crate::robot::PyRobot;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use tdcr::nalgebra::Vector3;

/// The result of `calibrate`.
#[pyclass(module = "tdcr", name = "Calibration", frozen, get_all)]
pub struct PyCalibration {
    /// Names of the fitted unknowns, e.g. `["E", "alpha", "beta", "gamma"]`.
    names: Vec<String>,
    /// Fitted Young's modulus E (Pa).
    youngs_modulus: f64,
    /// Fitted base XYZ Euler angles (deg), (3,).
    euler_deg: Py<PyArray1<f64>>,
    /// Fitted base position (m), (3,).
    base_position: Py<PyArray1<f64>>,
    /// Fitted factor on every tendon offset.
    offset_scale: f64,
    /// Fitted friction coefficient of the tendons with friction (0 without friction).
    friction: f64,
    /// Standard errors of the fitted unknowns by `names`, in the attributes' units (E in Pa,
    /// angles in deg, base position in m); None when there are no more residuals than
    /// unknowns or the fit is singular (as at beta = +-90 deg).
    standard_errors: Option<Py<PyDict>>,
    /// Noise estimate per tip coordinate (m), the standard errors' sigma.
    noise_estimate: f64,
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
    /// Why the fit does not explain the data (its noise estimate far above the stated
    /// `noise`, or above 1.5 % of the rod length without one), with the likely causes; None
    /// when it does. Also raised as `tdcr.PoorFitWarning`.
    poor_fit: Option<String>,
}

crate::pickle::pickled_fields! {
    PyCalibration {
        names, youngs_modulus, euler_deg, base_position, offset_scale, friction, standard_errors,
        noise_estimate, robot, tips, tip_errors,
        rms_error, max_error, converged, termination, iterations, solves, poor_fit,
    }
}

/// (M, 3) rows of `calibrate`'s argument `what`.
fn rows3(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vector3<f64>>> {
    Ok(table_of(value, &format!("calibrate: `{what}`"), Some(3))?
        .into_iter()
        .map(|r| Vector3::new(r[0], r[1], r[2]))
        .collect())
}

/// Calibration (`tdcr::fit::calibrate`): fits Young's modulus and the base XYZ Euler angles
/// (by default; `fit` names any of "youngs_modulus", "euler", "base_position",
/// "offset_scale", "friction": the first tendon with friction's coefficient, the others'
/// scaled with it in proportion, read
/// back from the fitted robot; `tdcr calibrate --fit`'s names "e", "position", "offset" and
/// "mu" are accepted too) to measured tips. `noise` (m per coordinate, e.g. 1e-4 for 0.1
/// mm) is the measurement noise: a fit whose noise estimate is above 3 times it (above 1.5 %
/// of the rod length without it) sets `poor_fit` and raises `tdcr.PoorFitWarning`, as
/// `tdcr calibrate --noise` warns. `tensions` is (M, k) (N, file order), `tip_forces`
/// (M, 3) (N, world frame), `measured_tips` (M, 3) (m); `motions`, M entries "pull" (a
/// loading step), "release" (an unloading step) or None (the robot's motion), gives the
/// motion the tendons with friction model in each measurement, as the CSV's `motion`
/// column does for `tdcr calibrate` (docs/calibration.md). The fit starts from the robot's own
/// parameters; `options` are the forward solver's (as `solve`, collocation), on a fixed
/// mesh (`intervals`; `tol` is refused) so that the model tips are smooth in the
/// parameters. Ctrl-C stops it within about 0.1 s with `KeyboardInterrupt` (no result).
#[pyfunction]
#[pyo3(
    signature = (robot, tensions, tip_forces, measured_tips, *, fit=None, motions=None, max_iterations=None, noise=None, **options),
    text_signature = "(robot, tensions, tip_forces, measured_tips, *, fit=None, motions=None, max_iterations=50, noise=None, **options)"
)]
#[allow(clippy::too_many_arguments)]
pub fn calibrate(
    py: Python<'_>,
    robot: &PyRobot,
    tensions: &Bound<'_, PyAny>,
    tip_forces: &Bound<'_, PyAny>,
    measured_tips: &Bound<'_, PyAny>,
    fit: Option<Vec<String>>,
    motions: Option<Vec<Option<String>>>,
    max_iterations: Option<&Bound<'_, PyAny>>,
    noise: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyCalibration> {
    use tdcr::fit::calibration::{CalibrationOptions, Fit, Measurement};
    let (forces, tips) = (rows3(tip_forces, "tip_forces")?, rows3(measured_tips, "measured_tips")?);
    let tensions = table_of(tensions, "calibrate: `tensions`", None)?;
    let max_iterations = max_iterations
        .filter(|n| !n.is_none())
        .map_or(Ok(CalibrationOptions::default().max_iterations), |n| {
            count(n, "calibrate: `max_iterations`")
        })?;
    let noise = match noise.filter(|n| !n.is_none()) {
        None => None,
        Some(n) => match number(n, "calibrate: `noise`")? {
            sigma if sigma.is_finite() && sigma > 0.0 => Some(sigma),
            sigma => {
                return Err(invalid(format!(
                    "calibrate: `noise` is {}; give the measurement noise per tip coordinate in m, finite and > 0 \
                     (e.g. 1e-4 for 0.1 mm), or None",
                    tdcr::Readable(sigma)
                )));
            }
        },
    };
    if tensions.len() != forces.len() || tips.len() != forces.len() {
        return Err(invalid(format!(
            "calibrate: {} rows of tensions, {} of tip_forces, {} of measured_tips; give one row per measurement",
            tensions.len(),
            forces.len(),
            tips.len()
        )));
    }
    let motions = crate::convert::motions(motions, forces.len())?;
    let experiments: Vec<Measurement> = tensions
        .into_iter()
        .zip(forces.into_iter().zip(tips))
        .zip(motions)
        .map(|((tensions, (tip_force, measured_tip)), motion)| Measurement {
            tensions,
            tip_force,
            measured_tip,
            motion,
        })
        .collect();
    let mut chosen = Fit::default();
    if let Some(names) = fit {
        chosen = Fit::none();
        for name in names {
            match name.as_str() {
                "youngs_modulus" | "e" => chosen.youngs_modulus = true,
                "euler" => chosen.euler = true,
                "base_position" | "position" => chosen.base_position = true,
                "offset_scale" | "offset" => chosen.offset_scale = true,
                "friction" | "mu" => chosen.friction = true,
                other => {
                    return Err(invalid(format!(
                        "calibrate: cannot fit `{other}`; choose from youngs_modulus (or e), euler, base_position (or \
                         position), offset_scale (or offset), friction (or mu)"
                    )));
                }
            }
        }
    }
    let defaults = CalibrationOptions::default();
    let mut settings = robot.file.solver.clone();
    settings.collocation.residual_tolerance = defaults.collocation.residual_tolerance;
    let mut settings = crate::options::apply(&settings, options, Use::FixedMesh("calibrate"))?;
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
    let (fit, signal) = boundary::stoppable(py, |stop| {
        tdcr::fit::calibrate_until(r, &experiments, &calibration_options, stop)
    })?;
    if let Some(e) = signal {
        return Err(e);
    }
    // Only a stop ends a fit without a result, and a stop comes with a signal.
    let Some(out) = fit else {
        return Err(crate::errors::Error::new_err("calibrate stopped without a result"));
    };
    let fitted = PyRobot {
        file: tdcr::io::RobotFile {
            robot: out.robot.clone(),
            solver: robot.file.solver.clone(),
            disks: robot.file.disks.clone(),
        },
        // Calibration does not change a rod given by `shear_modulus` (it cannot fit its E).
        given_rod: robot.given_rod.clone(),
    };
    let poor_fit = out.poor_fit(noise).map(|p| p.to_string());
    if let Some(text) = &poor_fit {
        let category = py.get_type::<crate::errors::PoorFitWarning>();
        let text = std::ffi::CString::new(text.as_str()).unwrap_or_default();
        PyErr::warn(py, &category, &text, 1)?;
    }
    let predicted = Array2::from_shape_fn((out.tips.len(), 3), |(i, k)| out.tips[i][k]);
    Ok(PyCalibration {
        names: out.fit.names().into_iter().map(String::from).collect(),
        youngs_modulus: out.fitted.youngs_modulus,
        euler_deg: PyArray1::from_slice(py, out.fitted.euler_deg().as_slice()).unbind(),
        base_position: PyArray1::from_slice(py, out.fitted.base_position.as_slice()).unbind(),
        offset_scale: out.fitted.offset_scale,
        friction: out.fitted.friction,
        standard_errors: out
            .standard_errors
            .map(|se| crate::convert::standard_errors(py, &out.fit, &se))
            .transpose()?,
        noise_estimate: out.noise_estimate,
        robot: Py::new(py, fitted)?,
        tips: predicted.into_pyarray(py).unbind(),
        tip_errors: PyArray1::from_vec(py, out.tip_errors()).unbind(),
        rms_error: out.errors.rms,
        max_error: out.errors.max,
        converged: out.converged(),
        termination: out.termination.to_string(),
        iterations: out.iterations,
        solves: out.solves,
        poor_fit,
    })
}
