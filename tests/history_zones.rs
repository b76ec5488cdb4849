//! Independent checks of the slip zones of a load history (docs/friction.md section 8,
//! "Slip zones inside a stuck stretch" and "tests25").
//!
//! The tendon's 1-D Coulomb problem on an answered step's shape is solved here by a method
//! the library does not use. With `z = ln tau`, the previous step's material `lambda_prev`
//! and the shape's path speed `a = |p'|` and turning rate `kappa`, the step's tension is the
//! minimiser of the convex problem
//!
//! ```text
//! minimise  integral of phi(s, z(s)) ds   over z with z(0) = ln tau(0), |z'| <= mu kappa,
//! phi(s, z) = lambda_prev z - a (z - ln(1 + e^z / (E_t A_t)))      (d phi / dz = lambda_prev - lambda)
//! ```
//!
//! whose optimality conditions are Coulomb's law: the multiplier `d` of the slope bound
//! obeys `d' = lambda_prev - lambda`, `d(l) = 0` (the termination holds its material), and
//! `z' = mu kappa sign(d)` where `d != 0`, so `d` is the slip and the multiplier
//! `w = z' / (mu kappa)` lies in [-1, 1] where it vanishes. On a fine uniform grid (the
//! objective by the trapezoidal rule, each cell's capacity `mu integral kappa` by Simpson's
//! rule on the shape's cubic Hermite interpolant) the discrete problem is solved by an
//! interior-point (log-barrier, damped Newton) method ([`coulomb`]): no march from the
//! base, no zones opened one by one, no bisection of a balance. The material of each step is carried along
//! by this solver too (from the step after a slack one, loaded from rest: full slip in), so
//! only the shapes come from the history.

use tdcr::analysis::equilibrium::imbalance;
use tdcr::analysis::history::{Contact, HistoryStep, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Parameter, Robot, Solution};

/// A 0.3 m nitinol rod under its own weight (0.2 N/m), two antagonistic straight tendons at
/// +-5 mm with mu 0.2 and E_t A_t 1500 N: a new user's robot of issue 24.
const NITINOL: &str = r#"
[rod]
length = 0.3
outer_radius = 0.0005
youngs_modulus = 60e9
poisson_ratio = 0.33

[base]
position = [0.0, 0.0, 0.0]

[loads]
distributed_force = [0.0, 0.0, -0.2]
tip_force = [0.0, 0.0, 0.0]

[[tendon]]
routing = { kind = "straight", x = 0.005, y = 0.0 }
tension = 0.0
friction = 0.2
stiffness = 1500.0

[[tendon]]
routing = { kind = "straight", x = -0.005, y = 0.0 }
tension = 0.0
friction = 0.2
stiffness = 1500.0
"#;

fn nitinol() -> Robot {
    tdcr::io::parse(NITINOL, "nitinol.toml").unwrap().robot
}

/// The nitinol rod's history of tendon 1's tension through `values`.
fn ranges(values: &[f64]) -> Ranges {
    Ranges::new(
        nitinol(),
        vec![(Input::Parameter(Parameter::Tension(0)), values.to_vec())],
    )
    .unwrap()
}

/// The up-down loop of the report: tendon 1 from 0 to 3 N in 10 steps and back (21 steps).
fn up_down() -> Ranges {
    let values: Vec<f64> = (0..=10).map(|k| 0.3 * k as f64).collect();
    ranges(&values).up_down()
}

/// The default options, or those with the tolerance `tolerance` (relative to L).
fn options(tolerance: Option<f64>) -> tdcr::collocation::Options {
    let mut options = tdcr::collocation::Options::default();
    if tolerance.is_some() {
        options.tolerance = tolerance;
    }
    options
}

fn solved(ranges: &Ranges, tolerance: Option<f64>) -> Vec<HistoryStep> {
    let result = history(ranges, &options(tolerance)).unwrap();
    if let Some((k, e)) = &result.failure {
        panic!("step {}: {e}", k + 1);
    }
    result.steps
}

/// The tendon with friction checked: tendon 1 (index 0).
const TENDON: usize = 0;

/// Fine-grid cells of the independent solve: h = 0.3 m / 12 000 = 2.5e-5 m.
const CELLS: usize = 12_000;

/// Tendon `i`'s path on `solution`'s shape at arc length `s`: its speed |p_i'| and its
/// turning rate kappa_i = |t_i'| (per unit s), from the cubic Hermite interpolant of
/// [`Solution::at`] (the rates v', u' by a central difference of it over 2e-7 m: a cubic's
/// difference error is 1e-14 relative, its rounding 1e-9 absolute in v', negligible against
/// kappa of order 1 to 10 1/m).
fn path(solution: &Solution, robot: &Robot, i: usize, s: f64) -> (f64, f64) {
    let length = robot.length();
    let here = solution.at(s);
    let (a, b) = ((s - 1e-7).max(0.0), (s + 1e-7).min(length));
    let (before, after) = (solution.at(a), solution.at(b));
    let v_s = (after.v - before.v) / (b - a);
    let u_s = (after.u - before.u) / (b - a);
    let r = robot.tendons[i].routing.at(s, length);
    let q = here.v + here.u.cross(&r.r) + r.r_s;
    let q_s = v_s + u_s.cross(&r.r) + here.u.cross(&r.r_s) + r.r_ss;
    let turn = here.u.cross(&q) + q_s;
    let t = q / q.norm();
    let normal = turn - t * t.dot(&turn);
    (q.norm(), normal.norm() / q.norm())
}

