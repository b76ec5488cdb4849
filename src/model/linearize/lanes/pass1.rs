//! Pass 1 of the lane linearization ([`assemble`], `assemble` of the scalar code in lanes):
//! M, the right-hand side, M's factors and the rates x at four points. [`rates_lanes`] is
//! this pass alone, the lanes of [`super::super::rates`] (eq. 13's rates without their
//! linearization), for the order-6 residual's stages and Newton's residual of four
//! intervals at once (`collocation::order6`, `collocation::residual`).
#![allow(non_snake_case)]

use super::{
    M3, Schur, SiteLanes, TendonLanes, V3, Z3, Z33, add, add_m, cross, gather, gather3, hat_mul, mat_vec, mul, mul_hat,
    sub, tr_vec,
};
use crate::model::equations::{Model, Site};
use crate::model::linearize::CACHED_TENDONS;
use crate::simd::four;
use crate::simd::lanes::F4;
use nalgebra::{Matrix3, Vector3, Vector6};
use std::mem::MaybeUninit;

/// Pass 1's values at four points that pass 2 reads again (the scalar `Assembled` and
/// what the scalar code has at hand besides).
pub(in crate::model) struct Assembled {
    pub(in crate::model) site: SiteLanes,
    pub(in crate::model) v: V3,
    pub(in crate::model) u: V3,
    pub(in crate::model) n_b: V3,
    pub(in crate::model) m_b: V3,
    pub(in crate::model) f_b: V3,
    pub(in crate::model) l_b: V3,
    pub(in crate::model) factor: Schur,
    /// The rates (v', u').
    pub(in crate::model) x: [F4; 6],
    /// Tendons that load the backbone, the first `count` slots of the caller's `tendons`.
    pub(in crate::model) count: usize,
    /// Their indices in the robot (the same in every lane), the first `count` entries.
    pub(in crate::model) indices: [usize; CACHED_TENDONS],
}

/// The scalar `assemble` (without `low`) at four points (one site, state and model per
/// lane, the same `segment_end`), each lane's tendons written into `tendons`: None as soon
/// as a lane leaves the uniform path (the module docs of `lanes`). The lanes' models may
/// differ in their tensions alone (friction's tension profile: each point's own).
#[inline(always)]
pub(in crate::model) fn assemble(
    models: [&Model; 4],
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
    tendons: &mut [MaybeUninit<TendonLanes>; CACHED_TENDONS],
) -> Option<Assembled> {
    if sites.iter().any(|s| s.inextensible) {
        return None;
    }
    let site = SiteLanes::new(sites);
    let [t0, t1, t2, t3] = states;
    let R: M3 = gather3([t0.0, t1.0, t2.0, t3.0]);
    let v = gather([t0.1, t1.1, t2.1, t3.1]);
    let u = gather([t0.2, t1.2, t2.2, t3.2]);

    let dv = sub(&v, &site.v_star);
    let du = sub(&u, &site.u_star);
    let n_b = mul(&dv, &site.kse);
    let m_b = mul(&du, &site.kbt);
    let f_b = tr_vec(&R, &site.f_e);
    let l_b = tr_vec(&R, &site.l_e);
    let (mut A, mut G, mut H) = (Z33, Z33, Z33);
    let (mut a, mut b) = (Z3, Z3);
    let mut count = 0;
    let mut indices = [0; CACHED_TENDONS];
    let [s0, s1, s2, s3] = sites;
    let [m0, m1, m2, m3] = models;
    let mut iters = [
        m0.distributed_tendons(s0.s, segment_end),
        m1.distributed_tendons(s1.s, segment_end),
        m2.distributed_tendons(s2.s, segment_end),
        m3.distributed_tendons(s3.s, segment_end),
    ];
    loop {
        let next = [iters[0].next(), iters[1].next(), iters[2].next(), iters[3].next()];
        let [Some(t0), Some(t1), Some(t2), Some(t3)] = &next else {
            if next.iter().any(Option::is_some) {
                return None;
            }
            break;
        };
        // The same tendons in every lane (each at its lane's tension).
        if count == CACHED_TENDONS || [t1.0, t2.0, t3.0] != [t0.0; 3] {
            return None;
        }
        let tension = F4([t0.1, t1.1, t2.1, t3.1]);
        let tp = TendonLanes::new(tension, [&t0.2, &t1.2, &t2.2, &t3.2], &v, &u)?;
        let A_i = tp.A();
        let G_i = mul_hat(&A_i, &[-tp.r[0], -tp.r[1], -tp.r[2]]);
        add_m(&mut A, &A_i);
        add_m(&mut G, &G_i);
        add_m(&mut H, &hat_mul(&tp.r, &G_i));
        let a_i = mat_vec(&A_i, &tp.c);
        b = add(&b, &cross(&tp.r, &a_i));
        a = add(&a, &a_i);
        tendons[count].write(tp);
        indices[count] = t0.0;
        count += 1;
    }
    let rhs_v = sub(
        &sub(
            &sub(
                &sub(
                    &sub(&mul(&site.v_star_s, &site.kse), &cross(&u, &n_b)),
                    &mul(&dv, &site.kse_s),
                ),
                &f_b,
            ),
            &site.f_follower,
        ),
        &a,
    );
    let rhs_u = sub(
        &sub(
            &sub(
                &sub(
                    &sub(&mul(&site.u_star_s, &site.kbt), &cross(&u, &m_b)),
                    &mul(&du, &site.kbt_s),
                ),
                &cross(&v, &n_b),
            ),
            &l_b,
        ),
        &b,
    );
    // M = [A + D, G; G^T, H + C]: its diagonal blocks as the scalar code adds D and C.
    let (mut P, mut Q) = (A, H);
    for j in 0..3 {
        P[j][j] += site.kse[j];
        Q[j][j] += site.kbt[j];
    }
    let factor = Schur::new(&P, &G, &Q)?;
    let mut x = [[rhs_v[0], rhs_v[1], rhs_v[2], rhs_u[0], rhs_u[1], rhs_u[2]]];
    factor.solve_rows(&mut x);
    let [x] = x;
    Some(Assembled {
        site,
        v,
        u,
        n_b,
        m_b,
        f_b,
        l_b,
        factor,
        x,
        count,
        indices,
    })
}

