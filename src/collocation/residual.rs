//! The residual blocks of the collocation system. The base, jump and tip blocks are generic
//! over the scalar, so one code path gives their residual (f64) and the jump blocks' exact
//! Jacobian (num-dual forward mode); the base and tip blocks' Jacobian is in closed form
//! ([`super::end_rows`]), checked against the dual numbers in its tests. The interval blocks have two f64 paths: [`interval`] for the
//! residual and [`interval_jacobian`] for the residual with its exact Jacobian by the chain
//! rule through the scheme and the analytic linearization of eq. 13
//! ([`crate::model::linearize`]); tests/jacobian.rs checks the two against central
//! differences.
//!
//! Unknowns (layout in [`super::unknowns`]): at every node a scaled perturbation d = (dp / L, dtheta, dv, du L) of the
//! current state, applied as p + L dp, R exp(dtheta), v + dv, u + du / L (rotations are
//! updated on SO(3), so every R stays orthonormal). Residual rows are scaled the same way:
//! positions by 1/L, curvatures by L, wrenches in strain units (D^-1 n, C^-1 m L), so all
//! are dimensionless and O(1) for O(1) errors.
//!
//! Interval rows: the Hermite-Simpson (3-stage Lobatto IIIA, order 4) collocation of the
//! ODE written in the interval's local coordinates y = (p, theta, v, u) with
//! R(s) = R_k exp(theta(s)), theta' = J_r(theta)^-1 u, theta(s_k) = 0 and
//! theta(s_k+1) = log(R_k^T R_k+1) (a Runge-Kutta-Munthe-Kaas collocation):
//!
//! ```text
//! y_m = (y_0 + y_1) / 2 + h/8 (F_0 - F_1),    F = (R v, J_r^-1 u, v', u')  (eq. 13)
//! 0   = y_1 - y_0 - h/6 (F_0 + 4 F(y_m) + F_1)
//! ```
#![allow(non_snake_case)]

pub(super) use super::ends::EndColumns;
pub use super::interval_jacobian::interval_jacobian;
pub(super) use super::interval_jacobian::{
    interval_jacobian_as_residual, interval_jacobian_into, interval_jacobian_keeping, midpoint_product,
};
pub(crate) use super::interval_kept::IntervalFactors;
pub use super::interval_kept::IntervalTensions;
pub use super::order6::{QuarterSites, interval_order6};
pub(super) use super::point::{PointFrame, PointLinearization, rhs_linearized_inline};
use super::unknowns::{P, THETA, U, V};
use crate::error::Result;
use crate::model::equations::{Model, Site, lift, lift_m};
use crate::model::linearize;
use crate::simd::{avx2_fma, four};
use crate::solution::State;
use crate::{Real, so3};
use nalgebra::{Matrix3, SVector, Vector3, Vector6};

/// Scaled perturbation of one node's unknowns.
pub type Delta<T> = SVector<T, 12>;
/// Residual of one link (interval or jump).
pub type Block<T> = SVector<T, 12>;

/// A node's state with the perturbation applied, in scalar type T.
struct Perturbed<T: Real> {
    p: Vector3<T>,
    R: Matrix3<T>,
    v: Vector3<T>,
    u: Vector3<T>,
}

fn perturb<T: Real>(x: &State, d: &Delta<T>, length: f64) -> Perturbed<T> {
    let l = T::from_f64(length).unwrap_or_else(T::one);
    let part = |i: usize| -> Vector3<T> { d.fixed_rows::<3>(i).into() };
    Perturbed {
        p: lift::<T>(&x.p) + part(0) * l,
        R: lift_m::<T>(&x.R) * so3::exp(&part(3)),
        v: lift::<T>(&x.v) + part(6),
        u: lift::<T>(&x.u) + part(9) / l,
    }
}

/// Scales a local-coordinate vector (p, theta, v, u) to residual units.
pub(super) fn scale_rows<T: Real>(mut y: Block<T>, length: f64) -> Block<T> {
    let l = T::from_f64(length).unwrap_or_else(T::one);
    for i in 0..3 {
        y[i] /= l;
        y[9 + i] *= l;
    }
    y
}

fn stack<T: Real>(a: &Vector3<T>, b: &Vector3<T>, c: &Vector3<T>, d: &Vector3<T>) -> Block<T> {
    // Block by block: a chained iterator here cost 9% of a residual evaluation.
    let mut y = Block::zeros();
    for (k, part) in [a, b, c, d].into_iter().enumerate() {
        y.fixed_rows_mut::<3>(3 * k).copy_from(part);
    }
    y
}

