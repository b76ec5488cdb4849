//! [`linearize_into`](super::linearize_into) at four points at once, one per f64 lane
//! ([`F4`]): eq. 13's pass 1 and pass 2 of the frictionless lanes (`linearize/lanes.rs`,
//! each lane at its own tensions), the tangential load of the one tendon with friction
//! loading the points in closed form (`tangential.rs`, `single`), and the derivative
//! columns, Woodbury's correction and the turning rates' derivatives of the scalar code.
//! Each operation is the scalar code's on each lane's values in the scalar code's order
//! (nalgebra's sums as nalgebra forms them: a 6-vector's dot product summed from +0 in
//! ascending order, a 3-vector's as (t_0 + t_1) + t_2), so each lane gives the bits of
//! the scalar linearization at its point (the tests compare them).
//!
//! Only the common path is written for lanes: the frictionless lanes' (a Cosserat rod,
//! M passing the SPD test, the same tendons in every lane), at most one tendon with
//! friction loading the points (the same in every lane) with a tangential load the closed
//! form gives (a non-zero normal load and multiplier, a positive leading coefficient and
//! a finite root) and a Schur complement 1 + g . y that is finite and non-zero.
//! [`linearize_lanes_into`] returns false as soon as a lane leaves it; the caller then
//! evaluates the points with the scalar code, which gives the error or Newton's loads.
#![allow(non_snake_case)]

use super::{FrictionLinearization, LaneResponse};
use crate::model::equations::{Model, Site};
use crate::model::linearize::CACHED_TENDONS;
use crate::model::linearize::Linearization;
use crate::model::linearize::lanes::pass1::assemble;
use crate::model::linearize::lanes::{
    M3, TendonLanes, V3, add, cross, derivative_lanes, dot, hat3, mat_mat, negate, scale, sub,
};
use crate::simd::lanes::F4;
use crate::simd::{filled, refill};
use nalgebra::{Matrix3, Matrix6, Matrix6x3, SMatrix, Vector3, Vector6};
use std::mem::MaybeUninit;

/// `tangential::Slip` in lanes (Cosserat rod).
struct SlipLanes {
    /// Its place in the list of tendons with friction.
    slot: usize,
    /// w mu, per lane.
    s: F4,
    tp: TendonLanes,
    e: [F4; 6],
    y: [F4; 6],
    g: F4,
    q: V3,
    q_hat: V3,
}

/// One lane's value picked by `mask` (a per-lane branch of the scalar code).
#[inline(always)]
fn select(mask: [bool; 4], a: F4, b: F4) -> F4 {
    F4([
        if mask[0] { a.0[0] } else { b.0[0] },
        if mask[1] { a.0[1] } else { b.0[1] },
        if mask[2] { a.0[2] } else { b.0[2] },
        if mask[3] { a.0[3] } else { b.0[3] },
    ])
}

/// Whether `f` holds in every lane.
#[inline(always)]
fn all(x: F4, f: impl Fn(f64) -> bool) -> bool {
    f(x.0[0]) && f(x.0[1]) && f(x.0[2]) && f(x.0[3])
}

/// a . b of 6-vectors as nalgebra's (summed from +0 in ascending order).
#[inline(always)]
fn dot6(a: &[F4; 6], b: &[F4; 6]) -> F4 {
    let mut sum = F4::ZERO;
    for i in 0..6 {
        sum += a[i] * b[i];
    }
    sum
}

impl SlipLanes {
    /// `Slip::project`: k (a - t (t . a)).
    #[inline(always)]
    fn project(&self, a: &V3) -> V3 {
        let t = &self.tp.t;
        scale(&sub(a, &scale(t, dot(t, a))), self.tp.k)
    }

    /// `Slip::normal_change`: the projection of x_v - r x x_u.
    #[inline(always)]
    fn normal_change(&self, x: &[F4; 6]) -> V3 {
        self.project(&sub(&[x[0], x[1], x[2]], &cross(&self.tp.r, &[x[3], x[4], x[5]])))
    }

