//! A link of a split level's mesh where a loaded tendon sticks, with its tangential load
//! point by point (docs/friction.md section 8, "Order 4 on stuck links").
//!
//! On a stuck link the log tension is the stuck material's, z = zeta(s). The link's rows
//! take its rate z' at the two nodes and the midpoint from the quadratic q through
//! (z_a, zeta_m, z_b), zeta_m the stuck material's log tension at the midpoint state y_m
//! (lambda there carried by the level's grip, [`super::Grip::midpoints`]):
//!
//! ```text
//! r_a = (-3 z_a + 4 zeta_m - z_b) / h,   r_m = (z_b - z_a) / h,   r_b = (z_a - 4 zeta_m + 3 z_b) / h
//! ```
//!
//! each the given relative rate tau' / tau of the tangential load tau r t at its point
//! (explicit: `model/tangential.rs`'s given slips). Hermite-Simpson's midpoint is then
//! z_m = zeta_m, and the quadratic's slope errors (h^2 zeta'''/12 at the ends,
//! -h^2 zeta'''/24 at the midpoint) cancel in Simpson's weights and in the midpoint's
//! h/8 (F_a - F_b): the link is of order 4 where the stuck profile is smooth. Since y_m
//! depends on F_a and F_b, hence on zeta_m, zeta_m solves zeta_m = Z(y_m(zeta_m)) per stuck
//! tendon inside the evaluation ([`midpoint`]). The Jacobian is exact: the link's at fixed
//! rates, plus the rows' columns in the rates times the rates' derivatives, whose zeta_m
//! part follows from the implicit function theorem,
//! `d zeta / dX = (I - dZ/d zeta)^-1 dZ/dX` (one small solve per link).

use super::interval::{IntervalLinearization, interval_at};
use super::profile::Profile;
use crate::collocation::residual::IntervalSites;
use crate::error::Result;
use crate::solution::State;
use crate::{Error, dense};
use nalgebra::{DMatrix, SMatrix, Vector3, Vector6};

/// A pointwise stuck link's extra derivatives from [`interval_at`] (this module):
/// the rows' columns in the given relative rates, and the midpoint's strains (v_m, u_m)
/// with their derivatives, at fixed rates.
#[derive(Debug)]
pub(super) struct Columns {
    /// The midpoint's strains v_m, u_m (u unscaled).
    pub(super) vm: Vector3<f64>,
    pub(super) um: Vector3<f64>,
    /// d(backbone rows (scaled), then psi)/dr: (12 + k) x 3k, columns r_a of slip l (l),
    /// r_m (k + l), r_b (2k + l).
    pub(super) rows_r: DMatrix<f64>,
    /// d(v_m, u_m)/d(the 18 columns of the midpoint: theta, v, u L of node a, then b).
    pub(super) d_ym: SMatrix<f64, 6, 18>,
    /// d(v_m, u_m)/dz: 6 x 2k, columns z_a of every slip, then z_b.
    pub(super) d_ym_z: DMatrix<f64>,
    /// d(v_m, u_m)/dr: 6 x 2k, columns r_a of every slip, then r_b.
    pub(super) d_ym_r: DMatrix<f64>,
}

impl Columns {
    /// Empty columns for `count` slips.
    pub(super) fn new(count: usize) -> Self {
        Columns {
            vm: Vector3::zeros(),
            um: Vector3::zeros(),
            rows_r: DMatrix::zeros(12 + count, 3 * count),
            d_ym: SMatrix::zeros(),
            d_ym_z: DMatrix::zeros(6, 2 * count),
            d_ym_r: DMatrix::zeros(6, 2 * count),
        }
    }
}

/// Iterations at most of the inner solve for zeta_m ([`midpoint`]): Newton on the affine
/// model converges quadratically from Hermite's z_m in three or four; the secant of the
/// general case in five to eight.
const ITERATIONS: usize = 30;

/// The midpoint's strains (v_m, u_m) for a zeta_m, and their change with each stuck
/// zeta_m where it is affine (None elsewhere).
type Strains = (Vector6<f64>, Option<Vec<Vector6<f64>>>);

/// A stuck log tension at the midpoint and its gradient in the midpoint's strains.
type Gradient = (f64, Vector6<f64>);

/// The reason a midpoint's stuck tension is refused (not positive).
const SLACK: &str = "the stuck tension at a link's midpoint is not positive";

