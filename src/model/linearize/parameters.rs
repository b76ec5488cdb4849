//! Eq. 13's rates differentiated in parameters rather than in the state: every tendon's
//! tension ([`tension_rates`]; with the linearization at the same point,
//! [`linearize_tensions_inline`]) and the section's six stiffnesses ([`stiffness_rates`]), at
//! fixed (R, v, u), from the same assembly and factors as [`super::linearize`] (its module
//! docs name the symbols). Checked against dual numbers seeded on the tension (the tests of
//! `linearize`) and, through the collocation system, against differenced residuals
//! (tests/sensitivity.rs).
#![allow(non_snake_case)]

use super::{Linearization, TendonCache, TendonPoint, assemble, breakdown, derivative};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::model::routing::RoutingPoint;
use crate::simd::avx2_fma;
use nalgebra::{Matrix3, Matrix6, Matrix6x3, Vector3, Vector6};

/// Eq. 13 (corrected) at (R, v, u) with the derivatives of its rates in every tendon's
/// tension: writes d(v', u')/dtau_i into `out[i]` (one entry per tendon of the robot, zero
/// for a tendon that does not load the backbone here) and returns the rates. With `along`,
/// the state's strains move with each tension too, by `along[i]` (d(v, u)/dtau_i: the
/// collocation midpoint's chain rule), and `out[i]` is the total derivative
/// -M^-1 (dF/dtau_i + dF/d(v, u) along[i]) ([`point_derivatives`]).
///
/// Tendon i enters F = M x - rhs only through q_i = A_i z_i (module docs), and
/// A_i = tau_i f P_i / |p_i| (f the tension factor) is linear in tau_i while p_i, c_i and
/// z_i do not depend on it, so at fixed x
///
/// ```text
/// dF/dtau_i = (f / |p_i|) [P_i z_i; r_i x P_i z_i],    d(v', u')/dtau_i = -M^-1 dF/dtau_i,
/// ```
///
/// exact, with one solve with the factored M per tendon. A slack tendon (tau_i = 0, not in
/// M) gets the same formula: the right derivative, the load its first pull adds.
///
/// # Errors
/// As [`rates`]; [`Error::SingularRouting`] also for a slack tendon without a tangent.
///
/// On x86-64 with AVX2 and FMA (checked at run time) compiled for them: the same operations
/// in the same order (Rust does not fuse a product and a sum into an FMA), so the same bits.
/// (Built with the full linearization it emitted a `vmovq xmm, xmm` that valgrind 3.19
/// cannot decode, docs/benchmarks.md "Control Jacobian"; `objdump` of the build is the check.)
pub(crate) fn tension_rates(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    along: Option<&[Vector6<f64>]>,
    out: &mut [Vector6<f64>],
) -> Result<Vector6<f64>> {
    avx2_fma!(tension_rates_kernel(model, site, segment_end, state, along, out))
}

/// [`tension_rates`]' operations.
#[inline(always)]
fn tension_rates_kernel(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    along: Option<&[Vector6<f64>]>,
    out: &mut [Vector6<f64>],
) -> Result<Vector6<f64>> {
    let (v, u) = (state.1, state.2);
    point_derivatives(model, site, segment_end, state, along, out, |x_v, x_u, cached, out| {
        tension_partials(model, site, segment_end, (v, u), (x_v, x_u), (cached, None), out)
    })
}

