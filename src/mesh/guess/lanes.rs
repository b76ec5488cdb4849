//! The default guess's pose integration in four-lane arithmetic ([`F4`]): every 3 x 3
//! matrix of an interval (hat(theta), its square, the half step's exponential, the
//! rotations) is held as three columns padded to four lanes, and a product's column is
//! three columns times three entries. Each entry gets the IEEE operations of the scalar
//! code in the same order (a product's entry (a_i0 b_0j + a_i1 b_1j) + a_i2 b_2j, as
//! nalgebra's product and `so3::exp_inlined` sum it), so the same bits, with about a third
//! of the instructions (docs/benchmarks.md, "guess20 (2026-12-07, twelfth session)").
#![allow(non_snake_case)]

use crate::mesh::MeshNode;
use crate::model::equations::Model;
use crate::simd::lanes::F4;
use crate::so3;
use nalgebra::{Matrix3, Vector3};

/// A 3 x 3 matrix as its columns, each padded with a fourth lane that is never read back.
type Columns = [F4; 3];

/// The poses along the mesh integrated from the base with the node coordinates `strains`
/// (module `guess`'s `integrate_poses_with` with [`Sums::Body`](super::Sums::Body)), into
/// `out` (cleared first): per interval of length h, with v and u the means of its end
/// nodes' strains and E = exp(u h/2), p += (R E) v h and R = (R E) E.
#[inline(always)]
pub(super) fn integrate_body(
    model: &Model,
    nodes: &[MeshNode],
    strains: &[(Vector3<f64>, Vector3<f64>)],
    out: &mut Vec<(Vector3<f64>, Matrix3<f64>)>,
) {
    let base = model.base_position();
    let mut p = F4([base[0], base[1], base[2], 0.0]);
    let mut R = columns(&model.robot.base_rotation);
    out.clear();
    out.push((base, model.robot.base_rotation));
    for k in 0..nodes.len() - 1 {
        let h = nodes[k + 1].s - nodes[k].s;
        if h > 0.0 {
            let v_k = super::strain(model, &nodes[k], &strains[k].0);
            let v = (v_k + super::strain(model, &nodes[k + 1], &strains[k + 1].0)) * 0.5;
            let u = (strains[k].1 + strains[k + 1].1) * 0.5;
            let half = exp(&(u * (h / 2.0)));
            let R_half = product(&R, &half);
            // (R E) v as nalgebra's matrix-vector product sums it, times h.
            p += (R_half[0] * v[0] + R_half[1] * v[1] + R_half[2] * v[2]) * h;
            R = product(&R_half, &half);
        }
        out.push((Vector3::new(p.0[0], p.0[1], p.0[2]), matrix(&R)));
    }
}

/// `so3::exp_inlined` in columns: I + k a + k^2 b with k = hat(theta) and (a, b) its
/// ratios ([`so3::exp_ratios`]), each entry ((I + k a) + k^2 b) as it sums them, k^2 as
/// its `hat_squared` sums each entry.
#[inline(always)]
fn exp(theta: &Vector3<f64>) -> Columns {
    let (a, b) = so3::exp_ratios(theta.norm_squared());
    let (x, y, z) = (theta[0], theta[1], theta[2]);
    // The columns of hat(theta): rows (0, -z, y), (z, 0, -x), (-y, x, 0).
    let k = [F4([0.0, z, -y, 0.0]), F4([-z, 0.0, x, 0.0]), F4([y, -x, 0.0, 0.0])];
    let k2 = product(&k, &k);
    let identity = [
        F4([1.0, 0.0, 0.0, 0.0]),
        F4([0.0, 1.0, 0.0, 0.0]),
        F4([0.0, 0.0, 1.0, 0.0]),
    ];
    [
        identity[0] + k[0] * a + k2[0] * b,
        identity[1] + k[1] * a + k2[1] * b,
        identity[2] + k[2] * a + k2[2] * b,
    ]
}

