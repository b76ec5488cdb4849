//! Tip sensitivities and inverse statics: `tdcr::tip_sensitivities`,
//! `tdcr::fit::solve_tensions` and `tdcr::fit::solve_displacements` with numpy in and out.

use crate::boundary;
use crate::convert::{count, counts, number, numbers, optional_number, table_of};
use crate::errors::invalid;
use crate::options::Use;
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
    /// The library's sensitivities.
    pub(crate) inner: tdcr::TipSensitivities,
}

#[pymethods]
impl PyTipSensitivities {
    /// Pickling and copying go through the matrices (column-major values).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let s = &slf.get().inner;
        let state = PyDict::new(slf.py());
        state.set_item("tendons", s.tension.ncols())?;
        state.set_item("tension", s.tension.as_slice())?;
        state.set_item("displacement", s.displacement.as_slice())?;
        state.set_item("friction", s.friction.as_slice())?;
        state.set_item("tip_force", s.tip_force.as_slice())?;
        state.set_item("tip_moment", s.tip_moment.as_slice())?;
        state.set_item("base_position", s.base_position.as_slice())?;
        state.set_item("base_rotation", s.base_rotation.as_slice())?;
        let moduli = s
            .moduli
            .map(|m| [m.youngs_modulus, m.youngs_modulus_fixed_shear, m.shear_modulus].map(|v| v.as_slice().to_vec()));
        state.set_item("moduli", moduli)?;
        Ok((slf.get_type().getattr("_from_state")?, (state,)))
    }

    /// The sensitivities of a state `__reduce__` made.
    #[staticmethod]
    fn _from_state(state: &Bound<'_, PyDict>) -> PyResult<Self> {
        use crate::pickle::field;
        use tdcr::nalgebra::{Matrix6x3, Vector6};
        let k: usize = field(state, "tendons")?;
        let matrix = |name: &str| -> PyResult<DMatrix<f64>> {
            let values: Vec<f64> = field(state, name)?;
            if values.len() != 6 * k {
                return Err(invalid(format!(
                    "the pickled `{name}` has {} values, not 6 x {k}",
                    values.len()
                )));
            }
            Ok(DMatrix::from_vec(6, k, values))
        };
        let six_by_three = |name: &str| -> PyResult<Matrix6x3<f64>> {
            let values: [f64; 18] = field(state, name)?;
            Ok(Matrix6x3::from_column_slice(&values))
        };
        let moduli: Option<[[f64; 6]; 3]> = field(state, "moduli")?;
        Ok(PyTipSensitivities {
            inner: tdcr::TipSensitivities {
                tension: matrix("tension")?,
                displacement: matrix("displacement")?,
                friction: matrix("friction")?,
                tip_force: six_by_three("tip_force")?,
                tip_moment: six_by_three("tip_moment")?,
                base_position: six_by_three("base_position")?,
                base_rotation: six_by_three("base_rotation")?,
                moduli: moduli.map(
                    |[e, e_fixed_shear, g]| tdcr::collocation::sensitivity::ModulusSensitivities {
                        youngs_modulus: Vector6::from_column_slice(&e),
                        youngs_modulus_fixed_shear: Vector6::from_column_slice(&e_fixed_shear),
                        shear_modulus: Vector6::from_column_slice(&g),
                    },
                ),
            },
        })
    }

    /// d(tip pose)/d(tension_i) (per N), shape (6, k), one column per tendon (zero for a
    /// displacement-controlled one: see `displacement`). For a tendon at 0 N, with or
    /// without friction, the one-sided derivative of its first pull (docs/friction.md
    /// section 3, "Sensitivities").
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

    /// d(tip pose)/d(friction coefficient mu_i) (per unit of mu), shape (6, k), one column
    /// per tendon: zero for a tendon without friction.
    #[getter]
    fn friction<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.inner.friction)
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
    boundary::detached(py, || tdcr::tip_sensitivities(r, s)).map(|inner| PyTipSensitivities { inner })
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
    bounds: Vec<String>,
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

crate::pickle::pickled_fields! {
    PyInverseResult {
        tensions, displacements, bounds, solution, residual, position_error, orientation_error,
        reachable, termination, iterations, forward_solves, explanation,
    }
}

/// The target of `function` from a (3,) position and an optional (3, 3) rotation.
fn target(function: &str, position: &Bound<'_, PyAny>, rotation: Option<&Bound<'_, PyAny>>) -> PyResult<Target> {
    let position = numbers(position, &format!("{function}: `position`"))?;
    let [x, y, z] = position[..] else {
        return Err(invalid(format!(
            "{function}: position has {} values, not 3",
            position.len()
        )));
    };
    let position = Vector3::new(x, y, z);
    match rotation.filter(|r| !r.is_none()) {
        None => Ok(Target::position(position)),
        Some(r) => {
            let r = table_of(r, &format!("{function}: `rotation`"), Some(3))?;
            if r.len() != 3 {
                return Err(invalid(format!("{function}: rotation must be a (3, 3) matrix")));
            }
            Ok(Target::pose(position, Matrix3::from_fn(|i, j| r[i][j])))
        }
    }
}

