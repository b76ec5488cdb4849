//! A quasi-static load history with stick/slip friction (docs/friction.md section 8): the
//! steps of [`Ranges`] solved in order, each from the tendon state the step before left
//! (which material of every tendon with friction sits where, and how stretched), so that
//! each stretch of tendon slides in, slides out or sticks as Coulomb's law says. Pulling a
//! tendon and letting it back out then follows two different branches: the hysteresis loop.
//! `tdcr sweep --history` and Python's `tdcr.history` both run it.
//!
//! The first step starts from rest: every tendon with friction slack in its channel, with
//! no material laid, so a loaded one is pulled in and slides all along (the full-slip pull
//! solve of the step's inputs; a step after one that left every tendon with friction slack
//! is loaded from rest too, and starts again from that solve where Newton from the slack
//! shape fails). All steps share one mesh, the one the default full-slip `pull` solve picks for the step
//! with the most tension on the tendons with friction, so that the material carried from
//! step to step sits on the same nodes.
//!
//! ```
//! use tdcr::analysis::history::{history, Contact};
//! use tdcr::analysis::sweep::{Input, Ranges};
//! use tdcr::{Friction, Parameter};
//! let mut robot = tdcr::cases::case_s();
//! robot.tendons[0].friction = Some(Friction::pull(0.1));
//! robot.tendons[0].stiffness = Some(2000.0);
//! let up = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), vec![0.0, 1.0, 2.0, 3.0, 4.0])]).unwrap();
//! let result = history(&up.up_down(), &Default::default()).unwrap();
//! assert!(result.failure.is_none());
//! // Letting the tendon out from 4 N to 3 N leaves part of it stuck.
//! let back = &result.steps[5];
//! assert!(back.zones[0].zones.iter().any(|z| z.contact == Contact::Stick));
//! ```

use super::sweep::Ranges;
use crate::collocation::dynamics::stuck;
use crate::collocation::{self, friction};
use crate::error::{Error, Result, invalid};
use crate::solution::Solution;

pub use crate::collocation::friction::Contact;

/// A stretch of a tendon with one contact during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zone {
    /// Where it starts (m, arc length of the backbone).
    pub start: f64,
    /// Where it ends (m).
    pub end: f64,
    /// How the tendon moves there during the step.
    pub contact: Contact,
}

/// The zones of one tendon with friction, from its base entry to its termination.
#[derive(Clone, Debug, PartialEq)]
pub struct TendonZones {
    /// The tendon (index in the robot, from 0).
    pub tendon: usize,
    /// Its zones in order.
    pub zones: Vec<Zone>,
}

/// One solved step of a history.
#[derive(Clone, Debug)]
pub struct HistoryStep {
    /// The solution, with the tension along every tendon ([`Solution::tendon_tensions`]).
    pub solution: Solution,
    /// The stick/slip zones of each tendon with friction.
    pub zones: Vec<TendonZones>,
}

/// The result of [`history`]: the steps solved, in order, and the failure that ended the
/// history early, if one did.
#[derive(Debug)]
pub struct HistoryResult {
    /// The steps solved, up to the first failure.
    pub steps: Vec<HistoryStep>,
    /// The step (from 0) that failed and its error; `None` when every step solved.
    pub failure: Option<(usize, Error)>,
}

/// The direction of each step of `ranges`' swept input ([`Ranges::swept`], the first input
/// that changes): `from_rest` for the first step, which is loaded from rest (every loaded
/// tendon with friction pulled in and sliding all along: the full-slip solve of its inputs,
/// docs/friction.md section 8, "From rest"), then `up` where the input rose from the step
/// before, `down` where it fell and `held` where it did not change: the CSV's `direction`
/// column and Python's `History.directions`.
pub fn directions(ranges: &Ranges) -> Vec<&'static str> {
    let swept = ranges.swept().map_or(0, |(i, _)| i);
    (0..ranges.steps())
        .map(|k| {
            let Some(p) = k.checked_sub(1) else {
                return FROM_REST;
            };
            let change = ranges.value(swept, k as f64) - ranges.value(swept, p as f64);
            if change > 0.0 {
                "up"
            } else if change < 0.0 {
                "down"
            } else {
                "held"
            }
        })
        .collect()
}

