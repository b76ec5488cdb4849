//! Four intervals' blocks at once in the Jacobian's assembly ([`System::interval_group`]):
//! the lane kernel of `collocation::interval_lanes` where four consecutive links are
//! intervals of one segment.

use super::{System, TensionSink};
use crate::collocation::friction::{self, IntervalLinearization, Profile};
use crate::collocation::interval_lanes::interval_jacobians4;
use crate::collocation::order6::intervals_order6_lanes;
use crate::collocation::residual::{self, Block, IntervalRows, IntervalSites};
use crate::collocation::unknowns::{NODE, link_row};
use crate::error::Result;
use crate::model::linearize;
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

    /// [`System::residual`] of a system with friction (`profile`): each link's evaluation
    /// kept in the profile; runs of four intervals of one segment at once
    /// ([`System::friction_group`]).
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(super) fn friction_residual(&self, profile: &Profile, x: &[State], out: &mut [f64]) -> Result<()> {
        let length = self.model.robot.length();
        // Runs of four intervals of one segment at once (`friction_group`), kept as
        // each link is reached.
        let mut group: Option<(usize, [Option<friction::IntervalLinearization>; 4])> = None;
        self.rows(x, out, |k, sites, seg, a, b, _| {
            let grouped = match &mut group {
                Some((first, lins)) if (*first..*first + 4).contains(&k) => lins[k - *first].take(),
                _ => self.friction_group(profile, k, x, None)?.and_then(|lins| {
                    let mut lins = lins.map(Some);
                    let first = lins[0].take();
                    group = Some((k, lins));
                    first
                }),
            };
            let lin = match grouped {
                Some(lin) => lin,
                None => friction::interval(profile, length, k, sites, seg, a, b, None)?,
            };
            let residual = lin.residual;
            profile.keep(k, lin);
            Ok((residual, Vector6::zeros()))
        })
    }

    /// The links k..k+4 of a system with friction (`profile`) evaluated at once
    /// ([`friction::intervals4`]) when they are four intervals of one segment and the group
    /// takes them, their blocks into `values` (from link k's on) when given; None otherwise
    /// (evaluate them one by one then).
    ///
    /// # Errors
    /// A model breakdown at node k.
    pub(crate) fn friction_group(
        &self,
        profile: &Profile,
        k: usize,
        x: &[State],
        values: Option<&mut [f64]>,
    ) -> Result<Option<[IntervalLinearization; 4]>> {
        let Some([Some(s0), Some(s1), Some(s2), Some(s3)]) = self.interval_sites.get(k..k + 4) else {
            return Ok(None);
        };
        let seg = self.mesh.nodes[k].segment_end;
        if self.mesh.nodes[k + 1..k + 4].iter().any(|n| n.segment_end != seg) {
            return Ok(None);
        }
        let length = self.model.robot.length();
        let values = values.map(|v| &mut v[..4 * NODE * 2 * NODE]);
        friction::intervals4(profile, length, k, [s0, s1, s2, s3], seg, &x[k..k + 5], values)
    }

    /// Link k's value from `group` (the first link and the values of the last four links
    /// evaluated at once, None where the lanes declined them) when it covers k; else, when
    /// the links k..k+4 are four intervals of one segment, from `lanes` (given their sites
    /// and segment end) evaluated and kept in `group`. None when neither gives it (evaluate
    /// link k alone then).
    fn grouped<T: Copy>(
        &self,
        k: usize,
        group: &mut Group<T>,
        lanes: impl FnOnce([&IntervalSites; 4], f64) -> Result<Option<[T; 4]>>,
    ) -> Result<Option<T>> {
        if let Some((first, values)) = group
            && (*first..*first + 4).contains(&k)
        {
            return Ok(values.map(|values| values[k - *first]));
        }
        let Some([Some(s0), Some(s1), Some(s2), Some(s3)]) = self.interval_sites.get(k..k + 4) else {
            return Ok(None);
        };
        let seg = self.mesh.nodes[k].segment_end;
        if self.mesh.nodes[k + 1..k + 4].iter().any(|n| n.segment_end != seg) {
            return Ok(None);
        }
        let values = lanes([s0, s1, s2, s3], seg)?;
        *group = Some((k, values));
        Ok(values.map(|values| values[0]))
    }

    /// Link k's order-6 rows ([`interval_order6`](crate::collocation::residual::interval_order6),
    /// given the node rates `rates` at `x`) from four intervals evaluated at once
    /// ([`intervals_order6_lanes`]; `group` as [`System::grouped`] keeps them).
    pub(super) fn order6_group(
        &self,
        k: usize,
        x: &[State],
        rates: &[Vector6<f64>],
        group: &mut Group<Block<f64>>,
    ) -> Option<Block<f64>> {
        let lanes = |sites: [&IntervalSites; 4], seg| {
            let quarters = std::array::from_fn(|j| self.quarters(k + j));
            let nodes = std::array::from_fn(|j| (&x[k + j], &x[k + j + 1]));
            let node_rates = std::array::from_fn(|j| (&rates[k + j], &rates[k + j + 1]));
            Ok(intervals_order6_lanes(
                &self.model,
                sites,
                quarters,
                seg,
                nodes,
                node_rates,
            ))
        };
        self.grouped(k, group, lanes).ok().flatten()
    }

    /// Link k's interval rows with the rates at its nodes ([`residual::interval`], given the
    /// rates at node k when known, `start`) from four intervals evaluated at once
    /// ([`residual::intervals_lanes`]; `group` as [`System::grouped`] keeps them).
    ///
    /// # Errors
    /// A model breakdown at node k (whose rates are evaluated here when not given).
    pub(super) fn residual_group(
        &self,
        k: usize,
        x: &[State],
        start: Option<Vector6<f64>>,
        group: &mut Group<IntervalRows>,
    ) -> Result<Option<IntervalRows>> {
        self.grouped(k, group, |sites, seg| {
            let start = match start {
                Some(r) => r,
                None => linearize::rates(&self.model, &sites[0].start, seg, &x[k].R, &x[k].v, &x[k].u)?,
            };
            Ok(residual::intervals_lanes(&self.model, sites, seg, &x[k..k + 5], start))
        })
    }
}

/// Four links' values evaluated at once: the first link, and the values (None where the
/// lanes declined them).
pub(super) type Group<T> = Option<(usize, Option<[T; 4]>)>;
