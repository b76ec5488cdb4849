//! The homotopies a path follows (the load path, a parameter's line, the Newton homotopy
//! from a warm start), their residual F(x, lambda) and its lambda-derivative, and the
//! tangent of the branch at a converged point (docs/numerics.md, "Load path").

use super::newton::Workspace;
use super::system::System;
use crate::model::parameter::Parameter;
use crate::report::SolveReport;
use crate::solution::State;

/// Difference step of F_lambda: the residual is smooth in lambda and resolves it to about
/// 1e-11, so a central difference at 1e-5 is accurate to about 1e-6 relative, plenty for
/// a tangent.
const DELTA: f64 = 1e-5;

/// A point of the path with the tangent there.
pub(super) struct Point {
    /// The states.
    pub x: Vec<State>,
    /// The path parameter.
    pub lambda: f64,
    /// Tangent, scaled unknowns (the Newton step's units) then lambda, normalized so that
    /// |t_x|^2 / n + t_lambda^2 = 1.
    pub tx: Vec<f64>,
    pub tl: f64,
}

/// The dot product of two vectors of one length.
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The largest absolute value (infinite if any is NaN).
pub(super) fn max_norm(v: &[f64]) -> f64 {
    v.iter()
        .fold(0.0, |m, x| if x.is_nan() { f64::INFINITY } else { m.max(x.abs()) })
}

/// Which problems the path connects.
pub(super) enum Homotopy {
    /// One input moved along a line: `parameter` = from + lambda (to - from). The load
    /// path is the load scale from 0 to 1, from the unloaded robot.
    Parameter {
        /// The input.
        parameter: Parameter,
        /// Its value at lambda = 0.
        from: f64,
        /// Its value at lambda = 1.
        to: f64,
    },
    /// From a warm start x0 (not a solution) to the robot: F(x) - (1 - lambda) F(x0) = 0,
    /// which x0 solves at lambda = 0 (a Newton homotopy). Holds F(x0).
    Newton(Vec<f64>),
}

impl Homotopy {
    /// The load path: every tension and load scaled from 0 to 1.
    pub(super) fn load() -> Self {
        Homotopy::Parameter {
            parameter: Parameter::LoadScale,
            from: 0.0,
            to: 1.0,
        }
    }

    /// Sets `system` to the problem at `lambda`.
    pub(super) fn set(&self, system: &mut System, lambda: f64) {
        if let Homotopy::Parameter { parameter, from, to } = *self {
            system.set_parameter(parameter, from + lambda * (to - from));
        }
    }
}

/// The residual at (x, lambda) into `out`; false when the model breaks down.
pub(super) fn residual(
    system: &mut System,
    homotopy: &Homotopy,
    x: &[State],
    lambda: f64,
    out: &mut [f64],
    report: &mut SolveReport,
) -> bool {
    homotopy.set(system, lambda);
    report.evaluations.residual += 1;
    report.evaluations.equations += system.rate_evaluations();
    let ok = system.residual(x, out).is_ok();
    if let Homotopy::Newton(r0) = homotopy {
        out.iter_mut().zip(r0).for_each(|(o, r)| *o -= (1.0 - lambda) * r);
    }
    ok && out.iter().all(|v| v.is_finite())
}

/// dF/dlambda at x: F(x0) for a Newton homotopy; for a parameter a central difference
/// (one-sided at lambda = 0, where tensions would turn negative).
pub(super) fn f_lambda(
    system: &mut System,
    homotopy: &Homotopy,
    x: &[State],
    lambda: f64,
    report: &mut SolveReport,
) -> Option<Vec<f64>> {
    if let Homotopy::Newton(r0) = homotopy {
        return Some(r0.clone());
    }
    let n = system.unknowns();
    let (mut hi, mut lo) = (vec![0.0; n], vec![0.0; n]);
    let (a, b) = if lambda >= DELTA {
        (lambda - DELTA, lambda + DELTA)
    } else {
        (lambda, lambda + DELTA)
    };
    let ok = residual(system, homotopy, x, b, &mut hi, report) && residual(system, homotopy, x, a, &mut lo, report);
    homotopy.set(system, lambda);
    ok.then(|| hi.iter().zip(&lo).map(|(h, l)| (h - l) / (b - a)).collect())
}

/// The tangent at a converged point whose Jacobian is factored in `ws`, oriented along
/// `previous` (or towards growing lambda).
pub(super) fn tangent(
    system: &mut System,
    homotopy: &Homotopy,
    ws: &mut Workspace,
    x: Vec<State>,
    lambda: f64,
    previous: Option<(&[f64], f64)>,
    report: &mut SolveReport,
) -> Option<(Point, Vec<f64>)> {
    let fl = f_lambda(system, homotopy, &x, lambda, report)?;
    let rhs: Vec<f64> = fl.iter().map(|v| -v).collect();
    let z = ws.solve_again(&rhs)?.to_vec();
    let (tx, tl) = oriented(&z, previous);
    Some((Point { x, lambda, tx, tl }, fl))
}

/// The unit tangent (tx, tl) of the direction (z, 1) in the scaled norm (mean square over
/// the unknowns plus lambda's square), turned to point the way `previous` did (forward in
/// lambda without one).
pub(super) fn oriented(z: &[f64], previous: Option<(&[f64], f64)>) -> (Vec<f64>, f64) {
    let n = z.len() as f64;
    let norm = (dot(z, z) / n + 1.0).sqrt();
    let mut tx: Vec<f64> = z.iter().map(|v| v / norm).collect();
    let mut tl = 1.0 / norm;
    let forward = match previous {
        Some((ptx, ptl)) if ptx.len() == tx.len() => dot(ptx, &tx) / n + ptl * tl >= 0.0,
        Some((_, ptl)) => ptl >= 0.0,
        None => true,
    };
    if !forward {
        tx.iter_mut().for_each(|v| *v = -*v);
        tl = -tl;
    }
    (tx, tl)
}
