//! The responses of eq. 13 with friction to the inertia loads, kept by the links'
//! evaluations with derivatives at the answer for the verdict's mass to read at the same
//! points (docs/stability.md, "Tendons with friction").
#![allow(non_snake_case)]

use super::*;

impl Profile<'_> {
    /// Sets whether the links' evaluations with derivatives keep eq. 13 with friction's
    /// response to the inertia loads at their start nodes and midpoints
    /// ([`Profile::keep_response`]; `mass`: the rod's density over its Young's modulus and
    /// its length, [`crate::collocation::dynamics::inertia_load_transposed`]), for the
    /// Jacobian at the answer whose verdict's mass reads them at the same points.
    pub(crate) fn keep_responses(&self, mass: Option<(f64, f64)>) {
        self.responding.set(mass);
    }

    /// Keeps the response of `lin`, eq. 13 with friction at point `index` (link k's start
    /// node 2k, its midpoint 2k + 1) of `site` evaluated at the state (R, v, u), log
    /// tensions `z`, multipliers `w` and segment end `segment_end`, when
    /// [`Profile::keep_responses`] is set.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::collocation::friction) fn keep_response(
        &self,
        index: usize,
        site: &Site,
        segment_end: f64,
        (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
        (z, w): (&[f64], Option<&[f64]>),
        lin: &FrictionLinearization,
    ) {
        let Some((ratio, length)) = self.responding.get() else {
            return;
        };
        let count = self.count();
        let mut responses = self.responses.borrow_mut();
        let Responses {
            points,
            z: zs,
            w: ws,
            turning,
            turns,
            ..
        } = &mut *responses;
        if points.len() <= index {
            // Every point of the mesh at once: 2 per link, and the stuck links' ends
            // ([`Profile::end_point`]).
            let size = (3 * self.z.first().map_or(0, Vec::len)).max(index + 1);
            points.resize(size, Response::default());
            for buffer in [&mut *zs, &mut *ws, &mut *turning] {
                buffer.resize(size * count, 0.0);
            }
            turns.resize(size * count, SMatrix::zeros());
        }
        let range = index * count..(index + 1) * count;
        let kept = &mut points[index];
        kept.segment_end = segment_end;
        kept.state = (*R, *v, *u);
        zs[range.clone()].copy_from_slice(z);
        kept.multipliers = w.is_some();
        if let Some(w) = w {
            ws[range.clone()].copy_from_slice(w);
        }
        kept.rates = lin.lin.rates;
        turning[range.clone()].copy_from_slice(&lin.turning);
        let mut loads = crate::collocation::dynamics::inertia_load_transposed(site, R, ratio, length);
        kept.valid = lin.load_response(&mut loads, &mut turns[range]);
        kept.loads = loads;
    }

    /// The point index [`Profile::keep_response`] keeps link k's end node at when the link
    /// has a stuck slip: evaluated with the link's own multipliers, which the next link's
    /// start (point 2k + 2) does not share.
    pub(crate) fn end_point(&self, k: usize) -> usize {
        2 * self.z.first().map_or(0, Vec::len) + k
    }

    /// [`Profile::keep_response`] of link k's end node `lin` at [`Profile::end_point`] when
    /// the link has a stuck slip (its multipliers are its own, not the next link's start's).
    pub(in crate::collocation::friction) fn keep_end_response(
        &self,
        k: usize,
        site: &Site,
        segment_end: f64,
        state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
        (z, w): (&[f64], Option<&[f64]>),
        lin: &FrictionLinearization,
    ) {
        if self.responding.get().is_none() || !(0..self.count()).any(|j| self.sticks(j, k)) {
            return;
        }
        self.keep_response(self.end_point(k), site, segment_end, state, (z, w), lin);
    }

    /// The rates and turning rates at point `index` with its response to the inertia loads
    /// (into `loads`, one load per row, and `turns`, one per slip) kept by
    /// [`Profile::keep_response`] from the same inputs, bit for bit (what evaluating them
    /// again gives); None otherwise.
    pub(crate) fn kept_response(
        &self,
        index: usize,
        segment_end: f64,
        state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
        (z, w): (&[f64], Option<&[f64]>),
        (loads, turns): (&mut SMatrix<f64, 6, 6>, &mut Vec<SMatrix<f64, 1, 6>>),
    ) -> Option<(Vector6<f64>, Vec<f64>)> {
        let responses = self.responses.borrow();
        let kept = responses.points.get(index)?;
        let range = index * self.count()..(index + 1) * self.count();
        let same = kept.valid
            && kept.segment_end == segment_end
            && (&kept.state.0, &kept.state.1, &kept.state.2) == state
            && responses.z[range.clone()] == *z
            && match w {
                Some(w) => kept.multipliers && responses.w[range.clone()] == *w,
                None => !kept.multipliers,
            };
        if !same {
            return None;
        }
        #[cfg(test)]
        responses.hits.set(responses.hits.get() + 1);
        *loads = kept.loads;
        turns.clear();
        turns.extend_from_slice(&responses.turns[range.clone()]);
        Some((kept.rates, responses.turning[range].to_vec()))
    }

    /// How many kept responses [`Profile::kept_response`] returned so far.
    #[cfg(test)]
    pub(crate) fn kept_hits(&self) -> usize {
        self.responses.borrow().hits.get()
    }
}
