//! The order-8 residual of the collocation system: what estimates the error of the order-6
//! (deferred-corrected) solution, as the order-6 residual estimates the order-4 one's
//! (docs/numerics.md, "The order-6 answer").
//!
//! On an interval of length h in its local coordinates y = (p, theta, v, u)
//! ([`super::residual`]), the stages are explicit in the end points y_0, y_1 and their
//! rates F_0, F_1, on the grid t_i = i / 6 of the interval, by Picard sweeps: each sweep
//! evaluates F at the stages it has, interpolates F by the polynomial through those values
//! and F_0, F_1, and integrates it from both ends, weighted by the distance to each,
//!
//! ```text
//! y(t) = (1 - t) (y_0 + h integral_0^t P) + t (y_1 - h integral_t^1 P)
//!      = y_0 + h integral_0^t P + t (y_1 - y_0 - h integral_0^1 P).
//! ```
//!
//! A sweep with stage errors O(h^k) and an interpolant of degree d gives stages with errors
//! O(h^min(k + 1, d + 2)) (the last term is h times the integral of P's error). Integrated
//! from y_0 alone, the stages took any disagreement between the end points and the rates
//! for growth from y_0: on a slender rod the axial strain's last place (a force of EA eps)
//! became a shear strain h EA u eps / GA at the stages and a curvature h^2 EA u eps / (2 EI)
//! in the rows, which the order-6 and order-4 schemes (whose stages treat both ends alike)
//! do not see, and the estimate read it as an error (docs/numerics.md, "An estimate low on
//! a slender rod: the sweeps' one-sided stages"). Starting from the cubic Hermite interpolant of the end points
//! (O(h^4)) at t = 2/6, 4/6, sweeps through 4, 5, 6 and 7 points (2/6, 4/6; 1/6, 3/6, 5/6;
//! 1/6, 2/6, 4/6, 5/6; all five) give stages at 1/6 ... 5/6 with errors O(h^8), and the
//! residual is
//!
//! ```text
//! phi_8 = y_1 - y_0 - h * (41 (F_0 + F_1) + 216 (F_1/6 + F_5/6) + 27 (F_2/6 + F_4/6) + 272 F_3/6) / 840,
//! ```
//!
//! the 7-point Newton-Cotes rule (exact to degree 7) on those stages: a local error
//! O(h^9), a global order 8, at 19 evaluations of eq. 13 per interval (2 + 3 + 4 + 5 + 5).

use super::residual::{Block, IntervalSites, end_values, scale_rows};
use super::stage::{rhs_stage, stage};
use super::system::System;
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::solution::State;
use nalgebra::Vector6;
use std::sync::OnceLock;

/// The interior grid points of an interval, in sixths of h: t_i = GRID[i] / 6.
const GRID: [i64; 5] = [1, 2, 3, 4, 5];

/// The grid point `GRID[i]` as a fraction of the interval.
fn at(i: usize) -> f64 {
    GRID[i] as f64 / 6.0
}

/// The sweeps: which grid points (indices into [`GRID`]) hold the stages a sweep evaluates
/// F at, and which it writes new stages to. The first sweep evaluates the Hermite stages.
const SWEEPS: [(&[usize], &[usize]); 4] = [
    (&[1, 3], &[0, 2, 4]),
    (&[0, 2, 4], &[0, 1, 3, 4]),
    (&[0, 1, 3, 4], &[0, 1, 2, 3, 4]),
    (&[0, 1, 2, 3, 4], &[0, 1, 2, 3, 4]),
];

/// Integration weights of one sweep: `weights[o][j]` = the integral from 0 to the output
/// point o of the Lagrange basis polynomial of node j, nodes (0, the sweep's input points, 1).
type Weights = Vec<Vec<f64>>;

