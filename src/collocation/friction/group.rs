//! Four consecutive links with friction at once ([`intervals4`]): eq. 13 with friction at
//! their four end nodes, then at their four midpoints, each in one pass of four f64 lanes
//! ([`linearize_lanes_into`], one link per lane), the rest of each link's evaluation by
//! the one-link kernel's own code ([`front`] and [`back`]), as the frictionless block of
//! four intervals does (`collocation/interval_lanes.rs`).
//!
//! Link k's start is link k-1's end, and its midpoint's state needs only its own nodes,
//! so the four links' ends and then their midpoints are independent points. Each lane
//! performs the scalar code's operations in its order, and every link reads the same
//! inputs as when the links are evaluated one by one (the start node's evaluation that
//! the link before kept is the lanes' end node of that link), so each link's evaluation
//! has the one-link kernel's bits (the tests compare them). Where the profile keeps the
//! responses to the inertia loads (the Jacobian at the answer, for the verdict), the lanes
//! give them too. The group declines (the caller evaluates the links one by one) where the
//! links' multipliers differ, a slip sticks on one of them, or a lane leaves the lanes'
//! path.
#![allow(non_snake_case)]

use super::grip::Contact;
use super::interval::{IntervalLinearization, Link, back, front, node_tensions};
use super::profile::{LinkScratch, Profile};
use crate::collocation::dynamics::inertia_load_transposed;
use crate::collocation::residual::IntervalSites;
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
/// A model breakdown at node k (the one point evaluated alone, as the first link does).
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

/// [`intervals4`]'s operations.
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
    if x.len() < 5 {
        return Ok(None);
    }
    if !slides_alike(profile, k) {
        return Ok(None);
    }
    // What the lanes decline whatever the states (two or more tendons with friction) is
    // declined before any point is evaluated; a Kirchhoff rod's sites decline in the lanes,
    // which keep the start node's evaluation for the one-link kernel.
    if profile.slipping.len() > 1 {
        return Ok(None);
    }
    let w = profile.multipliers(k);
    let w = w.as_deref();
    let derivatives = jac.is_some();
    let mut scratch: [Box<LinkScratch>; 4] = [
        profile.take_scratch(),
        profile.take_scratch(),
        profile.take_scratch(),
        profile.take_scratch(),
    ];
    for (j, s) in scratch.iter_mut().enumerate() {
        node_tensions(profile, k + j, s);
    }
    let la = profile.start_point(k, &sites[0].start, segment_end, &x[0], &scratch[0].za, w, derivatives)?;
    let state = |n: usize| (&x[n].R, &x[n].v, &x[n].u);
    // Where the profile keeps the responses to the inertia loads (a Jacobian at the answer),
    // the lanes give them at the points [`back`] keeps them for: each link's start (the
    // link before's end) and midpoint.
    let responding = profile.responding.get().filter(|_| derivatives);
    let inertia = |site: [&Site; 4], R: [&Matrix3<f64>; 4]| {
        responding.map(|(ratio, length)| std::array::from_fn(|j| inertia_load_transposed(site[j], R[j], ratio, length)))
    };
    let Some(ends) = points4(
        profile,
        sites.map(|s| &s.end),
        segment_end,
        [state(1), state(2), state(3), state(4)],
        [&scratch[0].zb, &scratch[1].zb, &scratch[2].zb, &scratch[3].zb],
        w,
        (
            derivatives,
            inertia(sites.map(|s| &s.end), [&x[1].R, &x[2].R, &x[3].R, &x[4].R]),
        ),
    ) else {
        // The start node's evaluation is kept for the one-link kernel that takes over.
        profile.keep_point(k, segment_end, &x[0], &scratch[0].za, w, derivatives, la);
        scratch.into_iter().for_each(|s| profile.give_scratch(s));
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
        w,
    };
    let links = [link(0), link(1), link(2), link(3)];
    let starts = [&*la, &*ends[0], &*ends[1], &*ends[2]];
    let [s0, s1, s2, s3] = &mut scratch;
    let [mut p0, mut p1, mut p2, mut p3] = [None, None, None, None];
    let fronts = [
        front(&links[0], starts[0], &ends[0], derivatives, s0, &mut p0),
        front(&links[1], starts[1], &ends[1], derivatives, s1, &mut p1),
        front(&links[2], starts[2], &ends[2], derivatives, s2, &mut p2),
        front(&links[3], starts[3], &ends[3], derivatives, s3, &mut p3),
    ];
    let mid = |j: usize| (&fronts[j].Rm, &fronts[j].vm, &fronts[j].um);
    let Some(mids) = points4(
        profile,
        sites.map(|s| &s.mid),
        segment_end,
        [mid(0), mid(1), mid(2), mid(3)],
        [&scratch[0].zm, &scratch[1].zm, &scratch[2].zm, &scratch[3].zm],
        w,
        (
            derivatives,
            inertia(
                sites.map(|s| &s.mid),
                [&fronts[0].Rm, &fronts[1].Rm, &fronts[2].Rm, &fronts[3].Rm],
            ),
        ),
    ) else {
        profile.give(la);
        ends.into_iter().for_each(|l| profile.give(l));
        scratch.into_iter().for_each(|s| profile.give_scratch(s));
        return Ok(None);
    };
    let mut blocks = jac.map(|jac| jac[..4 * BLOCK].chunks_exact_mut(BLOCK));
    let mut block = || blocks.as_mut().and_then(Iterator::next);
    let [f0, f1, f2, f3] = &fronts;
    let [s0, s1, s2, s3] = &mut scratch;
    let out = [
        back(&links[0], f0, [starts[0], &mids[0], &ends[0]], block(), s0),
        back(&links[1], f1, [starts[1], &mids[1], &ends[1]], block(), s1),
        back(&links[2], f2, [starts[2], &mids[2], &ends[2]], block(), s2),
        back(&links[3], f3, [starts[3], &mids[3], &ends[3]], block(), s3),
    ];
    let [e0, e1, e2, e3] = ends;
    profile.keep_point(k + 4, segment_end, &x[4], &scratch[3].zb, w, derivatives, e3);
    for lin in [la, e0, e1, e2].into_iter().chain(mids) {
        profile.give(lin);
    }
    scratch.into_iter().for_each(|s| profile.give_scratch(s));
    Ok(Some(out))
}

