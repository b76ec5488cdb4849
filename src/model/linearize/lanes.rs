//! [`linearize_keeping`](super::linearize_keeping) at four points at once, one per f64 lane
//! ([`F4`]): eq. 13's assembly, its factorization by 3x3 blocks, dF and the solves, each
//! operation the scalar code's on each lane's values in the scalar code's order (nalgebra's
//! sums as nalgebra forms them: a 3-term dot product or matrix-vector entry as
//! (t_0 + t_1) + t_2, a cross product's entries as `a_y b_z - a_z b_y` and so on), so each
//! lane gives the bits of the scalar linearization at its point.
//!
//! Only the path every lane takes in a default solve is written for lanes: a Cosserat rod,
//! at most [`CACHED_TENDONS`](super::CACHED_TENDONS) tendons, and an M whose blocks pass the
//! SPD test of [`Factor`](super::factor::Factor) in every lane. [`linearize_lanes`] returns
//! false as soon as one lane leaves it (a Kirchhoff rod, a vanishing tendon tangent, the
//! LU fallback, a tendon set that differs between the lanes); the caller then evaluates the
//! points with the scalar code, which gives the error or the fallback's values.
#![allow(non_snake_case)]

pub(in crate::model) mod pass1;
mod tensions;
pub(crate) use pass1::rates_lanes;
use pass1::{Assembled, assemble};

use super::{CACHED_TENDONS, Linearization};
use crate::model::equations::{MIN_TENDON_SPEED, Model, Site};
use crate::simd::lanes::F4;
use nalgebra::{Matrix3, Vector3};
use std::mem::MaybeUninit;
pub(crate) use tensions::TensionLanes;

/// A 3-vector of lanes.
pub(in crate::model) type V3 = [F4; 3];
/// A 3x3 matrix of lanes, `m[row][column]`.
pub(in crate::model) type M3 = [[F4; 3]; 3];

pub(in crate::model) const Z3: V3 = [F4::ZERO; 3];
pub(in crate::model) const Z33: M3 = [[F4::ZERO; 3]; 3];

/// The four lanes' values of a 3-vector.
#[inline(always)]
pub(in crate::model) fn gather(v: [&Vector3<f64>; 4]) -> V3 {
    let mut out = Z3;
    for (i, x) in out.iter_mut().enumerate() {
        *x = F4([v[0][i], v[1][i], v[2][i], v[3][i]]);
    }
    out
}

/// The four lanes' values of a 3x3 matrix.
#[inline(always)]
pub(in crate::model) fn gather3(m: [&Matrix3<f64>; 4]) -> M3 {
    let mut out = Z33;
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = F4([m[0][(r, c)], m[1][(r, c)], m[2][(r, c)], m[3][(r, c)]]);
        }
    }
    out
}