    /// `Slip::refresh` (its magnitude unused).
    #[inline(always)]
    fn refresh(&mut self, x: &[F4; 6]) {
        self.q = add(&self.normal_change(x), &self.project(&self.tp.c));
        let magnitude = dot(&self.q, &self.q).sqrt();
        let positive = magnitude.0.map(|m| m > 0.0);
        self.q_hat = self.q.map(|q| select(positive, q / magnitude, F4::ZERO));
    }

    /// `Slip::gradient` (Cosserat rod).
    #[inline(always)]
    fn gradient(&self) -> [F4; 6] {
        let m = cross(&self.tp.r, &self.q_hat);
        let h = &self.q_hat;
        let f = self.s * self.tp.k;
        [h[0] * f, h[1] * f, h[2] * f, m[0] * f, m[1] * f, m[2] * f]
    }
}

/// `tangential::single` in lanes: the tangential load and the rates with it, None where a
/// lane leaves the closed form's common path (module docs).
#[inline(always)]
fn single(slip: &mut SlipLanes, x0: &[F4; 6]) -> Option<[F4; 6]> {
    let q0 = add(&slip.normal_change(x0), &slip.project(&slip.tp.c));
    let s = slip.s;
    let zero = (0..4).any(|l| q0.iter().all(|q| q.0[l] == 0.0));
    if zero || !all(s, |s| s != 0.0) {
        return None;
    }
    let a = slip.normal_change(&slip.y);
    let s2 = s * s;
    let leading = F4::splat(1.0) - s2 * dot(&a, &a);
    if !all(leading, |l| l > 0.0) {
        return None;
    }
    let linear = F4::splat(2.0) * s2 * dot(&q0, &a);
    let constant = -s2 * dot(&q0, &q0);
    let root = (linear * linear - F4::splat(4.0) * leading * constant).sqrt();
    let t = select(
        linear.0.map(|l| l >= 0.0),
        F4::splat(-0.5) * (linear + root),
        F4::splat(0.5) * (root - linear),
    );
    let (first, second) = (t / leading, constant / t);
    let mut g = first;
    for l in 0..4 {
        g.0[l] = if s.0[l] > 0.0 {
            first.0[l].max(second.0[l])
        } else {
            first.0[l].min(second.0[l])
        };
    }
    if !all(g, f64::is_finite) {
        return None;
    }
    slip.g = g;
    let mut x = *x0;
    for (x, y) in x.iter_mut().zip(&slip.y) {
        *x -= *y * g;
    }
    slip.refresh(&x);
    Some(x)
}

