//! The interval block of four consecutive intervals at once ([`interval_jacobians4`]):
//! eq. 13's linearizations at their four end nodes, then at their four midpoints, each in
//! one pass of four f64 lanes ([`linearize_lanes`], one interval per lane), the rest of each
//! interval's block (the chain rule through the scheme, already wide within one interval)
//! as the scalar kernel forms it. For a Jacobian that forms the tension columns
//! ([`GroupTensions`]), the lanes also give each point's derivatives in every tension, and
//! each interval's rows are written by the scalar kernel's own tail (`tension_rows`).
//!
//! The 32 intervals of a Jacobian are independent once the node states are known: interval
//! k's start linearization is interval k-1's end one, and its midpoint's state needs only
//! its own two nodes. Eq. 13's linearization is short dependent chains on 3-vectors and 3x3
//! blocks, which wide registers do not shorten within one point but do across four. Each
//! lane performs the scalar kernel's operations in its order, so every lane gives the
//! scalar kernel's bits (the tests compare them); where a lane leaves the common path
//! (`linearize_lanes`' module docs) the four intervals go to the scalar kernel.
#![allow(non_snake_case)]

use super::interval_jacobian::{interval_jacobian_tensions, midpoint_product, tension_rows};
use super::residual::{
    Block, EndColumns, IntervalSites, IntervalTensions, PointFrame, end_points, rhs_linearized_inline, scale_rows,
};
use super::unknowns::{P, THETA, U, V};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::model::linearize::{Linearization, TensionLanes, linearize_keeping, linearize_lanes, linearize_tensions};
use crate::model::routing::RoutingPoint;
use crate::solution::State;
use nalgebra::{Vector3, Vector6};

/// Entries of one interval's row-major 12 x 24 block.
const BLOCK: usize = 12 * 24;

/// The buffers of four intervals' tension columns (what [`IntervalTensions`] is for one
/// interval; `TensionSink::group` lends them): d(v', u')/dtau_i at the first interval's
/// start node (read when its linearization is given, else written), at the four end nodes
/// and the four midpoints, the midpoint's strain motion (one entry per tendon in each), the
/// columns the rows go into (`n` rows each, interval j's from `rows[j]` on) and every
/// tendon's routing point at each interval's end node and midpoint when they are kept.
pub(super) struct GroupTensions<'t> {
    pub(super) start: &'t mut [Vector6<f64>],
    pub(super) ends: [&'t mut [Vector6<f64>]; 4],
    pub(super) mids: [&'t mut [Vector6<f64>]; 4],
    pub(super) dy_mid: &'t mut [Vector6<f64>],
    pub(super) columns: &'t mut [f64],
    pub(super) n: usize,
    pub(super) rows: [usize; 4],
    pub(super) routing: Option<[[&'t [RoutingPoint]; 2]; 4]>,
}

impl GroupTensions<'_> {
    /// Interval j's buffers as the one-interval kernel takes them (its start node's
    /// derivatives are interval j - 1's end ones).
    #[inline(always)]
    fn interval(&mut self, j: usize) -> IntervalTensions<'_> {
        let (before, from) = self.ends.split_at_mut(j);
        IntervalTensions {
            start: match before.last_mut() {
                Some(end) => end,
                None => &mut *self.start,
            },
            end: &mut *from[0],
            mid: &mut *self.mids[j],
            dy_mid: &mut *self.dy_mid,
            columns: &mut *self.columns,
            n: self.n,
            row: self.rows[j],
            routing: self.routing.map(|r| r[j]),
        }
    }

    /// The lanes' buffers at the end nodes (`at` 0) or the midpoints (`at` 1).
    #[inline(always)]
    fn lanes(&mut self, at: usize) -> TensionLanes<'_> {
        let [a, b, c, d] = if at == 0 { &mut self.ends } else { &mut self.mids };
        TensionLanes {
            out: [&mut **a, &mut **b, &mut **c, &mut **d],
            routing: self.routing.map(|r| [r[0][at], r[1][at], r[2][at], r[3][at]]),
        }
    }
}

