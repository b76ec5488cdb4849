//! What an interval's Jacobian (module `residual`) keeps or forms besides its block, for
//! work that reads the same evaluation of eq. 13: eq. 13's factored matrices at its points
//! (the mass of the linearized dynamics, `collocation/dynamics.rs`) or its tension rows (the
//! tension columns of the control Jacobian, docs/sensitivity.md).

#![allow(non_snake_case)] // R for rotation matrices, as the paper writes them

use crate::model::linearize;
use crate::model::routing::RoutingPoint;
use nalgebra::{Matrix3, Vector6};

/// The buffers of one interval's tension columns that [`interval_jacobian`](super::residual::interval_jacobian) fills besides
/// the Jacobian (one entry per tendon in each): d(v', u')/dtau_i at the start node (read
/// when the start node's linearization is given, as the previous interval's `end`, else
/// written), at the end node and at the midpoint (its total derivative), the midpoint's
/// strain motion; the columns the interval's rows of the right-hand sides -dF/dtau_i
/// (scaled: `residual::interval_derivatives` with `linearize::tension_rates`, negated) go
/// into, column i from `columns[i n]`, the interval's rows from `row` on; and every
/// tendon's routing point at the end node and at the midpoint when they are kept (else
/// each point evaluates the routings it needs).
pub struct IntervalTensions<'t> {
    pub(crate) start: &'t mut [Vector6<f64>],
    pub(crate) end: &'t mut [Vector6<f64>],
    pub(crate) mid: &'t mut [Vector6<f64>],
    pub(crate) dy_mid: &'t mut [Vector6<f64>],
    pub(crate) columns: &'t mut [f64],
    pub(crate) n: usize,
    pub(crate) row: usize,
    pub(crate) routing: Option<[&'t [RoutingPoint]; 2]>,
}

/// Eq. 13's factored matrix at an interval's three points and the midpoint's orientation,
/// as [`interval_jacobian_keeping`](super::residual::interval_jacobian_keeping) evaluated them.
#[derive(Clone)]
pub(crate) struct IntervalFactors {
    /// At the start node (valid when the interval Jacobian evaluated it).
    pub(crate) start: linearize::Factored,
    /// At the Hermite-Simpson midpoint.
    pub(crate) mid: linearize::Factored,
    /// At the end node.
    pub(crate) end: linearize::Factored,
    /// R at the midpoint, R_k exp(theta_m).
    pub(crate) mid_R: Matrix3<f64>,
}

impl IntervalFactors {
    /// Placeholders for a buffer [`interval_jacobian_keeping`](super::residual::interval_jacobian_keeping) fills.
    pub(crate) fn identity() -> Self {
        IntervalFactors {
            start: linearize::Factored::identity(),
            mid: linearize::Factored::identity(),
            end: linearize::Factored::identity(),
            mid_R: Matrix3::identity(),
        }
    }
}