/// Whether links k..k+4 of `profile` share one sliding pattern, which the group requires:
/// no slip sticks on any of them and each slip's multiplier is the same on all four (then
/// [`Profile::multipliers`] of each link is the same list). Read in place, no multipliers
/// formed: in a history the caller asks at each link of a stick zone and of its
/// neighbours, so the test is on the one-link path's bill (docs/benchmarks.md, fricfix20).
fn slides_alike(profile: &Profile, k: usize) -> bool {
    let Some(grips) = &profile.grips else {
        return true;
    };
    grips.iter().all(|g| {
        let w = |n: usize| g.multipliers.get(n).copied().unwrap_or(1.0);
        (k..k + 4).all(|n| g.contacts.get(n) != Some(&Contact::Stick)) && (k + 1..k + 4).all(|n| w(n) == w(k))
    })
}

/// Eq. 13 with friction at four points at once ([`Profile::point`] at each: the slips at
/// log tensions `z[l]` in lane l, multipliers `w`), in the profile's spare linearizations,
/// with derivatives when `derivatives.0` and the responses to the loads `derivatives.1`
/// when given; None where the lanes decline them.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn points4(
    profile: &Profile,
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
    z: [&[f64]; 4],
    w: Option<&[f64]>,
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
        [w; 4],
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

    /// In a history (an elastic helix, grips on the mesh): links that slide with one
    /// multiplier go to the group with the one-link bits; a stick zone on one of the four
    /// links (its multiplier then the stuck fraction, its row the stick row), a link that
    /// slides the other way, and two tendons with friction (Newton's tangential loads) make
    /// the group decline.
    #[test]
    fn group_takes_sliding_history_links_and_declines_a_stick_zone_and_two_slips() {
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        h.tendons[4].stiffness = Some(2000.0);
        let (setup, model) = prepare(&h);
        let links = setup.mesh.nodes.len() - 1;
        let grip = |contacts: Vec<Contact>| Grip {
            multipliers: contacts
                .iter()
                .map(|c| if *c == Contact::Release { 1.0 } else { -1.0 })
                .collect(),
            capacities: vec![0.05; links],
            reference: setup.x.iter().map(|n| 0.999 * (1.0 + 1e-3 * n.s)).collect(),
            kinks: Vec::new(),
            contacts,
        };
        let (mut p, mut alone) = (profile(&model, &setup), profile(&model, &setup));
        p.grips = Some(vec![grip(vec![Contact::Pull; links])]);
        alone.grips = p.grips.clone();
        assert!(compare(&setup, &p, &alone).is_some());
        let mut contacts = vec![Contact::Pull; links];
        contacts[setup.k + 2] = Contact::Stick;
        p.grips = Some(vec![grip(contacts)]);
        alone.grips = p.grips.clone();
        assert!(p.sticks(0, setup.k + 2));
        assert!(compare(&setup, &p, &alone).is_none());
        // Links that all slide, one of them the other way (multiplier +1 among -1s).
        let mut contacts = vec![Contact::Pull; links];
        contacts[setup.k + 3] = Contact::Release;
        p.grips = Some(vec![grip(contacts)]);
        alone.grips = p.grips.clone();
        assert!(!p.sticks(0, setup.k + 3));
        assert!(compare(&setup, &p, &alone).is_none());

        let mut two = cases::case_h();
        two.tendons[4].friction = Some(Friction::pull(0.3));
        two.tendons[0].set_tension(1.5);
        two.tendons[0].friction = Some(Friction::pull(0.2));
        let (two_setup, model) = prepare(&two);
        let (p, alone) = (profile(&model, &two_setup), profile(&model, &two_setup));
        assert!(compare(&two_setup, &p, &alone).is_none());
    }
}
