//! A time integration of the semi-discrete nonlinear dynamics M x'' + F(x) = 0 about an
//! equilibrium, to check the verdicts of the linearized dynamics against the motion they
//! predict (docs/stability.md, "The verdict against a time integration"). Tests only.
//!
//! x is the equilibrium x* moved by the scaled increment d (`System::retract`, as Newton
//! moves its iterates), M the mass of the linearized dynamics at x* ([`Mass`]), F the
//! collocation residual less its value at x* (so that x* is an equilibrium to rounding, not
//! only to Newton's tolerance). Each step is Newmark's rule (beta, gamma) written on the
//! displacements alone (no velocities, so that every step meets the constraints exactly),
//! solved for d_(n+1) by Newton with the fixed matrix J(x*) + M / (beta h^2):
//!
//! ```text
//! M (d_(n+1) - 2 d_n + d_(n-1)) / h^2 + beta F_(n+1) + (1/2 - 2 beta + gamma) F_n
//!     + (1/2 + beta - gamma) F_(n-1) = 0     (on the mass rows; F_(n+1) = 0 on the others),
//! ```
//!
//! from rest (d_(-1) = d_0). gamma = 1/2 (average acceleration) has no numerical damping,
//! but on this system it lets high modes grow at a rate and frequency that change with h
//! (measured on two stable columns: 2.8 1/s at 3.5e3 rad/s, then 10.9 1/s at 6.9e3 rad/s
//! with h halved; the rule's known weakness on constrained dynamics); gamma = 1/2 + delta,
//! beta = (gamma + 1/2)^2 / 4 damps them, and shifts a mode's rate by about
//! -delta h omega^2 / 2.
//!
//! M has rows only at the intervals' (v', u') rows and columns only at the nodes' (p, theta):
//! the other rows are algebraic (F = 0 at every step) and the other unknowns carry no
//! inertia (a differential-algebraic system).

use super::super::homotopy::dot;
use super::super::newton::Workspace;
use super::super::phase::generic;
use super::super::system::System;
use super::super::unknowns::{NODE, P, THETA, V, link_row};
use super::Mass;
use super::{MOVING, restrict};
use crate::report::{Method, SolveReport};
use crate::solution::State;

/// One sample of the motion: the time (s), the normalized norm of the configuration part
/// (p, theta) of d (sqrt(|d|^2 / its length)), and a fixed generic projection of it (a
/// scalar signal whose zero crossings give the frequency).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sample {
    pub t: f64,
    pub norm: f64,
    pub signal: f64,
}

