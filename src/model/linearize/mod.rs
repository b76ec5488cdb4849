//! Eq. 13 (corrected, docs/model.md) in f64, the crate's one implementation of it
//! ([`rates`]), and its exact, hand-derived linearization ([`linearize`]): the strain rates
//! (v', u') together with their derivatives with respect to the strains (v, u) and to a
//! right perturbation of the orientation R, without automatic differentiation. The unit
//! tests check both against a direct generic transcription of eq. 13 run in f64 and with
//! dual numbers.
//!
//! # Derivation
//!
//! Write the unknown rates as x = (x_v, x_u) = (v', u'). Eq. 13 is the linear system
//! M x = rhs, or F(x; R, v, u) = M x - rhs = 0 with
//! ```text
//! F_v = D x_v + (u^ D + D')(v - v*) - D v*' + R^T f_e + f_f + sum_i q_i
//! F_u = C x_u + (u^ C + C')(u - u*) - C u*' + v^ D (v - v*) + R^T l_e + sum_i r_i x q_i
//! ```
//! (f_f the follower force per length, body frame: it does not turn with R), where, per tendon i (body frame, symbols of docs/model.md section 4),
//! ```text
//! p_i  = u x r_i + r_i' + v             (p_i^b', the tendon path tangent)
//! e_i  = p_i + r_i'
//! c_i  = u x e_i + r_i''                (= u^ p_i^b' + u^ r_i' + r_i'')
//! w_i  = x_v - r_i x x_u                (= v' - r_i^ u', the part of p_i^b'' they drive)
//! z_i  = w_i + c_i                      (= p_i^b'')
//! q_i  = A_i z_i,   A_i = -tau_i (p_i^)^2 / |p_i|^3 = k_i P_i
//! k_i  = tau_i / |p_i|,   t_i = p_i / |p_i|,   P_i = I - t_i t_i^T.
//! ```
//! Indeed sum_i [A_i; r_i^ A_i] w_i = [A x_v + G x_u; B x_v + H x_u] (because
//! G = -sum A_i r_i^, B = sum r_i^ A_i, H = -sum r_i^ A_i r_i^) and
//! sum_i [A_i; r_i^ A_i] c_i = [a; b], so the tendon terms of F are sum_i [q_i; r_i x q_i].
//!
//! Differentiating F = 0 at the solution x gives dx = -M^-1 dF, where dF is the partial
//! derivative of F with x held fixed. M is factored once; the 9 directions (3 of v, 3 of u,
//! 3 of the rotation) are one solve with a 6x9 right-hand side. No 3x3x3 tensor is formed:
//! every derivative of A_i appears already contracted with z_i.
//!
//! **Derivative of A_i.** A_i = tau_i Hess |p| (p = p_i), so its derivative is the (totally
//! symmetric) third derivative of tau_i |p|. Contracted with z = alpha t + z_perp
//! (alpha = t . z, z_perp = P z) it is the symmetric 3x3 matrix
//! ```text
//! J_i(z) = d(A_i z)/dp |_(z fixed)
//!        = -(tau_i / |p|^2) (z t^T + t z^T + alpha I - 3 alpha t t^T)
//!        = -(alpha / |p|) A_i - (k_i / |p|) (z_perp t^T + t z_perp^T).
//! ```
//! **Derivative of q_i.** With dp_i/dv = I, dp_i/du = -r_i^, dc_i/dv = u^ and
//! dc_i/du = -(e_i^ + u^ r_i^) (from d(u x e_i) = du x e_i + u x (du x r_i)):
//! ```text
//! Q_i     := dq_i/dv = J_i(z_i) + A_i u^
//! dq_i/du = -J_i(z_i) r_i^ - A_i (e_i^ + u^ r_i^) = -Q_i r_i^ - A_i e_i^
//! ```
//! and the moment terms follow as r_i^ dq_i (r_i does not depend on the state).
//!
//! **Rod terms.** With n_b = D (v - v*) and m_b = C (u - u*) (body frame), and
//! d(a x b) = da x b + a x db:
//! ```text
//! dF_v/dv = u^ D + D'              dF_v/du = -n_b^
//! dF_u/dv = v^ D - n_b^            dF_u/du = u^ C + C' - m_b^
//! ```
//! **Rotation.** R enters only through R^T f_e and R^T l_e. For R -> R exp(phi^),
//! (R exp(phi^))^T f = R^T f - phi x R^T f + O(phi^2), so
//! ```text
//! dF_v/dphi = (R^T f_e)^          dF_u/dphi = (R^T l_e)^
//! ```
//! **Assembled.** With the sums over the tendons of [`Which::ActiveTo`]`(segment_end)`:
//! ```text
//!             v                          u                               phi
//! dF = [ u^ D + D' + sum Q_i        -n_b^ + sum dq_i/du           (R^T f_e)^ ]
//!      [ v^ D - n_b^ + sum r_i^ Q_i  u^ C + C' - m_b^
//!                                       + sum r_i^ dq_i/du        (R^T l_e)^ ]
//! d(v', u')/d(v, u, phi) = -M^-1 dF.
//! ```
//! Products with a hat matrix are written as cross products (m a^ has rows m_j x a, a^ m
//! has columns a x m_k), which halves their flops against a dense 3x3 product.
//!
//! **Kirchhoff rods** ([`Site::inextensible`], docs/model.md section 4b). The node's
//! translational coordinate v is then v* + D^-1 n_b and the strain is v* ([`Site::strain`]):
//! the tendon quantities are evaluated at the strain v*, v' = v*' is known and sits in c_i
//! (so in a, b), and M = [D, G; 0, C + H]. In dF the tendon columns dq_i/dv vanish (q_i sees
//! only the strain) and dF_u/dv = v*^ D (only n_b = D (v - v*) moves with the coordinate).
//!
//! # Cost
//! Two passes over the tendons (the second needs x); the per-tendon quantities of the first
//! are kept on the stack for up to 8 tendons, further ones are re-evaluated. M is factored
//! once by block elimination on its 3x3 blocks (LU fallback where rounding makes M fail the SPD test);
//! x is one solve and the nine derivative directions one solve with a 6x9 right-hand side.
//! For case H (one active tendon) a release build took about 390 ns per call on the
//! development machine with a 6x6 Cholesky factorization (before the block elimination),
//! against 280 ns for a generic 6x6 Cholesky solve of eq. 13 alone and 5.6 us for nine
//! dual-number passes of it. [`rates`] is pass 1 alone, for residuals.
#![allow(non_snake_case)]

