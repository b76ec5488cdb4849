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
    /// The input is valid, but the model (or the analysis asked) cannot answer it: a load
    /// history step whose stick/slip pattern the history does not model, an analysis that
    /// does not model friction yet. Changing the input (smaller steps, another analysis)
    /// may help; the input itself breaks no rule.
    #[error("outside the model: `{field}` {problem}; {hint}")]
    ModelLimit {
        /// Path of the field whose value takes the model past its limit, e.g.
        /// `tendons[0].friction`.
        field: String,
        /// What the model cannot answer, with the values.
        problem: String,
        /// What to try instead.
        hint: String,
    },
    /// A tendon's path has (nearly) no tangent, so its force per unit length is undefined.
    #[error(
        "tendon {} has a vanishing path tangent |p_i'| = {speed:.3e} at s = {s:.6} m; \
         its routing turns faster than the backbone can follow (|r'| too large or r, u* \
         cancel the axial strain); smooth or shorten the routing",
        tendon + 1
    )]
    SingularRouting {
        /// Index of the tendon (0-based; messages number tendons from 1, as robot files,
        /// parameters and the CLI do).
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
    /// Error control needs more intervals than the cap allows to meet the tip tolerance: a
    /// mesh of the cap (or the finest one it allows) was solved and misses it.
    #[error(
        "meeting the tip tolerance needs more than the cap of {cap} intervals: the last mesh \
         has {}; raise `max_intervals` or loosen `tolerance`",
        binding(*estimate, *tolerance, *rotation_estimate, *rotation_tolerance)
    )]
    IntervalCap {
        /// The cap (intervals).
        cap: usize,
        /// Estimated tip position error of the last mesh solved (m).
        estimate: f64,
        /// The requested position tolerance, tolerance x L (m).
        tolerance: f64,
        /// Estimated tip orientation error of the last mesh solved (rad).
        rotation_estimate: f64,
        /// The requested orientation tolerance (rad).
        rotation_tolerance: f64,
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

/// `x`, a number near 1 in magnitude that a message compares with 1 (a friction ratio
/// refused for exceeding 1), with enough decimals that it reads as different from 1: two
/// significant digits of |x| - 1, at least 3 decimals (`1.00040` for 1.0004, `1.500` for
/// 1.5), so that a refused `1.0004` is not printed `1.000`.
pub(crate) fn near_one(x: f64) -> String {
    let excess = (x.abs() - 1.0).abs();
    // 15 decimals: past them an f64 near 1 has no digits left to show.
    let decimals = if excess > 0.0 && excess.is_finite() {
        (1 - excess.log10().floor() as i64).clamp(3, 15) as usize
    } else {
        3
    };
    format!("{x:.decimals$}")
}

/// Which estimate of an [`Error::IntervalCap`] misses its tolerance, in words: the position,
/// the orientation or both, each with its value and tolerance (and, when only one binds, the
/// other's margin).
fn binding(position: f64, tolerance: f64, rotation: f64, rotation_tolerance: f64) -> String {
    let p = format!("an estimated tip position error of {position:.3e} m");
    let r = format!("an estimated tip orientation error of {rotation:.3e} rad");
    match (position > tolerance, rotation > rotation_tolerance) {
        (true, true) => format!("{p} > tolerance {tolerance:.3e} m and {r} > tolerance {rotation_tolerance:.3e} rad"),
        (false, true) => format!(
            "{r} > tolerance {rotation_tolerance:.3e} rad (its position error, {position:.3e} m, meets \
             the tolerance {tolerance:.3e} m)"
        ),
        _ => format!(
            "{p} > tolerance {tolerance:.3e} m (its orientation error, {rotation:.3e} rad, meets the \
             tolerance {rotation_tolerance:.3e} rad)"
        ),
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

/// How a hint names tendon `i`'s option `key` (e.g. `motion`) as something to change: its
/// field path in backquotes, `` `tendons[0].motion` ``, which the front ends spell as they
/// take it (`tdcr::io::user_message`: `--motion 1=release` on the command line).
pub(crate) fn option_token(i: usize, key: &str) -> String {
    format!("`tendons[{i}].{key}`")
}

/// An [`Error::ModelLimit`]: valid input the model cannot answer.
pub(crate) fn limit(field: impl Into<String>, problem: impl Into<String>, hint: impl Into<String>) -> Error {
    Error::ModelLimit {
        field: field.into(),
        problem: problem.into(),
        hint: hint.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ratio_near_one_shows_how_far_from_one_it_is() {
        // user24: w = -1.0004 was printed "1.000 times".
        assert_eq!(near_one(-1.0004), "-1.00040");
        assert_eq!(near_one(1.0004), "1.00040");
        assert_eq!(near_one(1.5), "1.500");
        assert_eq!(near_one(1.0 + 3e-9), "1.0000000030");
        assert_eq!(near_one(1.0), "1.000");
    }

    #[test]
    fn the_interval_cap_names_the_estimate_that_binds() {
        let cap = |estimate, rotation_estimate| Error::IntervalCap {
            cap: 64,
            estimate,
            tolerance: 1e-8,
            rotation_estimate,
            rotation_tolerance: 1e-7,
        };
        let orientation = cap(1e-10, 3e-7).to_string();
        assert!(
            orientation.contains("orientation error of 3.000e-7 rad > tolerance 1.000e-7 rad"),
            "{orientation}"
        );
        assert!(
            orientation.contains("position error, 1.000e-10 m, meets"),
            "{orientation}"
        );
        let position = cap(2e-8, 1e-8).to_string();
        assert!(
            position.contains("position error of 2.000e-8 m > tolerance 1.000e-8 m"),
            "{position}"
        );
        assert!(
            position.contains("orientation error, 1.000e-8 rad, meets"),
            "{position}"
        );
        let both = cap(2e-8, 3e-7).to_string();
        assert!(
            both.contains("m > tolerance") && both.contains("rad > tolerance"),
            "{both}"
        );
    }
}
