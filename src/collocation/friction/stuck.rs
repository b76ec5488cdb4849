//! A link of a history step where a tendon sticks, with its tangential load point by point
//! (docs/friction.md section 8, "A pointwise tangential load on a stuck link").
//!
//! On a stuck link the log tension is the stuck material's, z = zeta(s). The link's rows
//! take its rate z' at the two nodes and the midpoint from the quadratic through
//! (z_a, zeta_m, z_b), zeta_m the stuck material's log tension at the midpoint state y_m:
//!
//! ```text
//! z'_a = (-3 z_a + 4 zeta_m - z_b) / h,   z'_m = (z_b - z_a) / h,   z'_b = (z_a - 4 zeta_m + 3 z_b) / h
//! ```
//!
//! each as the multiplier w = z' / (mu kappa) of its point. Hermite-Simpson's midpoint is
//! then z_m = zeta_m, and the quadratic's derivative errors (h^2 z'''/12 at the ends,
//! -h^2 z'''/24 at the midpoint) cancel in Simpson's weights and in the midpoint's
//! h/8 (F_a - F_b): the link is order 4 where the stuck profile is smooth. Since y_m depends
//! on F_a and F_b, hence on zeta_m, zeta_m solves the scalar equation
//! zeta_m = Z(y_m(zeta_m)) per stuck tendon (a secant iteration, [`midpoint`]). The
//! Jacobian of the link's backbone rows and capstan rows is taken by central differences
//! of the whole evaluation, inner solve included.

use super::interval::{IntervalLinearization, interval_at};
use super::profile::Profile;
use crate::collocation::residual::{IntervalSites, end_points, rhs_from_rates};
use crate::collocation::unknowns::{NODE, P, THETA, U, V};
use crate::error::Result;
use crate::so3;
use crate::solution::State;
use nalgebra::Vector3;

/// Secant iterations of zeta_m at most: the map's slope is about -15 on the prototype
/// (docs/friction.md section 8) and nearly constant, so the secant converges in 4 to 6.
const ITERATIONS: usize = 30;
/// Central-difference step in the scaled node unknowns and the log tensions: truncation
/// about 1e-14 of the rows' scale, rounding of the inner solve (1e-13) over 1e-7.
const STEP: f64 = 1e-7;

/// Link k with the pointwise load of its stuck slips (module docs); the other slips keep
/// their multipliers `w`. Arguments as [`super::interval::interval`].
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
    a: &State,
    b: &State,
    w: &[f64],
    jac: Option<&mut [f64]>,
) -> Result<IntervalLinearization> {
    let za: Vec<f64> = profile.z.iter().map(|z| z[k]).collect();
    let zb: Vec<f64> = profile.z.iter().map(|z| z[k + 1]).collect();
    let Some(jac) = jac else {
        let points = multipliers(profile, length, k, sites, segment_end, (a, b), (&za, &zb), w)?;
        return interval_at(profile, length, k, sites, segment_end, a, b, refs(&points), None, None);
    };
    let count = profile.count();
    // The rows of the evaluation with the node states and log tensions moved.
    let rows = |a: &State, b: &State, za: &[f64], zb: &[f64]| -> Result<Vec<f64>> {
        let points = multipliers(profile, length, k, sites, segment_end, (a, b), (za, zb), w)?;
        let lin = interval_at(
            profile,
            length,
            k,
            sites,
            segment_end,
            a,
            b,
            refs(&points),
            Some((za, zb)),
            None,
        )?;
        let mut out: Vec<f64> = lin.residual.iter().copied().collect();
        out.extend_from_slice(&lin.psi);
        Ok(out)
    };
    let mut d_x = vec![vec![0.0; 12 + count]; 2 * NODE];
    for (c, column) in d_x.iter_mut().enumerate() {
        let moved = |step: f64| -> Result<Vec<f64>> {
            let (mut a, mut b) = (*a, *b);
            moved_state(if c < NODE { &mut a } else { &mut b }, c % NODE, step, length);
            rows(&a, &b, &za, &zb)
        };
        let (plus, minus) = (moved(STEP)?, moved(-STEP)?);
        for (d, (p, m)) in column.iter_mut().zip(plus.iter().zip(&minus)) {
            *d = (p - m) / (2.0 * STEP);
        }
    }
    let mut d_z = vec![vec![0.0; 12 + count]; 2 * count];
    for (c, column) in d_z.iter_mut().enumerate() {
        let moved = |step: f64| -> Result<Vec<f64>> {
            let (mut za, mut zb) = (za.clone(), zb.clone());
            if c < count {
                za[c] += step;
            } else {
                zb[c - count] += step;
            }
            rows(a, b, &za, &zb)
        };
        let (plus, minus) = (moved(STEP)?, moved(-STEP)?);
        for (d, (p, m)) in column.iter_mut().zip(plus.iter().zip(&minus)) {
            *d = (p - m) / (2.0 * STEP);
        }
    }
    // The evaluation itself last, so that the node evaluations the profile keeps for the
    // next link are this one's.
    let points = multipliers(profile, length, k, sites, segment_end, (a, b), (&za, &zb), w)?;
    let mut out = interval_at(
        profile,
        length,
        k,
        sites,
        segment_end,
        a,
        b,
        refs(&points),
        None,
        Some(&mut *jac),
    )?;
    for (c, column) in d_x.iter().enumerate() {
        for r in 0..12 {
            jac[r * 2 * NODE + c] = column[r];
        }
    }
    for (c, column) in d_z.iter().enumerate() {
        for r in 0..12 {
            out.rows_z[(r, c)] = column[r];
        }
    }
    // A sliding slip's capstan row sees the stuck ones through y_m; a stuck slip's stick
    // row does not (its exact derivatives stay).
    for l in (0..count).filter(|&l| profile.on_link(l, k) && !profile.sticks(l, k)) {
        for (c, column) in d_x.iter().enumerate() {
            out.psi_x[(l, c)] = column[12 + l];
        }
        for (c, column) in d_z.iter().enumerate() {
            out.psi_z[(l, c)] = column[12 + l];
        }
    }
    Ok(out)
}