/// The weights of every sweep and of the final quadrature, computed once.
struct Tables {
    /// `sweeps[j][o]`: sweep j's weights of its output o, less t_o times the sweep's
    /// weights over the whole interval (the stage's share of what integrating from y0 alone
    /// misses at y1, [`rows`]).
    sweeps: Vec<Weights>,
    quadrature: Vec<f64>,
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let nodes = |points: &[usize]| -> Vec<i64> {
            std::iter::once(0)
                .chain(points.iter().map(|&i| GRID[i]))
                .chain(std::iter::once(6))
                .collect()
        };
        let sweeps = SWEEPS
            .iter()
            .map(|(input, output)| {
                let n = nodes(input);
                let whole = integrals(&n, 6);
                output
                    .iter()
                    .map(|&o| {
                        let t = Ratio::new(i128::from(GRID[o]), 6);
                        let to_o = integrals(&n, GRID[o]);
                        to_o.iter()
                            .zip(&whole)
                            .map(|(&a, &w)| a.add(t.mul(w).neg()).value())
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let quadrature = integrals(&nodes(&[0, 1, 2, 3, 4]), 6)
            .iter()
            .map(|r| r.value())
            .collect();
        Tables { sweeps, quadrature }
    })
}

/// A rational number p / q (q > 0), exact for the small integers of these weights.
#[derive(Clone, Copy)]
struct Ratio(i128, i128);

impl Ratio {
    fn new(p: i128, q: i128) -> Self {
        let g = gcd(p.abs(), q.abs()).max(1);
        let sign = if q < 0 { -1 } else { 1 };
        Ratio(sign * p / g, sign * q / g)
    }
    fn add(self, o: Ratio) -> Ratio {
        Ratio::new(self.0 * o.1 + o.0 * self.1, self.1 * o.1)
    }
    fn mul(self, o: Ratio) -> Ratio {
        Ratio::new(self.0 * o.0, self.1 * o.1)
    }
    fn neg(self) -> Ratio {
        Ratio(-self.0, self.1)
    }
    /// Rounded once.
    fn value(self) -> f64 {
        self.0 as f64 / self.1 as f64
    }
}

fn gcd(a: i128, b: i128) -> i128 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// The integrals from 0 to `s` / 6 of the Lagrange basis polynomials of the nodes
/// `nodes` / 6, exact in rationals (nodes and limit in sixths).
fn integrals(nodes: &[i64], s: i64) -> Vec<Ratio> {
    (0..nodes.len())
        .map(|j| {
            // Coefficients in tau = 6 t (lowest degree first) of
            // prod_{k != j} (tau - tau_k) / (tau_j - tau_k).
            let mut c = vec![Ratio(1, 1)];
            for (k, &tk) in nodes.iter().enumerate() {
                if k == j {
                    continue;
                }
                let d = i128::from(nodes[j] - tk);
                let mut next = vec![Ratio(0, 1); c.len() + 1];
                for (i, &ci) in c.iter().enumerate() {
                    next[i + 1] = next[i + 1].add(ci.mul(Ratio::new(1, d)));
                    next[i] = next[i].add(ci.mul(Ratio::new(-i128::from(tk), d)));
                }
                c = next;
            }
            // integral_0^(s/6) L dt = (1/6) integral_0^s L d tau
            c.iter().enumerate().fold(Ratio(0, 1), |acc, (i, &ci)| {
                let power = i128::from(s).pow(i as u32 + 1);
                acc.add(ci.mul(Ratio::new(power, 6 * (i as i128 + 1))))
            })
        })
        .collect()
}

/// The order-8 residual of one interval of length `h` with end points `y0`, `y1` and their
/// rates `f0`, `f1` (local coordinates), where `eval(i, inc)` is F at grid point i ([`at`])
/// with the stage y0 + inc (given as its increment from y0, so that the caller keeps what
/// y0 + inc rounds away, [`super::stage::stage`]). Unscaled rows.
///
/// # Errors
/// The errors of `eval`.
pub(super) fn rows(
    y0: &Block<f64>,
    y1: &Block<f64>,
    f0: &Block<f64>,
    f1: &Block<f64>,
    h: f64,
    mut eval: impl FnMut(usize, &Block<f64>) -> Result<Block<f64>>,
) -> Result<Block<f64>> {
    let tables = tables();
    // Each stage as its increment from y0 (the stage is y0 + increment).
    let mut stages = [Block::<f64>::zeros(); 5];
    // The cubic Hermite interpolant of the end points at the first sweep's inputs
    // (2 t^3 - 3 t^2 + 1 = 1 - (3 t^2 - 2 t^3)).
    let d = y1 - y0;
    for &i in SWEEPS[0].0 {
        let t = at(i);
        let (t2, t3) = (t * t, t * t * t);
        stages[i] = d * (3.0 * t2 - 2.0 * t3) + f0 * (h * (t3 - 2.0 * t2 + t)) + f1 * (h * (t3 - t2));
    }
    let mut rates = [Block::<f64>::zeros(); 5];
    for ((input, output), weights) in SWEEPS.iter().zip(&tables.sweeps) {
        for &i in *input {
            rates[i] = eval(i, &stages[i])?;
        }
        // Stage o is (1 - t) (y0 + h int_0^t P) + t (y1 - h int_t^1 P) at t = t_o: the
        // integral from y0 plus t_o times what it misses at y1 (the weights hold the
        // difference, [`Tables`]).
        for (&o, w) in output.iter().zip(weights) {
            let mut integral = f0 * w[0] + f1 * w[w.len() - 1];
            for (&i, wi) in input.iter().zip(&w[1..]) {
                integral += rates[i] * *wi;
            }
            stages[o] = integral * h + d * at(o);
        }
    }
    let w = &tables.quadrature;
    let mut integral = f0 * w[0] + f1 * w[6];
    for i in 0..5 {
        integral += eval(i, &stages[i])? * w[i + 1];
    }
    Ok(d - integral * h)
}

/// The order-8 rows of interval k between node states `a`, `b` (scaled as the order-4 rows),
/// given the rates (v', u') at both nodes.
#[allow(clippy::too_many_arguments)]
fn interval(
    model: &Model,
    sites: &IntervalSites,
    grid: &[Site; 5],
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: &Vector6<f64>,
    end_rates: &Vector6<f64>,
) -> Result<Block<f64>> {
    let h = sites.end.s - sites.start.s;
    let [y0, y1, f0, f1] = end_values(sites, a, b, start_rates, end_rates);
    let r = rows(&y0, &y1, &f0, &f1, h, |i, inc| {
        let (y, low) = stage(&grid[i], &y0, inc);
        rhs_stage(model, &grid[i], segment_end, &a.R, (&y, &low))
    })?;
    Ok(scale_rows(r, model.robot.length()))
}

/// The residual of the order-8 scheme at the states `x` into `out`: base, jump and tip rows
/// as in [`System::residual`], interval rows by the order-8 formula above. `local[k]` gets
/// link k's max-norm of its rows (0 for jumps), `rates[k]` the rates (v', u') at node k.
/// Systems with friction are not handled (their order-6 answer is not built).
///
/// # Errors
/// A model breakdown at a visited state.
pub(super) fn residual(
    system: &System,
    x: &[State],
    out: &mut [f64],
    local: &mut [f64],
    rates: &mut [Vector6<f64>],
) -> Result<()> {
    local.fill(0.0);
    let model = &system.model;
    system.rows(x, out, |k, sites, seg, a, b, start| {
        let (start, end) = system.end_rates(sites, seg, a, b, start)?;
        (rates[k], rates[k + 1]) = (start, end);
        let h = sites.end.s - sites.start.s;
        let grid: [Site; 5] = std::array::from_fn(|i| {
            if GRID[i] == 3 {
                sites.mid
            } else {
                model.site(sites.start.s + at(i) * h)
            }
        });
        let r = interval(model, sites, &grid, seg, a, b, &start, &end)?;
        local[k] = r.amax();
        Ok((r, end))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth, non-autonomous test equation y' = F(t, y), component i:
    /// (1 + i / 10) cos(t) y_i + sin(3 i t / 10).
    fn f(t: f64, y: &Block<f64>) -> Block<f64> {
        Block::from_fn(|i, _| (1.0 + 0.1 * i as f64) * t.cos() * y[i] + (0.3 * i as f64 * t).sin())
    }

    /// The exact solution's end value from t0 over h, by classical RK4 on 4096 steps (error
    /// about h^4 / 4096^4, far below the local errors measured).
    fn exact(t0: f64, y0: &Block<f64>, h: f64) -> Block<f64> {
        let n = 4096;
        let dt = h / n as f64;
        let mut y = *y0;
        for k in 0..n {
            let t = t0 + k as f64 * dt;
            let k1 = f(t, &y);
            let k2 = f(t + dt / 2.0, &(y + k1 * (dt / 2.0)));
            let k3 = f(t + dt / 2.0, &(y + k2 * (dt / 2.0)));
            let k4 = f(t + dt, &(y + k3 * dt));
            y += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (dt / 6.0);
        }
        y
    }

    #[test]
    fn the_quadrature_is_newton_cotes_7() {
        let w = &tables().quadrature;
        let expected = [41.0, 216.0, 27.0, 272.0, 27.0, 216.0, 41.0].map(|c| c / 840.0);
        for (a, b) in w.iter().zip(expected) {
            // 1e-17: exact rationals rounded once
            assert!((a - b).abs() < 1e-17, "{a} vs {b}");
        }
    }

    #[test]
    fn the_local_error_falls_like_h9() {
        let y0 = Block::from_fn(|i, _| 0.5 + 0.05 * i as f64);
        let t0 = 0.3;
        let local = |h: f64| {
            let y1 = exact(t0, &y0, h);
            let r = rows(&y0, &y1, &f(t0, &y0), &f(t0 + h, &y1), h, |i, inc| {
                Ok(f(t0 + at(i) * h, &(y0 + inc)))
            })
            .unwrap();
            r.amax()
        };
        // h = 0.2 and 0.1: local errors 4.6e-10 and 1.0e-12, far above rounding (8.0e-15 at
        // h = 0.05).
        let (a, b) = (local(0.2), local(0.1));
        let order = (a / b).log2();
        // 8.6: the local error is O(h^9); at these h the next term still shows (measured 8.81;
        // 8.34 between h = 0.4 and 0.2, where sweeps that integrated from y0 alone gave 8.9)
        assert!(order > 8.6, "local errors {a:.3e}, {b:.3e}: observed {order:.2}");
    }

    /// End points that disagree with the rates, as a node's rounded axial strain does on a
    /// slender rod (docs/numerics.md, "An estimate low on a slender rod: the sweeps' one-sided
    /// stages"): a chain a -> b -> c, b' = k3 a and c' = k1 b (the axial strain drives the
    /// shear strain's rate, the shear strain the curvature's), a = eps at both ends and b = c = 0
    /// there. b's row is the disagreement, -h k3 eps, in every scheme; c's row is 0 in the
    /// order-4 and order-6 schemes, whose stages treat both ends alike, and must be 0 here too.
    /// Sweeps that integrated from y0 alone built b = h k3 eps t at the stages and gave c's
    /// row -h^2 k1 k3 eps / 2, which the estimate read as an error of 1e-11 L.
    #[test]
    fn the_rows_treat_both_end_points_alike() {
        // tests/data/est14-guess-miss.toml's GA / EI (1/m^2), EA u / GA (1/m) and interval on 100 intervals
        // (m), and one ulp of an axial strain near 1.
        let (k1, k3, h, eps) = (3.3e7, 14.0, 5.9e-3, f64::EPSILON);
        let f = |y: &Block<f64>| {
            let mut f = Block::zeros();
            f[1] = k3 * y[0];
            f[2] = k1 * y[1];
            f
        };
        let mut y0 = Block::zeros();
        y0[0] = eps;
        let r = rows(&y0, &y0, &f(&y0), &f(&y0), h, |_, inc| Ok(f(&(y0 + inc)))).unwrap();
        let b_row = h * k3 * eps;
        // 1e-12: the 7-point weights sum to 1 up to rounding
        assert!((r[1] + b_row).abs() <= 1e-12 * b_row, "b's row {:e}", r[1]);
        // 1e-9 of what one-sided sweeps gave (h^2 k1 k3 eps / 2 = 1.1e-9): rounding of the
        // stages' weights only
        let one_sided = h * h * k1 * k3 * eps / 2.0;
        assert!(
            r[2].abs() <= 1e-9 * one_sided,
            "c's row {:e} against {one_sided:e}",
            r[2]
        );
    }
}
