//! The [`Solution`] both solvers return, built from their node states: the strain rates
//! (eq. 13) and internal wrenches at every node from the model, and the tendon paths.
#![allow(non_snake_case)]

use crate::error::Result;
use crate::model::equations::Model;
use crate::model::linearize;
use crate::report::SolveReport;
use crate::solution::{Node, Solution, State};
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
    Ok(Solution {
        nodes,
        tendon_paths,
        report,
    })
}
