//! The count a load path compares between its points, for every load (docs/stability.md,
//! "Loads that are not conservative: the linearized dynamics", "Events on the load path").
//!
//! Under conservative loads it is the number of unstable directions (module `neutral`).
//! Under loads that are not conservative it is no verdict (the conjugate-point test needs a
//! potential energy), but the same count of the roots of det Q on [0, L) still labels the
//! branch. Its roots move continuously along a branch. One enters or leaves at the base only
//! where det J is zero (a fold, a real bifurcation, a real eigenvalue through zero). Two can
//! also leave as a pair in the interior, which conservative loads forbid and which no
//! measured path showed. So a change without a fold
//! is a jump to another branch or a crossing, as under conservative loads. Its parity is the
//! sign of det J relative to the rest state, but a jump can keep the parity (robot 254's, to
//! a state with 2 conjugate points), so the whole count is compared.

use super::neutral;
use super::newton::Workspace;
use super::stability;
use super::system::System;
use crate::report::{SolveReport, Stability};
use crate::solution::State;

/// The number of unstable directions at `x` (module `neutral`, [`neutral::index`]) under
/// conservative loads; under loads that are not conservative the count of the conjugate
/// points, roots in the neutral zone at the base included (a root there is det J near zero,
/// which the path must see). `ws` holds the Jacobian evaluated at `x`. None when the fields
/// cannot be carried along the rod.
pub(super) fn index(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    family: bool,
    report: &mut SolveReport,
) -> Option<usize> {
    if stability::non_conservative(&system.model).is_none() {
        return neutral::index(system, ws, x, family, report);
    }
    let t = std::time::Instant::now();
    // Not held as the workspace's verdict: it is no verdict of stability.
    let (verdict, at_base) = neutral::count(ws.jacobian(), system);
    report.timings.stability += t.elapsed();
    let counted = match verdict {
        Stability::Stable => 0,
        Stability::Unstable { directions, .. } => directions,
        Stability::Growing { .. } | Stability::Unknown { .. } => return None,
    };
    Some(counted + at_base.map_or(0, |(roots, _)| roots))
}
