//! The residual's exact columns in parameters at fixed states ([`System::parameter_columns`]:
//! every tension, or the section's stiffnesses), and the tension columns formed with the
//! Jacobian in one pass over the mesh ([`System::jacobian_and_tensions`]): the right-hand
//! sides of the sensitivities (docs/sensitivity.md, "Exact tension columns").

use super::{Columns, System};
use crate::collocation::interval_lanes::GroupTensions;
use crate::collocation::residual::{self, Block, IntervalSites, IntervalTensions};
use crate::collocation::unknowns::{BASE_ROWS, link_row, tip_row};
use crate::error::Result;
use crate::model::equations::Side;
use crate::model::linearize;
use crate::model::robot::Robot;
use crate::model::routing::{Routing, RoutingPoint};
use crate::solution::State;
use nalgebra::{Vector3, Vector6};

/// The buffers of the tension columns formed with the Jacobian ([`System::jacobian_and_tensions`]),
/// which a workspace keeps between Jacobians: the rates' derivatives at an interval's start
/// node, end node and midpoint, the midpoint's strain motion (one entry per tendon in
/// each), and the tendons' routing points at the intervals' end nodes and midpoints.
#[derive(Default)]
pub(crate) struct TensionSink {
    rates: [Vec<Vector6<f64>>; 4],
    /// A run of four intervals' end nodes but the last (whose are `rates[1]`, where the
    /// next interval reads them) and midpoints: seven entries per tendon.
    group: Vec<Vector6<f64>>,
    routing: RoutingPoints,
}

impl TensionSink {
    /// Makes the buffers those of `system`'s tendons and routing points (computed again
    /// where the kept ones are not `system`'s).
    fn prepare(&mut self, system: &System) {
        let width = system.model.robot.tendons.len();
        for rates in &mut self.rates {
            rates.resize(width, Vector6::zeros());
        }
        self.group.resize(7 * width, Vector6::zeros());
        self.routing.prepare(system.model.robot, &system.interval_sites);
    }

    /// The buffers of link `k` (an interval) for [`residual::interval_jacobian`], its rows
    /// of the right-hand sides going into `columns` (`n` rows each); with `carried`, the
    /// start node's derivatives are the last interval's end ones.
    #[inline]
    pub(super) fn interval<'t>(
        &'t mut self,
        carried: bool,
        k: usize,
        columns: &'t mut [f64],
        n: usize,
    ) -> IntervalTensions<'t> {
        if carried {
            self.rates.swap(0, 1);
        }
        let [start, end, mid, dy_mid] = &mut self.rates;
        IntervalTensions {
            routing: self.routing.interval(k, start.len()),
            start,
            end,
            mid,
            dy_mid,
            columns,
            n,
            row: link_row(k),
        }
    }
}

impl TensionSink {
    /// The buffers of the links `k..k + 4` (intervals of one segment) for the lane kernel
    /// (`interval_lanes::interval_jacobians4`), as [`TensionSink::interval`] gives them to
    /// one interval: with `carried`, the first start node's derivatives are the last
    /// interval's end ones; the last end node's are where the next interval reads them.
    pub(super) fn group<'t>(
        &'t mut self,
        carried: bool,
        k: usize,
        columns: &'t mut [f64],
        n: usize,
    ) -> GroupTensions<'t> {
        if carried {
            self.rates.swap(0, 1);
        }
        let width = self.rates[0].len();
        let [start, last, _, dy_mid] = &mut self.rates;
        let (e0, rest) = self.group.split_at_mut(width);
        let (e1, rest) = rest.split_at_mut(width);
        let (e2, rest) = rest.split_at_mut(width);
        let (m0, rest) = rest.split_at_mut(width);
        let (m1, rest) = rest.split_at_mut(width);
        let (m2, m3) = rest.split_at_mut(width);
        let routing = [0, 1, 2, 3].map(|j| self.routing.interval(k + j, width));
        GroupTensions {
            start,
            ends: [e0, e1, e2, last],
            mids: [m0, m1, m2, m3],
            dy_mid,
            columns,
            n,
            rows: [0, 1, 2, 3].map(|j| link_row(k + j)),
            routing: match routing {
                [Some(a), Some(b), Some(c), Some(d)] => Some([a, b, c, d]),
                _ => None,
            },
        }
    }
}

