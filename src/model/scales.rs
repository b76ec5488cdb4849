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
//! | kappa r | the bend the tendons cause: the curvature kappa = \|sum tau_i r_i\| / EI of their net moment on a straight rod, times the offset r of the tendon furthest inside that bend (along it) | at or above 1 somewhere along the rod: the bend radius 1 / kappa would fall below that tendon's offset, the path of a tendon running along the backbone would fold, and no equilibrium exists past it unless loads or a precurvature (not counted) hold the bend back; a tendon winding around the rod (a helix) keeps a tangent across the backbone and can have equilibria past it (a one-turn helix at 1.01 does); for one tendon kappa r = tau r^2 / EI, the geometric limit EI / r^2; tendons pulled against each other (co-contraction) cause no bend and no warning |
//! | F a^2 / EI | a tip force (a = L) or point force (a = its s) against stiffness | above 100: the rod bends only within (EI/F)^(1/2) < a/10 of the load |
//! | M a / EI | the bending angle a tip or point moment alone causes (rad) | above 20 pi (ten turns) |
//! | path / span | a tendon's path length on the straight rod against the length of rod it spans | above 2: a helix steeper than 60 degrees (one whose pitch is below 3.6 times its radius), which a channel in a rod rarely is; usually a turn count per metre given as per rod length or a radius in mm |
//! | mu | a tendon's friction coefficient | above 1: tendon-channel pairs measure about 0.05 (PTFE) to 0.5 (steel on steel) |
//! | mu theta | a tendon's friction coefficient times its path's total turning theta on the straight rod (rad) | above 10: a pulled tendon passes on less than exp(-10) = 4.5e-5 of its tension to its termination, a released one more than 2.2e4 times it; no default mesh resolves such a fall |
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

use crate::Robot;
use nalgebra::Vector3;
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
/// Largest plausible ratio of a tendon's path length on the straight rod to the rod it
/// spans, 2: a helix at 60 degrees to the backbone.
pub const PATH_LIMIT: f64 = 2.0;
/// Largest plausible ratio of a tendon's largest offset from the backbone to the rod's
/// length, 1: wider than long is a robot of disks, not a rod (an offset typed in mm reads
/// as metres, 1000 times too far out).
pub const OFFSET_LIMIT: f64 = 1.0;
/// Largest plausible friction coefficient, 1 (tendon-channel pairs: about 0.05 to 0.5).
pub const FRICTION_LIMIT: f64 = 1.0;
/// Largest plausible mu theta of a tendon (theta its path's total turning on the straight
/// rod, rad), 10: the capstan factor exp(10) = 2.2e4.
pub const FRICTION_TURNING_LIMIT: f64 = 10.0;

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
    /// The bend the tendons cause, curvature x offset of the tendon furthest inside it, is at
    /// or above [`TENDON_LIMIT`] ([`crate::Robot::plausibility`] computes it).
    TendonBend {
        /// The tendon furthest inside the bend (from 0; messages number from 1).
        tendon: usize,
        /// Where the bend is sharpest against that offset (m).
        s: f64,
        /// |sum tau_i r_i| there: the tendons' net bending moment on a straight rod (N m).
        moment: f64,
        /// That tendon's offset along the bend's direction, r . d / |d| (m).
        offset: f64,
        /// EI there, N m^2.
        bending_stiffness: f64,
        /// The tension alone that would bring that tendon to the limit, EI / r^2 (N).
        limit: f64,
        /// Whether that tendon's routing winds around the rod there (r'(s) != 0, a helix):
        /// its path then keeps a tangent across the backbone and need not fold at the limit.
        winds: bool,
        /// Whether the rod is precurved there (a bending u*(s) != 0), which the figure leaves
        /// out and which can hold the bend back.
        precurved: bool,
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
    /// A tendon's path on the straight rod is more than [`PATH_LIMIT`] times the rod it spans.
    PathLength {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// Its path length on the straight rod, m.
        path: f64,
        /// The length of rod it spans (its termination's arc length), m.
        span: f64,
        /// The turns its routing makes about the backbone over that span.
        turns: f64,
    },
    /// A tendon's largest offset from the backbone is more than [`OFFSET_LIMIT`] times the
    /// rod's length.
    Offset {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// Its largest distance from the backbone along the rod it spans, m.
        offset: f64,
        /// The rod's length L, m.
        length: f64,
    },
    /// A tendon's friction coefficient is above [`FRICTION_LIMIT`].
    Friction {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// mu, dimensionless.
        coefficient: f64,
    },
    /// A tendon's friction coefficient times its path's total turning on the straight rod is
    /// above [`FRICTION_TURNING_LIMIT`].
    FrictionTurning {
        /// The tendon (from 0; messages number from 1).
        tendon: usize,
        /// mu, dimensionless.
        coefficient: f64,
        /// theta: the integral of its path's turning rate |t'| over the rod it spans, rad.
        turning: f64,
    },
}

