//! The hint of a refused solve with friction ([`Tried::hint`]): what the continuations in
//! the friction coefficients found (docs/friction.md, "refuse21", "fold22", "fold23") and
//! what to try.

use super::{continuation, fold};

/// What the solve with friction tried before Newton failed for good, for the refusal's hint.
#[derive(Default)]
pub(super) struct Tried {
    /// Where the continuation in the coefficients gave up (on the first mesh, or on the
    /// later mesh of `later`).
    pub(super) reached: Option<continuation::GaveUp>,
    /// Where the branch past it ends (turns back, or a tendon's path degenerates).
    pub(super) ended: Option<fold::End>,
    /// The intervals of the last mesh the coefficients were followed to their values on.
    pub(super) followed: Option<usize>,
    /// Where Newton first failed on a later mesh from a converged mesh's answer: the
    /// intervals of the mesh it failed on and of the converged one.
    pub(super) later: Option<(usize, usize)>,
    /// Whether the continuation ran on a later mesh (once in a solve).
    pub(super) again: bool,
}

impl Tried {
    /// What to try after Newton with friction failed on a mesh of `intervals` intervals:
    /// where the branch past the continuation in the coefficients ends, where the
    /// continuation gave up, where it had answered a mesh, or where it did not run;
    /// `released`: whether a tendon with friction is released (its tension grows along its
    /// path, which can leave no full-slip equilibrium; a pulled one's falls).
    pub(super) fn hint(&self, intervals: usize, released: bool) -> String {
        // The mesh the continuation ran on, and why there.
        let (on, value) = match self.later {
            Some((failed, converged)) if self.again => {
                let halved = if failed == intervals {
                    String::new()
                } else {
                    format!(" and on {intervals}, that mesh halved")
                };
                (
                    format!(
                        "Newton from the answer of the mesh of {converged} intervals failed on {failed} \
                         intervals{halved}; on {intervals} intervals, from the frictionless shape,"
                    ),
                    format!("the value on {intervals} intervals"),
                )
            }
            _ => (
                format!("on the first mesh ({intervals} intervals)"),
                "the first mesh's value".to_string(),
            ),
        };
        match (&self.reached, &self.ended) {
            (Some(g), Some(e)) => {
                let (slow, speed) = e.slowest;
                let how = match (e.folded, speed < fold::DEGENERATE) {
                    (true, false) => "turns back there (a fold)".to_string(),
                    (true, true) => format!(
                        "turns back there (a fold), where tendon {}'s path has all but vanished ({speed:.1e} of the \
                         backbone's length per length: the rod's curvature is nearly the inverse of its offset)",
                        slow + 1
                    ),
                    (false, _) => format!(
                        "ends there: the rod's curvature reaches the inverse of tendon {}'s offset, where its path \
                         has all but vanished ({speed:.1e} of the backbone's length per length) and the model no \
                         longer holds",
                        slow + 1
                    ),
                };
                format!(
                    "no equilibrium on the branch the robot reaches as its friction grows from 0: {on} Newton solved \
                     {:.0} % of the friction coefficients (the termination and residual above are its run at {:.0} \
                     %), and the branch of equilibria followed on by its arclength reaches {:.2} % of them, where \
                     tendon {} has friction coefficient {:.3} and delivers {:.3} N, and {how} (docs/friction.md, \
                     \"Large friction on a released tendon\"). Lower the friction coefficients below {:.2} % of their \
                     values (the branch scales them all together), tendon {}'s below {:.3} ({value}; finer meshes \
                     move it), or pull it in instead",
                    100.0 * g.reached,
                    100.0 * g.tried,
                    100.0 * e.lambda,
                    e.tendon + 1,
                    e.coefficient,
                    e.tension,
                    100.0 * e.lambda,
                    e.tendon + 1,
                    e.coefficient,
                )
            }
            (Some(g), None) => {
                let why = if released {
                    "A full-slip equilibrium may not exist: a released tendon delivers up to exp(mu theta) times its \
                     input, which bends the rod and turns its path further (docs/friction.md, \"Large friction on a \
                     released tendon\"); lower the friction coefficient of a released tendon, or pull it in instead"
                } else {
                    "A pulled tendon's tension falls as exp(-mu theta) along its path (theta its total turning), so \
                     where mu theta is large its far end is all but slack and the mesh cannot resolve the fall; check \
                     the routings and friction coefficients (`tdcr check` names implausible ones), or lower the \
                     friction coefficients"
                };
                format!(
                    "the friction coefficients were followed from 0: {on} Newton solved {:.0} % of them and failed \
                     at {:.0} % (the termination and residual above are that run's), and the branch of equilibria \
                     past it, followed by its arclength, neither reached their values nor ended. {why}",
                    100.0 * g.reached,
                    100.0 * g.tried
                )
            }
            (None, _) => match self.followed {
                Some(k) => format!(
                    "the friction coefficients were followed from 0 to their values on a mesh of {k} intervals, and \
                     Newton then failed on a finer mesh ({intervals} intervals): loosen the tolerance, or lower the \
                     friction coefficient{}",
                    if released { " of a released tendon" } else { "s" }
                ),
                None => "friction is solved from the frictionless shape: lower the friction coefficient, or solve \
                         with the shooting solver to compare"
                    .into(),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Termination;

    /// A solve whose continuation gave up with no branch's end found names the released
    /// tendons' growth only where a tendon is released; a pulled one's hint speaks of its
    /// tension's fall (a user's 1000-turn helix, pulled, was told to pull it in instead).
    #[test]
    fn the_hint_speaks_of_a_released_tendon_only_where_one_is() {
        let tried = Tried {
            reached: Some(continuation::GaveUp {
                reached: 0.59,
                tried: 0.61,
                termination: Termination::LineSearchFailed,
                worst: 0,
                x: Vec::new(),
                z: None,
            }),
            ..Tried::default()
        };
        let released = tried.hint(8192, true);
        assert!(released.contains("a released tendon delivers"), "{released}");
        let pulled = tried.hint(8192, false);
        assert!(
            !pulled.contains("released") && pulled.contains("A pulled tendon's tension falls"),
            "{pulled}"
        );
    }
}