/// The direction of a history's first step ([`directions`]): loaded from rest.
pub const FROM_REST: &str = "from_rest";

/// The tip's displacement (m) at each of a history's steps from its place at the first:
/// |p(L)_k - p(L)_0| for the `solutions` in order (empty for none). The y axis of the
/// hysteresis loop by default ([`LoopAxis::TipDisplacement`]) and Python's
/// `History.tip_displacements`.
pub fn tip_displacements<'a>(solutions: impl IntoIterator<Item = &'a Solution>) -> Vec<f64> {
    let tips: Vec<_> = solutions.into_iter().map(Solution::tip_position).collect();
    tips.iter().map(|p| (p - tips[0]).norm()).collect()
}

/// What the y axis of a history's hysteresis loop shows against the swept input (`tdcr
/// sweep --history --plot --loop-y NAME`, Python's `History.loop_axis` and
/// `tdcr.plot_history(y=NAME)`). The displacement is a distance, so it is never negative:
/// a loop whose unloading branch lies below its loading branch in displacement may lie
/// above it in a tip coordinate (docs/cli.md: the prototype's tendon pulled in and let
/// out, whose tip lies above in x and z on the way back).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LoopAxis {
    /// The tip's displacement from the first step (mm), [`tip_displacements`]: `tip_displacement`.
    #[default]
    TipDisplacement,
    /// The bending angle (degrees; [`crate::analysis::samples::bending_angle`]): `bending_angle`.
    BendingAngle,
    /// One coordinate of the tip (mm, world frame; 0 for x, 1 for y, 2 for z): `tip_x`,
    /// `tip_y`, `tip_z`.
    Tip(usize),
}

impl LoopAxis {
    /// The names the command line and Python take, in the order of [`LoopAxis::ALL`].
    pub const NAMES: [&'static str; 5] = ["tip_displacement", "bending_angle", "tip_x", "tip_y", "tip_z"];
    /// Every axis, in the order of [`LoopAxis::NAMES`].
    pub const ALL: [LoopAxis; 5] = [
        LoopAxis::TipDisplacement,
        LoopAxis::BendingAngle,
        LoopAxis::Tip(0),
        LoopAxis::Tip(1),
        LoopAxis::Tip(2),
    ];

    /// The axis of `name` (one of [`LoopAxis::NAMES`]).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the choices for any other name.
    pub fn parse(name: &str) -> Result<LoopAxis> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
            .ok_or_else(|| {
                invalid(
                    "the loop's y axis",
                    format!("is `{name}`, which is not a quantity of a history step"),
                    format!("give one of {}", Self::NAMES.join(", ")),
                )
            })
    }

    /// The axis's label, with its unit.
    pub fn label(self) -> &'static str {
        match self {
            LoopAxis::TipDisplacement => "tip displacement from the first step (mm)",
            LoopAxis::BendingAngle => "bending angle (deg)",
            LoopAxis::Tip(0) => "tip x (mm)",
            LoopAxis::Tip(1) => "tip y (mm)",
            LoopAxis::Tip(_) => "tip z (mm)",
        }
    }

    /// The axis's value at each of the `solutions` of a history's steps (in order), in the
    /// unit of [`LoopAxis::label`] (mm or degrees).
    pub fn values<'a>(self, solutions: impl IntoIterator<Item = &'a Solution>) -> Vec<f64> {
        let solutions = solutions.into_iter();
        match self {
            LoopAxis::TipDisplacement => tip_displacements(solutions).iter().map(|d| d * 1e3).collect(),
            LoopAxis::BendingAngle => solutions
                .map(|s| crate::analysis::samples::bending_angle(s).to_degrees())
                .collect(),
            LoopAxis::Tip(i) => solutions.map(|s| s.tip_position()[i.min(2)] * 1e3).collect(),
        }
    }
}