/// One step's tendon on the fine grid: node arc lengths, path speeds |p'| at the nodes, and
/// each cell's friction capacity C_j = mu integral of kappa (Simpson's rule: the cell is
/// 2.5e-5 m, so its error, h^5 kappa'''' / 2880, is below 1e-20).
struct Grid {
    s: Vec<f64>,
    speed: Vec<f64>,
    capacity: Vec<f64>,
}

impl Grid {
    /// The path's friction capacity summed from the base entry (mu times the turning angle),
    /// as a function of s: linear within each cell.
    fn turning(&self) -> impl Fn(f64) -> f64 + '_ {
        let h = self.s[1] - self.s[0];
        let mut turn = vec![0.0; CELLS + 1];
        for j in 0..CELLS {
            turn[j + 1] = turn[j] + self.capacity[j];
        }
        move |s: f64| {
            let j = ((s / h).floor() as usize).min(CELLS - 1);
            let t = (s - self.s[j]) / h;
            turn[j] * (1.0 - t) + turn[j + 1] * t
        }
    }
}

fn grid(solution: &Solution, robot: &Robot, i: usize) -> Grid {
    let end = robot.tendons[i].end(robot.length());
    let mu = robot.tendons[i].friction.unwrap().coefficient;
    let h = end / CELLS as f64;
    let s: Vec<f64> = (0..=CELLS).map(|j| h * j as f64).collect();
    let nodes: Vec<(f64, f64)> = s.iter().map(|&x| path(solution, robot, i, x)).collect();
    let capacity = (0..CELLS)
        .map(|j| {
            let middle = path(solution, robot, i, s[j] + 0.5 * h).1;
            mu * h / 6.0 * (nodes[j].1 + 4.0 * middle + nodes[j + 1].1)
        })
        .collect();
    Grid {
        s,
        speed: nodes.iter().map(|n| n.0).collect(),
        capacity,
    }
}

/// The independent answer of one step on the fine grid: log tension z at the nodes and each
/// cell's contact.
struct Coulomb {
    z: Vec<f64>,
    contact: Vec<Contact>,
}

/// Solves A x = b for a tridiagonal A (sub-diagonal `low[j]` = A[j+1][j], diagonal `diag`,
/// super-diagonal `up[j]` = A[j][j+1]) by Gaussian elimination with partial pivoting
/// (LAPACK's dgtsv).
fn tridiagonal(mut low: Vec<f64>, mut diag: Vec<f64>, mut up: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
    let n = diag.len();
    let mut fill = vec![0.0; n];
    for i in 0..n - 1 {
        if diag[i].abs() >= low[i].abs() {
            let f = low[i] / diag[i];
            diag[i + 1] -= f * up[i];
            b[i + 1] -= f * b[i];
        } else {
            let f = diag[i] / low[i];
            diag[i] = low[i];
            let t = diag[i + 1];
            diag[i + 1] = up[i] - f * t;
            if i + 2 < n {
                fill[i] = up[i + 1];
                up[i + 1] = -f * fill[i];
            }
            up[i] = t;
            let t = b[i];
            b[i] = b[i + 1];
            b[i + 1] = t - f * b[i + 1];
        }
        low[i] = 0.0;
    }
    let mut x = b;
    for i in (0..n).rev() {
        let mut r = x[i];
        if i + 1 < n {
            r -= up[i] * x[i + 1];
        }
        if i + 2 < n {
            r -= fill[i] * x[i + 2];
        }
        x[i] = r / diag[i];
    }
    x
}

