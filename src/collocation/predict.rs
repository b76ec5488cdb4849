//! The a-priori first mesh of a cold start (docs/numerics.md, "The first mesh from the
//! guess"): the local error of Hermite-Simpson predicted from the rigid-equilibrium guess's
//! node states, before any Newton solve, and where it says the starting mesh is clearly too
//! coarse for the tolerance, a mesh with the intervals it needs.

use super::options::Options;
use super::refine;
use crate::Robot;
use crate::error::Result;
use crate::mesh::{Mesh, spare};
use crate::solution::State;
use nalgebra::Matrix3;

/// Simpson's error constant: the rule's error on an interval of length h is
/// h^5 f^(4) / 2880 (docs/numerics.md, "The first mesh from the guess").
const SIMPSON: f64 = 2880.0;

/// The starting mesh moves only where the predicted tip error exceeds the tolerance by
/// this factor: on random robots the first mesh's estimate ranges from 0.1 to 10 times the
/// prediction (docs/numerics.md, "The first mesh from the guess"), and a first mesh that
/// meets the tolerance should keep it.
const MARGIN: f64 = 8.0;

/// The m-th derivative (m! times the divided difference) of `values` at the distinct,
/// increasing arc lengths `s` (m + 1 of each; `values` is overwritten).
fn derivative(s: &[f64], values: &mut [Matrix3<f64>]) -> Matrix3<f64> {
    let m = s.len() - 1;
    let mut factorial = 1.0;
    for order in 1..=m {
        factorial *= order as f64;
        for i in 0..=m - order {
            values[i] = (values[i + 1] - values[i]) / (s[i + order] - s[i]);
        }
    }
    values[0] * factorial
}

/// The predicted local error of every link of `mesh` for the node states `x`: Simpson's
/// error h^5 |R^(5)|_F / 2880 of the interval's rotation, R^(5) the fourth derivative of
/// R' = R u^ from the five nodes of the interval's segment nearest it (divided differences);
/// 0 for jumps and in segments of fewer than four intervals.
pub(crate) fn local_errors(mesh: &Mesh, x: &[State]) -> Vec<f64> {
    const ORDER: usize = 4;
    let links = mesh.nodes.len() - 1;
    let mut out = spare::take(links);
    out.resize(links, 0.0);
    let mut s = [0.0; ORDER + 1];
    let mut values = [Matrix3::zeros(); ORDER + 1];
    let mut a = 0;
    while a < links {
        // One segment: nodes a..=b.
        let b = (a..links).find(|&j| mesh.is_jump(j)).unwrap_or(links);
        if b - a >= ORDER {
            for k in a..b {
                let j = k.saturating_sub(ORDER / 2).clamp(a, b - ORDER);
                for i in 0..=ORDER {
                    let n = &x[j + i];
                    s[i] = n.s;
                    values[i] = n.R * n.u.cross_matrix();
                }
                let h = x[k + 1].s - x[k].s;
                out[k] = h.powi(5) * derivative(&s, &mut values).norm() / SIMPSON;
            }
        }
        a = b + 1;
    }
    out
}

/// The most a predicted first mesh grows the starting one: a guess far from the answer can
/// ask for many times the intervals the answer needs (one random robot asked for 11 times).
const MAX_GROWTH: f64 = 4.0;

