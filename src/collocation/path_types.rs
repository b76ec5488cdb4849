//! What a path (module `path`) starts from, records and ends with: where it starts and what
//! it connects ([`Start`]), the points of a traced branch ([`Recorded`]) and the end of a
//! path ([`End`]), with the folds, bifurcations and snaps met on the way.

use crate::model::parameter::Parameter;
use crate::solution::State;

/// The end of a load path.
pub(super) struct End {
    /// The converged states at lambda = 1.
    pub x: Vec<State>,
    /// Load factors where the path turned back.
    pub folds: Vec<f64>,
    /// Load factors where the number of unstable directions changed without a fold: the
    /// path crossed a bifurcation (the symmetric column at Euler's load).
    pub bifurcations: Vec<f64>,
    /// Load factors where the path left a perfectly symmetric bifurcation along a picked
    /// side of the Jacobian's kernel (nothing preferred either).
    pub picked: Vec<f64>,
    /// The load factor of the fold from which the states were reached by Newton at
    /// lambda = 1 ([`super::snap::land_from_folds`]), and why: the path reached lambda = 1
    /// on an unstable state after its folds (true), or could not be followed to the end
    /// (false).
    pub snapped_from: Option<(f64, bool)>,
    /// The load factor of the bifurcation at which the path lost stability with no stable
    /// branch to continue on (or one it could not follow), from which the states were reached
    /// by the robot's damped motion under the full load ([`super::snap::from_bifurcation`],
    /// [`super::snap::relax_from`]), and whether the side it started on was picked (a perfect
    /// symmetry).
    pub relaxed_from: Option<(f64, bool)>,
    /// The load factors of the folds at which the robot snapped and from which its states were
    /// reached by its damped motion just past the fold and the load path on from where that
    /// came to rest ([`super::snap::from_fold`]), the first fold first, and why (as in
    /// `snapped_from`).
    pub moved_from: Vec<(f64, bool)>,
    /// Whether the side picked led onto a family of equilibria (module `phase`): the states
    /// are one member, every other member equally valid.
    pub family: bool,
}

impl End {
    /// The end of a path that reached lambda = 1 by continuation (or a trace's end) at `x`.
    pub(super) fn reached(
        x: Vec<State>,
        folds: Vec<f64>,
        bifurcations: Vec<f64>,
        picked: Vec<f64>,
        family: bool,
    ) -> End {
        End {
            x,
            folds,
            bifurcations,
            picked,
            snapped_from: None,
            relaxed_from: None,
            moved_from: Vec::new(),
            family,
        }
    }

    /// The end of a path that lost stability at the bifurcation at load factor `from.0`
    /// with no stable branch to follow (`from.1`: its side was picked) and reached `x` by
    /// the robot's damped motion: the bifurcation joins `bifurcations`.
    pub(super) fn relaxed(
        x: Vec<State>,
        folds: Vec<f64>,
        mut bifurcations: Vec<f64>,
        picked: Vec<f64>,
        family: bool,
        from: (f64, bool),
    ) -> End {
        bifurcations.push(from.0);
        End {
            x,
            folds,
            bifurcations,
            picked,
            snapped_from: None,
            relaxed_from: Some(from),
            moved_from: Vec::new(),
            family,
        }
    }

    /// The end of a path whose states `x` were reached by Newton at lambda = 1 from its fold
    /// at load factor `from.0` ([`super::snap::land_from_folds`]); `from.1`: the path had
    /// reached lambda = 1 on an unstable state after its folds (else it could not be
    /// followed to the end).
    pub(super) fn landed(
        x: Vec<State>,
        folds: Vec<f64>,
        bifurcations: Vec<f64>,
        picked: Vec<f64>,
        family: bool,
        from: (f64, bool),
    ) -> End {
        End {
            x,
            folds,
            bifurcations,
            picked,
            snapped_from: Some(from),
            relaxed_from: None,
            moved_from: Vec::new(),
            family,
        }
    }
}

/// Where a path starts and what it connects.
pub(super) enum Start<'x> {
    /// The load path from the unloaded robot; if `land`, a path that loses stability at a
    /// bifurcation with no stable branch to follow snaps there ([`super::snap::from_bifurcation`]),
    /// and one that cannot be followed to the end lands from its folds
    /// ([`super::snap::land_from_folds`]): every solve's path but one that keeps to the branch
    /// of its warm start (a sweep's bisection, [`super::solve_on_branch`]), so that the
    /// bisection sees where that branch ends or loses stability.
    Rest {
        /// Whether the path may leave its branch: snap from a bifurcation, land from a fold.
        land: bool,
    },
    /// The Newton homotopy from a warm start (not a solution of the system).
    Warm(&'x [State]),
    /// The load path from `x`, a stable state at rest under the load factor `lambda` (where
    /// the robot's damped motion past a fold came to rest, [`super::snap::from_fold`]), to 1;
    /// it snaps and lands as [`Start::Rest`] with `land` true.
    Resting {
        /// The states at `lambda`.
        x: &'x [State],
        /// Its load factor.
        lambda: f64,
        /// How many motions from folds the solve ran before this path.
        chain: usize,
    },
    /// A trace of `parameter` from `from` (where `x` is the converged solution) towards
    /// `to`, recording every point; it ends where lambda leaves [0, 1].
    Trace {
        /// The states at `from`.
        x: &'x [State],
        /// The input traced.
        parameter: Parameter,
        /// Its first value.
        from: f64,
        /// Its last value.
        to: f64,
        /// The longest step (normalized arclength), for a resolved picture of the branch.
        max_step: f64,
        /// Asked before every step whether to give up (a front end's Ctrl-C).
        stop: &'x dyn Fn() -> bool,
    },
}

/// A point of a traced branch.
#[derive(Clone, Debug)]
pub(super) struct Recorded {
    /// The path parameter.
    pub lambda: f64,
    /// The tip state.
    pub tip: State,
    /// Unstable directions (None: unknown).
    pub unstable: Option<usize>,
    /// Whether the branch turned back at this point.
    pub fold: bool,
    /// Iterations (Newton and chord) spent on the path so far.
    pub iterations: usize,
}