/// The likely causes of `error`, a failure to solve `robot`: its implausible scales
/// ([`Robot::plausibility`]) when the solver did not converge, reached its interval cap or
/// broke down (scales far from a robot's are the usual reason); none for bad input, which
/// says what is wrong itself.
pub fn likely_causes(error: &crate::Error, robot: &Robot) -> Vec<Warning> {
    match error {
        crate::Error::NotConverged { .. } | crate::Error::IntervalCap { .. } | crate::Error::Breakdown { .. } => {
            robot.plausibility()
        }
        _ => Vec::new(),
    }
}

/// [`likely_causes`] of `error`, a failure to solve one of `robots` (a sweep's or a
/// history's steps, when the failure is not one step's): each robot's, once each.
pub fn likely_causes_of(error: &crate::Error, robots: &[Robot]) -> Vec<Warning> {
    let mut causes: Vec<Warning> = Vec::new();
    for robot in robots {
        for w in likely_causes(error, robot) {
            if !causes.contains(&w) {
                causes.push(w);
            }
        }
    }
    causes
}

/// `message` (a failure's, possibly several lines) with `causes` after its first line, as
/// an indented list headed `likely cause:` (or `likely causes:`): the form the command line
/// and the Python package print.
pub fn with_likely_causes(message: &str, causes: &[Warning]) -> String {
    if causes.is_empty() {
        return message.to_string();
    }
    let (head, rest) = message.split_once('\n').unwrap_or((message, ""));
    let mut out = format!("{head}\n  likely cause{}:\n", if causes.len() > 1 { "s" } else { "" });
    for w in causes {
        out.push_str(&format!("    {w}\n"));
    }
    out.push_str(rest);
    out
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
            Warning::TendonBend {
                moment,
                offset,
                bending_stiffness,
                ..
            } => moment / bending_stiffness * offset,
            Warning::SolvedTension {
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
            Warning::PathLength { path, span, .. } => path / span,
            Warning::Offset { offset, length, .. } => offset / length,
            Warning::Friction { coefficient, .. } => coefficient,
            Warning::FrictionTurning {
                coefficient, turning, ..
            } => coefficient * turning,
        }
    }
}

