//! The phase condition of a branch that belongs to a family of equilibria (docs/stability.md,
//! "Families of equilibria"): where a path leaves a bifurcation whose kernel is two-dimensional
//! (the straight round column at Euler's load buckles in every plane alike), the branch it
//! takes is one member of a continuous family (every rotation of the buckled shape about the
//! axis), and the Jacobian J is singular all along it: its kernel direction c is the
//! family's own direction. The path is then held on the member it started on by one more row
//! and one more unknown mu,
//!
//! ```text
//! F(x, lambda) + mu psi = 0,    <c, x - x_0> / n = 0,
//! ```
//!
//! with psi the left kernel direction of J (J^T psi = 0 up to the small eigenvalue), so that
//! the bordered matrix [J psi; c^T 0] is regular where J is not. On the family mu = 0 (the
//! family solves F = 0 itself, and the bordered system has one solution nearby), so the
//! points are equilibria of the free problem; c and psi are refreshed at every point by
//! inverse iteration from their last values with the factors there, x_0 is the point the
//! step starts from. The bordered solves use the factors of J by block elimination: with
//! e = J^-1 (-psi), a step is a + dlambda b + dmu e, the two scalars from the two border rows.

use super::homotopy::{Homotopy, Point, dot, f_lambda, oriented};
use super::newton::Workspace;
use super::system::System;
use crate::report::SolveReport;
use crate::solution::State;

/// The most inverse-iteration solves for a kernel direction; near a bifurcation or on a
/// family the small eigenvalue is orders of magnitude below the next, so a few suffice.
const INVERSE_ITERATIONS: usize = 8;
/// Inverse iteration stops when successive directions agree to this cosine.
const CONVERGED_COS: f64 = 1.0 - 1e-10;
/// A bifurcation is the meeting point of a family when its kernel is two-dimensional: the
/// second kernel direction (orthogonal to the first) is as soft, its inverse iteration
/// growing at least this share as fast. The two buckling planes of the round column are alike
/// (measured 0.99999993 to 1.0073 over the column grid's switches, the spread being the
/// inverse iteration's); a section whose bending stiffnesses differ by 50 % gives 0.17-0.58 when
/// the switch is tried from a point far before its bifurcation, where both directions are
/// still stiff. Sections whose stiffnesses differ by less than about 1 % count as round.
const DOUBLE_KERNEL: f64 = 0.99;

/// A deterministic generic vector (entries spread over [-0.5, 0.5) by the golden ratio),
/// with a component along any given direction.
pub(super) fn generic(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| (i as f64 * 0.618_033_988_749_895).fract() - 0.5)
        .collect()
}

/// `v` scaled to |v|^2 / n = 1 (the tangent's normalization); None if zero or not finite.
pub(super) fn normalized(mut v: Vec<f64>) -> Option<Vec<f64>> {
    let norm = (dot(&v, &v) / v.len() as f64).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    v.iter_mut().for_each(|x| *x /= norm);
    Some(v)
}

/// `v` less its component along the normalized `d` (|d|^2 / n = 1).
fn deflate(v: &mut [f64], d: &[f64]) {
    let k = dot(v, d) / v.len() as f64;
    v.iter_mut().zip(d).for_each(|(x, d)| *x -= k * d);
}

/// Inverse iteration with the factors in `ws` from `start` (z <- J^-1 z normalized, or
/// J^-T z when `transposed`), kept orthogonal to `orthogonal` if given: the eigenvector of
/// the eigenvalue of least magnitude in the span `start` reaches, normalized, and the growth
/// |J^-1 z| / |z| of its last solve (the inverse of that eigenvalue's magnitude).
pub(super) fn kernel(
    ws: &mut Workspace,
    start: Vec<f64>,
    transposed: bool,
    orthogonal: Option<&[f64]>,
) -> Option<(Vec<f64>, f64)> {
    let n = start.len() as f64;
    let mut z = normalized(start)?;
    let mut growth = 0.0;
    for _ in 0..INVERSE_ITERATIONS {
        let mut next = match transposed {
            false => ws.solve_again(&z)?.to_vec(),
            true => ws.solve_transposed(&z)?.to_vec(),
        };
        if let Some(d) = orthogonal {
            deflate(&mut next, d);
        }
        growth = (dot(&next, &next) / n).sqrt();
        let next = normalized(next)?;
        let cos = dot(&next, &z) / n;
        z = next;
        if cos.abs() >= CONVERGED_COS {
            break;
        }
    }
    Some((z, growth))
}

