//! Four consecutive links with friction at once ([`intervals4`]): eq. 13 with friction at
//! their four end nodes, then at their four midpoints, each in one pass of four f64 lanes
//! ([`linearize_lanes_into`], one link per lane), the rest of each link's evaluation by
//! the one-link kernel's own code ([`front`] and [`back`]), as the frictionless block of
//! four intervals does (`collocation/interval_lanes.rs`).
//!
//! Where the four links' multipliers are equal, link k's start is link k-1's end, and its
//! midpoint's state needs only its own nodes, so the four links' ends and then their
//! midpoints are independent points; where they differ (stuck links, each at its own
//! multiplier), the four starts are evaluated in lanes too, each at its own link's
//! multipliers, as the one-link kernel does. A stuck link's moved rows (its multiplier's
//! central difference) are evaluated four links at a time as well. Each lane performs the
//! scalar code's operations in its order, and every link reads the same inputs as when the
//! links are evaluated one by one, so each link's evaluation has the one-link kernel's bits
//! (the tests compare them). Where the profile keeps the responses to the inertia loads
//! (the Jacobian at the answer, for the verdict), the lanes give them too. The group
//! declines (the caller evaluates the links one by one) with two or more tendons with
//! friction, fewer than four links left, or where a lane leaves the lanes' path (a
//! Kirchhoff rod's sites, a breakdown, a zero or NaN multiplier).
#![allow(non_snake_case)]

use super::interval::{IntervalLinearization, Link, back, front, interval_at, node_tensions, value_rows};
use super::profile::{LinkScratch, Profile};
use super::stuck_links::{MULTIPLIER_STEP, add_multiplier_columns, stuck_slips};
use crate::collocation::dynamics::inertia_load_transposed;
use crate::collocation::residual::{Block, IntervalSites};
use crate::error::Result;
use crate::model::equations::Site;
use crate::model::friction::{FrictionLinearization, linearize_lanes_into};
use crate::simd::avx2_fma;
use crate::solution::State;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Entries of one link's row-major 12 x 24 backbone block.
const BLOCK: usize = 12 * 24;

/// Links k..k+4 with friction (`sites` theirs, one segment ending at `segment_end`, `x`
/// the five node states from node k on) evaluated at once, as [`super::interval()`]
/// evaluates each, their blocks into `jac` (four consecutive 12 x 24 blocks) when given:
/// None where the group declines (module docs; then evaluate them one by one).
///
/// # Errors
/// A model breakdown at node k (the one point evaluated alone, as the first link does,
/// where the four links' multipliers are the same), or at a link whose rows' change with
/// a stuck multiplier the lanes declined ([`super::interval()`] evaluates it then).
///
/// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, with the lanes and
/// the one-link kernel's code inlined: the same operations in the same order.
pub(crate) fn intervals4(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    jac: Option<&mut [f64]>,
) -> Result<Option<[IntervalLinearization; 4]>> {
    avx2_fma!(intervals4_kernel(profile, length, k, sites, segment_end, x, jac))
}

