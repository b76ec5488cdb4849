//! What a solve did: termination reason, iterations, residual history, counts and timings.

use std::fmt;
use std::time::Duration;

/// Which solver produced a solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Sparse collocation with Newton (the main solver).
    Collocation,
    /// Shooting from the base with an adaptive Runge-Kutta integrator (cross-check).
    Shooting,
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Method::Collocation => "collocation",
            Method::Shooting => "shooting",
        })
    }
}

/// Why a Newton iteration stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// The scaled residual max-norm is at or below the tolerance, after at least one step.
    Converged,
    /// The iteration limit was reached first.
    MaxIterations,
    /// The line search could not decrease the merit function.
    LineSearchFailed,
    /// The linear solve hit a zero pivot or produced a non-finite step.
    SingularJacobian,
    /// The residual became non-finite (the model broke down at a visited state).
    NonFinite,
    /// A load-history step's stick/slip zones kept changing: every pass's Newton converged,
    /// but each march on the new shape changed the zones again (docs/friction.md section 8).
    ZonesUnsettled,
}

impl Termination {
    /// Every termination, in declaration order (to read one back from its name).
    pub const ALL: [Termination; 6] = [
        Termination::Converged,
        Termination::MaxIterations,
        Termination::LineSearchFailed,
        Termination::SingularJacobian,
        Termination::NonFinite,
        Termination::ZonesUnsettled,
    ];
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Termination::Converged => "converged: the scaled residual is below tolerance",
            Termination::MaxIterations => "stopped at the iteration limit before the residual reached tolerance",
            Termination::LineSearchFailed => "the line search found no step that reduces the residual",
            Termination::SingularJacobian => "the Newton matrix is singular: zero pivot or non-finite step",
            Termination::NonFinite => "the residual became non-finite at a state the iteration visited",
            Termination::ZonesUnsettled => {
                "the stick/slip zones did not settle: each pass's Newton converged, but the march on its shape \
                 changed the zones again"
            }
        })
    }
}

/// One Newton iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iteration {
    /// Scaled residual max-norm before the step.
    pub residual: f64,
    /// Scaled max-norm of the full Newton step.
    pub step: f64,
    /// Line-search fraction of the step taken, in (0, 1].
    pub damping: f64,
    /// Whether the step was solved with a Jacobian evaluated at this iterate (a Newton
    /// step); false for a chord step, solved with the factors of an earlier Jacobian.
    pub fresh_jacobian: bool,
}

/// Evaluation counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Evaluations {
    /// Residual evaluations (collocation) or tip-residual integrations (shooting).
    pub residual: usize,
    /// Jacobian evaluations.
    pub jacobian: usize,
    /// Evaluations of eq. 13 (solves of its 6x6 system, alone or with its linearization),
    /// counted the same way by both solvers.
    pub equations: usize,
}

/// Wall-clock time split by stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Residual and Jacobian assembly.
    pub assembly: Duration,
    /// Numeric factorization (sparse LU) or forward elimination (block elimination).
    pub factorization: Duration,
    /// Triangular solves (sparse LU) or back substitution (block elimination).
    pub solve: Duration,
    /// The error estimate (order-6 residual and its correction solve), not part of the
    /// three above.
    pub estimate: Duration,
    /// The stability verdict (the conjugate-point test, and the Jacobian it needed when
    /// Newton's last one was not at the solution).
    pub stability: Duration,
    /// Whole call.
    pub total: Duration,
}

/// The estimated discretization error of a collocation solution: the deferred correction of
/// docs/numerics.md ("Error estimate"), an asymptotically exact estimate of the difference
/// between the solution and the exact solution of the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// Estimated error of the tip position (m).
    pub tip_position: f64,
    /// Estimated error of the tip orientation: the angle of the rotation between the
    /// solution's and the exact tip frame (rad).
    pub tip_rotation: f64,
    /// Largest estimated position error over the nodes (m).
    pub backbone_max: f64,
    /// The order of accuracy of the answer this estimate belongs to: 4, the collocation
    /// solution (estimated from the order-6 residual), or 6, the deferred-corrected solution
    /// returned at tolerances of 1e-8 L and below (estimated from the order-8 residual;
    /// docs/numerics.md, "The order-6 answer"), or for a load-history step with a stuck
    /// stretch (estimated by the difference to the same step on a finer split mesh;
    /// docs/friction.md section 8, "Error control of stuck steps") 4 where its stuck links
    /// take per-point multipliers (one tendon with friction, "ord23"), else 2.
    pub order: u32,
}

