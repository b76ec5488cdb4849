//! The tendons' pulls of the default guess's sweeps, four tendons side by side: each lane
//! of [`F4`] does one tendon's arithmetic of `Model::tendon_pull_body_of` (eq. 9 in the
//! body frame) with the same IEEE operations in the same order, and the lanes are summed
//! one after the other in tendon order, as the scalar loop sums them: the same bits, with
//! a quarter of the products (docs/benchmarks.md, "guess20 (2026-12-07, twelfth session)").
//!
//! The tendons of a node and their routing points do not change between sweeps, so they
//! are laid out in lanes once per estimate ([`quads`]).
#![allow(non_snake_case)]

use crate::model::equations::MIN_TENDON_SPEED;
use crate::model::routing::RoutingPoint;
use crate::simd::lanes::F4;
use nalgebra::Vector3;

/// Up to four tendons of one node in lanes: routing point r and its rate r' component by
/// component, and the tension (N, with the model's tension factor). Lanes past `count` hold
/// zeros and are never read back.
#[derive(Clone, Copy, Debug)]
pub(super) struct TendonQuad {
    /// r (m), x, y and z.
    r: [F4; 3],
    /// r' (dr/ds), x, y and z.
    r_s: [F4; 3],
    /// tau_i (N).
    tension: F4,
    /// How many lanes, from the first, hold a tendon (1 to 4).
    count: usize,
}

/// The tendons `routes` of every node ([`Model::tendons`](crate::model::equations::Model::tendons)'s
/// order; `ends[k]` ends node k's) four by four into `out`, and where each node's quads end
/// into `quad_ends`.
pub(super) fn quads(
    (routes, ends): (&[(usize, f64, RoutingPoint)], &[usize]),
    (out, quad_ends): (&mut Vec<TendonQuad>, &mut Vec<usize>),
) {
    out.clear();
    quad_ends.clear();
    let mut from = 0;
    for &end in ends {
        for chunk in routes[from..end].chunks(4) {
            let mut quad = TendonQuad {
                r: [F4::ZERO; 3],
                r_s: [F4::ZERO; 3],
                tension: F4::ZERO,
                count: chunk.len(),
            };
            for (lane, (_, tension, rp)) in chunk.iter().enumerate() {
                for c in 0..3 {
                    quad.r[c].0[lane] = rp.r[c];
                    quad.r_s[c].0[lane] = rp.r_s[c];
                }
                quad.tension.0[lane] = *tension;
            }
            out.push(quad);
        }
        quad_ends.push(out.len());
        from = end;
    }
}

/// The sum over the tendons `quads` of their pulls tau_i p_b' / |p_b'| (body frame, N),
/// p_b' = u x r + r' + v, and of their moments r x (tau_i p_b' / |p_b'|) (N m), for the
/// strain `v` and curvature `u`; with `coupled` false (the point-moment model) the force
/// sum stays zero. Bitwise `Model::tendon_pull_body_of` of the same tendons; None where it
/// is an error (a tendon's |p_b'| below [`MIN_TENDON_SPEED`]).
#[inline(always)]
pub(super) fn pull(
    quads: &[TendonQuad],
    coupled: bool,
    v: &Vector3<f64>,
    u: &Vector3<f64>,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let mut force = Vector3::zeros();
    let mut moment = Vector3::zeros();
    let (ux, uy, uz) = (F4::splat(u[0]), F4::splat(u[1]), F4::splat(u[2]));
    for q in quads {
        let [rx, ry, rz] = q.r;
        // u x r (nalgebra's cross: y z - z y, z x - x z, x y - y x), + r', + v.
        let px = (uy * rz - uz * ry + q.r_s[0]) + v[0];
        let py = (uz * rx - ux * rz + q.r_s[1]) + v[1];
        let pz = (ux * ry - uy * rx + q.r_s[2]) + v[2];
        // |p_b'| as nalgebra's norm: sqrt((x x + y y) + z z).
        let speed = (px * px + py * py + pz * pz).sqrt();
        for lane in 0..q.count {
            if speed.lane(lane) < MIN_TENDON_SPEED {
                return None;
            }
        }
        let scale = q.tension / speed;
        let (fx, fy, fz) = (px * scale, py * scale, pz * scale);
        // r x f_b.
        let (mx, my, mz) = (ry * fz - rz * fy, rz * fx - rx * fz, rx * fy - ry * fx);
        for lane in 0..q.count {
            if coupled {
                force += Vector3::new(fx.lane(lane), fy.lane(lane), fz.lane(lane));
            }
            moment += Vector3::new(mx.lane(lane), my.lane(lane), mz.lane(lane));
        }
    }
    Some((force, moment))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::equations::{Model, Which};

    /// The lanes give `Model::tendon_pull_body_of`'s bits, force and moment, on the
    /// prototype with all five tendons pulled (a helical one among them: routing rates
    /// r' not zero; five tendons: a full quad and a quad of one) and with the point-moment
    /// model, for strains with signed zeros, exact zeros and large curvatures; and refuse
    /// where it errs (a tendon's path that stops: p_b' = 0).
    #[test]
    fn lanes_pull_as_the_scalar_sum() {
        let mut robot = crate::cases::prototype();
        for (i, tendon) in robot.tendons.iter_mut().enumerate() {
            tendon.set_tension(0.3 + 0.9 * i as f64);
        }
        let mut point_moment = robot.clone();
        point_moment.tendon_model = crate::model::robot::TendonModel::PointMoment;
        let strains = [
            (Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 0.0, 0.0)),
            (Vector3::new(-0.0, 0.0, 1.0), Vector3::new(-0.0, 4.1, -0.0)),
            (Vector3::new(1e-3, -2e-4, 0.9993), Vector3::new(-7.3, 2.9, 0.31)),
            (Vector3::new(0.1, 0.2, 1.3), Vector3::new(60.0, -45.0, 12.0)),
        ];
        let bits =
            |(f, l): (Vector3<f64>, Vector3<f64>)| f.iter().chain(l.iter()).map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut checked = 0;
        for robot in [robot, point_moment] {
            let model = Model::new(&robot);
            let coupled = robot.tendon_model == crate::model::robot::TendonModel::Coupled;
            for s in [0.0, 0.05, 0.121, 0.2] {
                let routes: Vec<_> = model.tendons(s, Which::ActiveTo(s)).collect();
                assert_eq!(routes.len(), 5);
                let (mut lanes, mut ends) = (Vec::new(), Vec::new());
                quads((&routes, &[routes.len()]), (&mut lanes, &mut ends));
                assert_eq!((lanes.len(), ends[0]), (2, 2));
                for (v, u) in strains {
                    let scalar = model.tendon_pull_body_of(routes.iter().copied(), s, &v, &u);
                    let got = pull(&lanes, coupled, &v, &u).expect("moving paths");
                    assert_eq!(bits(got), bits(scalar.expect("moving paths")));
                    checked += 1;
                }
                // A strain that stops tendon 1's path (p_b' = u x r + r' + v = 0) errs.
                let rp = routes[0].2;
                let stop = -(rp.r_s);
                assert!(
                    model
                        .tendon_pull_body_of(routes.iter().copied(), s, &stop, &Vector3::zeros())
                        .is_err()
                );
                assert!(pull(&lanes, coupled, &stop, &Vector3::zeros()).is_none());
            }
        }
        assert_eq!(checked, 32);
    }
}