/// The forward solver's settings of inverse statics: the robot file's and `options`, on a
/// fixed mesh unless `tol` asks otherwise (as the library's inverse statics: every
/// iteration then solves the same discretization).
fn forward_options(
    function: &str,
    robot: &PyRobot,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<tdcr::collocation::Options> {
    let mut settings = crate::options::apply(&robot.file.solver, options, Use::Collocation(function))?;
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
    let out = boundary::detached(py, || inverse(r, &target, &options))?;
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
        .map(String::from)
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

/// The arguments both inverse statics calls take, as given.
struct Common<'a, 'py> {
    tolerance: Option<&'a Bound<'py, PyAny>>,
    max_iterations: Option<&'a Bound<'py, PyAny>>,
    orientation_weight: Option<&'a Bound<'py, PyAny>>,
    free_tendons: Option<&'a Bound<'py, PyAny>>,
    options: Option<&'a Bound<'py, PyDict>>,
}

impl Common<'_, '_> {
    /// The library's defaults with these arguments of `function` set.
    fn options(&self, function: &str, robot: &PyRobot) -> PyResult<InverseOptions> {
        let defaults = InverseOptions::default();
        let what = |name: &str| format!("{function}: `{name}`");
        Ok(InverseOptions {
            tolerance: optional_number(self.tolerance, &what("tolerance"))?.unwrap_or(defaults.tolerance),
            max_iterations: self
                .max_iterations
                .filter(|n| !n.is_none())
                .map_or(Ok(defaults.max_iterations), |n| count(n, &what("max_iterations")))?,
            orientation_weight: optional_number(self.orientation_weight, &what("orientation_weight"))?,
            solver: forward_options(function, robot, self.options)?,
            free_tendons: self
                .free_tendons
                .filter(|t| !t.is_none())
                .map(|t| counts(t, &what("free_tendons")))
                .transpose()?,
            ..defaults
        })
    }
}

/// Inverse statics: the tensions, each in [0, `max_tension`] (N), that put the tip at
/// `position` (m, (3,)) and, if given, `rotation` ((3, 3), body to world), by bounded
/// Levenberg-Marquardt on the forward solver (`tdcr::fit::solve_tensions`).
/// `free_tendons` lists the 0-based indices of the tendons that may change (default all);
/// `options` are the forward solver's (as `solve`, collocation only); without `tol` the
/// forward solves use a fixed mesh, as the library's inverse statics do.
#[pyfunction]
#[pyo3(
    signature = (robot, position, rotation=None, *, max_tension, tolerance=None, max_iterations=None, orientation_weight=None, free_tendons=None, **options),
    text_signature = "(robot, position, rotation=None, *, max_tension, tolerance=1e-6, max_iterations=50, orientation_weight=None, free_tendons=None, **options)"
)]
#[allow(clippy::too_many_arguments)]
pub fn solve_tensions(
    py: Python<'_>,
    robot: &PyRobot,
    position: &Bound<'_, PyAny>,
    rotation: Option<&Bound<'_, PyAny>>,
    max_tension: &Bound<'_, PyAny>,
    tolerance: Option<&Bound<'_, PyAny>>,
    max_iterations: Option<&Bound<'_, PyAny>>,
    orientation_weight: Option<&Bound<'_, PyAny>>,
    free_tendons: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyInverseResult> {
    let f = "solve_tensions";
    let target = target(f, position, rotation)?;
    let common = Common {
        tolerance,
        max_iterations,
        orientation_weight,
        free_tendons,
        options,
    };
    let options = InverseOptions {
        max_tension: number(max_tension, &format!("{f}: `max_tension`"))?,
        ..common.options(f, robot)?
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
#[pyo3(
    signature = (robot, position, rotation=None, *, max_displacement, min_displacement=None, max_tension=None, tolerance=None, max_iterations=None, orientation_weight=None, free_tendons=None, **options),
    text_signature = "(robot, position, rotation=None, *, max_displacement, min_displacement=None, max_tension=0.0, tolerance=1e-6, max_iterations=50, orientation_weight=None, free_tendons=None, **options)"
)]
#[allow(clippy::too_many_arguments)]
pub fn solve_displacements(
    py: Python<'_>,
    robot: &PyRobot,
    position: &Bound<'_, PyAny>,
    rotation: Option<&Bound<'_, PyAny>>,
    max_displacement: &Bound<'_, PyAny>,
    min_displacement: Option<&Bound<'_, PyAny>>,
    max_tension: Option<&Bound<'_, PyAny>>,
    tolerance: Option<&Bound<'_, PyAny>>,
    max_iterations: Option<&Bound<'_, PyAny>>,
    orientation_weight: Option<&Bound<'_, PyAny>>,
    free_tendons: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyInverseResult> {
    let f = "solve_displacements";
    let target = target(f, position, rotation)?;
    let common = Common {
        tolerance,
        max_iterations,
        orientation_weight,
        free_tendons,
        options,
    };
    let max_displacement = number(max_displacement, &format!("{f}: `max_displacement`"))?;
    let options = InverseOptions {
        // A symmetric stroke unless told: under its own weight the unactuated robot's
        // upper tendons need letting out.
        min_displacement: optional_number(min_displacement, &format!("{f}: `min_displacement`"))?
            .unwrap_or(-max_displacement),
        max_displacement,
        max_tension: optional_number(max_tension, &format!("{f}: `max_tension`"))?.unwrap_or(0.0),
        ..common.options(f, robot)?
    };
    run_inverse(py, robot, target, options, tdcr::fit::solve_displacements)
}