/// [`super::linearize_into`] at four points (one site, state, model and multipliers per
/// lane, the same `segment_end` and tendons with friction `slipping`), written into `out`:
/// true when every lane took the common path (module docs), else false with `out` partly
/// written (evaluate the points with the scalar code then, which refills every field).
/// With derivatives and `loads` (one matrix of loads per lane, one load per row), each
/// lane's [`FrictionLinearization::load_response`] to its loads too, which the point then
/// returns for them.
/// Always inlined, for the AVX2 build of its caller.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn linearize_lanes_into(
    models: [&Model; 4],
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
    slipping: &[usize],
    multipliers: [Option<&[f64]>; 4],
    derivatives: bool,
    loads: Option<&[SMatrix<f64, 6, 6>; 4]>,
    out: [&mut FrictionLinearization; 4],
) -> bool {
    if slipping.len() > CACHED_TENDONS {
        return false;
    }
    let mut tendons = [const { MaybeUninit::<TendonLanes>::uninit() }; CACHED_TENDONS];
    let Some(pass1) = assemble(models, sites, segment_end, states, &mut tendons) else {
        return false;
    };
    // SAFETY: the first `count` slots were written by `assemble` (MaybeUninit<T> has T's
    // layout; TendonLanes is Copy).
    let taut = unsafe { std::slice::from_raw_parts(tendons.as_ptr().cast::<TendonLanes>(), pass1.count) };
    let robot_tendons = &models[0].robot.tendons;
    // `tangential::solve`: the tendons with friction loading the points, in order.
    let mut slip = None;
    for (c, tp) in taut.iter().enumerate() {
        let i = pass1.indices[c];
        let (Some(friction), Some(slot)) = (
            robot_tendons[i].active_friction(),
            slipping.iter().position(|&j| j == i),
        ) else {
            continue;
        };
        if slip.is_some() {
            return false;
        }
        let sign = |l: usize| multipliers[l].map_or(friction.motion.sign(), |w| w[slot]) * friction.coefficient;
        let m = cross(&tp.r, &tp.t);
        let e = [tp.t[0], tp.t[1], tp.t[2], m[0], m[1], m[2]];
        let mut rows = [e];
        pass1.factor.solve_rows(&mut rows);
        slip = Some(SlipLanes {
            slot,
            s: F4([sign(0), sign(1), sign(2), sign(3)]),
            tp: *tp,
            e,
            y: rows[0],
            g: F4::ZERO,
            q: [F4::ZERO; 3],
            q_hat: [F4::ZERO; 3],
        });
    }
    let x = match &mut slip {
        Some(slip) => match single(slip, &pass1.x) {
            Some(x) => x,
            None => return false,
        },
        None => pass1.x,
    };
    let k = slipping.len();
    // The turning rates: kappa = |q| inv_speed / k, w mu kappa = g inv_speed / k.
    let turning = slip.as_ref().map(|sl| {
        let norm = dot(&sl.q, &sl.q).sqrt();
        (norm * sl.tp.inv_speed / sl.tp.k, sl.g * sl.tp.inv_speed / sl.tp.k)
    });
    if !derivatives {
        for (lane, o) in out.into_iter().enumerate() {
            forget_response(o);
            fill_values(o, k, slip.as_ref().map(|sl| sl.slot), turning, lane);
            o.lin = Linearization {
                rates: filled(|i, _| x[i].lane(lane)),
                d_strains: Matrix6::zeros(),
                d_rotation: Matrix6x3::zeros(),
            };
        }
        return true;
    }
    let Some(derived) = derive(&pass1, taut, &x, slip.as_ref()) else {
        return false;
    };
    let mut out = out;
    match loads {
        Some(loads) => respond(&pass1, slip.as_ref(), loads, k, &mut out),
        None => out.iter_mut().for_each(|o| forget_response(o)),
    }
    for (lane, o) in out.into_iter().enumerate() {
        fill_values(o, k, slip.as_ref().map(|sl| sl.slot), turning, lane);
        let dx = &derived.dx;
        o.lin = Linearization {
            rates: filled(|i, _| x[i].lane(lane)),
            d_strains: filled(|i, c| dx[c][i].lane(lane)),
            d_rotation: filled(|i, c| dx[6 + c][i].lane(lane)),
        };
        refill(&mut o.d_log_tension, k, |_| Vector6::zeros());
        refill(&mut o.d_turning, k, |_| SMatrix::zeros());
        refill(&mut o.d_turning_log_tension, k * k, |_| 0.0);
        if let (Some(sl), Some((d_log, d_turning, d_turning_log))) = (&slip, &derived.slip) {
            o.d_log_tension[sl.slot] = filled(|i, _| d_log[i].lane(lane));
            o.d_turning[sl.slot] = filled(|_, c| d_turning[c].lane(lane));
            for (l, d) in d_turning_log.iter().enumerate().take(k) {
                o.d_turning_log_tension[sl.slot * k + l] = d.lane(lane);
            }
        }
    }
    true
}

/// Lane `lane`'s kappa and turning rates into `o` (zero but at `slot`), its derivative
/// buffers emptied, and the scalar code's scratch (eq. 13's point and the slips, which
/// [`FrictionLinearization::load_response`] reads) forgotten: it holds no evaluation of
/// this point.
#[inline(always)]
fn fill_values(o: &mut FrictionLinearization, k: usize, slot: Option<usize>, turning: Option<(F4, F4)>, lane: usize) {
    o.point = None;
    o.slips.clear();
    refill(&mut o.kappa, k, |_| 0.0);
    refill(&mut o.turning, k, |_| 0.0);
    if let (Some(slot), Some((kappa, turning))) = (slot, turning) {
        o.kappa[slot] = kappa.lane(lane);
        o.turning[slot] = turning.lane(lane);
    }
    o.d_log_tension.clear();
    o.d_turning.clear();
    o.d_turning_log_tension.clear();
}

