//! The other tendons' share of a stuck tension in the march (docs/friction.md section 8,
//! "Opposite tendons"): a step's inputs and the march's choices move the tendons' tensions
//! at a node from those the shape was solved with, and each change moves every stuck
//! tension there.

use super::super::grip::Stuck;
use super::{Contact, Profile, State};
use crate::model::equations::Site;
use nalgebra::{DMatrix, DVector, Vector3};

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
    /// Whether the link lies in one of its slip zones inside the stuck stretch on the
    /// pattern the shape was solved with: its tension there is the zone's, held at
    /// `solved` in the node's solve (the march sticks it, and the zone, opened after the
    /// march, moves it by the zone's balance, not by the node's answer).
    pub(super) held: bool,
}

/// The node's joint solve (docs/friction.md section 8, "Opposite tendons"): each loaded
/// slip's stuck tension at the link's end `b` (at `site`), `stuck_at[j]` (N, already at its
/// own fixed point, `read[j]` its value and derivatives), moved by the other slips' changes
/// of tension there from those the shape was solved with, `tau*_j += sum_l g_jl dtau_l /
/// (1 - g_jj)`, where the changes are the node's own answer: every loaded slip's tension is
/// its stuck one where it sticks and a bound of its link (`z_a -+ C`) where it slides, each
/// as [`choose`](super::super::grip::choose) (without the tie) and `before[j]` allow, and an unloaded one's 0. The
/// system is a box complementarity problem whose matrix (the identity less the scaled
/// cross gains) is a positive diagonal times a symmetric positive definite one, so its
/// answer is unique; it is found by block principal pivoting ([`Node::pivot`]: a few small
/// solves), or where that fails by trying each loaded slip's three cases (in, stuck, out),
/// 3^n small solves for n loaded slips on the link. Slips not loaded or not read are left.
/// A slip `held` in one of its slip zones keeps the tension the shape was solved with
/// there (both bounds at it).
///
/// Each loaded slip j that sticks in the node's answer gets in `coupled[j]` its stuck
/// tension's gain in its own tension with the others answering (a slip zone's balance reads
/// it, [`super::zone::Predictor`]): the stuck material's tension moves by g_jj per unit of
/// j's tension and by g_jl per unit of slip l's, and each other slip that sticks there
/// moves with j's tension as the node's system says (those sliding at a bound of their link
/// do not), so `g_eff = g_jj + sum_l g_jl dtau_l / dtau_j` (about -1 N/N for two opposite
/// tendons on the prototype, against g_jj = -30: the other tendon's answer nearly cancels
/// the own gain, docs/friction.md section 8, "opp25").
pub(super) fn couple(
    profile: &Profile,
    site: &Site,
    b: &State,
    read: &[Option<Stuck>],
    before: &[Before],
    stuck_at: &mut [f64],
    coupled: &mut [Option<f64>],
) {
    let loaded: Vec<usize> = (0..read.len())
        .filter(|&j| read[j].is_some() && stuck_at[j].is_finite())
        .collect();
    // Every slip on the link changes its tension: a loaded one by the node's answer, an
    // unloaded one (slack) to 0.
    let slack: Vec<usize> = (0..read.len())
        .filter(|&l| before[l].on && profile.base[l] == 0.0)
        .collect();
    if loaded.is_empty() || loaded.len() + slack.len() < 2 {
        return;
    }
    let n = loaded.len();
    // gains[a][c]: loaded slip a's stuck tension per N of loaded slip c's (0 on the
    // diagonal, which `stuck_at` holds already); fixed[a]: the unloaded slips' share.
    let mut gains = vec![vec![0.0; n]; n];
    let mut fixed = vec![0.0; n];
    let mut owns = vec![0.0; n];
    for (a, &j) in loaded.iter().enumerate() {
        let Some((_, d_v, d_u)) = read[j] else {
            continue;
        };
        let g = |l: usize| gain(profile, profile.slipping[l], site, b, &d_v, &d_u);
        let own = g(j);
        owns[a] = own;
        for (c, &l) in loaded.iter().enumerate() {
            if l != j && before[l].solved.is_finite() {
                gains[a][c] = g(l) / (1.0 - own);
            }
        }
        fixed[a] = slack
            .iter()
            .filter(|&&l| l != j && before[l].solved.is_finite())
            .map(|&l| g(l) * -before[l].solved)
            .sum::<f64>()
            / (1.0 - own);
    }
    // Each loaded slip's bounds (N): sliding in below `low`, out above `high`; a slip
    // stuck on an earlier link has neither, one whose first link slid one way only that
    // way's (the other way it sticks).
    let bounds: Vec<(f64, f64)> = loaded
        .iter()
        .map(|&j| {
            let w = &before[j];
            let base = profile.base[j];
            let (low, high) = (base * (w.za - w.capacity).exp(), base * (w.za + w.capacity).exp());
            match (w.stuck, w.first) {
                _ if w.held => (w.solved, w.solved),
                (true, _) => (f64::NEG_INFINITY, f64::INFINITY),
                (false, Some(Contact::Pull)) => (low, f64::INFINITY),
                (false, Some(Contact::Release)) => (f64::NEG_INFINITY, high),
                _ => (low, high),
            }
        })
        .collect();
    let node = Node {
        solved: loaded.iter().map(|&j| before[j].solved).collect(),
        alone: loaded.iter().map(|&j| stuck_at[j]).collect(),
        bounds,
        gains,
        fixed,
    };
    let Some(tau) = node.pivot().or_else(|| node.enumerate()) else {
        return;
    };
    for (a, &j) in loaded.iter().enumerate() {
        stuck_at[j] = node.stuck_of(a, &tau);
    }
    // The slips that stick in the answer (a sliding one's tension is its bound, exactly).
    let sticking: Vec<bool> = (0..n)
        .map(|a| tau[a] != node.bounds[a].0 && tau[a] != node.bounds[a].1)
        .collect();
    for (a, &j) in loaded.iter().enumerate() {
        if sticking[a] || before[j].held {
            coupled[j] = node.coupled_gain(a, owns[a], &sticking);
        }
    }
}

