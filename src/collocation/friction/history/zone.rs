//! Slip zones inside a stuck stretch (docs/friction.md section 8, "Slip zones inside a
//! stuck stretch"): where the march's stuck profile changes faster along s than friction
//! can hold (a stuck link with |w| > 1), the tendon slides at the full rate over a zone
//! that sticks at both ends, with no material crossing either end.
//!
//! On the mesh a zone is a *transition link* T, whose multiplier w_T in [-1, 1] is free
//! (its capstan row `z_b - z_a - w_T C`), then links sliding at the full rate sigma (the
//! sign of the steep stuck slope) up to the link where the clamp of the march sticks again
//! (the zone's end, an ordinary stuck link with |w| <= 1). w_T is the root of the zone's
//! material balance, `sum over the zone's nodes of (lambda^n - lambda^(n-1)) ds = 0` (the
//! trapezoidal rule of the slip check, [`super::slip`]): the slip d returns to 0 at its
//! start. A higher start tension lowers lambda^n at every node of the zone, so the balance
//! falls monotonically with w_T; where its root would need |w_T| > 1, T moves one link
//! toward the base. A zone that reaches the base zone with the base zone's direction
//! merges with it (a longer base zone); one that reaches the other way's base zone or an
//! earlier interior zone is refused, and so are zones of two tendons on one link
//! ([`overlap`]). The stuck tension a zone's balance reads moves with the node's own
//! tension by the own gain, with the other tendons that stick there answering
//! ([`Predictor`], `cross::couple`).

use super::*;

/// The stuck material's tension at a node as its own tension moves it, for the zone's
/// balance: `value` (N) on the shape solved with tension `solved` there, moving by `gain`
/// per unit of the node's tension ([`Profile::own_gain`], or with other tendons that stick
/// at the node the coupled gain of `cross::couple`, then through the node's joint answer;
/// 0 off a converged shape).
#[derive(Clone, Copy, Debug)]
pub(super) struct Predictor {
    /// The stuck tension on the current shape (N).
    pub(super) value: f64,
    /// Its change per unit of the node's own tension.
    pub(super) gain: f64,
    /// The node's tension the shape was solved with (N).
    pub(super) solved: f64,
}

/// One tendon's march result, which [`open`] turns into zones where a stuck link's
/// multiplier leaves the friction cone.
pub(super) struct Tendon<'a> {
    /// The links' contacts (the stuck stretch after the base zone all `Stick`).
    pub(super) contacts: &'a mut [Contact],
    /// The links' multipliers.
    pub(super) multipliers: &'a mut [f64],
    /// The links' capacities C.
    pub(super) capacities: &'a [f64],
    /// The log tensions at the nodes: the stuck stretch's the stuck material's (as the
    /// march chose them).
    pub(super) z: &'a mut [f64],
    /// The stuck-tension predictor at each node (None where not read).
    pub(super) predictors: &'a [Option<Predictor>],
    /// The carried material lambda^(n-1) at the nodes.
    pub(super) reference: &'a [f64],
    /// The nodes' arc lengths (m).
    pub(super) s: &'a [f64],
    /// E_t A_t (N).
    pub(super) stiffness: f64,
    /// The base tension (N).
    pub(super) base: f64,
    /// The base zone's contact (None or `Stick` where the tendon sticks from its base).
    pub(super) first: Option<Contact>,
    /// The march's tie width in log tension.
    pub(super) tie: f64,
}

/// A zone's path on the mesh from transition link `t` with multiplier `w`: its log
/// tensions at nodes t + 1 ..= end, its re-stick link (None: it reaches the termination)
/// and its material balance (m of unstretched tendon).
struct Run {
    z: Vec<f64>,
    restick: Option<usize>,
    balance: f64,
}