/// dF/dtau_i at fixed rates x = (x_v, x_u) and state (v, u) for every tendon that reaches
/// `segment_end` (F = M x - rhs, [`tension_rates`]), into `out[i]` (the other entries left
/// as they are), given the points of the first taut tendons eq. 13's assembly kept, in the
/// order it kept them (`cached`), and every tendon's routing point at the site if they are
/// kept (`routing`, in the robot's order: [`Routing::at`](crate::model::routing::Routing::at) at `site.s`, else
/// evaluated here). Always inlined, so that it is compiled with its caller's target
/// features (the interval Jacobian's AVX2 build, [`linearize_tensions_inline`]).
///
/// # Errors
/// [`crate::Error::SingularRouting`] for a slack tendon without a tangent.
#[inline(always)]
pub(super) fn tension_partials(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (v, u): (&Vector3<f64>, &Vector3<f64>),
    (x_v, x_u): (&Vector3<f64>, &Vector3<f64>),
    (cached, routing): (&[TendonPoint], Option<&[RoutingPoint]>),
    out: &mut [Vector6<f64>],
) -> Result<()> {
    let length = model.robot.length();
    // The taut tendons come in the order eq. 13's assembly kept their points.
    let mut kept = cached.iter();
    for (i, taut, tendon) in model.distributed_reaching_tendons(segment_end) {
        // Per unit of tau_i: k_i = f / |p_i|, so A() is (f / |p_i|) P_i; a kept point
        // differs only in k_i = tau_i f / |p_i|, and f * (1 / |p_i|) is what
        // TendonPoint::new computes for the tension f.
        let kept_point = if taut { kept.next() } else { None };
        let tp = match kept_point {
            Some(&tp) => TendonPoint {
                k: model.tension_factor * tp.inv_speed,
                ..tp
            },
            None => {
                let rp = match routing {
                    Some(points) => points[i],
                    None => tendon.routing.at(site.s, length),
                };
                TendonPoint::new(i, model.tension_factor, &rp, site, v, u)?
            }
        };
        // On a Kirchhoff rod q_i does not see the translational coordinate's rate.
        let x_v = if tp.inextensible { Vector3::zeros() } else { *x_v };
        let q = tp.A() * (x_v - tp.r.cross(x_u) + tp.c);
        let rq = tp.r.cross(&q);
        out[i] = Vector6::new(q[0], q[1], q[2], rq[0], rq[1], rq[2]);
    }
    Ok(())
}

/// [`super::linearize_keeping`] without keeping, also writing d(v', u')/dtau_i at the fixed state (R, v, u) for
/// every tendon of the robot into `tensions[i]` (one entry per tendon, zero for a tendon
/// that does not load the backbone here): [`tension_rates`] without `along`, from the same
/// assembly and factors of M as the linearization, one solve with them per tendon
/// (docs/sensitivity.md, "Tension columns formed with the verdict's Jacobian"). Always
/// inlined, for the interval Jacobian's AVX2 build. Its opening (assembly, dF, the solve)
/// repeats [`super::linearize_keeping`]'s on purpose: one always-inlined helper for both,
/// returning the assembly, measured 0.017 M instructions dearer per warm S solve with the
/// tension columns kept (2026-12-06), which put the control Jacobian over its 25 %.
/// `routing`: every tendon's routing point at the site when they are kept, as
/// [`tension_partials`] takes them.
///
/// # Errors
/// As [`super::linearize`]; [`Error::SingularRouting`] also for a slack tendon without a tangent.
#[inline(always)]
pub(crate) fn linearize_tensions_inline(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    tensions: &mut [Vector6<f64>],
    routing: Option<&[RoutingPoint]>,
) -> Result<Linearization> {
    let mut cache = TendonCache::new();
    let assembled = assemble(model, site, segment_end, (R, v, u), Some(&mut cache), None)?;
    let x = &assembled.x;
    let mut dFt = derivative(model, site, segment_end, (v, u), x, &assembled, &cache)?;
    if !assembled.factor.solve_transposed_mut(&mut dFt) {
        return Err(breakdown(site.s));
    }
    let x_v = Vector3::new(x[0], x[1], x[2]);
    let x_u = Vector3::new(x[3], x[4], x[5]);
    tensions.fill(Vector6::zeros());
    tension_partials(
        model,
        site,
        segment_end,
        (v, u),
        (&x_v, &x_u),
        (cache.points(), routing),
        tensions,
    )?;
    for d in tensions.iter_mut().filter(|d| **d != Vector6::zeros()) {
        let mut row = d.transpose();
        if !assembled.factor.solve_transposed_mut(&mut row) {
            return Err(breakdown(site.s));
        }
        *d = -row.transpose();
    }
    Ok(Linearization {
        rates: Vector6::from_fn(|i, _| x[i]),
        d_strains: Matrix6::from_fn(|i, k| -dFt[(k, i)]),
        d_rotation: Matrix6x3::from_fn(|i, k| -dFt[(6 + k, i)]),
    })
}

/// [`linearize_tensions_inline`] as a call (an interval's start node, linearized once per
/// run of intervals).
///
/// # Errors
/// As [`linearize_tensions_inline`].
pub(crate) fn linearize_tensions(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    tensions: &mut [Vector6<f64>],
) -> Result<Linearization> {
    linearize_tensions_inline(model, site, segment_end, state, tensions, None)
}

