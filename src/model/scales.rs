//! Plausibility of a robot's scales: dimensionless figures that flag a likely unit mistake
//! or a load beyond what a default solve resolves, each with the plausible range and what
//! to try.
//!
//! None of these is an error: a robot outside every range may be intentional, and the
//! solvers accept it. [`crate::Robot::plausibility`] computes them (and
//! [`crate::Robot::solved_tensions`] the solved tensions' figure); the command line's check
//! and solve print them as warnings, and a failed solve names them as its likely cause.
//! Every figure compares a load with the bending stiffness EI (N m^2), the smallest of
//! E Ixx and E Iyy along the rod:
//!
//! | figure | meaning | warned when |
//! | --- | --- | --- |
//! | L | rod length | outside [1 mm, 10 m]: continuum robots are millimetres to metres long |
//! | L / r | slenderness (r the outer radius) | outside [5, 2e4]: rod theory needs a slender rod; beyond 2e4 a thread |
//! | E | Young's modulus | outside [1e4, 1e12] Pa: from soft silicones (about 5e4 Pa) to diamond (1.2e12 Pa) |
//! | w L^3 / EI | self weight (w the distributed force, N/m) against stiffness | above 1e3: the rod hangs like a string, bending only within (EI/w)^(1/3) < L/10 of its base |
//! | tau r^2 / EI | a tendon's tension against the geometric limit EI / r^2 (r its largest offset) | at or above 1: the bend radius EI / (tau r) would fall below the offset; past it, with nothing holding the bend back (antagonist tendons, loads), the tendon path folds and no equilibrium exists |
//! | F a^2 / EI | a tip force (a = L) or point force (a = its s) against stiffness | above 100: the rod bends only within (EI/F)^(1/2) < a/10 of the load |
//! | M a / EI | the bending angle a tip or point moment alone causes (rad) | above 20 pi (ten turns) |
//!
//! A displacement-controlled tendon's tension is solved for, so these figures cannot check
//! it; [`crate::Robot::solved_tensions`] holds a solution's tensions to the same geometric limit
//! ([`Warning::SolvedTension`]): a displacement solve can converge past it when actuators
//! hold antagonistic tendons that the pull stretches and the tendons fight each other.
//!
//! The thresholds come from the solves that fail and those that do not: the prototype's
//! rod at 1 m (w L^3 / EI = 111) hangs and converges, at E = 1 MPa (3e5) it fails on every
//! mesh a default solve tries; a tendon at 0.97 EI / r^2 converges and at 1.1 EI / r^2 has
//! no solution (tests/hard.rs). The Table 2 experiments stay well inside every range
//! (w L^3 / EI = 1.6, tau r^2 / EI <= 0.074, F L^2 / EI <= 2.7).

use std::f64::consts::PI;
use std::fmt;

/// Plausible rod lengths (m): 1 mm to 10 m.
pub const LENGTH_RANGE: (f64, f64) = (1e-3, 10.0);
/// Plausible slenderness L / r: 5 (rod theory assumes a cross-section small against the
/// length) to 2e4 (a 1 m rod of 0.05 mm radius).
pub const SLENDERNESS_RANGE: (f64, f64) = (5.0, 2e4);
/// Plausible Young's moduli (Pa): 1e4 (below the softest silicones of soft robots, about
/// 5e4) to 1e12 (diamond, 1.2e12).
pub const MODULUS_RANGE: (f64, f64) = (1e4, 1e12);
/// Largest plausible w L^3 / EI, 1e3: the bending length (EI/w)^(1/3) is then L/10.
pub const SELF_WEIGHT_LIMIT: f64 = 1e3;
/// The geometric limit of a tendon, tau r^2 / EI = 1: the bend radius equals the offset.
pub const TENDON_LIMIT: f64 = 1.0;
/// Largest plausible F a^2 / EI, 100: the bending length (EI/F)^(1/2) is then a/10.
pub const FORCE_LIMIT: f64 = 100.0;
/// Largest plausible bending angle of a moment, M a / EI, 20 pi rad (ten turns).
pub const MOMENT_LIMIT: f64 = 20.0 * PI;

/// Where a force or moment acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadSite {
    /// The tip load.
    Tip,
    /// Point load `i` of `loads.point` (from 0; messages number from 1).
    Point(usize),
}

