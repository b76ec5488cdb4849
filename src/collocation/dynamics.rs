//! Stability from the linearized dynamics (docs/stability.md, "Loads that are not
//! conservative"): the rightmost eigenvalues of the rod's small vibrations about an
//! equilibrium, for loads the conjugate-point test does not cover (dead moments in 3D,
//! follower loads).
//!
//! With the inertia of the rod the equilibrium equations gain the distributed loads
//! -rho A p_tt (force, world frame) and -rho R J_b w_t (moment; w the body angular
//! velocity), so that the collocation residual F(x) becomes F(x) + M x_tt = 0 for small
//! motions about an equilibrium x*, M = dF/d(distributed load) * d(load)/d(x_tt). With J the
//! collocation Jacobian at x*, the modes x = phi e^(lambda t) solve
//!
//! ```text
//! J phi = mu M phi,   mu = -lambda^2,   lambda = +- sqrt(-mu).
//! ```
//!
//! A real positive mu is a vibration (lambda imaginary); a real negative mu a mode that grows
//! without oscillating (divergence, rate sqrt(-mu)); a complex mu a growing oscillation
//! (flutter, rate Re sqrt(-mu)). The modes that decide are those of least |mu| (the lowest
//! frequencies): shift-invert at 0, Arnoldi on J^-1 M with the factors of J that Newton
//! stored, gives them first.
//!
//! The mass: mass per length rho A and rotary inertia rho diag(Ixx, Iyy, Ixx + Iyy) of a
//! homogeneous rod, taken from the section's stiffness as (rho / E) EA and (rho / E) E I,
//! with rho = [`DENSITY`] and E the rod's Young's modulus (or [`MODULUS`] when the rod was
//! given by stiffnesses). A uniform change of rho scales every mu alike: the verdict does not
//! depend on it, only the growth rate does (as 1 / sqrt(rho)).

#![allow(non_snake_case)]

mod arnoldi;
pub(crate) mod friction;
mod hessenberg;
pub(crate) mod pulled;
#[cfg(test)]
mod simulate;
pub(crate) mod stuck;

use super::newton::Workspace;
use super::residual::{IntervalFactors, end_values};
use super::sensitivity::Sensitivity;
use super::system::System;
use super::unknowns::{BASE_COLUMNS, BASE_ROWS, NODE, P, THETA, U, V, link_row, unknowns};
use crate::model::equations::{Model, Site};
use crate::model::linearize;
use crate::report::{Growth, Stability};
use crate::simd::avx2_fma;
use crate::so3;
use crate::solution::State;
use crate::{Robot, Solution};
use arnoldi::{Ritz, arnoldi};
use nalgebra::{Complex, Matrix3, SMatrix, Vector3, Vector6};
use std::ops::AddAssign;

/// The density the mass is taken from (kg/m^3): stainless steel, the usual backbone. Only
/// the growth rate depends on it.
pub const DENSITY: f64 = 7850.0;
/// Young's modulus (Pa) that turns stiffness into cross-section geometry when the rod was
/// given by stiffnesses alone (steel's, to go with [`DENSITY`]).
pub const MODULUS: f64 = 200e9;
/// Krylov dimension of a solve's verdict: the most Arnoldi steps (solves with the stored
/// factors) it takes, unless its modes settle sooner ([`arnoldi`]). The decisive modes are the lowest few, which shift-invert at 0 makes
/// the dominant ones; 16 resolve the lowest 2-4 (12 leave Beck's flutter pair unconverged).
const KRYLOV: usize = 16;
/// Krylov dimension of [`vibration`], which reports the lowest modes' eigenvalues: 24
/// resolve the lowest 6-10 to rounding.
pub(super) const KRYLOV_MODES: usize = 24;
/// A Ritz value counts as converged when its residual estimate is below this fraction of
/// its magnitude.
const CONVERGED: f64 = 1e-6;
/// mu with |Im mu| above this fraction of |mu| is complex (flutter); Arnoldi's rounding on
/// these non-normal pencils leaves 1e-10 and less on real ones.
const COMPLEX: f64 = 1e-6;
/// mu with Re mu below -this fraction of 1e9 times the lowest mode's |mu| (about the
/// stiffest retained modes, axial and torsional, 1e8-1e10 times the lowest bending ones) is
/// negative (divergence); smaller ones are a neutral direction (a zero of the continuum,
/// moved by rounding).
const NEUTRAL: f64 = 1e-13;

