//! Coulomb's law checked on a step's answer (docs/friction.md section 8, "Limits"): every
//! stretch of a tendon slides the way its friction acts, every slip zone inside a stuck
//! stretch holds its material, and friction can hold every stuck link.

use crate::collocation::friction::*;

/// How far a stuck link's |w| may exceed 1 before its stretch is refused: w is the link's
/// mean of the stuck profile's tau' / (mu tau kappa), exact but for Simpson's rule in its
/// capacity C (relative error below 1e-6 on the meshes a history uses) and the tie width of
/// the stick/slip choice (1e-10 in z over capacities of 1e-5 and more), so 1e-4 is far above
/// both and far below a violation that matters.
pub(super) const CONE: f64 = 1e-4;

/// How far a slip zone inside a stuck stretch may leave its material balance, relative to
/// the unstretched length of the zone: the march accepts the zone's transition multiplier
/// once it moves by less than the tie (1e-10 in log tension) between passes, and a zone's
/// slip moves by tau / (E_t A_t + tau) (1 + |g|) of its log tensions' change per unit
/// length, with the stuck tension's own gain |g| about E_t A_t r^2 / (E I) (30 on the
/// prototype): 1e-10 times 31 is 3.1e-9, so 1e-8 is above it and far below a slip that
/// matters (the zones' slips are 1e-5 to 1e-3 of their length).
pub(super) const BALANCE: f64 = 1e-8;

/// The slip a zone's start gains over the rest of its link, of length `h`: the zone
/// starts a share `theta` of the link from its start, and the material's change per unit
/// s there is linear between `start` (at the link's start) and `end` (at its end), the
/// trapezoidal rule on the part of the link from the zone's start.
pub(super) fn zone_start(h: f64, theta: f64, start: f64, end: f64) -> f64 {
    let at = start + theta * (end - start);
    0.5 * (1.0 - theta) * h * (at + end)
}

/// Checks that every stretch of tendon `i` slides the way its friction acts (Coulomb's
/// direction): the slip since the last step, d(s) = xi_new(s) - xi_old(s) with xi the
/// unstretched length from s to the termination (trapezoidal rule on the nodes), is <= 0
/// on links sliding in and >= 0 on links sliding out. Every slip zone inside the stuck
/// stretch (docs/friction.md section 8, "Slip zones inside a stuck stretch") holds its
/// material: its slip is 0 at its start to [`BALANCE`] of its length (where it starts
/// inside the base zone sliding the other way, at the point of its transition link its
/// mean multiplier gives, [`zone_start`]), and the direction check allows that over the
/// zone. And every stuck link's multiplier w = (z_b - z_a) / C lies in [-1, 1] to
/// [`CONE`] (the march opens a zone beyond it).
///
/// # Errors
/// The direction violated beyond rounding and `slack` (m), a zone's balance missed, or a
/// stuck link's |w| above 1 + [`CONE`].
pub(super) fn check_slip(i: usize, grip: &Grip, lambda: &[f64], x: &[State], span: usize, slack: f64) -> Result<()> {
    let mut d = vec![0.0; span + 1];
    let mut size = 0.0_f64;
    for k in (0..span).rev() {
        let h = x[k + 1].s - x[k].s;
        let change = |n: usize| lambda[n] - grip.reference[n];
        d[k] = d[k + 1] + 0.5 * h * (change(k) + change(k + 1));
        size = size.max(d[k].abs());
    }
    // Rounding of the sums: 1e-12 of the largest slip, and of the span's length at 1e-15.
    let tolerance = 1e-12 * size + 1e-15 * x[span].s + slack;
    // Each slip zone inside the stuck stretch (a sliding link after a stuck one): no
    // material crosses its start, so its slip returns to 0 there (its end is stuck too).
    let mut balanced = vec![0.0; span + 1];
    let mut adjacent = vec![false; span];
    let sliding = |c: Contact| matches!(c, Contact::Pull | Contact::Release);
    for t in (0..span).filter(|&t| sliding(grip.contacts[t])) {
        let w = grip.multipliers[t];
        // A zone after a stuck link, or one that starts inside link t where the base zone
        // sliding the other way ends (after a link sliding the other way).
        let after_stuck = t > 0 && grip.contacts[t - 1] == Contact::Stick;
        let after_base = t > 0 && sliding(grip.contacts[t - 1]) && grip.contacts[t - 1] != grip.contacts[t];
        if !after_stuck && !after_base {
            continue;
        }
        let end = (t..span).find(|&k| grip.contacts[k] == Contact::Stick).unwrap_or(span);
        let zone: f64 = (t..end)
            .map(|k| 0.5 * (x[k + 1].s - x[k].s) * (lambda[k] + lambda[k + 1]))
            .sum();
        let allowed = BALANCE * zone + tolerance;
        let sigma = if grip.contacts[t] == Contact::Pull { -1.0 } else { 1.0 };
        let start = if after_stuck {
            d[t]
        } else {
            let change = |n: usize| lambda[n] - grip.reference[n];
            d[t + 1] + zone_start(x[t + 1].s - x[t].s, 0.5 * (1.0 - sigma * w), change(t), change(t + 1))
        };
        adjacent[t] = after_base && !after_stuck;
        if start.abs() > allowed {
            return Err(error::limit(
                format!("tendons[{i}].friction"),
                format!(
                    "tendon {}'s slip zone from s = {:.4} m to {:.4} m does not hold its material in this step (it \
                     moves {:.3e} m across its start, allowed {allowed:.1e} m), which the stick/slip history does \
                     not resolve",
                    i + 1,
                    x[t].s,
                    x[end].s,
                    start
                ),
                "take the history in smaller steps",
            ));
        }
        // The balance's residual moves the slip over the whole zone.
        for b in &mut balanced[t..=end] {
            *b = f64::max(*b, allowed);
        }
    }
    // Where a zone starts inside a link after the base zone sliding the other way, the
    // link's start belongs to the base zone (checked as the end of the link before).
    for t in (0..span).filter(|&t| adjacent[t]) {
        balanced[t] = f64::INFINITY;
    }
    for (k, &c) in grip.contacts.iter().enumerate() {
        let w = grip.multipliers[k];
        if c == Contact::Stick && w.abs() > 1.0 + CONE {
            return Err(error::limit(
                format!("tendons[{i}].friction"),
                format!(
                    "tendon {}'s stuck stretch near s = {:.4} m would need {} times the friction its channel \
                     can hold (w = {}) in this step: it would slip there while stuck on both sides, which the \
                     stick/slip history does not model",
                    i + 1,
                    x[k].s,
                    error::near_one(w.abs()),
                    error::near_one(w)
                ),
                format!(
                    "see docs/friction.md section 8, \"Limits\": the history cannot go on past this step; a \
                     full-slip solve ({}) gives the step without its history",
                    error::option_token(i, "motion")
                ),
            ));
        }
        // At a zone's start the slip is 0 to its balance.
        let (ta, tb) = (tolerance.max(balanced[k]), tolerance.max(balanced[k + 1]));
        let wrong = match c {
            Contact::Pull => d[k] > ta || d[k + 1] > tb,
            Contact::Release => d[k] < -ta || d[k + 1] < -tb,
            Contact::Stick | Contact::Slack => false,
        };
        if wrong {
            return Err(error::limit(
                format!("tendons[{i}].friction"),
                format!(
                    "tendon {} would slide against its friction near s = {:.4} m in this step (a slip zone that \
                     does not start at the base entry), which the stick/slip history does not model",
                    i + 1,
                    x[k].s
                ),
                "take the history in smaller steps, or hold the loads while the tendons move",
            ));
        }
    }
    Ok(())
}