/// Whether an equilibrium is stable: the second variation of the potential energy is
/// positive definite (docs/stability.md).
#[derive(Clone, Debug, PartialEq)]
pub enum Stability {
    /// No conjugate point in [0, L): a local minimum of the energy, the state a real robot
    /// can rest in.
    Stable,
    /// The energy decreases along `directions` independent perturbations: a small
    /// disturbance makes the robot leave this state (buckle or snap).
    Unstable {
        /// Number of unstable directions (negative eigenvalues of the second variation,
        /// counted with multiplicity: a round column past Euler's load has two).
        directions: usize,
        /// Arc length of the conjugate point nearest the tip (m).
        conjugate_point: f64,
    },
    /// Loads that are not conservative (a dead moment in 3D, a follower load): the
    /// linearized dynamics about the state has a growing mode (docs/stability.md, "Loads that
    /// are not conservative"), a disturbance grows like exp(rate t).
    Growing {
        /// How the fastest mode grows: without oscillating, or oscillating.
        growth: Growth,
        /// Its growth rate Re(lambda) (1/s), for the mass of [`DENSITY`](crate::collocation::DENSITY).
        rate: f64,
    },
    /// The test does not apply or could not be carried out.
    Unknown {
        /// Why.
        reason: String,
    },
}

/// How the fastest-growing mode of the linearized dynamics grows
/// ([`Stability::Growing`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Growth {
    /// A real eigenvalue lambda > 0: the state creeps away without oscillating (it buckles
    /// or snaps), as a conservative system's unstable state does.
    Divergence,
    /// A complex pair with Re lambda > 0: oscillations of growing amplitude, which only
    /// non-conservative loads (a follower force) cause.
    Flutter {
        /// The oscillation's frequency Im(lambda) / (2 pi) (Hz).
        frequency: f64,
    },
}

impl Growth {
    /// `"divergence"` or `"flutter"`.
    pub fn name(&self) -> &'static str {
        match self {
            Growth::Divergence => "divergence",
            Growth::Flutter { .. } => "flutter",
        }
    }

    /// For flutter growing at `rate` (1/s), the modal damping ratio zeta above which
    /// structural damping, which the model leaves out, outweighs the growth to first order:
    /// damping moves a mode of angular frequency omega by -zeta omega, so it decays when
    /// zeta > rate / omega (docs/stability.md). `None` for divergence, which no damping stops.
    pub fn damping_to_suppress(&self, rate: f64) -> Option<f64> {
        match self {
            Growth::Divergence => None,
            Growth::Flutter { frequency } => Some(rate / (2.0 * std::f64::consts::PI * frequency)),
        }
    }
}

impl Stability {
    /// `"stable"`, `"unstable"` or `"unknown"`.
    pub fn verdict(&self) -> &'static str {
        match self {
            Stability::Stable => "stable",
            Stability::Unstable { .. } | Stability::Growing { .. } => "unstable",
            Stability::Unknown { .. } => "unknown",
        }
    }

    /// Whether the verdict is [`Stability::Stable`].
    pub fn is_stable(&self) -> bool {
        matches!(self, Stability::Stable)
    }
}

impl fmt::Display for Stability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stability::Stable => f.write_str("stable"),
            Stability::Unstable {
                directions,
                conjugate_point,
            } => write!(
                f,
                "UNSTABLE ({directions} unstable direction{}, conjugate point at s = {:.1} mm)",
                if *directions == 1 { "" } else { "s" },
                conjugate_point * 1e3
            ),
            Stability::Growing { growth, rate } => match growth {
                Growth::Divergence => write!(f, "UNSTABLE (divergence, growth rate {rate:.4e} 1/s)"),
                Growth::Flutter { frequency } => write!(
                    f,
                    "UNSTABLE (flutter of the undamped model, growth rate {rate:.4e} 1/s at {frequency:.4e} Hz; \
                     a modal damping ratio above {:.2} % suppresses it)",
                    100.0 * growth.damping_to_suppress(*rate).unwrap_or(f64::NAN)
                ),
            },
            Stability::Unknown { reason } => write!(f, "stability unknown: {reason}"),
        }
    }
}

