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

use super::newton::Workspace;
use super::residual::end_values;
use super::sensitivity::Sensitivity;
use super::system::System;
use super::unknowns::{BASE_COLUMNS, BASE_ROWS, NODE, P, THETA, U, V, link_row, unknowns};
use crate::model::equations::Site;
use crate::model::linearize::Point;
use crate::report::{Growth, Stability};
use crate::so3;
use crate::solution::State;
use crate::{Robot, Solution};
use nalgebra::{Complex, DMatrix, Matrix3, SMatrix, Vector3};

/// The density the mass is taken from (kg/m^3): stainless steel, the usual backbone. Only
/// the growth rate depends on it.
pub const DENSITY: f64 = 7850.0;
/// Young's modulus (Pa) that turns stiffness into cross-section geometry when the rod was
/// given by stiffnesses alone (steel's, to go with [`DENSITY`]).
pub const MODULUS: f64 = 200e9;
/// Krylov dimension of a solve's verdict: the number of Arnoldi steps (solves with the
/// stored factors). The decisive modes are the lowest few, which shift-invert at 0 makes
/// the dominant ones; 16 resolve the lowest 2-4 (12 leave Beck's flutter pair unconverged).
const KRYLOV: usize = 16;
/// Krylov dimension of [`vibration`], which reports the lowest modes' eigenvalues: 24
/// resolve the lowest 6-10 to rounding.
const KRYLOV_MODES: usize = 24;
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
    /// The mass of `system` linearized at the equilibrium `x` (node states).
    ///
    /// # Errors
    /// A model breakdown at a collocation point.
    pub(crate) fn new(system: &System, x: &[State]) -> crate::Result<Self> {
        let model = &system.model;
        let length = model.robot.length();
        let ratio = DENSITY / model.robot.rod.geometry.map_or(MODULUS, |g| g.youngs_modulus);
        let links = x.len() - 1;
        let mut blocks = Vec::with_capacity(links);
        for k in 0..links {
            let Some(sites) = system.interval_sites(k) else {
                blocks.push(None);
                continue;
            };
            let seg = system.mesh.nodes[k].segment_end;
            let (a, b) = (&x[k], &x[k + 1]);
            let h = sites.end.s - sites.start.s;
            let pa = Point::new(model, &sites.start, seg, (&a.R, &a.v, &a.u))?;
            let pb = Point::new(model, &sites.end, seg, (&b.R, &b.v, &b.u))?;
            // The Hermite-Simpson midpoint, as the residual's.
            let [y0, y1, f0, f1] = end_values(sites, a, b, &pa.rates(), &pb.rates());
            let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
            let Rm = a.R * so3::exp(&ym.fixed_rows::<3>(THETA).into());
            let (vm, um): (Vector3<f64>, Vector3<f64>) = (ym.fixed_rows::<3>(V).into(), ym.fixed_rows::<3>(U).into());
            let pm = Point::new(model, &sites.mid, seg, (&Rm, &vm, &um))?;
            let mut block = SMatrix::<f64, 6, 12>::zeros();
            // Simpson's weights h/6 (1, 4, 1) at the start, midpoint and end, with the
            // accelerations interpolated linearly (weights of node a, node b).
            let points = [
                (&pa, &sites.start, &a.R, 1.0, (1.0, 0.0)),
                (&pm, &sites.mid, &Rm, 4.0, (0.5, 0.5)),
                (&pb, &sites.end, &b.R, 1.0, (0.0, 1.0)),
            ];
            for (point, site, Rc, weight, (wa, wb)) in points {
                let load = inertia_load(site, Rc, (&a.R, &b.R), (wa, wb), ratio, length);
                // d(v', u') / d(body load) = -M^-1 (eq. 13: F = M x - rhs with + R^T f_e,
                // + R^T l_e in F); the residual is y1 - y0 - h/6 sum w F: + h/6 w M^-1 load.
                let mut t = load.transpose();
                if !point.solve_rows(&mut t) {
                    return Err(crate::Error::Breakdown {
                        s: site.s,
                        what: "the 6x6 matrix of eq. 13 is singular".into(),
                    });
                }
                block += t.transpose() * (h / 6.0 * weight);
            }
            for r in 3..6 {
                for c in 0..12 {
                    block[(r, c)] *= length;
                }
            }
            blocks.push(Some(block));
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

    /// y = M x for scaled unknowns `x`.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (k, block) in self.blocks.iter().enumerate() {
            let Some(block) = block else { continue };
            let mut z = SMatrix::<f64, 12, 1>::zeros();
            for j in 0..3 {
                z[j] = x[k * NODE + P + j];
                z[3 + j] = x[k * NODE + THETA + j];
                z[6 + j] = x[(k + 1) * NODE + P + j];
                z[9 + j] = x[(k + 1) * NODE + THETA + j];
            }
            let r = block * z;
            let row = link_row(k) + V;
            y[row..row + 6].copy_from_slice(r.as_slice());
        }
    }
}

