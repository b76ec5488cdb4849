//! `tdcr.Solver`: the library's stateful [`tdcr::Solver`] for control loops: warm starts on
//! the factors of the last solve, and the control Jacobians (only the columns asked for)
//! from the same workspace.

use crate::analysis::PyTipSensitivities;
use crate::boundary;
use crate::convert::{numbers, type_name};
use crate::errors::{self, invalid, to_py};
use crate::options::{self, Use};
use crate::robot::PyRobot;
use crate::solution::PySolution;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use tdcr::collocation::sensitivity::columns;
use tdcr::{Parameter, Solution};

/// Solves `robot` with `solve` (GIL released, panics caught): `tdcr.PlausibilityWarning`s
/// before for the robot's implausible scales and after for solved tensions past their
/// limit, and a failure raised with its likely causes ([`errors::explained`]).
pub fn checked_solve(
    py: Python<'_>,
    robot: &tdcr::Robot,
    solve: impl FnOnce() -> tdcr::Result<Solution> + Send,
) -> PyResult<Solution> {
    errors::warn(py, &robot.plausibility())?;
    let solution = py.detach(|| boundary::caught(solve)).map_err(|failure| match failure {
        boundary::Failure::Library(e) => errors::explained(e, robot),
        other => other.into_py(),
    })?;
    errors::warn(py, &robot.solved_tensions(&solution.tensions()))?;
    Ok(solution)
}

/// Solver(robot=None, **options)
///
/// A collocation solver that keeps its workspace between solves, for control loops: each
/// `solve` starts from the last solution with chord steps on the factors of the last
/// Newton matrix (or of the last Jacobian), and `tip_jacobian` / `backbone_jacobian`
/// factor the Jacobian at the last solution in the same workspace and compute only the
/// columns asked for. `options` are `solve`'s (collocation), applied over each robot's
/// `[solver]` settings. Not safe to share between threads.
#[pyclass(module = "tdcr", name = "Solver")]
pub struct PySolver {
    /// The library's solver (its options are the current robot's settings with `options`).
    solver: tdcr::Solver,
    /// The keyword options given at construction.
    options: Option<Py<PyDict>>,
    /// The current robot: the last one given, with the parameters set since.
    robot: Option<PyRobot>,
    /// The last solution, the next solve's warm start.
    last: Option<Solution>,
}

impl PySolver {
    /// The current robot, or `tdcr.InvalidInput` saying how to give one.
    fn robot(&self, method: &str) -> PyResult<&PyRobot> {
        self.robot.as_ref().ok_or_else(|| {
            invalid(format!(
                "Solver.{method}: no robot yet; give one (Solver(robot) or solver.solve(robot))"
            ))
        })
    }

    /// Nothing, or `tdcr.InvalidInput` saying what is missing: a robot or a solution.
    fn solved(&self, method: &str) -> PyResult<()> {
        self.robot(method)?;
        match self.last {
            Some(_) => Ok(()),
            None => Err(invalid(format!(
                "Solver.{method}: nothing solved yet (or reset since); call solver.solve(...) first"
            ))),
        }
    }

    /// Makes `robot` the current robot, with its settings and the solver's options.
    fn set_robot(&mut self, py: Python<'_>, robot: PyRobot) -> PyResult<()> {
        let options = self.options.as_ref().map(|o| o.bind(py).clone());
        let settings = options::apply(&robot.file.solver, options.as_ref(), Use::Collocation("Solver"))?;
        self.solver.options = settings.collocation;
        self.robot = Some(robot);
        Ok(())
    }

    /// The parameters of `wrt`: names or groups (`tension`, `tip_force`, ...), a string or
    /// a sequence of them.
    fn columns(&self, method: &str, wrt: &Bound<'_, PyAny>) -> PyResult<Vec<Parameter>> {
        let names: Vec<String> = if let Ok(s) = wrt.cast::<PyString>() {
            vec![s.to_string()]
        } else {
            wrt.extract().map_err(|_| {
                invalid(format!(
                    "Solver.{method}: `wrt` must be a parameter name or a list of them (\"tension\", \"tip_force.z\", ...), not {}",
                    type_name(wrt)
                ))
            })?
        };
        let robot = &self.robot(method)?.file.robot;
        columns(&names, robot).map_err(to_py)
    }
}