/// The 6 x 12 mass block of each interval (None for a jump): rows (v', u') of the link's
/// residual (u' rows scaled by L, as the residual), columns (p, theta) of node k then node
/// k + 1 (scaled unknowns: p columns act on dp / L).
pub(crate) struct Mass {
    blocks: Vec<Option<SMatrix<f64, 6, 12>>>,
}

impl Mass {
    /// The mass of `system` linearized at the equilibrium `x` (node states); `kept`, when
    /// given, holds eq. 13's factored matrices at every interval's points of the Jacobian at
    /// `x` ([`Workspace::linearize_keeping`]), which spare evaluating eq. 13 there again.
    ///
    /// # Errors
    /// A model breakdown at a collocation point.
    pub(crate) fn new(system: &System, x: &[State], kept: Option<&[IntervalFactors]>) -> crate::Result<Self> {
        let model = &system.model;
        let length = model.robot.length();
        let ratio = DENSITY / model.robot.rod.geometry.map_or(MODULUS, |g| g.youngs_modulus);
        let links = x.len() - 1;
        let mut blocks: Vec<Option<SMatrix<f64, 6, 12>>> = Vec::with_capacity(links);
        // Eq. 13's rates at a point and its response to a unit acceleration ([`response`]),
        // written in place: at the start, midpoint and end of the interval.
        let point = |site: &Site, seg: f64, state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>), z: &mut _| {
            response(model, site, seg, state, ratio, length, z)
        };
        // The response from M factored at the point by the Jacobian ([`response_kept`]).
        let from = |site: &Site, factored: &linearize::Factored, Rc: &Matrix3<f64>, z: &mut _| {
            response_kept(site, factored, Rc, ratio, length, z)
        };
        let (mut za, mut zm, mut zb) = (SMatrix::<f64, 6, 6>::zeros(), SMatrix::zeros(), SMatrix::zeros());
        let (mut ra, mut rb) = (Vector6::zeros(), Vector6::zeros());
        // The node whose rates and response the last interval left in (rb, zb), with its
        // segment: the next interval's start when the two share the node's site and segment
        // (the same inputs, the same values).
        let mut carried: Option<(usize, f64)> = None;
        for k in 0..links {
            let Some(sites) = system.interval_sites(k) else {
                carried = None;
                blocks.push(None);
                continue;
            };
            let seg = system.mesh.nodes[k].segment_end;
            let (a, b) = (&x[k], &x[k + 1]);
            let h = sites.end.s - sites.start.s;
            let shared = matches!(carried.take(), Some((node, s)) if node == k && s == seg);
            if shared {
                std::mem::swap(&mut za, &mut zb);
                std::mem::swap(&mut ra, &mut rb);
            }
            if let Some(kept) = kept {
                let kept = &kept[k];
                if !shared {
                    from(&sites.start, &kept.start, &a.R, &mut za)?;
                }
                from(&sites.end, &kept.end, &b.R, &mut zb)?;
                from(&sites.mid, &kept.mid, &kept.mid_R, &mut zm)?;
            } else {
                if !shared {
                    ra = point(&sites.start, seg, (&a.R, &a.v, &a.u), &mut za)?;
                }
                rb = point(&sites.end, seg, (&b.R, &b.v, &b.u), &mut zb)?;
                // The Hermite-Simpson midpoint, as the residual's.
                let [y0, y1, f0, f1] = end_values(sites, a, b, &ra, &rb);
                let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
                let part = |at: usize| Vector3::new(ym[at], ym[at + 1], ym[at + 2]);
                let Rm = a.R * so3::exp(&part(THETA));
                let (vm, um) = (part(V), part(U));
                point(&sites.mid, seg, (&Rm, &vm, &um), &mut zm)?;
            }
            let mut block = quadrature(h, (&a.R, &b.R), [&za, &zm, &zb]);
            for r in 3..6 {
                for c in 0..12 {
                    block[(r, c)] *= length;
                }
            }
            blocks.push(Some(block));
            carried = Some((k + 1, seg));
        }
        Ok(Mass { blocks })
    }

    /// Adds `scale` times M to the Jacobian `values`, stored in
    /// [`pattern`](super::unknowns::pattern) order: each block lies in its link's (v', u') rows and
    /// the (p, theta) columns of the link's two nodes (the matrix J + M / dt of an implicit step
    /// of the damped motion, module `relax`).
    pub(crate) fn add_to(&self, values: &mut [f64], scale: f64) {
        // The link blocks follow the base block, each 12 rows of 24 columns, row major.
        let first = BASE_ROWS * BASE_COLUMNS;
        for (k, block) in self.blocks.iter().enumerate() {
            let Some(block) = block else { continue };
            let link = first + k * NODE * 2 * NODE;
            for r in 0..6 {
                let row = link + (V + r) * 2 * NODE;
                for j in 0..3 {
                    values[row + P + j] += scale * block[(r, j)];
                    values[row + THETA + j] += scale * block[(r, 3 + j)];
                    values[row + NODE + P + j] += scale * block[(r, 6 + j)];
                    values[row + NODE + THETA + j] += scale * block[(r, 9 + j)];
                }
            }
        }
    }

    /// y = M x for scaled unknowns x given by their (p, theta) part `z` alone (M reads no
    /// other column): [`MOVING`] per node, p then theta, as [`restrict`] gives them. Writes
    /// only the rows M has, the (v', u') rows of each interval; `y` must be zero elsewhere
    /// (as [`modes`]'s buffer, zeroed once, stays). Always inlined, so that a caller compiled
    /// for AVX2 (`friction::CapstanMass::apply`) compiles it so too.
    #[inline(always)]
    fn apply(&self, z: &[f64], y: &mut [f64]) {
        for (k, block) in self.blocks.iter().enumerate() {
            let Some(block) = block else { continue };
            // Node k's and node k + 1's (p, theta): the block's 12 columns, in order.
            let z = &z[k * MOVING..(k + 2) * MOVING];
            let mut sums = [0.0; 6];
            for (c, zc) in z.iter().enumerate() {
                for (r, sum) in sums.iter_mut().enumerate() {
                    *sum += block[(r, c)] * zc;
                }
            }
            let row = link_row(k) + V;
            y[row..row + 6].copy_from_slice(&sums);
        }
    }
}

