//! Tendons with friction in the collocation solver (docs/friction.md): the log tensions
//! z_j = ln(tau_j / tau_j(0)) at the nodes of each tendon's span are unknowns that border
//! the block-banded system, with one capstan row per interval ([`interval`]):
//!
//! ```text
//! [ J      F_z   ] [dx]   [ -F   ]
//! [ psi_x  psi_z ] [dz] = [ -psi ]
//! ```
//!
//! Every block is exact: J by the chain rule through eq. 13 with friction, F_z, psi_x and
//! psi_z from the same interval linearization, the termination's force by its linearity in
//! the tension. One factorization of J gives a = J^-1 (-F) and the columns X = J^-1 F_z
//! (one per unknown z), then dz from the Schur complement S = psi_z - psi_x X and
//! dx = a - X dz, in the Newton loop of displacement-controlled tendons
//! ([`newton::run_bordered`]). The solve starts from the frictionless solution on its mesh.
#![allow(non_snake_case)]

mod border;
mod grip;
pub(crate) mod history;
mod interval;
mod linearized;

pub use grip::Contact;
pub(crate) use grip::Grip;
pub(crate) use interval::{Profile, interval, interval_order6};

use super::newton::{self, Border, Linearization, Point, Settings, Workspace};
use super::residual::QuarterSites;
use super::system::System;
use super::unknowns::{self, NODE, link_row, tip_row};
use super::{Cache, Options, estimate, pipeline, refine};
use crate::dense::solve_dense;
use crate::error::{self, Result};
use crate::mesh::guess::interpolate;
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport, Stability, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Robot};
use std::time::Instant;

/// Passes of the iterative bordered solve before it falls back to the dense Schur
/// complement: at a contraction of 0.1 per pass, 16 reach rounding.
const ITERATIONS: usize = 30;

/// The unknown of slip j at node n given the slips' first unknowns and spans, if it is one
/// (n in 1..=span).
fn unknown(offsets: &[usize], spans: &[usize], j: usize, n: usize) -> Option<usize> {
    (1..=spans[j]).contains(&n).then(|| offsets[j] + n - 1)
}

/// The capstan rows psi of `profile` from its links' last evaluations (by the system's
/// residual or Jacobian) into `psi`, row (j, link k) at `offsets[j] + k`; NaN for a link
/// without an evaluation.
fn capstan_rows(profile: &Profile, offsets: &[usize], psi: &mut [f64]) {
    let last = profile.spans.iter().copied().max().unwrap_or(0);
    for k in 0..last {
        profile.cached(k, |lin| {
            for (j, &o) in offsets.iter().enumerate() {
                if profile.on_link(j, k) {
                    psi[o + k] = lin.map_or(f64::NAN, |l| l.psi[j]);
                }
            }
        });
    }
}

/// The border of the tendons with friction on one mesh.
pub(crate) struct Capstan<'r> {
    /// The collocation system, its profile at the log tensions of the last evaluation.
    system: System<'r>,
    /// First unknown (= row) of each slip: unknown (j, node n) is offsets[j] + n - 1, row
    /// (j, link k) is offsets[j] + k.
    offsets: Vec<usize>,
    /// z at the current and trial point, and the step dz and the last simplified dz.
    z: Vec<f64>,
    trial_z: Vec<f64>,
    dz: Vec<f64>,
    simplified: Vec<f64>,
    /// psi at the current and trial point.
    psi: Vec<f64>,
    trial_psi: Vec<f64>,
    /// X = J^-1 F_z, one column per unknown, formed only when the iterative solve does not
    /// contract (`columns_ready` once formed for the current J).
    columns: Vec<Vec<f64>>,
    columns_ready: bool,
    /// F_z by link: the 12 x 2k derivative of its backbone rows in the log tensions of its
    /// two nodes (None for jumps and links past every span).
    link_z: Vec<Option<nalgebra::DMatrix<f64>>>,
    /// Per slip, the termination rows' derivative in its last log tension: the first row
    /// and the values.
    terminations: Vec<Option<(usize, [f64; 6])>>,
    /// The step dz of the last bordered solve.
    border_step: Vec<f64>,
    /// Work vectors: n-long w = F_z dz and y = J^-1 w, m-long right-hand sides, and a small
    /// system per link.
    w: Vec<f64>,
    y: Vec<f64>,
    r0: Vec<f64>,
    rr: Vec<f64>,
    small_matrix: Vec<f64>,
    small_rhs: Vec<f64>,
    /// psi_x: each row's 24 entries over the unknowns of its link's two nodes.
    psi_x: Vec<[f64; 2 * NODE]>,
    /// The link of each row.
    row_link: Vec<usize>,
    /// psi_z, dense, row major.
    psi_z: Vec<f64>,
    schur: Vec<f64>,
    schur_rhs: Vec<f64>,
    /// The border rows of the elimination in hand (psi, or the estimate's difference).
    rows_in: Vec<f64>,
}