/// The body-frame distributed load (force, moment; N/m and N m/m) per unit scaled
/// acceleration of the (p, theta) columns of nodes a and b at a collocation point with
/// orientation `Rc`: -(rho A Rc^T p_tt, rho J_b w_t) with the accelerations interpolated
/// with weights `(wa, wb)`; w_t of a node is its rotation increment's, in its body frame.
fn inertia_load(
    site: &Site,
    Rc: &Matrix3<f64>,
    (Ra, Rb): (&Matrix3<f64>, &Matrix3<f64>),
    (wa, wb): (f64, f64),
    ratio: f64,
    length: f64,
) -> SMatrix<f64, 6, 12> {
    let section = &site.section.section;
    let rho_a = ratio * section.kse[2];
    let rho_j = Matrix3::from_diagonal(&Vector3::new(
        ratio * section.kbt[0],
        ratio * section.kbt[1],
        ratio * (section.kbt[0] + section.kbt[1]),
    ));
    let mut w = SMatrix::<f64, 6, 12>::zeros();
    // p columns hold dp / L.
    w.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Rc.transpose() * (-rho_a * wa * length)));
    w.fixed_view_mut::<3, 3>(0, 6)
        .copy_from(&(Rc.transpose() * (-rho_a * wb * length)));
    w.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(-rho_j * Rc.transpose() * Ra * wa));
    w.fixed_view_mut::<3, 3>(3, 9)
        .copy_from(&(-rho_j * Rc.transpose() * Rb * wb));
    w
}

/// The vibration modes of an equilibrium: the verdict of its linearized dynamics and the
/// eigenvalues it rests on ([`vibration`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Vibration {
    /// [`Stability::Stable`], [`Stability::Growing`], or [`Stability::Unknown`] when the
    /// lowest modes did not converge.
    pub stability: Stability,
    /// The converged eigenvalues mu = -lambda^2 (1/s^2) of the lowest modes, by increasing
    /// |mu|: omega^2 of a vibration at omega rad/s when real and positive.
    pub eigenvalues: Vec<Complex<f64>>,
}

/// The linearized dynamics of `robot` about its equilibrium `solution` (a collocation
/// solution of this robot): the verdict and the lowest modes' eigenvalues, for any loads
/// (conservative ones included, where the verdict agrees with the conjugate-point test of
/// [`SolveReport::stability`](crate::SolveReport::stability)); docs/stability.md.
///
/// # Errors
/// As [`crate::collocation::sensitivity::Sensitivity::new`]: an invalid robot, a solution that
/// does not solve its collocation system, a singular Jacobian; tendons with friction.
pub fn vibration(robot: &Robot, solution: &Solution) -> crate::Result<Vibration> {
    if let Some(i) = robot.tendons.iter().position(|t| t.active_friction().is_some()) {
        return Err(crate::error::invalid(
            format!("tendon {} friction", i + 1),
            "is set; the linearized dynamics does not include the capstan rows of tendons with friction",
            "set the friction to 0 for a verdict of the frictionless robot",
        ));
    }
    let (system, states, mut ws) = Sensitivity::new(robot, solution)?.into_parts();
    Ok(modes(&system, &states, &mut ws, KRYLOV_MODES, true, &mut |_| true))
}

/// The verdict of the linearized dynamics at the equilibrium `x` of `system`, with the
/// factors of its Jacobian held in `ws` (Newton's at `x`, or at its last iterate).
pub(crate) fn assess(system: &System, x: &[State], ws: &mut Workspace) -> Stability {
    modes(system, x, ws, KRYLOV, false, &mut |_| true).stability
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
    modes(system, x, ws, KRYLOV, false, border).stability
}

/// [`assess`] with the eigenvalues, from `krylov` Arnoldi steps; the residual of every Ritz
/// value when `all`, else only of those the verdict rests on; `border` as in
/// [`assess_bordered`].
fn modes(
    system: &System,
    x: &[State],
    ws: &mut Workspace,
    krylov: usize,
    all: bool,
    border: &mut dyn FnMut(&mut [f64]) -> bool,
) -> Vibration {
    let unknown = |reason: String| Vibration {
        stability: Stability::Unknown { reason },
        eigenvalues: Vec::new(),
    };
    let mass = match Mass::new(system, x) {
        Ok(m) => m,
        Err(e) => return unknown(format!("the mass matrix could not be formed: {e}")),
    };
    let n = unknowns(x.len());
    let mut w = vec![0.0; n];
    // y = J^-1 M z
    let mut operator = |z: &[f64], out: &mut Vec<f64>| -> bool {
        mass.apply(z, &mut w);
        match ws.solve_again(&w) {
            Some(y) => {
                out.clear();
                out.extend_from_slice(y);
                border(out)
            }
            None => false,
        }
    };
    let Some(ritz) = arnoldi(&mut operator, n, krylov, all) else {
        return unknown("the Jacobian's factors gave no finite solve for the vibration modes".into());
    };
    classify(&ritz)
}

