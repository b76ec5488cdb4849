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
    /// continuation gave up, where it had answered a mesh, or where it did not run.
    pub(super) fn hint(&self, intervals: usize) -> String {
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
            (Some(g), None) => format!(
                "the friction coefficients were followed from 0: {on} Newton solved {:.0} % of them and failed at \
                 {:.0} % (the termination and residual above are that run's), and the branch of equilibria past it, \
                 followed by its arclength, neither reached their values nor ended. A full-slip equilibrium may not \
                 exist: a released tendon delivers up to exp(mu theta) times its input, which bends the rod and \
                 turns its path further (docs/friction.md, \"Large friction on a released tendon\"); lower the \
                 friction coefficient of a released tendon, or pull it in instead",
                100.0 * g.reached,
                100.0 * g.tried
            ),
            (None, _) => match self.followed {
                Some(k) => format!(
                    "the friction coefficients were followed from 0 to their values on a mesh of {k} intervals, and \
                     Newton then failed on a finer mesh ({intervals} intervals): loosen the tolerance, or lower the \
                     friction coefficient of a released tendon"
                ),
                None => "friction is solved from the frictionless shape: lower the friction coefficient, or solve \
                         with the shooting solver to compare"
                    .into(),
            },
        }
    }
}
