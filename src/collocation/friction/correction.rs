//! The error estimate with friction (docs/friction.md section 3, "Error estimate"): the
//! deferred correction of [`estimate`] on the bordered system.

use super::Capstan;
use crate::collocation::estimate;
use crate::collocation::newton::{Border, Point};
use crate::error::Result;
use crate::solution::State;

/// The error estimate with friction, by deferred correction as in [`estimate`] on the
/// bordered system: the order-6 residuals of the backbone and capstan rows at the
/// converged `x` (against the order-4 residual `converged` when the caller has it, else
/// evaluated), and one bordered solve with Newton's staircase factors, so that the
/// estimate carries the tension profile's error into the shape's. Returns the correction
/// and the largest correction of a log tension (the relative error of the tension
/// profile); `None` without factors or with a singular border.
///
/// The correction of the node states is left in `dx` (scaled as Newton's steps,
/// [`unknowns::node_increments`](crate::collocation::unknowns::node_increments)) and that of
/// the log tensions in the border's last step (a load history reads its order-6 material
/// from them).
///
/// # Errors
/// A model breakdown at a stage of the order-6 scheme.
pub(super) fn estimate_with_friction(
    border: &mut Capstan,
    x: &[State],
    converged: Option<Vec<f64>>,
    dx: &mut Vec<f64>,
) -> Result<Option<(estimate::Correction, f64)>> {
    border.load(Point::Current);
    let n = border.system.unknowns();
    let phi4 = match converged {
        Some(phi4) => phi4,
        None => {
            let mut phi4 = vec![0.0; n];
            border.system.residual(x, &mut phi4)?;
            phi4
        }
    };
    border.rows(Point::Current, x);
    let system = &border.system;
    let mut rhs = vec![0.0; n];
    let mut local = vec![0.0; x.len() - 1];
    let mut node_rates = vec![nalgebra::Vector6::zeros(); x.len()];
    // The order-6 rows of every link; those with friction keep their capstan rows psi6.
    system.order6_residual(x, &mut rhs, &mut local, &mut node_rates)?;
    for (r, f) in rhs.iter_mut().zip(&phi4) {
        *r = f - *r;
    }
    let length = system.model.robot.length();
    let mut difference = border.psi.clone();
    if let Some(profile) = system.friction.as_ref() {
        let kept = profile.order6.borrow();
        for (j, &o) in border.offsets.iter().enumerate() {
            for k in 0..profile.spans[j] {
                if let Some(psi6) = kept.get(k).and_then(|p| p.get(j)) {
                    difference[o + k] -= psi6;
                }
            }
        }
    }
    // The staircase holds the factors of Newton's last bordered Jacobian.
    if !border.stairs.ready {
        return Ok(None);
    }
    dx.clear();
    dx.resize(n, 0.0);
    let Some(tension_error) = border.solve_factored(&rhs, &difference, dx) else {
        return Ok(None);
    };
    Ok(Some((
        estimate::correction(dx, x.len(), length, local, node_rates),
        tension_error,
    )))
}