use crate::Error;
use crate::error::Result;
use crate::model::equations::{Model, Site};
use nalgebra::{Matrix3, Matrix3x6, Matrix6, Matrix6x3, SMatrix, Vector3, Vector6};
use std::mem::MaybeUninit;

mod factor;
use factor::Factor;

pub(super) mod lanes;
pub(crate) use lanes::{TensionLanes, linearize_lanes, rates_lanes};

mod parameters;
pub(crate) use parameters::{linearize_tensions, linearize_tensions_inline, stiffness_rates, tension_rates};

mod point;
pub(crate) use point::{Factored, Point, rates_and_solve};

mod tendon;
use crate::simd::avx2_fma;
pub(crate) use tendon::TendonPoint;
use tendon::hat_mul;
pub(crate) use tendon::mul_hat;

/// Tendons whose per-tendon quantities are kept on the stack between the two passes (solve
/// for x, then differentiate at x); further tendons are re-evaluated from their routing.
/// 8 covers the usual 3-6 tendon robots (the prototype has 5) at 0.9 kB of stack.
pub(in crate::model) const CACHED_TENDONS: usize = 8;

/// The first [`CACHED_TENDONS`] tendon points of one linearization, kept on the stack
/// between its two passes. The slots past `len` stay uninitialized: zeroing all 0.9 kB
/// (`[TendonPoint::ZERO; 8]`) cost a memset of about 450 instructions per linearization,
/// 4 % of a default prototype solve, for slots a 5-tendon robot never reads.
struct TendonCache {
    points: [MaybeUninit<TendonPoint>; CACHED_TENDONS],
    len: usize,
}

impl TendonCache {
    /// An empty cache.
    fn new() -> Self {
        TendonCache {
            points: [const { MaybeUninit::uninit() }; CACHED_TENDONS],
            len: 0,
        }
    }

    /// Forgets the kept points (their slots are overwritten by the next pushes).
    fn clear(&mut self) {
        self.len = 0;
    }

    /// Keeps `tp` if a slot is free (the tendons beyond are evaluated again in pass 2).
    fn push(&mut self, tp: TendonPoint) {
        if let Some(slot) = self.points.get_mut(self.len) {
            slot.write(tp);
            self.len += 1;
        }
    }

    /// The points kept, in the order pushed.
    fn points(&self) -> &[TendonPoint] {
        // SAFETY: the first `len` slots were written by `push` (MaybeUninit<T> has T's
        // layout), and TendonPoint is Copy, so nothing is dropped.
        unsafe { std::slice::from_raw_parts(self.points.as_ptr().cast::<TendonPoint>(), self.len) }
    }
}

/// Strain rates and their exact derivatives at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Linearization {
    /// (v', u') stacked, 6-vector (1/m, rad/m^2), body frame: eq. 13 (corrected).
    pub rates: Vector6<f64>,
    /// d(v', u') / d(v, u): 6x6, rows (v', u'), columns (v, u), body frame.
    pub d_strains: Matrix6<f64>,
    /// d(v', u') / d(phi) for a right perturbation R -> R exp(hat(phi)): 6x3, phi in the body
    /// frame (rad).
    pub d_rotation: Matrix6x3<f64>,
}

impl Linearization {
    /// All zeros: a buffer for a linearization written later.
    pub(crate) fn zeros() -> Self {
        Linearization {
            rates: Vector6::zeros(),
            d_strains: Matrix6::zeros(),
            d_rotation: Matrix6x3::zeros(),
        }
    }
}

/// a^ diag(d) + diag(d_s): column l of a^ scaled by d_l, plus d_s on the diagonal.
fn hat_diag(a: &Vector3<f64>, d: &Vector3<f64>, d_s: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        d_s[0],
        -a[2] * d[1],
        a[1] * d[2],
        a[2] * d[0],
        d_s[1],
        -a[0] * d[2],
        -a[1] * d[0],
        a[0] * d[1],
        d_s[2],
    )
}

/// The hat map in f64 (`so3::hat` without the generic scalar).
fn hat3(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0)
}

/// Pass 1 of the linearization at one point: the per-tendon quantities (the first
/// [`CACHED_TENDONS`] of them, when a cache is given), the factored M and the rates x.
struct Assembled {
    factor: Factor,
    /// The rates (v', u') as a row.
    x: SMatrix<f64, 1, 6>,
    /// Tendons that load the backbone here.
    count: usize,
    /// n_b = D (v - v*), body frame (N).
    n_b: Vector3<f64>,
    /// m_b = C (u - u*), body frame (N m).
    m_b: Vector3<f64>,
    /// R^T f_e (N/m).
    f_b: Vector3<f64>,
    /// R^T l_e (N m/m).
    l_b: Vector3<f64>,
}

