//! The other tendons' share of a stuck tension in the march (docs/friction.md section 8,
//! "Opposite tendons"): a step's inputs and the march's choices move the tendons' tensions
//! at a node from those the shape was solved with, and each change moves every stuck
//! tension there.

use super::super::grip::{Stuck, choose};
use super::{Contact, Profile, State};
use crate::model::equations::Site;
use nalgebra::Vector3;

/// The gain g_jl (N/N) of slip j's stuck tension at a node (state `b` at `site`), with
/// derivatives `d_v`, `d_u` in the node's v and u, in the tension of tendon `l` (robot
/// index): that tension is part of the cross-section's load, so raising it by dtau shortens
/// the rod by K_se^-1 t_l dtau and bends it by K_bt^-1 (r_l x t_l) dtau, with t_l the
/// path's unit tangent and r_l the offset (about -E_t A_t r_j . r_l / (E I): negative for
/// a tendon on the same side, positive for one on the opposite side; l = j is the own gain
/// of `Profile::stuck_own`).
pub(super) fn gain(profile: &Profile, l: usize, site: &Site, b: &State, d_v: &Vector3<f64>, d_u: &Vector3<f64>) -> f64 {
    let robot = profile.robot();
    let rp = robot.tendons[l].routing.at(b.s, robot.length());
    let p = b.u.cross(&rp.r) + rp.r_s + site.strain(&b.v);
    let t = p / p.norm();
    let section = &site.section.section;
    // No v on a Kirchhoff rod: the stuck tension does not depend on it (d_v = 0).
    let along = if site.inextensible {
        0.0
    } else {
        d_v.dot(&t.component_div(&section.kse))
    };
    -(along + d_u.dot(&rp.r.cross(&t).component_div(&section.kbt)))
}

/// What the march knows of slip j on a link before the link's choices: its log tension
/// `za` at the link's start, the link's capacity, its tension at the link's end that the
/// shape was solved with, whether it must stick there (stuck before, or its first link slid
/// the other way than `first`), and whether the link is on its span.
pub(super) struct Before {
    /// z at the link's start.
    pub(super) za: f64,
    /// The link's capacity C.
    pub(super) capacity: f64,
    /// The tension (N) at the link's end that the shape was solved with.
    pub(super) solved: f64,
    /// Stuck on an earlier link.
    pub(super) stuck: bool,
    /// The way its first link slid, if it has been chosen.
    pub(super) first: Option<Contact>,
    /// Whether its span includes the link.
    pub(super) on: bool,
}

/// One Jacobi step of the node's system (docs/friction.md section 8, "Opposite tendons"):
/// each loaded slip's stuck tension at the link's end `b` (at `site`), `stuck_at[j]` (N,
/// already at its own fixed point, `read[j]` its value and derivatives), moved by the other
/// slips' changes of tension there, each from the one the shape was solved with to the one
/// its own choice ([`choose`] with `tie`, `before[j]`) gives (an unloaded one's to 0):
/// `tau*_j += sum_l g_jl dtau_l / (1 - g_jj)`. Slips not loaded or not read are left.
pub(super) fn couple(
    profile: &Profile,
    site: &Site,
    b: &State,
    read: &[Option<Stuck>],
    before: &[Before],
    stuck_at: &mut [f64],
    tie: f64,
) {
    let loaded: Vec<usize> = (0..read.len())
        .filter(|&j| read[j].is_some() && stuck_at[j].is_finite())
        .collect();
    // Every slip on the link changes its tension: a loaded one by its choice, an unloaded
    // one (slack) to 0.
    let sources: Vec<usize> = (0..read.len())
        .filter(|&l| before[l].on && (loaded.contains(&l) || profile.base[l] == 0.0))
        .collect();
    if loaded.is_empty() || sources.len() < 2 {
        return;
    }
    let change: Vec<f64> = sources
        .iter()
        .map(|&l| {
            let (base, w) = (profile.base[l], &before[l]);
            if base == 0.0 {
                return -w.solved;
            }
            let choice = choose(base, w.za, w.capacity, stuck_at[l], tie);
            let forced = w.stuck || w.first.is_some_and(|c| c != choice.contact);
            let zb = if forced || choice.contact == Contact::Stick {
                choice.zeta
            } else {
                w.za + choice.multiplier * w.capacity
            };
            base * zb.exp() - w.solved
        })
        .collect();
    let moved: Vec<f64> = loaded
        .iter()
        .map(|&j| {
            let Some((_, d_v, d_u)) = read[j] else {
                return stuck_at[j];
            };
            let own = gain(profile, profile.slipping[j], site, b, &d_v, &d_u);
            let shift: f64 = sources
                .iter()
                .zip(&change)
                .filter(|&(&l, dtau)| l != j && dtau.is_finite())
                .map(|(&l, dtau)| gain(profile, profile.slipping[l], site, b, &d_v, &d_u) * dtau)
                .sum();
            stuck_at[j] + shift / (1.0 - own)
        })
        .collect();
    for (&j, value) in loaded.iter().zip(moved) {
        stuck_at[j] = value;
    }
}

/// Slip j's stuck tension at node `node` (state `b` at `site`) for this step's base
/// tensions, read on a shape solved with the base tensions `solved` of every tendon (the
/// first march of a step, on the last step's shape), where `stuck` is the one that shape
/// gives: to first order in the changes of tension, the fixed point
/// `tau* = stuck + sum_l g_jl dtau_l + g_jj (tau* - tau_solved)`, with each other tendon's
/// change that of its base (a tendon with friction's times the carried exp(z) at the node;
/// none from a tendon that ends before it). A rigid tendon's (not finite) is returned as it is.
pub(super) fn stuck_moved(
    profile: &Profile,
    j: usize,
    node: usize,
    site: &Site,
    b: &State,
    stuck: &Stuck,
    solved: &[f64],
) -> f64 {
    let robot = profile.robot();
    let length = robot.length();
    let (value, d_v, d_u) = stuck;
    let i = profile.slipping[j];
    if !value.is_finite() {
        return *value;
    }
    let tension_at = |l: usize, base: f64| {
        profile
            .slipping
            .iter()
            .position(|&m| m == l)
            .map_or(base, |m| base * profile.z[m][node].exp())
    };
    let mut moved = *value;
    for (l, tendon) in robot.tendons.iter().enumerate() {
        let frictionless = !profile.slipping.contains(&l);
        if frictionless && tendon.tension() != solved[l] && b.s <= tendon.end(length) {
            moved += gain(profile, l, site, b, d_v, d_u) * (tension_at(l, tendon.tension()) - tension_at(l, solved[l]));
        }
    }
    let own = gain(profile, i, site, b, d_v, d_u);
    (moved - own * tension_at(i, solved[i])) / (1.0 - own)
}