/// A Ritz value theta of J^-1 M (theta = 1 / mu) and its residual estimate.
struct Ritz {
    theta: Complex<f64>,
    residual: f64,
}

/// Arnoldi on `operator` (y = J^-1 M z) from a generic start purified by two applications
/// (which removes the components along M's kernel, the infinite mu): the Ritz values and
/// their residual estimates |h_(m+1,m) y_m|. None if a solve fails.
fn arnoldi(
    operator: &mut impl FnMut(&[f64], &mut Vec<f64>) -> bool,
    n: usize,
    krylov: usize,
    all: bool,
) -> Option<Vec<Ritz>> {
    let mut q: Vec<f64> = (0..n)
        .map(|i| (i as f64 * 0.618_033_988_749_895).fract() - 0.5)
        .collect();
    let mut next = Vec::with_capacity(n);
    for _ in 0..2 {
        if !operator(&q, &mut next) {
            return None;
        }
        std::mem::swap(&mut q, &mut next);
    }
    let norm = dot(&q, &q).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    q.iter_mut().for_each(|v| *v /= norm);
    let m_max = krylov.min(n);
    let mut basis = vec![q];
    let mut h = DMatrix::<f64>::zeros(m_max + 1, m_max);
    let mut m = 0;
    while m < m_max {
        if !operator(&basis[m], &mut next) {
            return None;
        }
        let scale = dot(&next, &next).sqrt();
        // Modified Gram-Schmidt, twice (the second pass restores orthogonality lost to
        // rounding when the new vector is nearly in the span).
        for _ in 0..2 {
            for (j, b) in basis.iter().enumerate() {
                let c = dot(&next, b);
                h[(j, m)] += c;
                next.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
            }
        }
        let beta = dot(&next, &next).sqrt();
        h[(m + 1, m)] = beta;
        m += 1;
        // An invariant subspace (breakdown at rounding of the step's size): its Ritz
        // values are exact.
        if beta <= 1e-13 * scale || !beta.is_finite() {
            break;
        }
        basis.push(next.iter().map(|x| x / beta).collect());
    }
    let hm = h.view((0, 0), (m, m)).into_owned();
    let beta = h[(m, m - 1)];
    let values = hm.complex_eigenvalues();
    let largest = values.iter().map(|t| t.norm()).fold(0.0f64, f64::max);
    let hc = hm.map(|v| Complex::new(v, 0.0));
    // Residual estimates cost a complex LU each: unless `all`, only for the Ritz values a
    // verdict rests on, the lowest mode and any that grows ([`grows`]).
    Some(
        values
            .iter()
            .map(|&theta| Ritz {
                theta,
                residual: if all || theta.norm() >= (1.0 - 1e-9) * largest || grows(theta, largest) {
                    beta * last_component(&hc, theta)
                } else {
                    f64::INFINITY
                },
            })
            .collect(),
    )
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

/// |y_m| of the unit eigenvector y of `h` for its eigenvalue `theta`, by two steps of
/// inverse iteration with a shift moved off theta by rounding's size.
fn last_component(h: &DMatrix<Complex<f64>>, theta: Complex<f64>) -> f64 {
    let m = h.nrows();
    let scale = h.iter().fold(0.0f64, |a, v| a.max(v.norm()));
    let shift = theta + Complex::new(1e-12 * scale.max(f64::MIN_POSITIVE), 0.0);
    let a = h - DMatrix::<Complex<f64>>::identity(m, m) * shift;
    let lu = a.lu();
    let mut y = DMatrix::<Complex<f64>>::from_fn(m, 1, |i, _| Complex::new(1.0 + 0.1 * i as f64, 0.0));
    for _ in 0..2 {
        match lu.solve(&y) {
            Some(z) => {
                let norm = z.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    return f64::INFINITY;
                }
                y = z / Complex::new(norm, 0.0);
            }
            None => return 0.0,
        }
    }
    y[(m - 1, 0)].norm()
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
    eigenvalues.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    Vibration {
        stability: match worst {
            None => Stability::Stable,
            Some((growth, rate)) => Stability::Growing { growth, rate },
        },
        eigenvalues,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