/// The 1-D Coulomb problem (module docs) on `grid` with the material `previous` (unstretched
/// length per unit s at the grid's nodes), E_t A_t `stiffness` and base tension `tension`,
/// by an interior-point method: the log-barrier problem `sum_j q_j phi_j(z_j) - b sum_j
/// ln(C_j^2 - y_j^2)` (q the trapezoid weights, y_j = z_(j+1) - z_j the cells' changes of
/// log tension, z_0 the base's) by damped Newton (a tridiagonal Hessian; each step cut to 0.9
/// of the way to the bound), for barrier weights b from 1e-6 down to 1e-19 by factors of 10
/// (below that, Newton's steps in z no longer resolve a sliding cell's distance to its
/// bound, b / D_j). The changes y are the unknowns kept (z their sums), so that C_j - y_j is
/// resolved to 1e-16 of C_j, not of z. The cells' slips are the barrier's multipliers D_j =
/// b (1 / (C_j - y_j) - 1 / (C_j + y_j)) (the discrete d' = lambda_prev - lambda, D_N = 0):
/// as b falls, a sliding cell's D_j tends to its slip and a stuck cell's falls with b, so a
/// cell slides the way of its slip where D_j kept more than half its value over the last
/// tenfold fall of b, and sticks elsewhere (a stuck cell at the friction limit to 1e-4 has
/// D_j = 4e-11 m at b = 1e-19, so no threshold on D_j itself would do).
fn coulomb(grid: &Grid, previous: &[f64], stiffness: f64, tension: f64) -> Coulomb {
    let n = CELLS;
    let c = &grid.capacity;
    let h = grid.s[1] - grid.s[0];
    let weight = |k: usize| if k == n { 0.5 * h } else { h };
    let g = |k: usize, z: f64| {
        let e = z.exp() / stiffness;
        (
            previous[k] - grid.speed[k] / (1.0 + e),
            grid.speed[k] * e / ((1.0 + e) * (1.0 + e)),
        )
    };
    let sums = |y: &[f64]| {
        let mut z = vec![tension.ln(); n + 1];
        for j in 0..n {
            z[j + 1] = z[j] + y[j];
        }
        z
    };
    let slips = |b: f64, y: &[f64]| -> Vec<f64> { (0..n).map(|j| b / (c[j] - y[j]) - b / (c[j] + y[j])).collect() };
    let mut y = vec![0.0; n];
    let mut b = 1e-6;
    let mut last_slip = vec![0.0; n];
    loop {
        let mut converged = false;
        for _ in 0..200 {
            let z = sums(&y);
            let d1: Vec<f64> = (0..n).map(|j| b / (c[j] - y[j]) - b / (c[j] + y[j])).collect();
            let d2: Vec<f64> = (0..n)
                .map(|j| b / ((c[j] - y[j]) * (c[j] - y[j])) + b / ((c[j] + y[j]) * (c[j] + y[j])))
                .collect();
            // Newton in z_1..z_n (index k - 1).
            let (mut low, mut diag, mut up, mut rhs) = (vec![0.0; n - 1], vec![0.0; n], vec![0.0; n - 1], vec![0.0; n]);
            for k in 1..=n {
                let (value, slope) = g(k, z[k]);
                let q = weight(k);
                let mut gradient = q * value + d1[k - 1];
                diag[k - 1] = q * slope + d2[k - 1];
                if k < n {
                    gradient -= d1[k];
                    diag[k - 1] += d2[k];
                    up[k - 1] = -d2[k];
                    low[k - 1] = -d2[k];
                }
                rhs[k - 1] = -gradient;
            }
            let decrement: f64 = {
                let gradient = rhs.clone();
                let step = tridiagonal(low, diag, up, rhs);
                let dy: Vec<f64> = (0..n)
                    .map(|j| step[j] - if j > 0 { step[j - 1] } else { 0.0 })
                    .collect();
                let mut t = 1.0f64;
                for j in 0..n {
                    if dy[j] > 0.0 {
                        t = t.min(0.9 * (c[j] - y[j]) / dy[j]);
                    } else if dy[j] < 0.0 {
                        t = t.min(0.9 * (c[j] + y[j]) / -dy[j]);
                    }
                }
                for j in 0..n {
                    y[j] += t * dy[j];
                }
                if t < 1.0 {
                    f64::INFINITY
                } else {
                    step.iter().zip(&gradient).map(|(s, g)| s * g).sum::<f64>().abs()
                }
            };
            if decrement < 1e-3 * b {
                converged = true;
                break;
            }
        }
        assert!(
            converged,
            "the barrier problem at weight {b:e} did not converge in 200 Newton steps"
        );
        let slip = slips(b, &y);
        if b < 1e-19 {
            // a cell slides where its multiplier kept its value as b fell tenfold (it tends
            // to the slip), and sticks where it fell with b (it tends to 0)
            let contact = (0..n)
                .map(|j| match slip[j] / last_slip[j] {
                    r if r > 0.5 && slip[j] > 0.0 => Contact::Release,
                    r if r > 0.5 => Contact::Pull,
                    _ => Contact::Stick,
                })
                .collect();
            return Coulomb { z: sums(&y), contact };
        }
        last_slip = slip;
        b *= 0.1;
    }
}

/// The fine grid and independent answer of each step of a history (None where tendon 1 is
/// slack), the material carried from each to the next by the independent answers alone.
fn independent(ranges: &Ranges, steps: &[HistoryStep]) -> Vec<Option<(Grid, Coulomb)>> {
    let mut material: Option<Vec<f64>> = None;
    let mut answers = Vec::new();
    for (k, step) in steps.iter().enumerate() {
        let robot = ranges.robot(k as f64).unwrap();
        let tension = step.solution.tendons[TENDON].tension;
        if tension == 0.0 {
            material = None;
            answers.push(None);
            continue;
        }
        let stiffness = robot.tendons[TENDON].stiffness.unwrap();
        let grid = grid(&step.solution, &robot, TENDON);
        let answer = match &material {
            Some(previous) => coulomb(&grid, previous, stiffness, tension),
            // From rest: pulled in and sliding all along.
            None => {
                let mut z = vec![tension.ln(); CELLS + 1];
                for j in 0..CELLS {
                    z[j + 1] = z[j] - grid.capacity[j];
                }
                Coulomb {
                    z,
                    contact: vec![Contact::Pull; CELLS],
                }
            }
        };
        material = Some(
            (0..=CELLS)
                .map(|j| grid.speed[j] / (1.0 + answer.z[j].exp() / stiffness))
                .collect(),
        );
        answers.push(Some((grid, answer)));
    }
    answers
}