/// The blocks of the four intervals between the nodes `x[0..5]` (`sites[j]` interval j's,
/// all in one segment ending at `segment_end`) into `jac` (four 12 x 24 blocks in turn),
/// the linearizations at their end nodes into `ends`, and for each interval its residual
/// and the rates at its start node: what `interval_jacobian_into` gives for each (with
/// `as_residual`, `interval_jacobian_as_residual`), bit for bit, with `start` the
/// linearization at `x[0]` if known (the interval before's end one; else evaluated here).
///
/// With `tensions`, also each interval's rows of the tension columns' right-hand sides, as
/// `interval_jacobian_tensions` writes them with [`GroupTensions::interval`]'s buffers.
///
/// With AVX2 and FMA (checked at run time, as `avx2_fma!` checks) the linearizations run in
/// lanes; else, or where a lane leaves the common path, the four intervals are evaluated
/// one by one by the scalar kernel.
///
/// # Errors
/// As `interval_jacobian_into` (from the scalar kernel, which the lanes hand such
/// intervals to).
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_jacobians4(
    model: &Model,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    start: Option<&Linearization>,
    jac: &mut [f64],
    as_residual: bool,
    ends: &mut [Linearization; 4],
    mut tensions: Option<GroupTensions>,
) -> Result<[(Block<f64>, Vector6<f64>); 4]> {
    debug_assert!(x.len() == 5 && jac.len() == 4 * BLOCK);
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2_fma_detected() {
        // SAFETY: the processor has the features `lanes_avx2` is compiled for, as
        // `avx2_fma_detected()` has just said.
        let t = tensions.as_mut();
        let lanes = unsafe { lanes_avx2(model, sites, segment_end, x, start, jac, as_residual, ends, t) };
        if let Some(out) = lanes {
            return Ok(out);
        }
    }
    let mut out = [(Block::zeros(), Vector6::zeros()); 4];
    let mut start = start.copied();
    for (j, (block, end)) in jac.chunks_exact_mut(BLOCK).zip(ends.iter_mut()).enumerate() {
        let nodes = (&x[j], &x[j + 1]);
        let (s, t) = (start.as_ref(), tensions.as_mut().map(|t| t.interval(j)));
        out[j] = interval_jacobian_tensions(model, sites[j], segment_end, nodes, s, block, t, as_residual, end)?;
        start = Some(*end);
    }
    Ok(out)
}

/// [`lanes_kernel`] compiled with AVX2 and FMA: one `vaddpd`/`vmulpd` per lane operation.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
fn lanes_avx2(
    model: &Model,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    start: Option<&Linearization>,
    jac: &mut [f64],
    as_residual: bool,
    ends: &mut [Linearization; 4],
    tensions: Option<&mut GroupTensions>,
) -> Option<[(Block<f64>, Vector6<f64>); 4]> {
    lanes_kernel(model, sites, segment_end, x, start, jac, as_residual, ends, tensions)
}

/// One interval's values up to its midpoint state, as the scalar kernel forms them: what
/// the midpoint's linearization needs and what the rest of the block reads again.
struct Ahead {
    h: f64,
    y0: Block<f64>,
    y1: Block<f64>,
    frame1: PointFrame,
    ym: Block<f64>,
    frame_m: PointFrame,
}

/// F at a point of an interval, the `f` of [`rhs_linearized_inline`] with the same
/// operations: (R v, J_r^-1 u, or u at the start node, the rates).
#[inline(always)]
fn point_f(site: &Site, lin: &Linearization, y: &Block<f64>, frame: &PointFrame, start: bool) -> Block<f64> {
    let v = site.strain(&y.fixed_rows::<3>(V).into());
    let u: Vector3<f64> = y.fixed_rows::<3>(U).into();
    let mut f = Block::zeros();
    f.fixed_rows_mut::<3>(P).copy_from(&(frame.R * v));
    if start {
        f.fixed_rows_mut::<3>(THETA).copy_from(&u);
    } else {
        f.fixed_rows_mut::<3>(THETA).copy_from(&(frame.Jri * u));
    }
    f.fixed_rows_mut::<6>(V).copy_from(&lin.rates);
    f
}