/// Where a solve's answer came from: Newton from the guess, or the load path. (Named so
/// that it never shadows `std::path::Path`.)
#[derive(Clone, Debug, PartialEq)]
pub enum PathTaken {
    /// Newton converged from the initial guess or warm start to a stable state (or the
    /// caller asked for the equilibrium nearest the guess).
    Direct,
    /// Newton's residual at the warm start was followed to zero (a Newton homotopy from
    /// the warm start, docs/numerics.md "Load path"): the state the robot moves to from
    /// the warm start's shape.
    FromWarmStart {
        /// Homotopy parameters at which the path turned back.
        folds: Vec<f64>,
        /// Homotopy parameters at which the path crossed a bifurcation.
        bifurcations: Vec<f64>,
    },
    /// The loads were followed from the unloaded robot (load factor 0 to 1) by
    /// pseudo-arclength continuation.
    LoadPath {
        /// Load factors at which the path turned back (folds); past a fold the robot
        /// snaps through to another state.
        folds: Vec<f64>,
        /// Load factors at which the path crossed a bifurcation (the number of unstable
        /// directions changed without a fold), as a perfectly symmetric column does at
        /// Euler's load.
        bifurcations: Vec<f64>,
    },
    /// The load path could not be followed (it stalled, or could not move to a finer mesh),
    /// and the answer is Newton's root from the guess or warm start, stable or not: not
    /// necessarily the state the robot reaches when loaded from rest. `SolveReport::notes`
    /// says where the path stopped.
    Fallback,
}

impl PathTaken {
    /// The names of the kinds, as every file and front end writes them.
    pub const NAMES: [&'static str; 4] = ["direct", "from_warm_start", "load_path", "fallback"];

    /// The kind's name: `direct`, `from_warm_start`, `load_path` or `fallback`.
    pub fn name(&self) -> &'static str {
        match self {
            PathTaken::Direct => Self::NAMES[0],
            PathTaken::FromWarmStart { .. } => Self::NAMES[1],
            PathTaken::LoadPath { .. } => Self::NAMES[2],
            PathTaken::Fallback => Self::NAMES[3],
        }
    }

    /// Where the path turned back (load factors, or homotopy parameters from a warm start);
    /// empty for `Direct` and `Fallback`.
    pub fn folds(&self) -> &[f64] {
        match self {
            PathTaken::Direct | PathTaken::Fallback => &[],
            PathTaken::FromWarmStart { folds, .. } | PathTaken::LoadPath { folds, .. } => folds,
        }
    }

    /// Where the path crossed a bifurcation; empty for `Direct` and `Fallback`.
    pub fn bifurcations(&self) -> &[f64] {
        match self {
            PathTaken::Direct | PathTaken::Fallback => &[],
            PathTaken::FromWarmStart { bifurcations, .. } | PathTaken::LoadPath { bifurcations, .. } => bifurcations,
        }
    }

    /// The path of kind `name` (one of [`PathTaken::NAMES`]) with these folds and
    /// bifurcations (ignored for `direct` and `fallback`); `None` for another name.
    pub fn from_name(name: &str, folds: Vec<f64>, bifurcations: Vec<f64>) -> Option<PathTaken> {
        match name {
            "direct" => Some(PathTaken::Direct),
            "from_warm_start" => Some(PathTaken::FromWarmStart { folds, bifurcations }),
            "load_path" => Some(PathTaken::LoadPath { folds, bifurcations }),
            "fallback" => Some(PathTaken::Fallback),
            _ => None,
        }
    }
}

/// The reason of a report's stability before a verdict is assessed ([`SolveReport::new`]).
pub(crate) const NOT_ASSESSED: &str = "not assessed";

/// What a solve did. Filled by both solvers.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// Which solver.
    pub method: Method,
    /// Why it stopped (of the last Newton run).
    pub termination: Termination,
    /// Iterations (updates of the state), summed over load steps and meshes: Newton steps
    /// plus chord steps.
    pub iterations: usize,
    /// Newton steps: iterations that evaluated and factored a fresh Jacobian.
    pub newton_steps: usize,
    /// Chord steps: iterations solved with the factors of an earlier Jacobian (a fifth of a
    /// Newton step's cost).
    pub chord_steps: usize,
    /// Continuation steps along the load path (0 when Newton from the guess was enough).
    pub load_steps: usize,
    /// Meshes solved on (1 without refinement).
    pub meshes: usize,
    /// Per-iteration record of the last Newton run.
    pub history: Vec<Iteration>,
    /// Final scaled residual max-norm.
    pub residual: f64,
    /// Evaluation counts.
    pub evaluations: Evaluations,
    /// Timings.
    pub timings: Timings,
    /// Unknowns of the final system.
    pub unknowns: usize,
    /// Non-zeros of the final Jacobian.
    pub nonzeros: usize,
    /// Mesh intervals (collocation) or accepted integration steps (shooting).
    pub intervals: usize,
    /// The estimated discretization error (collocation; `None` for shooting, whose
    /// integrator controls its own local error).
    pub error_estimate: Option<ErrorEstimate>,
    /// The tip tolerance the solve worked to, relative to L (position error at most
    /// tolerance x L, orientation error at most tolerance rad); `None` on a fixed mesh.
    pub tolerance: Option<f64>,
    /// Whether the error estimate meets the tolerance (`None` without either).
    pub tolerance_met: Option<bool>,
    /// Stability of the equilibrium returned.
    pub stability: Stability,
    /// How it was reached.
    pub path: PathTaken,
    /// What a user should know about the choice of this answer, one sentence each: a side
    /// picked at a perfectly symmetric bifurcation (and the mirror state left out), or a
    /// fallback returned because the load path could not be followed.
    pub notes: Vec<String>,
}