/// The first mesh of a cold, error-controlled start on `mesh` with the guess `x`
/// ([`super::Options::first_mesh_from_guess`]): `None` where the predicted tip rotation
/// error (the sum of [`local_errors`]) is within [`MARGIN`] times the tolerance `tol`;
/// else a uniform mesh with the intervals that error needs at order 4 (aiming, as
/// re-meshing does, at [`refine::TARGET_FRACTION`] of the tolerance), at most
/// [`MAX_GROWTH`] times the start's and within the interval cap. Uniform, not
/// equidistributed by the predicted local errors: where the guess puts its errors is less
/// reliable than their sum (equidistributed first meshes doubled the final meshes of random
/// robots, docs/benchmarks.md "mesh18").
///
/// # Errors
/// [`crate::Error::InvalidInput`] if the mesh cannot be built.
pub(crate) fn first_mesh(robot: &Robot, mesh: &Mesh, x: &[State], tol: f64, options: &Options) -> Result<Option<Mesh>> {
    let local = local_errors(mesh, x);
    let ratio = local.iter().sum::<f64>() / tol;
    spare::give(local);
    // A NaN ratio (a guess that is not finite) keeps the start.
    if ratio.is_nan() || ratio <= MARGIN {
        return Ok(None);
    }
    let intervals = mesh.intervals() as f64;
    let wanted = intervals * (ratio / refine::TARGET_FRACTION).powf(0.25);
    let target = (wanted.min(MAX_GROWTH * intervals).ceil() as usize).min(options.max_intervals);
    if target as f64 <= intervals {
        return Ok(None);
    }
    Mesh::uniform(robot, target).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshNode;
    use nalgebra::Vector3;

    /// States along a rod of length `length` on `intervals` uniform intervals whose frame
    /// turns about its z axis by the angle `theta(s)` (curvature `rate(s)` = theta'(s)).
    fn turning(
        length: f64,
        intervals: usize,
        theta: impl Fn(f64) -> f64,
        rate: impl Fn(f64) -> f64,
    ) -> (Mesh, Vec<State>) {
        let nodes: Vec<MeshNode> = (0..=intervals)
            .map(|k| MeshNode {
                s: length * k as f64 / intervals as f64,
                segment_end: length,
            })
            .collect();
        let x = nodes
            .iter()
            .map(|n| State {
                s: n.s,
                p: Vector3::zeros(),
                R: crate::so3::exp(&Vector3::new(0.0, 0.0, theta(n.s))),
                v: Vector3::z(),
                u: Vector3::new(0.0, 0.0, rate(n.s)),
            })
            .collect();
        (Mesh { nodes }, x)
    }

    /// On a circular arc (constant curvature w) |R^(5)|_F = sqrt(2) w^5 everywhere; the
    /// fourth divided difference of R' = R u^ at five equally spaced nodes is exactly that
    /// times (sin(h w / 2) / (h w / 2))^4 (the difference operator on exp(i w s)), 0.66 %
    /// below at h w = 0.2: every interval's predicted error is sqrt(2) (h w)^5 / 2880 times
    /// that factor, to rounding (1e-9: the differences cancel about 6 digits of R').
    #[test]
    fn an_arc_predicts_simpsons_error_of_its_rotation() {
        let (length, w) = (0.25, 25.6);
        let (mesh, x) = turning(length, 32, |s| w * s, |_| w);
        let h = length / 32.0;
        let sinc = (h * w / 2.0).sin() / (h * w / 2.0);
        let exact = 2f64.sqrt() * (h * w).powi(5) / 2880.0 * sinc.powi(4);
        for (k, e) in local_errors(&mesh, &x).iter().enumerate() {
            assert!((e / exact - 1.0).abs() < 1e-9, "link {k}: {e:.6e} against {exact:.6e}");
        }
    }

    /// |d^5/ds^5 exp(i theta(s))| for theta = a sin(w s): the complete Bell polynomial
    /// B5 of (i theta', ..., i theta^(5)), whose real part is 10 t1^3 t2 - 10 t2 t3 - 5 t1 t4
    /// and imaginary part t1^5 - 15 t1 t2^2 - 10 t1^2 t3 + t5 (t_n = theta^(n)).
    fn fifth(a: f64, w: f64, s: f64) -> f64 {
        let t = |n: i32| a * w.powi(n) * (w * s + f64::from(n) * std::f64::consts::FRAC_PI_2).sin();
        let (t1, t2, t3, t4, t5) = (t(1), t(2), t(3), t(4), t(5));
        let re = 10.0 * t1.powi(3) * t2 - 10.0 * t2 * t3 - 5.0 * t1 * t4;
        let im = t1.powi(5) - 15.0 * t1 * t2 * t2 - 10.0 * t1 * t1 * t3 + t5;
        re.hypot(im)
    }

    /// A frame that oscillates about z, theta = a sin(w s) with one period per rod length
    /// (as a helical tendon of one turn per rod length turns case H's bending plane): the
    /// sum of the predicted local errors on 32 intervals against the integral of
    /// h^4 |R^(5)|_F / 2880 over the rod (|R^(5)|_F = sqrt(2) |d^5 exp(i theta) / ds^5|,
    /// midpoint rule on 20 000 points). The interval counts the tolerance 1e-7 asks for
    /// (the sum falls like N^-4) agree within 3 % (the divided differences' O((h w)^2) and
    /// the sum's sampling of |R^(5)| at 32 points).
    #[test]
    fn an_oscillating_frame_predicts_its_interval_count() {
        let (length, a) = (0.242, 0.5);
        let w = 2.0 * std::f64::consts::PI / length;
        let (mesh, x) = turning(length, 32, |s| a * (w * s).sin(), |s| a * w * (w * s).cos());
        let predicted: f64 = local_errors(&mesh, &x).iter().sum();
        let h = length / 32.0;
        let fine = 20_000;
        let integral: f64 = (0..fine)
            .map(|i| 2f64.sqrt() * fifth(a, w, length * (i as f64 + 0.5) / fine as f64))
            .sum::<f64>()
            * (length / fine as f64);
        let exact = h.powi(4) * integral / 2880.0;
        let count = |sum: f64| 32.0 * (sum / (0.8 * 1e-7)).powf(0.25);
        assert!(
            (count(predicted) / count(exact) - 1.0).abs() < 0.03,
            "predicted {predicted:.4e} ({:.1} intervals), exact {exact:.4e} ({:.1})",
            count(predicted),
            count(exact)
        );
    }
}