/// Base rows: p(0) = p0, R(0) = R0 (6 rows).
pub fn base<T: Real>(model: &Model, x: &State, d: &Delta<T>) -> SVector<T, 6> {
    let robot = model.robot;
    let n = perturb(x, d, robot.length());
    let l = T::from_f64(robot.length()).unwrap_or_else(T::one);
    let dp = (n.p - lift::<T>(&model.base_position())) / l;
    let dr = so3::log(&(lift_m::<T>(&robot.base_rotation).transpose() * n.R));
    SVector::<T, 6>::from_iterator(dp.iter().chain(dr.iter()).copied())
}

/// Tip rows: the free-end wrench balance n(L) = F_tip + sum F_i, m(L) = L_tip + sum L_i (6 rows).
pub fn tip<T: Real>(model: &Model, site: &Site, x: &State, d: &Delta<T>) -> Result<SVector<T, 6>> {
    let length = model.robot.length();
    let n = perturb(x, d, length);
    let (f, m) = model.wrench_balance(site.s, (site, &n.R, &n.v, &n.u), None)?;
    let l = T::from_f64(length).unwrap_or_else(T::one);
    Ok(SVector::<T, 6>::from_iterator(
        f.iter().copied().chain(m.iter().map(|&x| x * l)),
    ))
}

/// Jump rows at a breakpoint: p and R continuous, the point-load wrench balance (12 rows),
/// with the sites of its left and right nodes (`sites`: the section and precurvature may
/// jump there too).
pub fn jump<T: Real>(
    model: &Model,
    sites: (&Site, &Site),
    a: &State,
    b: &State,
    da: &Delta<T>,
    db: &Delta<T>,
) -> Result<Block<T>> {
    let length = model.robot.length();
    let (na, nb) = (perturb(a, da, length), perturb(b, db, length));
    let l = T::from_f64(length).unwrap_or_else(T::one);
    let dp = (nb.p - na.p) / l;
    let dr = so3::log(&(na.R.transpose() * nb.R));
    let (left, right) = sites;
    let (f, m) = model.wrench_balance(left.s, (left, &na.R, &na.v, &na.u), Some((right, &nb.R, &nb.v, &nb.u)))?;
    Ok(stack(&dp, &dr, &f, &(m * l)))
}

/// The right-hand side F(s, y) in the local coordinates of an interval starting at `Rk`.
pub(super) fn rhs(
    model: &Model,
    site: &Site,
    segment_end: f64,
    Rk: &Matrix3<f64>,
    y: &Block<f64>,
) -> Result<Block<f64>> {
    let v: Vector3<f64> = y.fixed_rows::<3>(V).into();
    let u: Vector3<f64> = y.fixed_rows::<3>(U).into();
    let (R, Jri) = rhs_frame(Rk, y);
    let rates = linearize::rates(model, site, segment_end, &R, &v, &u)?;
    Ok(rhs_with(site, &R, &Jri, y, &rates))
}

/// The frame R = R_k exp(theta) of y's theta in the local coordinates of an interval
/// starting at `Rk`, and J_r^-1(theta): what [`rhs`] evaluates besides the rates.
#[inline(always)]
fn rhs_frame(Rk: &Matrix3<f64>, y: &Block<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
    // exp(theta) and J_r^-1(theta) from one hat(theta) and its square: the bits of
    // `so3::exp` and `so3::right_jacobian_inv` (`exp_and_jacobians`; J_r is not used).
    let [E, _, Jri] = so3::exp_and_jacobians(&theta);
    (Rk * E, Jri)
}

/// F(s, y) in the local coordinates of an interval, given the frame R = R_k exp(theta) of
/// y's theta and the strain rates (v', u') there: p' = R v (v the strain of the coordinate,
/// [`Site::strain`]), theta' = J_r(theta)^-1 u, and the rates.
pub(super) fn rhs_from_rates(site: &Site, R: &Matrix3<f64>, y: &Block<f64>, rates: &Vector6<f64>) -> Block<f64> {
    let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
    rhs_with(site, R, &so3::right_jacobian_inv(&theta), y, rates)
}