impl SolveReport {
    /// An empty report for `method`.
    pub fn new(method: Method) -> Self {
        Self::new_in(method, NOT_ASSESSED.into())
    }

    /// Adds the counts of the work `tried` did (iterations, steps, meshes, evaluations and
    /// the timings by stage) to this report: a solve run again after a provisional route
    /// counts both runs.
    pub(crate) fn add_work(&mut self, tried: &SolveReport) {
        self.iterations += tried.iterations;
        self.newton_steps += tried.newton_steps;
        self.chord_steps += tried.chord_steps;
        self.load_steps += tried.load_steps;
        self.meshes += tried.meshes;
        self.evaluations.residual += tried.evaluations.residual;
        self.evaluations.jacobian += tried.evaluations.jacobian;
        self.evaluations.equations += tried.evaluations.equations;
        let (t, u) = (&mut self.timings, &tried.timings);
        t.assembly += u.assembly;
        t.factorization += u.factorization;
        t.solve += u.solve;
        t.estimate += u.estimate;
        t.stability += u.stability;
    }

    /// Replaces this report's work counts (those [`SolveReport::add_work`] adds) by
    /// `spent`'s: an answer that is the last of several solves reports all of them.
    pub(crate) fn set_work(&mut self, spent: &SolveReport) {
        self.iterations = spent.iterations;
        self.newton_steps = spent.newton_steps;
        self.chord_steps = spent.chord_steps;
        self.load_steps = spent.load_steps;
        self.meshes = spent.meshes;
        self.evaluations = spent.evaluations;
        let (t, u) = (&mut self.timings, &spent.timings);
        t.assembly = u.assembly;
        t.factorization = u.factorization;
        t.solve = u.solve;
        t.estimate = u.estimate;
        t.stability = u.stability;
    }

    /// Adds one more mesh's solve, reported by `solve`, to this report's work counts: its
    /// iterations, evaluations and timings, and one mesh (a history step's solves each
    /// carry the mesh count of the solve that chose the history's mesh, not their own).
    pub(crate) fn add_mesh_work(&mut self, solve: &SolveReport) {
        let meshes = self.meshes;
        self.add_work(solve);
        self.meshes = meshes + 1;
    }

    /// [`SolveReport::new`] with the stability's reason [`NOT_ASSESSED`] in `not_assessed`
    /// (a kept buffer that holds that text), so that no string is allocated.
    pub(crate) fn new_in(method: Method, not_assessed: String) -> Self {
        SolveReport {
            method,
            termination: Termination::MaxIterations,
            iterations: 0,
            newton_steps: 0,
            chord_steps: 0,
            load_steps: 0,
            meshes: 0,
            history: Vec::new(),
            residual: f64::NAN,
            evaluations: Evaluations::default(),
            timings: Timings::default(),
            unknowns: 0,
            nonzeros: 0,
            intervals: 0,
            error_estimate: None,
            tolerance: None,
            tolerance_met: None,
            stability: Stability::Unknown { reason: not_assessed },
            path: PathTaken::Direct,
            notes: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_termination_has_its_own_sentence() {
        let texts: Vec<String> = Termination::ALL.iter().map(|t| t.to_string()).collect();
        for (i, t) in texts.iter().enumerate() {
            assert!(t.len() > 20 && !t.contains('\n'));
            assert!(texts.iter().skip(i + 1).all(|o| o != t));
        }
        assert!(texts[3].contains("singular"));
        // A history step whose zones keep changing did not converge, whatever its last
        // Newton run did: its sentence says so, not "converged" (main's message did).
        assert!(
            texts[5].starts_with("the stick/slip zones did not settle"),
            "{}",
            texts[5]
        );
    }
}
