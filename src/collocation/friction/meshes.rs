//! The solve with friction mesh by mesh ([`refine_with_friction`]): Newton bordered by the
//! log tensions on each mesh, from the frictionless start, the initial guess ([`direct`])
//! or the last converged mesh, its error estimate, and the next mesh the estimate and the
//! kink nodes choose.

use super::*;

/// Where Newton with friction on the first mesh of [`refine_with_friction`] starts from, and
/// what it must do there.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Route {
    /// The direct route ([`direct`]): from the initial guess; Newton on the first mesh
    /// counts as converged only if it went straight to its root ([`CLEAN_ITERATIONS`], no
    /// damped step), with no second try from constant tensions.
    Direct,
    /// From a frictionless solution (or a pull-in's states): any converged Newton stands,
    /// and a Newton that failed from the capstan start tries once more from constant
    /// tensions.
    Frictionless,
}

/// On the mesh and from the node states of `from`, Newton bordered by the log tensions
/// ([`Capstan`]) from `previous` (node arc lengths and log tensions per slip, interpolated;
/// the capstan start of [`start`] when None), its error estimate ([`estimate_with_friction`]) and, with a
/// tolerance, re-meshing until the tip's estimate and the tension profile's (relative,
/// against the same tolerance as the rotation) meet it, each mesh with a node where a tendon
/// stops turning ([`kinks`]). `report` holds what came before
/// (the frictionless solve's counts, or none), with whether to assess the answer's
/// stability (the linearized dynamics with the capstan rows; else `unknown`); `start` is
/// when the solve began. `route` says what `from` is and what Newton on the first mesh must
/// do ([`Route`]).
///
/// Where Newton fails: from the capstan start, once more from `from` with constant tensions;
/// then (from a frictionless start) the friction coefficients followed from 0 on the first
/// mesh ([`continuation`]); on a mesh more than twice as fine as the last converged one, once
/// more through that one halved; on a later mesh that still fails, the coefficients followed
/// from 0 on it (once in a solve). Past those, the solve is refused.
///
/// # Errors
/// As [`super::solve`].
pub(super) fn refine_with_friction(
    robot: &Robot,
    options: &Options,
    from: (Mesh, Vec<State>),
    mut previous: Option<(Vec<f64>, Vec<Vec<f64>>)>,
    (mut report, assess): (SolveReport, bool),
    start: Instant,
    route: Route,
) -> Result<Solution> {
    let (mut mesh, mut x) = from;
    let settings = fresh_settings(options);
    // The direct route's first mesh: Newton from the guess must go straight to its root,
    // as the equilibrium choice's direct answer must ([`direct`]).
    let from_guess = route == Route::Direct;
    let mut first = from_guess.then_some(Settings {
        max_iterations: options.max_iterations.min(CLEAN_ITERATIONS),
        stop_when_damped: true,
        ..settings
    });
    let model = Model::new(robot);
    let length = robot.length();
    // Whether the first mesh starts from the capstan start, and the states it moves, for a
    // second try from them with constant tensions where Newton fails (not on the direct
    // route, whose caller falls back to the frictionless start instead). `capstan` is
    // cleared only by that retry: where the first mesh converged and Newton fails on a later
    // one, the retry runs too, on the first mesh from these states with the last converged
    // mesh's log tensions interpolated (`previous`), not constant ones, and the refinement
    // goes on from its answer.
    let mut capstan = previous.is_none();
    let plain = (capstan && !from_guess).then(|| (mesh.clone(), x.clone()));
    // Whether the continuation in the friction coefficients ran on the first mesh (once at
    // most, where both tries from `plain` failed on the first mesh itself; a later mesh's
    // failure goes to the halved mesh below, and then to a continuation on the mesh that
    // failed).
    let mut continued = false;
    // What the continuations found, for the refusal's hint.
    let mut tried = refusal::Tried::default();
    let mut kinks = kinks::Kinks::default();
    // The last converged mesh and its answer, for a mesh between it and a finer one Newton
    // failed on.
    let mut coarse: Option<(Mesh, Solution)> = None;
    // The last mesh's node arc lengths and log tensions, interpolated onto the next.
    loop {
        let settings = first.take().unwrap_or(settings);
        report.meshes += 1;
        let mut system = System::new(model.clone(), mesh);
        let mut profile = Profile::new(&model, &system.mesh);
        if let Some((s, z)) = &previous {
            for (zj, old) in profile.z.iter_mut().zip(z) {
                for (value, node) in zj.iter_mut().zip(&system.mesh.nodes) {
                    *value = linear(s, old, node.s);
                }
            }
        } else if capstan {
            // From the frictionless shape or the guess: its tension profile and the shape it
            // bends.
            let settle = if from_guess {
                start::Settle::Guess
            } else {
                start::Settle::Solution
            };
            start::capstan_start(&model, &system.mesh, &mut x, &mut profile, settle);
        }
        system.friction = Some(profile);
        let mut ws = match workspace::spare(&system.mesh, options.linear_solver) {
            Some((_, ws)) => ws,
            None => Workspace::new(&system, options.linear_solver)?,
        };
        let mut border = Capstan::new(system);
        // With a verdict, Newton evaluates the Jacobian at its predicted last trial point in
        // place of the residual there, which the verdict factors (below).
        let (mut termination, mut worst) = if assess {
            newton::run_bordered_ahead(&mut border, &mut ws, &mut x, &settings, &mut report)
        } else {
            newton::run_bordered(&mut border, &mut ws, &mut x, &settings, &mut report)
        };
        if termination != Termination::Converged
            && std::mem::take(&mut capstan)
            && let Some((m, states)) = &plain
        {
            // Newton failed from the capstan start: once more from the frictionless solution
            // with constant tensions, the start of earlier versions (its counts add up).
            report.meshes -= 1;
            (mesh, x) = (m.clone(), states.clone());
            continue;
        }
        if termination != Termination::Converged
            && let Some((m, states)) = &plain
            && same_nodes(&border.system.mesh, m)
            && !std::mem::replace(&mut continued, true)
        {
            // Both tries failed: the friction coefficients followed from 0 on the first mesh
            // ([`continuation`]), past where that gives up along the branch by its arclength
            // ([`fold`]), and the refinement from their answer.
            match continuation::follow_on(robot, options, m, states, &mut report)? {
                continuation::Followed::Solved(solved, z, how) => {
                    report.notes.push(format!(
                        "Newton with friction failed from the frictionless shape; {how}"
                    ));
                    tried.followed = Some(m.intervals());
                    report.meshes -= 1;
                    previous = Some((m.nodes.iter().map(|n| n.s).collect(), z));
                    (mesh, x) = (m.clone(), solved);
                    continue;
                }
                continuation::Followed::Refused(gave_up, end) => {
                    // The refusal reports the continuation's last run, at its coefficients.
                    (termination, worst) = (gave_up.termination, gave_up.worst);
                    (tried.reached, tried.ended) = (Some(gave_up), end);
                }
            }
        }
        if termination != Termination::Converged
            && let Some((m, guess)) = &coarse
            && 2 * m.intervals() < border.system.mesh.intervals()
        {
            // Newton failed on a mesh more than twice as fine as the last converged one,
            // from that one's answer interpolated: once more on the converged mesh with
            // every interval halved, and the refinement from there.
            let halved = halve(robot, m)?;
            tried
                .later
                .get_or_insert((border.system.mesh.intervals(), m.intervals()));
            report.notes.push(format!(
                "Newton with friction failed on a mesh of {} intervals; the refinement went on from the last \
                 converged mesh of {} intervals with every interval halved",
                border.system.mesh.intervals(),
                m.intervals()
            ));
            report.meshes -= 1;
            x = interpolate(&model, guess, &halved);
            mesh = halved;
            continue;
        }
        if termination != Termination::Converged
            && let Some((m, _)) = &coarse
            && let Some((m0, states)) = &plain
            && !std::mem::replace(&mut tried.again, true)
        {
            // Newton failed on a later mesh from a converged one's answer (and, where that
            // was more than twice as fine, on the converged one halved): that answer may be
            // its mesh's alone. The friction coefficients followed from 0 on the mesh that
            // failed, from the frictionless solution interpolated onto it, as on the first
            // mesh (once in a solve).
            let failed = border.system.mesh.clone();
            tried.later.get_or_insert((failed.intervals(), m.intervals()));
            let x0 = frictionless_on(robot, (m0, states), &failed)?;
            match continuation::follow_on(robot, options, &failed, &x0, &mut report)? {
                continuation::Followed::Solved(solved, z, how) => {
                    report.notes.push(format!(
                        "Newton with friction failed on a mesh of {} intervals from the answer of the last converged \
                         mesh ({} intervals); on it {how}",
                        failed.intervals(),
                        m.intervals()
                    ));
                    tried.followed = Some(failed.intervals());
                    report.meshes -= 1;
                    previous = Some((failed.nodes.iter().map(|n| n.s).collect(), z));
                    (mesh, x) = (failed, solved);
                    continue;
                }
                continuation::Followed::Refused(gave_up, end) => {
                    (termination, worst) = (gave_up.termination, gave_up.worst);
                    (tried.reached, tried.ended) = (Some(gave_up), end);
                }
            }
        }
        report.termination = termination;
        report.intervals = border.system.mesh.intervals();
        report.unknowns = unknowns::unknowns(border.system.mesh.nodes.len()) + border.z.len();
        report.nonzeros = unknowns::nonzeros(&border.system.mesh);
        if termination != Termination::Converged {
            report.timings.total = start.elapsed();
            let system = &border.system;
            return Err(Error::NotConverged {
                method: Method::Collocation,
                report: Box::new(report.clone()),
                worst_s: system.row_position(worst.min(system.unknowns() - 1)),
                hint: tried.hint(
                    border.system.mesh.intervals(),
                    robot.tendons.iter().any(|t| {
                        t.active_friction()
                            .is_some_and(|f| f.motion == crate::model::tendon::Motion::Release)
                    }),
                ),
            });
        }
        // A later failure is a new one, from this mesh's answer.
        tried.later = None;
        let t = Instant::now();
        // Newton's last residual is the backbone rows' at x.
        let converged = Some(ws.residual.clone());
        let estimated = estimate_with_friction(&mut border, &x, converged, &mut Vec::new())
            .ok()
            .flatten();
        report.timings.estimate += t.elapsed();
        border.load(Point::Current);
        // Whether the staircase's factors are the Jacobian's at x, for the verdict (Newton's
        // last Jacobian, factored: not one it evaluated ahead, left unfactored); whether the
        // workspace's values are the Jacobian at x itself, unfactored (evaluated ahead).
        let fresh = ws.jacobian_at_iterate() && !ws.unfactored;
        let ahead = ws.evaluated_at_solution() && ws.unfactored;
        let system = &border.system;
        let Some(profile) = system.friction.as_ref() else {
            return Err(error::invalid("tendons", "have no friction", "solve without friction"));
        };
        let tensions = profile.node_tensions(&model);
        let ends = pipeline::segment_ends(&system.mesh);
        let next = match (options.tolerance, &estimated) {
            (Some(tol), Some((correction, tension_error))) => {
                // The mesh choice sees the tension profile's error with the rotation's.
                let mut chosen = correction.clone();
                chosen.estimate.tip_rotation = chosen.estimate.tip_rotation.max(*tension_error);
                refine::next_mesh(robot, &system.mesh, &chosen, tol, options)?
            }
            _ => None,
        };
        // The estimate's mesh with a node where a tendon stops turning ([`kinks`]).
        let rates = estimated.as_ref().map(|(c, _)| c.node_rates.as_slice());
        let next = if let Some((correction, _)) = &estimated {
            let answer = || nodes::solution_with_tensions(&model, &x, &ends, (&tensions, None), rates, report.clone());
            kinks.next(robot, options, (&system.mesh, &x, &correction.estimate), answer, next)?
        } else {
            next
        };
        let Some(fine) = next else {
            pipeline::record_estimate(&mut report, estimated.as_ref().map(|(c, _)| c), options, length);
            kinks.widen(&mut report, length);
            let t = Instant::now();
            report.stability = if assess {
                // The Jacobian Newton evaluated at x, factored with the border's blocks from
                // the same evaluation; else the verdict evaluates and factors it (or takes
                // Newton's factors when they are x's). `factor_evaluated` reads the links'
                // cached evaluations without checking their state: it relies on nothing
                // between Newton's accepted trial (`ahead`: the Jacobian held is x's) and
                // here evaluating a link with derivatives (the estimate evaluates residuals
                // only), which any change on this way must keep.
                let fresh = fresh || (ahead && border.factor_evaluated(&x, &ws.values, &mut report));
                workspace::keep(border.system.mesh.clone(), options.linear_solver, ws);
                super::super::dynamics::friction::assess(&mut border, &x, fresh, &mut report)
            } else {
                workspace::keep(border.system.mesh.clone(), options.linear_solver, ws);
                super::super::dynamics::friction::held_unknown()
            };
            if !matches!(report.stability, Stability::Unknown { .. }) {
                report.notes.push(super::super::dynamics::friction::SLIP_HELD.into());
            }
            report.timings.stability += t.elapsed();
            report.timings.total = start.elapsed();
            // The estimate's node rates are eq. 13 with friction at the same states and tensions.
            return nodes::solution_with_tensions(&model, &x, &ends, (&tensions, None), rates, report);
        };
        workspace::keep(system.mesh.clone(), options.linear_solver, ws);
        let guess = nodes::solution_with_tensions(&model, &x, &ends, (&tensions, None), rates, report.clone())?;
        let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
        previous = Some((s, profile.z.clone()));
        x = interpolate(&model, &guess, &fine);
        coarse = Some((system.mesh.clone(), guess));
        mesh = fine;
    }
}

