//! Initial guesses: the rigid-equilibrium estimate.
//!
//! The loads distal to each node are summed on the unloaded (reference) shape, giving an
//! estimate of the internal wrench there; the linear constitutive law turns it into strains,
//! and the poses are integrated from the base with those strains. For tendon-only loading
//! this is already the exact constant-curvature answer; for small external loads it is
//! linear beam theory; with no load it is the reference shape itself.
#![allow(non_snake_case)]

use crate::equations::{Model, Which};
use crate::mesh::MeshNode;
use crate::so3;
use crate::solution::State;
use nalgebra::{Matrix3, Vector3};

/// Poses along the mesh integrated from the base with the node strains `v`, `u` (midpoint
/// rule on the Lie group); left and right limits at a breakpoint share a pose.
fn integrate_poses(
    model: &Model,
    nodes: &[MeshNode],
    strains: &[(Vector3<f64>, Vector3<f64>)],
) -> Vec<(Vector3<f64>, Matrix3<f64>)> {
    let mut p = model.robot.base_position;
    let mut R = model.robot.base_rotation;
    let mut out = Vec::with_capacity(nodes.len());
    out.push((p, R));
    for k in 0..nodes.len() - 1 {
        let h = nodes[k + 1].s - nodes[k].s;
        if h > 0.0 {
            let v = (strains[k].0 + strains[k + 1].0) * 0.5;
            let u = (strains[k].1 + strains[k + 1].1) * 0.5;
            p += R * so3::exp(&(u * (h / 2.0))) * v * h;
            R *= so3::exp(&(u * h));
        }
        out.push((p, R));
    }
    out
}

/// Most shape sweeps of the rigid-equilibrium estimate.
const MAX_SWEEPS: usize = 8;

/// The rigid-equilibrium estimate of the state at every mesh node, refined by re-summing
/// the loads on the shape it predicts (moment arms and body frames from the previous sweep)
/// until the curvature stops changing, or grows (then the previous sweep is kept).
pub fn rigid_estimate(model: &Model, nodes: &[MeshNode]) -> Vec<State> {
    let length = model.robot.length();
    let mut strains: Vec<_> = nodes
        .iter()
        .map(|n| {
            let r = model.robot.rod.reference_at(n.s);
            (r.v_star, r.u_star)
        })
        .collect();
    let mut shape = integrate_poses(model, nodes, &strains);
    let mut last_change = f64::INFINITY;
    for _ in 0..MAX_SWEEPS {
        let next = sweep(model, nodes, &shape, &strains);
        let change = next
            .iter()
            .zip(&strains)
            .map(|(a, b)| (a.1 - b.1).amax() * length)
            .fold(0.0, f64::max);
        if !(change < last_change || last_change.is_infinite()) || !change.is_finite() {
            break;
        }
        strains = next;
        shape = integrate_poses(model, nodes, &strains);
        last_change = change;
        // 1e-6 of a radian over the rod: far below what Newton needs from a guess
        if change < 1e-6 {
            break;
        }
    }
    shape
        .into_iter()
        .zip(nodes.iter().zip(strains))
        .map(|((p, R), (node, (v, u)))| State { s: node.s, p, R, v, u })
        .collect()
}

/// One sweep: node strains carrying the loads distal to each node, summed on `shape`.
fn sweep(
    model: &Model,
    nodes: &[MeshNode],
    shape: &[(Vector3<f64>, Matrix3<f64>)],
    strains: &[(Vector3<f64>, Vector3<f64>)],
) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let last = nodes.len() - 1;
    // Distal load sums (N, M about p_k) by a backward sweep with the trapezoid rule.
    let mut wrench = vec![(Vector3::zeros(), Vector3::zeros()); nodes.len()];
    wrench[last] = model.point_wrench(nodes[last].s);
    for k in (0..last).rev() {
        let (N, M) = wrench[k + 1];
        let h = nodes[k + 1].s - nodes[k].s;
        wrench[k] = if h == 0.0 {
            let (f, l) = model.point_wrench(nodes[k].s);
            (N + f, M + l)
        } else {
            let (a, b) = (model.site(nodes[k].s), model.site(nodes[k + 1].s));
            let d = shape[k + 1].0 - shape[k].0;
            (
                N + (a.f_e + b.f_e) * (h / 2.0),
                M + d.cross(&N) + (d.cross(&b.f_e) + a.l_e + b.l_e) * (h / 2.0),
            )
        };
    }
    nodes
        .iter()
        .enumerate()
        .map(|(k, node)| {
            let site = model.site(node.s);
            let R = shape[k].1;
            let (v, u) = strains[k];
            let (mut n, mut m) = wrench[k];
            // The tendons loading this node's segment pull it back along their paths.
            if let Ok((f, l)) = model.tendon_pull(node.s, Which::ActiveTo(node.segment_end), &R, &v, &u) {
                n -= f;
                m -= l;
            }
            model.strains_for_wrench(&site, &(R.transpose() * n), &(R.transpose() * m))
        })
        .collect()
}