#[pymethods]
impl PySolver {
    #[new]
    #[pyo3(signature = (robot=None, **options))]
    fn new(py: Python<'_>, robot: Option<&PyRobot>, options: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        // The options are checked now, against the default settings (again per robot).
        let settings = options::apply(&Default::default(), options, Use::Collocation("Solver"))?;
        let mut solver = PySolver {
            solver: tdcr::Solver::new(settings.collocation),
            options: options.map(|o| o.clone().unbind()),
            robot: None,
            last: None,
        };
        if let Some(robot) = robot {
            solver.set_robot(py, robot.clone())?;
        }
        Ok(solver)
    }

    /// solve(robot=None, /, parameters=None, *, tension=None) -> Solution
    ///
    /// Solves the current robot, warm-started from the last solution (cold after `reset`
    /// or for the first solve). `robot` replaces the current robot; `parameters` (a dict
    /// of parameter names and values, the names of `solve_batch`'s columns: `tension.1`,
    /// `tip_force.z`, ...) and `tension` (every tendon's tension, N, shape (k,)) change it
    /// and stay set. The GIL is released while solving. Raises as `solve`.
    #[pyo3(signature = (robot=None, /, parameters=None, *, tension=None))]
    fn solve(
        &mut self,
        py: Python<'_>,
        robot: Option<&Bound<'_, PyAny>>,
        parameters: Option<&Bound<'_, PyDict>>,
        tension: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PySolution> {
        let mut parameters = parameters.cloned();
        match robot.filter(|r| !r.is_none()) {
            Some(r) if r.cast::<PyRobot>().is_ok() => {
                let robot = r.cast::<PyRobot>()?.get().clone();
                self.set_robot(py, robot)?;
            }
            Some(r) if r.cast::<PyDict>().is_ok() && parameters.is_none() => {
                parameters = Some(r.cast::<PyDict>()?.clone());
            }
            Some(r) => {
                return Err(invalid(format!(
                    "Solver.solve: give a tdcr.Robot or a dict of parameter values, not {}",
                    type_name(r)
                )));
            }
            None => {}
        }
        let mut robot = self.robot("solve")?.file.robot.clone();
        let r = &mut robot;
        if let Some(parameters) = parameters {
            for (key, value) in parameters.iter() {
                let name: String = key
                    .extract()
                    .map_err(|_| invalid("Solver.solve: parameter names must be strings"))?;
                let p = Parameter::parse(&name, r).map_err(to_py)?;
                let v = crate::convert::number(&value, &format!("Solver.solve: parameter `{name}`"))?;
                p.apply(r, v).map_err(to_py)?;
            }
        }
        if let Some(tension) = tension {
            let values = numbers(tension, "Solver.solve: `tension`")?;
            if values.len() != r.tendons.len() {
                return Err(invalid(format!(
                    "Solver.solve: `tension` has {} values, but the robot has {} tendon(s): give one per tendon, in file order",
                    values.len(),
                    r.tendons.len()
                )));
            }
            for (i, v) in values.into_iter().enumerate() {
                Parameter::Tension(i).apply(r, v).map_err(to_py)?;
            }
        }
        r.validate().map_err(to_py)?;
        let (solver, last) = (&mut self.solver, &self.last);
        let robot_ref = &robot;
        let solution = checked_solve(py, robot_ref, || match last {
            Some(w) => solver.solve_from(robot_ref, w),
            None => solver.solve(robot_ref),
        })?;
        if let Some(current) = self.robot.as_mut() {
            current.file.robot = robot;
        }
        self.last = Some(solution.clone());
        Ok(PySolution { solution })
    }

    /// tip_jacobian(wrt=("tension",)) -> ndarray
    ///
    /// The columns `wrt` of d(tip pose)/dq at the last solution, shape (6, n): rows tip
    /// position x, y, z (m per unit of q), then the tip rotation as a world-frame rotation
    /// vector (rad per unit); the layout of `tip_sensitivities(robot, solution).tension`,
    /// whose columns they equal to rounding. `wrt`: parameter names (`tension.2`,
    /// `tip_force.z`, `tip_moment.x`, `base_position.y`, `youngs_modulus`) or the groups
    /// `tension` (every tendon, file order), `tip_force`, `tip_moment`, `base_position`.
    /// Only the columns asked for are computed, from one factorization in the solver's
    /// workspace.
    #[pyo3(signature = (wrt=None))]
    fn tip_jacobian<'py>(
        &mut self,
        py: Python<'py>,
        wrt: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let wrt = match wrt {
            Some(w) => self.columns("tip_jacobian", w)?,
            None => columns(&["tension"], &self.robot("tip_jacobian")?.file.robot).map_err(to_py)?,
        };
        self.solved("tip_jacobian")?;
        let (Some(robot), Some(solution), solver) = (&self.robot, &self.last, &mut self.solver) else {
            return Err(invalid("Solver: no solution"));
        };
        let robot = &robot.file.robot;
        let m = boundary::detached(py, || solver.tip_jacobian(robot, solution, &wrt))?;
        Ok(Array2::from_shape_fn((6, m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py))
    }

    /// tip_sensitivities(robot=None, solution=None) -> TipSensitivities
    ///
    /// Every tip sensitivity at the last solution of the current robot (or at `solution`, a
    /// solution of `robot`, given both): what `tdcr.tip_sensitivities(robot, solution)`
    /// returns, equal to rounding, from one factorization in the solver's workspace. After a
    /// warm solve that converged by chord steps that is the Jacobian its stability verdict
    /// evaluated at the solution, not assembled again. Raises as `tip_sensitivities`.
    #[pyo3(signature = (robot=None, solution=None))]
    fn tip_sensitivities(
        &mut self,
        py: Python<'_>,
        robot: Option<&PyRobot>,
        solution: Option<&PySolution>,
    ) -> PyResult<PyTipSensitivities> {
        let (robot, solution) = match (robot, solution) {
            (Some(r), Some(s)) => (&r.file.robot, &s.solution),
            (None, None) => {
                self.solved("tip_sensitivities")?;
                let (Some(r), Some(s)) = (&self.robot, &self.last) else {
                    return Err(invalid("Solver: no solution"));
                };
                (&r.file.robot, s)
            }
            _ => {
                return Err(invalid(
                    "Solver.tip_sensitivities: give both `robot` and `solution` (a solution of that robot), or neither for the last solution",
                ));
            }
        };
        let solver = &mut self.solver;
        boundary::detached(py, || solver.tip_sensitivities(robot, solution)).map(|inner| PyTipSensitivities { inner })
    }

    /// backbone_jacobian(s, wrt=("tension",)) -> ndarray
    ///
    /// The columns `wrt` of d p(s_j)/dq at the arc lengths `s` (m, from 0 to the rod
    /// length) of the last solution, shape (len(s), 3, n): world-frame position (m per unit
    /// of q), the exact derivative of `solution.at(s_j).p` on the solution's mesh. `wrt` as
    /// `tip_jacobian`. Not for robots with taut displacement-controlled tendons.
    #[pyo3(signature = (s, wrt=None))]
    fn backbone_jacobian<'py>(
        &mut self,
        py: Python<'py>,
        s: &Bound<'py, PyAny>,
        wrt: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let s = numbers(s, "Solver.backbone_jacobian: `s`")?;
        let wrt = match wrt {
            Some(w) => self.columns("backbone_jacobian", w)?,
            None => columns(&["tension"], &self.robot("backbone_jacobian")?.file.robot).map_err(to_py)?,
        };
        self.solved("backbone_jacobian")?;
        let (Some(robot), Some(solution), solver) = (&self.robot, &self.last, &mut self.solver) else {
            return Err(invalid("Solver: no solution"));
        };
        let robot = &robot.file.robot;
        let m = boundary::detached(py, || solver.backbone_jacobian(robot, solution, &wrt, &s))?;
        Ok(Array3::from_shape_fn((s.len(), 3, m.ncols()), |(j, k, c)| m[(3 * j + k, c)]).into_pyarray(py))
    }

    /// keep_tension_columns(on) -> None
    ///
    /// For a control loop that asks for `tip_jacobian()` in the tensions after every solve
    /// (`on`): a solve whose stability verdict evaluates the Jacobian at its answer (a warm
    /// solve that converged by chord steps) also forms the tension columns' right-hand
    /// sides, which `tip_jacobian` then takes instead of a pass over the mesh of its own.
    /// Such a solve costs a few per cent more, the answers are the same bits. Off by
    /// default (docs/sensitivity.md).
    fn keep_tension_columns(&mut self, on: bool) {
        self.solver.keep_tension_columns(on);
    }

    /// reset() -> None
    ///
    /// Forgets the workspace, its factors and the last solution (the robot stays): the
    /// next solve starts cold, as a new solver's.
    fn reset(&mut self) {
        self.solver.reset();
        self.last = None;
    }

    /// The current robot (the last given, with the parameters set since), or None.
    #[getter(robot)]
    fn current_robot(&self) -> Option<PyRobot> {
        self.robot.clone()
    }

    /// The last solution (the next solve's warm start), or None.
    #[getter]
    fn solution(&self) -> Option<PySolution> {
        self.last.clone().map(|solution| PySolution { solution })
    }
}