impl<'r> Capstan<'r> {
    fn new(system: System<'r>) -> Self {
        let profile = system.friction.as_ref().map_or_else(Vec::new, |p| p.spans.clone());
        let mut offsets = Vec::with_capacity(profile.len());
        let mut row_link = Vec::new();
        for &span in &profile {
            offsets.push(row_link.len());
            row_link.extend(0..span);
        }
        let m = row_link.len();
        let n = system.unknowns();
        let links = system.mesh.nodes.len() - 1;
        let mut border = Capstan {
            system,
            offsets,
            z: vec![0.0; m],
            trial_z: vec![0.0; m],
            dz: vec![0.0; m],
            simplified: vec![0.0; m],
            psi: vec![0.0; m],
            trial_psi: vec![0.0; m],
            columns: vec![vec![0.0; n]; m],
            columns_ready: false,
            link_z: vec![None; links],
            terminations: vec![None; profile.len()],
            border_step: vec![0.0; m],
            w: vec![0.0; n],
            y: vec![0.0; n],
            r0: vec![0.0; m],
            rr: vec![0.0; m],
            small_matrix: vec![0.0; profile.len() * profile.len()],
            small_rhs: vec![0.0; profile.len()],
            psi_x: vec![[0.0; 2 * NODE]; m],
            row_link,
            psi_z: vec![0.0; m * m],
            schur: vec![0.0; m * m],
            schur_rhs: vec![0.0; m],
            rows_in: vec![0.0; m],
        };
        border.reload();
        border
    }

    /// Reads the unknowns z (current and trial) from the system's profile again, after it
    /// was changed outside Newton (a history's march).
    fn reload(&mut self) {
        if let Some(p) = &self.system.friction {
            for (j, &o) in self.offsets.iter().enumerate() {
                for n in 1..=p.spans[j] {
                    self.z[o + n - 1] = p.z[j][n];
                }
            }
        }
        self.trial_z.copy_from_slice(&self.z);
    }

    /// Writes the unknowns `z` into the system's profile and the delivered tensions into
    /// its model.
    fn load(&mut self, point: Point) {
        let z = match point {
            Point::Current => &self.z,
            Point::Trial => &self.trial_z,
        };
        let Some(profile) = self.system.friction.as_mut() else {
            return;
        };
        for (j, &o) in self.offsets.iter().enumerate() {
            let span = profile.spans[j];
            let values = &mut profile.z[j];
            values[0] = 0.0;
            for n in 1..values.len() {
                values[n] = z[o + n.min(span) - 1];
            }
        }
        profile.deliver(&mut self.system.model);
    }