/// The mass of an interval's rows from their responses `z` (ROWS rows, one column per
/// acceleration component at a point) at its start, midpoint and end ([`response`]):
/// Simpson's weights h/6 (1, 4, 1), with the accelerations interpolated linearly between the
/// nodes (weights of node a, node b) and a node's rotation increment acting through its `R`;
/// columns (p, theta) of node a then node b. On x86-64 with AVX2 and FMA (checked at run
/// time) compiled for them: the same operations in the same order, so the same bits.
fn quadrature<const ROWS: usize>(
    h: f64,
    R: (&Matrix3<f64>, &Matrix3<f64>),
    z: [&SMatrix<f64, ROWS, 6>; 3],
) -> SMatrix<f64, ROWS, 12> {
    avx2_fma!(quadrature_kernel(h, R, z))
}

/// [`quadrature`]'s operations.
#[inline(always)]
fn quadrature_kernel<const ROWS: usize>(
    h: f64,
    (Ra, Rb): (&Matrix3<f64>, &Matrix3<f64>),
    z: [&SMatrix<f64, ROWS, 6>; 3],
) -> SMatrix<f64, ROWS, 12> {
    let mut block = SMatrix::<f64, ROWS, 12>::zeros();
    for (z, weight, (wa, wb)) in [
        (z[0], 1.0, (1.0, 0.0)),
        (z[1], 4.0, (0.5, 0.5)),
        (z[2], 1.0, (0.0, 1.0)),
    ] {
        let z = z * (h / 6.0 * weight);
        let (force, moment) = (z.fixed_columns::<3>(0), z.fixed_columns::<3>(3));
        for (column, w, R) in [(0, wa, Ra), (6, wb, Rb)] {
            if w != 0.0 {
                let mut node = block.fixed_columns_mut::<6>(column);
                node.fixed_columns_mut::<3>(0).add_assign(force * w);
                node.fixed_columns_mut::<3>(3).add_assign(moment * *R * w);
            }
        }
    }
    block
}

/// Unknowns per node that carry mass: p and theta (the inertia loads depend on their
/// accelerations alone).
const MOVING: usize = 6;

