//! Coulomb's law checked on a step's answer (docs/friction.md section 8, "Limits"): every
//! stretch of a tendon slides the way its friction acts, and friction can hold every stuck
//! one.

use crate::collocation::friction::*;

/// How far a stuck link's |w| may exceed 1 before its stretch is refused: w is the link's
/// mean of the stuck profile's tau' / (mu tau kappa), exact but for Simpson's rule in its
/// capacity C (relative error below 1e-6 on the meshes a history uses) and the tie width of
/// the stick/slip choice (1e-10 in z over capacities of 1e-5 and more), so 1e-4 is far above
/// both and far below a violation that matters.
pub(super) const CONE: f64 = 1e-4;

/// Checks that every stretch of tendon `i` slides the way its friction acts (Coulomb's
/// direction): the slip since the last step, d(s) = xi_new(s) - xi_old(s) with xi the
/// unstretched length from s to the termination (trapezoidal rule on the nodes), is <= 0
/// on links sliding in and >= 0 on links sliding out. A stretch that slides against its
/// friction would need a slip zone that starts away from the base entry, which the march
/// does not resolve. And every stuck link's multiplier w = (z_b - z_a) / C lies in
/// [-1, 1] to [`CONE`]: a stuck profile that changes faster than friction can hold would
/// slip inside the stuck stretch (a slip zone with both ends stuck), which the march does
/// not resolve either.
///
/// # Errors
/// The direction violated beyond rounding and `slack` (m), or a stuck link's |w| above
/// 1 + [`CONE`].
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
    for (k, &c) in grip.contacts.iter().enumerate() {
        let w = grip.multipliers[k];
        if c == Contact::Stick && w.abs() > 1.0 + CONE {
            return Err(error::invalid(
                format!("tendons[{i}].friction"),
                format!(
                    "tendon {}'s stuck stretch near s = {:.4} m would need {:.3} times the friction its channel \
                     can hold (w = {w:.4}) in this step: it would slip there while stuck on both sides, which the \
                     stick/slip history does not model",
                    i + 1,
                    x[k].s,
                    w.abs()
                ),
                "see docs/friction.md section 8, \"Limits\": the history cannot go on past this step; a \
                 full-slip solve (`motion`) gives the step without its history",
            ));
        }
        let wrong = match c {
            Contact::Pull => d[k].max(d[k + 1]) > tolerance,
            Contact::Release => d[k].min(d[k + 1]) < -tolerance,
            Contact::Stick | Contact::Slack => false,
        };
        if wrong {
            return Err(error::invalid(
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
