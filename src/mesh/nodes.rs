//! The [`Solution`] both solvers return, built from their node states: the strain rates
//! (eq. 13) and internal wrenches at every node from the model, and the tendon paths.
#![allow(non_snake_case)]

use crate::error::Result;
use crate::mesh::{points, spare};
use crate::model::equations::Model;
use crate::model::friction;
use crate::model::length;
use crate::model::linearize;
use crate::report::SolveReport;
use crate::solution::{Node, Solution, State, TendonState};
use nalgebra::Vector6;

/// Builds a solution from node states (s, p, R, v, u): fills v', u', n, m and the
/// tendon paths from the model. `segment_ends[k]` is the end of the segment node k
/// belongs to (which tendons load it). `rates`, when given, are the rates (v', u') of
/// eq. 13 at the nodes already evaluated at these states (by the error estimate).
pub(crate) fn solution(
    model: &Model,
    states: &[State],
    segment_ends: &[f64],
    rates: Option<&[Vector6<f64>]>,
    report: SolveReport,
) -> Result<Solution> {
    build(model, states, segment_ends, Along::Constant(rates), report)
}

/// As [`solution`] for tendons with friction: `profile[k]` holds every tendon's tension
/// (N) at node k, and the node rates are those of eq. 13 with friction there
/// ([`friction::rates`]), each tendon with friction at its motion's sign, or, when
/// `multipliers` is given, at the friction multiplier `multipliers[k][j]` of the j-th
/// tendon with friction at node k (a stick/slip history); `rates`, when given, are those
/// node rates evaluated already (the error estimate's, at the same states and tensions).
pub(crate) fn solution_with_tensions(
    model: &Model,
    states: &[State],
    segment_ends: &[f64],
    (profile, multipliers): (&[Vec<f64>], Option<&[Vec<f64>]>),
    rates: Option<&[Vector6<f64>]>,
    report: SolveReport,
) -> Result<Solution> {
    build(
        model,
        states,
        segment_ends,
        Along::Varying(profile, multipliers, rates),
        report,
    )
}

/// The tensions along the tendons: constant (the model's), with the node rates when known,
/// or given at every node (with the friction multipliers at every node, if not the
/// motions' signs, and the node rates when known).
enum Along<'a> {
    Constant(Option<&'a [Vector6<f64>]>),
    Varying(&'a [Vec<f64>], Option<&'a [Vec<f64>]>, Option<&'a [Vector6<f64>]>),
}

/// The nodes of a solution with constant tensions (what [`solution`] builds before the
/// tendon paths and lengths): enough for a dense evaluation, as the next mesh's guess needs;
/// in a buffer the thread kept ([`spare`]), for the caller to give back.
pub(crate) fn nodes(
    model: &Model,
    states: &[State],
    segment_ends: &[f64],
    rates: Option<&[Vector6<f64>]>,
) -> Result<Vec<Node>> {
    let mut nodes = spare::take(states.len());
    fill_nodes(model, states, segment_ends, &Along::Constant(rates), &mut nodes)?;
    Ok(nodes)
}

fn build(model: &Model, states: &[State], segment_ends: &[f64], along: Along, report: SolveReport) -> Result<Solution> {
    let robot = model.robot;
    let length = robot.length();
    let nodes = node_list(model, states, segment_ends, &along)?;
    let mut s = spare::take(nodes.len());
    s.extend(nodes.iter().map(|n| n.s));
    // Each tendon's path and tensions are allocated once at their final length (counted
    // first), and nothing else is. Its routing points are evaluated once for its path and
    // its length ([`points::with_points`]).
    let (mut tendon_paths, mut tendon_tensions) = (
        Vec::with_capacity(robot.tendons.len()),
        Vec::with_capacity(robot.tendons.len()),
    );
    let mut lengths = spare::take(robot.tendons.len());
    for (i, t) in robot.tendons.iter().enumerate() {
        let end = t.end(length);
        let count = on_path(&nodes, end).count();
        // The nodes on [0, end] and the first past it: those of the path and of the
        // length's quadrature (which weighs the node past `end` where `end` is not a node).
        let reach = (s.partition_point(|&sk| sk <= end) + 1).min(s.len());
        let (path, tendon_length) = points::with_points(&t.routing, length, &s[..reach], |points| {
            let mut path = Vec::with_capacity(count);
            path.extend(on_path(&nodes, end).map(|k| nodes[k].p + nodes[k].R * points.at(k).r));
            // The quadrature depends only on the nodes and the tendon's end: kept by the
            // thread.
            let tendon_length = length::NodeQuadrature::with_kept(&s, end, |q| {
                q.integrate(|k| length::speed(&points.at(k), &nodes[k].v, &nodes[k].u))
            });
            (path, tendon_length)
        });
        tendon_paths.push(path);
        lengths.push(tendon_length);
        let tensions = match along {
            Along::Constant(_) => vec![model.tensions[i]; count],
            Along::Varying(profile, _, _) => {
                let mut tensions = Vec::with_capacity(count);
                tensions.extend(on_path(&nodes, end).map(|k| profile[k][i]));
                tensions
            }
        };
        tendon_tensions.push(tensions);
    }
    let mut tendons = tendon_states(model, &lengths);
    spare::give(lengths);
    for (state, tensions) in tendons.iter_mut().zip(&tendon_tensions) {
        state.delivered_tension = tensions.last().copied().unwrap_or(state.tension);
    }
    if let Along::Varying(profile, _, _) = along {
        // An elastic tendon with friction stretches by its varying tension: the integral of
        // tau(s) / (E_t A_t) over its reference path, plus its free length at the base
        // tension (docs/friction.md); constant tension gives the compliance of tendon_states.
        for (i, (t, state)) in robot.tendons.iter().zip(tendons.iter_mut()).enumerate() {
            let (Some(stiffness), Some(_)) = (t.stiffness, t.active_friction()) else {
                continue;
            };
            let quadrature = length::NodeQuadrature::new(&s, t.end(length));
            let stretch = quadrature.integrate(|k| {
                let reference = robot.rod.reference_on(s[k], segment_ends[k]);
                profile[k][i] * length::speed(&t.routing.at(s[k], length), &reference.v_star, &reference.u_star)
            }) / stiffness
                + t.free_length * state.tension / stiffness;
            state.displacement = state.reference_length - state.length + stretch;
        }
    }
    spare::give(s);
    Ok(Solution {
        nodes,
        tendon_paths,
        tendon_tensions,
        tendons,
        report,
    })
}

/// The indices of the `nodes` on the path of a tendon that ends at `end`: up to its end, one
/// per arc length (the left limit at a breakpoint).
fn on_path(nodes: &[Node], end: f64) -> impl Iterator<Item = usize> + '_ {
    let mut last_s = f64::NEG_INFINITY;
    (0..nodes.len()).filter(move |&k| nodes[k].s <= end && std::mem::replace(&mut last_s, nodes[k].s) < nodes[k].s)
}