/// The node's box complementarity problem ([`couple`]) for n loaded slips: each slip's
/// tension is its stuck one, `stuck_of`, clamped to its `bounds`.
struct Node {
    /// Each slip's bounds (N), infinite where it cannot slide that way.
    bounds: Vec<(f64, f64)>,
    /// The tensions (N) the shape was solved with.
    solved: Vec<f64>,
    /// gains[a][c]: slip a's stuck tension per N of slip c's (0 on the diagonal).
    gains: Vec<Vec<f64>>,
    /// The unloaded slips' share of each stuck tension (N).
    fixed: Vec<f64>,
    /// Each stuck tension alone, at its own fixed point (N).
    alone: Vec<f64>,
}

/// Most case changes of [`Node::pivot`] before it gives up (to the enumeration): a
/// principal pivoting method on a P-matrix ends in at most a few on these nodes (two
/// tendons: at most 2); 50 bounds the work of any node with a handful of tendons.
const PIVOTS: usize = 50;

impl Node {
    /// Slip a's stuck tension (N) when the slips' tensions are `tau`.
    fn stuck_of(&self, a: usize, tau: &[f64]) -> f64 {
        self.alone[a]
            + self.fixed[a]
            + (0..tau.len())
                // A zero gain (also that of a slip whose solved tension is not finite) adds
                // nothing: skipped, so that 0 x inf does not make every case NaN.
                .filter(|&c| c != a && self.gains[a][c] != 0.0)
                .map(|c| self.gains[a][c] * (tau[c] - self.solved[c]))
                .sum::<f64>()
    }

    /// Slip a's stuck tension's gain in its own tension (own gain `own`, g_aa) with the
    /// other slips that are `sticking` answering ([`couple`]): their changes solve
    /// `(I - G_SS) dtau_S = G_Sa dtau_a` (G the scaled gains, each row already at its own
    /// fixed point), and slip a's unscaled cross gains are `(1 - g_aa) G_ac`. None where
    /// that system is singular.
    fn coupled_gain(&self, a: usize, own: f64, sticking: &[bool]) -> Option<f64> {
        let others: Vec<usize> = (0..sticking.len()).filter(|&c| c != a && sticking[c]).collect();
        if others.is_empty() {
            return Some(own);
        }
        let m = others.len();
        let matrix = DMatrix::from_fn(m, m, |r, c| {
            let (x, y) = (others[r], others[c]);
            if x == y { 1.0 } else { -self.gains[x][y] }
        });
        let rhs = DVector::from_fn(m, |r, _| self.gains[others[r]][a]);
        let response = matrix.lu().solve(&rhs)?;
        let moved: f64 = others
            .iter()
            .zip(response.iter())
            .map(|(&c, r)| self.gains[a][c] * r)
            .sum();
        Some(own + (1.0 - own) * moved)
    }