/// `FrictionLinearization::load_response` of each lane to its `loads` (one load per row),
/// kept in lane l's linearization in `out` (its buffers reused):
/// M^-1 by the lanes' factors, the one-slip Woodbury correction (its 1 + g . y checked
/// non-zero by [`derive`]) and the turning responses, as the scalar code forms them.
#[inline(always)]
fn respond(
    pass1: &crate::model::linearize::lanes::pass1::Assembled,
    slip: Option<&SlipLanes>,
    loads: &[SMatrix<f64, 6, 6>; 4],
    k: usize,
    out: &mut [&mut FrictionLinearization; 4],
) {
    let mut rows: [[F4; 6]; 6] = [[F4::ZERO; 6]; 6];
    for (r, row) in rows.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = F4([loads[0][(r, c)], loads[1][(r, c)], loads[2][(r, c)], loads[3][(r, c)]]);
        }
    }
    pass1.factor.solve_rows(&mut rows);
    let mut turning = [[F4::ZERO; 6]; 1];
    if let Some(sl) = slip {
        let gradient = sl.gradient();
        let schur = F4::splat(1.0) + dot6(&gradient, &sl.y);
        for row in rows.iter_mut() {
            let w = dot6(&gradient, row) / schur;
            for (m, y) in row.iter_mut().zip(&sl.y) {
                *m -= *y * w;
            }
        }
        let factor = sl.s * sl.tp.inv_speed / sl.tp.k;
        for (r, row) in rows.iter().enumerate() {
            turning[0][r] = factor * dot(&sl.q_hat, &sl.normal_change(row));
        }
    }
    for (lane, o) in out.iter_mut().enumerate() {
        let kept = o.lane_response.get_or_insert_with(|| LaneResponse {
            input: SMatrix::zeros(),
            output: SMatrix::zeros(),
            turning: Vec::new(),
            valid: false,
            current: false,
        });
        kept.current = true;
        kept.input = loads[lane];
        for (r, row) in rows.iter().enumerate() {
            for (c, value) in row.iter().enumerate() {
                kept.output[(r, c)] = value.lane(lane);
            }
        }
        refill(&mut kept.turning, k, |_| SMatrix::zeros());
        if let Some(sl) = slip {
            for (r, value) in turning[0].iter().enumerate() {
                kept.turning[sl.slot][r] = value.lane(lane);
            }
        }
        kept.valid = kept.output.iter().all(|v| v.is_finite());
    }
}

/// Marks `o`'s lane response as not of its current evaluation (its buffers kept).
#[inline(always)]
fn forget_response(o: &mut FrictionLinearization) {
    if let Some(kept) = &mut o.lane_response {
        kept.current = false;
    }
}

/// `woodbury` of the scalar code with one slip: `mb` minus y (S^-1 (g . mb)).
#[inline(always)]
fn woodbury(mb: &mut [F4; 6], gradient: &[F4; 6], inverse: F4, y: &[F4; 6]) {
    let w = inverse * dot6(gradient, mb);
    for (m, y) in mb.iter_mut().zip(y) {
        *m -= *y * w;
    }
}

/// Column c of a 3x3 matrix of lanes.
#[inline(always)]
fn column_of(m: &M3, c: usize) -> V3 {
    [m[0][c], m[1][c], m[2][c]]
}

/// The derivatives of [`linearize_lanes_into`]: d(v', u')/d(v, u, phi) (row c direction c),
/// and for the slip d(v', u')/dz, d(turning)/d(v, u, phi) and d(turning)/dz_l (one per
/// tendon with friction, at most [`CACHED_TENDONS`] read).
struct Derived {
    dx: [[F4; 6]; 9],
    slip: Option<([F4; 6], [F4; 9], [F4; CACHED_TENDONS])>,
}

