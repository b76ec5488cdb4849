//! The stuck stretches a history step refuses, with what the user can change
//! (docs/friction.md section 8, "Limits").

use crate::error::{self, Error};

/// The error for tendon `i` whose stuck part would go slack near `s`: the step's shape
/// makes the path there shorter than the material stuck in it. The first step of a history
/// never raises it (from rest every loaded tendon slides in all along), and smaller steps
/// do not remove it: the stuck material's tension falls with the shape as the input moves,
/// so it reaches 0 on the way whatever the steps.
pub(super) fn slack(i: usize, s: f64) -> Error {
    error::invalid(
        format!("tendons[{i}]"),
        format!(
            "tendon {} would go slack near s = {s:.4} m while stuck in its channel (the step's shape makes its path \
             there shorter than the material stuck in it), which the stick/slip history does not model",
            i + 1
        ),
        "keep the tendon taut through this step: pull it in further (more tension at its base entry), so that it \
         slides in along that stretch",
    )
}

/// The error for rigid tendon `i` that sticks near `s`.
pub(super) fn rigid(i: usize, s: f64) -> Error {
    error::invalid(
        format!("tendons[{i}].stiffness"),
        format!(
            "tendon {} sticks in its channel near s = {s:.4} m during this step, but it is rigid: the tension of \
             a stuck rigid tendon can be anything friction allows (statically indeterminate)",
            i + 1
        ),
        "set the tendon's axial stiffness E_t A_t (`stiffness` in N) so that its stuck part stretches",
    )
}
