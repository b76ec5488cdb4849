//! The stick/slip state of the tendons with friction during a step of a load history
//! (docs/friction.md section 8): each link's contact (sliding in, sliding out or stuck), the
//! friction multiplier of the backbone's tangential load, the carried material (lambda),
//! the stuck material's tension on a shape, and the Coulomb choice on one link.

use super::interval::Profile;
use crate::model::equations::Site;
use crate::solution::State;
use nalgebra::{Vector3, Vector6};

/// How the tension of a tendon with friction evolves on a stretch of it during a step of a
/// load history (docs/friction.md section 8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Sliding toward the actuator, as while pulled in: the tension falls toward the
    /// termination at the full friction rate (multiplier w = -1).
    Pull,
    /// Sliding toward the termination, as while let out: the tension rises toward the
    /// termination at the full friction rate (w = +1).
    Release,
    /// Stuck to its channel: the material has not moved since the last step, and the
    /// tension follows from its elastic stretch (|w| <= 1 + TIE / C: a tie within the
    /// march's TIE of the friction limit sticks).
    Stick,
    /// Unloaded (0 N at its base entry): no tension, so no normal force on the channel and
    /// nothing for friction to hold; the material is reset to its current path
    /// (docs/friction.md section 8).
    Slack,
}

impl Contact {
    /// The name the command line and files use: `pull`, `release`, `stick` or `slack`.
    pub fn name(self) -> &'static str {
        match self {
            Contact::Pull => "pull",
            Contact::Release => "release",
            Contact::Stick => "stick",
            Contact::Slack => "slack",
        }
    }
}

/// The stick/slip choice on one link of a history (docs/friction.md section 8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Choice {
    /// Slide in, slide out or stick.
    pub(crate) contact: Contact,
    /// zeta_b = ln(tau_stuck / tau(0)), the stuck material's log tension at the link's end
    /// (-infinity where it would be slack, +infinity for a rigid tendon stretched).
    pub(crate) zeta: f64,
    /// The multiplier w this choice gives the link: -1, +1, or where it sticks
    /// (zeta_b - z_a) / C, the stuck profile's share of the friction it can hold.
    pub(crate) multiplier: f64,
}

/// Where the stuck profile and a sliding one agree to this in log tension (relative
/// tension) at a link's end, the link sticks (nothing needs to slide): a tie decided by
/// rounding alternates between passes. A converged stick row resolves its log tension to
/// about 1e-13 to 4e-12 (measured on the pull-in history's trials, docs/friction.md
/// section 8, "Ties"), and a pull-in loop sees the tie as a jump of its pull-in of
/// TIE tau times the sliding slope (2e-12 m on the prototype), below its resolution.
const TIE: f64 = 1e-10;

/// The tie width of [`choose`] for Newton's `residual_tolerance`: [`TIE`] at the default
/// (1e-11) and below; a looser tolerance resolves the stick rows only to about itself, so
/// the width grows with it (ten times it: a margin over the 0.4 times measured at 1e-11).
pub(crate) fn tie(residual_tolerance: f64) -> f64 {
    TIE.max(10.0 * residual_tolerance)
}

/// The Coulomb choice on a link: with base tension `base`, log tension `za` at its start,
/// capacity `capacity` (C) and the stuck material's tension `stuck` at its end, the tension
/// there is `z_b = z_a + clamp(zeta_b - z_a, -C, C)`: it sticks where friction can hold the
/// stuck profile (to `tie`, from [`tie`]: nothing needs to slide), else slides the way the stuck
/// tension lies (above: out, below: in). An unloaded tendon (base 0) is slack (its
/// multiplier +1 as before it had its own name: its tension, 0, carries no load).
pub(crate) fn choose(base: f64, za: f64, capacity: f64, stuck: f64, tie: f64) -> Choice {
    if base == 0.0 {
        return Choice {
            contact: Contact::Slack,
            zeta: f64::NEG_INFINITY,
            multiplier: 1.0,
        };
    }
    let zeta = if stuck > 0.0 {
        (stuck / base).ln()
    } else {
        f64::NEG_INFINITY
    };
    let t = zeta - za;
    let (contact, multiplier) = if t <= -capacity - tie {
        (Contact::Pull, -1.0)
    } else if t >= capacity + tie {
        (Contact::Release, 1.0)
    } else {
        (Contact::Stick, stuck_multiplier(za, zeta, capacity))
    };
    Choice {
        contact,
        zeta,
        multiplier,
    }
}