/// The scalar code's derivatives at the rates `x`: dF with the tangential load's terms,
/// solved with M and corrected by Woodbury; None where 1 + g . y is zero or not finite.
#[inline(always)]
fn derive(
    pass1: &crate::model::linearize::lanes::pass1::Assembled,
    taut: &[TendonLanes],
    x: &[F4; 6],
    slip: Option<&SlipLanes>,
) -> Option<Derived> {
    let mut rows = derivative_lanes(pass1, taut, x);
    let Some(sl) = slip else {
        pass1.factor.solve_rows(&mut rows);
        negate(&mut rows);
        return Some(Derived { dx: rows, slip: None });
    };
    let tp = &sl.tp;
    let u = &pass1.u;
    let one = |i: usize, j: usize| F4::splat(f64::from(u8::from(i == j)));
    // P = I - t t^T; dt/dv = P / |p|, dt/du = (-P / |p|) r^
    let mut P: M3 = [[F4::ZERO; 3]; 3];
    for (i, row) in P.iter_mut().enumerate() {
        for (j, p) in row.iter_mut().enumerate() {
            *p = one(i, j) - tp.t[i] * tp.t[j];
        }
    }
    let (mut dt_dv, mut minus) = (P, P);
    for i in 0..3 {
        for j in 0..3 {
            dt_dv[i][j] = P[i][j] * tp.inv_speed;
            minus[i][j] = -P[i][j] * tp.inv_speed;
        }
    }
    let dt_du = mat_mat(&minus, &hat3(&tp.r));
    let (Q, dq_du) = tp.normal_derivative(&[x[0], x[1], x[2]], &[x[3], x[4], x[5]], u);
    let mut explicit = [F4::ZERO; 6];
    for (c, x) in explicit.iter_mut().enumerate() {
        let qq = if c < 3 {
            column_of(&Q, c)
        } else {
            column_of(&dq_du, c - 3)
        };
        *x = dot(&sl.q_hat, &qq);
    }
    for c in 0..6 {
        let dg = explicit[c] * sl.s;
        let dt = if c < 3 {
            column_of(&dt_dv, c)
        } else {
            column_of(&dt_du, c - 3)
        };
        let de_top = scale(&dt, sl.g);
        let de_bottom = scale(&cross(&tp.r, &dt), sl.g);
        for r in 0..3 {
            rows[c][r] += de_top[r] + sl.e[r] * dg;
            rows[c][r + 3] += de_bottom[r] + sl.e[r + 3] * dg;
        }
    }
    let m = cross(&tp.r, &sl.q);
    let q_m = [sl.q[0], sl.q[1], sl.q[2], m[0], m[1], m[2]];
    let mut column = q_m;
    for (c, e) in column.iter_mut().zip(&sl.e) {
        *c += *e * sl.g;
    }
    // Woodbury with one slip: S = 1 + g . y, S^-1 as `dense::solve_dense` gives it.
    let gradient = sl.gradient();
    let schur = F4::splat(1.0) + dot6(&gradient, &sl.y);
    if !all(schur, |s| s != 0.0 && s.is_finite()) {
        return None;
    }
    let inverse = F4::splat(1.0) / schur;
    if !all(inverse, f64::is_finite) {
        return None;
    }
    pass1.factor.solve_rows(&mut rows);
    for row in rows.iter_mut() {
        woodbury(row, &gradient, inverse, &sl.y);
    }
    negate(&mut rows);
    let dx = rows;
    let mut solved = [column];
    pass1.factor.solve_rows(&mut solved);
    woodbury(&mut solved[0], &gradient, inverse, &sl.y);
    negate(&mut solved);
    let [d_log] = solved;
    // turning = w mu |q| / tau: d = (w mu / tau) q^ . (dq|x + dq through dx).
    let factor = sl.s * tp.inv_speed / tp.k;
    let mut d_turning = [F4::ZERO; 9];
    for (c, d) in d_turning.iter_mut().enumerate() {
        let through = dot(&sl.q_hat, &sl.normal_change(&dx[c]));
        let direct = if c < 6 { explicit[c] } else { F4::ZERO };
        *d = factor * (direct + through);
    }
    // d turning / dz_l: the slip's own column, the zero columns of the others.
    let zero = factor * dot(&sl.q_hat, &sl.normal_change(&[F4::ZERO; 6]));
    let own = factor * dot(&sl.q_hat, &sl.normal_change(&d_log));
    let mut d_turning_log = [zero; CACHED_TENDONS];
    if let Some(d) = d_turning_log.get_mut(sl.slot) {
        *d = own;
    }
    Some(Derived {
        dx,
        slip: Some((d_log, d_turning, d_turning_log)),
    })
}