/// Eq. 13 (corrected) at (R, v, u): builds M and the right-hand side (module docs), factors
/// M and solves for the rates, keeping the first tendons' quantities in `cache` if given.
/// Always inlined: returned by value from a call it would copy M's factors (as it was
/// before friction made it a function of three callers).
#[inline(always)]
fn assemble(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    mut cache: Option<&mut TendonCache>,
    low: Option<&Vector3<f64>>,
) -> Result<Assembled> {
    let kse = &site.section.section.kse;
    let kbt = &site.section.section.kbt;
    let (kse_s, kbt_s) = (&site.section.kse_s, &site.section.kbt_s);
    let reference = &site.reference;
    // v - v* is exact where v is near v* (Sterbenz); the low part, when given, is the
    // strain's part below v's last place ([`rates_split`]).
    let dv = match low {
        Some(low) => (v - reference.v_star) + low,
        None => v - reference.v_star,
    };
    let du = u - reference.u_star;
    let n_b = dv.component_mul(kse); // D (v - v*)
    let m_b = du.component_mul(kbt); // C (u - u*)
    let f_b = R.tr_mul(&site.f_e); // R^T f_e
    let l_b = R.tr_mul(&site.l_e); // R^T l_e

    // The tendon blocks A, G and H of M, and a, b.
    let mut count = 0;
    let mut A = Matrix3::<f64>::zeros();
    let mut G = Matrix3::<f64>::zeros();
    let mut H = Matrix3::<f64>::zeros();
    let mut a = Vector3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for (i, tension, rp) in model.distributed_tendons(site.s, segment_end) {
        let tp = TendonPoint::new(i, tension, &rp, site, v, u)?;
        let A_i = tp.A();
        let G_i = mul_hat(&A_i, &-tp.r); // -A_i r^
        A += A_i;
        G += G_i;
        H += hat_mul(&tp.r, &G_i); // -r^ A_i r^
        let a_i = A_i * tp.c;
        b += tp.r.cross(&a_i);
        a += a_i;
        if let Some(cache) = cache.as_deref_mut() {
            cache.push(tp);
        }
        count += 1;
    }

    let rhs_v =
        reference.v_star_s.component_mul(kse) - u.cross(&n_b) - dv.component_mul(kse_s) - f_b - site.f_follower - a;
    let rhs_u = reference.u_star_s.component_mul(kbt)
        - u.cross(&m_b)
        - du.component_mul(kbt_s)
        - site.strain(v).cross(&n_b)
        - l_b
        - b;
    // On a Kirchhoff rod the tendons' loads do not depend on the rate of the translational
    // coordinate (v' = v*' is in a and b): M = [D, G; 0, C + H] (docs/model.md).
    let coupled = !site.inextensible;
    let mut M = Matrix6::<f64>::zeros();
    if coupled {
        M.fixed_view_mut::<3, 3>(0, 0).copy_from(&A);
        M.fixed_view_mut::<3, 3>(3, 0).copy_from(&G.transpose()); // B = G^T
    }
    M.fixed_view_mut::<3, 3>(0, 3).copy_from(&G);
    M.fixed_view_mut::<3, 3>(3, 3).copy_from(&H);
    for j in 0..3 {
        M[(j, j)] += kse[j];
        M[(j + 3, j + 3)] += kbt[j];
    }
    // The right-hand side as a row, (rhs_v^T, rhs_u^T).
    let mut x = SMatrix::<f64, 1, 6>::new(rhs_v[0], rhs_v[1], rhs_v[2], rhs_u[0], rhs_u[1], rhs_u[2]);
    // M is SPD (docs/model.md section 4): block elimination, LU only if rounding made it fail.
    let factor = Factor::new(&M, coupled);
    if !factor.solve_transposed_mut(&mut x) {
        return Err(breakdown(site.s));
    }
    Ok(Assembled {
        factor,
        x,
        count,
        n_b,
        m_b,
        f_b,
        l_b,
    })
}

fn breakdown(s: f64) -> Error {
    Error::Breakdown {
        s,
        what: "the 6x6 matrix [D + A, G; B, C + H] of eq. 13 is singular".into(),
    }
}

/// Eq. 13 (corrected): the strain rates (v', u') stacked. The one f64 implementation of
/// eq. 13 (pass 1 of [`linearize`]): residuals of both solvers, the solution's node rates
/// and [`Model::strain_rates`] all come here.
///
/// # Errors
/// [`Error::SingularRouting`] where a tendon's path tangent vanishes,
/// [`Error::Breakdown`] where the 6x6 system is singular.
pub fn rates(
    model: &Model,
    site: &Site,
    segment_end: f64,
    R: &Matrix3<f64>,
    v: &Vector3<f64>,
    u: &Vector3<f64>,
) -> Result<Vector6<f64>> {
    rates_of(model, site, segment_end, (R, v, u), None)
}

/// [`rates`] for the strain v + `low`, where `low` is below v's last place: the deviation
/// v - v* that carries the internal force, D (v - v*), is then (v - v*) + low, not v - v*
/// rounded to v's last place. A strain near v* = e3 holds the force of a stiff rod only to
/// EA eps (7e-12 N at EA = 6.6e4 N); the stages of the order-6 and order-8 schemes, which
/// know their deviation more precisely than their strain, keep it (docs/numerics.md, "Why
/// the estimate was low on some random robots").
///
/// # Errors
/// As [`rates`].
pub(crate) fn rates_split(
    model: &Model,
    site: &Site,
    segment_end: f64,
    R: &Matrix3<f64>,
    (v, low): (&Vector3<f64>, &Vector3<f64>),
    u: &Vector3<f64>,
) -> Result<Vector6<f64>> {
    rates_of(model, site, segment_end, (R, v, u), Some(low))
}

/// [`rates`] (`low` as in [`rates_split`]), compiled for AVX2 and FMA on a processor that
/// has them (checked at run time): the same operations in the same order (Rust does not
/// contract a product and a sum into an FMA), so the same bits in wider registers, as the
/// interval Jacobian's linearization (docs/benchmarks.md, "Default solve cost (row16,
/// 2026-12-07, eighth session)").
fn rates_of(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    low: Option<&Vector3<f64>>,
) -> Result<Vector6<f64>> {
    avx2_fma!(rates_kernel(model, site, segment_end, state, low))
}

/// [`rates_of`]' operations: eq. 13's pass 1 alone.
#[inline(always)]
fn rates_kernel(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    low: Option<&Vector3<f64>>,
) -> Result<Vector6<f64>> {
    let x = assemble(model, site, segment_end, state, None, low)?.x;
    Ok(Vector6::from_fn(|i, _| x[i]))
}

