//! Stick/slip over a quasi-static load history (docs/friction.md section 8): each step is
//! solved on the history's one mesh from the tendon state the last step left, the material
//! of every tendon with friction at every node (its unstretched length per unit s there,
//! lambda).
//!
//! On each link of a tendon's span the tension either slides at the full friction rate
//! (the capstan row of full slip with w = -1 or +1) or sticks: the material at the link's
//! end node b has not moved, so its tension is the stuck material's,
//! `tau(b) = E_t A_t (|p'(b)| / lambda(b) - 1)`, a stick row in place of the capstan row.
//! Which links slide and which stick is the exact solution of the tendon's 1-D Coulomb
//! problem on the current shape, marched from the base entry ([`march`]): the tension may
//! change across a link by at most the capstan increment C either way, so
//! `z_b = z_a + clamp(zeta_b - z_a, -C, C)` with zeta_b the stuck log tension. Newton solves
//! the backbone with the links' rows and multipliers held; the march is repeated on the new
//! shape until it changes nothing. Where the stuck profile changes faster along s than
//! friction can hold, the march opens a slip zone inside the stuck stretch ([`zone`]): a
//! transition link whose multiplier is the root of the zone's material balance, then links
//! sliding at the full rate to where the stretch sticks again.

mod cross;
mod inflection;
mod interpolant;
mod march;
mod refusal;
mod repeat;
mod rest;
mod slip;
mod split;
mod zone;

use march::march;
use refusal::{resolution, rigid, slack, stalled, unanswered};
pub(crate) use repeat::hold_last;
pub(crate) use rest::{all_slack, restart, start};
use slip::check_slip;

use super::grip::{self, Kink, Stuck, choose, stuck_multiplier};
use super::staircase::Staircase;
use super::*;
use crate::model::length;
use crate::solution::Solution;

/// Passes of march and Newton per step: each pass moves a stick/slip boundary to where the
/// last shape puts it and updates the stuck links' multipliers, whose effect on the shape
/// is about mu tau r^2 / (E I) (1e-3 on the prototype) per pass; 40 covers any settling
/// history many times over.
const PASSES: usize = 40;
/// A stuck link's capacity has settled when it changes by less than this (relative) from
/// the march before a step's first pass: the tangential load its multiplier scales is
/// mu tau kappa w, and 1e-10 of it moves the tip far below the residual tolerance. After a
/// converged pass only the contacts count: the multipliers divide by the capacity of
/// Newton's own last evaluation ([`Profile::stuck_capacity`]), so the march's capacity is
/// no input of the next pass, which only repeated the converged answer (docs/friction.md
/// section 8, "A pass that changes nothing").
const SETTLED: f64 = 1e-10;

/// What a history carries from one step to the next on its mesh.
pub(crate) struct Carried {
    /// The history's mesh.
    pub(crate) mesh: Mesh,
    /// The last step's node states (the first step's starting guess before it).
    pub(crate) x: Vec<State>,
    /// The last step's log tensions of each tendon with friction at every node.
    pub(crate) z: Vec<Vec<f64>>,
    /// Each tendon with friction's contacts, multipliers and material (lambda).
    pub(crate) grips: Vec<Grip>,
    /// Each tendon with friction's material at its best: at the nodes read from the
    /// deferred-corrected node states and log tensions of the step that last slid there
    /// (order 6; the order-4 one in `grips` where that step had no correction), with its
    /// kinks: only the estimate of a stuck step's material error reads it ([`split`]); the
    /// steps are solved from the order-4 node values (between nodes, on split meshes, the
    /// quintic through them), whose stuck tensions match the last step's answer exactly at
    /// the nodes where nothing moves.
    pub(crate) corrected: Vec<Material>,
    /// Whether (x, z) already solve the next step with the contacts held (the first step
    /// when the mesh was chosen on it).
    pub(crate) solved: bool,
    /// The report of the solve that chose the mesh: the template of every step's report.
    pub(crate) report: SolveReport,
    /// The last step's Newton workspace and bordered factors on this mesh, which the next
    /// step's first iterations reuse as chord steps (None before the first step).
    factors: Option<(Workspace, Staircase)>,
    /// The last step's answer as its stability verdict reads it (on the mesh it was solved
    /// on, split levels included); None before the first step.
    pub(crate) settled: Option<Settled>,
    /// Whether no step has been solved yet: the tendons are at rest, slack in their
    /// channels with no material laid along any path, so the first step pulls every loaded
    /// one in from its actuator and it slides in all along (docs/friction.md section 8).
    pub(crate) rest: bool,
    /// The base tension (N) of every tendon that `x` was solved with.
    pub(crate) tensions: Vec<f64>,
}