#[inline(always)]
pub(in crate::model) fn add(a: &V3, b: &V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(in crate::model) fn sub(a: &V3, b: &V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(in crate::model) fn mul(a: &V3, b: &V3) -> V3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

#[inline(always)]
pub(in crate::model) fn scale(a: &V3, k: F4) -> V3 {
    [a[0] * k, a[1] * k, a[2] * k]
}

/// a . b as nalgebra's 3-vector dot: (a_0 b_0 + a_1 b_1) + a_2 b_2.
#[inline(always)]
pub(in crate::model) fn dot(a: &V3, b: &V3) -> F4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a x b as nalgebra's `cross`.
#[inline(always)]
pub(in crate::model) fn cross(a: &V3, b: &V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// m v as nalgebra's product: entry i is (m_i0 v_0 + m_i1 v_1) + m_i2 v_2.
#[inline(always)]
pub(in crate::model) fn mat_vec(m: &M3, v: &V3) -> V3 {
    let mut out = Z3;
    for (x, row) in out.iter_mut().zip(m) {
        *x = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
    }
    out
}

/// m^T v as nalgebra's `tr_mul` (column dot products).
#[inline(always)]
pub(in crate::model) fn tr_vec(m: &M3, v: &V3) -> V3 {
    let mut out = Z3;
    for (i, x) in out.iter_mut().enumerate() {
        *x = m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2];
    }
    out
}

/// a b as nalgebra's product.
#[inline(always)]
pub(in crate::model) fn mat_mat(a: &M3, b: &M3) -> M3 {
    // Loops, not closures: a closure here stayed a call compiled for the baseline.
    let mut out = Z33;
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

/// a^T b as nalgebra's `tr_mul` (dot products of columns).
#[inline(always)]
pub(in crate::model) fn tr_mat(a: &M3, b: &M3) -> M3 {
    let mut out = Z33;
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[0][i] * b[0][j] + a[1][i] * b[1][j] + a[2][i] * b[2][j];
        }
    }
    out
}

#[inline(always)]
pub(in crate::model) fn add_m(a: &mut M3, b: &M3) {
    for (ra, rb) in a.iter_mut().zip(b) {
        for (x, y) in ra.iter_mut().zip(rb) {
            *x += *y;
        }
    }
}

/// `tendon::mul_hat`: m a^, row j is (m_j x a)^T.
#[inline(always)]
pub(in crate::model) fn mul_hat(m: &M3, a: &V3) -> M3 {
    let mut out = Z33;
    for (o, m) in out.iter_mut().zip(m) {
        *o = [
            m[1] * a[2] - m[2] * a[1],
            m[2] * a[0] - m[0] * a[2],
            m[0] * a[1] - m[1] * a[0],
        ];
    }
    out
}

/// `tendon::hat_mul` on a 3 x C matrix given by its columns: a^ m, column l is a x m_l.
#[inline(always)]
pub(in crate::model) fn hat_mul(a: &V3, m: &M3) -> M3 {
    let mut out = Z33;
    for l in 0..3 {
        out[0][l] = a[1] * m[2][l] - a[2] * m[1][l];
        out[1][l] = a[2] * m[0][l] - a[0] * m[2][l];
        out[2][l] = a[0] * m[1][l] - a[1] * m[0][l];
    }
    out
}

/// `linearize::hat3`.
#[inline(always)]
pub(in crate::model) fn hat3(a: &V3) -> M3 {
    let z = F4::ZERO;
    [[z, -a[2], a[1]], [a[2], z, -a[0]], [-a[1], a[0], z]]
}

/// `linearize::hat_diag`: a^ diag(d) + diag(d_s).
#[inline(always)]
pub(in crate::model) fn hat_diag(a: &V3, d: &V3, d_s: &V3) -> M3 {
    [
        [d_s[0], -a[2] * d[1], a[1] * d[2]],
        [a[2] * d[0], d_s[1], -a[0] * d[2]],
        [-a[1] * d[0], a[0] * d[1], d_s[2]],
    ]
}

/// `tendon::TendonPoint` in lanes (Cosserat rod).
#[derive(Clone, Copy)]
pub(in crate::model) struct TendonLanes {
    pub(in crate::model) r: V3,
    pub(in crate::model) e: V3,
    pub(in crate::model) c: V3,
    pub(in crate::model) t: V3,
    pub(in crate::model) k: F4,
    pub(in crate::model) inv_speed: F4,
}

impl TendonLanes {
    /// `TendonPoint::new` (each lane at its tension); None when a lane's tangent is shorter
    /// than the scalar code accepts (it reports the error).
    #[inline(always)]
    fn new(tension: F4, rp: [&crate::model::routing::RoutingPoint; 4], v: &V3, u: &V3) -> Option<Self> {
        let r = gather([&rp[0].r, &rp[1].r, &rp[2].r, &rp[3].r]);
        let r_s = gather([&rp[0].r_s, &rp[1].r_s, &rp[2].r_s, &rp[3].r_s]);
        let r_ss = gather([&rp[0].r_ss, &rp[1].r_ss, &rp[2].r_ss, &rp[3].r_ss]);
        let p = add(&add(&cross(u, &r), &r_s), v);
        let speed = dot(&p, &p).sqrt();
        // The scalar test (`speed < MIN` reports an error; NaN passes it), lane by lane.
        if speed.0.iter().any(|&s| s < MIN_TENDON_SPEED) {
            return None;
        }
        let inv_speed = F4::splat(1.0) / speed;
        let e = add(&p, &r_s);
        let c = add(&cross(u, &e), &r_ss);
        Some(TendonLanes {
            r,
            e,
            c,
            t: scale(&p, inv_speed),
            k: tension * inv_speed,
            inv_speed,
        })
    }

    /// `TendonPoint::A`.
    #[inline(always)]
    pub(in crate::model) fn A(&self) -> M3 {
        let (t, k) = (&self.t, self.k);
        let kt = scale(t, k);
        let (xy, xz, yz) = (-kt[0] * t[1], -kt[0] * t[2], -kt[1] * t[2]);
        [
            [k - kt[0] * t[0], xy, xz],
            [xy, k - kt[1] * t[1], yz],
            [xz, yz, k - kt[2] * t[2]],
        ]
    }

    /// `TendonPoint::normal_derivative` (Cosserat rod): [dq/dv, dq/du] as two 3x3 blocks.
    #[inline(always)]
    pub(in crate::model) fn normal_derivative(&self, x_v: &V3, x_u: &V3, u: &V3) -> (M3, M3) {
        let A = self.A();
        let t = &self.t;
        let z = add(&sub(x_v, &cross(&self.r, x_u)), &self.c);
        let alpha = dot(t, &z);
        let z_perp = sub(&z, &scale(t, alpha));
        let g = -alpha * self.inv_speed;
        let h = -self.k * self.inv_speed;
        let hz = scale(&z_perp, h);
        let mut Q = Z33;
        for j in 0..3 {
            for l in j..3 {
                let J_jl = g * A[j][l] + hz[j] * t[l] + t[j] * hz[l];
                Q[j][l] = J_jl;
                Q[l][j] = J_jl;
            }
        }
        add_m(&mut Q, &mul_hat(&A, u));
        let minus_r = [-self.r[0], -self.r[1], -self.r[2]];
        let minus_e = [-self.e[0], -self.e[1], -self.e[2]];
        let mut dq_du = mul_hat(&Q, &minus_r);
        add_m(&mut dq_du, &mul_hat(&A, &minus_e));
        (Q, dq_du)
    }
}

/// `factor::spd_inverse3`; None when a lane fails the SPD test.
#[inline(always)]
pub(in crate::model) fn spd_inverse3(a: &M3) -> Option<M3> {
    let c00 = a[1][1] * a[2][2] - a[1][2] * a[1][2];
    let c01 = a[0][2] * a[1][2] - a[0][1] * a[2][2];
    let c02 = a[0][1] * a[1][2] - a[0][2] * a[1][1];
    let minor2 = a[0][0] * a[1][1] - a[0][1] * a[0][1];
    let det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
    for i in 0..4 {
        let (a00, m2, d) = (a[0][0].lane(i), minor2.lane(i), det.lane(i));
        if !(a00 > 0.0 && m2 > 0.0 && d > 0.0 && d.is_finite()) {
            return None;
        }
    }
    let c11 = a[0][0] * a[2][2] - a[0][2] * a[0][2];
    let c12 = a[0][2] * a[0][1] - a[0][0] * a[1][2];
    let inv = F4::splat(1.0) / det;
    Some([
        [c00 * inv, c01 * inv, c02 * inv],
        [c01 * inv, c11 * inv, c12 * inv],
        [c02 * inv, c12 * inv, minor2 * inv],
    ])
}

/// `factor::Schur6` for a Cosserat rod (M symmetric, rho = 1).
pub(in crate::model) struct Schur {
    P_inv: M3,
    G: M3,
    W: M3,
    S_inv: M3,
}

impl Schur {
    /// `Schur6::new` from M's blocks P, G and Q.
    #[inline(always)]
    fn new(P: &M3, G: &M3, Q: &M3) -> Option<Self> {
        let P_inv = spd_inverse3(P)?;
        let W = mat_mat(&P_inv, G);
        let GtW = tr_mat(G, &W);
        let mut S = *Q;
        sub_m(&mut S, &GtW);
        let mut sym = Z33;
        for (i, row) in sym.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (S[i][j] + S[j][i]) * 0.5;
            }
        }
        let S_inv = spd_inverse3(&sym)?;
        Some(Schur { P_inv, G: *G, W, S_inv })
    }

    /// `Schur6::solve_transposed_mut` on rows: each row (b_v, b_u) of `rows` overwritten
    /// with its solution.
    #[inline(always)]
    pub(in crate::model) fn solve_rows<const C: usize>(&self, rows: &mut [[F4; 6]; C]) {
        let (P, G, S, W) = (&self.P_inv, &self.G, &self.S_inv, &self.W);
        for b in rows.iter_mut() {
            let (mut w, mut y, mut x_u) = (Z3, Z3, Z3);
            for j in 0..3 {
                w[j] = b[0] * P[0][j] + b[1] * P[1][j] + b[2] * P[2][j];
            }
            for j in 0..3 {
                y[j] = b[3 + j] - (w[0] * G[0][j] + w[1] * G[1][j] + w[2] * G[2][j]);
            }
            for j in 0..3 {
                x_u[j] = y[0] * S[0][j] + y[1] * S[1][j] + y[2] * S[2][j];
            }
            for j in 0..3 {
                b[j] = w[j] - (x_u[0] * W[j][0] + x_u[1] * W[j][1] + x_u[2] * W[j][2]);
                b[3 + j] = x_u[j];
            }
        }
    }
}