/// Eq. 13 (corrected) and its exact first derivatives at a site for the state (R, v, u):
/// the rates (v', u') of [`rates`], d(v', u')/d(v, u), and d(v', u')/d(phi)
/// for R -> R exp(hat(phi)). The tendons that reach `segment_end` load the backbone, as in
/// [`rates`]. f64 only; allocates nothing (unless it returns an error).
///
/// The derivation is in the module docs: M = [D + A, G; B, C + H] is factored once and the
/// nine derivative directions are a single solve with a 6x9 right-hand side.
///
/// # Errors
/// [`Error::SingularRouting`] where a tendon's path tangent vanishes,
/// [`Error::Breakdown`] where the 6x6 system is singular (the same as [`rates`]).
///
/// # Examples
/// ```
/// use nalgebra::Vector3;
/// use tdcr::advanced::equations::Model;
/// use tdcr::advanced::linearize::linearize;
///
/// let robot = tdcr::cases::case_h();
/// let model = Model::new(&robot);
/// let site = model.site(0.1);
/// let (v, u) = (Vector3::z(), Vector3::new(0.0, 10.0, 0.0));
/// let lin = linearize(&model, &site, robot.length(), &robot.base_rotation, &v, &u)?;
/// let (v_s, u_s) = model.strain_rates(&site, robot.length(), &robot.base_rotation, &v, &u)?;
/// assert!((lin.rates.fixed_rows::<3>(3) - u_s).norm() <= 1e-9 * u_s.norm());
/// assert!((lin.rates.fixed_rows::<3>(0) - v_s).norm() <= 1e-9 * v_s.norm().max(1e-12));
/// # Ok::<(), tdcr::Error>(())
/// ```
pub fn linearize(
    model: &Model,
    site: &Site,
    segment_end: f64,
    R: &Matrix3<f64>,
    v: &Vector3<f64>,
    u: &Vector3<f64>,
) -> Result<Linearization> {
    linearize_keeping(model, site, segment_end, R, v, u, None)
}

/// [`linearize`] always inlined, for a caller compiled for AVX2 (the interval Jacobian,
/// `collocation::residual`): its arithmetic is then compiled for AVX2 too, with the same
/// operations in the same order. It also moves eq. 13's factored matrix M into `keep` when
/// given (the interval Jacobian at an answer whose verdict comes from the linearized
/// dynamics: the mass solves with M at the same points, `collocation/dynamics.rs`).
///
/// # Errors
/// As [`linearize`].
#[inline(always)]
pub(crate) fn linearize_keeping(
    model: &Model,
    site: &Site,
    segment_end: f64,
    R: &Matrix3<f64>,
    v: &Vector3<f64>,
    u: &Vector3<f64>,
    keep: Option<&mut Factored>,
) -> Result<Linearization> {
    // Locals, not a Point: the frictionless path moves nothing between the passes.
    let mut cache = TendonCache::new();
    let assembled = assemble(model, site, segment_end, (R, v, u), Some(&mut cache), None)?;
    let x = &assembled.x;
    let mut dFt = derivative(model, site, segment_end, (v, u), x, &assembled, &cache)?;
    if !assembled.factor.solve_transposed_mut(&mut dFt) {
        return Err(breakdown(site.s));
    }
    // d(v', u') = -M^-1 dF
    let linearization = Linearization {
        rates: Vector6::from_fn(|i, _| x[i]),
        d_strains: Matrix6::from_fn(|i, k| -dFt[(k, i)]),
        d_rotation: Matrix6x3::from_fn(|i, k| -dFt[(6 + k, i)]),
    };
    if let Some(keep) = keep {
        keep.0 = assembled.factor;
    }
    Ok(linearization)
}

