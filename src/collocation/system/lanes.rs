//! Four intervals' blocks at once in the Jacobian's assembly ([`System::interval_group`]):
//! the lane kernel of `collocation::interval_lanes` where four consecutive links are
//! intervals of one segment.

use super::{System, TensionSink};
use crate::collocation::interval_lanes::interval_jacobians4;
use crate::collocation::unknowns::{NODE, link_row};
use crate::error::Result;
use crate::model::linearize::Linearization;
use crate::solution::State;
use nalgebra::Vector6;

impl System<'_> {
    /// The links k..k+4 of a frictionless system when they are four intervals of one
    /// segment: their residual rows into `out`, their blocks into `values` (from link k's
    /// on), the rates at their nodes into `rates` when given, their rows of the tension
    /// columns into `tensions` with its sink's buffers when given (as
    /// `System::jacobian_with` passes them), and the linearization at
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
        tensions: &mut Option<(&mut TensionSink, &mut [f64])>,
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
        let n = self.unknowns();
        let tensions = tensions
            .as_mut()
            .map(|(sink, columns)| sink.group(shared, k, columns, n));
        let group = interval_jacobians4(
            &self.model,
            [s0, s1, s2, s3],
            seg,
            &x[k..k + 5],
            start.as_ref(),
            block,
            as_residual,
            &mut ends,
            tensions,
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
}