/// The three points' multipliers as the slices [`interval_at`] takes.
fn refs(points: &[Vec<f64>; 3]) -> [Option<&[f64]>; 3] {
    [Some(&points[0]), Some(&points[1]), Some(&points[2])]
}

/// `state` moved by `step` in its scaled unknown `c` (0..12: p / L, theta, v, u L), as a
/// Newton step moves it ([`crate::collocation::unknowns::retract`]).
fn moved_state(state: &mut State, c: usize, step: f64, length: f64) {
    let mut e = Vector3::zeros();
    e[c % 3] = step;
    match c - c % 3 {
        P => state.p += e * length,
        THETA => state.R *= so3::exp(&e),
        V => state.v += e,
        U => state.u += e / length,
        _ => unreachable!("a node has 12 unknowns"),
    }
}

/// The multipliers at the link's start, end and midpoint (module docs): `w` for the slips
/// that do not stick on it, z' / (mu kappa) of the quadratic through (z_a, zeta_m, z_b) for
/// those that do, with zeta_m from [`midpoint`]. A point where the path does not turn
/// (kappa = 0) carries no friction and gets 0.
///
/// # Errors
/// A model breakdown at a point.
#[allow(clippy::too_many_arguments)]
fn multipliers(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    (za, zb): (&[f64], &[f64]),
    w: &[f64],
) -> Result<[Vec<f64>; 3]> {
    let count = profile.count();
    let h = sites.end.s - sites.start.s;
    let stuck: Vec<usize> = (0..count)
        .filter(|&j| profile.on_link(j, k) && profile.sticks(j, k) && profile.base[j] > 0.0)
        .collect();
    let (y0, y1) = end_points(a, b);
    let theta1: Vector3<f64> = y1.fixed_rows::<3>(THETA).into();
    let R1 = a.R * so3::exp(&theta1);
    let mu: Vec<f64> = (0..count).map(|j| profile.coefficient(j)).collect();
    // kappa at the nodes does not depend on the multipliers.
    let kappa = |site, R: &nalgebra::Matrix3<f64>, state: &State, z: &[f64]| -> Result<Vec<f64>> {
        let lin = profile.point(site, segment_end, R, (&state.v, &state.u), z, Some(w), false)?;
        let kappa = lin.kappa.clone();
        profile.give(lin);
        Ok(kappa)
    };
    let (kappa_a, kappa_b) = (kappa(&sites.start, &a.R, a, za)?, kappa(&sites.end, &b.R, b, zb)?);
    let share = |rate: f64, mu: f64, kappa: f64| {
        let friction = mu * kappa;
        if friction > 0.0 { rate / friction } else { 0.0 }
    };
    let ends = |zeta: &[f64]| -> [Vec<f64>; 2] {
        let (mut wa, mut wb) = (w.to_vec(), w.to_vec());
        for (&j, &zm) in stuck.iter().zip(zeta) {
            wa[j] = share((-3.0 * za[j] + 4.0 * zm - zb[j]) / h, mu[j], kappa_a[j]);
            wb[j] = share((za[j] - 4.0 * zm + 3.0 * zb[j]) / h, mu[j], kappa_b[j]);
        }
        [wa, wb]
    };
    // The midpoint state y_m for the ends' multipliers, and the stuck log tensions there.
    let s_m = sites.mid.s;
    let lambda: Vec<f64> = stuck.iter().map(|&j| profile.material_at_midpoint(j, k)).collect();
    let map = |zeta: &[f64]| -> Result<(Vec<f64>, Vector3<f64>, Vector3<f64>, nalgebra::Matrix3<f64>)> {
        let [wa, wb] = ends(zeta);
        let la = profile.point(&sites.start, segment_end, &a.R, (&a.v, &a.u), za, Some(&wa), false)?;
        let f0 = rhs_from_rates(&sites.start, &a.R, &y0, &la.lin.rates);
        profile.give(la);
        let lb = profile.point(&sites.end, segment_end, &b.R, (&b.v, &b.u), zb, Some(&wb), false)?;
        let f1 = rhs_from_rates(&sites.end, &R1, &y1, &lb.lin.rates);
        profile.give(lb);
        let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
        let (vm, um): (Vector3<f64>, Vector3<f64>) = (ym.fixed_rows::<3>(V).into(), ym.fixed_rows::<3>(U).into());
        let theta_m: Vector3<f64> = ym.fixed_rows::<3>(THETA).into();
        let next = stuck
            .iter()
            .zip(&lambda)
            .map(|(&j, &lambda)| {
                let (tension, _, _) = profile.stuck_tension_with(j, lambda, &sites.mid, (s_m, &vm, &um), length);
                (tension / profile.base[j]).ln()
            })
            .collect();
        Ok((next, vm, um, a.R * so3::exp(&theta_m)))
    };
    let zeta = midpoint(&stuck.iter().map(|&j| 0.5 * (za[j] + zb[j])).collect::<Vec<_>>(), |z| {
        map(z).map(|m| m.0)
    })?;
    let [wa, wb] = ends(&zeta);
    let (_, vm, um, Rm) = map(&zeta)?;
    // kappa at the midpoint state, with z_m = zeta_m for the stuck slips (Hermite's z_m
    // for the others is not needed: kappa does not depend on the tension).
    let mut zm: Vec<f64> = (0..count).map(|j| 0.5 * (za[j] + zb[j])).collect();
    for (&j, &z) in stuck.iter().zip(&zeta) {
        zm[j] = z;
    }
    let lm = profile.point(&sites.mid, segment_end, &Rm, (&vm, &um), &zm, Some(w), false)?;
    let mut wm = w.to_vec();
    for &j in &stuck {
        wm[j] = share((zb[j] - za[j]) / h, mu[j], lm.kappa[j]);
    }
    profile.give(lm);
    Ok([wa, wb, wm])
}