/// Solves the steps of `ranges` as a history with stick/slip friction (module docs), by
/// collocation with `options`, stopping at the first step that fails
/// ([`HistoryResult::failure`]). The friction coefficients are the tendons'; their
/// `motion` is not used (the history decides where each tendon slides, and which way).
///
/// # Errors
/// Before any step: invalid options or robots, no tendon with friction; the first step's
/// mesh-choosing solve failing. A step whose pull-ins' tensions are not found (Newton on
/// the tensions, docs/friction.md section 3b) is that step's failure.
pub fn history(ranges: &Ranges, options: &collocation::Options) -> Result<HistoryResult> {
    history_until(ranges, options, &|| false)
}

/// [`history`], asking `stop` before every step after the first whether to give up (a
/// front end's Ctrl-C): the steps solved up to there are returned, with no failure.
///
/// # Errors
/// As [`history`].
pub fn history_until(
    ranges: &Ranges,
    options: &collocation::Options,
    stop: &dyn Fn() -> bool,
) -> Result<HistoryResult> {
    options.validate()?;
    let robots = (0..ranges.steps())
        .map(|k| ranges.robot(k as f64))
        .collect::<Result<Vec<_>>>()?;
    for robot in &robots {
        robot.validate()?;
    }
    if !crate::model::friction::any(&robots[0]) {
        return Err(invalid(
            "tendons",
            "(the robot's tendons): none has friction, so a history has nothing to carry from step to step",
            "give a tendon friction (robot file `friction = 0.1`, command line --friction I=MU), or run a plain sweep",
        ));
    }
    let mut carried = friction::history::start(&robots, options)?;
    let mut steps: Vec<HistoryStep> = Vec::with_capacity(robots.len());
    for (k, robot) in robots.iter().enumerate() {
        if k > 0 && stop() {
            break;
        }
        // A step whose inputs are the last step's: nothing is driven, so nothing slides.
        let repeated =
            k > 0 && (0..ranges.inputs().len()).all(|i| ranges.value(i, k as f64) == ranges.value(i, (k - 1) as f64));
        if let Some(step) = steps
            .last()
            .filter(|_| repeated)
            .and_then(|last| held(robot, &mut carried, last))
        {
            steps.push(step);
            continue;
        }
        let start = std::time::Instant::now();
        // After a step that left every tendon with friction slack, this one is loaded from
        // rest: where Newton from the slack shape fails, it starts again from rest, from the
        // full-slip pull solve of its inputs (docs/friction.md section 8, "From rest").
        let from_rest = friction::history::all_slack(&carried, robot);
        let mut answer = solve_step(robot, options, &mut carried, &steps);
        if from_rest && let Err(Error::NotConverged { report: failed, .. }) = &answer {
            let failed = (**failed).clone();
            answer = friction::history::restart(robot, options, &mut carried).and_then(|first| {
                let mut answer = solve_step(robot, options, &mut carried, &steps)?;
                // The step's work: the failed attempt's, the full-slip solve's and its own.
                for done in [&failed, &first] {
                    let report = &mut answer.0.report;
                    report.iterations += done.iterations;
                    report.newton_steps += done.newton_steps;
                    report.chord_steps += done.chord_steps;
                    report.load_steps += done.load_steps;
                }
                Ok(answer)
            });
        }
        match answer {
            Ok((mut solution, zones)) => steps.push(HistoryStep {
                solution: {
                    // The whole step's time: its split levels, trial tensions and verdict
                    // included, which its parts' sums count too.
                    solution.report.timings.total = start.elapsed();
                    solution
                },
                zones: zones
                    .into_iter()
                    .map(|(tendon, list)| TendonZones {
                        tendon,
                        zones: list
                            .into_iter()
                            .map(|(start, end, contact)| Zone { start, end, contact })
                            .collect(),
                    })
                    .collect(),
            }),
            Err(e) => {
                return Ok(HistoryResult {
                    steps,
                    failure: Some((k, e)),
                });
            }
        }
    }
    Ok(HistoryResult { steps, failure: None })
}

