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
//! the tension. The whole matrix, reordered node by node, is factored as one staircase
//! ([`staircase`]; the blocks handed to it in `border.rs`), in the Newton loop of
//! displacement-controlled tendons ([`newton::run_bordered`]). The solve starts from the
//! initial guess ([`direct`]) or the frictionless solution on its mesh, moved to the
//! capstan start ([`start`]), mesh by mesh ([`meshes`]); where Newton fails from there, the
//! friction coefficients are followed from 0 ([`continuation`]).
#![allow(non_snake_case)]

mod border;
mod continuation;
mod correction;
mod direct;
mod fold;
mod grip;
mod group;
pub(crate) mod history;
mod interval;
mod kinks;
mod linearized;
mod meshes;
mod order6;
mod order6_lanes;
mod profile;
mod pull_ins;
mod refusal;
mod staircase;
mod start;
mod stuck_links;
mod turning;

pub use grip::Contact;
pub(crate) use grip::Grip;
pub(crate) use group::intervals4;
pub(crate) use interval::{IntervalLinearization, Profile, interval};
pub(crate) use linearized::Kept;
pub(crate) use order6::{Order6, interval_order6};
pub(crate) use order6_lanes::intervals4_order6;
pub(in crate::collocation) use pull_ins::solve_pull_ins;

use super::equilibrium::CLEAN_ITERATIONS;
use super::newton::{self, Border, Linearization, Point, Settings, Workspace};
use super::system::System;
use super::unknowns::{self, NODE, link_row, tip_row};
use super::{Cache, Options, pipeline, refine, workspace};
use crate::dense::solve_dense;
use crate::error::{self, Result};
use crate::mesh::guess::interpolate;
use crate::mesh::{Mesh, nodes};
use crate::model::equations::Model;
use crate::report::{Method, SolveReport, Stability, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Robot};
use correction::estimate_with_friction;
use meshes::{Route, refine_with_friction};
use staircase::Staircase;
use std::time::Instant;

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
    /// F_z by link: the 12 x 2k derivative of its backbone rows in the log tensions of its
    /// two nodes (None for jumps and links past every span).
    link_z: Vec<Option<nalgebra::DMatrix<f64>>>,
    /// Per slip, the termination rows' derivative in its last log tension: the first row
    /// and the values.
    terminations: Vec<Option<(usize, [f64; 6])>>,
    /// The step dz of the last bordered solve.
    border_step: Vec<f64>,
    /// Work vectors: the backbone rows' right-hand side, a small system per link (the
    /// forward substitution of psi_z).
    rhs_x: Vec<f64>,
    small_matrix: Vec<f64>,
    small_rhs: Vec<f64>,
    /// psi_x: each row's 24 entries over the unknowns of its link's two nodes.
    psi_x: Vec<[f64; 2 * NODE]>,
    /// psi_z by row: row r's derivatives in the log tensions of its link's two nodes, slip
    /// l's at node k at `r * 2c + l` and at node k + 1 at `r * 2c + c + l` (c slips; psi_z
    /// has no other entries). 0 where that log tension is no unknown (the base).
    psi_z: Vec<f64>,
    /// The border rows of the solve in hand (psi, or the estimate's difference).
    rows_in: Vec<f64>,
    /// The slips with a log-tension unknown at each node, in order.
    node_slips: Vec<Vec<usize>>,
    /// The factors of the bordered matrix reordered node by node ([`Staircase`]).
    stairs: Staircase,
    /// The residual and Jacobian buffers of [`Capstan::factor_at`], kept for a later
    /// border ([`Capstan::into_kept`]).
    at_buffers: (Vec<f64>, Vec<f64>),
}

impl<'r> Capstan<'r> {
    /// The border of `system`'s tendons with friction (its profile's log tensions and, in a
    /// history, contacts), unfactored.
    pub(crate) fn new(system: System<'r>) -> Self {
        Self::with_kept(system, Kept::default())
    }