    /// The bordered solve by the dense Schur complement S = psi_z - psi_x X with the columns
    /// X = J^-1 F_z: dz from S dz = -psi - psi_x a (psi: `rows_in`), left in `border_step`,
    /// and a becomes dx = a - X dz. Returns max |dz|, None when S is singular or a value is
    /// not finite.
    fn eliminate(&mut self, a: &mut [f64]) -> Option<f64> {
        let m = self.z.len();
        for r in 0..m {
            let first = self.row_link[r] * NODE;
            let row = &self.psi_x[r];
            let dot = |v: &[f64]| -> f64 { row.iter().zip(&v[first..first + 2 * NODE]).map(|(p, q)| p * q).sum() };
            for (c, column) in self.columns.iter().enumerate() {
                self.schur[r * m + c] = self.psi_z[r * m + c] - dot(column);
            }
            self.schur_rhs[r] = -self.rows_in[r] - dot(a);
        }
        if !solve_dense(&mut self.schur, &mut self.schur_rhs, m) {
            return None;
        }
        for (column, &d) in self.columns.iter().zip(&self.schur_rhs) {
            if d != 0.0 {
                for (s, c) in a.iter_mut().zip(column) {
                    *s -= c * d;
                }
            }
        }
        self.border_step.copy_from_slice(&self.schur_rhs);
        let finite = a.iter().chain(&self.schur_rhs).all(|v| v.is_finite());
        let norm = self.schur_rhs.iter().fold(0.0, |acc: f64, d| acc.max(d.abs()));
        finite.then_some(norm)
    }

    /// The derivative of the jump or tip rows at slip j's termination with respect to its
    /// log tension at its last node: the termination force is linear in the tension, so it
    /// is the rows' tendon part, the rows with the tension minus the rows without it. The
    /// first of those rows and the 6 values.
    fn termination_column(&self, j: usize, x: &[State]) -> Result<Option<(usize, [f64; 6])>> {
        let Some(profile) = self.system.friction.as_ref() else {
            return Ok(None);
        };
        let (tendon, span) = (profile.slipping[j], profile.spans[j]);
        let nodes = x.len();
        let length = self.system.model.robot.length();
        let first = if span + 1 == nodes {
            tip_row(nodes)
        } else {
            link_row(span) + 6
        };
        let on = |k: usize| self.system.model.site_on(x[k].s, self.system.mesh.nodes[k].segment_end);
        let site = on(span);
        let right = (span + 1 < nodes).then(|| on(span + 1));
        let rows = |model: &Model| -> Result<[f64; 6]> {
            let a = &x[span];
            let right = right
                .as_ref()
                .map(|site| (site, &x[span + 1].R, &x[span + 1].v, &x[span + 1].u));
            let (f, m) = model.wrench_balance(a.s, (&site, &a.R, &a.v, &a.u), right)?;
            Ok([f[0], f[1], f[2], m[0] * length, m[1] * length, m[2] * length])
        };
        let with = rows(&self.system.model)?;
        let mut without_model = self.system.model.clone();
        without_model.tensions[tendon] = 0.0;
        let without = rows(&without_model)?;
        Ok(Some((first, std::array::from_fn(|r| with[r] - without[r]))))
    }

    /// `out` = F_z v: the backbone rows' change along the log-tension change `v`.
    fn apply_columns(&self, v: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        let Some(profile) = self.system.friction.as_ref() else {
            return;
        };
        let count = self.offsets.len();
        for (k, rz) in self.link_z.iter().enumerate() {
            let Some(rz) = rz else {
                continue;
            };
            for l in 0..count {
                for (side, node) in [(0, k), (1, k + 1)] {
                    if let Some(u) = unknown(&self.offsets, &profile.spans, l, node)
                        && v[u] != 0.0
                    {
                        for r in 0..NODE {
                            out[link_row(k) + r] += rz[(r, side * count + l)] * v[u];
                        }
                    }
                }
            }
        }
        for (j, term) in self.terminations.iter().enumerate() {
            if let (Some((first, values)), Some(u)) =
                (term, unknown(&self.offsets, &profile.spans, j, profile.spans[j]))
            {
                for (r, value) in values.iter().enumerate() {
                    out[first + r] += value * v[u];
                }
            }
        }
    }