/// The lanes of a site's quantities that eq. 13 reads.
pub(in crate::model) struct SiteLanes {
    kse: V3,
    kbt: V3,
    kse_s: V3,
    kbt_s: V3,
    v_star: V3,
    u_star: V3,
    v_star_s: V3,
    u_star_s: V3,
    f_e: V3,
    l_e: V3,
    f_follower: V3,
}

impl SiteLanes {
    #[inline(always)]
    fn new(sites: [&Site; 4]) -> Self {
        let [s0, s1, s2, s3] = sites;
        // A macro, not a closure of field accessors (those would be calls).
        macro_rules! gather {
            ($($field:ident).+) => {
                gather([&s0.$($field).+, &s1.$($field).+, &s2.$($field).+, &s3.$($field).+])
            };
        }
        SiteLanes {
            kse: gather!(section.section.kse),
            kbt: gather!(section.section.kbt),
            kse_s: gather!(section.kse_s),
            kbt_s: gather!(section.kbt_s),
            v_star: gather!(reference.v_star),
            u_star: gather!(reference.u_star),
            v_star_s: gather!(reference.v_star_s),
            u_star_s: gather!(reference.u_star_s),
            f_e: gather!(f_e),
            l_e: gather!(l_e),
            f_follower: gather!(f_follower),
        }
    }
}