/// The sharpest bend the tendons cause ([`Warning::TendonBend`]) if it reaches
/// [`TENDON_LIMIT`]: at 33 evenly spaced arc lengths and at every tendon's end, the net moment
/// d = sum tau_i r_i of the tendons that reach there (their tensions about the backbone on a
/// straight rod: they bend it towards d), the curvature |d| / EI with EI the weaker bending
/// stiffness there, and of those tendons the taut one furthest along d, whose path the bend
/// shortens most (by the factor 1 - kappa r . d / |d|). Tension-controlled tendons only
/// (a displacement-controlled tendon's tension is solved for: [`Warning::SolvedTension`]).
pub(crate) fn tendon_bend(robot: &Robot) -> Option<Warning> {
    let length = robot.length();
    let ends: Vec<f64> = robot.tendons.iter().map(|t| t.end(length)).collect();
    let grid = (0..=32).map(|k| length * f64::from(k) / 32.0);
    let mut worst: Option<Warning> = None;
    for s in grid.chain(ends.clone()) {
        let active: Vec<(usize, &crate::Tendon)> = robot
            .tendons
            .iter()
            .enumerate()
            .filter(|(i, t)| ends[*i] >= s && t.displacement().is_none())
            .collect();
        let offset = |t: &crate::Tendon| t.routing.at(s, length).r;
        let d: Vector3<f64> = active.iter().map(|(_, t)| t.tension() * offset(t)).sum();
        let moment = d.norm();
        let k = robot.rod.section_at(s).section.kbt;
        let bending_stiffness = k[0].min(k[1]);
        if !(moment > 0.0 && bending_stiffness > 0.0) {
            continue;
        }
        // A slack tendon's path may fold: it goes slack. The first of equals is named.
        let inside = active
            .iter()
            .filter(|(_, t)| t.tension() > 0.0)
            .map(|&(i, t)| (i, offset(t).dot(&d) / moment, t.routing.max_offset(ends[i], length)));
        let Some((tendon, along, radius)) = inside.reduce(|a, b| if b.1 > a.1 { b } else { a }) else {
            continue;
        };
        let w = Warning::TendonBend {
            tendon,
            s,
            moment,
            offset: along,
            bending_stiffness,
            limit: bending_stiffness / (radius * radius),
            winds: robot.tendons[tendon].routing.at(s, length).r_s.norm() > 0.0,
            precurved: robot.rod.reference_at(s).u_star.xy().norm() > 0.0,
        };
        if worst.as_ref().is_none_or(|o| w.figure() > o.figure()) {
            worst = Some(w);
        }
    }
    worst.filter(|w| w.figure() >= TENDON_LIMIT)
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
            Warning::TendonBend {
                tendon,
                s,
                moment,
                offset,
                bending_stiffness,
                limit,
                winds,
                precurved,
            } => {
                let held = if precurved {
                    "loads or the rod's precurvature hold the bend back (neither is counted here)"
                } else {
                    "loads hold the bend back (they are not counted here)"
                };
                // A path running along the backbone folds where the bend radius reaches its
                // offset; one winding around the rod keeps its tangent across the backbone.
                let consequence = if winds {
                    format!(
                        "the bend would be tighter than the tendon's offset, so its path would run backwards \
                         along the backbone there; it winds around the rod, so the path need not fold and an \
                         equilibrium past 1 can exist (a one-turn helix at 1.01 has one), but a solve this \
                         near or past the limit may fail unless {held}"
                    )
                } else {
                    format!(
                        "the bend would be tighter than the tendon's offset, its path would fold, and no \
                         equilibrium exists past 1 unless {held}"
                    )
                };
                write!(
                    f,
                    "the tendons bend the rod at s = {} m with a moment of {} N m, a curvature of {} 1/m over \
                     EI = {} N m^2 (bend radius {} m); tendon {} runs {} m inside that bend, so curvature x \
                     offset = {} is {} 1: {consequence}; check the tensions' units (N) and the offsets (m), or \
                     lower the tensions (tendon {} alone reaches the limit at EI/r^2 = {} N)",
                    fig(s),
                    fig(moment),
                    fig(moment / bending_stiffness),
                    fig(bending_stiffness),
                    fig(bending_stiffness / moment),
                    tendon + 1,
                    fig(offset),
                    fig(x),
                    if x > TENDON_LIMIT { "past" } else { "at" },
                    tendon + 1,
                    fig(limit)
                )
            }
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
            Warning::PathLength {
                tendon,
                path,
                span,
                turns,
            } => write!(
                f,
                "tendon {}'s path on the straight rod is {} m long over {} m of rod ({} times, {} turns about \
                 the backbone), above {} times (a helix steeper than 60 degrees); check the routing: \
                 turns_per_rod_length counts the turns over the whole rod, and offsets are in metres",
                tendon + 1,
                fig(path),
                fig(span),
                fig(x),
                fig(turns),
                fig(PATH_LIMIT)
            ),
            Warning::Offset { tendon, offset, length } => write!(
                f,
                "tendon {} runs {} m from the backbone of a {} m rod ({} times its length, above {}); \
                 offsets are in metres (8 mm is 0.008)",
                tendon + 1,
                fig(offset),
                fig(length),
                fig(x),
                fig(OFFSET_LIMIT)
            ),
            Warning::Friction { tendon, coefficient } => write!(
                f,
                "tendon {}'s friction coefficient {} is above {}: tendon-channel pairs measure about 0.05 (PTFE) \
                 to 0.5 (steel on steel); check the value",
                tendon + 1,
                fig(coefficient),
                fig(FRICTION_LIMIT)
            ),
            Warning::FrictionTurning {
                tendon,
                coefficient,
                turning,
            } => write!(
                f,
                "tendon {}'s path turns by {} rad along the straight rod, so its friction coefficient {} gives \
                 mu theta = {}, above {}: pulled in, it passes on exp(-{}) = {} of its tension to its \
                 termination; released, {} times it. No default mesh resolves such a change, and a solve may \
                 fail or take minutes; check the routing (turns_per_rod_length, offsets in metres) and the \
                 coefficient",
                tendon + 1,
                fig(turning),
                fig(coefficient),
                fig(x),
                fig(FRICTION_TURNING_LIMIT),
                fig(x),
                fig((-x).exp()),
                fig(x.exp())
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

    /// Issues 25 and 28: the warning speaks of the bend the tendons cause together (the
    /// co-contracted are left out by the figure itself) and says that loads straightening the
    /// rod are not counted.
    #[test]
    fn the_bend_warning_says_what_it_does_not_count() {
        let text = Warning::TendonBend {
            tendon: 0,
            s: 0.0,
            moment: 0.8,
            offset: 0.008,
            bending_stiffness: 0.004_223,
            limit: 66.0,
            winds: false,
            precurved: false,
        }
        .to_string();
        assert!(
            text.contains("the tendons bend the rod") && text.contains("tendon 1 runs"),
            "{text}"
        );
        assert!(text.contains("unless loads hold the bend back"), "{text}");
    }

    /// The prototype in every experiment of Table 2 is a robot of ordinary scales, with
    /// friction 0.1 on every tendon too (the helical case H turns 1.5 rad: mu theta 0.15).
    #[test]
    fn table2_robots_have_no_warnings() {
        for e in cases::table2() {
            assert_eq!(e.robot().plausibility(), Vec::new(), "{}", e.label());
            let mut rough = e.robot();
            for t in &mut rough.tendons {
                t.friction = Some(crate::model::tendon::Friction::pull(0.1));
            }
            assert_eq!(rough.plausibility(), Vec::new(), "{} with friction", e.label());
        }
    }

    /// An offset typed in millimetres (8 for 0.008) is flagged by itself, with the tendon,
    /// the offset and the rod's length; the prototype's 8 mm on 0.242 m is not.
    #[test]
    fn an_offset_longer_than_the_rod_is_flagged() {
        let mut robot = cases::case_s();
        robot.tendons[2].routing = crate::model::routing::Routing::straight(0.0, 8.0);
        let warnings = robot.plausibility();
        let [
            Warning::Offset {
                tendon: 2,
                offset,
                length,
            },
        ] = warnings[..]
        else {
            panic!("{warnings:?}");
        };
        assert_eq!((offset, length), (8.0, robot.length()));
        let text = warnings[0].to_string();
        assert!(
            text.contains("tendon 3 runs 8 m from the backbone of a 0.242 m rod"),
            "{text}"
        );
    }

    /// A helix of 1000 turns over the prototype (a typo for turns per metre, or worse) is
    /// flagged by its path length, and with friction by mu theta: exactly the helix's
    /// (path = L sqrt(1 + (r w)^2), theta = L r w^2 / sqrt(1 + (r w)^2), w = 2 pi turns / L);
    /// a coefficient above 1 is flagged by itself.
    #[test]
    fn a_helix_of_many_turns_and_a_large_coefficient_are_flagged() {
        use crate::model::routing::Routing;
        use crate::model::tendon::Friction;
        let mut robot = cases::case_h();
        let length = robot.length();
        let r = 0.008;
        robot.tendons[0].routing = Routing::helical(r, 1000.0, 0.0);
        robot.tendons[0].friction = Some(Friction::pull(0.1));
        robot.tendons[1].friction = Some(Friction::pull(5.0));
        let warnings = robot.plausibility();
        let w = 2.0 * PI * 1000.0 / length;
        let root = (1.0 + (r * w).powi(2)).sqrt();
        let [
            Warning::PathLength { tendon: 0, path, .. },
            Warning::FrictionTurning { tendon: 0, turning, .. },
            Warning::Friction { tendon: 1, .. },
        ] = warnings[..]
        else {
            panic!("{warnings:?}");
        };
        // Rounding of the one-piece rule on a constant integrand.
        assert!((path / (length * root) - 1.0).abs() < 1e-12, "{path}");
        assert!((turning / (length * r * w * w / root) - 1.0).abs() < 1e-12, "{turning}");
        let text = warnings[1].to_string();
        assert!(
            text.contains("tendon 1's path turns by") && text.contains("mu theta = "),
            "{text}"
        );
    }
}