/// The independent answer's zones: runs of cells with one contact, (start, end, contact),
/// a run of at most two cells (the cell where two zones meet, whose slip crosses 0 inside
/// it) shared out between its neighbours at its middle.
fn zones(grid: &Grid, answer: &Coulomb) -> Vec<(f64, f64, Contact)> {
    let mut runs: Vec<(f64, f64, Contact)> = Vec::new();
    for (j, &c) in answer.contact.iter().enumerate() {
        match runs.last_mut() {
            Some(last) if last.2 == c => last.1 = grid.s[j + 1],
            _ => runs.push((grid.s[j], grid.s[j + 1], c)),
        }
    }
    let h = grid.s[1] - grid.s[0];
    let mut list: Vec<(f64, f64, Contact)> = Vec::new();
    let mut cut: Option<f64> = None;
    for run in runs {
        if run.1 - run.0 < 2.5 * h {
            let middle = 0.5 * (run.0 + run.1);
            match list.last_mut() {
                Some(last) => last.1 = middle,
                None => cut = Some(middle),
            }
            cut = Some(middle).or(cut);
            continue;
        }
        let start = cut.take().unwrap_or(run.0);
        match list.last_mut() {
            Some(last) if last.2 == run.2 => last.1 = run.1,
            _ => list.push((start, run.1, run.2)),
        }
    }
    if let Some(last) = list.last_mut() {
        last.1 = *grid.s.last().unwrap();
    }
    list
}

/// The independent log tension at arc length `s`, linear between the grid's nodes.
fn log_tension(grid: &Grid, answer: &Coulomb, s: f64) -> f64 {
    let h = grid.s[1] - grid.s[0];
    let j = ((s / h).floor() as usize).min(CELLS - 1);
    let t = (s - grid.s[j]) / h;
    answer.z[j] * (1.0 - t) + answer.z[j + 1] * t
}

/// The history's own log tension of tendon 1 on `grid`'s nodes: its node values, between
/// nodes linear in the path's turning angle (the capstan law's own variable: exact on a
/// link with one multiplier w, as every link of a sliding zone has).
fn code_log_tension(step: &HistoryStep, grid: &Grid) -> Vec<f64> {
    let solution = &step.solution;
    let turn_at = grid.turning();
    let end = *grid.s.last().unwrap();
    let mut points: Vec<(f64, f64)> = Vec::new();
    for node in &solution.nodes {
        if points.last().is_some_and(|p| node.s <= p.0) || node.s > end + 1e-15 {
            continue;
        }
        points.push((node.s, solution.tension_at(TENDON, node.s).unwrap().ln()));
    }
    let mut k = 0;
    grid.s
        .iter()
        .map(|&s| {
            while k + 2 < points.len() && points[k + 1].0 <= s {
                k += 1;
            }
            let ((a, za), (b, zb)) = (points[k], points[k + 1]);
            let span = turn_at(b) - turn_at(a);
            if span > 0.0 {
                za + (zb - za) * (turn_at(s) - turn_at(a)) / span
            } else {
                za + (zb - za) * (s - a) / (b - a)
            }
        })
        .collect()
}

/// The slip d of tendon 1 during `step` by the history's own answers: d(s) = integral from
/// s to the termination of lambda - lambda_prev, each material |p'| / (1 + tau / E_t A_t)
/// of its step's shape and tension on the fine grids (the same s), by the trapezoidal rule.
fn code_slip(before: (&HistoryStep, &Grid), after: (&HistoryStep, &Grid), stiffness: f64) -> Vec<f64> {
    let material = |(step, grid): (&HistoryStep, &Grid)| -> Vec<f64> {
        code_log_tension(step, grid)
            .iter()
            .zip(&grid.speed)
            .map(|(z, a)| a / (1.0 + z.exp() / stiffness))
            .collect()
    };
    let (old, new) = (material(before), material(after));
    let h = after.1.s[1] - after.1.s[0];
    let mut d = vec![0.0; CELLS + 1];
    for j in (0..CELLS).rev() {
        d[j] = d[j + 1] + 0.5 * h * ((new[j] - old[j]) + (new[j + 1] - old[j + 1]));
    }
    d
}

/// Coulomb's law on the history's own answer of `step` (after `before`), zone by zone: for
/// each zone its contact, the slip d at its start and the most adverse value of the slip
/// against the zone's friction (d > 0 in a pull zone, d < 0 in a release zone; 0 when none),
/// and on a stuck zone the largest |w| of its links (w = the link's change of log tension
/// over its capacity mu integral kappa).
struct Law {
    contact: Contact,
    start: f64,
    slip_at_start: f64,
    against: f64,
    largest_w: f64,
}

