//! The order-6 scheme's interval rows (docs/numerics.md, "Error estimate"): the defect the
//! deferred-correction estimate reads, in the local coordinates and scaling of
//! [`super::residual::interval`].

// R for rotation matrices, as in the paper and residual.rs.
#![allow(non_snake_case)]

use super::residual::{Block, IntervalSites, end_values, rhs, rhs_lanes, scale_rows};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::simd::{avx2_fma, four};
use crate::solution::State;
use nalgebra::Vector6;

/// The sites the order-6 residual of an interval needs besides its [`IntervalSites`]: at
/// a quarter and three quarters of the interval.
#[derive(Clone, Copy, Debug)]
pub struct QuarterSites {
    /// Site at s_k + h/4.
    pub quarter: Site,
    /// Site at s_k + 3h/4.
    pub three_quarters: Site,
}

/// Interval rows of the order-6 scheme (the 5-stage mono-implicit Runge-Kutta formula of
/// Cash and Singhal, whose quadrature is Boole's rule on 0, 1/4, 1/2, 3/4, 1), evaluated at
/// the states `a`, `b` of the order-4 solution, in the same local coordinates and scaling
/// as [`super::residual::interval`]; `start_rates` and `end_rates` are the rates (v', u')
/// at the two nodes.
/// Every stage is explicit in the end points (docs/numerics.md, "Error estimate"):
///
/// ```text
/// y_1/4 = (27 y_0 + 5 y_1) / 32 + h (9 F_0 - 3 F_1) / 64
/// y_3/4 = (5 y_0 + 27 y_1) / 32 + h (3 F_0 - 9 F_1) / 64
/// y_1/2 = (y_0 + y_1) / 2 + h (5 (F_1 - F_0) / 24 + 2 (F_1/4 - F_3/4) / 3)
/// phi_6 = y_1 - y_0 - h (7 (F_0 + F_1) + 32 (F_1/4 + F_3/4) + 12 F_1/2) / 90
/// ```
///
/// # Errors
/// A model breakdown at a stage.
#[allow(clippy::too_many_arguments)]
pub fn interval_order6(
    model: &Model,
    sites: &IntervalSites,
    quarters: &QuarterSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: &Vector6<f64>,
    end_rates: &Vector6<f64>,
) -> Result<Block<f64>> {
    let st = Stages::new(sites, a, b, start_rates, end_rates);
    let f_q = rhs(model, &quarters.quarter, segment_end, &a.R, &st.y_q)?;
    let f_tq = rhs(model, &quarters.three_quarters, segment_end, &a.R, &st.y_tq)?;
    let y_m = st.y_mid(&f_q, &f_tq);
    let f_m = rhs(model, &sites.mid, segment_end, &a.R, &y_m)?;
    Ok(st.rows(&f_q, &f_tq, &f_m, model.robot.length()))
}

/// An interval's values of [`interval_order6`] up to its quarter stages, and the steps
/// after them, shared by the scalar and the lane evaluation.
struct Stages {
    h: f64,
    y0: Block<f64>,
    y1: Block<f64>,
    f0: Block<f64>,
    f1: Block<f64>,
    /// y_1/4.
    y_q: Block<f64>,
    /// y_3/4.
    y_tq: Block<f64>,
}

impl Stages {
    #[inline(always)]
    fn new(sites: &IntervalSites, a: &State, b: &State, start_rates: &Vector6<f64>, end_rates: &Vector6<f64>) -> Self {
        let h = sites.end.s - sites.start.s;
        let [y0, y1, f0, f1] = end_values(sites, a, b, start_rates, end_rates);
        let y_q = (y0 * 27.0 + y1 * 5.0) / 32.0 + (f0 * 9.0 - f1 * 3.0) * (h / 64.0);
        let y_tq = (y0 * 5.0 + y1 * 27.0) / 32.0 + (f0 * 3.0 - f1 * 9.0) * (h / 64.0);
        Stages {
            h,
            y0,
            y1,
            f0,
            f1,
            y_q,
            y_tq,
        }
    }

    /// y_1/2 from F at the quarter stages.
    #[inline(always)]
    fn y_mid(&self, f_q: &Block<f64>, f_tq: &Block<f64>) -> Block<f64> {
        let (y0, y1, f0, f1) = (&self.y0, &self.y1, &self.f0, &self.f1);
        (y0 + y1) * 0.5 + ((f1 - f0) * (5.0 / 24.0) + (f_q - f_tq) * (2.0 / 3.0)) * self.h
    }

