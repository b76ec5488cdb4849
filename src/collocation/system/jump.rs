//! The rows of a jump (a segment end: continuity of the state across it, docs/model.md) and
//! their derivatives in the Jacobian, by one dual pass per unknown of its two nodes.

use super::System;
use crate::collocation::residual::{self, Delta};
use crate::collocation::unknowns::{NODE, link_row};
use crate::error::Result;
use crate::solution::State;
use num_dual::Dual64;

impl System<'_> {
    /// The residual rows of the jump between nodes k and k + 1 into `out` (at link k's rows)
    /// and their derivatives in the unknowns of the two nodes into `block` (link k's
    /// `NODE` x `2 NODE` block of the Jacobian values, row major): one dual pass per unknown
    /// (a mesh has few jumps).
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(super) fn jump_rows(&self, k: usize, x: &[State], out: &mut [f64], block: &mut [f64]) -> Result<()> {
        let width = 2 * NODE;
        for j in 0..width {
            let da = Delta::<Dual64>::from_fn(|i, _| {
                if i == j {
                    Dual64::from(0.0).derivative()
                } else {
                    Dual64::from(0.0)
                }
            });
            let db = Delta::<Dual64>::from_fn(|i, _| {
                if i + NODE == j {
                    Dual64::from(0.0).derivative()
                } else {
                    Dual64::from(0.0)
                }
            });
            let r = residual::jump(
                &self.model,
                (&self.node_sites[k], &self.node_sites[k + 1]),
                &x[k],
                &x[k + 1],
                &da,
                &db,
            )?;
            for (i, d) in r.iter().enumerate() {
                out[link_row(k) + i] = d.re;
                block[i * width + j] = d.eps;
            }
        }
        Ok(())
    }
}
