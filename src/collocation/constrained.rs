//! Stability of an equilibrium with displacement-controlled tendons (docs/stability.md,
//! "Displacement-controlled tendons").
//!
//! A tendon held at a pull-in keeps its length (plus its stretch c_j tau_j), and its tension
//! tau_j is the multiplier of that constraint: the energy is the one of constant tensions
//! tau, restricted to the states that meet the length constraints. Its second variation on
//! that subspace has the negative eigenvalues of the constant-tension second variation H
//! less those of the k x k length compliance
//!
//! ```text
//! A = c + G X,   X_m = J^-1 dF/dtau_m,   (G X)_jm = G_j . X_m = -dl_j/dtau_m   (m/N)
//! ```
//!
//! of the taut tendons (Haynsworth's inertia additivity on the bordered Hessian
//! [[H, G^T], [G, -c]]): count = conjugate points at the tensions tau - negative
//! eigenvalues of A. Pulling a tendon harder normally shortens it (A positive definite) and
//! the count is the constant-tension one; past a fold of the tension (a snap under tension
//! control) the tendon lengthens as it is pulled, A has a negative eigenvalue, and the
//! length constraint holds the state the tension would let go.
//!
//! Loads that are not conservative (a dead moment, a follower load) get the linearized
//! dynamics of the bordered system instead: the tensions are massless, so each shift-invert
//! solve a = J^-1 M z becomes a - X A^-1 G a.

use super::actuation::{Constraint, TENSION_STEP};
use super::newton::{self, Workspace};
use super::system::System;
use super::{dynamics, stability};
use crate::report::{SolveReport, Stability};
use crate::solution::State;
use nalgebra::DMatrix;

/// An eigenvalue of the length compliance A within this fraction of its largest is taken as
/// zero. More than three rigid straight tendons are redundant: their lengths depend on three
/// strains to first order, so A is singular to first order and its further eigenvalues are
/// of second order, below the error of the differenced dF/dtau (about 6e-6 relative). A
/// zero eigenvalue stabilizes nothing: with redundant constraints (G of rank r < k) the count
/// is that of H less the non-zero negative eigenvalues of A. The price is a band of 1e-4
/// relative about a fold of the pull-in (where an eigenvalue of A crosses zero) in which the
/// count can be off by one.
const NEUTRAL_COMPLIANCE: f64 = 1e-4;

/// The taut displacement-controlled tendons at an equilibrium: their constraints, the
/// columns X_m = J^-1 dF/dtau_m and the length compliance A.
pub(crate) struct Border {
    constraints: Vec<Constraint>,
    columns: Vec<Vec<f64>>,
    /// A (k x k, m/N).
    compliance: DMatrix<f64>,
    /// Backbone length L (m).
    length: f64,
}

impl Border {
    /// The border of the taut displacement-controlled tendons of `system` at its
    /// equilibrium `x`, with `ws` holding the factors of the Jacobian at `x` and its residual
    /// there; None when a residual or a solve is not finite.
    pub(crate) fn new(system: &System, x: &[State], ws: &mut Workspace, report: &mut SolveReport) -> Option<Self> {
        let model = &system.model;
        let robot = model.robot;
        let constraints: Vec<Constraint> = (0..robot.tendons.len())
            .filter(|&i| robot.tendons[i].displacement().is_some() && model.tensions[i] > 0.0)
            .map(|i| Constraint::new(robot, i, &system.mesh))
            .collect();
        let residual = ws.residual().to_vec();
        let mut probe = vec![0.0; residual.len()];
        let mut columns = Vec::with_capacity(constraints.len());
        for c in &constraints {
            // dF/dtau by a forward difference at fixed x, as Newton's border takes it.
            let tau = model.tensions[c.tendon];
            let h = TENSION_STEP * tau.max(c.tension_scale);
            let mut shifted = system.model.clone();
            shifted.tensions[c.tendon] = tau + h;
            let probed = System::new(shifted, system.mesh.clone());
            if !newton::residual(&probed, x, &mut probe, report) {
                return None;
            }
            for (p, f) in probe.iter_mut().zip(&residual) {
                *p = (*p - f) / h;
            }
            columns.push(ws.solve_again(&probe)?.to_vec());
        }
        let length = robot.length();
        let k = constraints.len();
        let compliance = DMatrix::from_fn(k, k, |j, m| {
            let own = if j == m { constraints[j].compliance } else { 0.0 };
            own + constraints[j].length_change(x, &columns[m], length)
        });
        Some(Border {
            constraints,
            columns,
            compliance,
            length,
        })
    }