/// zeta_m = Z(zeta_m) per stuck slip from `start`, by a secant iteration on each component
/// of zeta - Z(zeta) (the slips' midpoints are coupled only through the backbone, weakly),
/// to rounding: it stops when the residual no longer falls.
///
/// # Errors
/// Those of `map`.
fn midpoint(start: &[f64], map: impl Fn(&[f64]) -> Result<Vec<f64>>) -> Result<Vec<f64>> {
    let g = |zeta: &[f64]| -> Result<Vec<f64>> { Ok(zeta.iter().zip(map(zeta)?).map(|(z, m)| z - m).collect()) };
    let mut x0 = start.to_vec();
    let mut g0 = g(&x0)?;
    let mut x1: Vec<f64> = x0.iter().map(|x| x + 1e-6).collect();
    let mut g1 = g(&x1)?;
    let size = |g: &[f64]| g.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for _ in 0..ITERATIONS {
        if size(&g1) == 0.0 {
            break;
        }
        let x2: Vec<f64> = (0..x1.len())
            .map(|j| {
                let slope = (g1[j] - g0[j]) / (x1[j] - x0[j]);
                if slope.is_finite() && slope != 0.0 {
                    x1[j] - g1[j] / slope
                } else {
                    x1[j]
                }
            })
            .collect();
        let g2 = g(&x2)?;
        if size(&g2) >= size(&g1) && size(&g1) < 1e-10 {
            break;
        }
        (x0, g0, x1, g1) = (x1, g1, x2, g2);
    }
    Ok(x1)
}