/// The phase condition of a family's branch: its direction `c` (unknowns) and the left
/// kernel direction `psi` (residual rows), both normalized to |v|^2 / n = 1.
pub(super) struct Phase {
    /// The family's direction: the kernel of J on the branch, the rows' normal.
    pub c: Vec<f64>,
    /// The left kernel direction of J, the column of the extra unknown mu.
    pub psi: Vec<f64>,
}

impl Phase {
    /// The count of unstable directions `next` at a point of a family's branch, given the
    /// count `before` at the last point: the family's own direction is neutral there (an exact
    /// zero of the second variation, whose conjugate point lies at the base), and the error of
    /// a guide (converged to 1e-6 only) tips it to either side of the base, so a change by one
    /// is that direction, not a change of stability.
    pub(super) fn neutral(before: Option<usize>, next: Option<usize>) -> Option<usize> {
        match (before, next) {
            (Some(a), Some(b)) if a.abs_diff(b) == 1 => before,
            _ => next,
        }
    }

    /// At a bifurcation point whose factored Jacobian has the kernel direction `phi` (grown
    /// by `growth` in its inverse iteration): a direction for the family when the kernel is
    /// two-dimensional ([`DOUBLE_KERNEL`]), the second kernel direction, orthogonal to
    /// `phi`, which is the family's direction on the branch along `phi`. None for a simple
    /// bifurcation.
    pub fn second_kernel(ws: &mut Workspace, phi: &[f64], growth: f64) -> Option<Vec<f64>> {
        let mut start = generic(phi.len());
        deflate(&mut start, phi);
        let (c, second) = kernel(ws, start, false, Some(phi))?;
        (second >= DOUBLE_KERNEL * growth).then_some(c)
    }

    /// The phase condition at a point of the family's branch whose Jacobian is factored in
    /// `ws`, by inverse iteration from `c` (the last point's, or the second kernel direction
    /// at the bifurcation) and from `psi` (None: a generic start). None if a solve fails.
    pub fn at(ws: &mut Workspace, c: Vec<f64>, psi: Option<Vec<f64>>) -> Option<Phase> {
        let n = c.len();
        let (c, _) = kernel(ws, c, false, None)?;
        let (psi, _) = kernel(ws, psi.unwrap_or_else(|| generic(n)), true, None)?;
        Some(Phase { c, psi })
    }

    /// [`Phase::at`] from this phase's directions (the next point of the branch).
    pub fn refreshed(self, ws: &mut Workspace) -> Option<Phase> {
        Phase::at(ws, self.c, Some(self.psi))
    }

    /// e = J^-1 (-psi) with the factors in `ws`.
    pub fn e(&self, ws: &mut Workspace) -> Option<Vec<f64>> {
        let rhs: Vec<f64> = self.psi.iter().map(|v| -v).collect();
        Some(ws.solve_again(&rhs)?.to_vec())
    }

    /// The tangent of the held branch at the converged point `x` (Jacobian factored in
    /// `ws`): (t_x, t_lambda) with J t_x + F_lambda t_lambda + psi t_mu = 0 and
    /// <c, t_x> = 0, normalized as a path's tangent and oriented along `previous` (or towards
    /// growing lambda), with dF/dlambda there.
    #[allow(clippy::too_many_arguments)]
    pub fn tangent(
        &self,
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
        let b = ws.solve_again(&rhs)?.to_vec();
        let e = self.e(ws)?;
        let ce = dot(&self.c, &e);
        if !(ce.is_finite() && ce != 0.0) {
            return None;
        }
        let m = -dot(&self.c, &b) / ce;
        let z: Vec<f64> = b.iter().zip(&e).map(|(b, e)| b + m * e).collect();
        let (tx, tl) = oriented(&z, previous);
        tx.iter()
            .all(|v| v.is_finite())
            .then_some((Point { x, lambda, tx, tl }, fl))
    }
}
