//! `tdcr.compare`: one robot solved as several models, or by both solvers, each tip
//! compared with the first's (the library's `analysis::comparison`, as `tdcr compare`).

use crate::errors::{invalid, to_py};
use crate::robot::PyRobot;
use crate::solution::matrix;
use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use tdcr::Method;
use tdcr::analysis::comparison::{Variant, compare as compare_shapes, compare_models, shape};

/// compare(robot, *, models=None, methods=None, **options) -> list[dict]
///
/// Solves `robot` as each of `models` (names: "coupled", "point_moment",
/// "constant_curvature", "paper_jumps", "kirchhoff"; default all five, the first the
/// reference), or, with
/// `methods` instead, by each solver ("collocation", "shooting") on the robot's own model.
/// `options` are `tdcr.solve`'s. One dict per shape: `name`, `s` (m, shape (n,)), `p` (m,
/// world frame, shape (n, 3)), `tip_position` (3,), `tip_rotation` (3, 3), `tip_distance`
/// (m) and `tip_angle` (rad) from the first shape's tip. The GIL is released while solving.
///
/// Raises `tdcr.InvalidInput` for an unknown name or both `models` and `methods`, and the
/// errors of `tdcr.solve`.
#[pyfunction]
#[pyo3(signature = (robot, *, models=None, methods=None, **options))]
pub fn compare<'py>(
    py: Python<'py>,
    robot: &PyRobot,
    models: Option<Vec<String>>,
    methods: Option<Vec<String>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let settings = crate::options::apply(&robot.file.solver, options, crate::options::Use::Any("compare"))?;
    let r = &robot.file.robot;
    let shapes = match (models, methods) {
        (Some(_), Some(_)) => return Err(invalid("compare: give `models` or `methods`, not both")),
        (models, None) => {
            let variants = match models {
                Some(names) => names
                    .iter()
                    .map(|n| Variant::from_name(n))
                    .collect::<tdcr::Result<Vec<_>>>()
                    .map_err(to_py)?,
                None => Variant::ALL.to_vec(),
            };
            crate::boundary::detached(py, || compare_models(r, &variants, |v| crate::run(v, &settings, None)))?
        }
        (None, Some(names)) => {
            let mut shapes = Vec::new();
            for name in names {
                let method = match name.as_str() {
                    "collocation" => Method::Collocation,
                    "shooting" => Method::Shooting,
                    other => {
                        return Err(invalid(format!(
                            "compare: `{other}` is not a method; give \"collocation\" or \"shooting\""
                        )));
                    }
                };
                let mut s = settings.clone();
                s.method = method;
                let solution = crate::boundary::detached(py, || crate::run(r, &s, None))?;
                shapes.push((name, shape(&solution)));
            }
            compare_shapes(shapes)
        }
    };
    let out = PyList::empty(py);
    for c in shapes {
        let d = PyDict::new(py);
        d.set_item("name", &c.name)?;
        let s: Array1<f64> = c.states.iter().map(|x| x.s).collect();
        let p = Array2::from_shape_fn((c.states.len(), 3), |(i, k)| c.states[i].p[k]);
        d.set_item("s", s.into_pyarray(py))?;
        d.set_item("p", p.into_pyarray(py))?;
        d.set_item("tip_position", c.tip_position().as_slice().to_vec().into_pyarray(py))?;
        d.set_item("tip_rotation", matrix(py, &c.tip_rotation()))?;
        d.set_item("tip_distance", c.tip_distance)?;
        d.set_item("tip_angle", c.tip_angle)?;
        out.append(d)?;
    }
    Ok(out)
}
