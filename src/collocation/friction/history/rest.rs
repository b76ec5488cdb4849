//! The start of a load history from rest (docs/friction.md section 8): the history's mesh
//! and first guess from a full-slip solve, and every tendon with friction slack, with no
//! material laid yet.

use super::{Carried, Material};
use crate::collocation::friction::*;

/// The start of a history of `robots` (validated, same geometry) from rest: the mesh the
/// default full-slip `pull` solve picks for the step with the most tension on the tendons
/// with friction, its solution as the first guess, and every tendon with friction slack,
/// sliding in, with no material yet (lambda NaN until the first step lays it: nothing
/// reads it before, [`Carried::rest`]). A step lays it only up to the tendon's termination,
/// so past it lambda stays NaN on the history's mesh for the whole history: no material
/// there (docs/friction.md section 8, "From rest").
///
/// # Errors
/// As [`crate::collocation::solve`] on that step.
pub(crate) fn start(robots: &[Robot], options: &Options) -> Result<Carried> {
    // The most pull-in on the tendons with friction first (their tension is solved), then
    // the most tension.
    let load = |r: &Robot| -> (f64, f64) {
        let active = crate::model::friction::slipping(r);
        let pulled = active.iter().filter_map(|&i| r.tendons[i].displacement()).sum();
        (pulled, active.iter().map(|&i| r.tendons[i].tension()).sum())
    };
    let mut most = 0;
    for (n, r) in robots.iter().enumerate() {
        if load(r).partial_cmp(&load(&robots[most])) == Some(std::cmp::Ordering::Greater) {
            most = n;
        }
    }
    let mut pulled = robots[most].clone();
    for t in &mut pulled.tendons {
        if let Some(f) = t.friction.as_mut() {
            f.motion = crate::model::tendon::Motion::Pull;
        }
    }
    let mut first = crate::collocation::solve(&pulled, options)?;
    // The steps report their own verdicts: the full-slip verdict's note is not theirs.
    first
        .report
        .notes
        .retain(|n| n != crate::collocation::dynamics::friction::SLIP_HELD);
    // A pull-in's base tension is the solved one.
    let pulled = pulled.with_tensions(&first.tensions());
    let points: Vec<f64> = first.nodes.iter().map(|n| n.s).collect();
    let mesh = Mesh::from_points(&pulled, &points)?;
    let x: Vec<State> = first.nodes.iter().map(|n| n.state()).collect();
    let model = Model::new(&pulled);
    let profile = Profile::new(&model, &mesh);
    let mut z = profile.z.clone();
    let mut grips = Vec::with_capacity(profile.count());
    for (j, &i) in profile.slipping.iter().enumerate() {
        let span = profile.spans[j];
        let base = profile.base[j];
        for (n, value) in z[j].iter_mut().enumerate() {
            let tension = first.tendon_tensions[i][n.min(span)];
            *value = if base > 0.0 { (tension / base).ln() } else { 0.0 };
        }
        grips.push(Grip {
            contacts: vec![Contact::Pull; span],
            multipliers: vec![-1.0; span],
            capacities: vec![0.0; span],
            reference: vec![f64::NAN; mesh.nodes.len()],
            kinks: Vec::new(),
            points: Vec::new(),
        });
    }
    let corrected = grips
        .iter()
        .map(|g| Material {
            values: g.reference.clone(),
            kinks: Vec::new(),
        })
        .collect();
    Ok(Carried {
        mesh,
        x,
        z,
        grips,
        corrected,
        solved: most == 0,
        report: first.report,
        factors: None,
        settled: None,
        rest: true,
        tensions: pulled.tendons.iter().map(|t| t.tension()).collect(),
    })
}

/// Whether `carried`'s last step left every tendon with friction slack (0 N at its base):
/// then no tendon with friction grips its channel and the next step is loaded from rest, as
/// the first is (docs/friction.md section 8, "From rest"). False before the first step.
pub(crate) fn all_slack(carried: &Carried, robot: &Robot) -> bool {
    !carried.rest
        && crate::model::friction::slipping(robot)
            .iter()
            .all(|&i| carried.tensions.get(i).is_some_and(|&t| t == 0.0))
}

/// Starts `carried` again from rest for the step of `robot` after a step that left every
/// tendon with friction slack ([`all_slack`]): no material laid (lambda NaN, as [`start`]
/// leaves it), every tendon with friction sliding in, and the node states and log tensions
/// of the default full-slip `pull` solve of the step's inputs (on its own mesh, with its
/// load path where Newton needs one) at the history's nodes, from which the step's Newton
/// starts. That solve is the step's answer on its own mesh (a step from rest is the
/// full-slip pull), so the step's Newton on the history's mesh starts within that mesh
/// change of its answer instead of from the slack step's shape.
///
/// Returns the report of that full-slip solve (its work is the step's too).
///
/// # Errors
/// As [`crate::collocation::solve`] on the step.
pub(crate) fn restart(robot: &Robot, options: &Options, carried: &mut Carried) -> Result<SolveReport> {
    let mut pulled = robot.clone();
    for t in &mut pulled.tendons {
        if let Some(f) = t.friction.as_mut() {
            f.motion = crate::model::tendon::Motion::Pull;
        }
    }
    let first = crate::collocation::solve(&pulled, options)?;
    let pulled = pulled.with_tensions(&first.tensions());
    let nodes = &carried.mesh.nodes;
    // A breakpoint's two nodes: the first is the left limit.
    let x: Vec<State> = (0..nodes.len())
        .map(|n| first.at_limit(nodes[n].s, nodes.get(n + 1).is_some_and(|m| m.s == nodes[n].s)))
        .collect();
    let model = Model::new(&pulled);
    let profile = Profile::new(&model, &carried.mesh);
    let mut z = profile.z.clone();
    for (j, &i) in profile.slipping.iter().enumerate() {
        let (span, base) = (profile.spans[j], profile.base[j]);
        for (n, value) in z[j].iter_mut().enumerate() {
            let tension = first.tension_at(i, nodes[n.min(span)].s).unwrap_or(base);
            *value = if base > 0.0 { (tension / base).ln() } else { 0.0 };
        }
        let grip = &mut carried.grips[j];
        grip.contacts.fill(Contact::Pull);
        grip.multipliers.fill(-1.0);
        grip.capacities.fill(0.0);
        grip.reference.fill(f64::NAN);
        grip.kinks.clear();
        grip.points.clear();
    }
    for material in &mut carried.corrected {
        material.values.fill(f64::NAN);
        material.kinks.clear();
    }
    carried.x = x;
    carried.z = z;
    carried.solved = false;
    carried.factors = None;
    carried.settled = None;
    carried.rest = true;
    carried.tensions = pulled.tendons.iter().map(|t| t.tension()).collect();
    Ok(first.report)
}