/// Link k with the pointwise load of its stuck slips (module docs); the other slips keep
/// their multipliers `w`. Arguments as [`super::interval::interval`].
///
/// None where a stuck tension at the midpoint is not positive on the way (the material
/// there would go slack if it stuck: the link is far from sticking, and the march that
/// reads it takes the constant multiplier's evaluation instead).
///
/// # Errors
/// A model breakdown at a point.
#[allow(clippy::too_many_arguments)]
pub(super) fn interval(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    w: &[f64],
    jac: Option<&mut [f64]>,
) -> Result<Option<IntervalLinearization>> {
    let count = profile.count();
    let h = sites.end.s - sites.start.s;
    let za: Vec<f64> = profile.z.iter().map(|z| z[k]).collect();
    let zb: Vec<f64> = profile.z.iter().map(|z| z[k + 1]).collect();
    let stuck: Vec<usize> = (0..count)
        .filter(|&j| {
            profile.on_link(j, k)
                && profile.sticks(j, k)
                && profile.base[j] > 0.0
                && profile.material_at_midpoint(j, k).is_finite()
        })
        .collect();
    let lambda: Vec<f64> = stuck.iter().map(|&j| profile.material_at_midpoint(j, k)).collect();
    // The three points' multipliers for the stuck log tensions `zeta` at the midpoint: the
    // other slips' w, then the flags of the given rates.
    let points = |zeta: &[f64]| -> [Vec<f64>; 3] {
        let mut out: [Vec<f64>; 3] = std::array::from_fn(|_| {
            let mut v = w.to_vec();
            v.resize(2 * count, 0.0);
            v
        });
        for (&j, &zm) in stuck.iter().zip(zeta) {
            let rates = [
                (-3.0 * za[j] + 4.0 * zm - zb[j]) / h,
                (zb[j] - za[j]) / h,
                (za[j] - 4.0 * zm + 3.0 * zb[j]) / h,
            ];
            let mu = profile.coefficient(j);
            for (p, rate) in out.iter_mut().zip(rates) {
                p[j] = rate / mu;
                p[count + j] = 1.0;
            }
        }
        out
    };
    // The midpoint's strains (v_m, u_m) of Hermite-Simpson for `zeta`, and their change
    // with each stuck zeta_m where the nodes' rates are affine in the given rates (every
    // slip there given: then exact).
    let strains = |zeta: &[f64]| -> Result<Strains> {
        let [wa, _, wb] = points(zeta);
        let la = profile.point(&sites.start, segment_end, &a.R, (&a.v, &a.u), &za, Some(&wa), false)?;
        let lb = profile.point(&sites.end, segment_end, &b.R, (&b.v, &b.u), &zb, Some(&wb), false)?;
        let (xa, xb) = (la.lin.rates, lb.lin.rates);
        // y_m moves by h/8 (dx_a/dr_a 4/h + dx_b/dr_b 4/h) per unit of zeta_m.
        let slopes = (!la.d_given.is_empty() && !lb.d_given.is_empty())
            .then(|| stuck.iter().map(|&j| (la.d_given[j] + lb.d_given[j]) * 0.5).collect());
        profile.give(la);
        profile.give(lb);
        let ends = Vector6::new(a.v[0], a.v[1], a.v[2], a.u[0], a.u[1], a.u[2])
            + Vector6::new(b.v[0], b.v[1], b.v[2], b.u[0], b.u[1], b.u[2]);
        Ok((ends * 0.5 + (xa - xb) * (h / 8.0), slopes))
    };
    // The stuck log tensions at the midpoint strains `y`, with their gradients in them.
    let stuck_at = |y: &Vector6<f64>| -> Result<Vec<Gradient>> {
        let (v, u) = (y.fixed_rows::<3>(0).into_owned(), y.fixed_rows::<3>(3).into_owned());
        stuck
            .iter()
            .zip(&lambda)
            .map(|(&j, &lambda)| {
                let (tension, d_v, d_u) =
                    profile.stuck_tension_with(j, lambda, &sites.mid, (sites.mid.s, &v, &u), length);
                if !(tension > 0.0 && tension.is_finite()) {
                    return Err(Error::Breakdown {
                        s: sites.mid.s,
                        what: SLACK.into(),
                    });
                }
                let gradient = Vector6::new(d_v[0], d_v[1], d_v[2], d_u[0], d_u[1], d_u[2]) / tension;
                Ok(((tension / profile.base[j]).ln(), gradient))
            })
            .collect()
    };
    let start: Vec<f64> = stuck.iter().map(|&j| 0.5 * (za[j] + zb[j])).collect();
    let zeta = match midpoint(&start, &strains, &stuck_at) {
        Err(Error::Breakdown { what, .. }) if what == SLACK => return Ok(None),
        other => other?,
    };
    let [wa, wm, wb] = points(&zeta);
    let w3 = [Some(&wa[..]), Some(&wm[..]), Some(&wb[..])];
    let Some(jac) = jac else {
        return interval_at(profile, length, k, sites, segment_end, a, b, w3, None, None).map(Some);
    };
    let mut columns = Columns::new(count);
    let mut out = interval_at(
        profile,
        length,
        k,
        sites,
        segment_end,
        a,
        b,
        w3,
        Some(&mut *jac),
        Some(&mut columns),
    )?;
    // d zeta / dX = (I - dZ/dzeta)^-1 dZ/dX|zeta, X the 24 node columns then the 2 count
    // log tensions; the rates r_a, r_b of stuck slip j move with z_a, z_b at fixed zeta.
    let n = stuck.len();
    let width = 24 + 2 * count;
    // d r_a / dz, d r_m / dz, d r_b / dz of slip j in log-tension column c (z_a of slip l
    // at l, z_b at count + l), at fixed zeta.
    let slope = |j: usize, c: usize| -> [f64; 3] {
        if c == j {
            [-3.0 / h, -1.0 / h, 1.0 / h]
        } else if c == count + j {
            [-1.0 / h, 1.0 / h, 3.0 / h]
        } else {
            [0.0; 3]
        }
    };
    let Ok(gradients) = stuck_at(&Vector6::new(
        columns.vm[0],
        columns.vm[1],
        columns.vm[2],
        columns.um[0],
        columns.um[1],
        columns.um[2],
    )) else {
        return Ok(None);
    };
    let mut system = vec![0.0; n * n];
    let mut rhs = DMatrix::<f64>::zeros(n, width);
    for (i, (_, g)) in gradients.iter().enumerate() {
        let gt = g.transpose();
        for c in 0..18 {
            let column = if c < 9 { 3 + c } else { 6 + c };
            rhs[(i, column)] = (gt * columns.d_ym.column(c))[0];
        }
        for c in 0..2 * count {
            let mut value = (gt * columns.d_ym_z.column(c))[0];
            for &j in &stuck {
                let [ra, _, rb] = slope(j, c);
                if ra != 0.0 || rb != 0.0 {
                    value += ra * (gt * columns.d_ym_r.column(j))[0] + rb * (gt * columns.d_ym_r.column(count + j))[0];
                }
            }
            rhs[(i, 24 + c)] = value;
        }
        for (m, &j) in stuck.iter().enumerate() {
            let d_zeta = (columns.d_ym_r.column(j) - columns.d_ym_r.column(count + j)) * (4.0 / h);
            system[i * n + m] = f64::from(u8::from(i == m)) - (gt * d_zeta)[0];
        }
    }
    let mut d_zeta = DMatrix::<f64>::zeros(n, width);
    for c in 0..width {
        let mut column: Vec<f64> = (0..n).map(|i| rhs[(i, c)]).collect();
        let mut matrix = system.clone();
        if !dense::solve_dense(&mut matrix, &mut column, n) {
            return Err(Error::Breakdown {
                s: sites.mid.s,
                what: "the stuck tensions at a link's midpoint are singular in themselves".into(),
            });
        }
        for (i, value) in column.into_iter().enumerate() {
            d_zeta[(i, c)] = value;
        }
    }
    // Each output's total derivative: its columns in the rates times the rates' own.
    let total = |o: usize, c: usize| -> f64 {
        let mut sum = 0.0;
        for (m, &j) in stuck.iter().enumerate() {
            let (ra, rm, rb) = (
                columns.rows_r[(o, j)],
                columns.rows_r[(o, count + j)],
                columns.rows_r[(o, 2 * count + j)],
            );
            sum += (ra - rb) * (4.0 / h) * d_zeta[(m, c)];
            if c >= 24 {
                let [sa, sm, sb] = slope(j, c - 24);
                sum += ra * sa + rm * sm + rb * sb;
            }
        }
        sum
    };
    for r in 0..12 {
        for c in 0..24 {
            jac[r * 24 + c] += total(r, c);
        }
        for c in 0..2 * count {
            out.rows_z[(r, c)] += total(r, 24 + c);
        }
    }
    // A sliding slip's capstan row sees the stuck ones through the rates; a stick row does
    // not (its exact derivatives stay).
    for l in (0..count).filter(|&l| profile.on_link(l, k) && !profile.sticks(l, k)) {
        for c in 0..24 {
            out.psi_x[(l, c)] += total(12 + l, c);
        }
        for c in 0..2 * count {
            out.psi_z[(l, c)] += total(12 + l, 24 + c);
        }
    }
    Ok(Some(out))
}