/// A tendon's carried material on the history's mesh (docs/friction.md section 8).
#[derive(Clone)]
pub(crate) struct Material {
    /// lambda at the nodes.
    pub(crate) values: Vec<f64>,
    /// Its kinks, as [`Grip::kinks`].
    pub(crate) kinks: Vec<Kink>,
}

/// A step's answer with its pattern, on the mesh the step returns: what its verdict
/// (`collocation/dynamics/stuck.rs`) rebuilds the step's bordered system from.
#[derive(Clone)]
pub(crate) struct Settled {
    /// The mesh of the answer.
    pub(crate) mesh: Mesh,
    /// The node states.
    pub(crate) x: Vec<State>,
    /// The log tensions of each tendon with friction at every node.
    pub(crate) z: Vec<Vec<f64>>,
    /// The contacts, multipliers and capacities the answer solved with, and the material
    /// the step started from (its stick rows' lambda).
    pub(crate) grips: Vec<Grip>,
    /// The stuck links' per-point multipliers' shares and capacities at the answer
    /// (`Profile::shares`; empty with the constant multiplier), which its verdict's rows
    /// take as the answer's did (docs/stability.md, "Load-history steps").
    pub(crate) shares: Vec<Vec<Option<[f64; 4]>>>,
}

impl Carried {
    /// A copy of everything but the factors: the state a step starts from.
    fn material(&self) -> Carried {
        Carried {
            solved: self.solved,
            ..self.snapshot()
        }
    }

    /// A copy of the state without the factors (and not marked solved), for the trial
    /// steps of a pull-in's tension (`analysis::history`): each trial starts from this.
    pub(crate) fn snapshot(&self) -> Carried {
        Carried {
            mesh: self.mesh.clone(),
            x: self.x.clone(),
            z: self.z.clone(),
            grips: self.grips.clone(),
            corrected: self.corrected.clone(),
            solved: false,
            report: self.report.clone(),
            factors: None,
            settled: None,
            rest: self.rest,
            tensions: self.tensions.clone(),
        }
    }
}

/// One step's answer: the solution and, per tendon with friction (robot index), its zones
/// as (start s, end s, contact), base to termination.
pub(crate) type StepAnswer = (Solution, Vec<(usize, Vec<(f64, f64, Contact)>)>);

/// Solves one step of a history: `robot` (validated, the history's geometry) from the state
/// `carried` holds, which it then holds for the next step. Returns the solution and the
/// zones of the tendons with friction.
///
/// # Errors
/// Newton not converging on a pass, a stick/slip pattern that does not settle, a rigid
/// tendon that sticks ([`rigid`]), or a pattern outside what the march resolves (a stretch
/// sliding against its slip, section 8 of docs/friction.md).
pub(crate) fn step(robot: &Robot, options: &Options, carried: &mut Carried) -> Result<StepAnswer> {
    let before = carried.material();
    let (answer, stuck) = solve_on(robot, options, carried, None)?;
    if stuck {
        return split::refine(robot, options, carried, &before, answer);
    }
    // A step that slides all along where a tendon's path stops turning inside a link has
    // a kink of its tension there that its estimate does not see ([`inflection`]); a step
    // that misses its tolerance is solved again too.
    if answer.0.report.tolerance_met == Some(false) || !turning::inflections(robot, &answer.0).is_empty() {
        return inflection::refine(robot, options, carried, &before, answer);
    }
    Ok(answer)
}