/// [`rhs`] at four points of four intervals (interval j starting at `Rk[j]`), eq. 13's
/// rates in one pass of four f64 lanes ([`linearize::rates_lanes`]), each point's bits those
/// of [`rhs`]: None where a lane leaves the lanes' common path. Always inlined, for the
/// AVX2 build of its caller.
#[inline(always)]
pub(super) fn rhs_lanes(
    model: &Model,
    sites: [&Site; 4],
    segment_end: f64,
    Rk: [&Matrix3<f64>; 4],
    y: [&Block<f64>; 4],
) -> Option<[Block<f64>; 4]> {
    let frames = four!(j => rhs_frame(Rk[j], y[j]));
    let v: [Vector3<f64>; 4] = four!(j => y[j].fixed_rows::<3>(V).into());
    let u: [Vector3<f64>; 4] = four!(j => y[j].fixed_rows::<3>(U).into());
    let states = four!(j => (&frames[j].0, &v[j], &u[j]));
    let rates = linearize::rates_lanes(model, sites, segment_end, states)?;
    Some(four!(j => rhs_with(sites[j], &frames[j].0, &frames[j].1, y[j], &rates[j])))
}

/// [`rhs_from_rates`] given J_r^-1(theta) (`Jri`) too.
#[inline(always)]
fn rhs_with(site: &Site, R: &Matrix3<f64>, Jri: &Matrix3<f64>, y: &Block<f64>, rates: &Vector6<f64>) -> Block<f64> {
    let v: Vector3<f64> = y.fixed_rows::<3>(V).into();
    let u: Vector3<f64> = y.fixed_rows::<3>(U).into();
    let mut f = Block::zeros();
    f.fixed_rows_mut::<3>(P).copy_from(&(R * site.strain(&v)));
    f.fixed_rows_mut::<3>(THETA).copy_from(&(Jri * u));
    f.fixed_rows_mut::<6>(V).copy_from(rates);
    f
}

/// The sites an interval needs: at its start, midpoint and end.
#[derive(Clone, Copy, Debug)]
pub struct IntervalSites {
    /// Site at s_k.
    pub start: Site,
    /// Site at the midpoint.
    pub mid: Site,
    /// Site at s_k+1.
    pub end: Site,
}

/// The interval's end points in its local coordinates: y_0 = (p_a, 0, v_a, u_a) and
/// y_1 = (p_b, log(R_a^T R_b), v_b, u_b).
pub(super) fn end_points(a: &State, b: &State) -> (Block<f64>, Block<f64>) {
    let theta1 = so3::log(&a.R.tr_mul(&b.R));
    (
        stack(&a.p, &Vector3::zeros(), &a.v, &a.u),
        stack(&b.p, &theta1, &b.v, &b.u),
    )
}

/// The interval's end points [`end_points`] and F there ([`end_rhs`]), given the rates
/// (v', u') at both nodes: [y_0, y_1, F_0, F_1], what every scheme on an interval (orders 4,
/// 6 and 8, the dynamics' midpoint) starts from. Always inlined: returned from a call it
/// is copied (48 values), and whether the compiler inlines it otherwise changes between
/// builds of unchanged code (docs/benchmarks.md, "Batch row (branch row8)").
#[inline(always)]
pub(super) fn end_values(
    sites: &IntervalSites,
    a: &State,
    b: &State,
    start_rates: &Vector6<f64>,
    end_rates: &Vector6<f64>,
) -> [Block<f64>; 4] {
    let (y0, y1) = end_points(a, b);
    let theta1: Vector3<f64> = y1.fixed_rows::<3>(THETA).into();
    let f0 = end_rhs(&sites.start, a, &Vector3::zeros(), start_rates);
    let f1 = end_rhs(&sites.end, b, &theta1, end_rates);
    [y0, y1, f0, f1]
}

/// F at an interval's end point y_1 = (p_b, theta_1, v_b, u_b) in the local coordinates of
/// a frame R_a, given node b's site and the rates (v', u') there: (R_b v, J_r^-1(theta_1)
/// u_b, rates), with R_b = R_a exp(theta_1) and v the strain of v_b ([`Site::strain`]).
pub(super) fn end_rhs(site: &Site, b: &State, theta1: &Vector3<f64>, rates: &Vector6<f64>) -> Block<f64> {
    let mut f = Block::zeros();
    f.fixed_rows_mut::<3>(P).copy_from(&(b.R * site.strain(&b.v)));
    f.fixed_rows_mut::<3>(THETA)
        .copy_from(&(so3::right_jacobian_inv(theta1) * b.u));
    f.fixed_rows_mut::<6>(V).copy_from(rates);
    f
}