    /// [`Capstan::new`] in the buffers an earlier border left ([`Capstan::into_kept`]): its
    /// staircase where it has this mesh's shape ([`Staircase::fits`]; not factored), and
    /// the buffers of [`Capstan::factor_at`].
    pub(crate) fn with_kept(system: System<'r>, kept: Kept) -> Self {
        let profile = system.friction.as_ref().map_or_else(Vec::new, |p| p.spans.clone());
        let mut offsets = Vec::with_capacity(profile.len());
        let mut m = 0;
        for &span in &profile {
            offsets.push(m);
            m += span;
        }
        let n = system.unknowns();
        let nodes = system.mesh.nodes.len();
        let links = nodes - 1;
        let node_slips: Vec<Vec<usize>> = (0..nodes)
            .map(|n| (0..profile.len()).filter(|&j| (1..=profile[j]).contains(&n)).collect())
            .collect();
        let extra: Vec<usize> = node_slips.iter().map(Vec::len).collect();
        let frictionless = system.friction.is_none();
        let mut border = Capstan {
            system,
            offsets,
            z: vec![0.0; m],
            trial_z: vec![0.0; m],
            dz: vec![0.0; m],
            simplified: vec![0.0; m],
            psi: vec![0.0; m],
            trial_psi: vec![0.0; m],
            link_z: vec![None; links],
            terminations: vec![None; profile.len()],
            border_step: vec![0.0; m],
            // Only the bordered Newton step reads it, which runs on systems with a profile.
            rhs_x: vec![0.0; if frictionless { 0 } else { n }],
            small_matrix: vec![0.0; profile.len() * profile.len()],
            small_rhs: vec![0.0; profile.len()],
            psi_x: vec![[0.0; 2 * NODE]; m],
            psi_z: vec![0.0; m * 2 * profile.len()],
            rows_in: vec![0.0; m],
            // Without friction nothing factors the bordered matrix (`Capstan::factor` returns
            // at once without a profile, and a staircase never factored solves nothing): an
            // empty one, which allocates nothing, not one step per node.
            stairs: match kept.stairs {
                _ if frictionless => Staircase::default(),
                Some(mut stairs) if stairs.fits(&extra) => {
                    stairs.ready = false;
                    stairs
                }
                _ => Staircase::new(&extra),
            },
            node_slips,
            at_buffers: kept.at_buffers,
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

    /// Solves psi_z dz = r by forward substitution link by link (psi_z couples the log
    /// tensions of a link's two nodes only; each link is a small system over the slips on
    /// it). False for a singular link.
    fn forward(&mut self, r: &[f64], dz: &mut [f64]) -> bool {
        let Some(profile) = self.system.friction.as_ref() else {
            return true;
        };
        let count = self.offsets.len();
        let last = profile.spans.iter().copied().max().unwrap_or(0);
        for k in 0..last {
            let on: Vec<usize> = (0..count).filter(|&j| profile.on_link(j, k)).collect();
            let size = on.len();
            let (matrix, rhs) = (&mut self.small_matrix, &mut self.small_rhs);
            for (a, &j) in on.iter().enumerate() {
                let row = self.offsets[j] + k;
                let psi_z = &self.psi_z[row * 2 * count..(row + 1) * 2 * count];
                let mut value = r[row];
                for (l, d) in psi_z[..count].iter().enumerate() {
                    if let Some(u) = unknown(&self.offsets, &profile.spans, l, k) {
                        value -= d * dz[u];
                    }
                }
                rhs[a] = value;
                // Node k + 1's log tension of slip l (on link k: an unknown).
                for (b, &l) in on.iter().enumerate() {
                    matrix[a * size + b] = psi_z[count + l];
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
}

/// Solves a robot with tendons with friction (validated, with `options` validated): Newton
/// with friction from the initial guess moved to the capstan start ([`direct`]), where
/// that route applies and its answer stands; else the frictionless robot first
/// ([`pipeline::solve_start`]: its equilibrium choice on the first mesh, which also picks
/// the mesh to start on), then [`refine_with_friction`] from its states and constant
/// tensions, with the verdict of its linearized dynamics.
///
/// # Errors
/// As [`super::solve`].
pub(super) fn solve(robot: &Robot, options: &Options, warm: Option<&Solution>, cache: &mut Cache) -> Result<Solution> {
    solve_assessed(robot, options, warm, cache, true)
}

/// [`solve`], with the verdict of the linearized dynamics when `assess` (else `unknown`:
/// the held pull-ins' loop, whose verdict is not this solve's).
///
/// With a verdict, a cold start and the load path's choice, the direct route runs first
/// ([`direct::solve`]: Newton with friction from the guess, no frictionless Newton) unless
/// its first mesh is expected to be refined ([`direct::first_mesh`]); its answer stands
/// when Newton went straight to it and its verdict is `stable` (docs/friction.md section
/// 3, "Which start"). Otherwise (not `stable`, or a Newton with friction that failed) the
/// whole solve runs from the full choice on the frictionless robot, and the report counts
/// both (but for a failed first run whose error carries no report, whose work is then not
/// counted).
///
/// Where the direct route does not run (a warm start; `nearest` or no continuation, whose
/// frictionless choice takes Newton's answer without a verdict; a first mesh expected to
/// be refined), the frictionless start's equilibrium choice accepts a direct answer
/// without its own verdict ([`pipeline::solve_start`] `unassessed`) when the solve has one:
/// the answer with friction built on it stands when its verdict is `stable`, else the full
/// choice runs, as above.
///
/// # Errors
/// As [`super::solve`].
fn solve_assessed(
    robot: &Robot,
    options: &Options,
    warm: Option<&Solution>,
    cache: &mut Cache,
    assess: bool,
) -> Result<Solution> {
    let start = Instant::now();
    let mut smooth = robot.clone();
    for t in &mut smooth.tendons {
        t.friction = None;
    }
    let from_guess = if direct::applies(options, warm, assess) {
        direct::first_mesh(&smooth, options)?
    } else {
        None
    };
    let provisional = if let Some(from) = from_guess {
        direct::solve(robot, options, from, start)
    } else {
        let first = pipeline::solve_start(&smooth, options, warm, cache, assess)?;
        let provisional = first.provisional;
        let answer = from_start(robot, options, first, cache, assess, start);
        if !provisional {
            return answer;
        }
        answer
    };
    // The work of the provisional route, which the report of the full one counts.
    let tried = match provisional {
        Ok(solution) if solution.report.stability.is_stable() => return Ok(solution),
        Ok(solution) => Some(solution.report),
        Err(Error::NotConverged { report, .. }) => Some(*report),
        Err(_) => None,
    };
    let mut first = pipeline::solve_start(&smooth, options, warm, cache, false)?;
    if let Some(tried) = tried {
        first.report.add_work(&tried);
    }
    from_start(robot, options, first, cache, assess, start)
}

/// [`refine_with_friction`] from the frictionless start `first`, whose cached Newton
/// workspace (on the mesh Newton with friction starts on when the first mesh is kept) goes
/// to the thread's spare workspaces, where that Newton takes it.
///
/// # Errors
/// As [`super::solve`].
fn from_start(
    robot: &Robot,
    options: &Options,
    first: pipeline::Start,
    cache: &mut Cache,
    assess: bool,
    start: Instant,
) -> Result<Solution> {
    if let Some(c) = cache.take() {
        workspace::keep(c.mesh, c.solver, c.workspace);
    }
    // The counts and timings of the frictionless solve are part of this one.
    refine_with_friction(
        robot,
        options,
        (first.mesh, first.x),
        None,
        (first.report, assess),
        start,
        Route::Frictionless,
    )
}

/// Newton's settings of a friction solve from `options`: their residual tolerance and
/// iteration cap, a fresh Jacobian for each step's start (no factors carried in), and no
/// stop on damping.
fn fresh_settings(options: &Options) -> Settings {
    Settings {
        tolerance: options.residual_tolerance,
        max_iterations: options.max_iterations,
        reuse_factors: false,
        stop_when_damped: false,
    }
}
