//! Eq. 13 with friction's response to body loads at a point
//! ([`FrictionLinearization::load_response`], the mass of the linearized dynamics with
//! friction) and the Woodbury corrections it takes.
#![allow(non_snake_case)]

use super::{FrictionLinearization, Slip};
use nalgebra::allocator::Allocator;
use nalgebra::{DefaultAllocator, DimMin, Dyn, OMatrix, OVector, SMatrix, U1, U2, U3, Vector6};

/// [`FrictionLinearization::load_response`] of a point the lanes evaluated, for the loads
/// `input` (one per row): the rows it leaves, the turning responses and whether it holds.
#[derive(Debug)]
pub(super) struct LaneResponse {
    /// The body loads it answers, one per row (as `load_response` takes them).
    pub(super) input: SMatrix<f64, 6, 6>,
    /// The rates' responses to those loads, row by row (what `load_response` leaves).
    pub(super) output: SMatrix<f64, 6, 6>,
    /// Each slip's turning-rate response to the loads.
    pub(super) turning: Vec<SMatrix<f64, 1, 6>>,
    /// Whether its responses are finite (what `load_response` returns for it).
    pub(super) valid: bool,
    /// Whether it is of the point's current evaluation (the buffers outlive it).
    pub(super) current: bool,
}

impl FrictionLinearization {
    /// The response of this point's rates and turning rates to body loads (distributed
    /// force and moment, body frame, N/m and N m/m), for the mass of the linearized dynamics
    /// with friction (docs/stability.md, "Tendons with friction"): at fixed state, tensions
    /// and multipliers a load b changes the rates by -J^-1 b, J = M + sum_i e_i (dg_i/dx)^T
    /// the matrix of eq. 13 with the tangential loads (module docs: the frictionless -M^-1 b,
    /// and the tangential loads following the normal loads the new rates press), and each
    /// turning rate w_j mu_j kappa_j by -T_j b. `loads` holds one load per row (transposed,
    /// as [`crate::model::linearize::rates_and_solve`] takes them) and becomes row by row
    /// (J^-1 b)^T; `turning[j]` (one per tendon of [`super::slipping`], 0 for those not loading
    /// here) gets T_j b, one column per load. False for a point without an evaluation
    /// ([`super::linearize_into`]) or a singular J. A point the lanes evaluated
    /// ([`super::linearize_lanes_into`]) answers only for the loads they were given (what the
    /// scalar code gives for them, computed there), else false.
    pub(crate) fn load_response(&self, loads: &mut SMatrix<f64, 6, 6>, turning: &mut [SMatrix<f64, 1, 6>]) -> bool {
        if let Some(kept) = &self.lane_response
            && kept.current
            && kept.turning.len() == turning.len()
            && kept
                .input
                .iter()
                .zip(loads.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        {
            *loads = kept.output;
            turning.copy_from_slice(&kept.turning);
            return kept.valid;
        }
        let Some(point) = &self.point else {
            return false;
        };
        if !point.solve_rows(loads) {
            return false;
        }
        let slips = &self.slips;
        // On the stack for up to 3 tendons with friction here (no allocation per point).
        let woodbury = match slips.len() {
            0 => true,
            1 => woodbury_one(&slips[0], loads),
            2 => woodbury_rows(U2, slips, loads),
            3 => woodbury_rows(U3, slips, loads),
            m => woodbury_rows(Dyn(m), slips, loads),
        };
        if !woodbury {
            return false;
        }
        turning.iter_mut().for_each(|t| t.fill(0.0));
        for sl in slips {
            // d turning_j = (w_j mu_j / tau_j) q^_j . dq_j, dq_j through the rates alone
            // (the state is fixed), as `linearize_into`'s d_turning.
            let factor = sl.signed_mu * sl.tp.inv_speed / sl.tp.k;
            for (r, t) in turning[sl.slot].iter_mut().enumerate() {
                let change = sl.normal_change(&loads.row(r).transpose());
                *t = factor * sl.q_hat.dot(&change);
            }
        }
        loads.iter().all(|v| v.is_finite())
    }
}

/// [`woodbury_rows`] for one slip, written out: S = 1 + g . y is 1 x 1, and its LU solve is
/// w = (g . M^-1 b) / S (nalgebra's for a 1 x 1 matrix: no pivoting, one division, false for
/// S = 0), so the rows are the same bits without building the LU.
pub(super) fn woodbury_one(slip: &Slip, loads: &mut SMatrix<f64, 6, 6>) -> bool {
    let gradient = slip.gradient();
    let schur = 1.0 + gradient.dot(&slip.y);
    if schur == 0.0 {
        return false;
    }
    for r in 0..6 {
        let mb: Vector6<f64> = loads.row(r).transpose();
        let w = gradient.dot(&mb) / schur;
        let out = mb - slip.y * w;
        loads.set_row(r, &out.transpose());
    }
    true
}

/// J^-1 b = M^-1 b - Y S^-1 G^T M^-1 b for each row of `loads` (which holds (M^-1 b)^T),
/// S = I + G^T Y (Woodbury, as [`super::linearize_into`]), with S and its LU factors of dimension
/// `d` (the number of `slips`): fixed dimensions keep them on the stack, the same
/// operations in the same order as for a dynamic one. False for a singular S.
pub(super) fn woodbury_rows<D: DimMin<D, Output = D>>(d: D, slips: &[Slip], loads: &mut SMatrix<f64, 6, 6>) -> bool
where
    DefaultAllocator: Allocator<D, D> + Allocator<D>,
{
    let gradients = OVector::<Vector6<f64>, D>::from_fn_generic(d, U1, |l, _| slips[l].gradient());
    let schur =
        OMatrix::<f64, D, D>::from_fn_generic(d, d, |j, l| f64::from(u8::from(j == l)) + gradients[j].dot(&slips[l].y));
    let lu = schur.lu();
    for r in 0..6 {
        let mb: Vector6<f64> = loads.row(r).transpose();
        let g = OVector::<f64, D>::from_fn_generic(d, U1, |l, _| gradients[l].dot(&mb));
        let Some(w) = lu.solve(&g) else {
            return false;
        };
        let mut out = mb;
        for (sl, wj) in slips.iter().zip(w.iter()) {
            out -= sl.y * *wj;
        }
        loads.set_row(r, &out.transpose());
    }
    true
}
