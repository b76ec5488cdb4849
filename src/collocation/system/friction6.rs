//! The order-6 rows of a system with friction ([`System::friction_order6`]): runs of four
//! intervals of one segment evaluated at once ([`friction::intervals4_order6`]), the other
//! links one by one ([`friction::interval_order6`]), with the same bits either way.

use super::System;
use crate::collocation::friction::{self, Profile};
use crate::collocation::residual::IntervalSites;
use crate::error::Result;
use crate::solution::State;
use nalgebra::Vector6;

impl System<'_> {
    /// [`System::order6_residual`] of a system with friction (`profile`): each link's
    /// order-6 backbone rows into `out`, its capstan rows kept in the profile, its local
    /// error into `local` and the rates at its nodes into `rates`.
    ///
    /// # Errors
    /// A model breakdown at a stage.
    pub(super) fn friction_order6(
        &self,
        profile: &Profile,
        x: &[State],
        out: &mut [f64],
        local: &mut [f64],
        rates: &mut [Vector6<f64>],
    ) -> Result<()> {
        let length = self.model.robot.length();
        // The run of four links evaluated at once, each taken as it is reached.
        let mut run: Option<(usize, [Option<friction::Order6>; 4])> = None;
        self.rows(x, out, |k, sites, seg, a, b, _| {
            let grouped = match &mut run {
                Some((first, links)) if (*first..*first + 4).contains(&k) => links[k - *first].take(),
                _ => self.friction_order6_group(profile, length, k, x).and_then(|links| {
                    let mut links = links.map(Some);
                    let first = links[0].take();
                    run = Some((k, links));
                    first
                }),
            };
            let (r, psi, start, end) = match grouped {
                Some(link) => link,
                None => friction::interval_order6(profile, length, k, sites, self.quarters(k), seg, a, b)?,
            };
            (rates[k], rates[k + 1]) = (start, end);
            local[k] = psi.iter().fold(r.amax(), |m, p| m.max(p.abs()));
            Ok((r, end))
        })
    }

    /// Links k..k+4's order-6 rows evaluated at once ([`friction::intervals4_order6`]) when
    /// they are four intervals of one segment and the lanes take them; None otherwise.
    fn friction_order6_group(
        &self,
        profile: &Profile,
        length: f64,
        k: usize,
        x: &[State],
    ) -> Option<[friction::Order6; 4]> {
        let Some([Some(s0), Some(s1), Some(s2), Some(s3)]) = self.interval_sites.get(k..k + 4) else {
            return None;
        };
        let seg = self.mesh.nodes[k].segment_end;
        if self.mesh.nodes[k + 1..k + 4].iter().any(|n| n.segment_end != seg) {
            return None;
        }
        let sites: [&IntervalSites; 4] = [s0, s1, s2, s3];
        let quarters = std::array::from_fn(|j| self.quarters(k + j));
        friction::intervals4_order6(profile, length, k, (sites, quarters), seg, &x[k..k + 5])
    }
}