/// The motion of `system` from its equilibrium `x` displaced by `amplitude` (normalized
/// norm of the scaled unknowns) along J^-1 M g, g a fixed generic vector on the nodes'
/// (p, theta) (a direction that meets the constraints to first order and holds every mode,
/// no one in particular), at rest: `steps` steps of length `h` (s), stopped early once the
/// norm has grown `stop` times; Newmark's gamma = 1/2 + `delta`. `ws` holds the factors of the Jacobian at `x` on entry (its
/// factors are J + M / (beta h^2) on return, beta = (gamma + 1/2)^2 / 4). None when a factorization, a solve or a step's
/// Newton iteration fails.
pub(crate) fn motion(
    system: &System,
    x: &[State],
    ws: &mut Workspace,
    (h, steps): (f64, usize),
    amplitude: f64,
    stop: f64,
    delta: f64,
) -> Option<Vec<Sample>> {
    // Newmark's (beta, gamma) with gamma = 1/2 + delta, beta = (gamma + 1/2)^2 / 4, written on
    // the displacements alone and divided by beta: the weights of F_n and F_(n-1).
    let gamma = 0.5 + delta;
    let beta = (gamma + 0.5) * (gamma + 0.5) / 4.0;
    let (w1, w2) = ((0.5 - 2.0 * beta + gamma) / beta, (0.5 + beta - gamma) / beta);
    let mass = Mass::new(system, x, None).ok()?;
    let n = system.unknowns();
    let nodes = x.len();
    let times = |d: &[f64]| -> Vec<f64> {
        let mut z = d.to_vec();
        restrict(&mut z);
        let mut y = vec![0.0; n];
        mass.apply(&z, &mut y);
        y
    };
    let g = generic(nodes * MOVING);
    let mut direction = vec![0.0; n];
    for k in 0..nodes {
        direction[k * NODE..k * NODE + MOVING].copy_from_slice(&g[k * MOVING..(k + 1) * MOVING]);
    }
    let mut d = ws.solve_again(&times(&direction))?.to_vec();
    let scale = amplitude / (dot(&d, &d) / n as f64).sqrt();
    d.iter_mut().for_each(|v| *v *= scale);
    let c = 1.0 / (beta * h * h);
    let mut report = SolveReport::new(Method::Collocation);
    if !ws.linearize_shifted(system, x, &mut report, |values| mass.add_to(values, c)) {
        eprintln!("J + c M does not factor");
        return None;
    }
    let f0 = ws.residual().to_vec();
    // F(x* + d) - F(x*) into `out`.
    let mut moved = Vec::with_capacity(nodes);
    let mut force = |d: &[f64], out: &mut [f64]| -> Option<()> {
        system.retract(x, d, 1.0, &mut moved);
        system.residual(&moved, out).ok()?;
        out.iter_mut().zip(&f0).for_each(|(o, f)| *o -= f);
        Some(())
    };
    // The rows that carry mass: M a = -F there, the other rows are the constraints.
    let mut massive = vec![false; n];
    for (k, block) in mass.blocks.iter().enumerate() {
        if block.is_some() {
            massive[link_row(k) + V..link_row(k) + V + 6].fill(true);
        }
    }
    // The mass rows of F at the last two steps (F_n, F_(n-1)); at rest before the start.
    let mut f = vec![0.0; n];
    force(&d, &mut f)?;
    let mut fn_: Vec<f64> = f.iter().zip(&massive).map(|(f, &m)| if m { *f } else { 0.0 }).collect();
    let mut fp = fn_.clone();
    let mut previous = d.clone();
    let sample = |t: f64, d: &[f64]| {
        let (mut sum, mut signal) = (0.0, 0.0);
        for k in 0..nodes {
            for (j, dj) in d[k * NODE + P..k * NODE + THETA + 3].iter().enumerate() {
                sum += dj * dj;
                signal += dj * g[k * MOVING + j];
            }
        }
        Sample {
            t,
            norm: (sum / (nodes * MOVING) as f64).sqrt(),
            signal,
        }
    };
    let mut samples = vec![sample(0.0, &d)];
    let start = samples[0].norm;
    let (mut next, mut g_step) = (vec![0.0; n], vec![0.0; n]);
    for step in 1..=steps {
        // Newton from the extrapolation 2 d_n - d_(n-1).
        let base: Vec<f64> = d.iter().zip(&previous).map(|(a, b)| 2.0 * a - b).collect();
        next.copy_from_slice(&base);
        let (mut converged, mut last) = (false, f64::INFINITY);
        for _ in 0..30 {
            if force(&next, &mut f).is_none() {
                eprintln!(
                    "step {step}: residual fails at norm {:e}",
                    (dot(&next, &next) / n as f64).sqrt()
                );
                return None;
            }
            let offset: Vec<f64> = next.iter().zip(&base).map(|(a, b)| a - b).collect();
            let inertia = times(&offset);
            for i in 0..n {
                g_step[i] = -(f[i] + c * inertia[i] + w1 * fn_[i] + w2 * fp[i]);
            }
            let Some(delta) = ws.solve_again(&g_step) else {
                eprintln!("step {step}: solve fails");
                return None;
            };
            let size = (dot(delta, delta) / n as f64).sqrt();
            next.iter_mut().zip(delta).for_each(|(a, b)| *a += b);
            let norm = (dot(&next, &next) / n as f64).sqrt();
            // Converged: a correction of 1e-10 of the motion, or one that no longer falls
            // (halves) below 1e-5 of it: the rounding floor of F(x* + d) - F(x*), some
            // 1e-16 / 1e-8 of d times the solve's gain; either is far below what the fit
            // of the envelope sees (rates to 1e-2).
            if size <= 1e-10 * norm || (size > 0.5 * last && size <= 1e-5 * norm) {
                converged = true;
                break;
            }
            last = size;
        }
        if !converged {
            eprintln!("step {step}: Newton did not converge ({last:e})");
            return None;
        }
        std::mem::swap(&mut fp, &mut fn_);
        for i in 0..n {
            fn_[i] = if massive[i] { f[i] } else { 0.0 };
        }
        std::mem::swap(&mut previous, &mut d);
        std::mem::swap(&mut d, &mut next);
        samples.push(sample(step as f64 * h, &d));
        if samples[samples.len() - 1].norm >= stop * start {
            break;
        }
    }
    Some(samples)
}