    /// Solves psi_z dz = r by forward substitution link by link (psi_z couples the log
    /// tensions of a link's two nodes only; each link is a small system over the slips on
    /// it). False for a singular link.
    fn forward(&mut self, r: &[f64], dz: &mut [f64]) -> bool {
        let Some(profile) = self.system.friction.as_ref() else {
            return true;
        };
        let m = self.z.len();
        let count = self.offsets.len();
        let last = profile.spans.iter().copied().max().unwrap_or(0);
        for k in 0..last {
            let on: Vec<usize> = (0..count).filter(|&j| profile.on_link(j, k)).collect();
            let size = on.len();
            let (matrix, rhs) = (&mut self.small_matrix, &mut self.small_rhs);
            for (a, &j) in on.iter().enumerate() {
                let row = self.offsets[j] + k;
                let mut value = r[row];
                for l in 0..count {
                    if let Some(u) = unknown(&self.offsets, &profile.spans, l, k) {
                        value -= self.psi_z[row * m + u] * dz[u];
                    }
                }
                rhs[a] = value;
                for (b, &l) in on.iter().enumerate() {
                    let u = self.offsets[l] + k;
                    matrix[a * size + b] = self.psi_z[row * m + u];
                }
            }
            if !solve_dense(&mut matrix[..size * size], &mut rhs[..size], size) {
                return false;
            }
            for (a, &l) in on.iter().enumerate() {
                dz[self.offsets[l] + k] = rhs[a];
            }
        }
        true
    }

    /// The bordered solve for the border rows `rows_in` (psi) and `a` = J^-1 (-F), with
    /// `solve` applying J^-1: dz from (psi_z - psi_x J^-1 F_z) dz = -psi - psi_x a, left in
    /// `border_step`, and a becomes dx = a - J^-1 F_z dz. Returns max |dz|, None for a
    /// singular system or a value that is not finite.
    ///
    /// The log tensions move the shape only a little (the iteration below contracts by
    /// about mu times the path's turning per pass, 0.01 to 0.1 on the prototype), so the Schur
    /// system is solved by the iteration dz <- psi_z^-1 (-psi - psi_x (a - J^-1 F_z dz)),
    /// one solve with J per pass, to rounding; where it does not contract (strong friction)
    /// the dense Schur complement is formed from one solve per unknown.
    fn bordered(&mut self, a: &mut [f64], solve: &mut dyn FnMut(&[f64], &mut [f64]) -> bool) -> Option<f64> {
        let m = self.z.len();
        let dot = |row: &[f64; 2 * NODE], first: usize, v: &[f64]| -> f64 {
            row.iter().zip(&v[first..first + 2 * NODE]).map(|(p, q)| p * q).sum()
        };
        for r in 0..m {
            self.r0[r] = -self.rows_in[r] - dot(&self.psi_x[r], self.row_link[r] * NODE, a);
        }
        let mut dz = std::mem::take(&mut self.border_step);
        let (r0, mut rr) = (std::mem::take(&mut self.r0), std::mem::take(&mut self.rr));
        let mut ok = self.forward(&r0, &mut dz);
        let mut converged = false;
        let mut last_change = f64::INFINITY;
        for _ in 0..ITERATIONS {
            if !ok {
                break;
            }
            let (mut w, mut y) = (std::mem::take(&mut self.w), std::mem::take(&mut self.y));
            self.apply_columns(&dz, &mut w);
            ok = solve(&w, &mut y);
            for r in 0..m {
                rr[r] = r0[r] + dot(&self.psi_x[r], self.row_link[r] * NODE, &y);
            }
            (self.w, self.y) = (w, y);
            let previous = dz.clone();
            ok = ok && self.forward(&rr, &mut dz);
            let size = dz.iter().fold(0.0_f64, |acc, d| acc.max(d.abs()));
            let change = dz
                .iter()
                .zip(&previous)
                .fold(0.0_f64, |acc, (p, q)| acc.max((p - q).abs()));
            // Converged to 1e-12 relative, far below what a Newton step needs to keep its
            // quadratic convergence; a change that does not halve means no contraction.
            if change <= 1e-12 * size || size == 0.0 {
                converged = true;
                break;
            }
            if change > 0.5 * last_change {
                break;
            }
            last_change = change;
        }
        (self.r0, self.rr) = (r0, rr);
        if converged {
            let mut y = std::mem::take(&mut self.y);
            let mut w = std::mem::take(&mut self.w);
            self.apply_columns(&dz, &mut w);
            let solved = solve(&w, &mut y);
            for (s, c) in a.iter_mut().zip(&y) {
                *s -= c;
            }
            (self.w, self.y) = (w, y);
            self.border_step = dz;
            let finite = solved && a.iter().chain(&self.border_step).all(|v| v.is_finite());
            let norm = self.border_step.iter().fold(0.0, |acc: f64, d| acc.max(d.abs()));
            return finite.then_some(norm);
        }
        self.border_step = dz;
        // The dense Schur complement: one column J^-1 F_z e_u per unknown.
        if !self.columns_ready {
            let mut unit = vec![0.0; m];
            let mut w = std::mem::take(&mut self.w);
            let mut columns = std::mem::take(&mut self.columns);
            for (u, column) in columns.iter_mut().enumerate() {
                unit[u] = 1.0;
                self.apply_columns(&unit, &mut w);
                unit[u] = 0.0;
                if !solve(&w, column) {
                    (self.w, self.columns) = (w, columns);
                    return None;
                }
            }
            (self.w, self.columns) = (w, columns);
            self.columns_ready = true;
        }
        self.eliminate(a)
    }
}