/// E a in place: the (p, theta) part of every node of the scaled unknowns `a`, [`MOVING`]
/// per node, moved to the front and the rest dropped. The nonzero eigenvalues of J^-1 M
/// (= J^-1 M_r E, M_r the columns M reads) are those of E J^-1 M_r, whose vectors are half
/// as long (docs/stability.md, "How it is computed").
fn restrict(a: &mut Vec<f64>) {
    const _: () = assert!(P == 0 && THETA == 3 && MOVING == 6);
    let nodes = a.len() / NODE;
    for k in 0..nodes {
        a.copy_within(k * NODE..k * NODE + MOVING, k * MOVING);
    }
    a.truncate(nodes * MOVING);
}

/// [`restrict`] of `a` into `out` (its (p, theta) parts, [`MOVING`] per node), without
/// copying `a` whole first.
fn restricted(a: &[f64], out: &mut Vec<f64>) {
    out.resize(a.len() / NODE * MOVING, 0.0);
    for (to, node) in out.chunks_exact_mut(MOVING).zip(a.chunks_exact(NODE)) {
        to.copy_from_slice(&node[..MOVING]);
    }
}

/// The rates (v', u') of eq. 13 at a collocation point with state (Rc, v, u), and
/// d(v', u') / d(acceleration) there into `z`, up to the quadrature weight: M^-1 of the
/// load per unit acceleration ([`inertia_load_transposed`]) (eq. 13: F = M x - rhs with
/// the terms R^T f_e and R^T l_e in F, so d(v', u') / d(body load) = -M^-1, and the
/// residual y1 - y0 - h/6 sum w F gains h/6 w M^-1 load).
///
/// # Errors
/// A model breakdown at the point (the 6 x 6 matrix of eq. 13 singular there).
fn response(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (Rc, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    ratio: f64,
    length: f64,
    z: &mut SMatrix<f64, 6, 6>,
) -> crate::Result<Vector6<f64>> {
    let mut t = inertia_load_transposed(site, Rc, ratio, length);
    let rates = linearize::rates_and_solve(model, site, segment_end, (Rc, v, u), &mut t)?;
    transpose_into(&t, z);
    Ok(rates)
}

/// [`response`] without the rates, from M factored at the point already (by the Jacobian at
/// the same state, [`linearize_keeping`](crate::model::linearize::linearize_keeping)): the
/// same solve of the same load, the same bits.
///
/// # Errors
/// M singular at the point.
fn response_kept(
    site: &Site,
    factored: &linearize::Factored,
    Rc: &Matrix3<f64>,
    ratio: f64,
    length: f64,
    z: &mut SMatrix<f64, 6, 6>,
) -> crate::Result<()> {
    let mut t = inertia_load_transposed(site, Rc, ratio, length);
    if !factored.solve_rows(&mut t) {
        return Err(crate::Error::Breakdown {
            s: site.s,
            what: "the 6x6 matrix [D + A, G; B, C + H] of eq. 13 is singular".into(),
        });
    }
    transpose_into(&t, z);
    Ok(())
}

/// `z` = `t` transposed, entry by entry: nalgebra's transpose goes through an iterator
/// constructor that the build does not always inline (docs/stability.md, "Cost").
fn transpose_into(t: &SMatrix<f64, 6, 6>, z: &mut SMatrix<f64, 6, 6>) {
    for i in 0..6 {
        for j in 0..6 {
            z[(i, j)] = t[(j, i)];
        }
    }
}

/// The transpose of the body-frame distributed load (force, moment; N/m and N m/m) per
/// unit acceleration at a collocation point with orientation `Rc`: -(rho A Rc^T p_tt,
/// rho J_b Rc^T w_t) for p_tt in the p columns' scaled units (dp / L) and w_t in the world
/// frame; a node's rotation increment's w_t is its R times the body-frame one, with the
/// accelerations interpolated linearly between the nodes ([`Mass::new`]). Row i of the
/// result is the load of acceleration component i.
pub(crate) fn inertia_load_transposed(site: &Site, Rc: &Matrix3<f64>, ratio: f64, length: f64) -> SMatrix<f64, 6, 6> {
    let section = &site.section.section;
    let rho_a = ratio * section.kse[2];
    let rho_j = [
        ratio * section.kbt[0],
        ratio * section.kbt[1],
        ratio * (section.kbt[0] + section.kbt[1]),
    ];
    let mut t = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            t[(i, j)] = Rc[(i, j)] * (-rho_a * length);
            t[(3 + i, 3 + j)] = -rho_j[j] * Rc[(i, j)];
        }
    }
    t
}