/// [`super::linearize_keeping`] without keeping at four points (one site and state per
/// lane, the same `segment_end`), written into `out`, with `tensions` also
/// [`super::linearize_tensions_inline`]'s derivatives in every tension: true when every
/// lane took the uniform path (module docs), else false with `out` and `tensions` partly
/// written (evaluate the points with the scalar code then). Always inlined, for the AVX2
/// build of its caller.
#[inline(always)]
pub(crate) fn linearize_lanes(
    model: &Model,
    sites: [&Site; 4],
    segment_end: f64,
    states: [(&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>); 4],
    out: &mut [Linearization; 4],
    tensions: Option<TensionLanes>,
) -> bool {
    // Only the first `count` slots are written and read (zeroing all 8 was a memset).
    let mut tendons = [const { MaybeUninit::<TendonLanes>::uninit() }; CACHED_TENDONS];
    let Some(pass1) = assemble([model; 4], sites, segment_end, states, &mut tendons) else {
        return false;
    };
    // SAFETY: the first `count` slots were written by `assemble` (MaybeUninit<T> has T's
    // layout; TendonLanes is Copy).
    let taut = unsafe { std::slice::from_raw_parts(tendons.as_ptr().cast::<TendonLanes>(), pass1.count) };
    let x = pass1.x;
    if let Some(tensions) = tensions {
        let solved = tensions::Solved {
            v: &pass1.v,
            u: &pass1.u,
            x_v: &[x[0], x[1], x[2]],
            x_u: &[x[3], x[4], x[5]],
            factor: &pass1.factor,
        };
        if !tensions::tension_lanes(model, sites, segment_end, taut, &solved, tensions) {
            return false;
        }
    }
    let mut dFt = derivative_lanes(&pass1, taut, &x);
    pass1.factor.solve_rows(&mut dFt);
    // d(v', u') = -M^-1 dF, negated in lanes (the same bits as lane by lane).
    negate(&mut dFt);
    // Lane l's values into out[l]: the rates, then row k of dF^T as column k of the
    // derivatives (six consecutive entries of the column-major d_strains or d_rotation).
    let [o0, o1, o2, o3] = out;
    let rates = [
        o0.rates.as_mut_slice(),
        o1.rates.as_mut_slice(),
        o2.rates.as_mut_slice(),
        o3.rates.as_mut_slice(),
    ];
    scatter6(&x, rates);
    for (k, row) in dFt.iter().enumerate() {
        let c = if k < 6 { 6 * k } else { 6 * (k - 6) };
        let columns = if k < 6 {
            [
                &mut o0.d_strains.as_mut_slice()[c..c + 6],
                &mut o1.d_strains.as_mut_slice()[c..c + 6],
                &mut o2.d_strains.as_mut_slice()[c..c + 6],
                &mut o3.d_strains.as_mut_slice()[c..c + 6],
            ]
        } else {
            [
                &mut o0.d_rotation.as_mut_slice()[c..c + 6],
                &mut o1.d_rotation.as_mut_slice()[c..c + 6],
                &mut o2.d_rotation.as_mut_slice()[c..c + 6],
                &mut o3.d_rotation.as_mut_slice()[c..c + 6],
            ]
        };
        scatter6(row, columns);
    }
    true
}

