//! The [`Solution`] both solvers return, built from their node states: the strain rates
//! (eq. 13) and internal wrenches at every node from the model, and the tendon paths.
#![allow(non_snake_case)]

use crate::Robot;
use crate::error::Result;
use crate::model::equations::Model;
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
    let robot = model.robot;
    let length = robot.length();
    let mut nodes = Vec::with_capacity(states.len());
    for (k, &State { s, p, R, v, u }) in states.iter().enumerate() {
        let site = model.site(s);
        let rates = match rates {
            Some(r) => r[k],
            None => linearize::rates(model, &site, segment_ends[k], &R, &v, &u)?,
        };
        let (v_s, u_s) = (rates.fixed_rows::<3>(0).into(), rates.fixed_rows::<3>(3).into());
        let (n, m) = model.internal_wrench(&site, &R, &v, &u);
        nodes.push(Node {
            s,
            p,
            R,
            v,
            u,
            v_s,
            u_s,
            n,
            m,
        });
    }
    let tendon_paths = robot
        .tendons
        .iter()
        .map(|t| {
            let end = t.end(length);
            let mut last_s = f64::NEG_INFINITY;
            nodes
                .iter()
                .filter(|nd| nd.s <= end && std::mem::replace(&mut last_s, nd.s) < nd.s)
                .map(|nd| nd.p + nd.R * t.routing.at(nd.s, length).r)
                .collect()
        })
        .collect();
    let tendons = tendon_states(model, &nodes);
    Ok(Solution {
        nodes,
        tendon_paths,
        tendons,
        report,
    })
}

/// Each tendon's tension, pull-in, lengths and slack at the solved `nodes` (docs/actuation.md):
/// the length by the node quadrature, and for a displacement-controlled tendon the slack
/// phi = l_ref - l - q + c tau when its tension is 0 (phi is the solver's residual, about 0,
/// when taut).
fn tendon_states(model: &Model, nodes: &[Node]) -> Vec<TendonState> {
    let robot = model.robot;
    let s: Vec<f64> = nodes.iter().map(|n| n.s).collect();
    robot
        .tendons
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let length = tendon_length(robot, i, &s, nodes);
            let reference_length = length::reference_length(robot, i);
            let tension = model.tensions[i];
            let taken_up = reference_length - length + t.compliance(reference_length) * tension;
            match t.displacement() {
                Some(q) => TendonState {
                    tension,
                    displacement: q,
                    length,
                    reference_length,
                    slack: if tension > 0.0 { 0.0 } else { (taken_up - q).max(0.0) },
                },
                None => TendonState {
                    tension,
                    displacement: taken_up,
                    length,
                    reference_length,
                    slack: 0.0,
                },
            }
        })
        .collect()
}

/// The path length of tendon `i` over solved `nodes` at arc lengths `s`
/// ([`length::NodeQuadrature`]).
pub(crate) fn tendon_length(robot: &Robot, i: usize, s: &[f64], nodes: &[Node]) -> f64 {
    let t = &robot.tendons[i];
    let l = robot.length();
    length::NodeQuadrature::new(s, t.end(l))
        .integrate(|k| length::speed(&t.routing.at(s[k], l), &nodes[k].v, &nodes[k].u))
}