/// The vibration modes of an equilibrium: the verdict of its linearized dynamics and the
/// eigenvalues it rests on ([`vibration`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Vibration {
    /// [`Stability::Stable`], [`Stability::Growing`], or [`Stability::Unknown`] when the
    /// lowest modes did not converge.
    pub stability: Stability,
    /// The converged eigenvalues mu = -lambda^2 (1/s^2) of the lowest modes, by increasing
    /// |mu| (of a complex pair, the one with the negative imaginary part first): omega^2 of
    /// a vibration at omega rad/s when real and positive.
    pub eigenvalues: Vec<Complex<f64>>,
}

/// The linearized dynamics of `robot` about its equilibrium `solution` (a collocation
/// solution of this robot): the verdict and the lowest modes' eigenvalues, for any loads
/// (conservative ones included, where the verdict agrees with the conjugate-point test of
/// [`SolveReport::stability`](crate::SolveReport::stability)); docs/stability.md.
///
/// # Errors
/// As [`crate::collocation::sensitivity::Sensitivity::new`]: an invalid robot, a solution that
/// does not solve its collocation system, a singular Jacobian. With tendons with friction,
/// the dynamics of full slip in each tendon's motion about the solution's tension profile
/// (docs/stability.md, "Tendons with friction"; a load-history step's stuck stretches are
/// not read from a solution, its report carries the step's verdict).
pub fn vibration(robot: &Robot, solution: &Solution) -> crate::Result<Vibration> {
    if crate::model::friction::any(robot) {
        // The bordered dynamics of full slip in each tendon's motion ([`friction`]), on the
        // solution's tension profile.
        let (mut border, states, ws) = Sensitivity::new(robot, solution)?.into_border();
        if !border.factor_from(&ws) {
            return Err(super::sensitivity::singular());
        }
        return Ok(friction::modes(&mut border, &states, KRYLOV_MODES, true));
    }
    let (system, states, mut ws) = Sensitivity::new(robot, solution)?.into_parts();
    Ok(modes(
        &system,
        &states,
        &mut ws,
        KRYLOV_MODES,
        true,
        &mut |_| true,
        false,
    ))
}

/// The verdict of the linearized dynamics at the equilibrium `x` of `system`, with the
/// factors of its Jacobian at `x` held in `ws`; `kept` when they come from
/// [`Workspace::linearize_keeping`] at `x`, whose factored matrices of eq. 13 the mass takes.
pub(crate) fn assess(system: &System, x: &[State], ws: &mut Workspace, kept: bool) -> Stability {
    modes(system, x, ws, KRYLOV, false, &mut |_| true, kept).stability
}

/// The mu (1/s^2) of the lowest vibration mode at the equilibrium `x` of `system` (the
/// converged one of least |mu|), with the factors of its Jacobian at `x` held in `ws`; None
/// when that mode did not converge or a solve failed. Module `neutral` reads its sign where
/// the conjugate-point test leaves a root in the neutral zone at the base.
pub(crate) fn lowest(system: &System, x: &[State], ws: &mut Workspace) -> Option<Complex<f64>> {
    modes(system, x, ws, KRYLOV, false, &mut |_| true, false)
        .eigenvalues
        .first()
        .copied()
}

/// The rod's bending scale EI / (rho A L^4) (1/s^2) at its base, with the mass of [`Mass`]:
/// omega^2 of its lowest bending modes is of this order (a clamped-free rod's first is 12.4
/// times it), and a uniform change of the density scales it as every mu.
pub(crate) fn bending_scale(system: &System) -> f64 {
    let robot = system.model.robot;
    let section = robot.rod.section_at(0.0).section;
    let ratio = DENSITY / robot.rod.geometry.map_or(MODULUS, |g| g.youngs_modulus);
    section.kbt[0].min(section.kbt[1]) / (ratio * section.kse[2] * robot.length().powi(4))
}

/// [`assess`] for a system bordered by massless unknowns (the tensions of
/// displacement-controlled tendons, `collocation/constrained.rs`): `border` turns each solve
/// a = J^-1 M z into the bordered solve's x part (for the tendons, a - X A^-1 G a), false
/// when it cannot.
pub(crate) fn assess_bordered(
    system: &System,
    x: &[State],
    ws: &mut Workspace,
    border: &mut dyn FnMut(&mut [f64]) -> bool,
) -> Stability {
    modes(system, x, ws, KRYLOV, false, border, false).stability
}