/// Interval j's [`Ahead`] (`lin0`, `lin1` its end nodes' linearizations; `as_residual` as
/// in [`interval_jacobians4`]).
#[inline(always)]
fn ahead(
    site: &IntervalSites,
    (a, b): (&State, &State),
    (lin0, lin1): (&Linearization, &Linearization),
    as_residual: bool,
) -> Ahead {
    let h = site.end.s - site.start.s;
    let (y0, y1) = end_points(a, b);
    let theta1: Vector3<f64> = y1.fixed_rows::<3>(THETA).into();
    let frame1 = PointFrame::new(&a.R, &theta1);
    let f0 = point_f(&site.start, lin0, &y0, &PointFrame::start(&a.R), true);
    let mut f1 = point_f(&site.end, lin1, &y1, &frame1, false);
    if as_residual {
        f1.fixed_rows_mut::<3>(P).copy_from(&(b.R * site.end.strain(&b.v)));
    }
    let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
    let frame_m = PointFrame::new(&a.R, &ym.fixed_rows::<3>(THETA).into());
    Ahead {
        h,
        y0,
        y1,
        frame1,
        ym,
        frame_m,
    }
}

/// [`interval_jacobians4`] with the linearizations in lanes; None (nothing valid written)
/// where a lane leaves their common path or the start node's linearization fails.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lanes_kernel(
    model: &Model,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    start: Option<&Linearization>,
    jac: &mut [f64],
    as_residual: bool,
    ends: &mut [Linearization; 4],
    mut tensions: Option<&mut GroupTensions>,
) -> Option<[(Block<f64>, Vector6<f64>); 4]> {
    let length = model.robot.length();
    let computed;
    let start = match start {
        Some(l) => l,
        None => {
            let (a, site) = (&x[0], &sites[0].start);
            computed = match tensions.as_deref_mut() {
                Some(t) => linearize_tensions(model, site, segment_end, (&a.R, &a.v, &a.u), t.start),
                None => linearize_keeping(model, site, segment_end, &a.R, &a.v, &a.u, None),
            }
            .ok()?;
            &computed
        }
    };
    let [s0, s1, s2, s3] = sites;
    let end_states = [
        (&x[1].R, &x[1].v, &x[1].u),
        (&x[2].R, &x[2].v, &x[2].u),
        (&x[3].R, &x[3].v, &x[3].u),
        (&x[4].R, &x[4].v, &x[4].u),
    ];
    if !linearize_lanes(
        model,
        [&s0.end, &s1.end, &s2.end, &s3.end],
        segment_end,
        end_states,
        ends,
        tensions.as_deref_mut().map(|t| t.lanes(0)),
    ) {
        return None;
    }
    let ahead = [
        ahead(s0, (&x[0], &x[1]), (start, &ends[0]), as_residual),
        ahead(s1, (&x[1], &x[2]), (&ends[0], &ends[1]), as_residual),
        ahead(s2, (&x[2], &x[3]), (&ends[1], &ends[2]), as_residual),
        ahead(s3, (&x[3], &x[4]), (&ends[2], &ends[3]), as_residual),
    ];
    let mut mids = [Linearization::zeros(); 4];
    let mid_v = |j: usize| -> (Vector3<f64>, Vector3<f64>) {
        (
            ahead[j].ym.fixed_rows::<3>(V).into(),
            ahead[j].ym.fixed_rows::<3>(U).into(),
        )
    };
    let [(v0, u0), (v1, u1), (v2, u2), (v3, u3)] = [mid_v(0), mid_v(1), mid_v(2), mid_v(3)];
    let mid_states = [
        (&ahead[0].frame_m.R, &v0, &u0),
        (&ahead[1].frame_m.R, &v1, &u1),
        (&ahead[2].frame_m.R, &v2, &u2),
        (&ahead[3].frame_m.R, &v3, &u3),
    ];
    if !linearize_lanes(
        model,
        [&s0.mid, &s1.mid, &s2.mid, &s3.mid],
        segment_end,
        mid_states,
        &mut mids,
        tensions.as_deref_mut().map(|t| t.lanes(1)),
    ) {
        return None;
    }
    let mut out = [(Block::zeros(), Vector6::zeros()); 4];
    let mut columns = EndColumns::zeros();
    for (j, (block, p)) in jac.chunks_exact_mut(BLOCK).zip(&ahead).enumerate() {
        let (site, a, b) = (sites[j], &x[j], &x[j + 1]);
        let lin0 = if j == 0 { start } else { &ends[j - 1] };
        let p0 = rhs_linearized_inline(&site.start, lin0, &a.R, &p.y0, &PointFrame::start(&a.R));
        let mut p1 = rhs_linearized_inline(&site.end, &ends[j], &a.R, &p.y1, &p.frame1);
        if as_residual {
            p1.f.fixed_rows_mut::<3>(P).copy_from(&(b.R * site.end.strain(&b.v)));
        }
        let pm = rhs_linearized_inline(&site.mid, &mids[j], &a.R, &p.ym, &p.frame_m);
        let residual = scale_rows(p.y1 - p.y0 - (p0.f + pm.f * 4.0 + p1.f) * (p.h / 6.0), length);
        out[j] = (residual, lin0.rates);
        columns.fill(&p0, &p1, &p.frame1, length);
        let dFm = midpoint_product(&pm, &columns.midpoint(p.h));
        columns.write(&dFm, p.h, length, block);
        if let Some(t) = tensions.as_deref_mut() {
            tension_rows(
                t.interval(j),
                p.h,
                length,
                &mids[j],
                (site.mid.inextensible, &p.frame_m),
            );
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::system::System;
    use crate::mesh::{Mesh, guess::rigid_estimate};
    use crate::model::linearize::linearize;
    use crate::{Robot, so3};

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Compares the four-interval kernels (the lanes compiled for the baseline, the lanes
    /// compiled for AVX2 where the processor has it, and the dispatched
    /// [`interval_jacobians4`]) with the scalar kernel on every run of four intervals of one
    /// segment of `robot` on `intervals` uniform intervals at the states `x` (the rigid
    /// estimate when None): block, residual, start rates and end linearizations bit for bit,
    /// with and without a given start, as the Jacobian and as Newton's residual. Returns how
    /// many runs the lanes took (not handed to the scalar kernel).
    fn compare(robot: &Robot, intervals: usize, turn: f64) -> usize {
        let model = Model::new(robot);
        let mesh = Mesh::uniform(robot, intervals).unwrap();
        let mut x = rigid_estimate(&model, &mesh.nodes);
        // Turn each node about a fixed axis by `turn` rad more than the one before: angles
        // theta_1 beyond the exponential's series switch (0.5 rad) for large turns.
        for (k, state) in x.iter_mut().enumerate() {
            state.R *= so3::exp(&(Vector3::new(0.3, -0.5, 0.8) * (turn * k as f64)));
        }
        let system = System::new(model.clone(), mesh.clone());
        let mut taken = 0;
        for k in 0..mesh.nodes.len().saturating_sub(4) {
            let Some(sites) = (0..4).map(|j| system.interval_sites(k + j)).collect::<Option<Vec<_>>>() else {
                continue;
            };
            let seg = mesh.nodes[k].segment_end;
            if mesh.nodes[k..k + 4].iter().any(|n| n.segment_end != seg) {
                continue;
            }
            let sites: [&IntervalSites; 4] = sites.try_into().unwrap();
            let given = linearize(&model, &sites[0].start, seg, &x[k].R, &x[k].v, &x[k].u).unwrap();
            for (start, as_residual) in [(None, false), (Some(&given), false), (Some(&given), true), (None, true)] {
                let mut scalar_jac = vec![0.0; 4 * BLOCK];
                let mut scalar_ends = [Linearization::zeros(); 4];
                let mut scalar = Vec::new();
                let mut s = start.copied();
                for (j, (block, end)) in scalar_jac
                    .chunks_exact_mut(BLOCK)
                    .zip(scalar_ends.iter_mut())
                    .enumerate()
                {
                    let nodes = (&x[k + j], &x[k + j + 1]);
                    let out = interval_jacobian_tensions(
                        &model,
                        sites[j],
                        seg,
                        nodes,
                        s.as_ref(),
                        block,
                        None,
                        as_residual,
                        end,
                    )
                    .unwrap();
                    scalar.push(out);
                    s = Some(*end);
                }
                let check = |jac: &[f64], ends: &[Linearization; 4], out: &[(Block<f64>, Vector6<f64>); 4]| {
                    assert_eq!(bits(jac), bits(&scalar_jac), "blocks at {k}");
                    for j in 0..4 {
                        assert_eq!(
                            bits(out[j].0.as_slice()),
                            bits(scalar[j].0.as_slice()),
                            "residual {}",
                            k + j
                        );
                        assert_eq!(
                            bits(out[j].1.as_slice()),
                            bits(scalar[j].1.as_slice()),
                            "rates {}",
                            k + j
                        );
                        let (a, b) = (&ends[j], &scalar_ends[j]);
                        assert_eq!(bits(a.rates.as_slice()), bits(b.rates.as_slice()));
                        assert_eq!(bits(a.d_strains.as_slice()), bits(b.d_strains.as_slice()));
                        assert_eq!(bits(a.d_rotation.as_slice()), bits(b.d_rotation.as_slice()));
                    }
                };
                let nodes = &x[k..k + 5];
                let (mut jac, mut ends) = (vec![0.0; 4 * BLOCK], [Linearization::zeros(); 4]);
                let out = interval_jacobians4(&model, sites, seg, nodes, start, &mut jac, as_residual, &mut ends, None)
                    .unwrap();
                check(&jac, &ends, &out);
                let (mut jac, mut ends) = (vec![0.0; 4 * BLOCK], [Linearization::zeros(); 4]);
                if let Some(out) =
                    lanes_kernel(&model, sites, seg, nodes, start, &mut jac, as_residual, &mut ends, None)
                {
                    check(&jac, &ends, &out);
                    taken += 1;
                }
                #[cfg(target_arch = "x86_64")]
                if crate::simd::avx2_fma_detected() {
                    let (mut jac, mut ends) = (vec![0.0; 4 * BLOCK], [Linearization::zeros(); 4]);
                    // SAFETY: the processor has AVX2 and FMA.
                    let lanes =
                        unsafe { lanes_avx2(&model, sites, seg, nodes, start, &mut jac, as_residual, &mut ends, None) };
                    if let Some(out) = lanes {
                        check(&jac, &ends, &out);
                    }
                }
            }
        }
        taken
    }

    /// Every lane gives the scalar kernel's bits on the prototype with four tendons pulled
    /// (small angles on 32 intervals, angles past the exponential's series switch), on
    /// case H's helical tendon with its tip force, and on a tendon that ends mid-rod (a
    /// segment jump: runs of four within each segment); the lanes take every run there.
    #[test]
    fn lanes_give_the_scalar_bits() {
        let prototype = crate::collocation::test_support::pulled_prototype();
        assert_eq!(compare(&prototype, 32, 0.0), 4 * 29);
        assert_eq!(compare(&prototype, 12, 0.7), 4 * 9);
        assert_eq!(compare(&crate::cases::case_h(), 16, 0.0), 4 * 13);
        let mut ending = crate::cases::case_s();
        ending.tendons[1].set_tension(1.5);
        let half = 0.5 * ending.length();
        ending = ending.with_tendon(
            crate::model::tendon::Tendon::new(crate::model::routing::Routing::straight(0.0, 0.008), 2.0)
                .ending_at(half),
        );
        assert!(compare(&ending, 16, 0.01) > 0);
    }

    /// Compares the four-interval kernels with the tension columns (as `compare`, with and
    /// without the routing points kept) with the scalar kernel given the buffers as
    /// `TensionSink::interval` lends them, on every run of four intervals of one segment:
    /// the blocks, residuals and end linearizations, the rows written into the columns, and
    /// the derivatives at every end node and midpoint, bit for bit. Returns how many runs
    /// the lanes took.
    fn compare_tensions(robot: &Robot, intervals: usize, turn: f64) -> usize {
        let model = Model::new(robot);
        let mesh = Mesh::uniform(robot, intervals).unwrap();
        let mut x = rigid_estimate(&model, &mesh.nodes);
        for (k, state) in x.iter_mut().enumerate() {
            state.R *= so3::exp(&(Vector3::new(0.3, -0.5, 0.8) * (turn * k as f64)));
        }
        let system = System::new(model.clone(), mesh.clone());
        let (width, length) = (robot.tendons.len(), robot.length());
        let (n, rows) = (48, [0, 12, 24, 36]);
        let at = |s: f64| {
            robot
                .tendons
                .iter()
                .map(|t| t.routing.at(s, length))
                .collect::<Vec<_>>()
        };
        let mut taken = 0;
        for k in 0..mesh.nodes.len().saturating_sub(4) {
            let Some(sites) = (0..4).map(|j| system.interval_sites(k + j)).collect::<Option<Vec<_>>>() else {
                continue;
            };
            let seg = mesh.nodes[k].segment_end;
            if mesh.nodes[k..k + 4].iter().any(|n| n.segment_end != seg) {
                continue;
            }
            let sites: [&IntervalSites; 4] = sites.try_into().unwrap();
            let points: Vec<[Vec<_>; 2]> = sites.iter().map(|s| [at(s.end.s), at(s.mid.s)]).collect();
            let a = &x[k];
            let mut given_t = vec![Vector6::zeros(); width];
            let given = linearize_tensions(&model, &sites[0].start, seg, (&a.R, &a.v, &a.u), &mut given_t).unwrap();
            for ((start, as_residual), kept) in
                [(None, false), (Some(&given), false), (Some(&given), true), (None, true)]
                    .into_iter()
                    .zip([true, false, true, false])
            {
                let routing = |j: usize| kept.then(|| [&points[j][0][..], &points[j][1][..]]);
                // The scalar kernel with the sink's buffers: start, end, mid, dy_mid.
                let mut rates: [Vec<Vector6<f64>>; 4] = std::array::from_fn(|_| vec![Vector6::zeros(); width]);
                rates[0].copy_from_slice(&given_t);
                let (mut scalar_columns, mut scalar_jac) = (vec![f64::NAN; n * width], vec![0.0; 4 * BLOCK]);
                let (mut scalar_ends, mut scalar_at, mut s) = ([Linearization::zeros(); 4], Vec::new(), start.copied());
                for (j, (block, end)) in scalar_jac
                    .chunks_exact_mut(BLOCK)
                    .zip(scalar_ends.iter_mut())
                    .enumerate()
                {
                    if j > 0 {
                        rates.swap(0, 1);
                    }
                    let [t_start, t_end, mid, dy_mid] = &mut rates;
                    let t = IntervalTensions {
                        start: t_start,
                        end: t_end,
                        mid,
                        dy_mid,
                        columns: &mut scalar_columns,
                        n,
                        row: rows[j],
                        routing: routing(j),
                    };
                    let nodes = (&x[k + j], &x[k + j + 1]);
                    interval_jacobian_tensions(
                        &model,
                        sites[j],
                        seg,
                        nodes,
                        s.as_ref(),
                        block,
                        Some(t),
                        as_residual,
                        end,
                    )
                    .unwrap();
                    s = Some(*end);
                    scalar_at.push([rates[1].clone(), rates[2].clone()]);
                }
                let nodes = &x[k..k + 5];
                let run = |lanes: bool| {
                    let mut buffers: Vec<Vec<Vector6<f64>>> = vec![vec![Vector6::zeros(); width]; 10];
                    buffers[0].copy_from_slice(&given_t);
                    let [b0, e0, e1, e2, e3, m0, m1, m2, m3, dy] = &mut buffers[..] else {
                        unreachable!()
                    };
                    let (mut columns, mut jac) = (vec![f64::NAN; n * width], vec![0.0; 4 * BLOCK]);
                    let mut ends = [Linearization::zeros(); 4];
                    let mut group = GroupTensions {
                        start: b0,
                        ends: [e0, e1, e2, e3],
                        mids: [m0, m1, m2, m3],
                        dy_mid: dy,
                        columns: &mut columns,
                        n,
                        rows,
                        routing: kept.then(|| std::array::from_fn(|j| [&points[j][0][..], &points[j][1][..]])),
                    };
                    let took = if lanes {
                        lanes_kernel(
                            &model,
                            sites,
                            seg,
                            nodes,
                            start,
                            &mut jac,
                            as_residual,
                            &mut ends,
                            Some(&mut group),
                        )
                        .is_some()
                    } else {
                        interval_jacobians4(
                            &model,
                            sites,
                            seg,
                            nodes,
                            start,
                            &mut jac,
                            as_residual,
                            &mut ends,
                            Some(group),
                        )
                        .unwrap();
                        true
                    };
                    if took {
                        assert_eq!(bits(&jac), bits(&scalar_jac), "blocks at {k}");
                        assert_eq!(bits(&columns), bits(&scalar_columns), "tension rows at {k}");
                        let flat =
                            |v: &[Vector6<f64>]| bits(&v.iter().flat_map(|d| d.iter().copied()).collect::<Vec<_>>());
                        for j in 0..4 {
                            assert_eq!(
                                bits(ends[j].d_strains.as_slice()),
                                bits(scalar_ends[j].d_strains.as_slice())
                            );
                            assert_eq!(flat(&buffers[1 + j]), flat(&scalar_at[j][0]), "end {}", k + j);
                            assert_eq!(flat(&buffers[5 + j]), flat(&scalar_at[j][1]), "midpoint {}", k + j);
                        }
                    }
                    took
                };
                run(false);
                if run(true) {
                    taken += 1;
                }
            }
        }
        taken
    }

    /// The tension columns' rows and derivatives of every lane are the scalar kernel's
    /// bits: on the prototype with four tendons pulled and its helical tendon slack (small
    /// angles, angles past the exponential's series switch), on case S (one straight tendon
    /// taut, the others slack) and case H (the helical tendon taut, with its tip force); the
    /// lanes take every run there.
    #[test]
    fn lanes_give_the_scalar_bits_of_the_tension_columns() {
        let prototype = crate::collocation::test_support::pulled_prototype();
        assert_eq!(compare_tensions(&prototype, 32, 0.0), 4 * 29);
        assert_eq!(compare_tensions(&prototype, 12, 0.7), 4 * 9);
        assert_eq!(compare_tensions(&crate::cases::case_s(), 16, 0.01), 4 * 13);
        assert_eq!(compare_tensions(&crate::cases::case_h(), 16, 0.0), 4 * 13);
    }

    /// A Kirchhoff rod leaves the lanes' path: the four intervals go to the scalar kernel,
    /// with its bits.
    #[test]
    fn a_kirchhoff_rod_goes_to_the_scalar_kernel() {
        let mut robot = crate::collocation::test_support::pulled_prototype();
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        assert_eq!(compare(&robot, 8, 0.0), 0);
    }
}
