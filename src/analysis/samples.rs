//! The solved shape at output arc lengths, with the internal wrench there (eq. 3), and the
//! bending angle: what result files and tables report. SI units throughout.
#![allow(non_snake_case)]

use crate::model::equations::Model;
use crate::model::robot::RodModel;
use crate::solution::Node;
use crate::{Robot, Solution};
use nalgebra::{Matrix3, Vector3};

/// The state at one output arc length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Arc length (m).
    pub s: f64,
    /// Centreline position (m), world frame.
    pub p: Vector3<f64>,
    /// Orientation, body to world.
    pub R: Matrix3<f64>,
    /// Internal force (N), world frame.
    pub n: Vector3<f64>,
    /// Internal moment (N m), world frame.
    pub m: Vector3<f64>,
}

/// The solution at the output arc lengths: its own nodes when `count` is `None` (both
/// limits where the solution jumps), otherwise `count` (>= 2; fewer are raised to 2) evenly
/// spaced arc lengths from 0 to L, interpolated with the solution's Hermite interpolant
/// ([`Solution::at`]) and n, m from the constitutive law (eq. 3) at the interpolated strains
/// (on a Kirchhoff rod n is the reaction, interpolated between the nodes by the cubic
/// Hermite interpolant with the slopes n' of eq. 13 there).
pub fn samples(robot: &Robot, solution: &Solution, count: Option<usize>) -> Vec<Sample> {
    let Some(count) = count else {
        return node_samples(solution);
    };
    let model = Model::new(robot);
    let count = count.max(2);
    let length = solution.length();
    (0..count)
        .map(|k| {
            let s = length * k as f64 / (count - 1) as f64;
            let state = solution.at(s);
            let (mut n, m) = model.internal_wrench(&model.site(s), &state.R, &state.v, &state.u);
            if robot.rod_model == RodModel::Kirchhoff {
                // The force is the constraint's reaction, not eq. 3 of the strain v = v*.
                n = reaction(&model, solution, s);
            }
            Sample {
                s,
                p: state.p,
                R: state.R,
                n,
                m,
            }
        })
        .collect()
}

/// The internal force n(s) (N, world frame) of a solved Kirchhoff rod: the cubic Hermite
/// interpolant between the nodes' forces with the slopes n' = R (n_b' + u x n_b) of eq. 13
/// there (n_b' from the rate of the node's translational coordinate,
/// [`crate::model::equations::Site::strain`]); the secant slope where eq. 13 breaks down.
fn reaction(model: &Model, solution: &Solution, s: f64) -> Vector3<f64> {
    let (k, [h00, h10, h01, h11]) = solution.interval(s, false);
    let (a, b) = (&solution.nodes[k], &solution.nodes[k + 1]);
    let h = b.s - a.s;
    let secant = (b.n - a.n) / h;
    // Both nodes on the stretch of backbone that ends at b (or later): its segment's site.
    let slope = |node: &Node| -> Vector3<f64> {
        let site = model.site_on(node.s, b.s);
        let n_b = node.R.transpose() * node.n;
        let (v, _) = model.strains_for_wrench(&site, &n_b, &Vector3::zeros());
        match model.strain_rates(&site, b.s, &node.R, &v, &node.u) {
            Ok((v_s, _)) => {
                let kse = &site.section.section.kse;
                let n_b_s = site.section.kse_s.component_mul(&n_b.component_div(kse))
                    + kse.component_mul(&(v_s - site.reference.v_star_s));
                node.R * (n_b_s + node.u.cross(&n_b))
            }
            Err(_) => secant,
        }
    };
    a.n * h00 + slope(a) * (h10 * h) + b.n * h01 + slope(b) * (h11 * h)
}

/// The solution's own nodes as samples (both limits where the solution jumps).
pub fn node_samples(solution: &Solution) -> Vec<Sample> {
    solution
        .nodes
        .iter()
        .map(|n| Sample {
            s: n.s,
            p: n.p,
            R: n.R,
            n: n.n,
            m: n.m,
        })
        .collect()
}

/// Bending angle (rad): the angle between the base tangent R(0) e3 and the tip tangent
/// R(L) e3, in [0, pi].
pub fn bending_angle(solution: &Solution) -> f64 {
    let a = solution.base().R.column(2).into_owned();
    let b = solution.tip().R.column(2).into_owned();
    a.cross(&b).norm().atan2(a.dot(&b))
}
