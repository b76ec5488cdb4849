//! The count a load path compares between its points, for every load (docs/stability.md,
//! "Loads that are not conservative: events on the load path").
//!
//! Under conservative loads it is the number of unstable directions (module `neutral`).
//! Under loads that are not conservative that number has no meaning (the conjugate-point
//! test needs a potential energy), but the parity of the conjugate points still does: it is
//! the sign of det Q at the base, det Q(L) = I at the tip, and det Q(0) vanishes exactly
//! where the Jacobian is singular, so the parity changes where a real eigenvalue of the
//! linearization crosses zero (a fold, a real bifurcation, a divergence), whatever the
//! load, and nowhere else. From the rest state (parity 0) an odd parity proves an odd number
//! of real eigenvalues crossed: unstable by divergence. An even parity proves nothing (two
//! crossings, or a flutter pair); the answer's verdict still comes from the linearized
//! dynamics.

use super::neutral;
use super::newton::Workspace;
use super::stability;
use super::system::System;
use crate::report::{SolveReport, Stability};
use crate::solution::State;

/// The number of unstable directions at `x` (module `neutral`, [`neutral::index`]) under
/// conservative loads; under loads that are not conservative the parity of the conjugate
/// points (0 or 1), roots in the neutral zone at the base included (a root there is det Q
/// near zero at the base, which the sign must see). `ws` holds the Jacobian evaluated at
/// `x`. None when the fields cannot be carried along the rod.
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
