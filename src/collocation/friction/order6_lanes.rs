//! Four consecutive links' order-6 rows with friction at once ([`intervals4_order6`]), for
//! the error estimate: each link's nodes and quarter stages by the one-link code's own
//! steps ([`Stages`]), then eq. 13 with friction at the four links' quarter stages, at
//! their three-quarter stages and at their midpoints, each in one pass of four f64 lanes
//! ([`linearize_lanes_into`], one link per lane), as the frictionless order-6 rows of
//! four intervals are evaluated (`collocation/order6.rs`, `intervals_order6_lanes`).
//!
//! A link's inner stages need only its own nodes, so the four links' stages of one kind
//! are independent points. Each lane performs the scalar code's operations in its order
//! on the inputs the one-link code reads (the link's own log tensions and multipliers, so
//! a stuck link's stage takes its own multiplier), so each link's rows have the bits of
//! [`super::interval_order6`] (the tests compare them). The group declines (the caller
//! evaluates the links one by one, which gives any error) where a node's evaluation
//! breaks down or a lane leaves the lanes' path.
#![allow(non_snake_case)]

use super::order6::{Order6, Stages, stage_rhs, stage_state};
use super::profile::Profile;
use crate::collocation::residual::{IntervalSites, QuarterSites};
use crate::model::equations::Site;
use crate::model::friction::FrictionLinearization;
use crate::simd::{avx2_fma, four};
use crate::solution::State;

/// Links k..k+4 with friction (`sites` and `quarters` theirs, one segment ending at
/// `segment_end`, `x` the five node states from node k on): their order-6 rows as
/// [`super::interval_order6`] gives each, or None where the group declines (module docs;
/// then evaluate them one by one).
///
/// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, with the lanes and
/// the one-link code's steps inlined: the same operations in the same order.
pub(crate) fn intervals4_order6(
    profile: &Profile,
    length: f64,
    k: usize,
    (sites, quarters): ([&IntervalSites; 4], [&QuarterSites; 4]),
    segment_end: f64,
    x: &[State],
) -> Option<[Order6; 4]> {
    avx2_fma!(kernel(profile, length, k, (sites, quarters), segment_end, x))
}

/// [`intervals4_order6`]'s operations.
#[inline(always)]
fn kernel(
    profile: &Profile,
    length: f64,
    k: usize,
    (sites, quarters): ([&IntervalSites; 4], [&QuarterSites; 4]),
    segment_end: f64,
    x: &[State],
) -> Option<[Order6; 4]> {
    if x.len() < 5 {
        return None;
    }
    let mut st = Vec::with_capacity(4);
    for j in 0..4 {
        match Stages::new(profile, k + j, sites[j], segment_end, (&x[j], &x[j + 1])) {
            Ok(s) => st.push(s),
            Err(_) => return decline(profile, st),
        }
    }
    let Ok::<[Stages; 4], _>(mut st) = st.try_into() else {
        return None;
    };
    let Rk = four!(j => &x[j].R);
    // The quarter stages, then the three-quarter stages, of the four links.
    let q_sites = four!(j => &quarters[j].quarter);
    let states = four!(j => stage_state(Rk[j], &st[j].y_q));
    let z = four!(j => &st[j].scratch.z_q[..]);
    let w = four!(j => st[j].w.as_deref());
    let Some(lins) = points4(profile, q_sites, segment_end, &states, z, w) else {
        return decline(profile, st.into());
    };
    let f_q = four!(j => {
        let t = &mut st[j];
        stage_rhs(q_sites[j], &states[j].0, &t.y_q, &lins[j], &mut t.scratch.turnings[2])
    });
    lins.into_iter().for_each(|l| profile.give(l));
    let tq_sites = four!(j => &quarters[j].three_quarters);
    let states = four!(j => stage_state(Rk[j], &st[j].y_tq));
    let z = four!(j => &st[j].scratch.z_tq[..]);
    let w = four!(j => st[j].w.as_deref());
    let Some(lins) = points4(profile, tq_sites, segment_end, &states, z, w) else {
        return decline(profile, st.into());
    };
    let f_tq = four!(j => {
        let t = &mut st[j];
        stage_rhs(tq_sites[j], &states[j].0, &t.y_tq, &lins[j], &mut t.scratch.turnings[3])
    });
    lins.into_iter().for_each(|l| profile.give(l));
    // The midpoints, from each link's quarter stages.
    let y_m = four!(j => st[j].mid(&f_q[j], &f_tq[j]));
    let m_sites = four!(j => &sites[j].mid);
    let states = four!(j => stage_state(Rk[j], &y_m[j]));
    let z = four!(j => &st[j].scratch.zm[..]);
    let w = four!(j => st[j].w.as_deref());
    let Some(lins) = points4(profile, m_sites, segment_end, &states, z, w) else {
        return decline(profile, st.into());
    };
    let f_m = four!(j => stage_rhs(m_sites[j], &states[j].0, &y_m[j], &lins[j], &mut st[j].scratch.turnings[4]));
    lins.into_iter().for_each(|l| profile.give(l));
    let [s0, s1, s2, s3] = st;
    let f = |j: usize| [&f_q[j], &f_tq[j], &f_m[j]];
    Some([
        s0.rows(profile, length, (sites[0], &x[1]), f(0)),
        s1.rows(profile, length, (sites[1], &x[2]), f(1)),
        s2.rows(profile, length, (sites[2], &x[3]), f(2)),
        s3.rows(profile, length, (sites[3], &x[4]), f(3)),
    ])
}