/// [`intervals4`]'s operations: the rows at the stuck links' moved multipliers (as
/// [`super::interval()`] forms them, before the links' own evaluation, which the profile
/// then keeps at the nodes), the four links' evaluation, and the moved rows' columns.
#[inline(always)]
fn intervals4_kernel(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    jac: Option<&mut [f64]>,
) -> Result<Option<[IntervalLinearization; 4]>> {
    // What the lanes decline whatever the states (two or more tendons with friction) is
    // declined before any point is evaluated; a Kirchhoff rod's sites decline in the lanes,
    // which keep the start node's evaluation for the one-link kernel.
    if x.len() < 5 || profile.slipping.len() > 1 {
        return Ok(None);
    }
    let group = Group {
        profile,
        length,
        k,
        sites,
        segment_end,
        x,
    };
    // Full slip: every multiplier the motion's sign and no stuck link, so none of the
    // history's per-point multipliers or moved rows below.
    if profile.grips.is_none() {
        return group.evaluate([None; 4], jac);
    }
    // Each link's multipliers at its start, midpoint and end ([`Profile::point_multipliers`]),
    // of its one slip (or none), in place: the lists cost an allocation each.
    let count = profile.count();
    let multipliers: [Option<[[f64; 1]; 3]>; 4] = std::array::from_fn(|l| {
        profile.grips.as_ref().map(|grips| {
            let mut points = [[0.0]; 3];
            if let Some(grip) = grips.first().filter(|_| count == 1) {
                let w = profile.multiplier(grip, 0, k + l);
                for (point, at) in points.iter_mut().zip(profile.point_multiplier(0, k + l, w)) {
                    point[0] = at;
                }
            }
            points
        })
    });
    let w: Points = std::array::from_fn(|l| {
        multipliers[l]
            .as_ref()
            .map(|p| [&p[0][..count], &p[1][..count], &p[2][..count]])
    });
    // With derivatives, each stuck slip's rows at its multiplier moved both ways.
    let mut moved = Vec::new();
    if jac.is_some() {
        for j in 0..profile.count() {
            let stuck: [Option<f64>; 4] =
                std::array::from_fn(|l| w[l].and_then(|_| stuck_slips(profile, k + l).find(|s| s.0 == j).map(|s| s.1)));
            if stuck.iter().all(Option::is_none) {
                continue;
            }
            let plus = group.moved_rows(w, j, &stuck, MULTIPLIER_STEP)?;
            let minus = group.moved_rows(w, j, &stuck, -MULTIPLIER_STEP)?;
            moved.push((j, stuck, plus, minus));
        }
    }
    let Some(mut out) = group.evaluate(w, jac)? else {
        return Ok(None);
    };
    let count = profile.count();
    for (j, stuck, plus, minus) in &moved {
        for (l, capacity) in stuck.iter().enumerate() {
            if let Some(capacity) = capacity {
                add_multiplier_columns(&mut out[l], count, (*j, *capacity), &plus[l], &minus[l]);
            }
        }
    }
    Ok(Some(out))
}

/// Each of four links' multipliers at its start, midpoint and end (None in full slip).
type Points<'w> = [Option<[&'w [f64]; 3]>; 4];

/// The four links' multipliers at their point `p` (0 start, 1 midpoint, 2 end).
fn at(w: Points<'_>, p: usize) -> [Option<&[f64]>; 4] {
    w.map(|w| w.map(|w| w[p]))
}

/// Four consecutive links of one segment: link k + l in lane l.
struct Group<'g, 'p> {
    profile: &'g Profile<'p>,
    length: f64,
    k: usize,
    sites: [&'g IntervalSites; 4],
    segment_end: f64,
    /// The five node states from node k on.
    x: &'g [State],
}

impl Group<'_, '_> {
    /// Link k + l's backbone rows, without derivatives, at its multipliers `w[l]` with slip
    /// j's moved by `step` where `stuck[l]` (zero rows in the other lanes): the four links
    /// at once, or each moved one by [`interval_at`] where the lanes decline them.
    ///
    /// # Errors
    /// A model breakdown at a point of a moved link.
    #[inline(always)]
    fn moved_rows(&self, w: Points, j: usize, stuck: &[Option<f64>; 4], step: f64) -> Result<[Block<f64>; 4]> {
        let moved: [Option<[Vec<f64>; 3]>; 4] = std::array::from_fn(|l| {
            w[l].map(|w| {
                let sigma = self.profile.sigma(j, self.k + l);
                std::array::from_fn(|p| {
                    let mut w = w[p].to_vec();
                    if stuck[l].is_some() {
                        w[j] += sigma.map_or(step, |sigma| step * sigma[p]);
                    }
                    w
                })
            })
        });
        let moved_w: Points = std::array::from_fn(|l| moved[l].as_ref().map(|p| [&p[0][..], &p[1][..], &p[2][..]]));
        if let Some(rows) = self.rows(moved_w) {
            return Ok(std::array::from_fn(|l| {
                if stuck[l].is_some() { rows[l] } else { Block::zeros() }
            }));
        }
        let mut rows = [Block::zeros(); 4];
        for (l, row) in rows.iter_mut().enumerate().filter(|(l, _)| stuck[*l].is_some()) {
            let Group {
                profile,
                length,
                k,
                sites,
                segment_end,
                x,
            } = *self;
            let lin = interval_at(
                profile,
                length,
                k + l,
                sites[l],
                segment_end,
                &x[l],
                &x[l + 1],
                moved_w[l],
                None,
            )?;
            *row = lin.residual;
            profile.give_link(lin);
        }
        Ok(rows)
    }