/// The error estimate with friction, by deferred correction as in [`estimate`] on the
/// bordered system: the order-6 residuals of the backbone and capstan rows at the
/// converged `x`, and one bordered solve with Newton's factors and columns, so that the
/// estimate carries the tension profile's error into the shape's. Returns the correction
/// and the largest correction of a log tension (the relative error of the tension
/// profile); `None` without factors or with a singular border.
///
/// # Errors
/// A model breakdown at a stage of the order-6 scheme.
fn estimate_with_friction(
    border: &mut Capstan,
    ws: &mut Workspace,
    x: &[State],
) -> Result<Option<(estimate::Correction, f64)>> {
    border.load(Point::Current);
    let n = border.system.unknowns();
    let mut phi4 = vec![0.0; n];
    border.system.residual(x, &mut phi4)?;
    border.rows(Point::Current, x);
    let system = &border.system;
    let mut rhs = vec![0.0; n];
    let mut local = vec![0.0; x.len() - 1];
    let mut node_rates = vec![nalgebra::Vector6::zeros(); x.len()];
    system.order6_residual(x, &mut rhs, &mut local, &mut node_rates)?;
    for (r, f) in rhs.iter_mut().zip(&phi4) {
        *r = f - *r;
    }
    let length = system.model.robot.length();
    let mut difference = border.psi.clone();
    if let Some(profile) = system.friction.as_ref() {
        let last = profile.spans.iter().copied().max().unwrap_or(0);
        for k in 0..last {
            let Some(sites) = system.interval_sites(k) else {
                continue;
            };
            let h = sites.end.s - sites.start.s;
            let quarters = QuarterSites {
                quarter: system.model.site(sites.start.s + 0.25 * h),
                three_quarters: system.model.site(sites.start.s + 0.75 * h),
            };
            let seg = system.mesh.nodes[k].segment_end;
            let (_, psi6, _, _) = interval_order6(profile, length, k, sites, &quarters, seg, &x[k], &x[k + 1])?;
            for (j, &o) in border.offsets.iter().enumerate() {
                if profile.on_link(j, k) {
                    difference[o + k] -= psi6[j];
                }
            }
        }
    }
    if !ws.has_factors() {
        return Ok(None);
    }
    let Some(a) = ws.solve_again(&rhs) else {
        return Ok(None);
    };
    let mut dx = a.to_vec();
    // S dz = -rows_in - psi_x a with rows_in = -(psi4 - psi6)
    for (r, d) in border.rows_in.iter_mut().zip(&difference) {
        *r = -d;
    }
    let mut solve = |rhs: &[f64], out: &mut [f64]| match ws.solve_again(rhs) {
        Some(x) => {
            out.copy_from_slice(x);
            true
        }
        None => false,
    };
    let Some(tension_error) = border.bordered(&mut dx, &mut solve) else {
        return Ok(None);
    };
    Ok(Some((
        estimate::correction(&dx, x.len(), length, local, node_rates),
        tension_error,
    )))
}

