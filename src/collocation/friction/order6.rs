//! The order-6 rows of a link with friction ([`interval_order6`]), for the error estimate
//! (docs/friction.md, "Collocation"): the Cash-Singhal formula on the state (y, z) of
//! [`super::interval`]. Its steps ([`Stages`]) are shared with the lanes, which evaluate
//! the inner stages of four links at once (`order6_lanes.rs`).
#![allow(non_snake_case)]

use super::super::residual::{Block, IntervalSites, QuarterSites, end_points, rhs_from_rates, scale_rows};
use super::super::unknowns::THETA;
use super::profile::{LinkScratch, Profile};
use crate::error::Result;
use crate::model::equations::Site;
use crate::model::friction::FrictionLinearization;
use crate::so3;
use crate::solution::State;
use nalgebra::{Matrix3, Vector3, Vector6};

/// Link k's order-6 rows with friction: backbone rows, capstan rows (one per slip) and the
/// rates at the two nodes.
pub(crate) type Order6 = (Block<f64>, Vec<f64>, Vector6<f64>, Vector6<f64>);

/// Link k's order-6 rows with friction (the Cash-Singhal formula of
/// [`super::super::residual::interval_order6`] on the state (y, z)): the 12 backbone rows,
/// the capstan rows psi6 (0 for slips not on the link), and the rates (v', u') at the two
/// nodes.
///
/// # Errors
/// A model breakdown at a stage.
#[allow(clippy::too_many_arguments)]
pub(crate) fn interval_order6(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    quarters: &QuarterSites,
    segment_end: f64,
    a: &State,
    b: &State,
) -> Result<Order6> {
    let mut st = Stages::new(profile, k, sites, segment_end, (a, b))?;
    let (s, w) = (&mut *st.scratch, st.w.as_deref());
    let [_, _, k_q, k_tq, _] = &mut s.turnings;
    let f_q = inner(
        profile,
        (&quarters.quarter, segment_end),
        &a.R,
        &st.y_q,
        (&s.z_q, w),
        k_q,
    )?;
    let f_tq = inner(
        profile,
        (&quarters.three_quarters, segment_end),
        &a.R,
        &st.y_tq,
        (&s.z_tq, w),
        k_tq,
    )?;
    let y_m = st.mid(&f_q, &f_tq);
    let (s, w) = (&mut *st.scratch, st.w.as_deref());
    let f_m = inner(
        profile,
        (&sites.mid, segment_end),
        &a.R,
        &y_m,
        (&s.zm, w),
        &mut s.turnings[4],
    )?;
    Ok(st.rows(profile, length, (sites, b), [&f_q, &f_tq, &f_m]))
}

/// One link's order-6 evaluation up to its inner stages: the end points y_0, y_1 and F
/// there (eq. 13 with friction at the nodes), the quarter stages' local states, and in the
/// link's scratch buffers the log tensions at the nodes and the quarter stages and the
/// nodes' turning rates. The inner stages' F and turning rates (`turnings[2..5]`) come from
/// the caller, one point at a time ([`interval_order6`]) or four links at once.
pub(super) struct Stages {
    k: usize,
    h: f64,
    /// The link's friction multipliers ([`Profile::multipliers`]).
    pub(super) w: Option<Vec<f64>>,
    /// The link's buffers, the profile's spare ones (given back by [`Stages::rows`]).
    pub(super) scratch: Box<LinkScratch>,
    y0: Block<f64>,
    y1: Block<f64>,
    f0: Block<f64>,
    f1: Block<f64>,
    /// y_1/4 and y_3/4.
    pub(super) y_q: Block<f64>,
    pub(super) y_tq: Block<f64>,
}

