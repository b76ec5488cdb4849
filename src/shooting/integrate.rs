//! One trial of shooting: eq. 13 integrated from the base by the Dormand-Prince 5(4) pair
//! with Runge-Kutta-Munthe-Kaas steps on SO(3), the tendon path lengths integrated along,
//! and the jump conditions solved at every interior breakpoint.
#![allow(non_snake_case)]

use super::problem::Scale;
use super::{Options, Point};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::model::friction;
use crate::model::length;
use crate::report::SolveReport;
use crate::solution::State;
use crate::{Error, so3};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use num_dual::DualSVec64;

/// Local-coordinate state (p, theta, v, u) of one integration step.
type Local = SVector<f64, 12>;

/// Integrates from the base with base strains `x` (scaled) and returns the scaled tip
/// residual and the path lengths of the tendons `paths` ((tendon index, end) each,
/// integrated over the segments up to its end); `traj` receives every accepted step and
/// `profile`, when given, every tendon's tension there (docs/friction.md).
#[allow(clippy::too_many_arguments)]
pub(super) fn shoot(
    model: &Model,
    scale: &Scale,
    x: &SVector<f64, 6>,
    paths: &[(usize, f64)],
    options: &Options,
    traj: &mut Vec<Point>,
    mut profile: Option<&mut Vec<Vec<f64>>>,
    report: &mut SolveReport,
) -> Result<(SVector<f64, 6>, Vec<f64>)> {
    report.evaluations.residual += 1;
    traj.clear();
    // The tensions of tendons with friction vary along s: a copy of the model holds them at
    // the current s (docs/friction.md).
    let mut model = model.clone();
    let slipping: Vec<usize> = (0..model.robot.tendons.len())
        .filter(|&i| model.robot.tendons[i].active_friction().is_some())
        .collect();
    if let Some(out) = profile.as_deref_mut() {
        out.clear();
        out.push(model.tensions.clone());
    }
    let robot = model.robot;
    let length = robot.length();
    let (v, u) = scale.strains(x);
    let mut state = State {
        s: 0.0,
        p: robot.base_position,
        R: robot.base_rotation,
        v,
        u,
    };
    traj.push(state);
    let mut lengths = vec![0.0; paths.len()];
    let mut seg_start = 0.0;
    let breaks = robot.breakpoints();
    for seg_end in breaks.iter().copied().chain(std::iter::once(length)) {
        // The tendons whose paths run over this segment (terminations are breakpoints).
        let slots: Vec<usize> = (0..paths.len()).filter(|&j| seg_end <= paths[j].1).collect();
        state = integrate(
            &mut model,
            seg_start,
            seg_end,
            state,
            options.integration_tolerance,
            Paths {
                paths,
                slots: &slots,
                lengths: &mut lengths,
            },
            Slipping {
                tendons: &slipping,
                profile: profile.as_deref_mut(),
            },
            traj,
            report,
        )?;
        if seg_end < length {
            // The segment after the jump ends at the next breakpoint (or the tip).
            let next_end = breaks.iter().copied().find(|&b| b > seg_end).unwrap_or(length);
            let (v_b, u_b) = jump(&model, seg_end, next_end, &state)?;
            if let Some(out) = profile.as_deref_mut() {
                out.push(model.tensions.clone());
            }
            state = State {
                s: seg_end,
                v: v_b,
                u: u_b,
                ..state
            };
            traj.push(state);
        }
        seg_start = seg_end;
    }
    let site = model.site(length);
    let State { s, R, v, u, .. } = state;
    let (f, m) = model.wrench_balance(s, (&site, &R, &v, &u), None)?;
    Ok((
        SVector::<f64, 6>::from_iterator(f.iter().copied().chain(m.iter().map(|x| x * length))),
        lengths,
    ))
}

/// Right-limit strains at breakpoint s from the jump conditions (Newton on 6 unknowns with
/// an exact dual-number Jacobian; p and R are continuous); `next_end` (m) is where the
/// segment after s ends, which says the right side's section and precurvature.
fn jump(model: &Model, s: f64, next_end: f64, left: &Point) -> Result<(Vector3<f64>, Vector3<f64>)> {
    type D6 = DualSVec64<6>;
    let (site, right) = (model.site(s), model.site_on(s, next_end));
    let State { R, v: va, u: ua, .. } = *left;
    let (mut v, mut u) = (va, ua);
    let lift3 = |x: &Vector3<f64>| x.map(D6::from);
    let (Rd, vad, uad) = (R.map(D6::from), lift3(&va), lift3(&ua));
    for _ in 0..30 {
        let mut vd = lift3(&v);
        let mut ud = lift3(&u);
        for i in 0..3 {
            vd[i] = D6::from(v[i]).derivative(i);
            ud[i] = D6::from(u[i]).derivative(i + 3);
        }
        let (fr, mr) = model.wrench_balance(s, (&site, &Rd, &vad, &uad), Some((&right, &Rd, &vd, &ud)))?;
        let r = SVector::<f64, 6>::from_iterator(fr.iter().chain(mr.iter()).map(|d| d.re));
        let mut J = SMatrix::<f64, 6, 6>::zeros();
        for (row, d) in fr.iter().chain(mr.iter()).enumerate() {
            if let Some(eps) = d.eps.0.as_ref() {
                J.set_row(row, &eps.transpose());
            }
        }
        let step = J.lu().solve(&(-r)).ok_or_else(|| Error::Breakdown {
            s,
            what: "the jump conditions are singular".into(),
        })?;
        v += step.fixed_rows::<3>(0);
        u += step.fixed_rows::<3>(3);
        // 1e-15 relative to the strains: converged to rounding
        if step.amax() <= 1e-15 * (1.0 + v.amax() + u.amax()) {
            break;
        }
    }
    Ok((v, u))
}