/// [`step`] on `carried`'s own mesh, and whether a tendon has a stuck stretch (then the
/// answer has no error estimate: [`split::refine`] gives it one). With `held` (a slip in
/// m), `carried` is an answer whose material was changed slightly: Newton solves once with
/// its pattern and capacities held, without a march ([`split`]'s material error), and a
/// slip against the friction up to `held` beyond rounding passes the slip check.
///
/// # Errors
/// As [`step`].
fn solve_on(robot: &Robot, options: &Options, carried: &mut Carried, held: Option<f64>) -> Result<(StepAnswer, bool)> {
    let start = Instant::now();
    let tie = grip::tie(options.residual_tolerance);
    let model = Model::new(robot);
    let mut system = System::new(model.clone(), carried.mesh.clone());
    let mut profile = Profile::new(&model, &system.mesh);
    profile.z.clone_from(&carried.z);
    profile.grips = Some(carried.grips.clone());
    // A held solve (the material's term) is the answer with its material changed slightly:
    // its stuck links start from the answer's own per-point shares, not from the constant
    // multiplier a fresh profile's first evaluation takes (docs/friction.md section 8,
    // "est25"), so Newton starts near the answer it converges to.
    if let Some(settled) = carried.settled.as_ref().filter(|_| held.is_some()) {
        profile.held_shares.clone_from(&settled.shares);
    }
    system.friction = Some(profile);
    let mut border = Capstan::new(system);
    let mut ws = match carried.factors.take() {
        Some((ws, stairs)) => {
            border.stairs = stairs;
            ws
        }
        None => Workspace::new(&border.system, options.linear_solver)?,
    };
    let mut x = carried.x.clone();
    let mut report = carried.report.clone();
    (
        report.iterations,
        report.newton_steps,
        report.chord_steps,
        report.load_steps,
    ) = (0, 0, 0, 0);
    // Each pass after the first starts with chord steps on the last pass's factors (its
    // pattern a march ago): Newton takes a fresh Jacobian as soon as they do not contract.
    // The first pass has no factors and starts with a Newton step.
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors: true,
        stop_when_damped: false,
    };
    let solved = std::mem::replace(&mut carried.solved, false);
    // The first step when it is the mesh-choosing full-slip solve itself (its answer, held
    // by the march): that solve's work and estimate are the step's.
    let template = solved.then(|| carried.report.clone());
    let rest = carried.rest;
    let mut settled = held.is_none() && !march(&mut border, &x, false, tie, rest, &carried.tensions)? && solved;
    // A rigid tendon that would stick is refused by the march; one that is near sticking
    // may keep Newton or the passes from settling, which the hint names.
    let rigid_hint = robot
        .tendons
        .iter()
        .enumerate()
        .find(|(_, t)| t.active_friction().is_some() && t.stiffness.is_none())
        .map_or(String::new(), |(i, _)| {
            format!("; tendon {} is rigid: set its `stiffness` if it sticks", i + 1)
        });
    let mut ran = false;
    let mut worst_s = 0.0;
    for _ in 0..PASSES {
        if settled {
            break;
        }
        let (termination, worst) = newton::run_bordered(&mut border, &mut ws, &mut x, &settings, &mut report);
        ran = true;
        worst_s = border.system.row_position(worst.min(border.system.unknowns() - 1));
        report.termination = termination;
        if termination != Termination::Converged {
            // A stuck stretch the shape drives toward 0 N stalls Newton before the march
            // can refuse it as slack: that is the reason, and its hint the one that helps.
            border.load(Point::Current);
            let system = &border.system;
            let mut looser = String::new();
            if let Some(profile) = system.friction.as_ref() {
                let s: Vec<f64> = x.iter().map(|n| n.s).collect();
                if let Some(refusal) = stalled(profile, &s, options.residual_tolerance) {
                    return Err(refusal);
                }
                // A healthy stuck tension under a residual tolerance tighter than its stick
                // row resolves: loosening it is what helps.
                if let Some(hint) = resolution(profile, options.residual_tolerance) {
                    looser = format!("; {hint}");
                }
            }
            return Err(Error::NotConverged {
                method: Method::Collocation,
                report: Box::new(unanswered(report)),
                worst_s: system.row_position(worst.min(system.unknowns() - 1)),
                hint: format!(
                    "a history step is solved from the last step's state: take smaller steps{rigid_hint}{looser}"
                ),
            });
        }
        // The contacts and multipliers on the converged shape: settled when Newton's were.
        border.load(Point::Current);
        settled = held.is_some() || !march(&mut border, &x, true, tie, rest, &carried.tensions)?;
    }
    if !settled {
        // Every pass's Newton converged: what failed is the zones (the termination says so).
        report.termination = Termination::ZonesUnsettled;
        return Err(Error::NotConverged {
            method: Method::Collocation,
            report: Box::new(unanswered(report)),
            worst_s,
            hint: format!("{PASSES} passes of march and Newton: take smaller steps of the history{rigid_hint}"),
        });
    }
    // The estimate does not see a stuck stretch's error (its multiplier is constant per
    // link and its boundary falls inside one: about 1e3 times the estimate on the
    // prototype, docs/friction.md section 8), so a step with one reports none and skips it.
    let stuck = border
        .system
        .friction
        .as_ref()
        .and_then(|p| p.grips.as_ref())
        .is_some_and(|g| {
            g.iter()
                .any(|g| g.contacts.contains(&Contact::Stick) || !g.zone_starts().is_empty())
        });
    // The deferred correction of the node states and log tensions (scaled as Newton's
    // steps): the order-6 material the step leaves for the next stuck step's estimate.
    let mut correction = Vec::new();
    let estimated = if stuck {
        None
    } else {
        // Newton's last residual is the backbone rows' at x when a pass ran.
        let converged = ran.then(|| ws.residual.clone());
        estimate_with_friction(&mut border, &x, converged, &mut correction)
            .ok()
            .flatten()
    };
    let corrected = estimated.is_some();
    border.load(Point::Current);
    let system = &border.system;
    let Some(profile) = system.friction.as_ref() else {
        return Err(error::invalid(
            "tendons",
            "have no friction",
            "solve a history of a robot with friction",
        ));
    };
    let grips = profile.grips.clone().unwrap_or_default();
    let tensions = profile.node_tensions(&model);
    let multipliers: Vec<Vec<f64>> = (0..x.len())
        .map(|n| {
            grips
                .iter()
                .map(|g| {
                    g.multipliers
                        .get(n.saturating_sub(1).min(g.multipliers.len().saturating_sub(1)))
                        .copied()
                        .unwrap_or(-1.0)
                })
                .collect()
        })
        .collect();
    pipeline::record_estimate(&mut report, estimated.as_ref().map(|(c, _)| c), options, robot.length());
    if let Some(first) = template.filter(|_| !ran && !stuck) {
        // No pass ran: x is the full-slip solve's answer on this mesh, with its counts and
        // its estimate (deferred correction, as a step that slides all along has).
        (
            report.iterations,
            report.newton_steps,
            report.chord_steps,
            report.load_steps,
        ) = (
            first.iterations,
            first.newton_steps,
            first.chord_steps,
            first.load_steps,
        );
        report.termination = first.termination;
        report.error_estimate = first.error_estimate;
        report.tolerance_met = first.tolerance_met;
    }
    if stuck {
        report.error_estimate = None;
        report.tolerance_met = None;
    }
    // The verdict is the caller's, once the step's answer is final (`analysis::history`).
    report.stability = Stability::Unknown {
        reason: crate::report::NOT_ASSESSED.into(),
    };
    report.intervals = system.mesh.intervals();
    report.unknowns = unknowns::unknowns(system.mesh.nodes.len()) + border.z.len();
    report.nonzeros = unknowns::nonzeros(&system.mesh);
    report.timings.total = start.elapsed();
    let ends = pipeline::segment_ends(&system.mesh);
    let solution = nodes::solution_with_tensions(&model, &x, &ends, (&tensions, Some(&multipliers)), None, report)?;
    let mut zones = Vec::with_capacity(grips.len());
    let mut next = grips.clone();
    let length = robot.length();
    for (j, &i) in profile.slipping.iter().enumerate() {
        let tendon = &robot.tendons[i];
        let span = profile.spans[j];
        // The material now at each node: lambda = |p'| / (1 + tau / (E_t A_t)), and the
        // same from the deferred-corrected node states and log tensions where the step has
        // them (order 6 at the nodes: docs/friction.md section 8, "Error control of stuck
        // steps").
        let material = |corrected: bool| -> Vec<f64> {
            (0..=span)
                .map(|n| {
                    let (mut v, mut u, mut tension) = (x[n].v, x[n].u, tensions[n][i]);
                    if corrected {
                        let [_, _, dv, du] = unknowns::node_increments(&correction, n, length);
                        v += dv;
                        u += du;
                        if let Some(dz) = unknown(&border.offsets, &profile.spans, j, n).map(|u| border.border_step[u])
                        {
                            tension *= dz.exp();
                        }
                    }
                    let speed = length::speed(&tendon.routing.at(x[n].s, length), &v, &u);
                    tendon.stiffness.map_or(speed, |e| speed / (1.0 + tension / e))
                })
                .collect()
        };
        let lambda = material(false);
        // (A split mesh carries none: its step's material goes back to the history's mesh.)
        // (A stuck step's is replaced by its split meshes' hand-back.)
        if let Some(order6) = carried.corrected.get_mut(j) {
            order6.values[..=span].copy_from_slice(&if corrected { material(true) } else { lambda.clone() });
            order6.kinks.clear();
        }
        // An unloaded tendon is slack: no normal force, so friction holds nothing back; at
        // rest a loaded one is pulled in from slack, which has no material to slip against.
        // A held solve is the answer's linear response to its material, with the answer's
        // checked pattern: where the slip is 0 to rounding its sign may flip by up to the
        // material's change, which `held` bounds.
        if profile.base[j] > 0.0 && !rest {
            check_slip(i, &grips[j], &lambda, &x, span, held.unwrap_or(0.0))?;
        }
        let nodes: Vec<f64> = x[..=span].iter().map(|n| n.s).collect();
        // The other tendons' stick/slip boundaries: kinks of this one's path speed, so of
        // the material it lays where it slides (docs/friction.md section 8, "hist20").
        let others: Vec<f64> = (0..grips.len())
            .filter(|&l| l != j)
            .filter_map(|l| grips[l].boundary().map(|k| x[k].s))
            .collect();
        next[j].kinks = if grips[j].zone_starts().is_empty() {
            grips[j].kinks_after(&grips[j].contacts, &nodes, &lambda, &others)
        } else {
            let old = |n: usize| grips[j].reference[n];
            zone::kinks(&grips[j].contacts, &nodes, &lambda, &old, &grips[j].kinks, &others)
        };
        next[j].reference[..=span].copy_from_slice(&lambda);
        let mut list: Vec<(f64, f64, Contact)> = Vec::new();
        for (k, &c) in grips[j].contacts.iter().enumerate() {
            match list.last_mut() {
                Some(last) if last.2 == c => last.1 = x[k + 1].s,
                _ => list.push((x[k].s, x[k + 1].s, c)),
            }
        }
        zones.push((i, list));
    }
    carried.settled = Some(Settled {
        mesh: system.mesh.clone(),
        x: x.clone(),
        z: profile.z.clone(),
        grips,
        shares: profile.shares(),
    });
    carried.z.clone_from(&profile.z);
    carried.grips = next;
    carried.x = x;
    carried.factors = Some((ws, border.stairs));
    carried.rest = false;
    carried.tensions = robot.tendons.iter().map(|t| t.tension()).collect();
    Ok(((solution, zones), stuck))
}