/// The multiplier of a stuck link with log tensions `za`, `zb` at its ends and capacity
/// `capacity`: the share of the friction it can hold that the stuck profile uses.
pub(crate) fn stuck_multiplier(za: f64, zb: f64, capacity: f64) -> f64 {
    if capacity > 0.0 { (zb - za) / capacity } else { 0.0 }
}

/// The stick/slip state of one tendon with friction on a mesh during a history step.
#[derive(Clone, Debug)]
pub(crate) struct Grip {
    /// Per link of its span, how its tension evolves there.
    pub(crate) contacts: Vec<Contact>,
    /// Per link, the friction multiplier w of the backbone's tangential load: -1 or +1
    /// where it slides, the stick profile's tau' / (mu tau kappa) where it sticks.
    pub(crate) multipliers: Vec<f64>,
    /// Per link, its capacity C (the most friction can change the log tension across it)
    /// at the last march.
    pub(crate) capacities: Vec<f64>,
    /// Per node, lambda: the unstretched length of tendon per unit s of the material there
    /// at the end of the last step (docs/friction.md section 8); NaN before the first step
    /// and, on the history's mesh, past the tendon's termination for the whole history (no
    /// material: the march, the slip check and the kinks read the nodes up to it).
    pub(crate) reference: Vec<f64>,
    /// The kinks of that material, in increasing s: each where an earlier step's stick/slip
    /// boundary left one, still inside the stretch that has stuck since, or where another
    /// tendon's stick/slip boundary lay while this one slid ([`Grip::kinks_after`]), as (s
    /// in m, lambda just before it, lambda just after it). Between them lambda is smooth, so it is
    /// interpolated from one piece's nodes and bounding kinks only (docs/friction.md
    /// section 8, "The material's kinks").
    pub(crate) kinks: Vec<Kink>,
    /// Per link of a split mesh, the carried material's interpolant there: (lambda' at
    /// its start, lambda at its midpoint, lambda' there, lambda' at its end), from the
    /// smooth piece that holds the link, for the stuck links' per-point multipliers
    /// ([`Profile::stuck_slope`]); empty where not given (the history's own mesh: a stuck
    /// link's multiplier is constant across it there).
    pub(crate) points: Vec<[f64; 4]>,
}

/// A kink of the carried material: its arc length (m), and lambda at it as the smooth
/// piece before it and the one after it have it. The two agree at a kink laid where another
/// tendon's boundary lay (only the slope jumps there) and at a stick/slip boundary the step
/// placed exactly; a boundary misplaced by delta leaves a jump of order delta
/// between the sliding side's material and the stuck side's (docs/friction.md section 8).
pub(crate) type Kink = (f64, f64, f64);

impl Grip {
    /// The start links of its slip zones other than the base zone (docs/friction.md
    /// section 8, "Slip zones inside a stuck stretch"): a sliding link after a stuck one
    /// or after one sliding the other way (a zone starting inside it where the base zone
    /// ends). Empty where the tendon slides
    /// from its base and then sticks, as the march leaves it without zones.
    pub(crate) fn zone_starts(&self) -> Vec<usize> {
        let sliding = |c: Contact| matches!(c, Contact::Pull | Contact::Release);
        (0..self.contacts.len())
            .filter(|&t| sliding(self.contacts[t]) && t > 0 && self.contacts[t - 1] != self.contacts[t])
            .collect()
    }

    /// The stick/slip boundary of these contacts: the start node of the first stuck link
    /// after a sliding one (None where the tendon slides all along or sticks all along).
    pub(crate) fn boundary(&self) -> Option<usize> {
        self.contacts
            .iter()
            .position(|&c| c == Contact::Stick)
            .filter(|&k| k > 0)
    }

    /// The kinks of the material a step leaves, whose solved `contacts` on the nodes `s`
    /// of its mesh give `lambda` at those nodes, started from this grip's material
    /// (`reference` on the same nodes, the stuck stretch's material): the step's stick/slip
    /// boundary (the start node of its first stuck link after a sliding one), with the
    /// material the sliding stretch leaves there before it and the stuck material after it,
    /// then this material's kinks beyond it (its stuck stretch kept them; the sliding
    /// stretch replaced the material, and with it the kinks). The material the sliding
    /// stretch lays is smooth but where another tendon's stick/slip boundary lies (the
    /// points `others`, nodes of `s`): that tendon's tangential load jumps there, and with
    /// it the rate of the rod's strains and so of this tendon's path speed; each such node
    /// inside the sliding stretch is a kink too, with the same lambda on both sides
    /// (docs/friction.md section 8, "hist20"). A tendon that slides all along leaves only
    /// those; one stuck all along keeps its kinks. A slack tendon (no stuck link) records
    /// them too, harmlessly: its material is laid afresh when it next takes load, sliding
    /// in all along.
    pub(crate) fn kinks_after(&self, contacts: &[Contact], s: &[f64], lambda: &[f64], others: &[f64]) -> Vec<Kink> {
        let first = contacts.iter().position(|&c| c == Contact::Stick);
        let mut laid: Vec<Kink> = (1..first.unwrap_or(contacts.len()))
            .filter(|&n| others.contains(&s[n]))
            .map(|n| (s[n], lambda[n], lambda[n]))
            .collect();
        let Some(first) = first else {
            return laid;
        };
        let boundary = s[first];
        laid.extend((first > 0).then_some((boundary, lambda[first], self.reference[first])));
        laid.into_iter()
            .chain(self.kinks.iter().copied().filter(|&(e, _, _)| e > boundary))
            .collect()
    }
}