/// Scaled local state: p / L, theta, v, u L.
fn scaled(y: &Local, length: f64) -> Local {
    let mut z = *y;
    for i in 0..3 {
        z[i] /= length;
        z[9 + i] *= length;
    }
    z
}

/// d/ds of the local state (p, theta, v, u) of a step that started at rotation `R_n`; with
/// tendons with friction (`turning` not empty, one entry per tendon) eq. 13 with friction,
/// and the relative tension rates tau_i' / tau_i into `turning`.
fn local_rhs(
    model: &Model,
    site: &Site,
    seg_end: f64,
    R_n: &Matrix3<f64>,
    y: &Local,
    turning: &mut [f64],
) -> Result<Local> {
    let theta: Vector3<f64> = y.fixed_rows::<3>(3).into();
    let v: Vector3<f64> = y.fixed_rows::<3>(6).into();
    let u: Vector3<f64> = y.fixed_rows::<3>(9).into();
    let R = R_n * so3::exp(&theta);
    let (v_s, u_s) = if turning.is_empty() {
        model.strain_rates(site, seg_end, &R, &v, &u)?
    } else {
        let x = friction::rates(model, site, seg_end, (&R, &v, &u), None, turning)?;
        (x.fixed_rows::<3>(0).into(), x.fixed_rows::<3>(3).into())
    };
    let mut d = Local::zeros();
    d.fixed_rows_mut::<3>(0).copy_from(&(R * site.strain(&v)));
    d.fixed_rows_mut::<3>(3)
        .copy_from(&(so3::right_jacobian_inv(&theta) * u));
    d.fixed_rows_mut::<3>(6).copy_from(&v_s);
    d.fixed_rows_mut::<3>(9).copy_from(&u_s);
    Ok(d)
}

// Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett & Wanner, table II.5.2).
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// 5th-order weights (the last row of A).
const B5: [f64; 7] = {
    // First same as last: the 5th-order weights are the last row of A, with 0 for stage 7.
    let last = A[6];
    [last[0], last[1], last[2], last[3], last[4], last[5], 0.0]
};
/// 4th-order embedded weights.
const B4: [f64; 7] = [
    5179.0 / 57600.0,
    0.0,
    7571.0 / 16695.0,
    393.0 / 640.0,
    -92097.0 / 339200.0,
    187.0 / 2100.0,
    1.0 / 40.0,
];

/// The tendon path lengths integrated along with the state over one segment.
struct Paths<'a> {
    /// (tendon index, end) of every tracked tendon.
    paths: &'a [(usize, f64)],
    /// The entries of `paths` whose tendons run over this segment.
    slots: &'a [usize],
    /// The path length so far of each entry of `paths` (m).
    lengths: &'a mut [f64],
}

/// The tendons with friction, whose tensions are integrated along with the state.
struct Slipping<'a> {
    /// Indices of the tendons with friction.
    tendons: &'a [usize],
    /// When given, receives the model's tensions (all tendons, N) at every accepted step.
    profile: Option<&'a mut Vec<Vec<f64>>>,
}