impl Stages {
    /// Link k's (`sites`, nodes `a` and `b`) end points, F at them (eq. 13 with friction at
    /// each node's own state, taken from the last pass that evaluated it there when it has
    /// the same inputs) and its quarter stages.
    ///
    /// # Errors
    /// A model breakdown at a node.
    #[inline(always)]
    pub(super) fn new(
        profile: &Profile,
        k: usize,
        sites: &IntervalSites,
        segment_end: f64,
        (a, b): (&State, &State),
    ) -> Result<Self> {
        let count = profile.count();
        let h = sites.end.s - sites.start.s;
        let mut scratch = profile.take_scratch();
        let s = &mut *scratch;
        s.za.clear();
        s.za.extend(profile.z.iter().map(|z| z[k]));
        s.zb.clear();
        s.zb.extend(profile.z.iter().map(|z| z[k + 1]));
        let (y0, y1) = end_points(a, b);
        let w = profile.multipliers(k);
        let [k0, k1, ..] = &mut s.turnings;
        let f0 = node(
            profile,
            (&sites.start, segment_end),
            &a.R,
            &y0,
            (k, a),
            (&s.za, w.as_deref()),
            k0,
        )?;
        let f1 = node(
            profile,
            (&sites.end, segment_end),
            &a.R,
            &y1,
            (k + 1, b),
            (&s.zb, w.as_deref()),
            k1,
        )?;
        let (za, zb, k0, k1) = (&s.za, &s.zb, &s.turnings[0], &s.turnings[1]);
        let combine = |c0: f64, c1: f64, d0: f64, d1: f64, z: &mut Vec<f64>| {
            let y = (y0 * c0 + y1 * c1) / 32.0 + (f0 * d0 + f1 * d1) * (h / 64.0);
            z.clear();
            z.extend((0..count).map(|j| (za[j] * c0 + zb[j] * c1) / 32.0 + (k0[j] * d0 + k1[j] * d1) * (h / 64.0)));
            y
        };
        let y_q = combine(27.0, 5.0, 9.0, -3.0, &mut s.z_q);
        let y_tq = combine(5.0, 27.0, 3.0, -9.0, &mut s.z_tq);
        Ok(Stages {
            k,
            h,
            w,
            scratch,
            y0,
            y1,
            f0,
            f1,
            y_q,
            y_tq,
        })
    }

    /// y_1/2 from F at the quarter stages, and its log tensions z_1/2 into the scratch's
    /// `zm` (from the turning rates at the quarter stages, `turnings[2]` and `[3]`).
    #[inline(always)]
    pub(super) fn mid(&mut self, f_q: &Block<f64>, f_tq: &Block<f64>) -> Block<f64> {
        let (y0, y1, f0, f1, h) = (&self.y0, &self.y1, &self.f0, &self.f1, self.h);
        let y_m = (y0 + y1) * 0.5 + ((f1 - f0) * (5.0 / 24.0) + (f_q - f_tq) * (2.0 / 3.0)) * h;
        let s = &mut *self.scratch;
        let [k0, k1, k_q, k_tq, _] = &s.turnings;
        let (za, zb) = (&s.za, &s.zb);
        s.zm.clear();
        s.zm.extend(
            (0..za.len()).map(|j| {
                0.5 * (za[j] + zb[j]) + ((k1[j] - k0[j]) * (5.0 / 24.0) + (k_q[j] - k_tq[j]) * (2.0 / 3.0)) * h
            }),
        );
        y_m
    }

    /// The link's order-6 rows from F at its inner stages `[f_q, f_tq, f_m]` (their turning
    /// rates in the scratch's `turnings[2..5]`), `sites` its sites and `b` its end node;
    /// its capstan rows kept in the profile for the estimate and its buffers given back.
    #[inline(always)]
    pub(super) fn rows(
        self,
        profile: &Profile,
        length: f64,
        (sites, b): (&IntervalSites, &State),
        f: [&Block<f64>; 3],
    ) -> Order6 {
        let (k, h) = (self.k, self.h);
        let s = &*self.scratch;
        let (za, zb) = (&s.za, &s.zb);
        let [k0, k1, k_q, k_tq, k_m] = &s.turnings;
        let [f_q, f_tq, f_m] = f;
        let (y0, y1, f0, f1) = (&self.y0, &self.y1, &self.f0, &self.f1);
        let quadrature = ((f0 + f1) * 7.0 + (f_q + f_tq) * 32.0 + f_m * 12.0) * (h / 90.0);
        let psi: Vec<f64> = (0..za.len())
            .map(|j| {
                if profile.on_link(j, k) && profile.sticks(j, k) {
                    // The stick row is algebraic: the same at any order.
                    zb[j] - (profile.stuck_tension(j, k + 1, &sites.end, b, length).0 / profile.base[j]).ln()
                } else if profile.on_link(j, k) {
                    zb[j] - za[j] - (7.0 * (k0[j] + k1[j]) + 32.0 * (k_q[j] + k_tq[j]) + 12.0 * k_m[j]) * (h / 90.0)
                } else {
                    0.0
                }
            })
            .collect();
        let rates = |f: &Block<f64>| f.fixed_rows::<6>(6).into_owned();
        profile.order6.borrow_mut()[k].clone_from(&psi);
        let rows = scale_rows(y1 - y0 - quadrature, length);
        let (start, end) = (rates(f0), rates(f1));
        profile.give_scratch(self.scratch);
        (rows, psi, start, end)
    }
}