/// zeta_m = Z(y_m(zeta_m)) for the stuck slips (module docs), from `start`: `strains`
/// gives y_m's strains for a zeta (two point evaluations) and, where the nodes' rates are
/// affine in the given rates, their exact change with each zeta_m; `stuck_at` the Z and
/// their gradients at strains. Affine (every slip at the nodes stuck here, the usual case):
/// y_m is known for every zeta from one evaluation, and Newton on the cheap Z solves the
/// fixed point to rounding. Otherwise a secant per slip on the evaluations themselves,
/// until the fixed point holds to 1e-12 (Z's own rounding is about 1e-13: the stuck
/// tension's stretch is 1e-3) or the iterates stop moving.
///
/// # Errors
/// Those of `strains` and `stuck_at`.
fn midpoint(
    start: &[f64],
    strains: &dyn Fn(&[f64]) -> Result<Strains>,
    stuck_at: &dyn Fn(&Vector6<f64>) -> Result<Vec<Gradient>>,
) -> Result<Vec<f64>> {
    let n = start.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let (y0, slopes) = strains(start)?;
    if let Some(slopes) = slopes {
        // y(zeta) = y0 + sum_j slopes_j (zeta_j - start_j): Newton on zeta - Z(y(zeta)),
        // whose Jacobian is I - (grad Z_i . slopes_j).
        let mut zeta = start.to_vec();
        for _ in 0..ITERATIONS {
            let mut y = y0;
            for (j, slope) in slopes.iter().enumerate() {
                y += slope * (zeta[j] - start[j]);
            }
            let at = stuck_at(&y)?;
            let mut step: Vec<f64> = at.iter().zip(&zeta).map(|((z, _), x)| z - x).collect();
            let mut matrix: Vec<f64> = (0..n * n)
                .map(|e| {
                    let (i, j) = (e / n, e % n);
                    f64::from(u8::from(i == j)) - at[i].1.dot(&slopes[j])
                })
                .collect();
            if !dense::solve_dense(&mut matrix, &mut step, n) {
                break;
            }
            let moved = step.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
            for (x, d) in zeta.iter_mut().zip(&step) {
                *x += d;
            }
            if moved <= 4.0 * f64::EPSILON * (1.0 + zeta.iter().fold(0.0_f64, |m, x| m.max(x.abs()))) {
                break;
            }
        }
        return Ok(zeta);
    }
    let left = |zeta: &[f64], y: &Vector6<f64>| -> Result<Vec<f64>> {
        Ok(stuck_at(y)?.iter().zip(zeta).map(|((z, _), x)| x - z).collect())
    };
    let size = |g: &[f64]| g.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let (mut p, mut gp) = (start.to_vec(), left(start, &y0)?);
    let mut c: Vec<f64> = start.iter().map(|x| x + 1e-3).collect();
    let mut gc = left(&c, &strains(&c)?.0)?;
    for _ in 0..ITERATIONS {
        if size(&gc) <= 1e-12 {
            break;
        }
        let next: Vec<f64> = (0..n)
            .map(|j| {
                let slope = (gc[j] - gp[j]) / (c[j] - p[j]);
                if slope.is_finite() && slope != 0.0 {
                    c[j] - gc[j] / slope
                } else {
                    c[j]
                }
            })
            .collect();
        let moved = next.iter().zip(&c).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let g = left(&next, &strains(&next)?.0)?;
        (p, gp) = (std::mem::replace(&mut c, next), std::mem::replace(&mut gc, g));
        if moved <= 1e-14 {
            break;
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::collocation::friction::grip::{Contact, Grip};
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::length;
    use crate::model::tendon::Friction;
    use crate::so3;
    use nalgebra::Vector3;

    /// A stuck link's rows with the pointwise load and the inner solve for zeta_m, against
    /// central differences of the whole evaluation (inner solve included) in the scaled node
    /// unknowns and the log tensions: the prototype's tendon 1 stuck at the tensions of a
    /// full-slip solve, its material stretched by them at the nodes and, at the midpoints,
    /// the mean of the nodes' (so the stuck tension there differs from Hermite's).
    #[test]
    fn pointwise_jacobian_matches_central_differences() {
        let mut robot = cases::prototype();
        robot.tendons[0].set_tension(3.0);
        robot.tendons[0].friction = Some(Friction::pull(0.1));
        robot.tendons[0].stiffness = Some(2000.0);
        let solution = crate::solve(&robot, &crate::collocation::Options::fixed(8)).unwrap();
        let model = Model::new(&robot);
        let mesh = Mesh::from_points(&robot, &solution.nodes.iter().map(|n| n.s).collect::<Vec<_>>()).unwrap();
        let mut profile = Profile::new(&model, &mesh);
        let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
        let length = robot.length();
        let tendon = &robot.tendons[0];
        let base = profile.base[0];
        let tensions = &solution.tendon_tensions[0];
        profile.z[0] = tensions.iter().map(|t| (t / base).ln()).collect();
        let reference: Vec<f64> = x
            .iter()
            .zip(tensions)
            .map(|(n, t)| length::speed(&tendon.routing.at(n.s, length), &n.v, &n.u) / (1.0 + t / 2000.0))
            .collect();
        let span = mesh.nodes.len() - 1;
        profile.grips = Some(vec![Grip {
            contacts: vec![Contact::Stick; span],
            multipliers: vec![0.0; span],
            capacities: vec![0.0; span],
            midpoints: reference.windows(2).map(|p| 0.5 * (p[0] + p[1])).collect(),
            reference,
            kinks: Vec::new(),
            boundary: None,
        }]);
        let k = 3;
        let (s0, s1) = (x[k].s, x[k + 1].s);
        let sites = IntervalSites {
            start: model.site(s0),
            mid: model.site(0.5 * (s0 + s1)),
            end: model.site(s1),
        };
        let seg = mesh.nodes[k].segment_end;
        assert!(profile.pointwise(k));
        let w = profile.multipliers(k).unwrap();
        let evaluate = |p: &Profile, a: &State, b: &State, jac: Option<&mut [f64]>| {
            interval(p, length, k, &sites, seg, (a, b), &w, jac)
                .unwrap()
                .expect("the stuck tension at the midpoint is positive")
        };
        let mut jac = [0.0; 12 * 24];
        let lin = evaluate(&profile, &x[k], &x[k + 1], Some(&mut jac));
        // The midpoint's log tension is the stuck one: not Hermite's (z_a + z_b) / 2.
        let moved = |column: usize, h: f64| {
            let (mut a, mut b) = (x[k], x[k + 1]);
            let node = if column < 12 { &mut a } else { &mut b };
            let (part, i) = ((column % 12) / 3, column % 3);
            let mut d = Vector3::zeros();
            d[i] = h;
            match part {
                0 => node.p += d * length,
                1 => node.R *= so3::exp(&d),
                2 => node.v += d,
                _ => node.u += d / length,
            }
            evaluate(&profile, &a, &b, None)
        };
        // Richardson-extrapolated central differences (error O(h^4)), as the constant
        // multiplier's test in `interval.rs`.
        let extrapolate = |f: &dyn Fn(f64) -> IntervalLinearization, h: f64| -> Vec<f64> {
            let central = |h: f64| -> Vec<f64> {
                let (p, m) = (f(h), f(-h));
                (0..12).map(|r| (p.residual[r] - m.residual[r]) / (2.0 * h)).collect()
            };
            let (r1, r2) = (central(h), central(h / 2.0));
            r1.iter().zip(&r2).map(|(x, y)| (4.0 * y - x) / 3.0).collect()
        };
        let mut largest = 0.0_f64;
        for column in 0..24 {
            // v moves the internal force by E A dv: a step of 1e-8 there (as in `interval.rs`).
            let step = if (6..9).contains(&(column % 12)) { 1e-8 } else { 1e-5 };
            let rows = extrapolate(&|h| moved(column, h), step);
            for (row, &fd) in rows.iter().enumerate() {
                let exact = jac[row * 24 + column];
                largest = largest.max(exact.abs());
                // 1e-6 relative to at least 1: the rows are O(1) scaled; the inner solve's
                // rounding (1e-13 in zeta_m) over the steps stays below 1e-7.
                assert!(
                    (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                    "row {row}, column {column}: {fd} vs {exact}"
                );
            }
        }
        for side in 0..2 {
            let at = |h: f64| {
                let mut p = profile.clone_z();
                p.z[0][k + side] += h;
                evaluate(&p, &x[k], &x[k + 1], None)
            };
            let rows = extrapolate(&at, 1e-5);
            for (row, &fd) in rows.iter().enumerate() {
                let exact = lin.rows_z[(row, side)];
                assert!(
                    (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                    "row {row}, z {side}: {fd} vs {exact}"
                );
            }
        }
        // The rank-one term matters: the rows' Jacobian is not small.
        assert!(largest > 1.0);
    }
}
