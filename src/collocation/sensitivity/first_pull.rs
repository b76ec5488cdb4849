//! The tension column of a tendon with friction at 0 N: the one-sided derivative at 0+, the
//! response to the first pull (docs/friction.md section 3, "Sensitivities").
//!
//! At 0 N the tendon loads nothing, and the capstan rows leave its log tensions z at 0 (its
//! turning rate is taken as 0 at zero tension). Under a pull of h > 0 N the solve has the
//! capstan profile instead: as h -> 0+ the shape does not move, so z tends to z*, the
//! solution of the tendon's discrete capstan rows on the current shape in its motion
//! (z*' = w mu kappa, kappa the turning rate of its path there), and its loads on the rod
//! are h exp(z*(s)) times its loads per unit tension. So at 0+
//!
//! ```text
//! [ J      F_z   ] [dx/dh]     [ dF/dh(x, z*) ]
//! [ psi_x  psi_z ] [dz/dh] = - [ 0            ]   (the tendon's own capstan rows)
//! ```
//!
//! with the blocks of the linearization at the solution, where the tendon's z enters
//! nothing else (F_z and the other tendons' psi_z vanish in its columns at 0 N) and its own
//! rows are z_b - z_a (psi_x 0): the rows for x and the other log tensions decouple from
//! its z, whose derivative the solve leaves at 0 (its tension derivative, exp(z*) per N at
//! 0+, does not need it).

use super::{Difference, Sensitivity, force_scale};
use crate::collocation::friction::Capstan;
use crate::error::{Result, invalid};
use crate::model::equations::Model;
use crate::solution::State;

/// The tension (relative to the tension that bends the rod through about a radian) at which
/// the turning rates of z* are evaluated, 1e-12: at tension h the shape moves by about h
/// relative to that scale, so the rates and z* differ from their limit by about 1e-12
/// relative, while the tendon stays loading (a tension > 0) and its turning rate
/// |q| / tau is a ratio of two quantities linear in it (no underflow).
const PROBE: f64 = 1e-12;

impl Sensitivity<'_> {
    /// Tendon `tendon`'s slip index and z* (module docs), its log tensions at every node
    /// under its first pull, when it has friction and 0 N at its base entry; None otherwise.
    ///
    /// # Errors
    /// A model breakdown at a visited state; [`crate::Error::InvalidInput`] when z* is not
    /// finite.
    pub(super) fn first_pull(&mut self, tendon: usize) -> Result<Option<(usize, Vec<f64>)>> {
        let n = self.border.system().unknowns();
        let slot = self.border.system().friction.as_ref().and_then(|p| {
            let j = p.slipping.iter().position(|&i| i == tendon)?;
            (p.base[j] == 0.0).then_some((j, p.spans[j], p.z[j].len()))
        });
        let Some((j, span, nodes)) = slot else {
            return Ok(None);
        };
        // The capstan rows at a probe tension, log tensions 0, give each link's increment
        // (psi = z_b - z_a - increment; at this tension the increments do not depend on z).
        let probe = PROBE * bend_scale(self.robot(), tendon);
        let zero = vec![0.0; nodes];
        let out = &mut self.scratch[1];
        residual_with(&self.border, &self.states, (tendon, j, &zero), probe, out)?;
        let mut z = vec![0.0; nodes];
        for k in 0..span {
            z[k + 1] = z[k] - out[n + self.border.capstan_row(j, k)];
        }
        let last = z[span];
        z[span + 1..].iter_mut().for_each(|v| *v = last);
        if !z.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                format!("tendons[{tendon}].tension"),
                "is 0 N on a tendon with friction, and its first-pull tension profile is not finite here",
                "give the tendon a small tension (e.g. 1e-3 N) to differentiate there",
            ));
        }
        Ok(Some((j, z)))
    }

    /// Writes -(dF/dh, dpsi/dh) at h = 0+ for tendon `tendon` with friction at 0 N into the
    /// right-hand side buffer (module docs): the second-order forward difference with the
    /// step `step` of the residual with the tendon's log tensions held at z*, its own
    /// capstan rows 0.
    ///
    /// # Errors
    /// A model breakdown at a visited state; [`crate::Error::InvalidInput`] when the tendon
    /// has no log tensions (no friction) or z* is not finite.
    pub(super) fn first_pull_rhs(&mut self, tendon: usize, step: f64) -> Result<()> {
        let Some((j, z)) = self.first_pull(tendon)? else {
            return Err(invalid(
                format!("tendons[{tendon}].friction"),
                "has no first-pull profile here: the tendon is not one with friction at 0 N",
                "differentiate it through Sensitivity::tension, which takes this route only for such a tendon",
            ));
        };
        let n = self.border.system().unknowns();
        let span = self.border.system().friction.as_ref().map_or(0, |p| p.spans[j]);
        let rows: Vec<usize> = (0..span).map(|k| n + self.border.capstan_row(j, k)).collect();
        self.differenced_rhs(step, Difference::Forward, |border, states, dq, out| {
            residual_with(border, states, (tendon, j, &z), dq, out)
        })?;
        // Its own capstan rows hold z at z* (module docs): 0, not the jump from 0 to z*.
        let rhs = &mut self.scratch[0];
        rows.iter().for_each(|&r| rhs[r] = 0.0);
        Ok(())
    }
}

/// The tension that bends the rod through about a radian from tendon `tendon`'s offset,
/// E I / (L |r(0)|) (E I / L^2 on the centreline): the scale of its tension steps.
pub(super) fn bend_scale(robot: &crate::Robot, tendon: usize) -> f64 {
    let offset = robot.tendons[tendon].routing.at(0.0, robot.length()).r.norm();
    if offset > 0.0 {
        robot.bending_stiffness() / (robot.length() * offset)
    } else {
        force_scale(robot)
    }
}

/// The residual (backbone rows, then capstan rows) of `border`'s system at `states` with
/// tendon `tendon` (slip `j`) at tension `tension` and its log tensions `z` at every node,
/// the others' as the border holds them.
fn residual_with(
    border: &Capstan,
    states: &[State],
    (tendon, j, z): (usize, usize, &[f64]),
    tension: f64,
    out: &mut [f64],
) -> Result<()> {
    let robot = border.system().model.robot;
    let mut probe = robot.clone();
    probe.tendons[tendon].set_tension(tension);
    let mut model = Model::new(&probe);
    for (i, t) in probe.tendons.iter().enumerate() {
        if t.displacement().is_some() {
            model.tensions[i] = border.system().model.tensions[i];
        }
    }
    let mut system = border.moved(model);
    if let Some(profile) = system.friction.as_mut() {
        profile.z[j].copy_from_slice(z);
        profile.deliver(&mut system.model);
    }
    border.residual_of(&system, states, out)
}