/// The robots the lane tests of friction run on: the prototype with friction 0.1 on
/// tendon 1 pulled at 2 N (friction S), case H with friction 0.3 on its helix pulled
/// (friction H), and that helix released with friction 0.2.
#[cfg(test)]
pub(crate) fn friction_robots() -> [crate::Robot; 3] {
    use crate::model::tendon::{Friction, Motion};
    let mut s = crate::cases::prototype();
    s.tendons[0].friction = Some(Friction::pull(0.1));
    s.tendons[0].set_tension(2.0);
    let mut h = crate::cases::case_h();
    h.tendons[4].friction = Some(Friction::pull(0.3));
    let mut released = h.clone();
    released.tendons[4].friction = Some(Friction {
        coefficient: 0.2,
        motion: Motion::Release,
    });
    [s, h, released]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::model::friction::{linearize, slipping};
    use crate::model::tendon::Friction;
    use crate::so3;

    /// Every field a caller reads of a friction linearization, as bits.
    fn bits(l: &FrictionLinearization) -> Vec<u64> {
        let lin = &l.lin;
        let mut out: Vec<f64> = lin
            .rates
            .iter()
            .chain(lin.d_strains.iter())
            .chain(lin.d_rotation.iter())
            .copied()
            .collect();
        out.extend(l.d_log_tension.iter().flat_map(|v| v.iter().copied()));
        out.extend(l.turning.iter().chain(&l.kappa).copied());
        out.extend(l.d_turning.iter().flat_map(|v| v.iter().copied()));
        out.extend(&l.d_turning_log_tension);
        out.push(f64::from(
            u32::try_from(l.d_log_tension.len() + 100 * l.d_turning.len()).unwrap_or(0),
        ));
        out.into_iter().map(f64::to_bits).collect()
    }

    /// Four lanes of `robot` against the scalar linearization at the same points: sites
    /// along the rod, bent and twisted states, each lane's tensions of the tendons with
    /// friction scaled apart (a tension profile), multipliers `w` per lane when given. True
    /// when the lanes took the points (then each lane's bits are the scalar ones).
    fn compare(robot: &crate::Robot, w: [Option<&[f64]>; 4], derivatives: bool) -> bool {
        let slipping = slipping(robot);
        let base = Model::new(robot);
        let models: [Model; 4] = std::array::from_fn(|l| {
            let mut m = base.clone();
            for &i in &slipping {
                m.tensions[i] *= (-0.07 * l as f64 - 0.01).exp();
            }
            m
        });
        let end = robot.length();
        let sites: [Site; 4] = std::array::from_fn(|l| base.site(end * (0.05 + 0.11 * l as f64)));
        let R: [Matrix3<f64>; 4] =
            std::array::from_fn(|l| so3::exp(&(Vector3::new(0.3, -0.7, 0.4) * (1.0 + l as f64))));
        let v: [Vector3<f64>; 4] = std::array::from_fn(|l| Vector3::new(0.01, -0.02 * l as f64, 0.98));
        let u: [Vector3<f64>; 4] = std::array::from_fn(|l| Vector3::new(4.0 - l as f64, 9.0, -3.0 + 0.5 * l as f64));
        let loads: [SMatrix<f64, 6, 6>; 4] =
            std::array::from_fn(|l| SMatrix::from_fn(|i, j| (R[l][(i % 3, j % 3)] + 0.1 * (i + 2 * j) as f64) * 1e-3));
        let mut lanes: [FrictionLinearization; 4] = std::array::from_fn(|_| FrictionLinearization::default());
        let [a, b, c, d] = &mut lanes;
        let taken = linearize_lanes_into(
            models.each_ref(),
            sites.each_ref(),
            end,
            std::array::from_fn(|l| (&R[l], &v[l], &u[l])),
            &slipping,
            w,
            derivatives,
            derivatives.then_some(&loads),
            [a, b, c, d],
        );
        if !taken {
            return false;
        }
        for l in 0..4 {
            let scalar = linearize(
                &models[l],
                &sites[l],
                end,
                (&R[l], &v[l], &u[l]),
                &slipping,
                w[l],
                derivatives,
            )
            .unwrap();
            assert!(scalar.turning.iter().any(|t| *t != 0.0), "lane {l}: no friction here");
            assert_eq!(bits(&lanes[l]), bits(&scalar), "lane {l}");
            assert!(lanes[l].point.is_none() && lanes[l].slips.is_empty());
            // The response to the lane's loads is the scalar point's, bit for bit; to other
            // loads the lanes give none.
            let mut turns = [
                vec![SMatrix::<f64, 1, 6>::zeros(); slipping.len()],
                vec![SMatrix::zeros(); slipping.len()],
            ];
            let (mut mine, mut theirs) = (loads[l], loads[l]);
            let [t0, t1] = &mut turns;
            assert_eq!(lanes[l].load_response(&mut mine, t0), derivatives);
            if derivatives {
                assert!(scalar.load_response(&mut theirs, t1));
                let bits6 = |m: &SMatrix<f64, 6, 6>| m.map(f64::to_bits);
                assert_eq!(bits6(&mine), bits6(&theirs), "lane {l} response");
                assert_ne!(bits6(&mine), bits6(&loads[l]));
                let tb =
                    |t: &[SMatrix<f64, 1, 6>]| t.iter().flat_map(|t| t.iter().map(|x| x.to_bits())).collect::<Vec<_>>();
                assert_eq!(tb(t0), tb(t1), "lane {l} turning response");
                let mut other = loads[(l + 1) % 4];
                assert!(!lanes[l].load_response(&mut other, t0));
            }
        }
        true
    }

    /// Each lane gives the scalar linearization's bits (the lanes compiled for the
    /// baseline here, the scalar code for AVX2 where the processor has it: the same
    /// operations in the same order), with and without derivatives: the prototype with
    /// friction on tendon 1 pulled (friction S), case H with friction on its helix pulled
    /// and released (friction H), and per-lane multipliers of a history (a stuck link's
    /// fraction in one lane).
    #[test]
    fn lanes_give_the_scalar_bits() {
        let robots = friction_robots();
        for robot in &robots {
            for derivatives in [false, true] {
                assert!(compare(robot, [None; 4], derivatives));
            }
        }
        let (slide, stuck) = ([-1.0], [0.37]);
        let w = [Some(&slide[..]), Some(&stuck[..]), Some(&slide[..]), Some(&[1.0][..])];
        assert!(compare(&robots[1], w, true));
    }

    /// Where the lanes decline (two tendons with friction loading the points: Newton's
    /// loads; a Kirchhoff rod; a zero multiplier), the caller evaluates the points with the
    /// scalar code.
    #[test]
    fn lanes_decline_what_they_do_not_take() {
        let mut two = cases::case_h();
        two.tendons[4].friction = Some(Friction::pull(0.3));
        two.tendons[0].set_tension(1.5);
        two.tendons[0].friction = Some(Friction::pull(0.2));
        assert!(!compare(&two, [None; 4], true));
        let mut kirchhoff = cases::case_h();
        kirchhoff.tendons[4].friction = Some(Friction::pull(0.3));
        kirchhoff.rod_model = crate::model::robot::RodModel::Kirchhoff;
        assert!(!compare(&kirchhoff, [None; 4], true));
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.3));
        let zero = [0.0];
        assert!(!compare(&h, [None, Some(&zero[..]), None, None], false));
    }
}