fn law(before: (&HistoryStep, &Grid), after: (&HistoryStep, &Grid), stiffness: f64) -> Vec<Law> {
    let (step, grid) = after;
    let d = code_slip(before, after, stiffness);
    let h = grid.s[1] - grid.s[0];
    let index = |s: f64| ((s / h).round() as usize).min(CELLS);
    let turn_at = grid.turning();
    let solution = &step.solution;
    let mut nodes: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    nodes.dedup();
    step.zones[0]
        .zones
        .iter()
        .map(|z| {
            let (a, b) = (index(z.start), index(z.end));
            // the slip against the friction, away from the zone's ends by 2 cells
            let inner = &d[(a + 2).min(b)..b.saturating_sub(2).max(a)];
            let against = match z.contact {
                Contact::Pull => inner.iter().fold(0.0f64, |m, &x| m.max(x)),
                Contact::Release => inner.iter().fold(0.0f64, |m, &x| m.min(x)),
                _ => 0.0,
            };
            let largest_w = if z.contact == Contact::Stick {
                nodes
                    .windows(2)
                    .filter(|w| w[0] >= z.start - 1e-12 && w[1] <= z.end + 1e-12)
                    .map(|w| {
                        let rise = solution.tension_at(TENDON, w[1]).unwrap().ln()
                            - solution.tension_at(TENDON, w[0]).unwrap().ln();
                        (rise / (turn_at(w[1]) - turn_at(w[0]))).abs()
                    })
                    .fold(0.0, f64::max)
            } else {
                0.0
            };
            Law {
                contact: z.contact,
                start: z.start,
                slip_at_start: d[a],
                against,
                largest_w,
            }
        })
        .collect()
}

/// The width of the history's link at a zone end `s` of `step`: the larger of its node
/// spacings on either side (a zone end is reported at a node, and the meeting it stands for
/// lies within a link of it).
fn link_at(step: &HistoryStep, s: f64) -> f64 {
    let mut nodes: Vec<f64> = step.solution.nodes.iter().map(|n| n.s).collect();
    nodes.dedup();
    let k = nodes.partition_point(|&x| x < s).clamp(1, nodes.len() - 1);
    let next = nodes.get(k + 1).map_or(0.0, |n| n - nodes[k]);
    (nodes[k] - nodes[k - 1]).max(next)
}

#[test]
fn the_nitinol_loop_is_answered_with_zones_from_where_the_base_zone_meets_them() {
    // Before slip24 (2026-12-07) main refused step 12 (the first step back) with |w| = 1.026
    // on a stuck link: this history was not answered, so this test failed there.
    let ranges = up_down();
    let steps = solved(&ranges, None);
    assert_eq!(steps.len(), 21);
    let mut meeting = 0.0;
    for (k, step) in steps.iter().enumerate() {
        let report = &step.solution.report;
        assert_eq!(report.tolerance_met, Some(true), "step {}", k + 1);
        let e = imbalance(&ranges.robot(k as f64).unwrap(), &step.solution);
        // 1e-8: the solver's tolerance in the wrenches relative to the tension, as for the
        // full-slip solves (tests/history.rs)
        assert!(e.max() < 1e-8, "step {}: imbalance {e:?}", k + 1);
        let zones = &step.zones[0].zones;
        let contacts: Vec<Contact> = zones.iter().map(|z| z.contact).collect();
        match k + 1 {
            1 | 21 => assert_eq!(contacts, [Contact::Slack]),
            2..=11 => assert_eq!(contacts, [Contact::Pull]),
            12..=15 => {
                // let out at the base, pulled in beyond where the two meet: the zone that
                // reaches the termination starts inside the base zone
                assert_eq!(contacts, [Contact::Release, Contact::Pull], "step {}", k + 1);
                assert!(zones[0].end > meeting, "the meeting point moves toward the tip");
                meeting = zones[0].end;
            }
            _ => assert_eq!(contacts, [Contact::Release]),
        }
    }
}

#[test]
fn the_nitinol_loops_estimates_are_honest_against_a_tight_history() {
    let steps = solved(&up_down(), None);
    let tight = solved(&up_down(), Some(1e-10));
    for (k, (step, exact)) in steps.iter().zip(&tight).enumerate().skip(1) {
        let error = (step.solution.tip_position() - exact.solution.tip_position()).norm();
        let estimate = step.solution.report.error_estimate.unwrap().tip_position;
        let bound = exact.solution.report.error_estimate.unwrap().tip_position;
        eprintln!(
            "step {}: error {error:.3e} m, estimate {estimate:.3e} m, ratio {:.3}",
            k + 1,
            error / estimate
        );
        // an estimate must not be below the error, the tight history's own estimate (below
        // 3e-10 m; its zoned steps reach the interval cap) counted as the reference's error;
        // a sliding step's deferred correction is its error to a fraction of a percent
        // (measured 0.996 to 1.007): 1 % for that, as in tests/history.rs
        // 1e-13 m: rounding, for the slack steps (measured 3.5e-15 m)
        let slack = if step.zones[0].zones.len() > 1 { 1.0 } else { 1.01 };
        assert!(
            error <= slack * estimate + bound + 1e-13,
            "step {}: error {error:e}, estimate {estimate:e}",
            k + 1
        );
    }
}