/// Six values of four lanes into the lanes' outputs, lane l's six into `out[l][..6]`
/// together (moves only, so the values): a transpose, not a loop of `lane` per lane and
/// value, which went through the stack value by value.
#[inline(always)]
fn scatter6(v: &[F4; 6], out: [&mut [f64]; 4]) {
    let [a, b, c, d, e, f] = [v[0].0, v[1].0, v[2].0, v[3].0, v[4].0, v[5].0];
    for (l, o) in out.into_iter().enumerate() {
        o[..6].copy_from_slice(&[a[l], b[l], c[l], d[l], e[l], f[l]]);
    }
}

/// Pass 2 (the scalar `derivative`) at four points: dF^T at the rates `x`, x held fixed,
/// from pass 1's values and its taut tendons (`taut`, in its order). Row k is direction k
/// of (v, u, phi), column j row j of F.
#[inline(always)]
pub(in crate::model) fn derivative_lanes(pass1: &Assembled, taut: &[TendonLanes], x: &[F4; 6]) -> [[F4; 6]; 9] {
    let (x_v, x_u) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
    let (site, v, u) = (&pass1.site, &pass1.v, &pass1.u);
    let (mut top_v, mut top_u, mut bottom_v, mut bottom_u) = (Z33, Z33, Z33, Z33);
    for tp in taut {
        let (dv_, du_) = tp.normal_derivative(&x_v, &x_u, u);
        add_m(&mut top_v, &dv_);
        add_m(&mut top_u, &du_);
        add_m(&mut bottom_v, &hat_mul(&tp.r, &dv_));
        add_m(&mut bottom_u, &hat_mul(&tp.r, &du_));
    }
    let n_hat = hat3(&pass1.n_b);
    let mut strain_term = hat_diag(v, &site.kse, &Z3);
    sub_m(&mut strain_term, &n_hat);
    let mut b00 = hat_diag(u, &site.kse, &site.kse_s);
    add_m(&mut b00, &top_v);
    let mut b01 = top_u;
    sub_m(&mut b01, &n_hat);
    let mut b10 = strain_term;
    add_m(&mut b10, &bottom_v);
    let mut b11 = hat_diag(u, &site.kbt, &site.kbt_s);
    sub_m(&mut b11, &hat3(&pass1.m_b));
    add_m(&mut b11, &bottom_u);
    let blocks = [[b00, b01, hat3(&pass1.f_b)], [b10, b11, hat3(&pass1.l_b)]];
    let mut dFt = [[F4::ZERO; 6]; 9];
    for (row, blocks_row) in blocks.iter().enumerate() {
        for (col, block) in blocks_row.iter().enumerate() {
            for (r, block_row) in block.iter().enumerate() {
                for (c, value) in block_row.iter().enumerate() {
                    dFt[3 * col + c][3 * row + r] = *value;
                }
            }
        }
    }
    dFt
}

/// Every entry negated (the scalar code's `-` on each lane).
#[inline(always)]
pub(in crate::model) fn negate<const R: usize>(rows: &mut [[F4; 6]; R]) {
    for row in rows.iter_mut() {
        for v in row.iter_mut() {
            *v = -*v;
        }
    }
}

#[inline(always)]
pub(in crate::model) fn sub_m(a: &mut M3, b: &M3) {
    for (ra, rb) in a.iter_mut().zip(b) {
        for (x, y) in ra.iter_mut().zip(rb) {
            *x -= *y;
        }
    }
}