/// The value at `s` of the piecewise-linear interpolant through (`points`, `values`)
/// (clamped at the ends; at a repeated point, the value of its last copy: the right limit).
fn linear(points: &[f64], values: &[f64], s: f64) -> f64 {
    let k = points
        .iter()
        .rposition(|&p| p <= s)
        .unwrap_or(0)
        .min(points.len().saturating_sub(2));
    let (a, b) = (points[k], points[k + 1]);
    if b <= a {
        return values[k];
    }
    let t = ((s - a) / (b - a)).clamp(0.0, 1.0);
    values[k] + t * (values[k + 1] - values[k])
}

/// Whether meshes `a` and `b` have the same nodes (arc lengths, bit for bit).
fn same_nodes(a: &Mesh, b: &Mesh) -> bool {
    a.nodes.len() == b.nodes.len()
        && a.nodes
            .iter()
            .zip(&b.nodes)
            .all(|(p, q)| p.s.to_bits() == q.s.to_bits())
}

/// The frictionless solution `states` on the mesh `from` of `robot`, interpolated onto
/// `mesh` (the start of a continuation in the friction coefficients there).
///
/// # Errors
/// A model breakdown at those states.
fn frictionless_on(robot: &Robot, (from, states): (&Mesh, &[State]), mesh: &Mesh) -> Result<Vec<State>> {
    let mut smooth = robot.clone();
    for t in &mut smooth.tendons {
        t.friction = None;
    }
    let model = Model::new(&smooth);
    let ends = pipeline::segment_ends(from);
    let nodes = nodes::nodes(&model, states, &ends, None)?;
    Ok(crate::mesh::guess::interpolate_nodes(&model, &nodes, mesh))
}

/// `mesh` with every interval of positive length halved.
///
/// # Errors
/// None in practice: the midpoints lie on the rod ([`Mesh::from_points`]).
fn halve(robot: &Robot, mesh: &Mesh) -> Result<Mesh> {
    let nodes = &mesh.nodes;
    let mut points: Vec<f64> = nodes.iter().map(|n| n.s).collect();
    points.extend(
        nodes
            .windows(2)
            .filter(|w| w[1].s > w[0].s)
            .map(|w| 0.5 * (w[0].s + w[1].s)),
    );
    Mesh::from_points(robot, &points)
}