/// Checks the history's zones and tensions of `steps` (of `ranges`) against the
/// independent solve, step by step; returns the largest tension difference of a step with
/// more than one zone (relative to the base tension) beyond what the offset of its zone
/// ends explains (mu kappa at the end times the offset, summed over the ends).
fn check_independent(ranges: &Ranges, steps: &[HistoryStep], only: impl Fn(usize) -> bool) -> f64 {
    let answers = independent(ranges, steps);
    let mut largest = 0.0f64;
    for (k, (step, answer)) in steps.iter().zip(&answers).enumerate() {
        let Some((grid, answer)) = answer else { continue };
        if !only(k + 1) {
            continue;
        }
        let h = grid.s[1] - grid.s[0];
        let mine = zones(grid, answer);
        let code = &step.zones[0].zones;
        let contacts: Vec<Contact> = code.iter().map(|z| z.contact).collect();
        let own: Vec<Contact> = mine.iter().map(|z| z.2).collect();
        assert_eq!(contacts, own, "step {}: history {code:?}, independent {mine:?}", k + 1);
        let mut ends = Vec::new();
        // the log tension beyond a meeting point is off by mu kappa times the point's offset
        let mut moved = 0.0f64;
        for (z, m) in code.iter().zip(&mine).take(code.len() - 1) {
            // the history's end within its link at the end, the independent one within the
            // 1.5 cells of its meeting cell
            let allowed = link_at(step, z.end) + 1.5 * h;
            let off = (z.end - m.1).abs();
            eprintln!(
                "step {}: zone end {:.6} m, independent {:.6} m ({off:.1e} m, allowed {allowed:.1e})",
                k + 1,
                z.end,
                m.1
            );
            assert!(off <= allowed, "step {}: zone end {} vs {} m", k + 1, z.end, m.1);
            let j = ((m.1 / h) as usize).min(CELLS - 1);
            moved += grid.capacity[j] / h * off;
            let link = link_at(step, z.end);
            ends.push(((z.end - link).min(m.1 - 2.0 * h), (z.end + link).max(m.1 + 2.0 * h)));
        }
        // the tension at the history's nodes away from the ends: outside the history's links
        // on either side of its end (its kink lies within a link of it) and the independent
        // end's cells
        let solution = &step.solution;
        let base = solution.tendons[TENDON].tension;
        let mut worst = 0.0f64;
        let mut last = f64::NEG_INFINITY;
        for node in &solution.nodes {
            if node.s <= last || ends.iter().any(|(a, b)| node.s > *a && node.s < *b) {
                continue;
            }
            last = node.s;
            let tau = solution.tension_at(TENDON, node.s).unwrap();
            worst = worst.max((tau - log_tension(grid, answer, node.s).exp()).abs() / base);
        }
        eprintln!(
            "step {}: largest tension difference {worst:.2e} of the base tension ({:.2e} beyond the ends' offset)",
            k + 1,
            (worst - moved).max(0.0)
        );
        if code.len() > 1 {
            largest = largest.max(worst - moved);
        } else {
            // one zone all along: the same capstan profile on the same shape; the
            // history's capacities are Simpson's rule on its links with the collocation's
            // own rates at the midpoints, the independent ones on 2.5e-5 m cells of the
            // cubic interpolant (measured 2.1e-12 on 32 intervals, 1.8e-10 on 150)
            assert!(worst < 1e-9, "step {}: {worst:e}", k + 1);
        }
    }
    largest
}

#[test]
fn the_nitinol_loops_zones_agree_with_an_independent_coulomb_solve() {
    let ranges = up_down();
    let steps = solved(&ranges, None);
    let largest = check_independent(&ranges, &steps, |_| true);
    // beyond the zone ends' offsets (up to 3.2e-4 m at step 15: the history's meeting
    // point lies within its link, 2e-3 m there; its log tension beyond is off by mu kappa
    // that, 6.1e-5): a meeting point is where the material over the zone beyond it
    // balances, so a relative error e in the material moves it by about e / (mu kappa tau /
    // E_t A_t) and the log tension beyond it by e E_t A_t / tau: 1e-9 (the shape between the
    // history's nodes, read by either side) gives 5e-7. Measured below 4.7e-6 (steps 13 and
    // 14 about the same at --tol 1e-10, so not the step's mesh): 1e-5.
    assert!(largest < 1e-5, "largest tension difference {largest:e}");
}

#[test]
fn a_partial_reversals_zones_agree_with_an_independent_coulomb_solve() {
    // 3 N, back to 2.9 and 2.8 N: steps 3 and 4 slide out at the base and in beyond, as the
    // loop's steps back do, on 152 intervals.
    let ranges = ranges(&[0.0, 3.0, 2.9, 2.8]);
    let steps = solved(&ranges, None);
    let largest = check_independent(&ranges, &steps, |_| true);
    // as for the loop (measured 3.3e-6 and 9.6e-6)
    assert!(largest < 2e-5, "largest tension difference {largest:e}");
}

#[test]
fn the_tight_nitinol_loops_zones_agree_with_an_independent_coulomb_solve() {
    // The same at --tol 1e-10 (2 496 intervals on the zoned steps: links of 1.2e-4 m).
    let ranges = up_down();
    let steps = solved(&ranges, Some(1e-10));
    let largest = check_independent(&ranges, &steps, |k| (11..=16).contains(&k));
    // as for the default loop (measured below 4.8e-6)
    assert!(largest < 1e-5, "largest tension difference {largest:e}");
}