/// The columns of `m`.
#[inline(always)]
fn columns(m: &Matrix3<f64>) -> Columns {
    [
        F4([m[(0, 0)], m[(1, 0)], m[(2, 0)], 0.0]),
        F4([m[(0, 1)], m[(1, 1)], m[(2, 1)], 0.0]),
        F4([m[(0, 2)], m[(1, 2)], m[(2, 2)], 0.0]),
    ]
}

/// The matrix of the columns `c`.
#[inline(always)]
fn matrix(c: &Columns) -> Matrix3<f64> {
    Matrix3::new(
        c[0].0[0], c[1].0[0], c[2].0[0], c[0].0[1], c[1].0[1], c[2].0[1], c[0].0[2], c[1].0[2], c[2].0[2],
    )
}

/// The product a b, column by column: column j is (a_0 b_0j + a_1 b_1j) + a_2 b_2j (a_m
/// column m of a, b_mj = lane m of column j of b), each entry as nalgebra's product sums it.
#[inline(always)]
fn product(a: &Columns, b: &Columns) -> Columns {
    [
        a[0] * b[0].0[0] + a[1] * b[0].0[1] + a[2] * b[0].0[2],
        a[0] * b[1].0[0] + a[1] * b[1].0[1] + a[2] * b[1].0[2],
        a[0] * b[2].0[0] + a[1] * b[2].0[1] + a[2] * b[2].0[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lanes give the scalar integration's bits, every pose: the half step's
    /// exponential `so3::exp_inlined`, the rotations and positions by nalgebra's products,
    /// p += R E v h and R = (R E) E, on the prototype's mesh with strains that bend it in
    /// 3D (rotations of a half interval above and below the exponential's series switch,
    /// |theta| = 1/2, and exact zeros, whose signs the sums must keep).
    #[test]
    fn lanes_integrate_as_the_scalar_products() {
        let robot = crate::cases::prototype();
        let model = Model::new(&robot);
        for intervals in [1, 3, 16] {
            let mesh = crate::mesh::Mesh::uniform(&robot, intervals).expect("mesh");
            let nodes = &mesh.nodes;
            for scale in [0.0, 1.0, 40.0] {
                let strains: Vec<_> = nodes
                    .iter()
                    .enumerate()
                    .map(|(k, _)| {
                        let t = k as f64;
                        let v = Vector3::new(1e-4 * t.sin(), -0.0, 1.0 + 1e-5 * t);
                        let u = Vector3::new(scale * (0.3 + 0.1 * t), -scale * 0.7 * t.cos(), 0.0);
                        (v, u)
                    })
                    .collect();
                let mut got = Vec::new();
                integrate_body(&model, nodes, &strains, &mut got);
                let mut p = model.base_position();
                let mut R = robot.base_rotation;
                let mut want = vec![(p, R)];
                let mut largest = 0.0f64;
                for k in 0..nodes.len() - 1 {
                    let h = nodes[k + 1].s - nodes[k].s;
                    let v = (strains[k].0 + strains[k + 1].0) * 0.5;
                    let u = (strains[k].1 + strains[k + 1].1) * 0.5;
                    let theta = u * (h / 2.0);
                    largest = largest.max(theta.norm());
                    let half = so3::exp_inlined(&theta);
                    let R_half = R * half;
                    p += R_half * v * h;
                    R = R_half * half;
                    want.push((p, R));
                }
                let bits = |x: &[(Vector3<f64>, Matrix3<f64>)]| {
                    x.iter()
                        .flat_map(|(p, R)| p.iter().chain(R.iter()).map(|x| x.to_bits()).collect::<Vec<_>>())
                        .collect::<Vec<_>>()
                };
                assert_eq!(bits(&got), bits(&want), "{intervals} intervals, scale {scale}");
                if scale == 40.0 && intervals == 1 {
                    assert!(largest > 0.5, "{largest}");
                }
            }
        }
    }
}