/// Solves a robot with tendons with friction (validated, with `options` validated): the
/// frictionless robot first (the standard pipeline, which also picks the first mesh), then
/// on each mesh Newton bordered by the log tensions ([`Capstan`]) from the last mesh's
/// solution (the frictionless one and constant tensions on the first), its error estimate
/// ([`estimate_with_friction`]) and, with a tolerance, re-meshing until the tip's estimate
/// and the tension profile's (relative, against the same tolerance as the rotation) meet it.
///
/// # Errors
/// As [`super::solve`].
pub(super) fn solve(robot: &Robot, options: &Options, warm: Option<&Solution>, cache: &mut Cache) -> Result<Solution> {
    let start = Instant::now();
    let mut smooth = robot.clone();
    for t in &mut smooth.tendons {
        t.friction = None;
    }
    let first = pipeline::solve_impl(&smooth, options, warm, cache)?;
    let points: Vec<f64> = first.nodes.iter().map(|n| n.s).collect();
    let mut mesh = Mesh::from_points(robot, &points)?;
    let mut x = interpolate(&Model::new(robot), &first, &mesh);
    // The counts and timings of the frictionless solve are part of this one.
    let mut report = first.report.clone();
    let settings = Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let model = Model::new(robot);
    let length = robot.length();
    // The last mesh's node arc lengths and log tensions, interpolated onto the next.
    let mut previous: Option<(Vec<f64>, Vec<Vec<f64>>)> = None;
    loop {
        report.meshes += 1;
        let mut system = System::new(model.clone(), mesh);
        let mut profile = Profile::new(&model, &system.mesh);
        if let Some((s, z)) = &previous {
            for (zj, old) in profile.z.iter_mut().zip(z) {
                for (value, node) in zj.iter_mut().zip(&system.mesh.nodes) {
                    *value = linear(s, old, node.s);
                }
            }
        }
        system.friction = Some(profile);
        let mut ws = Workspace::new(&system, options.linear_solver)?;
        let mut border = Capstan::new(system);
        let (termination, worst) = newton::run_bordered(&mut border, &mut ws, &mut x, &settings, &mut report);
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
                hint: "friction is solved from the frictionless shape: lower the friction coefficient, or solve \
                       with the shooting solver to compare"
                    .into(),
            });
        }
        let t = Instant::now();
        let estimated = estimate_with_friction(&mut border, &mut ws, &x).ok().flatten();
        report.timings.estimate += t.elapsed();
        border.load(Point::Current);
        let system = border.system;
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
        let Some(fine) = next else {
            pipeline::record_estimate(&mut report, estimated.as_ref().map(|(c, _)| c), options, length);
            report.stability = Stability::Unknown {
                reason: "friction is not conservative".into(),
            };
            report.timings.total = start.elapsed();
            return nodes::solution_with_tensions(&model, &x, &ends, &tensions, None, report);
        };
        let guess = nodes::solution_with_tensions(&model, &x, &ends, &tensions, None, report.clone())?;
        let s: Vec<f64> = system.mesh.nodes.iter().map(|n| n.s).collect();
        previous = Some((s, profile.z.clone()));
        x = interpolate(&model, &guess, &fine);
        mesh = fine;
    }
}

/// The value at `s` of the piecewise-linear interpolant through (`points`, `values`)
/// (clamped at the ends; at a repeated point, the first).
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