/// [`assess`] with the eigenvalues, from `krylov` Arnoldi steps when `all` (with the
/// residual of every Ritz value), else from at most `krylov`, stopped once the modes the
/// verdict rests on have settled ([`arnoldi`]); `border` as in [`assess_bordered`], `kept`
/// as in [`assess`].
fn modes(
    system: &System,
    x: &[State],
    ws: &mut Workspace,
    krylov: usize,
    all: bool,
    border: &mut dyn FnMut(&mut [f64]) -> bool,
    kept: bool,
) -> Vibration {
    let unknown = |reason: String| Vibration {
        stability: Stability::Unknown { reason },
        eigenvalues: Vec::new(),
    };
    let mass = match Mass::new(system, x, kept.then(|| ws.kept())) {
        Ok(m) => m,
        Err(e) => return unknown(format!("the mass matrix could not be formed: {e}")),
    };
    let n = unknowns(x.len());
    // Zero outside the rows [`Mass::apply`] writes, which it leaves as they are.
    let mut w = vec![0.0; n];
    // z -> E J^-1 M z on the (p, theta) parts z ([`restrict`]; M reads nothing else).
    let mut operator = |z: &[f64], out: &mut Vec<f64>| -> bool {
        mass.apply(z, &mut w);
        match ws.solve_again(&w) {
            Some(y) => {
                out.clear();
                out.extend_from_slice(y);
                let bordered = border(out);
                restrict(out);
                bordered
            }
            None => false,
        }
    };
    spectrum(&mut operator, x.len(), krylov, all)
}

/// The verdict and eigenvalues from `krylov` Arnoldi steps (at most, unless `all`) on
/// `operator`, z -> E J^-1 M z on the (p, theta) parts of the unknowns of `nodes` nodes.
fn spectrum(
    operator: &mut impl FnMut(&[f64], &mut Vec<f64>) -> bool,
    nodes: usize,
    krylov: usize,
    all: bool,
) -> Vibration {
    let Some(ritz) = arnoldi(operator, nodes * MOVING, krylov, all) else {
        return Vibration {
            stability: Stability::Unknown {
                reason: "the Jacobian's factors gave no finite solve for the vibration modes".into(),
            },
            eigenvalues: Vec::new(),
        };
    };
    classify(&ritz)
}

/// Whether the mode of the Ritz value `theta` (= 1 / mu) grows: mu complex (flutter) or
/// negative beyond the neutral band (divergence); `largest` is the largest |theta| (the
/// lowest mode), the stiffest mode's |mu| being at least 1 / the smallest retained.
fn grows(theta: Complex<f64>, largest: f64) -> bool {
    if theta.norm() <= 1e-9 * largest {
        return false;
    }
    let mu = theta.inv();
    mu.im.abs() > COMPLEX * mu.norm() || mu.re < -NEUTRAL * 1e9 / largest
}