/// The frame and strains (R = R_k exp(theta), v, u) of a link's local state `y`, the link
/// starting at frame `Rk`.
#[inline(always)]
pub(super) fn stage_state(Rk: &Matrix3<f64>, y: &Block<f64>) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
    let (v, u): (Vector3<f64>, Vector3<f64>) = (y.fixed_rows::<3>(6).into(), y.fixed_rows::<3>(9).into());
    (Rk * so3::exp(&theta), v, u)
}

/// F at a stage (`site`, frame `R` of its local state `y`) from eq. 13 with friction's
/// evaluation `lin` there, its turning rates into `turning`. p' = R v with v the strain of
/// the coordinate (v* on a Kirchhoff rod, whose coordinate carries the force), as in the
/// order-4 rows.
#[inline(always)]
pub(super) fn stage_rhs(
    site: &Site,
    R: &Matrix3<f64>,
    y: &Block<f64>,
    lin: &FrictionLinearization,
    turning: &mut Vec<f64>,
) -> Block<f64> {
    turning.clone_from(&lin.turning);
    rhs_from_rates(site, R, y, &lin.lin.rates)
}

/// F and the turning rates (into `turning`) at an inner stage of a link starting at frame
/// `Rk`: its site and segment end, local state `y`, log tensions and multipliers `(z, w)`.
///
/// # Errors
/// A model breakdown there.
#[inline(always)]
pub(super) fn inner(
    profile: &Profile,
    (site, segment_end): (&Site, f64),
    Rk: &Matrix3<f64>,
    y: &Block<f64>,
    (z, w): (&[f64], Option<&[f64]>),
    turning: &mut Vec<f64>,
) -> Result<Block<f64>> {
    let (R, v, u) = stage_state(Rk, y);
    let lin = profile.point(site, segment_end, &R, (&v, &u), z, w, false)?;
    let f = stage_rhs(site, &R, y, &lin, turning);
    profile.give(lin);
    Ok(f)
}

/// [`inner`] at a node (its index and state `(n, state)`, local state `y`), eq. 13 with
/// friction at the node's own state, taken from the last pass that evaluated it there when
/// it has the same inputs ([`Profile::node_rates`]).
///
/// # Errors
/// A model breakdown there.
#[inline(always)]
fn node(
    profile: &Profile,
    (site, segment_end): (&Site, f64),
    Rk: &Matrix3<f64>,
    y: &Block<f64>,
    (n, state): (usize, &State),
    (z, w): (&[f64], Option<&[f64]>),
    turning: &mut Vec<f64>,
) -> Result<Block<f64>> {
    let (R, _, _) = stage_state(Rk, y);
    let rates = match profile.node_rates(n, segment_end, state, (z, w), turning) {
        Some(rates) => rates,
        None => {
            let lin = profile.point(site, segment_end, &state.R, (&state.v, &state.u), z, w, false)?;
            turning.clone_from(&lin.turning);
            let rates = lin.lin.rates;
            profile.give(lin);
            rates
        }
    };
    Ok(rhs_from_rates(site, &R, y, &rates))
}