/// A stuck material's tension (N) and its derivatives in a node's v and u.
pub(crate) type Stuck = (f64, Vector3<f64>, Vector3<f64>);

impl Profile<'_> {
    /// Slip j's tension (N) at node state `b` (arc length b.s) if the material there had
    /// not moved since the last step of a history: E_t A_t (|p_j'| / lambda - 1) with
    /// lambda the carried unstretched length per unit s at node `node` (docs/friction.md
    /// section 8), and its derivative in (v, u) (none in v on a Kirchhoff rod of `site`). A rigid tendon has +-infinity (its
    /// stuck material cannot stretch) and no derivative.
    pub(crate) fn stuck_tension(
        &self,
        j: usize,
        node: usize,
        site: &Site,
        b: &State,
        length: f64,
    ) -> (f64, Vector3<f64>, Vector3<f64>) {
        let robot = self.robot();
        let tendon = &robot.tendons[self.slipping[j]];
        let Some(grip) = self.grips.as_ref().map(|g| &g[j]) else {
            return (f64::NAN, Vector3::zeros(), Vector3::zeros());
        };
        let rp = tendon.routing.at(b.s, length);
        // The path sees the strain: v* on a Kirchhoff rod, whose coordinate v is the force's.
        let p = b.u.cross(&rp.r) + rp.r_s + site.strain(&b.v);
        let speed = p.norm();
        let lambda = grip.reference[node];
        let Some(stiffness) = tendon.stiffness else {
            let sign = (speed - lambda).signum();
            return (sign * f64::INFINITY, Vector3::zeros(), Vector3::zeros());
        };
        let t = p / speed;
        let scale = stiffness / lambda;
        let d_v = if site.inextensible { Vector3::zeros() } else { t * scale };
        (stiffness * (speed / lambda - 1.0), d_v, rp.r.cross(&t) * scale)
    }

    /// The stuck material's log-tension slope zeta' = tau_stuck' / tau_stuck (1/m) of slip
    /// j at a point (`site`, strains `(v, u)`, eq. 13's rates `rates` there with the
    /// tangential load `load` (N/m) it was evaluated with), the material there `lambda`
    /// with slope `slope` (docs/friction.md section 8, "ord23"). With the path speed
    /// `|p'|` and tangent t of the tendon (body frame),
    /// `tau_stuck' = E_t A_t (t . p'' / lambda - |p'| lambda' / lambda^2)`, and
    /// `t . p'' = t . (v' + u' x r + u x r' + r'')` falls with the tendon's own tangential
    /// load g by `s g`, `s = e . M^-1 e` (e = (t, r x t)), so the stuck profile's own load
    /// solves `g = A (t . p''|_0 - s g) - B`. `s` is taken from the section's stiffness,
    /// `t . K_se^-1 t + (r x t) . K_bt^-1 (r x t)`, as [`Profile::stuck_own`] does: the rates
    /// evaluated with `load` give `t . p''|_0 = t . p'' + s load` to that approximation, and
    /// where `load` is the stuck profile's own (a settled lag) the answer is exact whatever
    /// `s`. NaN for a rigid tendon or a stuck tension that is not positive.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn stuck_slope(
        &self,
        j: usize,
        site: &Site,
        (v, u): (&Vector3<f64>, &Vector3<f64>),
        rates: &Vector6<f64>,
        load: f64,
        (lambda, slope): (f64, f64),
        length: f64,
    ) -> f64 {
        let tendon = &self.robot().tendons[self.slipping[j]];
        let Some(stiffness) = tendon.stiffness else {
            return f64::NAN;
        };
        let rp = tendon.routing.at(site.s, length);
        let p = u.cross(&rp.r) + rp.r_s + site.strain(v);
        let speed = p.norm();
        let t = p / speed;
        let x_v = if site.inextensible {
            Vector3::zeros()
        } else {
            Vector3::new(rates[0], rates[1], rates[2])
        };
        let x_u = Vector3::new(rates[3], rates[4], rates[5]);
        let along = t.dot(&(x_v + x_u.cross(&rp.r) + u.cross(&rp.r_s) + rp.r_ss));
        let section = &site.section.section;
        let m = rp.r.cross(&t);
        let own = if site.inextensible {
            0.0
        } else {
            t.dot(&t.component_div(&section.kse))
        } + m.dot(&m.component_div(&section.kbt));
        let a = stiffness / lambda;
        let b = stiffness * speed * slope / (lambda * lambda);
        let g = (a * (along + own * load) - b) / (1.0 + a * own);
        let stuck = stiffness * (speed / lambda - 1.0);
        if stuck > 0.0 { g / stuck } else { f64::NAN }
    }

    /// The stuck tension at a node as the node's own tension moves it: `stuck`
    /// ([`Profile::stuck_tension`] at the node, with its derivatives in v and u) on a shape
    /// solved with tension `solved` there, carried to the tension at which the two agree,
    /// which is what the link's stick row settles on (docs/friction.md section 8, "The
    /// march's own tension"). The tendon's tension tau at s is part of the cross-section's
    /// load: raising it by dtau shortens the rod by dv = -K_se^-1 t dtau and bends it toward
    /// the tendon by du = -K_bt^-1 (r x t) dtau, with t the path's unit tangent and r the
    /// tendon's offset (body frame), so the stuck tension changes by
    /// g dtau, g = -(d_v . K_se^-1 d_v + d_u . K_bt^-1 d_u) / (E_t A_t / lambda) <= 0
    /// (about -E_t A_t r^2 / (E I), -30 on the prototype with E_t A_t = 2000 N). The two
    /// agree at (stuck - g solved) / (1 - g). A slack or rigid stuck tension (not finite or
    /// not positive) is returned as it is.
    pub(crate) fn stuck_own(&self, j: usize, node: usize, site: &Site, stuck: &Stuck, solved: f64) -> f64 {
        let value = stuck.0;
        if !(value.is_finite() && value > 0.0 && solved.is_finite()) {
            return value;
        }
        match self.own_gain(j, node, site, stuck) {
            Some(gain) => (value - gain * solved) / (1.0 - gain),
            None => value,
        }
    }

    /// The gain g <= 0 of [`Profile::stuck_own`]: how much the stuck tension at a node
    /// (`stuck`, with its derivatives in v and u) moves per unit of the node's own tension
    /// (None for a rigid tendon or a material that is not positive).
    pub(crate) fn own_gain(&self, j: usize, node: usize, site: &Site, stuck: &Stuck) -> Option<f64> {
        let (_, d_v, d_u) = *stuck;
        let tendon = &self.robot().tendons[self.slipping[j]];
        let lambda = self.grips.as_ref().map_or(f64::NAN, |g| g[j].reference[node]);
        let stiffness = tendon.stiffness?;
        // (NaN past the termination: no material.)
        if lambda.is_nan() || lambda <= 0.0 {
            return None;
        }
        let section = &site.section.section;
        let compliance = d_v.dot(&d_v.component_div(&section.kse)) + d_u.dot(&d_u.component_div(&section.kbt));
        Some(-compliance * lambda / stiffness)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tie_sticks_and_a_choice_beyond_it_slides() {
        let (base, za, capacity) = (2.0, -0.1, 0.05);
        let at = |t: f64| choose(base, za, capacity, base * (za + t).exp(), tie(1e-11)).contact;
        // Just inside the capacity plus the tie (the log tension is rounded to about 1e-16
        // relative here, far inside 0.5 TIE): both sides stick.
        assert_eq!(at(-capacity - 0.5 * TIE), Contact::Stick);
        assert_eq!(at(capacity + 0.5 * TIE), Contact::Stick);
        // Twice the tie beyond: the link slides, in below and out above.
        assert_eq!(at(-capacity - 2.0 * TIE), Contact::Pull);
        assert_eq!(at(capacity + 2.0 * TIE), Contact::Release);
        // The width is TIE at the default residual tolerance and grows with a looser one.
        assert_eq!(tie(1e-11), TIE);
        assert_eq!(tie(1e-8), 1e-7);
        assert_eq!(choose(0.0, 0.0, capacity, 1.0, TIE).contact, Contact::Slack);
    }
}