    /// phi_6, scaled, from F at the three inner stages.
    #[inline(always)]
    fn rows(&self, f_q: &Block<f64>, f_tq: &Block<f64>, f_m: &Block<f64>, length: f64) -> Block<f64> {
        let (y0, y1, f0, f1) = (&self.y0, &self.y1, &self.f0, &self.f1);
        let quadrature = ((f0 + f1) * 7.0 + (f_q + f_tq) * 32.0 + f_m * 12.0) * (self.h / 90.0);
        scale_rows(y1 - y0 - quadrature, length)
    }
}

/// [`interval_order6`] of four intervals of one segment (`segment_end`) at once (interval j
/// between `nodes[j]`, with its sites and the rates at its nodes), each stage's eq. 13 at
/// the four intervals in one pass of four f64 lanes ([`rhs_lanes`]), each interval's bits
/// those of [`interval_order6`]. The stages of one interval depend on each other (y_1/2 on
/// F at y_1/4 and y_3/4), the intervals do not. Compiled for AVX2 and FMA where the
/// processor has them (checked at run time). None where a lane leaves the lanes' common
/// path: evaluate the intervals one by one then (which gives the errors).
pub(super) fn intervals_order6_lanes(
    model: &Model,
    sites: [&IntervalSites; 4],
    quarters: [&QuarterSites; 4],
    segment_end: f64,
    nodes: [(&State, &State); 4],
    rates: [(&Vector6<f64>, &Vector6<f64>); 4],
) -> Option<[Block<f64>; 4]> {
    avx2_fma!(lanes_kernel(model, sites, quarters, segment_end, nodes, rates))
}