/// Integrates one segment [s0, s1] with adaptive steps, pushing every accepted step; the
/// path lengths of `paths` grow by the integral of |v + u x r_j + r_j'| with the same
/// stages, their error (relative to L) in the step control. The tensions of the tendons
/// with friction (`slipping`, held in `model`'s tensions) grow by tau_i' = w_i mu_i
/// kappa_i tau_i with the same stages, their error relative to the tension in the step
/// control; `model` ends with the tensions at s1.
#[allow(clippy::too_many_arguments)]
fn integrate(
    model: &mut Model,
    s0: f64,
    s1: f64,
    start: Point,
    tol: f64,
    paths: Paths,
    mut slipping: Slipping,
    traj: &mut Vec<Point>,
    report: &mut SolveReport,
) -> Result<Point> {
    let length = model.robot.length();
    let State {
        mut p,
        mut R,
        mut v,
        mut u,
        ..
    } = start;
    let mut s = s0;
    // First step: a few percent of the segment; the controller adapts it at once.
    let mut h = (s1 - s0) * 0.02;
    let mut steps = 0usize;
    let mut speeds = Vec::with_capacity(7 * paths.slots.len());
    let slips = slipping.tendons.len();
    // Tensions at the step's start, the stages' tension rates and each stage's turning.
    let mut tau: Vec<f64> = slipping.tendons.iter().map(|&i| model.tensions[i]).collect();
    let mut tau_rates = vec![0.0; 7 * slips];
    let mut turning = vec![0.0; if slips > 0 { model.robot.tendons.len() } else { 0 }];
    while s < s1 {
        steps += 1;
        // 1e6 steps means the tolerance cannot be met: report instead of looping
        if steps > 1_000_000 || !h.is_finite() {
            return Err(Error::Breakdown {
                s,
                what: "the integrator's step size collapsed".into(),
            });
        }
        let last = s + h >= s1 - 1e-14 * length;
        if last {
            h = s1 - s;
        }
        let mut y0 = Local::zeros();
        y0.fixed_rows_mut::<3>(0).copy_from(&p);
        y0.fixed_rows_mut::<3>(6).copy_from(&v);
        y0.fixed_rows_mut::<3>(9).copy_from(&u);
        let mut k = [Local::zeros(); 7];
        // Speeds |w_j| of the tracked tendon paths at each stage.
        speeds.clear();
        for i in 0..7 {
            let mut yi = y0;
            for (j, kj) in k.iter().enumerate().take(i) {
                yi += kj * (h * A[i][j]);
            }
            let si = s + C[i] * h;
            let site = model.site_on(si, s1);
            for (j, &t) in slipping.tendons.iter().enumerate() {
                let rate: f64 = (0..i).map(|l| A[i][l] * tau_rates[l * slips + j]).sum();
                model.tensions[t] = tau[j] + h * rate;
            }
            k[i] = local_rhs(model, &site, s1, &R, &yi, &mut turning)?;
            for (j, &t) in slipping.tendons.iter().enumerate() {
                tau_rates[i * slips + j] = model.tensions[t] * turning[t];
            }
            report.evaluations.equations += 1;
            let (vi, ui): (Vector3<f64>, Vector3<f64>) = (yi.fixed_rows::<3>(6).into(), yi.fixed_rows::<3>(9).into());
            for &j in paths.slots {
                let rp = model.robot.tendons[paths.paths[j].0].routing.at(si, length);
                speeds.push(length::speed(&rp, &site.strain(&vi), &ui));
            }
        }
        let tracked = paths.slots.len();
        let step_lengths =
            |b: &[f64; 7], slot: usize| -> f64 { (0..7).map(|i| b[i] * speeds[i * tracked + slot]).sum::<f64>() * h };
        let mut y5 = y0;
        let mut y4 = y0;
        for i in 0..7 {
            y5 += k[i] * (h * B5[i]);
            y4 += k[i] * (h * B4[i]);
        }
        let (z0, z5, z4) = (scaled(&y0, length), scaled(&y5, length), scaled(&y4, length));
        let mut err: f64 = 0.0;
        for i in 0..12 {
            let sc = tol * (1.0 + z0[i].abs().max(z5[i].abs()));
            err = err.max(((z5[i] - z4[i]) / sc).abs());
        }
        for (slot, &j) in paths.slots.iter().enumerate() {
            let (l0, dl5) = (paths.lengths[j] / length, step_lengths(&B5, slot) / length);
            let sc = tol * (1.0 + l0.abs().max((l0 + dl5).abs()));
            err = err.max(((dl5 - step_lengths(&B4, slot) / length) / sc).abs());
        }
        let step_tension =
            |b: &[f64; 7], j: usize| -> f64 { (0..7).map(|i| b[i] * tau_rates[i * slips + j]).sum::<f64>() * h };
        // Relative to the tension itself: it changes by the factor exp(mu theta), whatever
        // its size (a tendon at 0 N stays there).
        for (j, &t0) in tau.iter().enumerate().filter(|(_, t)| **t > 0.0) {
            let sc = tol * t0.max(t0 + step_tension(&B5, j));
            err = err.max(((step_tension(&B5, j) - step_tension(&B4, j)) / sc).abs());
        }
        if !err.is_finite() {
            h *= 0.25;
            continue;
        }
        if err <= 1.0 {
            s = if last { s1 } else { s + h };
            p = y5.fixed_rows::<3>(0).into();
            R *= so3::exp(&y5.fixed_rows::<3>(3).into());
            v = y5.fixed_rows::<3>(6).into();
            u = y5.fixed_rows::<3>(9).into();
            for (slot, &j) in paths.slots.iter().enumerate() {
                paths.lengths[j] += step_lengths(&B5, slot);
            }
            for (j, t) in tau.iter_mut().enumerate() {
                *t += step_tension(&B5, j);
            }
            for (j, &t) in slipping.tendons.iter().enumerate() {
                model.tensions[t] = tau[j];
            }
            if let Some(out) = slipping.profile.as_deref_mut() {
                out.push(model.tensions.clone());
            }
            traj.push(State { s, p, R, v, u });
        }
        // Standard controller: safety 0.9, exponent 1/5, growth limited to [0.2, 5].
        h *= (0.9 * err.powf(-0.2)).clamp(0.2, 5.0);
    }
    for (j, &t) in slipping.tendons.iter().enumerate() {
        model.tensions[t] = tau[j];
    }
    Ok(State { s, p, R, v, u })
}
