//! The crate's one error type.

use crate::report::{Method, SolveReport};
use std::fmt;

/// Everything that can go wrong in tdcr. Each message says what is wrong, the values
/// involved, and what to try.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A field of the robot description or of the solver options is not acceptable.
    #[error("invalid input: `{field}` {problem}; {hint}")]
    InvalidInput {
        /// Path of the offending field, e.g. `tendons[2].termination`.
        field: String,
        /// What is wrong, with the value.
        problem: String,
        /// What to do about it.
        hint: String,
    },
    /// A tendon's path has (nearly) no tangent, so its force per unit length is undefined.
    #[error(
        "tendon {tendon} has a vanishing path tangent |p_i'| = {speed:.3e} at s = {s:.6} m; \
         its routing turns faster than the backbone can follow (|r'| too large or r, u* \
         cancel the axial strain); smooth or shorten the routing"
    )]
    SingularRouting {
        /// Index of the tendon (0-based).
        tendon: usize,
        /// Arc length (m).
        s: f64,
        /// |p_i'| in the body frame (dimensionless).
        speed: f64,
    },
    /// The model equations broke down numerically (singular eq. 13 matrix, non-finite
    /// values) at a state the solver visited.
    #[error(
        "the model equations broke down at s = {s:.6} m: {what}; the state is unphysical \
         (try load continuation, a finer mesh, or a warm start)"
    )]
    Breakdown {
        /// Arc length (m).
        s: f64,
        /// What failed.
        what: String,
    },
    /// A solver stopped without meeting its tolerances.
    #[error("{method} did not converge: {}; largest residual at s = {worst_s:.6} m; {hint}", report.termination)]
    NotConverged {
        /// Which solver.
        method: Method,
        /// The whole report: iterations, residual history, termination reason.
        report: Box<SolveReport>,
        /// Arc length (m) where the scaled residual is largest.
        worst_s: f64,
        /// What to try next.
        hint: String,
    },
    /// Error control needs more intervals than the cap allows to meet the tip tolerance.
    #[error(
        "meeting the tip tolerance needs more than the cap of {cap} intervals: the last mesh \
         has an estimated tip error of {estimate:.3e} m > tolerance {tolerance:.3e} m; raise \
         `max_intervals` or loosen `tolerance`"
    )]
    IntervalCap {
        /// The cap (intervals).
        cap: usize,
        /// Estimated tip position error of the last mesh solved (m).
        estimate: f64,
        /// The requested tolerance, tolerance x L (m).
        tolerance: f64,
    },
}

/// A number as messages print it, like C's `%g`: plain (shortest round-trip digits) for
/// ordinary magnitudes, scientific beyond 1e6 or below 1e-4, so that an extreme value reads
/// `-1e300`, not three hundred digits. `format!("is {} m", Readable(x))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readable(pub f64);

impl fmt::Display for Readable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        // 1e6 and 1e-4: the magnitudes where plain digits stop being quicker to read
        // (%g switches at 1e-5 and at its precision, 1e6 by default).
        if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

/// Shorthand for results in this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

pub(crate) fn invalid(field: impl Into<String>, problem: impl Into<String>, hint: impl Into<String>) -> Error {
    Error::InvalidInput {
        field: field.into(),
        problem: problem.into(),
        hint: hint.into(),
    }
}
