//! The tendons' pulls on the backbone at a site: tau_i t_i and its moment, summed over the
//! tendons that reach s (eq. 9 and eq. 11's tendon terms), in the world frame (generic over
//! the scalar, for the automatic derivatives of the end blocks) or in the body frame (the
//! default initial guess's sweeps).
#![allow(non_snake_case)]

use super::{MIN_TENDON_SPEED, Model, Which, lift, to_f64};
use crate::error::Result;
use crate::model::robot::TendonModel;
use crate::model::routing::RoutingPoint;
use crate::{Error, Real};
use nalgebra::{Matrix3, Vector3};

impl Model<'_> {
    /// The sum over the selected tendons of their internal tension tau_i t_i (world frame,
    /// N) and its moment about the centreline (R r_i) x tau_i t_i (N m), where
    /// t_i = p_i' / |p_i'| is the unit tangent of the tendon's path (eq. 9) for the state
    /// (R, v, u), v the strain ([`Site::strain`](super::Site::strain) of a node's coordinate).
    ///
    /// The point load of tendon i on the backbone where its path ends or bends is
    /// tau_i (t_i(s+) - t_i(s-)) (docs/model.md section 5), so jump and tip conditions are
    /// differences of these sums.
    pub fn tendon_pull<T: Real>(
        &self,
        s: f64,
        which: Which,
        R: &Matrix3<T>,
        v: &Vector3<T>,
        u: &Vector3<T>,
    ) -> Result<(Vector3<T>, Vector3<T>)> {
        self.tendon_pull_of(self.tendons(s, which), s, R, v, u)
    }

    /// [`Model::tendon_pull`] of the tendons `tendons` at s, given as [`Model::tendons`]
    /// yields them (index, tension, routing point at s): for a caller that sums the same
    /// tendons at s on many shapes (the initial guess's sweeps) and keeps their routing
    /// points instead of evaluating them on every sweep.
    pub(crate) fn tendon_pull_of<T: Real>(
        &self,
        tendons: impl Iterator<Item = (usize, f64, RoutingPoint)>,
        s: f64,
        R: &Matrix3<T>,
        v: &Vector3<T>,
        u: &Vector3<T>,
    ) -> Result<(Vector3<T>, Vector3<T>)> {
        let mut force = Vector3::<T>::zeros();
        let mut moment = Vector3::<T>::zeros();
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        for (i, tension, rp) in tendons {
            let (f_b, r) = body_pull(i, tension, &rp, s, v, u)?;
            // The point-moment model keeps only the moment of the tendon's pull.
            if coupled {
                force += R * f_b;
            }
            moment += R * r.cross(&f_b);
        }
        Ok((force, moment))
    }

    /// [`Model::tendon_pull_of`] in the body frame: R^T times its force and moment, summed
    /// over the tendons in the body frame and so without a rotation per tendon (the same
    /// sums to rounding, not the same bits). For the default initial guess's sweeps, which
    /// need the pulls only in the body frame; always inlined, so that it is compiled into
    /// their AVX2 build (`mesh/guess.rs`).
    #[inline(always)]
    pub(crate) fn tendon_pull_body_of(
        &self,
        tendons: impl Iterator<Item = (usize, f64, RoutingPoint)>,
        s: f64,
        v: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> Result<(Vector3<f64>, Vector3<f64>)> {
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        for (i, tension, rp) in tendons {
            let (f_b, r) = body_pull(i, tension, &rp, s, v, u)?;
            if coupled {
                force += f_b;
            }
            moment += r.cross(&f_b);
        }
        Ok((force, moment))
    }
}

/// A tendon's pull at s in the body frame, tau_i p_b' / |p_b'| with p_b' = u x r + r' + v
/// (eq. 9), and its routing point r lifted: tendon `i` of tension `tension` (N) at routing
/// point `rp`, for the strain `v` and curvature `u`.
///
/// # Errors
/// [`Error::SingularRouting`] where |p_b'| is below [`MIN_TENDON_SPEED`].
#[inline(always)]
fn body_pull<T: Real>(
    i: usize,
    tension: f64,
    rp: &RoutingPoint,
    s: f64,
    v: &Vector3<T>,
    u: &Vector3<T>,
) -> Result<(Vector3<T>, Vector3<T>)> {
    let r = lift::<T>(&rp.r);
    let pb_s = u.cross(&r) + lift::<T>(&rp.r_s) + v;
    let speed = pb_s.norm();
    if speed < T::from_f64(MIN_TENDON_SPEED).unwrap_or_else(T::zero) {
        return Err(Error::SingularRouting {
            tendon: i,
            s,
            speed: to_f64(speed),
        });
    }
    Ok((pb_s * (T::from_f64(tension).unwrap_or_else(T::zero) / speed), r))
}