/// The tendons' routing points r, r', r'' at every interval's end node and midpoint, kept
/// between the Jacobians that form the tension columns ([`TensionSink`]): they depend on
/// the routings, the rod's length and the arc lengths only, not on the state, and a slack
/// tendon (no point kept by eq. 13's assembly) needs them at every point (a helical
/// routing's a sine and a cosine each). Computed by [`Routing::at`] as the pass would, so
/// the same bits; an interval's are computed again when its arc lengths differ from those
/// they were computed at, all of them when the routings or the length differ. Not kept for
/// a robot with a user routing ([`Routing::Custom`]: a closure, which cannot be compared).
#[derive(Default)]
struct RoutingPoints {
    /// The routings' parameters and the rod's length the points are for; empty: none kept.
    key: Vec<f64>,
    /// Per link, the arc lengths of its end node and midpoint the points were computed at
    /// (NaN: not computed).
    at: Vec<[f64; 2]>,
    /// Per link, every tendon's point at its end node, then at its midpoint.
    points: Vec<RoutingPoint>,
}

impl RoutingPoints {
    /// Makes the points those of `robot` at the end nodes and midpoints of the intervals
    /// `sites` (one entry per link, None for a jump): all computed again unless they were
    /// computed for `robot`'s routings and length, else a link's where its arc lengths
    /// differ.
    fn prepare(&mut self, robot: &Robot, sites: &[Option<IntervalSites>]) {
        let length = robot.length();
        let mut key = std::mem::take(&mut self.key);
        let same = key.len() == KEY * robot.tendons.len() + 1
            && key[0] == length
            && robot
                .tendons
                .iter()
                .zip(key[1..].chunks_exact(KEY))
                .all(|(t, k)| routing_key(&t.routing).is_some_and(|r| r[..] == *k));
        if !same {
            key.clear();
            self.at.clear();
            self.points.clear();
            let keys: Option<Vec<[f64; KEY]>> = robot.tendons.iter().map(|t| routing_key(&t.routing)).collect();
            if let Some(keys) = keys {
                key.push(length);
                key.extend(keys.iter().flatten());
            }
        }
        self.key = key;
        if self.key.is_empty() {
            return;
        }
        let width = robot.tendons.len();
        if self.at.len() != sites.len() {
            let zero = RoutingPoint {
                r: Vector3::zeros(),
                r_s: Vector3::zeros(),
                r_ss: Vector3::zeros(),
            };
            self.at.resize(sites.len(), [f64::NAN; 2]);
            self.points.resize(sites.len() * 2 * width, zero);
        }
        let links = self
            .at
            .iter_mut()
            .zip(self.points.chunks_exact_mut(2 * width))
            .zip(sites);
        for ((at, points), sites) in links {
            let Some(sites) = sites else { continue };
            let s = [sites.end.s, sites.mid.s];
            if *at != s {
                for (points, s) in points.chunks_exact_mut(width).zip(s) {
                    for (p, t) in points.iter_mut().zip(&robot.tendons) {
                        *p = t.routing.at(s, length);
                    }
                }
                *at = s;
            }
        }
    }

    /// Every tendon's routing point at link `k`'s end node and at its midpoint (`width`
    /// tendons); None when none are kept (a user routing).
    #[inline]
    fn interval(&self, k: usize, width: usize) -> Option<[&[RoutingPoint]; 2]> {
        if self.key.is_empty() {
            return None;
        }
        let (end, mid) = self.points[2 * k * width..2 * (k + 1) * width].split_at(width);
        Some([end, mid])
    }
}

/// The kind and parameters that fix a routing's points on a rod of given length; None for
/// a user routing.
fn routing_key(routing: &Routing) -> Option<[f64; KEY]> {
    match *routing {
        Routing::Straight { x, y } => Some([0.0, x, y, 0.0]),
        Routing::Helical { radius, turns, phase } => Some([1.0, radius, turns, phase]),
        Routing::Custom(_) => None,
    }
}

/// Numbers of a routing's key ([`routing_key`]).
const KEY: usize = 4;