/// A figure of the robot outside its plausible range ([`crate::Robot::plausibility`]), with the
/// numbers it was computed from (SI units).
#[derive(Clone, Debug, PartialEq)]
pub enum Warning {
    /// The rod length L (m) is outside [`LENGTH_RANGE`].
    Length {
        /// L, m.
        length: f64,
    },
    /// The slenderness L / r is outside [`SLENDERNESS_RANGE`].
    Slenderness {
        /// L, m.
        length: f64,
        /// The outer radius r (m), or for a rod given by its stiffnesses the radius of the
        /// solid circle with the same EI / EA.
        radius: f64,
    },
    /// Young's modulus E (Pa) is outside [`MODULUS_RANGE`].
    Modulus {
        /// E, Pa.
        youngs_modulus: f64,
    },
    /// The distributed force against the stiffness, w L^3 / EI, is above
    /// [`SELF_WEIGHT_LIMIT`].
    SelfWeight {
        /// |distributed force| w, the largest along the rod (N/m).
        weight_per_length: f64,
        /// L, m.
        length: f64,
        /// EI, N m^2.
        bending_stiffness: f64,
    },
    /// A tendon's tension x offset^2 against EI is at or above [`TENDON_LIMIT`].
    TendonCurl {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// tau, N.
        tension: f64,
        /// The tendon's largest offset |r| from the backbone, m.
        offset: f64,
        /// EI, N m^2.
        bending_stiffness: f64,
    },
    /// The solved tension of a displacement-controlled tendon ([`crate::Robot::solved_tensions`])
    /// times its offset^2 against EI is at or above [`TENDON_LIMIT`]: the solve converged,
    /// but to a tension past the limit no tension input may reach, which is what tendons
    /// that fight each other give (actuators holding antagonists that the pull stretches).
    SolvedTension {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// The solved tension tau, N.
        tension: f64,
        /// The tendon's actuator pull-in q, m.
        displacement: f64,
        /// The tendon's largest offset |r| from the backbone, m.
        offset: f64,
        /// EI, N m^2.
        bending_stiffness: f64,
    },
    /// A tip or point force against the stiffness, F a^2 / EI, is above [`FORCE_LIMIT`].
    Force {
        /// Where it acts.
        site: LoadSite,
        /// |F|, N.
        force: f64,
        /// a: the arc length where it acts (L for the tip), m.
        arm: f64,
        /// EI, N m^2.
        bending_stiffness: f64,
    },
    /// A tip or point moment's bending angle M a / EI is above [`MOMENT_LIMIT`].
    Moment {
        /// Where it acts.
        site: LoadSite,
        /// |M|, N m.
        moment: f64,
        /// a: the arc length where it acts (L for the tip), m.
        arm: f64,
        /// EI, N m^2.
        bending_stiffness: f64,
    },
}

impl Warning {
    /// The dimensionless figure the warning is about (L in m for [`Warning::Length`], E in
    /// Pa for [`Warning::Modulus`]).
    pub fn figure(&self) -> f64 {
        match *self {
            Warning::Length { length } => length,
            Warning::Slenderness { length, radius } => length / radius,
            Warning::Modulus { youngs_modulus } => youngs_modulus,
            Warning::SelfWeight {
                weight_per_length,
                length,
                bending_stiffness,
            } => weight_per_length * length.powi(3) / bending_stiffness,
            Warning::TendonCurl {
                tension,
                offset,
                bending_stiffness,
                ..
            }
            | Warning::SolvedTension {
                tension,
                offset,
                bending_stiffness,
                ..
            } => tension * offset * offset / bending_stiffness,
            Warning::Force {
                force,
                arm,
                bending_stiffness,
                ..
            } => force * arm * arm / bending_stiffness,
            Warning::Moment {
                moment,
                arm,
                bending_stiffness,
                ..
            } => moment * arm / bending_stiffness,
        }
    }
}