/// One step of `robot` from the `carried` state after the `steps` solved before it: a
/// pull-in step ([`pulled_step`]) or a tension step, with its verdict.
fn solve_step(
    robot: &crate::Robot,
    options: &collocation::Options,
    carried: &mut friction::history::Carried,
    steps: &[HistoryStep],
) -> Result<friction::history::StepAnswer> {
    if robot.has_displacement_inputs() {
        let mut back = steps.iter().rev().map(|s| &s.solution);
        return pulled_step(robot, options, carried, (back.next(), back.next()));
    }
    let (mut solution, zones) = friction::history::step(robot, options, carried)?;
    // The step's answer is final: its verdict, with the step's pattern held.
    stuck::assess_step(robot, carried, &mut solution.report);
    Ok((solution, zones))
}

/// The note of a step whose inputs repeat the last step's: its answer is the last one, stuck all
/// along (docs/friction.md section 8, "A repeated step").
pub const REPEATED: &str = "the inputs repeat the last step's: nothing is driven, so nothing slides, and the last \
     step's answer (its estimate included) is this step's, every loaded tendon with friction stuck all along";

/// A step of `robot` whose inputs equal those of the `last` step (docs/friction.md section
/// 8, "A repeated step"): the last answer, with no iterations, its estimate, the note
/// [`REPEATED`], every loaded tendon with friction stuck all along (a slack one stays
/// slack), and its own stability verdict with that pattern held. `carried` keeps the last
/// state. None where a loaded tendon with friction is rigid (the step is then solved).
fn held(robot: &crate::Robot, carried: &mut friction::history::Carried, last: &HistoryStep) -> Option<HistoryStep> {
    let solved = robot.with_tensions(&last.solution.tensions());
    if !friction::history::hold_last(&solved, carried) {
        return None;
    }
    let mut solution = last.solution.clone();
    let report = &mut solution.report;
    (
        report.iterations,
        report.newton_steps,
        report.chord_steps,
        report.load_steps,
    ) = (0, 0, 0, 0);
    report.history.clear();
    report.evaluations = Default::default();
    report.timings = Default::default();
    report.notes.retain(|n| n != stuck::STICK_HELD && n != REPEATED);
    report.notes.push(REPEATED.into());
    if robot.has_displacement_inputs() {
        stuck::assess_pulled(robot, carried, &mut solution);
    } else {
        stuck::assess_step(robot, carried, &mut solution.report);
    }
    let zones = last
        .zones
        .iter()
        .map(|t| {
            let (start, end) = (
                t.zones.first().map_or(0.0, |z| z.start),
                t.zones.last().map_or(0.0, |z| z.end),
            );
            let slack = t.zones.iter().all(|z| z.contact == Contact::Slack);
            let contact = if slack { Contact::Slack } else { Contact::Stick };
            TendonZones {
                tendon: t.tendon,
                zones: vec![Zone { start, end, contact }],
            }
        })
        .collect();
    Some(HistoryStep { solution, zones })
}

