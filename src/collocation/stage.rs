//! Stages whose strains keep their part below the last place (docs/numerics.md, "Why the
//! estimate was low on some random robots: the strain's last place").
//!
//! A node or stage holds the strain v, near v* = e3 on a straight rod, and eq. 13 reads the
//! internal force from it as D (v - v*): v's last place (1.1e-16 near 1) is a force of
//! EA eps (7e-12 N on a rod with EA = 6.6e4 N). A stage formed as a combination of the end
//! points rounds its strain to that place, and every stage rounds differently: noise in
//! each evaluation of eq. 13 that the order-6 answer and its order-8 estimate see as an
//! error of 1e-12 to 1e-11 L on stiff, slender rods. Formed as y0 + an increment, a stage
//! knows its deviation v_0 - v* + inc_v far more precisely than its strain; [`stage`] keeps
//! what rounding the strain drops and [`rhs_stage`] hands it to eq. 13
//! ([`linearize::rates_split`]). The order-6 answer's defect ([`interval_order6_split`]),
//! the order-8 residual and the order-4 rows of the order-6 answer's correction
//! ([`interval_split`]) evaluate their stages so; the default order-4 solve and its error
//! estimate do not (their answers and cost are unchanged).

// R for rotation matrices, as in the paper and residual.rs.
#![allow(non_snake_case)]

use super::residual::{Block, IntervalSites, QuarterSites, end_values, rhs_from_rates, scale_rows};
use super::unknowns::{THETA, U, V};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::model::linearize;
use crate::so3;
use crate::solution::State;
use nalgebra::{Matrix3, Vector3, Vector6};

/// A stage y_0 + `inc` of an interval at `site` (local coordinates, `inc` the stage's
/// increment from the interval's start `y0`), with its strain's part below the last place:
/// the strain v = v* + (v_0 - v* + inc_v) rounds the deviation in parentheses, which carries
/// the internal force, to v's last place (about 1e-16 of a strain near 1: a force of EA eps);
/// the low part returned is what that rounding dropped (exact: Fast2Sum, componentwise
/// where |v*_i| >= the deviation, and nothing to drop where v*_i = 0; v_0 - v* is exact
/// where v_0 is near v*). [`rhs_stage`] takes both.
pub(super) fn stage(site: &Site, y0: &Block<f64>, inc: &Block<f64>) -> (Block<f64>, Vector3<f64>) {
    let mut y = y0 + inc;
    let v_star = site.reference.v_star;
    let v0: Vector3<f64> = y0.fixed_rows::<3>(V).into();
    let deviation = (v0 - v_star) + inc.fixed_rows::<3>(V);
    let v = v_star + deviation;
    y.fixed_rows_mut::<3>(V).copy_from(&v);
    (y, deviation - (v - v_star))
}

/// [`super::residual::rhs`] at a stage of [`stage`]: the strain v of `y` plus `low` below its last place
/// ([`linearize::rates_split`]).
///
/// # Errors
/// As [`super::residual::rhs`].
pub(super) fn rhs_stage(
    model: &Model,
    site: &Site,
    segment_end: f64,
    Rk: &Matrix3<f64>,
    (y, low): (&Block<f64>, &Vector3<f64>),
) -> Result<Block<f64>> {
    let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
    let v: Vector3<f64> = y.fixed_rows::<3>(V).into();
    let u: Vector3<f64> = y.fixed_rows::<3>(U).into();
    let R = Rk * so3::exp(&theta);
    let rates = linearize::rates_split(model, site, segment_end, &R, (&v, low), &u)?;
    Ok(rhs_from_rates(site, &R, y, &rates))
}

/// [`super::residual::interval`] with the midpoint's strain kept below its last place ([`stage`]): the
/// order-4 rows the order-6 answer is corrected with (docs/numerics.md, "The order-6
/// answer"). Returns the rows and the rates at node b.
///
/// # Errors
/// As [`super::residual::interval`].
pub(super) fn interval_split(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: Option<Vector6<f64>>,
) -> Result<(Block<f64>, Vector6<f64>)> {
    let h = sites.end.s - sites.start.s;
    let rates0 = match start_rates {
        Some(r) => r,
        None => linearize::rates(model, &sites.start, segment_end, &a.R, &a.v, &a.u)?,
    };
    let rates1 = linearize::rates(model, &sites.end, segment_end, &b.R, &b.v, &b.u)?;
    let [y0, y1, f0, f1] = end_values(sites, a, b, &rates0, &rates1);
    let m = stage(&sites.mid, &y0, &((y1 - y0) * 0.5 + (f0 - f1) * (h / 8.0)));
    let fm = rhs_stage(model, &sites.mid, segment_end, &a.R, (&m.0, &m.1))?;
    Ok((
        scale_rows(y1 - y0 - (f0 + fm * 4.0 + f1) * (h / 6.0), model.robot.length()),
        rates1,
    ))
}

