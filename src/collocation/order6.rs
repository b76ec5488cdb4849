//! The order-6 scheme's interval rows (docs/numerics.md, "Error estimate"): the defect the
//! deferred-correction estimate reads, in the local coordinates and scaling of
//! [`super::residual::interval`].

// R for rotation matrices, as in the paper and residual.rs.
#![allow(non_snake_case)]

use super::residual::{Block, IntervalSites, end_values, rhs, scale_rows};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::solution::State;
use nalgebra::Vector6;

/// The sites the order-6 residual of an interval needs besides its [`IntervalSites`]: at
/// a quarter and three quarters of the interval.
#[derive(Clone, Copy, Debug)]
pub struct QuarterSites {
    /// Site at s_k + h/4.
    pub quarter: Site,
    /// Site at s_k + 3h/4.
    pub three_quarters: Site,
}

/// Interval rows of the order-6 scheme (the 5-stage mono-implicit Runge-Kutta formula of
/// Cash and Singhal, whose quadrature is Boole's rule on 0, 1/4, 1/2, 3/4, 1), evaluated at
/// the states `a`, `b` of the order-4 solution, in the same local coordinates and scaling
/// as [`super::residual::interval`]; `start_rates` and `end_rates` are the rates (v', u')
/// at the two nodes.
/// Every stage is explicit in the end points (docs/numerics.md, "Error estimate"):
///
/// ```text
/// y_1/4 = (27 y_0 + 5 y_1) / 32 + h (9 F_0 - 3 F_1) / 64
/// y_3/4 = (5 y_0 + 27 y_1) / 32 + h (3 F_0 - 9 F_1) / 64
/// y_1/2 = (y_0 + y_1) / 2 + h (5 (F_1 - F_0) / 24 + 2 (F_1/4 - F_3/4) / 3)
/// phi_6 = y_1 - y_0 - h (7 (F_0 + F_1) + 32 (F_1/4 + F_3/4) + 12 F_1/2) / 90
/// ```
///
/// # Errors
/// A model breakdown at a stage.
#[allow(clippy::too_many_arguments)]
pub fn interval_order6(
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
    let y_q = (y0 * 27.0 + y1 * 5.0) / 32.0 + (f0 * 9.0 - f1 * 3.0) * (h / 64.0);
    let y_tq = (y0 * 5.0 + y1 * 27.0) / 32.0 + (f0 * 3.0 - f1 * 9.0) * (h / 64.0);
    let f_q = rhs(model, &quarters.quarter, segment_end, &a.R, &y_q)?;
    let f_tq = rhs(model, &quarters.three_quarters, segment_end, &a.R, &y_tq)?;
    let y_m = (y0 + y1) * 0.5 + ((f1 - f0) * (5.0 / 24.0) + (f_q - f_tq) * (2.0 / 3.0)) * h;
    let f_m = rhs(model, &sites.mid, segment_end, &a.R, &y_m)?;
    let quadrature = ((f0 + f1) * 7.0 + (f_q + f_tq) * 32.0 + f_m * 12.0) * (h / 90.0);
    Ok(scale_rows(y1 - y0 - quadrature, model.robot.length()))
}