impl Tendon<'_> {
    /// The material node n gains in the step at log tension `z` (lambda^n - lambda^(n-1),
    /// per unit s), from the stuck tension's predictor: lambda^(n-1) (tau_stuck - tau) /
    /// (E_t A_t + tau).
    fn gained(&self, n: usize, z: f64) -> f64 {
        let tau = self.base * z.exp();
        let p = self.predictors[n].unwrap_or(Predictor {
            value: self.base * self.z[n].exp(),
            gain: 0.0,
            solved: tau,
        });
        let stuck = p.value + p.gain * (tau - p.solved);
        self.reference[n] * (stuck - tau) / (self.stiffness + tau)
    }

    /// Node n's weight in the trapezoidal rule of the slip check.
    fn weight(&self, n: usize) -> f64 {
        let before = if n > 0 { self.s[n] - self.s[n - 1] } else { 0.0 };
        let after = self.s.get(n + 1).map_or(0.0, |&b| b - self.s[n]);
        0.5 * (before + after)
    }

    /// The zone from transition link `t` with multiplier `w`, sliding the way `sigma`
    /// (+-1) after it, against the stuck profile `zeta` (the march's stuck log tensions).
    /// Where `t` starts at the end of the base zone sliding the other way (`adjacent`), the
    /// zone starts where the two meet inside it, a share (1 - sigma w) / 2 of the link
    /// from its start (its mean multiplier w), and the balance counts the link from there,
    /// with the material's change linear across it ([`super::slip::zone_start`]).
    fn run(&self, t: usize, w: f64, sigma: f64, zeta: &[f64], adjacent: bool) -> Run {
        let links = self.contacts.len();
        let mut zz = self.z[t] + w * self.capacities[t];
        let h = self.s[t + 1] - self.s[t];
        let gained = self.gained(t + 1, zz);
        let head = if adjacent {
            super::slip::zone_start(h, 0.5 * (1.0 - sigma * w), self.gained(t, self.z[t]), gained)
        } else {
            0.5 * h * gained
        };
        let after = self.s.get(t + 2).map_or(0.0, |&b| 0.5 * (b - self.s[t + 1]));
        let mut out = Run {
            z: vec![zz],
            restick: None,
            balance: head + after * gained,
        };
        let mut crossed = sigma * (zeta[t + 1] - zz) > 0.0;
        for m in t + 1..links {
            let full = zz + sigma * self.capacities[m];
            let ahead = sigma * (zeta[m + 1] - full);
            if crossed && ahead < self.tie {
                out.restick = Some(m);
                return out;
            }
            zz = full;
            crossed |= ahead > 0.0;
            out.z.push(zz);
            out.balance += self.weight(m + 1) * self.gained(m + 1, zz);
        }
        out
    }

    /// The root in w of the balance of the zone from link `t` between `from` (where the
    /// balance has sign -sigma or is 0) and `to`, by bisection to rounding.
    fn root(&self, t: usize, sigma: f64, (from, to): (f64, f64), zeta: &[f64], adjacent: bool) -> f64 {
        let (mut lo, mut hi) = (from, to);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                break;
            }
            if sigma * self.run(t, mid, sigma, zeta, adjacent).balance <= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