    /// How far slip a's tension `tau` (of the case `case`) is from its complementarity
    /// condition: 0 where it holds.
    fn violation(&self, a: usize, case: usize, tau: &[f64]) -> f64 {
        let f = self.stuck_of(a, tau);
        let (low, high) = self.bounds[a];
        match case {
            // A held slip (equal bounds): its tension is given, whatever its stuck one.
            0 | 2 if low == high => 0.0,
            0 => (f - low).max(0.0),
            2 => (high - f).max(0.0),
            _ => (low - f).max(0.0) + (f - high).max(0.0),
        }
    }

    /// Whether slip a may take case `case` (not a bound that is infinite).
    fn allowed(&self, a: usize, case: usize) -> bool {
        !((case == 0 && self.bounds[a].0 == f64::NEG_INFINITY) || (case == 2 && self.bounds[a].1 == f64::INFINITY))
    }

    /// The answer by block principal pivoting (Judice and Pires' method for a box
    /// complementarity problem with a P-matrix): from each slip's own choice (its stuck
    /// tension alone clamped to its bounds), the tensions of the case; every slip whose
    /// condition fails (a stuck tension beyond a bound, a bound its stuck tension does not
    /// reach) changes its case, all at once while that lowers the count of failing slips
    /// and, after three changes that did not, only the first (Murty's least index rule,
    /// which ends for a P-matrix). A condition holds to 1e-12 of the tension (rounding).
    /// None after [`PIVOTS`] changes or on a singular case.
    fn pivot(&self) -> Option<Vec<f64>> {
        let n = self.alone.len();
        let mut case: Vec<usize> = (0..n)
            .map(|a| {
                let f = self.alone[a] + self.fixed[a];
                let (low, high) = self.bounds[a];
                if f < low || low == high {
                    0
                } else if f > high {
                    2
                } else {
                    1
                }
            })
            .collect();
        let (mut fewest, mut stalled) = (n + 1, 0);
        for _ in 0..PIVOTS {
            let tau = tensions(&case, &self.bounds, &self.solved, &self.gains, &self.fixed, &self.alone)?;
            let failing: Vec<usize> = (0..n)
                .filter(|&a| self.violation(a, case[a], &tau) > 1e-12 * (1.0 + tau[a].abs()))
                .collect();
            if failing.is_empty() {
                return Some(tau);
            }
            if failing.len() < fewest {
                (fewest, stalled) = (failing.len(), 0);
            } else {
                stalled += 1;
            }
            let change = if stalled < 3 { &failing[..] } else { &failing[..1] };
            for &a in change {
                let f = self.stuck_of(a, &tau);
                let low = self.bounds[a].0;
                case[a] = match case[a] {
                    1 if f < low => 0,
                    1 => 2,
                    _ => 1,
                };
                if !self.allowed(a, case[a]) {
                    return None;
                }
            }
        }
        None
    }

    /// The answer by trying every case (3^n): the one with the least violation (0 for the
    /// answer; rounding may leave a little). The fallback of [`Node::pivot`], and its check.
    fn enumerate(&self) -> Option<Vec<f64>> {
        let n = self.alone.len();
        let mut best: Option<(f64, Vec<f64>)> = None;
        let mut case = vec![0; n];
        for code in 0..3usize.pow(n as u32) {
            // case[a]: 0 slides in (at low), 1 sticks, 2 slides out (at high).
            let mut rest = code;
            for c in &mut case {
                *c = rest % 3;
                rest /= 3;
            }
            if (0..n).any(|a| !self.allowed(a, case[a])) {
                continue;
            }
            let Some(tau) = tensions(&case, &self.bounds, &self.solved, &self.gains, &self.fixed, &self.alone) else {
                continue;
            };
            let violation: f64 = (0..n).map(|a| self.violation(a, case[a], &tau)).sum();
            if violation.is_finite() && best.as_ref().is_none_or(|(v, _)| violation < *v) {
                best = Some((violation, tau));
            }
        }
        best.map(|(_, tau)| tau)
    }
}