/// Interval rows: Hermite-Simpson collocation in local coordinates (12 rows) between the
/// node states `a` and `b`, and the rates (v', u') of eq. 13 at node a and at node b; the
/// next interval takes node b's as `start_rates` (node rates do not depend on the interval:
/// eq. 13 sees R only through R^T f_e and R^T l_e, and R_a exp(theta_1) is R_b). Without
/// `start_rates` the rates at node a are evaluated here.
///
/// # Errors
/// A model breakdown at a node or at the midpoint.
pub fn interval(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: Option<Vector6<f64>>,
) -> Result<(Block<f64>, Vector6<f64>, Vector6<f64>)> {
    let h = sites.end.s - sites.start.s;
    let rates0 = match start_rates {
        Some(r) => r,
        None => linearize::rates(model, &sites.start, segment_end, &a.R, &a.v, &a.u)?,
    };
    let rates1 = linearize::rates(model, &sites.end, segment_end, &b.R, &b.v, &b.u)?;
    let [y0, y1, f0, f1] = end_values(sites, a, b, &rates0, &rates1);
    let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
    let fm = rhs(model, &sites.mid, segment_end, &a.R, &ym)?;
    Ok((
        simpson_rows([y0, y1, f0, f1], &fm, h, model.robot.length()),
        rates0,
        rates1,
    ))
}

/// The interval rows y_1 - y_0 - h/6 (F_0 + 4 F_m + F_1), scaled, from [`end_values`]' y_0,
/// y_1, F_0, F_1 and F_m at the midpoint.
#[inline(always)]
fn simpson_rows([y0, y1, f0, f1]: [Block<f64>; 4], fm: &Block<f64>, h: f64, length: f64) -> Block<f64> {
    scale_rows(y1 - y0 - (f0 + fm * 4.0 + f1) * (h / 6.0), length)
}

/// An interval's rows with the rates (v', u') at its two nodes, as [`interval`] gives them.
pub(super) type IntervalRows = (Block<f64>, Vector6<f64>, Vector6<f64>);

/// [`interval`] of four intervals of one segment (`segment_end`) at once, interval j between
/// the nodes `x[j]` and `x[j + 1]` with the sites `sites[j]`, given the rates at `x[0]`
/// (`start`): eq. 13's rates at the four end nodes in one pass of four f64 lanes, then at
/// the four midpoints in a second ([`rhs_lanes`]), the rest as [`interval`] forms it, so
/// each interval's rows and node rates have [`interval`]'s bits. Compiled for AVX2 and FMA
/// where the processor has them (checked at run time). None where a lane leaves the lanes'
/// common path: evaluate the intervals one by one then (which gives the errors).
pub(super) fn intervals_lanes(
    model: &Model,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    start: Vector6<f64>,
) -> Option<[IntervalRows; 4]> {
    avx2_fma!(intervals_kernel(model, sites, segment_end, x, start))
}

/// [`intervals_lanes`]' evaluation.
#[inline(always)]
fn intervals_kernel(
    model: &Model,
    sites: [&IntervalSites; 4],
    segment_end: f64,
    x: &[State],
    start: Vector6<f64>,
) -> Option<[IntervalRows; 4]> {
    let end_states = four!(j => (&x[j + 1].R, &x[j + 1].v, &x[j + 1].u));
    let end_rates = linearize::rates_lanes(model, four!(j => &sites[j].end), segment_end, end_states)?;
    let start_rates = [start, end_rates[0], end_rates[1], end_rates[2]];
    let values = four!(j => end_values(sites[j], &x[j], &x[j + 1], &start_rates[j], &end_rates[j]));
    let h = four!(j => sites[j].end.s - sites[j].start.s);
    let ym = four!(j => (values[j][0] + values[j][1]) * 0.5 + (values[j][2] - values[j][3]) * (h[j] / 8.0));
    let fm = rhs_lanes(
        model,
        four!(j => &sites[j].mid),
        segment_end,
        four!(j => &x[j].R),
        four!(j => &ym[j]),
    )?;
    let length = model.robot.length();
    Some(four!(j => (simpson_rows(values[j], &fm[j], h[j], length), start_rates[j], end_rates[j])))
}