/// Opens a zone at every stuck link of `tendon` (tendon `i` of the robot) whose multiplier
/// leaves the friction cone (module docs), rewriting its contacts, multipliers and log
/// tensions.
///
/// # Errors
/// A zone that would reach the other way's base zone or an earlier zone, or one whose end
/// would be steep the other way (zones the march does not resolve).
pub(super) fn open(i: usize, tendon: &mut Tendon) -> Result<()> {
    let links = tendon.contacts.len();
    let Some(first_stuck) = tendon.contacts.iter().position(|&c| c == Contact::Stick) else {
        return Ok(());
    };
    let zeta = tendon.z.to_vec();
    // A base zone sliding the other way: the first zone may start inside it (the two
    // meet where the slip is 0, with no stuck point between them).
    let opposite =
        |contact: Contact| first_stuck > 0 && tendon.first.is_some_and(|f| f != contact && f != Contact::Stick);
    let mut lower = first_stuck;
    let mut k = first_stuck;
    while k < links {
        let step = tendon.z[k + 1] - tendon.z[k];
        if tendon.contacts[k] != Contact::Stick || step.abs() <= tendon.capacities[k] * (1.0 + super::slip::CONE) {
            k += 1;
            continue;
        }
        let sigma = step.signum();
        let contact = if sigma < 0.0 { Contact::Pull } else { Contact::Release };
        // The transition link and its multiplier: from the steep link toward the base, the
        // first whose bracket [sigma, w_stuck] holds the balance's root.
        let mut found = None;
        let bottom = if lower == first_stuck && opposite(contact) {
            1
        } else {
            lower
        };
        for t in (bottom..=k).rev() {
            let adjacent = t <= first_stuck && opposite(contact);
            if sigma * tendon.run(t, sigma, sigma, &zeta, adjacent).balance > 0.0 {
                continue;
            }
            let stuck = if t < first_stuck {
                -sigma
            } else {
                stuck_multiplier(tendon.z[t], zeta[t + 1], tendon.capacities[t]).clamp(-1.0, 1.0)
            };
            found = Some((t, tendon.root(t, sigma, (sigma, stuck), &zeta, adjacent), adjacent));
            break;
        }
        // Where no link down to the base zone holds the root, the zone reaches it: with
        // the base zone's direction it is a longer base zone; against it, it reaches the
        // base entry (searched down to link 0) and is the base zone, sliding its way from
        // there. Either way the slip keeps the zone's sign all along: no start from any
        // link balanced it.
        let merge = found.is_none()
            && lower == first_stuck
            && (first_stuck == 0
                || tendon.first == Some(contact)
                || tendon.first == Some(Contact::Stick)
                || opposite(contact));
        let (t, w, adjacent) = match found {
            Some(found) => found,
            None if merge && opposite(contact) => (0, sigma, false),
            None if merge => (first_stuck, sigma, false),
            None => {
                return Err(error::limit(
                    format!("tendons[{i}].friction"),
                    format!(
                        "tendon {}'s stuck stretch near s = {:.4} m would slip while stuck on both sides, and the \
                         slip zone that holds its material would reach {} before it, which the stick/slip history \
                         does not model",
                        i + 1,
                        tendon.s[k],
                        if lower == first_stuck {
                            "the base entry"
                        } else {
                            "another slip zone"
                        }
                    ),
                    format!(
                        "take the history in smaller steps; a full-slip solve ({}) gives the step without its \
                         history",
                        error::option_token(i, "motion")
                    ),
                ));
            }
        };
        let run = tendon.run(t, w, sigma, &zeta, adjacent);
        tendon.contacts[t] = contact;
        tendon.multipliers[t] = w;
        for (n, &zz) in run.z.iter().enumerate() {
            tendon.z[t + 1 + n] = zz;
            if t + 1 + n < links && Some(t + 1 + n) != run.restick {
                tendon.contacts[t + 1 + n] = contact;
                tendon.multipliers[t + 1 + n] = sigma;
            }
        }
        let Some(r) = run.restick else {
            return Ok(());
        };
        let w_r = stuck_multiplier(tendon.z[r], zeta[r + 1], tendon.capacities[r]);
        if w_r.abs() > 1.0 + tendon.tie / tendon.capacities[r].max(f64::MIN_POSITIVE) {
            return Err(error::limit(
                format!("tendons[{i}].friction"),
                format!(
                    "tendon {}'s slip zone near s = {:.4} m would end where its stuck stretch changes faster than \
                     friction can hold the other way (w = {}), which the stick/slip history does not model",
                    i + 1,
                    tendon.s[r],
                    error::near_one(w_r),
                ),
                "take the history in smaller steps",
            ));
        }
        tendon.contacts[r] = Contact::Stick;
        tendon.multipliers[r] = w_r;
        tendon.z[r + 1] = zeta[r + 1];
        lower = r + 1;
        k = r + 1;
    }
    Ok(())
}

/// Per link of a tendon's `contacts`, whether it lies in a slip zone inside the stuck
/// stretch: a sliding link after the base zone's run (the leading links that all have the
/// first link's contact).
pub(super) fn in_zone(contacts: &[Contact]) -> Vec<bool> {
    let base = contacts.first().copied();
    let mut left = false;
    contacts
        .iter()
        .map(|&c| {
            left |= Some(c) != base;
            left && matches!(c, Contact::Pull | Contact::Release)
        })
        .collect()
}