/// The growth rate (1/s) and, when the motion oscillates, the angular frequency (rad/s)
/// of the samples from time `from` on: the frequency from the zero crossings of the signal
/// (pi per half period, the crossing times interpolated linearly), oscillating when there
/// are at least 4; the rate the least-squares slope of the log of the envelope against t,
/// the envelope the largest norm in each whole period (of the oscillation, else of length
/// `window`) that ends by the last sample: for a mode e^(sigma t) times a periodic function
/// its maxima over consecutive periods are exactly geometric.
pub(crate) fn measure(samples: &[Sample], from: f64, window: f64) -> (f64, Option<f64>) {
    let late: Vec<&Sample> = samples.iter().filter(|s| s.t >= from).collect();
    let mut crossings = Vec::new();
    for w in late.windows(2) {
        let (a, b) = (w[0], w[1]);
        if a.signal != 0.0 && a.signal.signum() != b.signal.signum() {
            crossings.push(a.t + (b.t - a.t) * a.signal / (a.signal - b.signal));
        }
    }
    let omega = (crossings.len() >= 4)
        .then(|| std::f64::consts::PI * (crossings.len() - 1) as f64 / (crossings[crossings.len() - 1] - crossings[0]));
    let period = omega.map_or(window, |w| 2.0 * std::f64::consts::PI / w);
    let end = late[late.len() - 1].t;
    let mut points = Vec::new();
    let mut top = end;
    while top - period >= from {
        let max = late
            .iter()
            .filter(|s| s.t > top - period && s.t <= top)
            .map(|s| s.norm)
            .fold(0.0f64, f64::max);
        points.push((top, max.ln()));
        top -= period;
    }
    let m = points.len() as f64;
    let (st, sy) = points.iter().fold((0.0, 0.0), |(a, b), (t, y)| (a + t, b + y));
    let (mt, my) = (st / m, sy / m);
    let (num, den) = points.iter().fold((0.0, 0.0), |(n, d), (t, y)| {
        (n + (t - mt) * (y - my), d + (t - mt) * (t - mt))
    });
    (num / den, omega)
}

#[cfg(test)]
mod tests {
    use super::super::{bending_scale, vibration};
    use super::*;
    use crate::collocation::sensitivity::Sensitivity;
    use crate::collocation::{self, Equilibrium, Options};
    use crate::report::{Growth, Stability};
    use crate::{Loads, Robot, Rod};
    use nalgebra::Vector3;
    use std::f64::consts::PI;

    /// The verdict's rate and angular frequency (0 and None when stable), the motion's
    /// measured ones (fitted from the second half of the run) and how much the motion grew,
    /// from a perturbation of 1e-8 (normalized norm) run until it grew 1e4 times (1e-4: small
    /// enough that the quadratic terms change a rate by 1e-4) or for `periods` periods of
    /// the unloaded rod's first bending mode, `per_period` steps each, with Newmark's
    /// gamma = 1/2 + 0.02.
    fn compare(robot: &Robot, options: &Options, per_period: f64, periods: f64) -> [f64; 5] {
        let solution = collocation::solve(robot, options).unwrap();
        let (rate, omega) = match vibration(robot, &solution).unwrap().stability {
            Stability::Stable => (0.0, 0.0),
            Stability::Growing {
                growth: Growth::Divergence,
                rate,
            } => (rate, 0.0),
            Stability::Growing {
                growth: Growth::Flutter { frequency },
                rate,
            } => (rate, 2.0 * PI * frequency),
            other => panic!("{other}"),
        };
        let (system, x, mut ws) = Sensitivity::new(robot, &solution).unwrap().into_parts();
        // The period of the unloaded clamped-free rod's first bending mode (omega^2 = 12.36
        // times the bending scale): the time scale, independent of the verdict.
        let period = 2.0 * PI / (12.36 * bending_scale(&system)).sqrt();
        let h = period / per_period;
        let steps = (periods * per_period) as usize;
        let samples = motion(&system, &x, &mut ws, (h, steps), 1e-8, 1e4, 0.02).unwrap();
        let end = samples[samples.len() - 1].t;
        let (measured, frequency) = measure(&samples, 0.5 * end, 0.5 * end / 8.0);
        let grown = samples[samples.len() - 1].norm / samples[0].norm;
        let result = [rate, omega, measured, frequency.unwrap_or(0.0), grown];
        eprintln!(
            "{} steps to {end:.3e} s: verdict rate, omega; measured rate, omega; growth {result:?}",
            samples.len()
        );
        result
    }

