//! Four intervals' blocks at once in the Jacobian's assembly ([`System::interval_group`]):
//! the lane kernel of `collocation::interval_lanes` where four consecutive links are
//! intervals of one segment.

use super::System;
use crate::collocation::interval_lanes::interval_jacobians4;
use crate::collocation::order6::intervals_order6_lanes;
use crate::collocation::residual::Block;
use crate::collocation::unknowns::{NODE, link_row};
use crate::error::Result;
use crate::model::linearize::Linearization;
use crate::solution::State;
use nalgebra::Vector6;

impl System<'_> {
    /// The links k..k+4 of a frictionless system when they are four intervals of one
    /// segment: their residual rows into `out`, their blocks into `values` (from link k's
    /// on), the rates at their nodes into `rates` when given, and the linearization at
    /// node k + 4 into `lins[k % 2]`, where link k + 4 reads it (the one at node k read
    /// from there when `shared`, as `System::jacobian_with` passes them); true when they
    /// were (else nothing is written).
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn interval_group(
        &self,
        k: usize,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        lins: &mut [Linearization; 2],
        shared: bool,
        rates: Option<&mut [Vector6<f64>]>,
    ) -> Result<bool> {
        let Some(links) = self.interval_sites.get(k..k + 4) else {
            return Ok(false);
        };
        let [Some(s0), Some(s1), Some(s2), Some(s3)] = links else {
            return Ok(false);
        };
        let seg = self.mesh.nodes[k].segment_end;
        if self.mesh.nodes[k + 1..k + 4].iter().any(|n| n.segment_end != seg) {
            return Ok(false);
        }
        let slot = &mut lins[k % 2];
        let start = shared.then_some(*slot);
        let mut ends = [Linearization::zeros(); 4];
        let block = &mut values[..4 * NODE * 2 * NODE];
        let as_residual = rates.is_some();
        let group = interval_jacobians4(
            &self.model,
            [s0, s1, s2, s3],
            seg,
            &x[k..k + 5],
            start.as_ref(),
            block,
            as_residual,
            &mut ends,
        )?;
        for (j, (residual, _)) in group.iter().enumerate() {
            out[link_row(k + j)..link_row(k + j + 1)].copy_from_slice(residual.as_slice());
        }
        if let Some(rates) = rates {
            rates[k] = group[0].1;
            for (j, end) in ends.iter().enumerate() {
                rates[k + j + 1] = end.rates;
            }
        }
        *slot = ends[3];
        Ok(true)
    }

    /// Link k's order-6 rows ([`interval_order6`](crate::collocation::residual::interval_order6), given the node rates `rates`)
    /// from four intervals' evaluation in lanes ([`intervals_order6_lanes`]), which covers
    /// the links k..k+4 when they are four intervals of one segment and starts where `group`
    /// (the last group's first link and rows, None where the lanes declined) does not cover
    /// k: None when link k is not covered or the lanes declined (evaluate it alone then).
    pub(super) fn order6_group(
        &self,
        k: usize,
        x: &[State],
        rates: &[Vector6<f64>],
        group: &mut Option<(usize, Option<[Block<f64>; 4]>)>,
    ) -> Option<Block<f64>> {
        if let Some((first, rows)) = group
            && (*first..*first + 4).contains(&k)
        {
            return rows.map(|rows| rows[k - *first]);
        }
        let [Some(s0), Some(s1), Some(s2), Some(s3)] = self.interval_sites.get(k..k + 4)? else {
            return None;
        };
        let seg = self.mesh.nodes[k].segment_end;
        if self.mesh.nodes[k + 1..k + 4].iter().any(|n| n.segment_end != seg) {
            return None;
        }
        let sites = [s0, s1, s2, s3];
        let quarters = sites.map(|s| self.quarters(s));
        let nodes = std::array::from_fn(|j| (&x[k + j], &x[k + j + 1]));
        let node_rates = std::array::from_fn(|j| (&rates[k + j], &rates[k + j + 1]));
        let rows = intervals_order6_lanes(&self.model, sites, quarters.each_ref(), seg, nodes, node_rates);
        *group = Some((k, rows));
        rows.map(|rows| rows[0])
    }
}