/// `x` to 3 significant digits, plain from 1e-3 to 1e5 and scientific beyond.
fn fig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if (1e-3..1e5).contains(&x.abs()) {
        let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.2e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// How a message names a load site.
fn site(s: LoadSite) -> String {
    match s {
        LoadSite::Tip => "tip".into(),
        LoadSite::Point(i) => format!("point load {} (loads.point[{}])", i + 1, i + 1),
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.figure();
        match *self {
            Warning::Length { length } => write!(
                f,
                "rod length {} m is outside the plausible {} to {} m of continuum robots; lengths are \
                 in metres (0.242, not 242 for 242 mm)",
                fig(length),
                fig(LENGTH_RANGE.0),
                fig(LENGTH_RANGE.1)
            ),
            Warning::Slenderness { length, radius } => write!(
                f,
                "slenderness L/r = {} m / {} m = {} is outside the plausible {} to {}: {}; check that \
                 length and outer_radius are both in metres",
                fig(length),
                fig(radius),
                fig(x),
                fig(SLENDERNESS_RANGE.0),
                fig(SLENDERNESS_RANGE.1),
                if x < SLENDERNESS_RANGE.0 {
                    "rod theory describes slender rods, and this one is stubby"
                } else {
                    "a thread rather than a rod"
                }
            ),
            Warning::Modulus { youngs_modulus } => write!(
                f,
                "Young's modulus {} Pa is outside the plausible {:e} to {:e} Pa (soft silicone about 5e4, \
                 Nitinol 5e10 to 8e10, steel 2.1e11); it is in Pa (210e9 for steel, not 210)",
                fig(youngs_modulus),
                MODULUS_RANGE.0,
                MODULUS_RANGE.1
            ),
            Warning::SelfWeight {
                weight_per_length,
                length,
                bending_stiffness,
            } => write!(
                f,
                "self weight w L^3/(EI) = {} N/m x ({} m)^3 / {} N m^2 = {} is above {}: the rod cannot carry \
                 its own weight and hangs like a string, bending only within (EI/w)^(1/3) = {} m of its base, \
                 which needs a fine mesh; check the units of distributed_force (N/m), the modulus (Pa) and \
                 the radius (m)",
                fig(weight_per_length),
                fig(length),
                fig(bending_stiffness),
                fig(x),
                fig(SELF_WEIGHT_LIMIT),
                fig((bending_stiffness / weight_per_length).cbrt())
            ),
            Warning::TendonCurl {
                tendon,
                tension,
                offset,
                bending_stiffness,
            } => write!(
                f,
                "tendon {}: tension {} N x offset^2 ({} m)^2 = {} N m^2 is {}x the bending stiffness EI = {} N m^2: \
                 {} the geometric limit EI/r^2 = {} N: bent by this tendon alone, the rod would curl tighter \
                 than the tendon offset (bend radius EI/(tau r) = {} m against the offset {} m), and past the \
                 limit no equilibrium exists unless other tendons or loads hold the bend back (antagonists \
                 pulling against it, a load that straightens it); check the tension's units (N) and the \
                 offset (m), or lower the tension below {} N",
                tendon + 1,
                fig(tension),
                fig(offset),
                fig(tension * offset * offset),
                fig(x),
                fig(bending_stiffness),
                if x > TENDON_LIMIT { "past" } else { "at" },
                fig(bending_stiffness / (offset * offset)),
                fig(bending_stiffness / (tension * offset)),
                fig(offset),
                fig(bending_stiffness / (offset * offset))
            ),
            Warning::SolvedTension {
                tendon,
                tension,
                displacement,
                offset,
                bending_stiffness,
            } => write!(
                f,
                "tendon {}: solved tension {} N (actuator pull-in {} m) x offset^2 ({} m)^2 = {} N m^2 is {}x \
                 the bending stiffness EI = {} N m^2: {} the geometric limit EI/r^2 = {} N that bounds a tension \
                 input (a tension-controlled tendon has no equilibrium beyond it). Displacement control reaches \
                 such tensions when actuators hold antagonistic tendons that the pull stretches (a bend lengthens \
                 the paths on its far side): held at their pull-ins, they pull back, and the tendons compress the \
                 rod instead of bending it. Let the antagonists out (a negative displacement, about the \
                 lengthening of their paths; a solution reports each tendon's length), drive them by tension (e.g. \
                 tension = 0), or pull in less",
                tendon + 1,
                fig(tension),
                fig(displacement),
                fig(offset),
                fig(tension * offset * offset),
                fig(x),
                fig(bending_stiffness),
                if x > TENDON_LIMIT { "past" } else { "at" },
                fig(bending_stiffness / (offset * offset)),
            ),
            Warning::Force {
                site: s,
                force,
                arm,
                bending_stiffness,
            } => write!(
                f,
                "{} force {} N x ({} m)^2 / EI = {} is above {} (EI/a^2 = {} N): the rod bends only within \
                 (EI/F)^(1/2) = {} m of the load and may buckle; check the force's units (N)",
                site(s),
                fig(force),
                fig(arm),
                fig(x),
                fig(FORCE_LIMIT),
                fig(bending_stiffness / (arm * arm)),
                fig((bending_stiffness / force).sqrt())
            ),
            Warning::Moment {
                site: s,
                moment,
                arm,
                bending_stiffness,
            } => write!(
                f,
                "{} moment {} N m at a = {} m alone bends the rod by M a/EI = {} rad ({} turns), above {} \
                 turns; check the moment's units (N m; EI = {} N m^2)",
                site(s),
                fig(moment),
                fig(arm),
                fig(x),
                fig(x / (2.0 * PI)),
                fig(MOMENT_LIMIT / (2.0 * PI)),
                fig(bending_stiffness)
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;

    #[test]
    fn figures_print_three_significant_digits() {
        assert_eq!(fig(66.3245), "66.3");
        assert_eq!(fig(2940.0), "2940");
        assert_eq!(fig(0.004_223), "0.00422");
        assert_eq!(fig(366_000.0), "3.66e5");
        assert_eq!(fig(200.0), "200");
        assert_eq!(fig(1e-5), "1e-5");
    }

    /// Issue 25: co-contracted robots past a tendon's limit converge, so the warning says
    /// the limit holds for the tendon bending the rod alone.
    #[test]
    fn the_curl_warning_allows_for_what_holds_the_bend_back() {
        let text = Warning::TendonCurl {
            tendon: 0,
            tension: 100.0,
            offset: 0.008,
            bending_stiffness: 0.004_223,
        }
        .to_string();
        assert!(
            text.contains("tendon 1:") && text.contains("bent by this tendon alone"),
            "{text}"
        );
        assert!(
            text.contains("unless other tendons or loads hold the bend back"),
            "{text}"
        );
    }

    /// The prototype in every experiment of Table 2 is a robot of ordinary scales.
    #[test]
    fn table2_robots_have_no_warnings() {
        for e in cases::table2() {
            assert_eq!(e.robot().plausibility(), Vec::new(), "{}", e.label());
        }
    }
}