/// The group's decline: the links' buffers given back to the profile.
fn decline(profile: &Profile, stages: Vec<Stages>) -> Option<[Order6; 4]> {
    stages.into_iter().for_each(|s| profile.give_scratch(s.scratch));
    None
}

/// Eq. 13 with friction without derivatives at four points at once (`Profile::point` at
/// each: a site, a state, the slips at log tensions `z[l]` and multipliers `w[l]` in lane
/// l), in the profile's spare linearizations; None where the lanes decline them. One
/// function for the three stages, compiled for AVX2 and FMA where the processor has them
/// (checked at run time): inlined at each stage, the three copies of the lanes cost S's
/// order-6 rows 32 k instructions more (H's 88 k).
#[inline(never)]
fn points4(
    profile: &Profile,
    sites: [&Site; 4],
    segment_end: f64,
    states: &[(nalgebra::Matrix3<f64>, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>); 4],
    z: [&[f64]; 4],
    w: [Option<&[f64]>; 4],
) -> Option<[Box<FrictionLinearization>; 4]> {
    avx2_fma!(points4_kernel(profile, sites, segment_end, states, z, w))
}

/// [`points4`]'s operations: [`group::points4`](super::group::points4) without derivatives.
#[inline(always)]
fn points4_kernel(
    profile: &Profile,
    sites: [&Site; 4],
    segment_end: f64,
    states: &[(nalgebra::Matrix3<f64>, nalgebra::Vector3<f64>, nalgebra::Vector3<f64>); 4],
    z: [&[f64]; 4],
    w: [Option<&[f64]>; 4],
) -> Option<[Box<FrictionLinearization>; 4]> {
    let states = four!(j => (&states[j].0, &states[j].1, &states[j].2));
    super::group::points4(profile, sites, segment_end, states, z, w, (false, None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::collocation::friction::{Contact, Grip, interval_order6};
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::tendon::Friction;
    use crate::so3;
    use nalgebra::Vector3;

    /// A link's order-6 rows, capstan rows, node rates and the capstan rows the profile
    /// kept, as bits.
    fn bits(o: &Order6, kept: &[f64]) -> Vec<u64> {
        let (rows, psi, start, end) = o;
        let values = rows.iter().chain(psi).chain(start.iter()).chain(end.iter()).chain(kept);
        values.map(|x| x.to_bits()).collect()
    }

    /// `robot` solved on 8 intervals, its node states moved off the answer (a twist and a
    /// strain change growing along the rod), the first four links of one segment (their
    /// first index, interval and quarter sites, segment end) and its profile on that mesh
    /// with log tensions falling along it.
    struct Setup<'a> {
        model: Model<'a>,
        mesh: Mesh,
        x: Vec<State>,
        k: usize,
        sites: Vec<IntervalSites>,
        quarters: Vec<QuarterSites>,
    }

    fn prepare(robot: &crate::Robot) -> Setup<'_> {
        let solution = crate::solve(robot, &crate::collocation::Options::fixed(8)).unwrap();
        let model = Model::new(robot);
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(robot, &s).unwrap();
        let x = solution
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
        let sites: Vec<IntervalSites> = (k..k + 4)
            .map(|j| IntervalSites {
                start: model.site(nodes[j].s),
                mid: model.site(0.5 * (nodes[j].s + nodes[j + 1].s)),
                end: model.site(nodes[j + 1].s),
            })
            .collect();
        let quarters = sites
            .iter()
            .map(|s| {
                let h = s.end.s - s.start.s;
                QuarterSites {
                    quarter: model.site(s.start.s + 0.25 * h),
                    three_quarters: model.site(s.start.s + 0.75 * h),
                }
            })
            .collect();
        Setup {
            model,
            mesh,
            x,
            k,
            sites,
            quarters,
        }
    }

    impl<'a> Setup<'a> {
        fn profile(&self) -> Profile<'a> {
            let mut profile = Profile::new(&self.model, &self.mesh);
            for (j, z) in profile.z.iter_mut().enumerate() {
                for (n, value) in z.iter_mut().enumerate() {
                    *value = -0.03 * n as f64 * (j as f64 + 1.0);
                }
            }
            profile
        }

        /// The four links at once on `profile` against the one-link code on `alone` (the
        /// same profile): None where the group declines, which it must where a link's
        /// one-link evaluation fails; else the bits of every link asserted.
        fn compare(&self, profile: &Profile, alone: &Profile) -> Option<()> {
            let (k, length) = (self.k, self.model.robot.length());
            let seg = self.mesh.nodes[k].segment_end;
            let sites: [&IntervalSites; 4] = std::array::from_fn(|j| &self.sites[j]);
            let quarters: [&QuarterSites; 4] = std::array::from_fn(|j| &self.quarters[j]);
            let x = &self.x[k..k + 5];
            let group = intervals4_order6(profile, length, k, (sites, quarters), seg, x);
            let one: Vec<_> = (0..4)
                .map(|j| interval_order6(alone, length, k + j, sites[j], quarters[j], seg, &x[j], &x[j + 1]))
                .collect();
            if one.iter().any(|o| o.is_err()) {
                assert!(group.is_none(), "the group answers where the one-link code fails");
                return None;
            }
            let group = group?;
            for (j, (g, o)) in group.iter().zip(one).enumerate() {
                let o = o.unwrap();
                let kept = |p: &Profile| p.order6.borrow()[k + j].clone();
                assert_eq!(bits(g, &kept(profile)), bits(&o, &kept(alone)), "link {}", k + j);
                assert!(o.1.iter().any(|p| *p != 0.0), "link {} has capstan rows", k + j);
            }
            Some(())
        }
    }

    /// Each link of the group has the bits of the one-link code (the lanes compiled as the
    /// kernel is: for AVX2 where the processor has it) on friction S (the prototype, tendon 1
    /// pulled), friction H (case H's helix pulled) and the helix released.
    #[test]
    fn group_gives_the_one_link_bits() {
        for robot in &crate::model::friction::friction_robots() {
            let setup = prepare(robot);
            assert!(setup.compare(&setup.profile(), &setup.profile()).is_some());
        }
    }

    /// In a history (an elastic helix, grips on the mesh): the group takes links that slide
    /// either way and a stuck link (each lane its own link's multiplier; the stuck link's
    /// row the stick row) with the one-link bits.
    #[test]
    fn group_takes_mixed_contacts_with_the_one_link_bits() {
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        h.tendons[4].stiffness = Some(2000.0);
        let setup = prepare(&h);
        let links = setup.mesh.nodes.len() - 1;
        let mut contacts = vec![Contact::Pull; links];
        contacts[setup.k + 1] = Contact::Release;
        contacts[setup.k + 2] = Contact::Stick;
        let grip = Grip {
            multipliers: contacts
                .iter()
                .map(|c| if *c == Contact::Release { 1.0 } else { -1.0 })
                .collect(),
            capacities: vec![0.05; links],
            reference: setup.x.iter().map(|n| 0.999 * (1.0 + 1e-3 * n.s)).collect(),
            kinks: Vec::new(),
            points: Vec::new(),
            contacts,
        };
        let (mut p, mut alone) = (setup.profile(), setup.profile());
        p.grips = Some(vec![grip]);
        alone.grips = p.grips.clone();
        assert!(p.sticks(0, setup.k + 2));
        assert!(setup.compare(&p, &alone).is_some());
    }

    /// A NaN or an infinity in a node's state or log tension: the group declines where the
    /// one-link code fails (a curvature, a strain or a log tension that is not finite), and
    /// where that answers (a position that is not finite: rows that are not finite) it
    /// gives the one-link bits; on S, H and the helix released.
    #[test]
    fn group_with_nan_and_infinities_declines_or_gives_the_one_link_bits() {
        let (mut answered, mut declined) = (0, 0);
        for robot in &crate::model::friction::friction_robots() {
            let mut setup = prepare(robot);
            let (n, x) = (setup.k + 2, setup.x.clone());
            for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                // A node's curvature, its strain, a log tension at it, its position (which
                // eq. 13 does not read: the rows are not finite, the evaluation goes on).
                for what in 0..4 {
                    setup.x.clone_from(&x);
                    let (mut p, mut alone) = (setup.profile(), setup.profile());
                    match what {
                        0 => setup.x[n].u[1] = value,
                        1 => setup.x[n].v[2] = value,
                        2 => setup.x[n].p[0] = value,
                        _ => {
                            p.z[0][n] = value;
                            alone.z[0][n] = value;
                        }
                    }
                    match setup.compare(&p, &alone) {
                        Some(()) => answered += 1,
                        None => declined += 1,
                    }
                }
            }
        }
        // Both ways are seen: the cases are not all of one kind.
        assert!(answered > 0 && declined > 0, "answered {answered}, declined {declined}");
    }
}