impl System<'_> {
    /// The exact derivative of the residual in some parameters at the states `x`,
    /// column-major into `out`, one column of [`System::unknowns`] rows per parameter:
    /// [`Columns::Tensions`], one per tendon of the robot (slack tendons: the right
    /// derivative), or [`Columns::Stiffness`], the six diagonal stiffnesses of a section
    /// that does not vary along the rod (GA, GA, EA, EIxx, EIyy, GJ). The residual is linear
    /// in each tension once the tendon's path terms are formed, and eq. 13 in each stiffness:
    /// interval rows by the chain rule through the scheme (`residual::interval_derivatives`),
    /// jump and tip rows by `Model::wrench_balance_tensions` or
    /// `Model::wrench_balance_stiffness`, base rows 0
    /// (docs/sensitivity.md, "Exact tension columns"). Without friction: the log tensions
    /// of tendons with friction are not unknowns here.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub fn parameter_columns(&self, x: &[State], columns: Columns, out: &mut [f64]) -> Result<()> {
        let model = &self.model;
        let n = self.unknowns();
        let (width, point): (usize, residual::PointDerivatives) = match columns {
            Columns::Tensions => (model.robot.tendons.len(), linearize::tension_rates),
            Columns::Stiffness => (6, linearize::stiffness_rates),
        };
        debug_assert_eq!(out.len(), n * width);
        let mut rates = [
            vec![Vector6::zeros(); width],
            vec![Vector6::zeros(); width],
            vec![Vector6::zeros(); width],
            vec![Vector6::zeros(); width],
        ];
        let mut block = vec![Block::zeros(); width];
        let links = x.len() - 1;
        let mut node_rates = None;
        for k in 0..links {
            let row = link_row(k);
            let Some(sites) = &self.interval_sites[k] else {
                node_rates = None;
                continue;
            };
            let seg = self.mesh.nodes[k].segment_end;
            if node_rates.is_some() {
                // Node k's derivatives are the previous interval's end ones.
                rates.swap(0, 1);
            }
            let [d0, d1, dm, dy] = &mut rates;
            let (a, b) = (&x[k], &x[k + 1]);
            let end = residual::interval_derivatives(
                model,
                sites,
                seg,
                a,
                b,
                node_rates,
                point,
                [d0, d1, dm, dy],
                &mut block,
            )?;
            node_rates = Some(end);
            for (i, b) in block.iter().enumerate() {
                out[i * n + row..i * n + row + b.len()].copy_from_slice(b.as_slice());
            }
        }
        self.point_load_columns(x, columns, out)
    }

    /// The residual into `out`, the Jacobian values into `values` (as [`System::jacobian`],
    /// the same bits), and -dF/dtau_i of every tendon into `tensions` (column-major; the
    /// right-hand sides of the tension columns: [`System::parameter_columns`] with
    /// [`Columns::Tensions`] negated, to rounding), with the buffers `sink` keeps between
    /// calls: each interval's
    /// tension rows from the same assembly and factors of eq. 13 at its nodes and midpoint
    /// as its Jacobian block, the midpoint's chain rule through the linearization's
    /// d(v', u')/d(v, u) (docs/sensitivity.md, "Tension columns formed with the verdict's
    /// Jacobian"). Without friction.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn jacobian_and_tensions(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        tensions: &mut [f64],
        sink: &mut TensionSink,
    ) -> Result<()> {
        debug_assert!(self.friction.is_none());
        sink.prepare(self);
        self.jacobian_with(x, out, values, None, Some((sink, &mut *tensions)), None)?;
        self.point_load_columns(x, Columns::Tensions, tensions)?;
        self.negate_outer_rows(tensions);
        Ok(())
    }

    /// [`System::jacobian_rates`] with the tension columns' right-hand sides -dF/dtau_i of
    /// [`System::jacobian_and_tensions`] from the same evaluations (tendons without
    /// friction): the Jacobian at a trial point of Newton's for a verdict that keeps the
    /// tension columns.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    pub(crate) fn jacobian_rates_and_tensions(
        &self,
        x: &[State],
        out: &mut [f64],
        values: &mut [f64],
        rates: &mut [Vector6<f64>],
        tensions: &mut [f64],
        sink: &mut TensionSink,
    ) -> Result<()> {
        debug_assert!(self.friction.is_none());
        sink.prepare(self);
        self.jacobian_with(x, out, values, None, Some((sink, &mut *tensions)), Some(rates))?;
        self.jump_residual_rows(x, out)?;
        self.point_load_columns(x, Columns::Tensions, tensions)?;
        self.negate_outer_rows(tensions);
        Ok(())
    }

    /// Negates the rows of the columns `out` outside the intervals (base rows, jumps, tip
    /// rows), which [`System::point_load_columns`] wrote as dF/dq: with the interval rows
    /// the sink wrote negated, the columns are then -dF/dq throughout (negation is exact:
    /// the bits of negating the whole columns afterwards).
    fn negate_outer_rows(&self, out: &mut [f64]) {
        let n = self.unknowns();
        let negate = |out: &mut [f64], rows: std::ops::Range<usize>| {
            for column in out.chunks_exact_mut(n) {
                column[rows.clone()].iter_mut().for_each(|v| *v = -*v);
            }
        };
        negate(out, 0..BASE_ROWS);
        for (k, sites) in self.interval_sites.iter().enumerate() {
            if sites.is_none() {
                negate(out, link_row(k)..link_row(k + 1));
            }
        }
        negate(out, tip_row(self.mesh.nodes.len())..n);
    }

    /// The rows of [`System::parameter_columns`] outside the intervals: base rows 0, a
    /// jump's continuity rows 0 and its balance rows, the tip rows (the point loads'
    /// derivatives); the intervals' rows are left as they are.
    ///
    /// # Errors
    /// A model breakdown at a visited state.
    fn point_load_columns(&self, x: &[State], columns: Columns, out: &mut [f64]) -> Result<()> {
        let model = &self.model;
        let n = self.unknowns();
        let width = out.len() / n;
        // The point-load rows' derivative.
        let balance =
            |s: f64, left: Side<f64>, right: Option<Side<f64>>, out: &mut [(Vector3<f64>, Vector3<f64>)]| match columns
            {
                Columns::Tensions => model.wrench_balance_tensions(s, left, right, out),
                Columns::Stiffness => model.wrench_balance_stiffness(s, left, right, out),
            };
        // Every row is written but the base rows (no parameter moves them) and the first
        // six rows of a jump (its position and rotation continuity): those are zeroed here,
        // not the whole buffer.
        for column in out.chunks_exact_mut(n) {
            column[..BASE_ROWS].fill(0.0);
        }
        for (k, _) in self
            .interval_sites
            .iter()
            .enumerate()
            .filter(|(_, sites)| sites.is_none())
        {
            for column in out.chunks_exact_mut(n) {
                column[link_row(k)..link_row(k) + 6].fill(0.0);
            }
        }
        let length = model.robot.length();
        let mut wrench = vec![(Vector3::zeros(), Vector3::zeros()); width];
        let mut write = |rows: usize, i: usize, values: &[f64]| {
            out[i * n + rows..i * n + rows + values.len()].copy_from_slice(values);
        };
        let links = x.len() - 1;
        for k in (0..links).filter(|&k| self.interval_sites[k].is_none()) {
            let row = link_row(k);
            let (left, right) = (&self.node_sites[k], &self.node_sites[k + 1]);
            let (a, b) = (&x[k], &x[k + 1]);
            wrench.fill((Vector3::zeros(), Vector3::zeros()));
            balance(
                left.s,
                (left, &a.R, &a.v, &a.u),
                Some((right, &b.R, &b.v, &b.u)),
                &mut wrench,
            )?;
            for (i, (f, m)) in wrench.iter().enumerate() {
                write(row + 6, i, f.as_slice());
                write(row + 9, i, (m * length).as_slice());
            }
        }
        let (site, tip) = (&self.node_sites[links], &x[links]);
        wrench.fill((Vector3::zeros(), Vector3::zeros()));
        balance(site.s, (site, &tip.R, &tip.v, &tip.u), None, &mut wrench)?;
        let row = tip_row(x.len());
        for (i, (f, m)) in wrench.iter().enumerate() {
            write(row, i, f.as_slice());
            write(row + 3, i, (m * length).as_slice());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::{Options, unknowns::nonzeros};
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::robot::RodModel;

    /// The Jacobian formed with the tension columns is the plain Jacobian's bits (residual
    /// and values), and its tension columns are `parameter_columns`' to rounding, at the
    /// solutions of case H with three tendons pulled (two taut, slack ones, tendon
    /// terminations as jumps), as a Cosserat and as a Kirchhoff rod.
    #[test]
    fn tension_columns_with_the_jacobian_equal_the_pass_over_the_mesh() {
        for rod_model in [RodModel::Cosserat, RodModel::Kirchhoff] {
            let mut robot = crate::cases::case_h();
            robot.rod_model = rod_model;
            robot.tendons[1].set_tension(0.7);
            robot.tendons[3].set_tension(1.3);
            let solution = crate::collocation::solve(&robot, &Options::default()).unwrap();
            let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
            let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
            let system = System::new(Model::new(&robot), Mesh::from_points(&robot, &s).unwrap());
            let (n, width) = (system.unknowns(), robot.tendons.len());
            let (mut plain, mut values) = (vec![0.0; n], vec![0.0; nonzeros(&system.mesh)]);
            system.jacobian(&x, &mut plain, &mut values).unwrap();
            let (mut residual, mut with) = (vec![0.0; n], vec![0.0; values.len()]);
            let mut columns = vec![f64::NAN; n * width];
            system
                .jacobian_and_tensions(&x, &mut residual, &mut with, &mut columns, &mut TensionSink::default())
                .unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&plain), bits(&residual));
            assert_eq!(bits(&values), bits(&with));
            let mut pass = vec![f64::NAN; n * width];
            system.parameter_columns(&x, Columns::Tensions, &mut pass).unwrap();
            // The right-hand sides: -dF/dtau.
            pass.iter_mut().for_each(|v| *v = -*v);
            for i in 0..width {
                let (a, b) = (&columns[i * n..(i + 1) * n], &pass[i * n..(i + 1) * n]);
                let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let gap = a.iter().zip(b).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                // 1e-13 of the column: the same derivative through the midpoint's chain rule
                // as -M^-1 dF/dtau + (d(v', u')/d(v, u)) dy instead of -M^-1 (dF/dtau +
                // dF/d(v, u) dy), which differ in rounding only.
                assert!(
                    scale > 0.0 && gap <= 1e-13 * scale,
                    "{rod_model:?} tendon {i}: {gap:e} of {scale:e}"
                );
            }
        }
    }

    /// `jacobian_rates` (and `jacobian_rates_and_tensions`) gives `residual_rates`' residual
    /// and node rates bit for bit, and `jacobian`'s values (and `jacobian_and_tensions`'
    /// columns), at the solutions of case H with three tendons pulled (tendon
    /// terminations as jumps) and of the prototype with four, each as a Cosserat and as a
    /// Kirchhoff rod, and at their rigid-equilibrium guesses (states far from a root).
    #[test]
    fn the_jacobian_at_a_trial_point_gives_the_residual_evaluation_bits() {
        // The first entry whose bits differ, if any.
        let bits = |a: &[f64], b: &[f64]| a.iter().zip(b).position(|(a, b)| a.to_bits() != b.to_bits());
        for (case, rod_model) in [0, 1]
            .into_iter()
            .flat_map(|c| [(c, RodModel::Cosserat), (c, RodModel::Kirchhoff)])
        {
            let mut robot = if case == 0 {
                crate::cases::case_h()
            } else {
                crate::cases::prototype()
            };
            robot.rod_model = rod_model;
            for (i, tendon) in robot.tendons.iter_mut().enumerate().take(4).skip(1) {
                tendon.set_tension(0.3 + 0.5 * i as f64);
            }
            let solution = crate::collocation::solve(&robot, &Options::default()).unwrap();
            let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
            let answer: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
            let system = System::new(Model::new(&robot), Mesh::from_points(&robot, &s).unwrap());
            let guess = crate::mesh::guess::rigid_estimate(&system.model, &system.mesh.nodes);
            // Kept from the answer's columns for the guess's, as a workspace keeps them.
            let mut kept = TensionSink::default();
            for x in [answer, guess] {
                let n = system.unknowns();
                let (mut residual, mut rates) = (vec![0.0; n], vec![Vector6::zeros(); x.len()]);
                assert!(system.residual_rates(&x, &mut residual, &mut rates).unwrap());
                let (mut plain, mut values) = (vec![0.0; n], vec![0.0; nonzeros(&system.mesh)]);
                system.jacobian(&x, &mut plain, &mut values).unwrap();
                let (mut with, mut with_values) = (vec![0.0; n], vec![0.0; values.len()]);
                let mut with_rates = vec![Vector6::zeros(); x.len()];
                assert!(
                    system
                        .jacobian_rates(&x, &mut with, &mut with_values, &mut with_rates)
                        .unwrap()
                );
                assert_eq!(bits(&residual, &with), None, "{case} {rod_model:?}");
                assert_eq!(bits(&values, &with_values), None, "{case} {rod_model:?}");
                let flat = |r: &[Vector6<f64>]| r.iter().flat_map(|v| v.iter().copied()).collect::<Vec<_>>();
                assert_eq!(bits(&flat(&rates), &flat(&with_rates)), None, "{case} {rod_model:?}");
                // With the tension columns (a `Solver` that keeps them): the same bits again,
                // and the columns `jacobian_and_tensions` forms, bit for bit (the same
                // operations on the same evaluations).
                let width = robot.tendons.len();
                let (mut both, mut both_values) = (vec![0.0; n], vec![0.0; values.len()]);
                let mut both_rates = vec![Vector6::zeros(); x.len()];
                let mut columns = vec![f64::NAN; n * width];
                system
                    .jacobian_rates_and_tensions(
                        &x,
                        &mut both,
                        &mut both_values,
                        &mut both_rates,
                        &mut columns,
                        &mut kept,
                    )
                    .unwrap();
                assert_eq!(bits(&residual, &both), None, "{case} {rod_model:?}");
                assert_eq!(bits(&values, &both_values), None, "{case} {rod_model:?}");
                assert_eq!(bits(&flat(&rates), &flat(&both_rates)), None, "{case} {rod_model:?}");
                let (mut r, mut v) = (vec![0.0; n], vec![0.0; values.len()]);
                let mut want = vec![f64::NAN; n * width];
                let fresh = &mut TensionSink::default();
                system
                    .jacobian_and_tensions(&x, &mut r, &mut v, &mut want, fresh)
                    .unwrap();
                assert_eq!(bits(&want, &columns), None, "{case} {rod_model:?}");
            }
        }
    }

    /// Routing points kept from another robot's tension columns on the same mesh (the
    /// helical tendon's phase and a straight tendon's offset moved, an unloaded tendon made
    /// helical) are computed again, and
    /// kept ones give the columns of fresh ones bit for bit; a robot with a user routing
    /// keeps none.
    #[test]
    fn kept_routing_points_give_the_bits_of_fresh_ones() {
        let bits = |a: &[f64], b: &[f64]| a.iter().zip(b).position(|(a, b)| a.to_bits() != b.to_bits());
        let robot = crate::cases::case_h();
        let solution = crate::collocation::solve(&robot, &Options::default()).unwrap();
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
        let mut moved = robot.clone();
        moved.tendons[4].routing = Routing::Helical {
            radius: 0.008,
            turns: 1.0,
            phase: 0.3,
        };
        moved.tendons[0].routing = Routing::Straight { x: 0.007, y: 0.001 };
        // An unloaded tendon's points enter its tension column (a loaded one's come from the
        // linearization's own), and a helical one's move with s.
        moved.tendons[1].routing = Routing::Helical {
            radius: 0.008,
            turns: 0.5,
            phase: 1.0,
        };
        let mut custom = robot.clone();
        custom.tendons[4].routing = Routing::Custom(std::sync::Arc::new(|s: f64, length: f64| {
            Routing::Helical {
                radius: 0.008,
                turns: 1.0,
                phase: 0.0,
            }
            .at(s, length)
        }));
        // The same node count with every odd interior node moved a quarter interval (the
        // links' `at != s` branch), and every other node (fewer links).
        let shifted: Vec<f64> = (0..s.len())
            .map(|k| {
                if k % 2 == 1 && k + 1 < s.len() {
                    s[k] + 0.25 * (s[k + 1] - s[k])
                } else {
                    s[k]
                }
            })
            .collect();
        let half: Vec<usize> = (0..s.len()).filter(|&k| k % 2 == 0 || k + 1 == s.len()).collect();
        let (s_half, x_half): (Vec<f64>, Vec<State>) = half.iter().map(|&k| (s[k], x[k])).unzip();
        let meshes = [
            (&robot, &s, &x),
            (&robot, &s, &x),
            (&moved, &s, &x),
            (&moved, &shifted, &x),
            (&moved, &s_half, &x_half),
            (&moved, &s, &x),
            (&custom, &s, &x),
        ];
        let mut kept = TensionSink::default();
        for (k, (robot, s, x)) in meshes.into_iter().enumerate() {
            let system = System::new(Model::new(robot), Mesh::from_points(robot, s).unwrap());
            let (n, width) = (system.unknowns(), robot.tendons.len());
            let columns = |sink: &mut TensionSink| {
                let (mut r, mut v) = (vec![0.0; n], vec![0.0; nonzeros(&system.mesh)]);
                let mut c = vec![f64::NAN; n * width];
                system.jacobian_and_tensions(x, &mut r, &mut v, &mut c, sink).unwrap();
                c
            };
            let with_kept = columns(&mut kept);
            assert_eq!(
                bits(&with_kept, &columns(&mut TensionSink::default())),
                None,
                "mesh {k}"
            );
            assert_eq!(kept.routing.key.is_empty(), k == 6, "mesh {k}");
        }
    }
}
