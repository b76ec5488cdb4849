//! One tendon's quantities at a point of the rod (the per-tendon terms of eq. 13's
//! linearization, module docs of `linearize`): its path tangent, normal-load factor and the
//! derivative of its normal load q_i in the node coordinates.
#![allow(non_snake_case)]

use crate::Error;
use crate::error::Result;
use crate::model::equations::MIN_TENDON_SPEED;
use crate::model::equations::Site;
use crate::model::routing::RoutingPoint;
use nalgebra::{Matrix3, Matrix3x6, SMatrix, Vector3};

/// Per-tendon quantities of the derivation (body frame) that both passes need.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TendonPoint {
    /// r_i (m).
    pub(crate) r: Vector3<f64>,
    /// e_i = p_i^b' + r_i'.
    pub(crate) e: Vector3<f64>,
    /// c_i = u x e_i + r_i'' (1/m), the state-dependent part of p_i^b''.
    pub(crate) c: Vector3<f64>,
    /// t_i = p_i^b' / |p_i^b'|, the unit tangent.
    pub(crate) t: Vector3<f64>,
    /// k_i = tau_i / |p_i^b'| (N).
    pub(crate) k: f64,
    /// 1 / |p_i^b'|.
    pub(crate) inv_speed: f64,
    /// On a Kirchhoff rod ([`Site::inextensible`]) v' = v*' is no unknown: it is part of
    /// `c`, and q_i does not depend on the translational coordinate.
    pub(crate) inextensible: bool,
}

impl TendonPoint {
    /// Tendon `i` with tension `tension` (N) at the routing point `rp` of `site`, for the
    /// node coordinates (v, u) (the strain is [`Site::strain`] of v).
    #[inline(always)]
    pub(crate) fn new(
        i: usize,
        tension: f64,
        rp: &RoutingPoint,
        site: &Site,
        v: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> Result<Self> {
        let p = u.cross(&rp.r) + rp.r_s + site.strain(v);
        let speed = p.norm();
        if speed < MIN_TENDON_SPEED {
            return Err(Error::SingularRouting {
                tendon: i,
                s: site.s,
                speed,
            });
        }
        let inv_speed = 1.0 / speed;
        let e = p + rp.r_s;
        let mut c = u.cross(&e) + rp.r_ss;
        if site.inextensible {
            c += site.reference.v_star_s; // v' = v*'
        }
        Ok(TendonPoint {
            r: rp.r,
            e,
            c,
            t: p * inv_speed,
            k: tension * inv_speed,
            inv_speed,
            inextensible: site.inextensible,
        })
    }

    /// A_i = k_i (I - t_i t_i^T) (N), symmetric.
    #[inline(always)]
    pub(super) fn A(&self) -> Matrix3<f64> {
        let (t, k) = (&self.t, self.k);
        let kt = t * k;
        let (xy, xz, yz) = (-kt[0] * t[1], -kt[0] * t[2], -kt[1] * t[2]);
        Matrix3::new(
            k - kt[0] * t[0],
            xy,
            xz,
            xy,
            k - kt[1] * t[1],
            yz,
            xz,
            yz,
            k - kt[2] * t[2],
        )
    }

    /// Adds [dq_i/dv, dq_i/du] to `top` and r_i^ [dq_i/dv, dq_i/du] to `bottom` (module docs),
    /// at the rates x = (x_v, x_u).
    #[inline(always)]
    pub(super) fn add_derivatives(
        &self,
        x_v: &Vector3<f64>,
        x_u: &Vector3<f64>,
        u: &Vector3<f64>,
        top: &mut Matrix3x6<f64>,
        bottom: &mut Matrix3x6<f64>,
    ) {
        let QQ = self.normal_derivative(x_v, x_u, u);
        *top += QQ;
        *bottom += hat_mul(&self.r, &QQ);
    }

    /// [dq_i/dv, dq_i/du] (module docs) at the rates x = (x_v, x_u), with x held fixed: the
    /// change of the tendon's normal load q_i with the node coordinates (on a Kirchhoff rod
    /// q_i does not depend on v nor x_v, the translational coordinate and its rate).
    #[inline(always)]
    pub(crate) fn normal_derivative(&self, x_v: &Vector3<f64>, x_u: &Vector3<f64>, u: &Vector3<f64>) -> Matrix3x6<f64> {
        let A = self.A();
        let t = &self.t;
        let x_v = if self.inextensible { Vector3::zeros() } else { *x_v };
        let z = x_v - self.r.cross(x_u) + self.c; // p_i^b''
        let alpha = t.dot(&z);
        let z_perp = z - t * alpha;
        // J = -(alpha/|p|) A - (k/|p|) (z_perp t^T + t z_perp^T)
        let g = -alpha * self.inv_speed;
        let h = -self.k * self.inv_speed;
        let hz = z_perp * h;
        let mut Q = Matrix3::zeros();
        for j in 0..3 {
            for l in j..3 {
                let J_jl = g * A[(j, l)] + hz[j] * t[l] + t[j] * hz[l];
                Q[(j, l)] = J_jl;
                Q[(l, j)] = J_jl;
            }
        }
        Q += mul_hat(&A, u); // + A u^
        // dq/du = -Q r^ - A e^: rows r x Q_j + e x A_j
        let dq_du = mul_hat(&Q, &-self.r) + mul_hat(&A, &-self.e);
        let mut QQ = Matrix3x6::zeros();
        if !self.inextensible {
            QQ.fixed_columns_mut::<3>(0).copy_from(&Q);
        }
        QQ.fixed_columns_mut::<3>(3).copy_from(&dq_du);
        QQ
    }
}

/// m a^: row j is (m_j x a)^T.
#[inline(always)]
pub(crate) fn mul_hat(m: &Matrix3<f64>, a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::from_fn(|j, l| match l {
        0 => m[(j, 1)] * a[2] - m[(j, 2)] * a[1],
        1 => m[(j, 2)] * a[0] - m[(j, 0)] * a[2],
        _ => m[(j, 0)] * a[1] - m[(j, 1)] * a[0],
    })
}

/// a^ m: column l is a x m_l.
#[inline(always)]
pub(super) fn hat_mul<const C: usize>(a: &Vector3<f64>, m: &SMatrix<f64, 3, C>) -> SMatrix<f64, 3, C> {
    SMatrix::<f64, 3, C>::from_fn(|j, l| match j {
        0 => a[1] * m[(2, l)] - a[2] * m[(1, l)],
        1 => a[2] * m[(0, l)] - a[0] * m[(2, l)],
        _ => a[0] * m[(1, l)] - a[1] * m[(0, l)],
    })
}