    /// The four links' backbone rows alone (no derivatives; the profile keeps nothing of
    /// them) at the slips' multipliers `w`, each link's start evaluated at its own: the
    /// rows [`Group::evaluate`] gives there. None where the lanes decline a point.
    #[inline(always)]
    fn rows(&self, w: Points) -> Option<[Block<f64>; 4]> {
        let Group {
            profile,
            length,
            k,
            sites,
            segment_end,
            x,
        } = *self;
        let mut scratch: [Box<LinkScratch>; 4] = [
            profile.take_scratch(),
            profile.take_scratch(),
            profile.take_scratch(),
            profile.take_scratch(),
        ];
        for (j, s) in scratch.iter_mut().enumerate() {
            node_tensions(profile, k + j, s);
        }
        let state = |n: usize| (&x[n].R, &x[n].v, &x[n].u);
        let starts = points4(
            profile,
            sites.map(|s| &s.start),
            segment_end,
            [state(0), state(1), state(2), state(3)],
            [&scratch[0].za, &scratch[1].za, &scratch[2].za, &scratch[3].za],
            at(w, 0),
            (false, None),
        );
        let ends = starts.as_ref().and_then(|_| {
            points4(
                profile,
                sites.map(|s| &s.end),
                segment_end,
                [state(1), state(2), state(3), state(4)],
                [&scratch[0].zb, &scratch[1].zb, &scratch[2].zb, &scratch[3].zb],
                at(w, 2),
                (false, None),
            )
        });
        let mut rows = None;
        if let (Some(starts), Some(ends)) = (&starts, &ends) {
            let link = |j: usize| Link {
                profile,
                length,
                k: k + j,
                sites: sites[j],
                segment_end,
                a: &x[j],
                b: &x[j + 1],
                w: w[j],
            };
            let links = [link(0), link(1), link(2), link(3)];
            let [s0, s1, s2, s3] = &mut scratch;
            let [mut p0, mut p1, mut p2, mut p3] = [None, None, None, None];
            let fronts = [
                front(&links[0], (&starts[0], &ends[0]), (false, false), s0, &mut p0),
                front(&links[1], (&starts[1], &ends[1]), (false, false), s1, &mut p1),
                front(&links[2], (&starts[2], &ends[2]), (false, false), s2, &mut p2),
                front(&links[3], (&starts[3], &ends[3]), (false, false), s3, &mut p3),
            ];
            let mid = |j: usize| (&fronts[j].Rm, &fronts[j].vm, &fronts[j].um);
            if let Some(mids) = points4(
                profile,
                sites.map(|s| &s.mid),
                segment_end,
                [mid(0), mid(1), mid(2), mid(3)],
                [&scratch[0].zm, &scratch[1].zm, &scratch[2].zm, &scratch[3].zm],
                at(w, 1),
                (false, None),
            ) {
                rows = Some(std::array::from_fn(|j| value_rows(&links[j], &fronts[j], &mids[j])));
                mids.into_iter().for_each(|l| profile.give(l));
            }
        }
        starts.into_iter().chain(ends).flatten().for_each(|l| profile.give(l));
        scratch.into_iter().for_each(|s| profile.give_scratch(s));
        rows
    }