/// Coulomb's law on the history's own answers of `steps` (of `ranges`), step by step from
/// the second: on stuck zones |w| <= 1 + 1e-4 (the slip check's cone), in sliding zones the
/// slip of the friction's sign away from the zone's ends, and at the start of a zone that
/// starts inside the tendon the slip 0 (its material balance). A zone end is reported at a
/// node, with the meeting it stands for within the link there, so the slip there may be up
/// to the slope of d (lambda_prev - lambda, read on the zone's first cells) times the link;
/// with 1e-10 m for the integration of d (trapezoids of 2.5e-5 m; each side's tension read
/// between the history's nodes linearly in the turning angle).
fn check_law(ranges: &Ranges, steps: &[HistoryStep]) -> (f64, f64) {
    let answers = independent(ranges, steps);
    let (mut balance, mut against) = (0.0f64, 0.0f64);
    for k in 1..steps.len() {
        let (Some((g0, _)), Some((g1, _))) = (&answers[k - 1], &answers[k]) else {
            continue;
        };
        let stiffness = ranges.robot(k as f64).unwrap().tendons[TENDON].stiffness.unwrap();
        let d = code_slip((&steps[k - 1], g0), (&steps[k], g1), stiffness);
        let h = g1.s[1] - g1.s[0];
        for l in law((&steps[k - 1], g0), (&steps[k], g1), stiffness) {
            let j = ((l.start / h).round() as usize).min(CELLS - 4);
            let slope = (d[j + 4] - d[j]).abs() / (4.0 * h);
            let allowed = slope * link_at(&steps[k], l.start) + 1e-10;
            eprintln!(
                "step {}: {:?} from {:.5} m: slip at the start {:.2e} m (allowed {allowed:.1e}), against the friction {:.2e} m, |w| {:.6}",
                k + 1,
                l.contact,
                l.start,
                l.slip_at_start,
                l.against,
                l.largest_w
            );
            assert!(
                l.largest_w <= 1.0 + 1e-4,
                "step {}: |w| {} on a stuck zone",
                k + 1,
                l.largest_w
            );
            if l.start > 0.0 && l.contact != Contact::Stick {
                balance = balance.max(l.slip_at_start.abs() - allowed);
            }
            if l.contact != Contact::Stick {
                against = against.max(l.against.abs() - allowed);
            }
        }
    }
    (balance, against)
}

/// Asserts [`check_law`]: every zone's slip at its start and against its friction within
/// the allowance.
fn obeys_coulomb(ranges: &Ranges, steps: &[HistoryStep]) {
    let (balance, against) = check_law(ranges, steps);
    assert!(
        balance <= 0.0,
        "a zone's slip at its start exceeds the allowance by {balance:e} m"
    );
    assert!(
        against <= 0.0,
        "a zone slides against its friction by {against:e} m beyond the allowance"
    );
}

#[test]
fn the_nitinol_loops_zones_obey_coulombs_law() {
    let ranges = up_down();
    let steps = solved(&ranges, None);
    obeys_coulomb(&ranges, &steps);
}

#[test]
#[ignore = "fails on main (ed634ba): step 5 of this history, answered (tolerance missed), slides \
            against its friction and does not balance; the independent solve finds another pattern"]
fn a_second_reversal_obeys_coulombs_law() {
    // 3 N, back to 2.9 and 2.8 N, up to 2.9 and 3 N. Measured on main: step 5's release
    // zone from 0.0138 m has slip -4.7e-8 m all along (against its friction), its pull
    // zone from 0.0283 m starts with slip -6.7e-8 m (1.7e-6 of its length, 170 times the
    // slip check's BALANCE), and the independent solve's pattern differs (pull, release,
    // pull to 0.049 m, stick to 0.067 m, pull to the termination; the history: pull,
    // release, stick, pull to 0.067 m, stick to the termination), its tension 8.6e-4 of the
    // base tension apart. At --tol 1e-10 main refuses the step (the zone from 0.0136 m
    // "does not hold its material", -1.0e-9 m across its start).
    let ranges = ranges(&[0.0, 3.0, 2.9, 2.8, 2.9, 3.0]);
    let steps = solved(&ranges, None);
    obeys_coulomb(&ranges, &steps);
    check_independent(&ranges, &steps, |_| true);
}

#[test]
fn a_loop_back_through_full_slip_closes() {
    // 0, 1, 2, 3, 2, 1, 2, 3 N: step 6 (1 N) slides out all along and steps 7 and 8 in all
    // along, so they are the full-slip pull solves of 2 and 3 N, whatever came before.
    let steps = solved(&ranges(&[0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 2.0, 3.0]), None);
    let contacts = |k: usize| -> Vec<Contact> { steps[k - 1].zones[0].zones.iter().map(|z| z.contact).collect() };
    assert_eq!(contacts(5), [Contact::Release, Contact::Pull]);
    assert_eq!(contacts(6), [Contact::Release]);
    for (again, first) in [(7, 3), (8, 4)] {
        assert_eq!(contacts(again), [Contact::Pull]);
        let (a, b) = (&steps[again - 1].solution, &steps[first - 1].solution);
        let gap = (a.tip_position() - b.tip_position()).norm();
        let estimates = a.report.error_estimate.unwrap().tip_position + b.report.error_estimate.unwrap().tip_position;
        eprintln!("step {again} vs step {first}: {gap:.2e} m apart, estimates {estimates:.2e} m");
        // the same solve to the two answers' estimated errors (measured 1.2e-11 and 4.4e-12 m)
        assert!(gap <= estimates, "step {again} is {gap:e} m from step {first}");
    }
}