/// The verdict from the Ritz values: the fastest-growing converged mode.
fn classify(ritz: &[Ritz]) -> Vibration {
    let largest = ritz.iter().map(|r| r.theta.norm()).fold(0.0f64, f64::max);
    // theta near 0 is an infinite mu (M's kernel: the constraints, the strains).
    let finite: Vec<&Ritz> = ritz.iter().filter(|r| r.theta.norm() > 1e-9 * largest).collect();
    let converged: Vec<&Ritz> = finite
        .iter()
        .copied()
        .filter(|r| r.residual <= CONVERGED * r.theta.norm())
        .collect();
    // The lowest mode (largest |theta|) must be among the converged ones for any verdict.
    if largest == 0.0 || !converged.iter().any(|r| r.theta.norm() >= (1.0 - 1e-9) * largest) {
        return Vibration {
            stability: Stability::Unknown {
                reason: "the lowest vibration modes did not converge in the Arnoldi steps".into(),
            },
            eigenvalues: Vec::new(),
        };
    }
    let mut worst: Option<(Growth, f64)> = None;
    for r in converged.iter().filter(|r| grows(r.theta, largest)) {
        let mu = r.theta.inv();
        let lambda = (-mu).sqrt();
        let rate = lambda.re.abs();
        let growth = if mu.im.abs() > COMPLEX * mu.norm() {
            Growth::Flutter {
                frequency: lambda.im.abs() / (2.0 * std::f64::consts::PI),
            }
        } else {
            Growth::Divergence
        };
        if worst.as_ref().is_none_or(|(_, r)| rate > *r) {
            worst = Some((growth, rate));
        }
    }
    let mut eigenvalues: Vec<Complex<f64>> = converged.iter().map(|r| r.theta.inv()).collect();
    eigenvalues.sort_by(|a, b| a.norm().total_cmp(&b.norm()).then(a.im.total_cmp(&b.im)));
    Vibration {
        stability: match worst {
            None => Stability::Stable,
            Some((growth, rate)) => Stability::Growing { growth, rate },
        },
        eigenvalues,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{Method, SolveReport};

    /// The Jacobian that keeps eq. 13's factored matrices is the plain one, and the mass
    /// from those matrices is the mass evaluated afresh, bit for bit, on every interval
    /// (the same points, the same solves): case S with a dead tip moment, and case H with
    /// one and a point load halfway (a breakpoint: a jump between two intervals, after which
    /// no node is shared), at their answers. The same holds for the Jacobian Newton
    /// evaluates ahead in place of its last residual (`System::jacobian_rates_keeping`),
    /// whose residual and node rates are also `residual_rates`' bit for bit.
    #[test]
    fn the_kept_factors_give_the_jacobian_and_the_mass_bit_for_bit() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut s = crate::cases::case_s();
        s.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
        let mut h = crate::cases::case_h();
        h.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
        h.loads.point.push(crate::model::loads::PointLoad {
            s: 0.5 * h.length(),
            force: Vector3::new(0.05, 0.0, 0.0),
            moment: Vector3::zeros(),
        });
        for (robot, jumps) in [(s, 0), (h, 1)] {
            let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
            let (system, x, mut ws) = Sensitivity::new(&robot, &solution).unwrap().into_parts();
            let mut report = SolveReport::new(Method::Collocation);
            assert!(ws.linearize(&system, &x, &mut report));
            let plain = ws.jacobian().to_vec();
            assert!(ws.linearize_keeping(&system, &x, &mut report));
            assert_eq!(bits(ws.jacobian()), bits(&plain));
            let fresh = Mass::new(&system, &x, None).unwrap();
            let kept = Mass::new(&system, &x, Some(ws.kept())).unwrap();
            // Newton's Jacobian ahead, keeping the matrices.
            let n = system.unknowns();
            let (mut residual, mut rates) = (vec![0.0; n], vec![Vector6::zeros(); x.len()]);
            assert!(system.residual_rates(&x, &mut residual, &mut rates).unwrap());
            let (mut with, mut values) = (vec![f64::NAN; n], vec![f64::NAN; plain.len()]);
            let mut with_rates = vec![Vector6::zeros(); x.len()];
            let mut factors = vec![IntervalFactors::identity(); x.len() - 1];
            system
                .jacobian_rates_keeping(&x, &mut with, &mut values, &mut with_rates, &mut factors)
                .unwrap();
            assert_eq!(bits(&with), bits(&residual));
            assert_eq!(bits(&values), bits(&plain));
            let flat = |r: &[Vector6<f64>]| r.iter().flat_map(|v| v.iter().copied()).collect::<Vec<_>>();
            assert_eq!(bits(&flat(&with_rates)), bits(&flat(&rates)));
            let ahead = Mass::new(&system, &x, Some(&factors)).unwrap();
            let mut compared = 0;
            for (k, ((a, b), c)) in fresh.blocks.iter().zip(&kept.blocks).zip(&ahead.blocks).enumerate() {
                match (a, b, c) {
                    (Some(a), Some(b), Some(c)) => {
                        assert_eq!(bits(a.as_slice()), bits(b.as_slice()), "interval {k}");
                        assert_eq!(bits(a.as_slice()), bits(c.as_slice()), "interval {k}, ahead");
                        compared += 1;
                    }
                    (None, None, None) => {}
                    _ => panic!("interval {k}: a jump in one mass only"),
                }
            }
            assert_eq!(fresh.blocks.len() - compared, jumps);
            assert!(compared >= 16, "{compared} intervals");
        }
    }
}