/// [`super::residual::interval_order6`] with the stages' strains kept below their last place
/// ([`stage`]): the order-6 rows of the order-6 answer's defect. The stages as y0 + an
/// increment ((27 y0 + 5 y1) / 32 = y0 + 5 (y1 - y0) / 32).
///
/// # Errors
/// As [`super::residual::interval_order6`].
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_order6_split(
    model: &Model,
    sites: &IntervalSites,
    quarters: &QuarterSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: &Vector6<f64>,
    end_rates: &Vector6<f64>,
) -> Result<Block<f64>> {
    let h = sites.end.s - sites.start.s;
    let [y0, y1, f0, f1] = end_values(sites, a, b, start_rates, end_rates);
    let d = y1 - y0;
    let q = stage(
        &quarters.quarter,
        &y0,
        &(d * (5.0 / 32.0) + (f0 * 9.0 - f1 * 3.0) * (h / 64.0)),
    );
    let tq = stage(
        &quarters.three_quarters,
        &y0,
        &(d * (27.0 / 32.0) + (f0 * 3.0 - f1 * 9.0) * (h / 64.0)),
    );
    let f_q = rhs_stage(model, &quarters.quarter, segment_end, &a.R, (&q.0, &q.1))?;
    let f_tq = rhs_stage(model, &quarters.three_quarters, segment_end, &a.R, (&tq.0, &tq.1))?;
    let m = stage(
        &sites.mid,
        &y0,
        &(d * 0.5 + ((f1 - f0) * (5.0 / 24.0) + (f_q - f_tq) * (2.0 / 3.0)) * h),
    );
    let f_m = rhs_stage(model, &sites.mid, segment_end, &a.R, (&m.0, &m.1))?;
    let quadrature = ((f0 + f1) * 7.0 + (f_q + f_tq) * 32.0 + f_m * 12.0) * (h / 90.0);
    Ok(scale_rows(d - quadrature, model.robot.length()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The strain and its low part hold the deviation v_0 - v* + inc_v exactly (Fast2Sum):
    /// v - v* + low is that deviation to the bit, where v alone rounds it to v's last place.
    #[test]
    fn a_stage_keeps_the_deviation_its_strain_rounds_away() {
        let robot = crate::cases::case_s();
        let model = Model::new(&robot);
        let site = model.site(0.1);
        let v_star = site.reference.v_star;
        let mut y0 = Block::<f64>::from_fn(|i, _| 0.1 * i as f64);
        y0.fixed_rows_mut::<3>(V)
            .copy_from(&(v_star + Vector3::new(1e-6, -2e-6, 1.234_567_891e-5)));
        let mut inc = Block::<f64>::from_fn(|i, _| 1e-3 * i as f64);
        inc.fixed_rows_mut::<3>(V)
            .copy_from(&Vector3::new(3e-9, 1e-9, 7.654_321_987_6e-10));
        let (y, low) = stage(&site, &y0, &inc);
        let v0: Vector3<f64> = y0.fixed_rows::<3>(V).into();
        let deviation = (v0 - v_star) + inc.fixed_rows::<3>(V);
        let v: Vector3<f64> = y.fixed_rows::<3>(V).into();
        for i in 0..3 {
            assert_eq!((v[i] - v_star[i]) + low[i], deviation[i], "component {i}");
            // Below v's last place: at most half an ulp of v.
            assert!(
                low[i].abs() <= 0.5 * f64::EPSILON * v[i].abs(),
                "component {i}: {:e}",
                low[i]
            );
        }
        // The axial strain near 1 does round: its low part is what D (v - v*) keeps.
        assert_ne!(low[2], 0.0);
        // The other rows are y0 + inc.
        for i in (0..12).filter(|i| !(V..V + 3).contains(i)) {
            assert_eq!(y[i], y0[i] + inc[i]);
        }
    }
}