/// Pass 2 of [`linearize`]: dF^T at the rates `x` (a row), x held fixed, from pass 1's
/// `assembled` and `cache` ([`Point::derivative`]).
#[inline(always)]
fn derivative(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (v, u): (&Vector3<f64>, &Vector3<f64>),
    x: &SMatrix<f64, 1, 6>,
    assembled: &Assembled,
    cache: &TendonCache,
) -> Result<SMatrix<f64, 9, 6>> {
    let count = assembled.count;
    let (n_b, m_b, f_b, l_b) = (assembled.n_b, assembled.m_b, assembled.f_b, assembled.l_b);
    let (kse, kbt) = (&site.section.section.kse, &site.section.section.kbt);
    let (kse_s, kbt_s) = (&site.section.kse_s, &site.section.kbt_s);
    let x_v = Vector3::new(x[0], x[1], x[2]);
    let x_u = Vector3::new(x[3], x[4], x[5]);

    // Pass 2: dF (module docs), the partial derivative of M x - rhs at this x.
    let mut top = Matrix3x6::<f64>::zeros();
    let mut bottom = Matrix3x6::<f64>::zeros();
    for tp in cache.points() {
        tp.add_derivatives(&x_v, &x_u, u, &mut top, &mut bottom);
    }
    if count > CACHED_TENDONS {
        for (i, tension, rp) in model.distributed_tendons(site.s, segment_end).skip(CACHED_TENDONS) {
            TendonPoint::new(i, tension, &rp, site, v, u)?.add_derivatives(&x_v, &x_u, u, &mut top, &mut bottom);
        }
    }
    let n_hat = hat3(&n_b);
    // d(v x n_b)/dv = v^ D - n_b^ on a Cosserat rod; on a Kirchhoff rod v = v* and only
    // n_b = D (coordinate - v*) changes.
    let strain_term = if site.inextensible {
        hat_diag(&site.strain(v), kse, &Vector3::zeros())
    } else {
        hat_diag(v, kse, &Vector3::zeros()) - n_hat
    };
    let blocks = [
        [
            hat_diag(u, kse, kse_s) + top.fixed_columns::<3>(0),
            top.fixed_columns::<3>(3) - n_hat,
            hat3(&f_b),
        ],
        [
            strain_term + bottom.fixed_columns::<3>(0),
            hat_diag(u, kbt, kbt_s) - hat3(&m_b) + bottom.fixed_columns::<3>(3),
            hat3(&l_b),
        ],
    ];
    // dF^T: row k is direction k of (v, u, phi), column j is row j of F.
    let mut dFt = SMatrix::<f64, 9, 6>::zeros();
    for (row, blocks_row) in blocks.iter().enumerate() {
        for (col, block) in blocks_row.iter().enumerate() {
            dFt.fixed_view_mut::<3, 3>(3 * col, 3 * row)
                .copy_from(&block.transpose());
        }
    }
    Ok(dFt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Real;
    use crate::model::equations::{MIN_TENDON_SPEED, lift, to_f64};
    use crate::model::loads::{Field, Loads};
    use crate::model::robot::Robot;
    use crate::model::rod::{ReferenceStrains, Rod, Section, SectionPoint, Stiffness, StrainPoint, shear_modulus};
    use crate::model::routing::Routing;
    use crate::model::tendon::Tendon;
    use crate::so3::hat;
    use crate::{cases, so3};
    use num_dual::{Dual64, DualNum};
    use std::sync::Arc;

    /// The test oracle: eq. 13 (corrected, docs/model.md) transcribed directly, generic over
    /// the scalar, with nalgebra's Cholesky (LU fallback). Dual numbers through it give the
    /// forward-mode derivatives the hand-derived linearization is checked against; in f64 it
    /// checks [`rates`], which factors M by 3x3 blocks instead. On a Kirchhoff rod's site it
    /// is the force balance n_b' + u x n_b + ... = 0 with n_b = D (v - v*) for the coordinate
    /// v, the strain v* in the tendon paths and the moment balance, and v' = v*' in the
    /// tendons' p_i'' (docs/model.md, "Kirchhoff rods"), solved by LU.
    fn strain_rates<T: Real>(
        model: &Model,
        site: &Site,
        segment_end: f64,
        R: &Matrix3<T>,
        v: &Vector3<T>,
        u: &Vector3<T>,
    ) -> Result<(Vector3<T>, Vector3<T>)> {
        let tension = |_: usize, t: f64| (t > 0.0).then(|| T::from_f64(t).unwrap_or_else(T::zero));
        strain_rates_with(model, site, segment_end, (R, v, u), &tension)
    }

    /// [`strain_rates`] with each reaching tendon's tension given by `tension(i, tau_i)`
    /// (`None` leaves the tendon out): a dual tension seeds the derivative in it.
    fn strain_rates_with<T: Real>(
        model: &Model,
        site: &Site,
        segment_end: f64,
        (R, v, u): (&Matrix3<T>, &Vector3<T>, &Vector3<T>),
        tension: &dyn Fn(usize, f64) -> Option<T>,
    ) -> Result<(Vector3<T>, Vector3<T>)> {
        let kse = lift::<T>(&site.section.section.kse);
        let kbt = lift::<T>(&site.section.section.kbt);
        let D = Matrix3::from_diagonal(&kse);
        let C = Matrix3::from_diagonal(&kbt);
        let D_s = Matrix3::from_diagonal(&lift::<T>(&site.section.kse_s));
        let C_s = Matrix3::from_diagonal(&lift::<T>(&site.section.kbt_s));
        let v_star = lift::<T>(&site.reference.v_star);
        let u_star = lift::<T>(&site.reference.u_star);
        let dv = v - v_star;
        let du = u - u_star;
        let u_hat = hat(u);
        let Rt = R.transpose();
        let kirchhoff = site.inextensible;
        // The strain in the tendon paths and the moment balance.
        let strain = if kirchhoff { v_star } else { *v };
        let v_star_s = lift::<T>(&site.reference.v_star_s);

        let mut A = Matrix3::<T>::zeros();
        let mut B = Matrix3::<T>::zeros();
        let mut G = Matrix3::<T>::zeros();
        let mut H = Matrix3::<T>::zeros();
        let mut a = Vector3::<T>::zeros();
        let mut b = Vector3::<T>::zeros();
        for (i, tau, rp) in model.distributed_reaching(site.s, segment_end) {
            let Some(tau) = tension(i, tau) else { continue };
            let r = lift::<T>(&rp.r);
            let r_s = lift::<T>(&rp.r_s);
            let r_ss = lift::<T>(&rp.r_ss);
            let pb_s = u.cross(&r) + r_s + strain; // p_i^b'
            let speed = pb_s.norm();
            if speed < T::from_f64(MIN_TENDON_SPEED).unwrap_or_else(T::zero) {
                return Err(Error::SingularRouting {
                    tendon: i,
                    s: site.s,
                    speed: to_f64(speed),
                });
            }
            let ph = hat(&pb_s);
            let A_i = ph * ph * (-tau / (speed * speed * speed));
            let r_hat = hat(&r);
            let B_i = r_hat * A_i;
            let known = if kirchhoff { v_star_s } else { Vector3::zeros() }; // v' = v*'
            let a_i = A_i * (u_hat * pb_s + u_hat * r_s + r_ss + known);
            A += A_i;
            B += B_i;
            G -= A_i * r_hat;
            H -= B_i * r_hat;
            b += r.cross(&a_i);
            a += a_i;
        }

        let rhs_v = D * lift::<T>(&site.reference.v_star_s) - (u_hat * D + D_s) * dv - Rt * lift::<T>(&site.f_e) - a;
        let rhs_u = C * lift::<T>(&site.reference.u_star_s)
            - (u_hat * C + C_s) * du
            - hat(&strain) * D * dv
            - Rt * lift::<T>(&site.l_e)
            - b;
        let mut M = Matrix6::<T>::zeros();
        if kirchhoff {
            M.fixed_view_mut::<3, 3>(0, 0).copy_from(&D);
        } else {
            M.fixed_view_mut::<3, 3>(0, 0).copy_from(&(D + A));
            M.fixed_view_mut::<3, 3>(3, 0).copy_from(&B);
        }
        M.fixed_view_mut::<3, 3>(0, 3).copy_from(&G);
        M.fixed_view_mut::<3, 3>(3, 3).copy_from(&(C + H));
        let mut rhs = Vector6::<T>::zeros();
        rhs.fixed_rows_mut::<3>(0).copy_from(&rhs_v);
        rhs.fixed_rows_mut::<3>(3).copy_from(&rhs_u);
        // M is symmetric positive definite (B = G^T, H symmetric, A_i PSD): Cholesky first;
        // LU only if rounding made the factorization fail.
        let cholesky = if kirchhoff { None } else { M.cholesky() };
        let x = match cholesky {
            Some(ch) => ch.solve(&rhs),
            None => M.lu().solve(&rhs).ok_or_else(|| Error::Breakdown {
                s: site.s,
                what: "the 6x6 matrix [D + A, G; B, C + H] of eq. 13 is singular".into(),
            })?,
        };
        Ok((x.fixed_rows::<3>(0).into(), x.fixed_rows::<3>(3).into()))
    }

    /// (rates, d_strains, d_rotation) by forward-mode AD through the generic
    /// the oracle [`strain_rates`], one seeded direction per pass.
    fn by_dual(
        model: &Model,
        site: &Site,
        end: f64,
        R: &Matrix3<f64>,
        v: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> (Vector6<f64>, Matrix6<f64>, Matrix6x3<f64>) {
        let lift = |a: &Vector3<f64>| a.map(Dual64::from);
        let mut rates = Vector6::zeros();
        let mut d_strains = Matrix6::zeros();
        let mut d_rotation = Matrix6x3::zeros();
        for k in 0..9 {
            let (mut v_d, mut u_d, mut phi) = (lift(v), lift(u), Vector3::<Dual64>::zeros());
            match k {
                0..3 => v_d[k] = v_d[k].derivative(),
                3..6 => u_d[k - 3] = u_d[k - 3].derivative(),
                _ => phi[k - 6] = phi[k - 6].derivative(),
            }
            let R_d = R.map(Dual64::from) * so3::exp(&phi);
            let (v_s, u_s) = strain_rates(model, site, end, &R_d, &v_d, &u_d).unwrap();
            let col = Vector6::from_fn(|j, _| if j < 3 { v_s[j] } else { u_s[j - 3] });
            rates = col.map(|d| d.re);
            let d = col.map(|d| d.eps);
            if k < 6 {
                d_strains.set_column(k, &d);
            } else {
                d_rotation.set_column(k - 6, &d);
            }
        }
        (rates, d_strains, d_rotation)
    }

    /// Largest relative difference over every column, taken separately on the v' rows and the
    /// u' rows (their units differ): |a - b|_inf / |b|_inf per 3-vector.
    fn rel<const C: usize>(a: &SMatrix<f64, 6, C>, b: &SMatrix<f64, 6, C>) -> f64 {
        let mut worst = 0.0_f64;
        for l in 0..C {
            for r0 in [0, 3] {
                let (x, y) = (a.fixed_view::<3, 1>(r0, l), b.fixed_view::<3, 1>(r0, l));
                worst = worst.max((x - y).amax() / y.amax().max(f64::MIN_POSITIVE));
            }
        }
        worst
    }

    /// [`check_model`] for the robot at full load.
    fn check(robot: &Robot, s: f64, end: f64, R: &Matrix3<f64>, v: &Vector3<f64>, u: &Vector3<f64>) {
        check_model(&Model::new(robot), s, end, R, v, u);
    }

    /// Checks `linearize` and `rates` at (s, R, v, u) against the f64 oracle `strain_rates` and against AD.
    fn check_model(model: &Model, s: f64, end: f64, R: &Matrix3<f64>, v: &Vector3<f64>, u: &Vector3<f64>) {
        let site = model.site(s);
        let lin = linearize(model, &site, end, R, v, u).unwrap();
        let (v_s, u_s) = strain_rates(model, &site, end, R, v, u).unwrap();
        let rates = Vector6::from_fn(|j, _| if j < 3 { v_s[j] } else { u_s[j - 3] });
        let (ad_rates, d_strains, d_rotation) = by_dual(model, &site, end, R, v, u);
        let fast = super::rates(model, &site, end, R, v, u).unwrap();
        let errors = [
            rel(&lin.rates, &rates).max(rel(&fast, &rates)),
            rel(&ad_rates, &rates),
            rel(&lin.d_strains, &d_strains),
            rel(&lin.d_rotation, &d_rotation),
        ];
        let worst = errors.iter().fold(0.0_f64, |w, e| w.max(*e));
        println!(
            "rates {:.1e}, d_strains {:.1e}, d_rotation {:.1e}",
            errors[0], errors[2], errors[3]
        );
        // 1e-12: both sides are exact derivatives in f64; only rounding in M^-1 differs
        assert!(worst < 1e-12, "worst relative difference {worst:.3e}: {errors:?}");
        assert!(lin.d_strains.iter().chain(lin.d_rotation.iter()).all(|x| x.is_finite()));
    }

    fn generic_rotation() -> Matrix3<f64> {
        so3::exp(&Vector3::new(0.3, -0.7, 1.1)) * cases::prototype_base_rotation()
    }

    fn state() -> (Vector3<f64>, Vector3<f64>) {
        (Vector3::new(1e-4, -2e-4, 1.0 - 3e-5), Vector3::new(3.0, -5.0, 2.0))
    }

    #[test]
    fn case_h_matches_ad() {
        let robot = cases::case_h();
        let (v, u) = state();
        for s in [0.0, 0.1, 0.2] {
            check(&robot, s, robot.length(), &generic_rotation(), &v, &u);
        }
    }

    #[test]
    fn case_h_with_distributed_moment_matches_ad() {
        let mut robot = cases::case_h();
        robot.loads.distributed_moment = Field::Constant(Vector3::new(0.02, -0.05, 0.01));
        let (v, u) = state();
        check(&robot, 0.13, robot.length(), &generic_rotation(), &v, &u);
    }

    fn several_tendons() -> Robot {
        let l = cases::LENGTH;
        let curve = Routing::from_dual(|s, l| {
            let a = s / l;
            [(a * a * 3.0).cos() * 0.005 + a * 0.002, (a * 2.0 + 0.3).sin() * 0.006]
        });
        cases::prototype()
            .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 2.0))
            .with_tendon(Tendon::new(Routing::straight(0.0, -0.006), 1.3))
            .with_tendon(Tendon::new(Routing::helical(0.007, -0.75, 0.4), 3.1))
            .with_tendon(Tendon::new(curve, 0.8))
            .with_tendon(Tendon::new(Routing::straight(-0.008, 0.001), 1.5).ending_at(0.5 * l))
            .with_tendon(Tendon::new(Routing::straight(0.0, 0.008), 0.0))
    }

    #[test]
    fn several_tendons_match_ad() {
        let robot = several_tendons();
        let mut loads = Loads::self_weight(0.47, -Vector3::z()).with_tip_force(Vector3::new(0.0, 0.0, -0.1));
        loads.distributed_moment = Field::Constant(Vector3::new(-0.01, 0.0, 0.03));
        let robot = robot.with_loads(loads);
        let (v, u) = state();
        let l = robot.length();
        // the tendon ending at L/2 is active in the first segment only
        check(&robot, 0.07, l, &generic_rotation(), &v, &u);
        check(&robot, 0.07, 0.5 * l, &generic_rotation(), &v, &u);
        let (v, u) = (Vector3::new(-3e-5, 4e-5, 0.9999), Vector3::new(-8.0, 12.0, -1.0));
        check(&robot, 0.2, l, &Matrix3::identity(), &v, &u);
    }

    #[test]
    fn more_tendons_than_cached_match_ad() {
        let mut robot = cases::prototype();
        for j in 0..CACHED_TENDONS + 3 {
            let angle = j as f64 * 0.7;
            let routing = if j % 2 == 0 {
                Routing::straight(0.008 * angle.cos(), 0.008 * angle.sin())
            } else {
                Routing::helical(0.006, 0.5 + j as f64 * 0.1, angle)
            };
            robot = robot.with_tendon(Tendon::new(routing, 0.5 + 0.1 * j as f64));
        }
        let (v, u) = state();
        check(&robot, 0.11, robot.length(), &generic_rotation(), &v, &u);
    }

    #[test]
    fn varying_stiffness_and_precurvature_match_ad() {
        let e = cases::YOUNGS_MODULUS;
        let base = Section::solid_circle(cases::RADIUS, e, shear_modulus(e, cases::POISSON_RATIO));
        let mut rod = Rod::new(cases::LENGTH, base);
        // stiffness growing linearly (axial) and quadratically (bending) with s
        rod.stiffness = Stiffness::Varying(Arc::new(move |s| {
            let f = 1.0 + 2.0 * s;
            SectionPoint {
                section: Section {
                    kse: base.kse * f,
                    kbt: base.kbt * (f * f),
                },
                kse_s: base.kse * 2.0,
                kbt_s: base.kbt * (4.0 * f),
            }
        }));
        rod.reference = ReferenceStrains::Varying(Arc::new(|s| StrainPoint {
            v_star: Vector3::new(1e-3 * s, -2e-3, 1.0 + 1e-3 * s),
            u_star: Vector3::new(2.0 + 3.0 * s, -1.0, 4.0 * s * s),
            v_star_s: Vector3::new(1e-3, 0.0, 1e-3),
            u_star_s: Vector3::new(3.0, 0.0, 8.0 * s),
        }));
        let mut loads = Loads::self_weight(0.47, Vector3::new(0.2, -0.1, -1.0));
        loads.distributed_moment = Field::Constant(Vector3::new(0.02, 0.01, -0.04));
        let robot = Robot::new(rod)
            .with_loads(loads)
            .with_tendon(Tendon::new(Routing::straight(0.006, -0.004), 2.5))
            .with_tendon(Tendon::new(Routing::helical(0.008, 1.5, 0.2), 1.7));
        let (v, u) = state();
        for s in [0.05, 0.19] {
            check(&robot, s, robot.length(), &generic_rotation(), &v, &u);
        }
    }

    #[test]
    fn errors_match_strain_rates() {
        // a straight tendon at (8, 0) mm with v = 0, u = 0 has p_i^b' = 0
        let robot = cases::case_s();
        let model = Model::new(&robot);
        let site = model.site(0.1);
        let (R, z) = (Matrix3::identity(), Vector3::zeros());
        let lin = linearize(&model, &site, robot.length(), &R, &z, &z);
        let generic = strain_rates(&model, &site, robot.length(), &R, &z, &z);
        assert!(matches!(lin, Err(Error::SingularRouting { tendon: 0, .. })), "{lin:?}");
        assert!(
            matches!(generic, Err(Error::SingularRouting { tendon: 0, .. })),
            "{generic:?}"
        );

        // zero stiffness and no tendon: M = 0
        let robot = Robot::new(Rod::new(0.1, Section::explicit(0.0, 0.0, 0.0, 0.0, 0.0)));
        let model = Model::new(&robot);
        let site = model.site(0.05);
        let v = Vector3::z();
        let lin = linearize(&model, &site, 0.1, &R, &v, &z);
        let generic = strain_rates(&model, &site, 0.1, &R, &v, &z);
        let message = lin.as_ref().map(|_| String::new()).unwrap_or_else(|e| e.to_string());
        assert!(matches!(lin, Err(Error::Breakdown { .. })), "{lin:?}");
        assert!(matches!(generic, Err(Error::Breakdown { .. })), "{generic:?}");
        assert!(message.contains("is singular"), "{message}");
    }

    #[test]
    fn kirchhoff_rods_match_ad() {
        // every term: several tendons (one ending mid-rod), loads, varying stiffness and
        // reference strains (v*' != 0), on the inextensible rod
        let mut robot = several_tendons();
        robot.loads.distributed_moment = Field::Constant(Vector3::new(0.03, 0.02, -0.01));
        robot.loads.distributed_force = Field::Constant(Vector3::new(-0.2, 0.1, -0.4));
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        let (v, u) = state();
        let l = robot.length();
        for end in [l, 0.5 * l] {
            check(&robot, 0.07, end, &generic_rotation(), &v, &u);
        }
        let e = cases::YOUNGS_MODULUS;
        let base = Section::solid_circle(cases::RADIUS, e, shear_modulus(e, cases::POISSON_RATIO));
        let mut rod = Rod::new(cases::LENGTH, base);
        rod.stiffness = Stiffness::Varying(Arc::new(move |s| {
            let f = 1.0 + 2.0 * s;
            SectionPoint {
                section: Section {
                    kse: base.kse * f,
                    kbt: base.kbt * (f * f),
                },
                kse_s: base.kse * 2.0,
                kbt_s: base.kbt * (4.0 * f),
            }
        }));
        rod.reference = ReferenceStrains::Varying(Arc::new(|s| StrainPoint {
            v_star: Vector3::new(1e-3 * s, -2e-3, 1.0 + 1e-3 * s),
            u_star: Vector3::new(2.0 + 3.0 * s, -1.0, 4.0 * s * s),
            v_star_s: Vector3::new(1e-3, 0.0, 1e-3),
            u_star_s: Vector3::new(3.0, 0.0, 8.0 * s),
        }));
        let mut robot = Robot::new(rod)
            .with_tendon(Tendon::new(Routing::straight(0.006, -0.004), 2.5))
            .with_tendon(Tendon::new(Routing::helical(0.008, 1.5, 0.2), 1.7));
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        check(&robot, 0.19, robot.length(), &generic_rotation(), &v, &u);
    }

    #[test]
    fn scaled_loads_match_ad() {
        let mut robot = several_tendons();
        robot.loads.distributed_moment = Field::Constant(Vector3::new(0.03, 0.02, -0.01));
        let model = Model {
            tension_factor: 0.4,
            load_factor: 0.7,
            ..Model::new(&robot)
        };
        let (v, u) = state();
        check_model(&model, 0.09, robot.length(), &generic_rotation(), &v, &u);
    }

    /// d(v', u')/dtau_i of [`tension_rates`] against dual numbers seeded on tendon i's
    /// tension in the oracle, for every tendon: taut, slack (the right derivative), ending
    /// before the segment end (zero), at a tension factor below 1.
    #[test]
    fn tension_rates_match_ad() {
        check_tension_rates(&several_tendons());
    }

    /// The same on a Kirchhoff rod, whose tendon loads see the strain v* and not the
    /// translational coordinate.
    #[test]
    fn tension_rates_of_a_kirchhoff_rod_match_ad() {
        let mut robot = several_tendons();
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        check_tension_rates(&robot);
    }

    fn check_tension_rates(robot: &Robot) {
        let model = Model {
            tension_factor: 0.4,
            ..Model::new(robot)
        };
        let (v, u) = state();
        let R = generic_rotation();
        let l = robot.length();
        for (s, end) in [(0.07, l), (0.07, 0.5 * l), (0.2, l)] {
            let site = model.site(s);
            let mut out = vec![Vector6::zeros(); robot.tendons.len()];
            let rates = tension_rates(&model, &site, end, (&R, &v, &u), None, &mut out).unwrap();
            // The rates are those of `rates`, bit for bit.
            assert_eq!(rates, super::rates(&model, &site, end, &R, &v, &u).unwrap());
            // With the strains moving along dy_i, the total derivative is the partial one
            // plus the full linearization's d(v', u')/d(v, u) dy_i.
            let along: Vec<Vector6<f64>> = (0..out.len())
                .map(|i| Vector6::from_fn(|k, _| ((i * 6 + k) as f64 * 0.7).sin() * 1e-2))
                .collect();
            let mut total = vec![Vector6::zeros(); robot.tendons.len()];
            let moved = tension_rates(&model, &site, end, (&R, &v, &u), Some(&along), &mut total).unwrap();
            assert_eq!(moved, rates);
            let lin = linearize(&model, &site, end, &R, &v, &u).unwrap();
            for ((t, d), dy) in total.iter().zip(&out).zip(&along) {
                let expected = d + lin.d_strains * dy;
                // 1e-12: the same exact derivatives, summed before or after the solve with M.
                assert!(rel(t, &expected) < 1e-12, "at {s}: {t} vs {expected}");
            }
            for (j, d) in out.iter().enumerate() {
                let seeded = |i: usize, t: f64| {
                    if i == j {
                        Some(Dual64::new(t, model.tension_factor))
                    } else {
                        (t > 0.0).then(|| Dual64::from(t))
                    }
                };
                let lift = |a: &Vector3<f64>| a.map(Dual64::from);
                let R_d = R.map(Dual64::from);
                let (v_s, u_s) = strain_rates_with(&model, &site, end, (&R_d, &lift(&v), &lift(&u)), &seeded).unwrap();
                let ad = Vector6::from_fn(|k, _| if k < 3 { v_s[k].eps } else { u_s[k - 3].eps });
                let ends_before = robot.tendons[j].end(l) < end;
                if ends_before {
                    assert_eq!(*d, Vector6::zeros(), "tendon {j} does not reach {end}");
                    assert_eq!(ad, Vector6::zeros());
                } else {
                    assert!(d.amax() > 0.0, "tendon {j} (slack or taut) loads the rod at {s}");
                    // 1e-12: both exact derivatives in f64; only rounding in M^-1 differs.
                    assert!(rel(d, &ad) < 1e-12, "tendon {j} at {s}: {d} vs {ad}");
                }
            }
        }
    }

    /// The AVX2 build of [`rates`] gives the baseline build's bits (the same operations in
    /// the same order) on the several-tendon robot with loads, at sites in both segments,
    /// with and without a low part of the strain (on a processor without AVX2 both are the
    /// baseline).
    #[test]
    fn rates_give_the_baseline_bits() {
        let robot = several_tendons().with_loads(Loads::self_weight(0.47, -Vector3::z()));
        let model = Model::new(&robot);
        let l = robot.length();
        let (v, u) = state();
        let low = Vector3::new(3e-17, -1e-17, 2e-17);
        let bits = |x: &Vector6<f64>| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (s, end) in [(0.0, l), (0.07, 0.5 * l), (0.13, l), (0.2, l)] {
            let site = model.site(s);
            for low in [None, Some(&low)] {
                let state = (&generic_rotation(), &v, &u);
                let fast = rates_of(&model, &site, end, state, low).unwrap();
                let baseline = rates_kernel(&model, &site, end, state, low).unwrap();
                assert_eq!(bits(&fast), bits(&baseline), "at {s}");
                assert!(fast.iter().all(|x| x.is_finite()));
            }
        }
    }
}