/// One step of a history whose `robot` has displacement-controlled tendons: their pull-ins
/// fix the base tensions ([`crate::model::pull_in::hold`]), each trial tension a step from
/// the `carried` state, which then holds the last trial's (the one at the tensions found).
/// Newton starts from the tensions [`predicted`] from the `last` step and the one `before`
/// it, or the full-slip solve's on the first.
fn pulled_step(
    robot: &crate::Robot,
    options: &collocation::Options,
    carried: &mut friction::history::Carried,
    (last, before): (Option<&Solution>, Option<&Solution>),
) -> Result<friction::history::StepAnswer> {
    // A rigid tendon with friction at the last step's tension is stuck all along (nothing
    // is driven), which is statically indeterminate and refused: where no secant moves
    // the second step's start off it, the start is the full-slip solve's, as the first's.
    let rigid = robot
        .tendons
        .iter()
        .any(|t| t.displacement().is_some() && t.active_friction().is_some() && t.stiffness.is_none());
    let start = match last {
        Some(w) if !(rigid && before.is_none()) => predicted(robot, w, before),
        _ => collocation::solve(robot, options)?.tensions(),
    };
    let mut kept = None;
    let solution = crate::model::pull_in::hold(
        robot,
        &start,
        last,
        options.residual_tolerance,
        |r, _| {
            let mut trial = carried.snapshot();
            let (solution, zones) = friction::history::step(r, options, &mut trial)?;
            kept = Some((trial, zones));
            Ok(solution)
        },
        |at, solution, held| toward_root(robot, options, carried, (at, solution), held),
    )?;
    let (trial, zones) = kept.ok_or_else(|| invalid("tendons", "have no solved step", "report this as a bug"))?;
    *carried = trial;
    let mut solution = solution;
    // The step's answer is final: its verdict, with the step's pattern and the pull-ins held.
    stuck::assess_pulled(robot, carried, &mut solution);
    Ok((solution, zones))
}

/// The base tensions a pull-in step of `robot` starts its Newton from: the `last` step's,
/// each held tendon's moved along the secant of its pull-in against its tension over the
/// last two steps (`before`, `last`) to its new pull-in (not below 0 N). The last step's
/// tension itself is a kink of the step's pull-in (see [`toward_root`]) and a tie for every
/// link of the march, whose stuck profile there is the last answer's; the secant's tension
/// lies off it, on the side of the root. Where the secant is missing (the second step, a
/// slack or unmoved tendon), not increasing, or behind the input's new direction (a
/// reversal), the last step's tension.
fn predicted(robot: &crate::Robot, last: &Solution, before: Option<&Solution>) -> Vec<f64> {
    let mut tensions = last.tensions();
    let Some(before) = before else {
        return tensions;
    };
    for (i, tendon) in robot.tendons.iter().enumerate() {
        let Some(q) = tendon.displacement() else {
            continue;
        };
        let (a, b) = (&before.tendons[i], &last.tendons[i]);
        let slope = (b.displacement - a.displacement) / (b.tension - a.tension);
        // At a reversal the secant spans the stuck kink (a slope near zero): not used there.
        let onward = (q - b.displacement) * (b.displacement - a.displacement) > 0.0;
        if onward && a.tension > 0.0 && b.tension > 0.0 && slope.is_finite() && slope > 0.0 {
            tensions[i] = (b.tension + (q - b.displacement) / slope).max(0.0);
        }
    }
    tensions
}

/// Relative size of the one-sided difference of a pull-in in its base tension, of
/// max(tau, T) (T the tendon's tension scale), as the full solve's forward difference
/// (`model::pull_in`): the steps resolve the pull-in to about 1e-13 m, so the difference is
/// accurate to about 1e-4 relative, which only slows Newton's contraction.
const STEP: f64 = 1e-5;

