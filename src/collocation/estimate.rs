//! The error estimate of a converged collocation solution, by deferred correction.
//!
//! At the order-4 solution x4 the residual of an order-6 scheme on the same mesh,
//! phi6(x4), is of the size of x4's own error times the Jacobian: since phi6 vanishes to
//! O(h^6) at the exact solution x*, phi6(x4) = J (x4 - x*) + O(h^6) + O(|x4 - x*|^2). One
//! solve with the factors Newton already holds, J delta = phi4(x4) - phi6(x4) (phi4(x4) is
//! zero for the exact discrete solution; subtracting Newton's final residual keeps the
//! iteration's own error out), therefore gives delta = x* - x4 up to O(h^6): an
//! asymptotically exact estimate of the discretization error of every node, at the cost of
//! two residual-like passes and one re-solve (docs/numerics.md, "Error estimate").

use super::newton::Workspace;
use super::system::System;
use super::unknowns::{self, nonzeros};
use crate::error::Result;
use crate::mesh::spare;
use crate::report::ErrorEstimate;
use crate::solution::State;
use nalgebra::Vector6;

/// The estimate and what re-meshing needs from it.
#[derive(Clone, Debug)]
pub(crate) struct Correction {
    /// Tip and backbone error estimates, and the order of the solution estimated
    /// (`estimate.order`: 4, or 6 for the deferred-corrected one of [`super::deferred`]),
    /// whose error falls like h^order and whose `local` errors like h^(order + 1).
    pub estimate: ErrorEstimate,
    /// Local error of each link: the max-norm of its order-6 residual (dimensionless, about
    /// C h^5 on an interval; 0 for jumps), or of its order-8 residual for the order-6
    /// answer (about C h^7).
    pub local: Vec<f64>,
    /// The rates (v', u') of eq. 13 at every node, evaluated on the way (the solution's
    /// nodes reuse them).
    pub node_rates: Vec<Vector6<f64>>,
}

/// Estimates the error of `x`, converged on `system`, with the factors in `ws` (factoring
/// the Jacobian at `x` first when there are none). `None` when the linear solve fails (a
/// singular Jacobian: no estimate exists there).
///
/// # Errors
/// A model breakdown at a stage of the order-6 scheme.
pub(crate) fn estimate(system: &System, ws: &mut Workspace, x: &[State]) -> Result<Option<Correction>> {
    estimate_with(system, ws, x, None, None)
}

/// [`estimate`] with the order-4 residual at `x` when the caller has it (Newton's last
/// residual), saving its evaluation, and the node rates of eq. 13 at `x` when that residual's
/// evaluation gave them (`node_rates`: [`System::residual_rates`] at `x`, one per node),
/// saving theirs.
///
/// # Errors
/// As [`estimate`].
pub(crate) fn estimate_with(
    system: &System,
    ws: &mut Workspace,
    x: &[State],
    phi4: Option<&[f64]>,
    node_rates: Option<Vec<Vector6<f64>>>,
) -> Result<Option<Correction>> {
    let n = system.unknowns();
    // The buffers come from the thread's kept ones ([`spare`]; [`Correction::release`]).
    let zeros = |len: usize| {
        let mut buffer = spare::take(len);
        buffer.resize(len, 0.0);
        buffer
    };
    let mut rhs = zeros(n);
    let mut local = zeros(x.len() - 1);
    let known = node_rates.as_ref().is_some_and(|r| r.len() == x.len());
    let mut node_rates = match node_rates {
        Some(r) if known => r,
        _ => {
            let mut rates = spare::take(x.len());
            rates.resize(x.len(), Vector6::zeros());
            rates
        }
    };
    system.order6_residual_with(x, &mut rhs, &mut local, &mut node_rates, known)?;
    // The difference phi4(x) - phi6(x), not -phi6(x) alone: Newton stops at a small but
    // non-zero phi4(x), whose part J^-1 phi4 is the iteration's error, not the mesh's; it
    // must not make the mesh finer.
    let evaluated;
    let phi4 = match phi4 {
        Some(r) => r,
        None => {
            let mut r = vec![0.0; n];
            system.residual(x, &mut r)?;
            evaluated = r;
            &evaluated[..]
        }
    };
    for (r, f) in rhs.iter_mut().zip(phi4) {
        *r = f - *r;
    }
    if !ws.has_factors() {
        let mut residual = vec![0.0; n];
        let mut values = vec![0.0; nonzeros(&system.mesh)];
        system.jacobian(x, &mut residual, &mut values)?;
        if !ws.factor(&values) {
            return Ok(None);
        }
    }
    let Some(dx) = ws.solve_again(&rhs) else {
        spare::give(rhs);
        return Ok(None);
    };
    let c = correction(dx, x.len(), system.model.robot.length(), local, node_rates);
    spare::give(rhs);
    Ok(Some(c))
}

impl Correction {
    /// Gives the buffers of the interval errors and node rates back to the thread's kept
    /// ones ([`spare`]) when the solve is done with them.
    pub(crate) fn release(self) {
        spare::give(self.local);
        spare::give(self.node_rates);
    }
}

/// The correction dx of `nodes` node states on a rod of `length` (m) as the error estimate:
/// the tip's position and rotation increments and the largest position increment, with the
/// intervals' `local` errors and the `node_rates` of the order-6 pass.
pub(super) fn correction(
    dx: &[f64],
    nodes: usize,
    length: f64,
    local: Vec<f64>,
    node_rates: Vec<Vector6<f64>>,
) -> Correction {
    let backbone_max = (0..nodes)
        .map(|k| unknowns::node_increments(dx, k, length)[0].norm())
        .fold(0.0, f64::max);
    let [dp, dtheta, _, _] = unknowns::node_increments(dx, nodes - 1, length);
    Correction {
        estimate: ErrorEstimate {
            tip_position: dp.norm(),
            tip_rotation: dtheta.norm(),
            backbone_max,
            order: 4,
        },
        local,
        node_rates,
    }
}