#[test]
fn a_minor_loop_that_does_not_reach_full_slip_does_not_close() {
    // 3 N and back to 2.7 N three times: every step down slides out at the base and in
    // beyond where the two meet, to the termination; every step up pulls in a base zone and
    // leaves the rest stuck with the material the step down left. So the tendon beyond the
    // base zone gains material toward the actuator on every cycle and the tip at 3 N creeps
    // on (measured 8.7e-6, 9.4e-6, 7.9e-6 m per cycle in tip x; the estimates 3e-9 to
    // 6e-9 m): Coulomb's law holds on every step, checked as for the nitinol loop.
    let ranges = ranges(&[0.0, 3.0, 2.7, 3.0, 2.7, 3.0, 2.7, 3.0]);
    let steps = solved(&ranges, None);
    let (balance, against) = check_law(&ranges, &steps);
    assert!(
        balance <= 0.0 && against <= 0.0,
        "balance {balance:e}, against {against:e}"
    );
    // The steps down are the nitinol loop's first step back (checked against the
    // independent solve there). The steps up are not compared with it: their stuck
    // stretches sit at |w| = 0.99999 (the material the step down left, which slid in at the
    // full rate), so where the base zone ends is ill-conditioned (a change dz of the log
    // tension moves it by dz / (mu kappa (1 - |w|)), 1e-3 m for 1e-8); the independent end
    // at step 4 is 0.1374 m, the history's 0.1348 m.
    let mut last = steps[1].solution.tip_position();
    for k in [4, 6, 8] {
        let solution = &steps[k - 1].solution;
        let contacts: Vec<Contact> = steps[k - 1].zones[0].zones.iter().map(|z| z.contact).collect();
        assert_eq!(contacts, [Contact::Pull, Contact::Stick], "step {k}");
        let creep = solution.tip_position()[0] - last[0];
        let estimate = solution.report.error_estimate.unwrap().tip_position;
        eprintln!(
            "step {k}: tip x {:.2e} m beyond the last time at 3 N, estimate {estimate:.1e} m",
            creep
        );
        // a creep of the same sign each cycle, over 100 times the estimate
        assert!(
            creep > 100.0 * estimate,
            "step {k}: creep {creep:e} m, estimate {estimate:e} m"
        );
        last = solution.tip_position();
    }
}

#[test]
fn a_zoned_steps_observed_order_is_two_as_its_estimate_says() {
    // The nitinol loop's first step back at tolerances 1e-5, 1e-6 and 1e-7 L: the split
    // levels double its intervals (76, 152, 304), against the history at --tol 1e-10
    // (2 496 intervals, estimate 2.6e-10 m). The zone's transition link holds one multiplier
    // w_T across it, and the meeting point it stands for lies inside it, so its tension has
    // a kink a link cannot follow: second order, which the step's estimate says
    // (`ErrorEstimate.order` 2), not the fourth order of a stuck step's split levels.
    let tight = solved(&up_down(), Some(1e-10));
    let exact = tight[11].solution.tip_position();
    let mut last: Option<(usize, f64)> = None;
    for tolerance in [1e-5, 1e-6, 1e-7] {
        let steps = solved(&up_down(), Some(tolerance));
        let solution = &steps[11].solution;
        let estimate = solution.report.error_estimate.unwrap();
        assert_eq!(estimate.order, 2);
        let error = (solution.tip_position() - exact).norm();
        let intervals = solution.report.intervals;
        if let Some((n, e)) = last {
            let order = (e / error).ln() / (intervals as f64 / n as f64).ln();
            eprintln!("{n} -> {intervals} intervals: tip error {e:.3e} -> {error:.3e} m, observed order {order:.2}");
            // measured 1.94 and 1.77 (the second with the reference's 2.6e-10 m in an error
            // of 3.8e-9 m): 2 to within 0.5
            assert!((order - 2.0).abs() < 0.5, "observed order {order}");
        }
        last = Some((intervals, error));
    }
}

#[test]
#[ignore = "fails on main (ed634ba): the nitinol loop at --tol 1e-8 is refused at step 15"]
fn the_nitinol_loop_is_answered_at_a_tolerance_of_1e_8() {
    // Main answers the loop at the default tolerance (1e-7 L) and at 1e-10, but at 1e-8 it
    // refuses step 15: "tendon 1's slip zone from s = 0.2775 m to 0.3000 m does not hold its
    // material in this step (it moves 1.055e-7 m across its start, allowed 2.2e-10 m)". The
    // zone's meeting point is 0.2804 m on the other two (0.2800 and 0.2804 m reported).
    let steps = solved(&up_down(), Some(1e-8));
    assert_eq!(steps.len(), 21);
}