/// dphi/dtau of the `held` tendons of a history step (`robot`, displacement-controlled) at
/// `solution`, solved at the tensions of `at` from the `carried` state, row major: one
/// one-sided difference per held tendon, each a step from `carried` at a tension moved
/// toward the pull-in's root (down where the tendon holds too much pull-in, else up).
///
/// The pull-in of a history step is not differentiable at the last step's tension, where
/// Newton on the tensions starts (docs/friction.md section 8, "Pull-in histories"): moved
/// the way the tendon last slid, it slides at once; moved the other way it first sticks
/// all along, and its pull-in barely changes (by the free length's stretch and the shape's
/// change, 1e-5 of the sliding slope on the prototype) until the base tension has changed
/// by what the friction of the first links holds. A difference taken across that kink
/// reads the stuck slope, whose size and even sign are set by 1e-9 m changes of the
/// material, and sends Newton orders of magnitude past the root. The slope on the root's
/// side is the one Newton's step needs. None (and `model::pull_in` differences forward)
/// where a difference's step fails.
fn toward_root(
    robot: &crate::Robot,
    options: &collocation::Options,
    carried: &friction::history::Carried,
    (at, solution): (&crate::Robot, &Solution),
    held: &[usize],
) -> Option<Vec<f64>> {
    let k = held.len();
    let mut slope = vec![0.0; k * k];
    for (m, &i) in held.iter().enumerate() {
        let tau = at.tendons[i].tension();
        let gap = solution.tendons[i].displacement - robot.tendons[i].displacement()?;
        let size = STEP * tau.max(robot.tension_scale(i));
        // Down toward a smaller pull-in, not below 0 N (the slack side has no slope).
        let h = if gap > 0.0 && tau > 0.0 { -size.min(tau) } else { size };
        let mut tensions: Vec<f64> = at.tendons.iter().map(|t| t.tension()).collect();
        tensions[i] = tau + h;
        let mut trial = carried.snapshot();
        let (moved, _) = friction::history::step(&at.with_tensions(&tensions), options, &mut trial).ok()?;
        for (n, &j) in held.iter().enumerate() {
            slope[n * k + m] = (moved.tendons[j].displacement - solution.tendons[j].displacement) / h;
        }
    }
    Some(slope)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first step is loaded from rest whatever its value (here 0 N, then 2 N): it is
    /// `from_rest`, not `held`, which is kept for a value repeated from the step before.
    #[test]
    fn the_first_step_is_from_rest_and_a_repeated_value_is_held() {
        use crate::analysis::sweep::Input;
        let tension = Input::Parameter(crate::Parameter::Tension(0));
        let ranges = |values: Vec<f64>| Ranges::new(crate::cases::case_s(), vec![(tension, values)]).unwrap();
        assert_eq!(
            directions(&ranges(vec![0.0, 1.0, 1.0, 0.5])),
            [FROM_REST, "up", "held", "down"]
        );
        assert_eq!(directions(&ranges(vec![2.0, 2.0])), [FROM_REST, "held"]);
    }

    #[test]
    fn loop_axes_parse_from_their_names_and_others_are_refused() {
        for (name, axis) in LoopAxis::NAMES.iter().zip(LoopAxis::ALL) {
            assert_eq!(LoopAxis::parse(name).unwrap(), axis);
        }
        let e = LoopAxis::parse("angle").unwrap_err().to_string();
        assert!(
            e.contains("`angle`") && e.contains("tip_displacement, bending_angle, tip_x"),
            "{e}"
        );
        assert_eq!(LoopAxis::default(), LoopAxis::TipDisplacement);
    }

    #[test]
    fn loop_axes_give_the_distance_the_angle_and_the_coordinates_of_the_steps() {
        let robot = crate::cases::case_s();
        let rest = collocation::solve(&robot.with_tensions(&[0.0; 5]), &Default::default()).unwrap();
        let pulled = collocation::solve(&robot, &Default::default()).unwrap();
        let steps = [&rest, &pulled];
        let moved = (pulled.tip_position() - rest.tip_position()).norm();
        assert_eq!(tip_displacements(steps), vec![0.0, moved]);
        assert_eq!(LoopAxis::TipDisplacement.values(steps), vec![0.0, moved * 1e3]);
        let angle = crate::analysis::samples::bending_angle(&pulled).to_degrees();
        assert_eq!(LoopAxis::BendingAngle.values(steps)[1], angle);
        assert_eq!(LoopAxis::Tip(2).values(steps)[1], pulled.tip_position().z * 1e3);
        assert!(tip_displacements(std::iter::empty()).is_empty());
    }
}