/// [`intervals_order6_lanes`]' evaluation.
#[inline(always)]
fn lanes_kernel(
    model: &Model,
    sites: [&IntervalSites; 4],
    quarters: [&QuarterSites; 4],
    segment_end: f64,
    nodes: [(&State, &State); 4],
    rates: [(&Vector6<f64>, &Vector6<f64>); 4],
) -> Option<[Block<f64>; 4]> {
    let st = four!(j => Stages::new(sites[j], nodes[j].0, nodes[j].1, rates[j].0, rates[j].1));
    let Rk = four!(j => &nodes[j].0.R);
    let q_sites = four!(j => &quarters[j].quarter);
    let f_q = rhs_lanes(model, q_sites, segment_end, Rk, four!(j => &st[j].y_q))?;
    let tq_sites = four!(j => &quarters[j].three_quarters);
    let f_tq = rhs_lanes(model, tq_sites, segment_end, Rk, four!(j => &st[j].y_tq))?;
    let y_m = four!(j => st[j].y_mid(&f_q[j], &f_tq[j]));
    let f_m = rhs_lanes(model, four!(j => &sites[j].mid), segment_end, Rk, four!(j => &y_m[j]))?;
    let length = model.robot.length();
    Some(four!(j => st[j].rows(&f_q[j], &f_tq[j], &f_m[j], length)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::system::System;
    use crate::mesh::{Mesh, guess::rigid_estimate};
    use crate::model::linearize::rates;
    use crate::{Robot, so3};
    use nalgebra::Vector3;

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Compares [`intervals_order6_lanes`] with [`interval_order6`], and Newton's residual
    /// rows in lanes (`residual::intervals_lanes`) with `residual::interval`, bit for bit on every
    /// run of four intervals of one segment of `robot` on `intervals` uniform intervals, at
    /// the rigid estimate with node k turned by k `turn` rad about a fixed axis and its
    /// curvature moved by k `bend` (stages off the straight rod). Returns how many runs the
    /// lanes took (did not decline).
    fn compare(robot: &Robot, intervals: usize, turn: f64, bend: f64) -> usize {
        let model = Model::new(robot);
        let mesh = Mesh::uniform(robot, intervals).unwrap();
        let mut x = rigid_estimate(&model, &mesh.nodes);
        for (k, state) in x.iter_mut().enumerate() {
            state.R *= so3::exp(&(Vector3::new(0.3, -0.5, 0.8) * (turn * k as f64)));
            state.u += Vector3::new(1.0, -2.0, 0.5) * (bend * k as f64);
        }
        let system = System::new(model.clone(), mesh.clone());
        let (mut taken, mut residual_taken) = (0, 0);
        for k in 0..mesh.nodes.len().saturating_sub(4) {
            let Some(sites) = (0..4).map(|j| system.interval_sites(k + j)).collect::<Option<Vec<_>>>() else {
                continue;
            };
            let seg = mesh.nodes[k].segment_end;
            if mesh.nodes[k..k + 4].iter().any(|n| n.segment_end != seg) {
                continue;
            }
            let sites: [&IntervalSites; 4] = sites.try_into().unwrap();
            let quarters = sites.map(|s| {
                let h = s.end.s - s.start.s;
                QuarterSites {
                    quarter: model.site(s.start.s + 0.25 * h),
                    three_quarters: model.site(s.start.s + 0.75 * h),
                }
            });
            let node_rates: [(Vector6<f64>, Vector6<f64>); 4] = std::array::from_fn(|j| {
                let (a, b) = (&x[k + j], &x[k + j + 1]);
                let start = rates(&model, &sites[j].start, seg, &a.R, &a.v, &a.u).unwrap();
                (start, rates(&model, &sites[j].end, seg, &b.R, &b.v, &b.u).unwrap())
            });
            let scalar: [Block<f64>; 4] = std::array::from_fn(|j| {
                let (a, b, (r0, r1)) = (&x[k + j], &x[k + j + 1], &node_rates[j]);
                interval_order6(&model, sites[j], &quarters[j], seg, a, b, r0, r1).unwrap()
            });
            let nodes = std::array::from_fn(|j| (&x[k + j], &x[k + j + 1]));
            let lane_rates = std::array::from_fn(|j| (&node_rates[j].0, &node_rates[j].1));
            // Newton's residual rows of the four intervals (`residual::intervals_lanes`).
            let mut start = node_rates[0].0;
            let residual: [_; 4] = std::array::from_fn(|j| {
                let (a, b) = (&x[k + j], &x[k + j + 1]);
                let out = crate::collocation::residual::interval(&model, sites[j], seg, a, b, Some(start)).unwrap();
                start = out.2;
                out
            });
            if let Some(lanes) =
                crate::collocation::residual::intervals_lanes(&model, sites, seg, &x[k..k + 5], node_rates[0].0)
            {
                // Rows, start rates and end rates of each interval in one row of values.
                let flat = |r: &(Block<f64>, Vector6<f64>, Vector6<f64>)| {
                    bits(&[r.0.as_slice(), r.1.as_slice(), r.2.as_slice()].concat())
                };
                for j in 0..4 {
                    assert_eq!(flat(&lanes[j]), flat(&residual[j]), "interval {}", k + j);
                }
                residual_taken += 1;
            }
            if let Some(lanes) = intervals_order6_lanes(&model, sites, quarters.each_ref(), seg, nodes, lane_rates) {
                for j in 0..4 {
                    assert!(scalar[j].amax() > 0.0, "interval {} has order-6 rows", k + j);
                    assert_eq!(
                        bits(lanes[j].as_slice()),
                        bits(scalar[j].as_slice()),
                        "interval {}",
                        k + j
                    );
                }
                taken += 1;
            }
        }
        // Both see the lanes' path at points of the same intervals.
        assert_eq!(residual_taken, taken);
        taken
    }

    /// Every lane gives the scalar rows' bits on the prototype with four tendons pulled
    /// (small and large turns between nodes, bent), on case H's helical tendon with its tip
    /// force, and across a tendon that ends mid-rod (runs within each segment), where the
    /// lanes take every run; a Kirchhoff rod's runs they decline.
    #[test]
    fn lanes_give_the_scalar_bits() {
        let prototype = crate::collocation::test_support::pulled_prototype();
        let mut ending = crate::cases::case_s();
        ending.tendons[1].set_tension(1.5);
        let half = 0.5 * ending.length();
        ending = ending.with_tendon(
            crate::model::tendon::Tendon::new(crate::model::routing::Routing::straight(0.0, 0.008), 2.0)
                .ending_at(half),
        );
        let mut kirchhoff = prototype.clone();
        kirchhoff.rod_model = crate::model::robot::RodModel::Kirchhoff;
        let runs = [
            compare(&prototype, 32, 0.0, 0.2),
            compare(&prototype, 12, 0.7, 0.5),
            compare(&crate::cases::case_h(), 16, 0.0, 0.3),
            compare(&ending, 16, 0.01, 0.1),
        ];
        assert_eq!(compare(&kirchhoff, 8, 0.0, 0.2), 0);
        // The lanes run in the AVX2 build or the baseline one alike: they take every run.
        assert_eq!(runs[..3], [29, 9, 13]);
        assert!(runs[3] > 0);
    }
}