/// The loaded slips' tensions (N) at the node for one case per slip (0: at its low bound,
/// 1: stuck, 2: at its high bound): the stuck ones solve
/// `tau_a - sum_c gains[a][c] (tau_c - solved_c) = stuck[a] + fixed[a]` with the others at
/// their bounds. None where that system is singular.
fn tensions(
    case: &[usize],
    bounds: &[(f64, f64)],
    solved: &[f64],
    gains: &[Vec<f64>],
    fixed: &[f64],
    stuck: &[f64],
) -> Option<Vec<f64>> {
    let n = case.len();
    let mut tau: Vec<f64> = (0..n)
        .map(|a| match case[a] {
            0 => bounds[a].0,
            2 => bounds[a].1,
            _ => 0.0,
        })
        .collect();
    let free: Vec<usize> = (0..n).filter(|&a| case[a] == 1).collect();
    if free.is_empty() {
        return Some(tau);
    }
    let m = free.len();
    let matrix = DMatrix::from_fn(m, m, |r, c| {
        let (a, e) = (free[r], free[c]);
        if a == e { 1.0 } else { -gains[a][e] }
    });
    let rhs = DVector::from_fn(m, |r, _| {
        let a = free[r];
        stuck[a]
            + fixed[a]
            + (0..n)
                .filter(|&c| gains[a][c] != 0.0)
                .map(|c| {
                    if case[c] == 1 {
                        -gains[a][c] * solved[c]
                    } else {
                        gains[a][c] * (tau[c] - solved[c])
                    }
                })
                .sum::<f64>()
    });
    let x = matrix.lu().solve(&rhs)?;
    for (r, &a) in free.iter().enumerate() {
        tau[a] = x[r];
    }
    Some(tau)
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

#[cfg(test)]
mod tests {
    use super::Node;
    use nalgebra::DMatrix;

    /// A small linear congruential generator: uniform numbers in [0, 1), reproducible.
    struct Uniform(u64);

    impl Uniform {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }

        fn between(&mut self, low: f64, high: f64) -> f64 {
            low + (high - low) * self.next()
        }
    }

    /// A random node of n slips whose matrix has the structure of the march's (docs/
    /// friction.md section 8): I - G = D^-1 (D + B^T B) with D a positive diagonal, rows
    /// scaled to a unit diagonal (G's diagonal is folded into the stuck tensions), so a
    /// P-matrix; random bounds (some infinite on one side or both), stuck tensions and
    /// solved tensions.
    fn node(n: usize, random: &mut Uniform) -> Node {
        let b = DMatrix::from_fn(n, n, |_, _| random.between(-1.5, 1.5));
        let d: Vec<f64> = (0..n).map(|_| random.between(0.2, 2.0)).collect();
        let mut m = b.transpose() * &b;
        for a in 0..n {
            m[(a, a)] += d[a];
            for c in 0..n {
                m[(a, c)] /= d[a];
            }
        }
        let gains = (0..n)
            .map(|a| {
                (0..n)
                    .map(|c| if a == c { 0.0 } else { -m[(a, c)] / m[(a, a)] })
                    .collect()
            })
            .collect();
        let bounds = (0..n)
            .map(|_| {
                let low = random.between(-1.0, 3.0);
                let high = low + random.between(0.0, 2.0);
                match (random.next() * 6.0) as usize {
                    0 => (f64::NEG_INFINITY, high),
                    1 => (low, f64::INFINITY),
                    2 => (f64::NEG_INFINITY, f64::INFINITY),
                    _ => (low, high),
                }
            })
            .collect();
        Node {
            bounds,
            solved: (0..n).map(|_| random.between(0.0, 5.0)).collect(),
            gains,
            fixed: (0..n).map(|_| random.between(-0.5, 0.5)).collect(),
            alone: (0..n).map(|_| random.between(-3.0, 6.0)).collect(),
        }
    }

    #[test]
    fn a_stuck_slips_coupled_gain_is_its_stuck_tensions_slope_with_the_others_answering() {
        // The slope of slip a's stuck material's tension in its own tension, measured by
        // holding a's tension (both bounds at it) a little either side of the node's answer
        // and solving the node again, against `coupled_gain`. That material's tension is
        // (1 - g_aa) stuck_of(a) + g_aa tau_a (stuck_of is at a's own fixed point).
        let mut random = Uniform(25);
        let mut checked = 0;
        for n in 2..=4 {
            for _ in 0..300 {
                let node = node(n, &mut random);
                let own = random.between(-40.0, 0.0);
                let Some(tau) = node.pivot() else { continue };
                let case = |tau: &[f64], bounds: &[(f64, f64)]| -> Vec<bool> {
                    (0..n).map(|c| tau[c] != bounds[c].0 && tau[c] != bounds[c].1).collect()
                };
                let sticking = case(&tau, &node.bounds);
                for a in (0..n).filter(|&a| sticking[a]) {
                    let delta = 1e-6 * (1.0 + tau[a].abs());
                    let material = |held: f64| -> Option<(f64, Vec<bool>)> {
                        let mut moved = Node {
                            bounds: node.bounds.clone(),
                            solved: node.solved.clone(),
                            gains: node.gains.clone(),
                            fixed: node.fixed.clone(),
                            alone: node.alone.clone(),
                        };
                        moved.bounds[a] = (held, held);
                        let t = moved.pivot()?;
                        let mut cases = case(&t, &node.bounds);
                        cases[a] = true;
                        Some(((1.0 - own) * moved.stuck_of(a, &t) + own * t[a], cases))
                    };
                    let (Some((up, cu)), Some((down, cd))) = (material(tau[a] + delta), material(tau[a] - delta))
                    else {
                        panic!("a held slip's node is solved");
                    };
                    // Skip a slip whose small move changes another slip's case (a kink of
                    // the slope, not its value).
                    if cu != sticking || cd != sticking {
                        continue;
                    }
                    let slope = (up - down) / (2.0 * delta);
                    let gain = node
                        .coupled_gain(a, own, &sticking)
                        .expect("a P-matrix's block is regular");
                    // The node's tensions are linear in the held one while no case changes:
                    // the central difference is exact but for rounding (1e-16 / 1e-6 times
                    // the gains, below 1e-7 of 40)
                    assert!(
                        (slope - gain).abs() <= 1e-6 * (1.0 + gain.abs()),
                        "n = {n}, slip {a}: measured {slope}, coupled_gain {gain}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 300, "{checked} slips checked");
    }

    #[test]
    fn pivoting_finds_the_enumerations_answer_on_random_p_matrices() {
        let mut random = Uniform(24);
        for n in 1..=4 {
            for trial in 0..500 {
                let node = node(n, &mut random);
                let pivoted = node.pivot().expect("pivoting ends on a P-matrix");
                let enumerated = node.enumerate().expect("one case is the answer");
                for (a, (p, e)) in pivoted.iter().zip(&enumerated).enumerate() {
                    // 1e-9 of the tension: the same case solved by the same LU, or a
                    // degenerate tie (a stuck tension at its bound) decided by rounding
                    assert!(
                        (p - e).abs() <= 1e-9 * (1.0 + e.abs()),
                        "n = {n}, trial {trial}, slip {a}: pivoting {pivoted:?}, enumeration {enumerated:?}"
                    );
                }
                // The answer holds every slip's condition (to rounding: 1e-12 of it).
                for a in 0..n {
                    let case = match pivoted[a] {
                        t if t == node.bounds[a].0 => 0,
                        t if t == node.bounds[a].1 => 2,
                        _ => 1,
                    };
                    let violation = node.violation(a, case, &pivoted);
                    assert!(
                        violation <= 1e-12 * (1.0 + pivoted[a].abs()),
                        "n = {n}, trial {trial}: {violation}"
                    );
                }
            }
        }
    }
}
