//! The stuck stretches a history step refuses, with what the user can change
//! (docs/friction.md section 8, "Limits"), and the report of a step that failed.

use crate::collocation::friction::{Contact, Profile};
use crate::error::{self, Error};
use crate::report::{NOT_ASSESSED, SolveReport, Stability};

/// What the user can change when a stuck stretch goes slack: more tension at the base
/// entry slides the tendon in along it.
const TAUT: &str = "keep the tendon taut through this step: pull it in further (more tension at its base entry), so that \
                    it slides in along that stretch";

/// The error for tendon `i` whose stuck part would go slack near `s`: the step's shape
/// makes the path there shorter than the material stuck in it. The first step of a history
/// never raises it (from rest every loaded tendon slides in all along), and smaller steps
/// do not remove it: the stuck material's tension falls with the shape as the input moves,
/// so it reaches 0 on the way whatever the steps.
pub(super) fn slack(i: usize, s: f64) -> Error {
    error::limit(
        format!("tendons[{i}]"),
        format!(
            "tendon {} would go slack near s = {s:.4} m if stuck in its channel (the step's shape makes its path \
             there shorter than the material stuck in it), unless it slips there in a zone, which the stick/slip \
             history does not place at such a node: neither is modelled",
            i + 1
        ),
        TAUT,
    )
}

/// The true reason a step whose Newton did not converge (at its last iterate, loaded into
/// `profile`; `s` the nodes' arc lengths) failed, when it is a stuck stretch going slack:
/// a stuck link whose tension at its end node is below what the stick row resolves at
/// `tolerance` and below a tenth of its tendon's base-entry tension (so that a healthy stuck
/// tension under a residual tolerance too tight for its stick row, or an iterate that blew
/// up, keeps Newton's own error). Its row `z_b - ln(tau / tau_0)` reads tau from
/// `E_t A_t (|p'| / lambda - 1)`, whose ratio rounds to about eps, so it resolves tau only
/// to about E_t A_t eps / tau in log tension: below tau = E_t A_t eps / tolerance (0.044 N
/// at 2000 N and 1e-11) Newton cannot reach the tolerance (it stalled at 1.01e-11 with
/// tau about 0.01 N: docs/friction.md section 8, "Limits"). That stretch is going slack (the shape
/// drives its stuck tension smoothly toward 0 N, where the march would refuse it as
/// [`slack`]), and smaller steps do not help; more tension at the base entry does. None
/// when no stuck link is that close to slack (Newton failed for another reason).
pub(super) fn stalled(profile: &Profile, s: &[f64], tolerance: f64) -> Option<Error> {
    let grips = profile.grips.as_ref()?;
    let robot = profile.robot();
    let mut weakest: Option<(f64, usize, f64)> = None;
    for (j, grip) in grips.iter().enumerate() {
        let i = profile.slipping[j];
        let Some(stiffness) = robot.tendons[i].stiffness else {
            continue;
        };
        if profile.base[j] <= 0.0 {
            continue;
        }
        // A tenth of the base entry's tension: well below it, the stretch is being driven
        // toward 0 N, not merely resolved too finely.
        let floor = (stiffness * f64::EPSILON / tolerance).min(0.1 * profile.base[j]);
        for k in (0..profile.spans[j]).filter(|&k| grip.contacts[k] == Contact::Stick) {
            let tension = profile.tension(j, profile.z[j][k + 1]);
            if tension.is_finite() && tension < floor && weakest.is_none_or(|(t, ..)| tension < t) {
                weakest = Some((tension, i, s[k + 1]));
            }
        }
    }
    let (tension, i, at) = weakest?;
    let hint = match resolution(profile, tolerance) {
        Some(looser) => format!("{TAUT}; {looser}"),
        None => TAUT.to_string(),
    };
    Some(error::limit(
        format!("tendons[{i}]"),
        format!(
            "tendon {} is going slack near s = {at:.4} m while stuck in its channel: the step's shape drives its stuck \
             tension there toward 0 N ({tension:.2e} N at Newton's last iterate, below what the stick row resolves at \
             the residual tolerance), which the stick/slip history does not model; smaller steps do not remove it",
            i + 1
        ),
        hint,
    ))
}

/// What to loosen when the residual `tolerance` is tighter than the stick row of a stuck
/// link of `profile` resolves, E_t A_t eps / tau in log tension ([`stalled`]), while the
/// default residual tolerance would resolve it: the weakest such link's tendon, its stuck
/// tension and the tolerance that resolves it. None when no stuck link is below its
/// resolution, or only below the default's (then loosening is not what helps).
pub(super) fn resolution(profile: &Profile, tolerance: f64) -> Option<String> {
    let grips = profile.grips.as_ref()?;
    let robot = profile.robot();
    let default = crate::collocation::Options::default().residual_tolerance;
    let mut weakest: Option<(f64, usize, f64)> = None;
    for (j, grip) in grips.iter().enumerate() {
        let i = profile.slipping[j];
        let Some(stiffness) = robot.tendons[i].stiffness else {
            continue;
        };
        for k in (0..profile.spans[j]).filter(|&k| grip.contacts[k] == Contact::Stick) {
            let tension = profile.tension(j, profile.z[j][k + 1]);
            let needed = stiffness * f64::EPSILON / tension;
            if tension > 0.0 && needed > tolerance && needed <= default && weakest.is_none_or(|(n, ..)| needed > n) {
                weakest = Some((needed, i, tension));
            }
        }
    }
    let (needed, i, tension) = weakest?;
    Some(format!(
        "or loosen residual_tolerance ({tolerance:e}) to {needed:.1e} or more: tendon {}'s stick row resolves its stuck \
         tension ({tension:.2} N) only to E_t A_t eps / tau = {needed:.1e} in log tension",
        i + 1
    ))
}

/// The error for rigid tendon `i` that sticks near `s`.
pub(super) fn rigid(i: usize, s: f64) -> Error {
    error::limit(
        format!("tendons[{i}].stiffness"),
        format!(
            "is not set (tendon {} is rigid), but the tendon sticks in its channel near s = {s:.4} m during this \
             step: the tension of a stuck rigid tendon can be anything friction allows (statically indeterminate)",
            i + 1
        ),
        "set the tendon's axial stiffness E_t A_t (`stiffness` in N) so that its stuck part stretches",
    )
}

/// The report of a step that failed: its template's estimate, tolerance and verdict are
/// those of the solve that chose the history's mesh, not this step's, which has none.
pub(super) fn unanswered(mut report: SolveReport) -> SolveReport {
    report.error_estimate = None;
    report.tolerance_met = None;
    report.stability = Stability::Unknown {
        reason: NOT_ASSESSED.into(),
    };
    report
}