    fn rod() -> Robot {
        Robot::new(Rod::solid_circle(0.5, 1e-3, 200e9, 0.3))
    }

    /// Beck's column just above its flutter load, the dead-load column past Euler's load
    /// (Newton's nearest: the straight, diverging state), both again just below (stable).
    #[test]
    fn the_motion_grows_as_the_columns_verdicts_say() {
        let ei = 200e9 * PI * 1e-12 / 4.0;
        let pcr = PI * PI * ei / (4.0 * 0.25);
        let nearest = Options {
            equilibrium: Equilibrium::Nearest,
            ..Default::default()
        };
        let beck = |load: f64| {
            rod().with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.0, 0.0, -load * ei / 0.25)))
        };
        let dead = |f: f64| rod().with_loads(Loads::none().with_tip_force(Vector3::new(0.0, 0.0, -f * pcr)));
        let [rate, omega, measured, frequency, grown] = compare(&beck(21.0), &Options::default(), 200.0, 40.0);
        assert!(rate > 0.0 && omega > 0.0 && grown >= 1e4);
        // 2 %: Newmark's damping shifts the rate by (gamma - 1/2) h omega^2 / 2 (0.5 % here)
        // and the fit window holds the decaying modes' last traces.
        assert!((measured / rate - 1.0).abs() < 0.02, "{measured} against {rate}");
        // 0.5 %: the rule's frequency error (h omega)^2 / 12 and the crossings' interpolation.
        assert!((frequency / omega - 1.0).abs() < 5e-3, "{frequency} against {omega}");
        let [rate, omega, measured, _, grown] = compare(&dead(1.2), &nearest, 200.0, 40.0);
        assert!(rate > 0.0 && omega == 0.0 && grown >= 1e4);
        // 1 %: as above, the damping's shift at a real lambda is smaller.
        assert!((measured / rate - 1.0).abs() < 0.01, "{measured} against {rate}");
        for robot in [beck(19.0), dead(0.8)] {
            let [rate, _, _, _, grown] = compare(&robot, &nearest, 200.0, 40.0);
            // Stable: no growth over 40 periods (the growing cases grow 1e4 times in 3 to 8).
            assert!(rate == 0.0 && grown < 2.0, "{grown}");
        }
    }

    /// The prototype under a dead tip moment: (2, 1, 0) mN m flutters slowly (1.35 1/s at
    /// 61.9 Hz), (0.2, 0.1, 0) mN m is stable (docs/stability.md, "Flutter and damping").
    #[test]
    fn the_motion_grows_as_the_dead_moment_verdicts_say() {
        let mut robot = crate::cases::prototype();
        robot.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
        let [rate, omega, _, _, grown] = compare(&robot, &Options::default(), 200.0, 40.0);
        assert!(rate > 1.0 && omega > 0.0);
        // e^(1.35 t) over the run's 4 s less Newmark's damping (0.3 to 0.5 1/s at 62 Hz,
        // which is why the rate is not compared here): 10 times at least.
        assert!(grown > 10.0, "{grown}");
        robot.loads.tip_moment = Vector3::new(2e-4, 1e-4, 0.0);
        let [rate, _, _, _, grown] = compare(&robot, &Options::default(), 200.0, 40.0);
        assert!(rate == 0.0 && grown < 2.0, "{grown}");
    }
}
