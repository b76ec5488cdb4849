//! The order-6 rows of a link with friction ([`interval_order6`]), for the error estimate
//! (docs/friction.md, "Collocation"): the Cash-Singhal formula on the state (y, z) of
//! [`super::interval`].
#![allow(non_snake_case)]

use super::super::residual::{Block, IntervalSites, QuarterSites, end_points, rhs_from_rates, scale_rows};
use super::super::unknowns::THETA;
use super::profile::{LinkScratch, Profile};
use crate::error::Result;
use crate::model::equations::Site;
use crate::so3;
use crate::solution::State;
use nalgebra::{Vector3, Vector6};

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
    let count = profile.count();
    let h = sites.end.s - sites.start.s;
    // The link's buffers, the profile's spare ones (given back at the end).
    let mut scratch = profile.take_scratch();
    let LinkScratch {
        za,
        zb,
        zm: z_m,
        z_q,
        z_tq,
        turnings: [k0, k1, k_q, k_tq, k_m],
        ..
    } = &mut *scratch;
    za.clear();
    za.extend(profile.z.iter().map(|z| z[k]));
    zb.clear();
    zb.extend(profile.z.iter().map(|z| z[k + 1]));
    let (y0, y1) = end_points(a, b);
    let w = profile.multipliers(k);
    let w = w.as_deref();
    // F and kappa~ (into `turning`) at a local state (y, z) of the interval; at a node
    // (`node`: its index and state), eq. 13 with friction at the node's own state, taken
    // from the last pass that evaluated it there when it has the same inputs.
    let stage = |site: &Site, y: &Block<f64>, z: &[f64], node: Option<(usize, &State)>, turning: &mut Vec<f64>| {
        let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
        let (v, u): (Vector3<f64>, Vector3<f64>) = (y.fixed_rows::<3>(6).into(), y.fixed_rows::<3>(9).into());
        let R = a.R * so3::exp(&theta);
        let rates = match node {
            Some((n, state)) => match profile.node_rates(n, segment_end, state, (z, w), turning) {
                Some(rates) => rates,
                None => {
                    let lin = profile.point(site, segment_end, &state.R, (&state.v, &state.u), z, w, false)?;
                    turning.clone_from(&lin.turning);
                    let rates = lin.lin.rates;
                    profile.give(lin);
                    rates
                }
            },
            None => {
                let lin = profile.point(site, segment_end, &R, (&v, &u), z, w, false)?;
                turning.clone_from(&lin.turning);
                let rates = lin.lin.rates;
                profile.give(lin);
                rates
            }
        };
        // p' = R v with v the strain of the coordinate (v* on a Kirchhoff rod, whose
        // coordinate carries the force), as in the order-4 rows.
        Ok::<_, crate::Error>(rhs_from_rates(site, &R, y, &rates))
    };
    let f0 = stage(&sites.start, &y0, za, Some((k, a)), k0)?;
    let f1 = stage(&sites.end, &y1, zb, Some((k + 1, b)), k1)?;
    let (k0, k1) = (&*k0, &*k1);
    let combine = |c0: f64, c1: f64, d0: f64, d1: f64, z: &mut Vec<f64>| {
        let y = (y0 * c0 + y1 * c1) / 32.0 + (f0 * d0 + f1 * d1) * (h / 64.0);
        z.clear();
        z.extend((0..count).map(|j| (za[j] * c0 + zb[j] * c1) / 32.0 + (k0[j] * d0 + k1[j] * d1) * (h / 64.0)));
        y
    };
    let y_q = combine(27.0, 5.0, 9.0, -3.0, z_q);
    let y_tq = combine(5.0, 27.0, 3.0, -9.0, z_tq);
    let f_q = stage(&quarters.quarter, &y_q, z_q, None, k_q)?;
    let f_tq = stage(&quarters.three_quarters, &y_tq, z_tq, None, k_tq)?;
    let y_m = (y0 + y1) * 0.5 + ((f1 - f0) * (5.0 / 24.0) + (f_q - f_tq) * (2.0 / 3.0)) * h;
    z_m.clear();
    z_m.extend(
        (0..count)
            .map(|j| 0.5 * (za[j] + zb[j]) + ((k1[j] - k0[j]) * (5.0 / 24.0) + (k_q[j] - k_tq[j]) * (2.0 / 3.0)) * h),
    );
    let f_m = stage(&sites.mid, &y_m, z_m, None, k_m)?;
    let quadrature = ((f0 + f1) * 7.0 + (f_q + f_tq) * 32.0 + f_m * 12.0) * (h / 90.0);
    let psi: Vec<f64> = (0..count)
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
    profile.give_scratch(scratch);
    Ok((scale_rows(y1 - y0 - quadrature, length), psi, rates(&f0), rates(&f1)))
}