    /// Negative eigenvalues of A (of its symmetric part: A is symmetric for the exact
    /// energy, and the discrete one is to the truncation error), those within
    /// [`NEUTRAL_COMPLIANCE`] of the largest in size taken as zero.
    fn negative(&self) -> usize {
        if self.constraints.is_empty() {
            return 0;
        }
        let a = &self.compliance;
        let eig = (0.5 * (a + a.transpose())).symmetric_eigenvalues();
        let scale = eig.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        eig.iter().filter(|&&v| v < -NEUTRAL_COMPLIANCE * scale).count()
    }

    /// a -> a - X A^-1 G a: the x part of the bordered solve whose plain solve is a (the
    /// tensions' rows ask for no change of length). False for a singular A.
    pub(crate) fn project(&self, x: &[State], a: &mut [f64]) -> bool {
        if self.constraints.is_empty() {
            return true;
        }
        let g = nalgebra::DVector::from_iterator(
            self.constraints.len(),
            self.constraints.iter().map(|c| c.length_change(x, a, self.length)),
        );
        let Some(eta) = self.compliance.clone().lu().solve(&g) else {
            return false;
        };
        for (column, e) in self.columns.iter().zip(eta.iter()) {
            for (v, c) in a.iter_mut().zip(column) {
                *v -= c * e;
            }
        }
        a.iter().all(|v| v.is_finite())
    }
}

/// The stability of the equilibrium `x` of `system` (whose model holds the solved
/// tensions) with its displacement-controlled tendons held at their pull-ins: the Jacobian
/// at `x` is evaluated and factored into `ws` (counted in `report`), then the count of the
/// module docs, or the bordered linearized dynamics for loads that are not conservative.
pub(super) fn stability(system: &System, x: &[State], ws: &mut Workspace, report: &mut SolveReport) -> Stability {
    let unknown = |reason: &str| Stability::Unknown { reason: reason.into() };
    if crate::model::friction::any(system.model.robot) {
        // Not reached from a solve: displacement control with friction is assessed by
        // `dynamics::pulled` on the bordered capstan system (pipeline routes it there).
        return unknown("tendons with friction and displacement control are assessed on the capstan system, not here");
    }
    if !ws.linearize(system, x, report) {
        return unknown("the Jacobian at the solution is singular or not finite");
    }
    let Some(border) = Border::new(system, x, ws, report) else {
        return unknown("the tension columns of the displacement-controlled tendons are not finite");
    };
    if stability::non_conservative(&system.model).is_some() {
        return dynamics::assess_bordered(system, x, ws, &mut |a| border.project(x, a));
    }
    let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
    let negative = border.negative();
    match ws.verdict(|values| stability::assess(values, &s)) {
        Stability::Stable if negative == 0 => Stability::Stable,
        Stability::Unstable {
            directions,
            conjugate_point,
        } if directions >= negative => {
            if directions == negative {
                Stability::Stable
            } else {
                Stability::Unstable {
                    directions: directions - negative,
                    conjugate_point,
                }
            }
        }
        Stability::Unknown { reason } => Stability::Unknown { reason },
        _ => unknown(
            "the length constraints count more stabilized directions than the constant-tension state has \
             unstable ones (rounding at a critical state)",
        ),
    }
}

#[cfg(test)]
mod tests;
