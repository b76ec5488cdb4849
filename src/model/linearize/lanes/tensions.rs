//! The tension part of [`linearize_tensions_inline`](super::super::linearize_tensions_inline)
//! at four points at once, one per f64 lane: each tendon's dF/dtau_i at the fixed state and
//! rates (`parameters::tension_partials`) and its solve with the lanes' factors of M, each
//! operation the scalar code's on each lane's values in the scalar code's order, so each
//! lane gives the bits of the scalar derivatives at its point (the tests of
//! `collocation::interval_lanes` compare them).
#![allow(non_snake_case)]

use super::{F4, Schur, TendonLanes, V3, add, cross, mat_vec, sub};
use crate::model::equations::{Model, Site};
use crate::model::routing::RoutingPoint;
use nalgebra::Vector6;

/// Where [`linearize_lanes`](super::linearize_lanes) writes each lane's d(v', u')/dtau_i
/// at the fixed state (one entry per tendon of the robot, zero for a tendon that does not
/// load the backbone there), and every tendon's routing point at each lane's site when they
/// are kept (else each lane evaluates the routings it needs, as the scalar code does).
pub(crate) struct TensionLanes<'t> {
    /// Per lane, one entry per tendon.
    pub(crate) out: [&'t mut [Vector6<f64>]; 4],
    /// Per lane, every tendon's routing point at its site.
    pub(crate) routing: Option<[&'t [RoutingPoint]; 4]>,
}

/// The lanes' quantities the tension part reads from the linearization: the state's
/// strains, the rates and M's factors.
pub(super) struct Solved<'a> {
    pub(super) v: &'a V3,
    pub(super) u: &'a V3,
    pub(super) x_v: &'a V3,
    pub(super) x_u: &'a V3,
    pub(super) factor: &'a Schur,
}

/// `tension_partials` and the solves of `linearize_tensions_inline` in lanes, given the
/// taut tendons' points the lanes' assembly kept (`taut`, in its order): false when a
/// lane leaves the scalar code's path (a slack tendon without a tangent, which the scalar
/// code reports; more taut tendons than kept), with `out` partly written.
#[inline(always)]
pub(super) fn tension_lanes(
    model: &Model,
    sites: [&Site; 4],
    segment_end: f64,
    taut: &[TendonLanes],
    solved: &Solved,
    tensions: TensionLanes,
) -> bool {
    let TensionLanes { mut out, routing } = tensions;
    let Solved { v, u, x_v, x_u, factor } = *solved;
    let length = model.robot.length();
    let zero = Vector6::zeros();
    for lane in out.iter_mut() {
        lane.fill(zero);
    }
    let tension = F4::splat(model.tension_factor);
    let mut kept = taut.iter();
    for (i, is_taut, tendon) in model.distributed_reaching_tendons(segment_end) {
        // A kept point per unit tension (`tension_partials`): k = f * (1 / |p|).
        let tp = if is_taut {
            let Some(tp) = kept.next() else {
                return false;
            };
            TendonLanes {
                k: tension * tp.inv_speed,
                ..*tp
            }
        } else {
            let point = |lane: usize| match routing {
                Some(points) => points[lane][i],
                None => tendon.routing.at(sites[lane].s, length),
            };
            let rp = [point(0), point(1), point(2), point(3)];
            match TendonLanes::new(F4::splat(model.tension_factor), [&rp[0], &rp[1], &rp[2], &rp[3]], v, u) {
                Some(tp) => tp,
                None => return false,
            }
        };
        let q = mat_vec(&tp.A(), &add(&sub(x_v, &cross(&tp.r, x_u)), &tp.c));
        let rq = cross(&tp.r, &q);
        let partial = [q[0], q[1], q[2], rq[0], rq[1], rq[2]];
        let mut rows = [partial];
        factor.solve_rows(&mut rows);
        let [solution] = rows;
        for (lane, o) in out.iter_mut().enumerate() {
            let d = lane6(&partial, lane);
            // The scalar code solves only the non-zero ones (a zero keeps its signs).
            o[i] = if d == zero { d } else { -lane6(&solution, lane) };
        }
    }
    true
}

/// One lane of a 6-vector of lanes (written out: `from_fn`'s closure stays a call compiled
/// for the baseline).
#[inline(always)]
fn lane6(l: &[F4; 6], lane: usize) -> Vector6<f64> {
    Vector6::new(
        l[0].lane(lane),
        l[1].lane(lane),
        l[2].lane(lane),
        l[3].lane(lane),
        l[4].lane(lane),
        l[5].lane(lane),
    )
}