    /// The four links' evaluations at the slips' multipliers `w` (one list per link), their
    /// blocks into `jac` when given, the rows' change with a stuck multiplier aside: None
    /// where the lanes decline a point. Where the links' multipliers are the same, each
    /// link's start is the link before's end, and link k's start is evaluated alone
    /// ([`Profile::start_point`], which takes it from the link before when that kept it);
    /// else the four starts are evaluated at once, each at its own link's multipliers (as
    /// the one-link kernel evaluates them: a link's end at its own multipliers is not the
    /// next one's start).
    ///
    /// # Errors
    /// A model breakdown at node k where it is evaluated alone.
    #[inline(always)]
    fn evaluate(&self, w: Points, jac: Option<&mut [f64]>) -> Result<Option<[IntervalLinearization; 4]>> {
        let Group {
            profile,
            length,
            k,
            sites,
            segment_end,
            x,
        } = *self;
        let derivatives = jac.is_some();
        // Alike: every link's multipliers the same at its three points and as the others'.
        let alike = w.iter().all(|wl| *wl == w[0]) && w[0].is_none_or(|w| w[0] == w[1] && w[1] == w[2]);
        let mut scratch: [Box<LinkScratch>; 4] = [
            profile.take_scratch(),
            profile.take_scratch(),
            profile.take_scratch(),
            profile.take_scratch(),
        ];
        for (j, s) in scratch.iter_mut().enumerate() {
            node_tensions(profile, k + j, s);
        }
        let state = |n: usize| (&x[n].R, &x[n].v, &x[n].u);
        // Where the profile keeps the responses to the inertia loads (a Jacobian at the
        // answer), the lanes give them at the points [`back`] keeps them for: each link's
        // start and midpoint (and the last end, the next link's start where it is taken).
        let responding = profile.responding.get().filter(|_| derivatives);
        let inertia = |site: [&Site; 4], R: [&Matrix3<f64>; 4]| {
            responding
                .map(|(ratio, length)| std::array::from_fn(|j| inertia_load_transposed(site[j], R[j], ratio, length)))
        };
        let give_scratch = |scratch: [Box<LinkScratch>; 4]| scratch.into_iter().for_each(|s| profile.give_scratch(s));
        // Link k's start alone (`first`) or the four starts at once (`starts`).
        let (first, starts) = if alike {
            let za = &scratch[0].za;
            let first = profile.start_point(k, &sites[0].start, segment_end, &x[0], za, at(w, 0)[0], derivatives)?;
            (Some(first), None)
        } else {
            let Some(starts) = points4(
                profile,
                sites.map(|s| &s.start),
                segment_end,
                [state(0), state(1), state(2), state(3)],
                [&scratch[0].za, &scratch[1].za, &scratch[2].za, &scratch[3].za],
                at(w, 0),
                (
                    derivatives,
                    inertia(sites.map(|s| &s.start), [&x[0].R, &x[1].R, &x[2].R, &x[3].R]),
                ),
            ) else {
                give_scratch(scratch);
                return Ok(None);
            };
            (None, Some(starts))
        };
        let give_starts = |first: Option<Box<FrictionLinearization>>,
                           starts: Option<[Box<FrictionLinearization>; 4]>| {
            first
                .into_iter()
                .chain(starts.into_iter().flatten())
                .for_each(|l| profile.give(l));
        };
        let Some(ends) = points4(
            profile,
            sites.map(|s| &s.end),
            segment_end,
            [state(1), state(2), state(3), state(4)],
            [&scratch[0].zb, &scratch[1].zb, &scratch[2].zb, &scratch[3].zb],
            at(w, 2),
            (
                derivatives,
                inertia(sites.map(|s| &s.end), [&x[1].R, &x[2].R, &x[3].R, &x[4].R]),
            ),
        ) else {
            // Link k's start is kept for the one-link kernel that takes over.
            if let Some(first) = first {
                profile.keep_point(k, segment_end, &x[0], &scratch[0].za, at(w, 0)[0], derivatives, first);
            }
            give_starts(None, starts);
            give_scratch(scratch);
            return Ok(None);
        };
        let link = |j: usize| Link {
            profile,
            length,
            k: k + j,
            sites: sites[j],
            segment_end,
            a: &x[j],
            b: &x[j + 1],
            w: w[j],
        };
        let links = [link(0), link(1), link(2), link(3)];
        let start_of: [&FrictionLinearization; 4] = match (&first, &starts) {
            (Some(first), _) => [first, &ends[0], &ends[1], &ends[2]],
            (_, Some(s)) => [&s[0], &s[1], &s[2], &s[3]],
            (None, None) => unreachable!("link k's start is evaluated alone or with the others"),
        };
        let [s0, s1, s2, s3] = &mut scratch;
        let [mut p0, mut p1, mut p2, mut p3] = [None, None, None, None];
        let fronts = [
            front(&links[0], (start_of[0], &ends[0]), (derivatives, true), s0, &mut p0),
            front(&links[1], (start_of[1], &ends[1]), (derivatives, true), s1, &mut p1),
            front(&links[2], (start_of[2], &ends[2]), (derivatives, true), s2, &mut p2),
            front(&links[3], (start_of[3], &ends[3]), (derivatives, true), s3, &mut p3),
        ];
        let mid = |j: usize| (&fronts[j].Rm, &fronts[j].vm, &fronts[j].um);
        let Some(mids) = points4(
            profile,
            sites.map(|s| &s.mid),
            segment_end,
            [mid(0), mid(1), mid(2), mid(3)],
            [&scratch[0].zm, &scratch[1].zm, &scratch[2].zm, &scratch[3].zm],
            at(w, 1),
            (
                derivatives,
                inertia(
                    sites.map(|s| &s.mid),
                    [&fronts[0].Rm, &fronts[1].Rm, &fronts[2].Rm, &fronts[3].Rm],
                ),
            ),
        ) else {
            give_starts(first, starts);
            ends.into_iter().for_each(|l| profile.give(l));
            give_scratch(scratch);
            return Ok(None);
        };
        let mut blocks = jac.map(|jac| jac[..4 * BLOCK].chunks_exact_mut(BLOCK));
        let mut block = || blocks.as_mut().and_then(Iterator::next);
        let [f0, f1, f2, f3] = &fronts;
        let [s0, s1, s2, s3] = &mut scratch;
        let out = [
            back(&links[0], f0, [start_of[0], &mids[0], &ends[0]], block(), s0),
            back(&links[1], f1, [start_of[1], &mids[1], &ends[1]], block(), s1),
            back(&links[2], f2, [start_of[2], &mids[2], &ends[2]], block(), s2),
            back(&links[3], f3, [start_of[3], &mids[3], &ends[3]], block(), s3),
        ];
        let [e0, e1, e2, e3] = ends;
        profile.keep_point(k + 4, segment_end, &x[4], &scratch[3].zb, at(w, 2)[3], derivatives, e3);
        give_starts(first, starts);
        for lin in [e0, e1, e2].into_iter().chain(mids) {
            profile.give(lin);
        }
        give_scratch(scratch);
        Ok(Some(out))
    }
}

/// Eq. 13 with friction at four points at once ([`Profile::point`] at each: the slips at
/// log tensions `z[l]` and multipliers `w[l]` in lane l), in the profile's spare linearizations,
/// with derivatives when `derivatives.0` and the responses to the loads `derivatives.1`
/// when given; None where the lanes decline them.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn points4(
    profile: &Profile,
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
    z: [&[f64]; 4],
    w: [Option<&[f64]>; 4],
    (derivatives, loads): (bool, Option<[SMatrix<f64, 6, 6>; 4]>),
) -> Option<[Box<FrictionLinearization>; 4]> {
    let mut quad = profile.quad.borrow_mut();
    if quad.is_empty() {
        let model = profile.scratch.borrow();
        quad.extend((0..4).map(|_| model.clone()));
    }
    for (model, z) in quad.iter_mut().zip(z) {
        for (j, &i) in profile.slipping.iter().enumerate() {
            model.tensions[i] = profile.tension(j, z[j]);
        }
    }
    let mut out: [Box<FrictionLinearization>; 4] =
        std::array::from_fn(|_| profile.spare.borrow_mut().pop().unwrap_or_default());
    let [o0, o1, o2, o3] = &mut out;
    let models = [&quad[0], &quad[1], &quad[2], &quad[3]];
    let outs = [&mut **o0, &mut **o1, &mut **o2, &mut **o3];
    if linearize_lanes_into(
        models,
        sites,
        segment_end,
        states,
        &profile.slipping,
        w,
        derivatives,
        loads.as_ref(),
        outs,
    ) {
        return Some(out);
    }
    out.into_iter().for_each(|l| profile.give(l));
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::collocation::friction::{Contact, Grip, interval};
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::tendon::Friction;
    use crate::so3;

    /// A link's evaluation and block as bits.
    fn bits(lin: &IntervalLinearization, block: &[f64]) -> Vec<u64> {
        let mut v: Vec<f64> = lin.residual.iter().copied().collect();
        v.extend(lin.psi.iter().chain(&lin.capacity).chain(&lin.stuck_tension));
        if lin.derivatives {
            v.extend(lin.rows_z.iter().chain(lin.psi_x.iter()).chain(lin.psi_z.iter()));
        }
        v.extend(block);
        v.into_iter().map(f64::to_bits).collect()
    }

    /// A setup: `robot` solved on 8 intervals, its profile on that mesh with a made-up
    /// tension profile, the node states moved off the answer, and the first four links of
    /// one segment (their first index, sites and segment end).
    struct Setup {
        length: f64,
        mesh: Mesh,
        x: Vec<State>,
        k: usize,
        sites: Vec<IntervalSites>,
    }

    fn prepare(robot: &crate::Robot) -> (Setup, Model<'_>) {
        let solution = crate::solve(robot, &crate::collocation::Options::fixed(8)).unwrap();
        let model = Model::new(robot);
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(robot, &s).unwrap();
        // Off the answer: a twist and a strain change growing along the rod.
        let x: Vec<State> = solution
            .nodes
            .iter()
            .enumerate()
            .map(|(n, node)| {
                let mut state = node.state();
                state.R *= so3::exp(&Vector3::new(0.01, -0.02, 0.015 * n as f64));
                state.u += Vector3::new(0.3, -0.1 * n as f64, 0.2);
                state
            })
            .collect();
        let nodes = &mesh.nodes;
        let k = (0..nodes.len() - 4)
            .find(|&k| {
                (k..k + 4).all(|j| nodes[j].s < nodes[j + 1].s && nodes[j + 1].segment_end == nodes[k].segment_end)
            })
            .expect("four links of one segment");
        let sites = (k..k + 4)
            .map(|j| IntervalSites {
                start: model.site(nodes[j].s),
                mid: model.site(0.5 * (nodes[j].s + nodes[j + 1].s)),
                end: model.site(nodes[j + 1].s),
            })
            .collect();
        let length = robot.length();
        (
            Setup {
                length,
                mesh,
                x,
                k,
                sites,
            },
            model,
        )
    }

    /// The profile of `model` on the setup's mesh with log tensions falling along it.
    fn profile<'a>(model: &Model<'a>, s: &Setup) -> Profile<'a> {
        let mut profile = Profile::new(model, &s.mesh);
        for (j, z) in profile.z.iter_mut().enumerate() {
            for (n, value) in z.iter_mut().enumerate() {
                *value = -0.03 * n as f64 * (j as f64 + 1.0);
            }
        }
        profile
    }

    /// The group of four links on `profile` against the links one by one on a copy, with
    /// and without derivatives: None where the group declines, else asserts the bits.
    fn compare(s: &Setup, profile: &Profile, alone: &Profile) -> Option<()> {
        let sites: [&IntervalSites; 4] = std::array::from_fn(|j| &s.sites[j]);
        let seg = s.mesh.nodes[s.k].segment_end;
        let x = &s.x[s.k..s.k + 5];
        for derivatives in [false, true] {
            let mut jac = vec![0.0; 4 * BLOCK];
            let group = intervals4(
                profile,
                s.length,
                s.k,
                sites,
                seg,
                x,
                derivatives.then_some(&mut jac[..]),
            )
            .unwrap()?;
            for (j, lin) in group.iter().enumerate() {
                let mut block = vec![0.0; BLOCK];
                let one = interval(
                    alone,
                    s.length,
                    s.k + j,
                    sites[j],
                    seg,
                    &x[j],
                    &x[j + 1],
                    derivatives.then_some(&mut block[..]),
                )
                .unwrap();
                let grouped = if derivatives {
                    &jac[j * BLOCK..(j + 1) * BLOCK]
                } else {
                    &block[..]
                };
                assert_eq!(
                    bits(lin, grouped),
                    bits(&one, &block),
                    "link {} derivatives {derivatives}",
                    s.k + j
                );
                assert!(lin.psi.iter().any(|p| *p != 0.0) && (!derivatives || lin.rows_z.amax() > 0.0));
            }
        }
        Some(())
    }

    /// Each link of the group has the bits of the one-link kernel (the lanes compiled as
    /// the kernel is: for AVX2 where the processor has it), on friction S (the prototype,
    /// tendon 1 pulled), friction H (case H's helix pulled) and the helix released.
    #[test]
    fn group_gives_the_one_link_bits() {
        for robot in &crate::model::friction::friction_robots() {
            let (setup, model) = prepare(robot);
            let (p, alone) = (profile(&model, &setup), profile(&model, &setup));
            assert!(compare(&setup, &p, &alone).is_some());
        }
    }

    /// In a history (an elastic helix, grips on the mesh), every link goes to the group
    /// with the one-link bits, blocks and the stuck multipliers' columns included: links
    /// that slide with one multiplier, a stick zone on one of the four links (its
    /// multiplier the stuck fraction, its row the stick row), links that slide both ways,
    /// four stuck links each at its own multiplier and four at the same one; two tendons
    /// with friction (Newton's tangential loads) make the group decline.
    #[test]
    fn group_takes_stuck_and_sliding_history_links_and_declines_two_slips() {
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        h.tendons[4].stiffness = Some(2000.0);
        let (setup, model) = prepare(&h);
        let links = setup.mesh.nodes.len() - 1;
        let k = setup.k;
        // Capacities that differ from link to link (so do the stuck multipliers then) or
        // one for all.
        let grip = |contacts: Vec<Contact>, capacity: &dyn Fn(usize) -> f64| Grip {
            multipliers: contacts
                .iter()
                .map(|c| if *c == Contact::Release { 1.0 } else { -1.0 })
                .collect(),
            capacities: (0..links).map(capacity).collect(),
            reference: setup.x.iter().map(|n| 0.999 * (1.0 + 1e-3 * n.s)).collect(),
            kinks: Vec::new(),
            points: Vec::new(),
            contacts,
        };
        let varied = |n: usize| 0.05 + 0.01 * n as f64;
        let (mut p, mut alone) = (profile(&model, &setup), profile(&model, &setup));
        // Log tensions falling by a binary fraction per node: equal capacities give equal
        // stuck multipliers, bit for bit.
        for q in [&mut p, &mut alone] {
            for (n, z) in q.z[0].iter_mut().enumerate() {
                *z = -0.03125 * n as f64;
            }
        }
        let mut check = |contacts: Vec<Contact>, capacity: &dyn Fn(usize) -> f64| {
            p.grips = Some(vec![grip(contacts, capacity)]);
            alone.grips = p.grips.clone();
            let w: Vec<f64> = (k..k + 4).map(|n| p.multipliers(n).unwrap()[0]).collect();
            assert!(compare(&setup, &p, &alone).is_some(), "multipliers {w:?}");
            w
        };
        assert_eq!(check(vec![Contact::Pull; links], &varied), [-1.0; 4]);
        let mut contacts = vec![Contact::Pull; links];
        contacts[k + 2] = Contact::Stick;
        let w = check(contacts, &varied);
        assert!(w[2] != -1.0 && w[2] != 0.0 && w[3] == -1.0);
        // Links that all slide, one of them the other way (multiplier +1 among -1s).
        let mut contacts = vec![Contact::Pull; links];
        contacts[k + 3] = Contact::Release;
        assert_eq!(check(contacts, &varied), [-1.0, -1.0, -1.0, 1.0]);
        // Four stuck links, each at its own multiplier, then all at the same one.
        let w = check(vec![Contact::Stick; links], &varied);
        assert!((1..4).all(|l| w[l] != w[l - 1] && w[l] != 0.0));
        let w = check(vec![Contact::Stick; links], &|_| 0.05);
        assert!(w.iter().all(|x| *x == w[0] && *x != 0.0 && *x != -1.0));
        // Four stuck links with per-point multipliers (docs/friction.md section 8, "ord23"):
        // the material's interpolant given, each link evaluated once so that its shares are
        // kept, then the group against the links one by one.
        let mut stuck = grip(vec![Contact::Stick; links], &varied);
        // A material 10 % shorter than the path: stuck tensions of about 200 N.
        stuck.reference = setup.x.iter().map(|n| 0.9 * (1.0 + 1e-3 * n.s)).collect();
        stuck.points = (0..links)
            .map(|l| [2e-3, 0.5 * (stuck.reference[l] + stuck.reference[l + 1]), 2e-3, 2e-3])
            .collect();
        p.grips = Some(vec![stuck]);
        alone.grips = p.grips.clone();
        let seg = setup.mesh.nodes[k].segment_end;
        for q in [&p, &alone] {
            for l in 0..4 {
                let lin = interval(
                    q,
                    setup.length,
                    k + l,
                    &setup.sites[l],
                    seg,
                    &setup.x[k + l],
                    &setup.x[k + l + 1],
                    None,
                )
                .unwrap();
                q.keep(k + l, lin);
            }
        }
        // (The first link's start and midpoint give no finite share on this made-up state: it
        // keeps the constant multiplier.)
        assert!(p.sigma(0, k).is_none());
        for l in 1..4 {
            let sigma = p.sigma(0, k + l).expect("per-point shares kept");
            assert!(sigma[0] != sigma[1] && sigma[1] != sigma[2], "{sigma:?}");
        }
        assert!(compare(&setup, &p, &alone).is_some());

        let mut two = cases::case_h();
        two.tendons[4].friction = Some(Friction::pull(0.3));
        two.tendons[0].set_tension(1.5);
        two.tendons[0].friction = Some(Friction::pull(0.2));
        let (two_setup, model) = prepare(&two);
        let (p, alone) = (profile(&model, &two_setup), profile(&model, &two_setup));
        assert!(compare(&two_setup, &p, &alone).is_none());
    }

    /// A NaN in a log tension of a stuck link (its multiplier NaN): the group declines it,
    /// or with derivatives gives the error the one-link kernel gives at that link (where
    /// the rows at the moved multipliers are evaluated alone); a NaN in a node state: the
    /// group declines it, and the one-link kernel gives NaN rows or an error.
    #[test]
    fn group_declines_nan() {
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        h.tendons[4].stiffness = Some(2000.0);
        let (mut setup, model) = prepare(&h);
        let links = setup.mesh.nodes.len() - 1;
        let k = setup.k;
        let mut p = profile(&model, &setup);
        p.grips = Some(vec![Grip {
            multipliers: vec![-1.0; links],
            capacities: vec![0.05; links],
            reference: setup.x.iter().map(|n| 0.999 * (1.0 + 1e-3 * n.s)).collect(),
            kinks: Vec::new(),
            points: Vec::new(),
            contacts: vec![Contact::Stick; links],
        }]);
        let sites: [&IntervalSites; 4] = std::array::from_fn(|j| &setup.sites[j]);
        let seg = setup.mesh.nodes[k].segment_end;
        let group = |p: &Profile, x: &[State], derivatives: bool| {
            let mut jac = vec![0.0; 4 * BLOCK];
            intervals4(
                p,
                setup.length,
                k,
                sites,
                seg,
                &x[k..k + 5],
                derivatives.then_some(&mut jac[..]),
            )
            .map(|g| g.is_some())
        };
        let one = |p: &Profile, x: &[State], derivatives: bool| {
            let mut block = vec![0.0; BLOCK];
            let jac = derivatives.then_some(&mut block[..]);
            interval(p, setup.length, k + 1, sites[1], seg, &x[k + 1], &x[k + 2], jac)
        };
        p.z[0][k + 2] = f64::NAN;
        assert!(p.multipliers(k + 1).unwrap()[0].is_nan());
        assert!(matches!(group(&p, &setup.x, false), Ok(false)));
        let (grouped, alone) = (group(&p, &setup.x, true), one(&p, &setup.x, true));
        assert!(
            matches!((&grouped, &alone), (Err(a), Err(b)) if format!("{a:?}") == format!("{b:?}")),
            "{grouped:?}"
        );
        p.z[0][k + 2] = -0.1;
        setup.x[k + 2].u[1] = f64::NAN;
        for derivatives in [false, true] {
            assert!(matches!(group(&p, &setup.x, derivatives), Ok(false)));
            // Alone, the link gives NaN rows or eq. 13's breakdown at the NaN node, as its
            // points meet the NaN.
            if let Ok(alone) = one(&p, &setup.x, derivatives) {
                assert!(alone.residual.iter().any(|r| r.is_nan()));
            }
        }
    }
}