/// [`super::super::rates`] at four points (one site and state per lane, the same
/// `segment_end`), each lane the scalar function's bits: None where a lane leaves the
/// uniform path (the module docs of `lanes`; evaluate the points with the scalar code
/// then, which gives the error or the fallback's values). Always inlined, for the AVX2
/// build of its caller.
#[inline(always)]
pub(crate) fn rates_lanes(
    model: &Model,
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
) -> Option<[Vector6<f64>; 4]> {
    let mut tendons = [const { MaybeUninit::<TendonLanes>::uninit() }; CACHED_TENDONS];
    let x = assemble([model; 4], sites, segment_end, states, &mut tendons)?.x;
    Some(
        four!(lane => Vector6::new(x[0].lane(lane), x[1].lane(lane), x[2].lane(lane), x[3].lane(lane), x[4].lane(lane), x[5].lane(lane))),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::linearize::rates;
    use crate::so3;

    /// Each lane of [`rates_lanes`] (compiled for the baseline here) gives the bits of the
    /// scalar [`rates`] (compiled for AVX2 where the processor has it: the same operations
    /// in the same order) at four sites and states of the prototype with four tendons
    /// pulled, in both builds; a Kirchhoff rod's sites are declined.
    #[test]
    fn lanes_give_the_scalar_rates() {
        let mut robot = crate::cases::prototype();
        for (i, tendon) in robot.tendons.iter_mut().enumerate().take(4) {
            tendon.set_tension(0.4 + 0.7 * i as f64);
        }
        let model = Model::new(&robot);
        let l = robot.length();
        let sites = [0.0, 0.13, 0.41, 0.77].map(|a| model.site(a * l));
        let R: [Matrix3<f64>; 4] = std::array::from_fn(|j| so3::exp(&(Vector3::new(0.3, -0.7, 1.1) * j as f64)));
        let v: [Vector3<f64>; 4] = std::array::from_fn(|j| Vector3::new(1e-4, -2e-4 * j as f64, 1.0 - 3e-5));
        let u: [Vector3<f64>; 4] = std::array::from_fn(|j| Vector3::new(3.0, -5.0 + j as f64, 2.0));
        let states = std::array::from_fn(|j| (&R[j], &v[j], &u[j]));
        let lanes = rates_lanes(&model, sites.each_ref(), l, states).unwrap();
        for j in 0..4 {
            let scalar = rates(&model, &sites[j], l, &R[j], &v[j], &u[j]).unwrap();
            assert!(scalar.amax() > 0.0);
            assert_eq!(lanes[j].map(f64::to_bits), scalar.map(f64::to_bits), "lane {j}");
        }
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        let model = Model::new(&robot);
        let sites = [0.0, 0.13, 0.41, 0.77].map(|a| model.site(a * l));
        assert!(rates_lanes(&model, sites.each_ref(), l, states).is_none());
    }
}