/// Eq. 13 (corrected) at (R, v, u) with the derivatives of its rates in the six diagonal
/// stiffnesses of the section, kse = (GA, GA, EA) then kbt = (EIxx, EIyy, GJ): writes
/// d(v', u')/dk_j into `out[j]` (six entries) and returns the rates; `along` as in
/// [`tension_rates`]. For a section that does not vary along s (D' = C' = 0,
/// and they stay 0), at fixed x, with n_b = D (v - v*) and m_b = C (u - u*) (module docs):
///
/// ```text
/// dF/dkse_j = (e_j (x_v - v*')_j + u x e_j (v - v*)_j,  v x e_j (v - v*)_j)
/// dF/dkbt_j = (0,                                      e_j (x_u - u*')_j + u x e_j (u - u*)_j)
/// ```
///
/// and d(v', u')/dk_j = -M^-1 dF/dk_j: exact, one solve with the factored M each.
///
/// # Errors
/// As [`rates`].
pub(crate) fn stiffness_rates(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    along: Option<&[Vector6<f64>]>,
    out: &mut [Vector6<f64>],
) -> Result<Vector6<f64>> {
    let (v, u) = (state.1, state.2);
    let reference = &site.reference;
    let dv = v - reference.v_star;
    let du = u - reference.u_star;
    // v x n_b sees the strain: v* on a Kirchhoff rod, whose coordinate v carries n_b.
    let strain = site.strain(v);
    point_derivatives(model, site, segment_end, state, along, out, |x_v, x_u, _, out| {
        for j in 0..3 {
            let e = Vector3::ith(j, 1.0);
            let top = e * (x_v[j] - reference.v_star_s[j]) + u.cross(&e) * dv[j];
            let bottom = strain.cross(&e) * dv[j];
            out[j] = Vector6::new(top[0], top[1], top[2], bottom[0], bottom[1], bottom[2]);
            let bottom = e * (x_u[j] - reference.u_star_s[j]) + u.cross(&e) * du[j];
            out[3 + j] = Vector6::new(0.0, 0.0, 0.0, bottom[0], bottom[1], bottom[2]);
        }
        Ok(())
    })
}

/// The rates at (R, v, u) and their derivatives in some parameters: `partial(x_v, x_u,
/// points, out)` writes each parameter's dF/dq at fixed rates x = (x_v, x_u) and state
/// (F = M x - rhs, module docs) into `out` (zeroed first), given the points of the first
/// taut tendons the assembly kept. With `along`, the strains move with parameter i by
/// `along[i]` = d(v, u)/dq_i, which adds dF/d(v, u) along[i] (pass 2 of the linearization,
/// its v and u rows, without solving for them); each then becomes d(v', u')/dq =
/// -M^-1 dF/dq, one solve with the factors of M (instead of solving for the full
/// linearization's nine directions and multiplying).
#[inline(always)]
fn point_derivatives(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    along: Option<&[Vector6<f64>]>,
    out: &mut [Vector6<f64>],
    partial: impl FnOnce(&Vector3<f64>, &Vector3<f64>, &[TendonPoint], &mut [Vector6<f64>]) -> Result<()>,
) -> Result<Vector6<f64>> {
    let mut cache = TendonCache::new();
    let assembled = assemble(model, site, segment_end, (R, v, u), Some(&mut cache), None)?;
    let x = &assembled.x;
    // Written out, not `from_fn`: nalgebra's iterator constructor, shared with more
    // callers, is not inlined into the AVX2 build and costs a call per use.
    let rates = Vector6::new(x[0], x[1], x[2], x[3], x[4], x[5]);
    let x_v = Vector3::new(x[0], x[1], x[2]);
    let x_u = Vector3::new(x[3], x[4], x[5]);
    out.fill(Vector6::zeros());
    partial(&x_v, &x_u, cache.points(), out)?;
    if let Some(along) = along {
        // dF^T: rows v (3), u (3), then the rotation's (3), columns F's six components.
        let dFt = derivative(model, site, segment_end, (v, u), x, &assembled, &cache)?;
        for (d, dy) in out.iter_mut().zip(along) {
            let mut add = Vector6::zeros();
            for (j, a) in add.iter_mut().enumerate() {
                *a = (0..6).map(|k| dFt[(k, j)] * dy[k]).sum::<f64>();
            }
            *d += add;
        }
    }
    for d in out.iter_mut().filter(|d| **d != Vector6::zeros()) {
        let mut row = d.transpose();
        if !assembled.factor.solve_transposed_mut(&mut row) {
            return Err(breakdown(site.s));
        }
        *d = -row.transpose();
    }
    Ok(rates)
}