/// Node states with their rates (v', u') of eq. 13 and internal wrenches (n, m).
fn node_list(model: &Model, states: &[State], segment_ends: &[f64], along: &Along) -> Result<Vec<Node>> {
    let mut nodes = Vec::with_capacity(states.len());
    fill_nodes(model, states, segment_ends, along, &mut nodes)?;
    Ok(nodes)
}

/// [`node_list`] appended to `nodes`.
fn fill_nodes(
    model: &Model,
    states: &[State],
    segment_ends: &[f64],
    along: &Along,
    nodes: &mut Vec<Node>,
) -> Result<()> {
    let robot = model.robot;
    // A model holding each node's tensions, made when they vary.
    let mut local: Option<(Model, Vec<f64>)> = None;
    for (k, &State { s, p, R, v, u }) in states.iter().enumerate() {
        let site = model.site_on(s, segment_ends[k]);
        let rates = match along {
            Along::Constant(Some(r)) => r[k],
            Along::Constant(None) => linearize::rates(model, &site, segment_ends[k], &R, &v, &u)?,
            Along::Varying(_, _, Some(r)) => r[k],
            Along::Varying(profile, multipliers, None) => {
                let (local, turning) = local.get_or_insert_with(|| (model.clone(), vec![0.0; robot.tendons.len()]));
                local.tensions.copy_from_slice(&profile[k]);
                let w = multipliers.map(|m| m[k].as_slice());
                friction::rates(local, &site, segment_ends[k], (&R, &v, &u), w, turning)?
            }
        };
        let (n, m) = model.internal_wrench(&site, &R, &v, &u);
        // The strain and its rate: on a Kirchhoff rod v = v* (the coordinate carries n).
        let v_s = if site.inextensible {
            site.reference.v_star_s
        } else {
            rates.fixed_rows::<3>(0).into()
        };
        let u_s = rates.fixed_rows::<3>(3).into();
        nodes.push(Node {
            s,
            p,
            R,
            v: site.strain(&v),
            u,
            v_s,
            u_s,
            n,
            m,
        });
    }
    Ok(())
}

/// Each tendon's tension, pull-in, lengths and slack (docs/actuation.md), its path length
/// given (`lengths`, m: the node quadrature over the solved nodes): for a
/// displacement-controlled tendon the slack phi = l_ref - l - q + c tau when its tension is
/// 0 (phi is the solver's residual, about 0, when taut).
fn tendon_states(model: &Model, lengths: &[f64]) -> Vec<TendonState> {
    let robot = model.robot;
    let mut breakpoints = spare::take(robot.tendons.len());
    robot.breakpoints_into(&mut breakpoints);
    let states = robot
        .tendons
        .iter()
        .zip(lengths)
        .enumerate()
        .map(|(i, (t, &length))| {
            let reference_length = length::reference_length_on(robot, &breakpoints, i);
            let tension = model.tensions[i];
            let taken_up = reference_length - length + t.compliance(reference_length) * tension;
            match t.displacement() {
                Some(q) => TendonState {
                    tension,
                    delivered_tension: tension,
                    displacement: q,
                    length,
                    reference_length,
                    slack: if tension > 0.0 { 0.0 } else { (taken_up - q).max(0.0) },
                },
                None => TendonState {
                    tension,
                    delivered_tension: tension,
                    displacement: taken_up,
                    length,
                    reference_length,
                    slack: 0.0,
                },
            }
        })
        .collect();
    spare::give(breakpoints);
    states
}