/// The derivative of eq. 13's rates at one point in some parameters (with the strains
/// moving along the given directions, when given), and the rates:
/// [`linearize::tension_rates`] (every tendon's tension) or [`linearize::stiffness_rates`]
/// (the six section stiffnesses).
pub(super) type PointDerivatives = fn(
    &Model,
    &Site,
    f64,
    (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    Option<&[Vector6<f64>]>,
    &mut [Vector6<f64>],
) -> Result<Vector6<f64>>;

/// The derivative of the interval rows of [`interval`] in some parameters at fixed node
/// states: `out[i]` gets dF/dq_i (scaled rows) for the parameters `point` differentiates
/// eq. 13 in. `d_start`, `d_end` and `d_mid` hold d(v', u')/dq_i at node a, node b and the
/// midpoint (the midpoint's total derivative, its strains moving by `dy_mid`); with
/// `start_rates`, `d_start` already holds node a's (the previous interval's `d_end`), else
/// both are evaluated here. Returns the rates at node b, whose derivatives stay in `d_end`.
///
/// The chain rule through the scheme (docs/sensitivity.md, "Exact tension columns"): only
/// the rate rows of F_0 and F_1 move with q_i, by dF_0 = (0, 0, d_start[i]) and
/// dF_1 = (0, 0, d_end[i]), so the midpoint state moves by dy_m = h/8 (dF_0 - dF_1) in its
/// strains alone, and F_m by (R_m dv_m, J_r^-1(theta_m) du_m, the rates' total derivative
/// -M^-1 (dF/dq_i + dF/d(v, u) dy_m) at the midpoint, one solve with its M). The rows move
/// by -h/6 (dF_0 + 4 dF_m + dF_1), scaled.
///
/// # Errors
/// A model breakdown at a node or at the midpoint.
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_derivatives(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start_rates: Option<Vector6<f64>>,
    point: PointDerivatives,
    [d_start, d_end, d_mid, dy_mid]: [&mut [Vector6<f64>]; 4],
    out: &mut [Block<f64>],
) -> Result<Vector6<f64>> {
    let h = sites.end.s - sites.start.s;
    let rates0 = match start_rates {
        Some(r) => r,
        None => point(model, &sites.start, segment_end, (&a.R, &a.v, &a.u), None, d_start)?,
    };
    let rates1 = point(model, &sites.end, segment_end, (&b.R, &b.v, &b.u), None, d_end)?;
    let [y0, y1, f0, f1] = end_values(sites, a, b, &rates0, &rates1);
    let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
    let theta_m: Vector3<f64> = ym.fixed_rows::<3>(THETA).into();
    let R_m = a.R * so3::exp(&theta_m);
    let (v_m, u_m) = (ym.fixed_rows::<3>(V).into(), ym.fixed_rows::<3>(U).into());
    for ((dy, s), e) in dy_mid.iter_mut().zip(d_start.iter()).zip(d_end.iter()) {
        *dy = (s - e) * (h / 8.0);
    }
    point(model, &sites.mid, segment_end, (&R_m, &v_m, &u_m), Some(dy_mid), d_mid)?;
    let Jri = so3::right_jacobian_inv(&theta_m);
    let mid = (sites.mid.inextensible, &R_m, &Jri);
    let rows = [&*d_start, &*d_end, &*d_mid, &*dy_mid];
    derivative_rows(mid, -h / 6.0, model.robot.length(), rows, |i, b| out[i] = b);
    Ok(rates1)
}

/// The interval rows' derivatives of [`interval_derivatives`] from the rates' derivatives
/// at node a, node b and the midpoint (its total derivative) and the midpoint's strain
/// motion `dy_mid`, for an interval of length `h` whose midpoint has the rotation R_m and
/// J_r(theta_m)^-1 (`mid`, with whether its rod is inextensible): `write(i, rows)` for
/// each parameter i with rows = `weight` (dF_0 + 4 dF_m + dF_1), scaled; the rows'
/// derivatives for `weight` = -h/6, the right-hand sides (their negation, the same bits:
/// rounding is symmetric in the sign) for h/6.
#[inline(always)]
pub(super) fn derivative_rows(
    (inextensible, R_m, Jri): (bool, &Matrix3<f64>, &Matrix3<f64>),
    weight: f64,
    length: f64,
    [d_start, d_end, d_mid, dy_mid]: [&[Vector6<f64>]; 4],
    mut write: impl FnMut(usize, Block<f64>),
) {
    for (i, &dym) in dy_mid.iter().enumerate() {
        // dF_0 + 4 dF_m + dF_1.
        let mut dF = Block::zeros();
        // The midpoint's position rate is R_m times the strain: on a Kirchhoff rod that is
        // v*, which no parameter moves through the translational coordinate.
        if !inextensible {
            dF.fixed_rows_mut::<3>(P)
                .copy_from(&(R_m * dym.fixed_rows::<3>(0) * 4.0));
        }
        dF.fixed_rows_mut::<3>(THETA)
            .copy_from(&(Jri * dym.fixed_rows::<3>(3) * 4.0));
        dF.fixed_rows_mut::<6>(V)
            .copy_from(&(d_mid[i] * 4.0 + d_start[i] + d_end[i]));
        write(i, scale_rows(dF * weight, length));
    }
}