/// Refuses slip zones of two tendons over the same link (`grips` the tendons' patterns
/// after the march, `spans` their spans, `slipping` their robot indices, `s` the nodes'
/// arc lengths): each zone's balance is solved with the other tendon's tension held there
/// (docs/friction.md section 8, "opp25"), and the other's zone moves its stuck tension by
/// about as much as its own tension does (`cross::gain`), so the two balances form one
/// system, which the march does not solve: passes of march and Newton that solve each
/// alone alternate between patterns (measured on the opposite tendons' way back).
///
/// # Errors
/// Two tendons with a slip zone on one link.
pub(super) fn overlap(grips: &[Grip], spans: &[usize], slipping: &[usize], s: &[f64]) -> Result<()> {
    let zones: Vec<Vec<bool>> = grips
        .iter()
        .zip(spans)
        .map(|(g, &span)| in_zone(&g.contacts[..span]))
        .collect();
    for (a, za) in zones.iter().enumerate() {
        for (b, zb) in zones.iter().enumerate().skip(a + 1) {
            let Some(k) = (0..za.len().min(zb.len())).find(|&k| za[k] && zb[k]) else {
                continue;
            };
            return Err(error::limit(
                format!("tendons[{}].friction", slipping[b]),
                format!(
                    "tendons {} and {} would both slip while stuck on both sides near s = {:.4} m in this step: their \
                     slip zones lie on the same stretch, where each moves the other's stuck tension about as much as \
                     its own, which the stick/slip history does not model",
                    slipping[a] + 1,
                    slipping[b] + 1,
                    s[k]
                ),
                format!(
                    "see docs/friction.md section 8, \"opp25\": the history cannot go on past this step; a full-slip \
                     solve ({}) gives the step without its history",
                    error::option_token(slipping[b], "motion")
                ),
            ));
        }
    }
    Ok(())
}

/// The kinks of the material a step with slip zones inside its stuck stretch leaves
/// ([`Grip::kinks_after`] for a step without them): `contacts` on the nodes `s`, `new` the
/// material at the nodes where it moved (a node moved unless the link before it sticks),
/// `old(n)` the material before the step at node n with its kinks `before`. A kink where a
/// moved stretch meets a stuck one (at the first stuck link's start node, the sliding
/// side's value first, as the base zone's boundary), where a zone starts after a stuck
/// stretch (at the zone's first node after the link holding its start, the stuck side's
/// value first), where a zone starts inside the base zone sliding the other way (at the
/// start node of the link holding it, one value: only the slope jumps) and at the nodes
/// `others` inside moved stretches; `before`'s kinks inside the stretches that stuck. A
/// zone of a single node leaves no kinks of its own (its node's material is its own).
pub(super) fn kinks(
    contacts: &[Contact],
    s: &[f64],
    new: &[f64],
    old: &dyn Fn(usize) -> f64,
    before: &[Kink],
    others: &[f64],
) -> Vec<Kink> {
    let links = contacts.len();
    let stuck = |k: usize| k < links && contacts[k] == Contact::Stick;
    let moved = |n: usize| n == 0 || !stuck(n - 1);
    let mut out: Vec<Kink> = Vec::new();
    // The start of the stretch that stuck (exclusive), while in one.
    let mut kept: Option<f64> = None;
    let mut skip = None;
    for n in 0..links {
        if moved(n) && stuck(n) {
            if n > 0 && skip != Some(n) {
                out.push((s[n], new[n], old(n)));
            }
            kept = kept.or(Some(s[n]));
        } else if !moved(n) && !stuck(n) {
            // A zone starts inside link n, after a stuck stretch.
            let from = kept.take().unwrap_or(f64::NEG_INFINITY);
            out.extend(before.iter().copied().filter(|&(e, _, _)| e > from && e < s[n + 1]));
            if !stuck(n + 1) {
                out.push((s[n + 1], old(n + 1), new[n + 1]));
            }
            skip = Some(n + 1);
        } else if n > 0 && moved(n) && !stuck(n) && skip != Some(n) {
            let turned = !stuck(n - 1) && contacts[n - 1] != contacts[n];
            if turned || others.contains(&s[n]) {
                out.push((s[n], new[n], new[n]));
            }
        }
    }
    if let Some(from) = kept {
        out.extend(before.iter().copied().filter(|&(e, _, _)| e > from));
    }
    out
}
