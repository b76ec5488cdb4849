//! The chain rule of an interval's Jacobian through its end points ([`EndColumns`]): the
//! columns of the scaled unknowns of both nodes in y_0, y_1, F_0 and F_1, the midpoint's
//! columns and the 12 x 24 block they make (`residual::interval_jacobian` and the friction
//! intervals).
//!
//! Most of the four 12 x 18 column blocks are structurally zero: y_0 depends on v_a, u_a
//! only (through the identity and 1/L), y_1 on theta_a, theta_b (through theta_1) and v_b,
//! u_b, F_0 on node a's columns and F_1 on theta_a and node b's. Only their non-zero parts
//! are stored; every entry of the midpoint's columns and of the block is computed by the same
//! expression as with the full matrices, with the structural zeros as the literal 0.0 (which
//! the compiler folds only where IEEE arithmetic gives the same bits), so the values are bit
//! for bit those of the dense formulation, signed zeros included.
#![allow(non_snake_case)]

use super::residual::{PointFrame, PointLinearization};
use nalgebra::{Matrix3, SMatrix};

/// Column blocks of the 18 columns (theta, v, u of node a, then of node b) and row blocks of
/// the 12 rows (p, theta, v, u), three each.
const A_THETA: usize = 0;
const A_V: usize = 1;
const A_U: usize = 2;
const B_THETA: usize = 3;
const B_V: usize = 4;
const B_U: usize = 5;
const ROW_THETA: usize = 1;
const ROW_V: usize = 2;
const ROW_U: usize = 3;

/// The columns (theta_a, v_a, u_a, theta_b, v_b, u_b) of the scaled unknowns (p + L dp,
/// R exp(dtheta), v + dv, u + du / L) in an interval's end points y_0, y_1 and in F_0, F_1,
/// from the end points' linearizations: the chain rule of
/// [`super::residual::interval_jacobian`], shared with the friction intervals
/// (collocation/friction). Only the blocks that are not structurally zero are kept (module
/// docs).
pub(super) struct EndColumns {
    /// d theta_1 / d theta_a = -J_r^-1(theta_1) exp(theta_1)^T: y_1's theta rows on the
    /// theta_a columns.
    dtheta1_da: Matrix3<f64>,
    /// J_r^-1(theta_1): y_1's theta rows on the theta_b columns.
    jri1: Matrix3<f64>,
    /// 1 / L: y_0's (y_1's) u rows on the u_a (u_b) columns.
    inv_length: f64,
    /// F_0 on the columns theta_a, v_a, u_a (zero on node b's).
    dF0: SMatrix<f64, 12, 9>,
    /// F_1 on the columns theta_a, theta_b, v_b, u_b (zero on v_a, u_a).
    dF1: SMatrix<f64, 12, 12>,
}

impl EndColumns {
    /// The columns from the end points' linearizations `p0`, `p1` and the end point's
    /// frame (at theta_1).
    #[inline(always)]
    pub(super) fn new(p0: &PointLinearization, p1: &PointLinearization, frame1: &PointFrame, length: f64) -> Self {
        let mut ends = EndColumns::zeros();
        ends.fill(p0, p1, frame1, length);
        ends
    }

    /// Columns of zeros, for [`EndColumns::fill`].
    #[inline(always)]
    pub(super) fn zeros() -> Self {
        EndColumns {
            dtheta1_da: Matrix3::zeros(),
            jri1: Matrix3::zeros(),
            inv_length: 0.0,
            dF0: SMatrix::zeros(),
            dF1: SMatrix::zeros(),
        }
    }

    /// [`EndColumns::new`] in place (every entry is overwritten): for a kernel that forms
    /// the columns of several intervals in turn, without moving them out of a constructor.
    #[inline(always)]
    pub(super) fn fill(&mut self, p0: &PointLinearization, p1: &PointLinearization, frame1: &PointFrame, length: f64) {
        // theta_1 = log(exp(-d_a) Q exp(d_b)): d/d d_b = J_r^-1, d/d d_a = -J_r^-1 exp(theta_1)^T
        let jri1 = frame1.Jri;
        let dtheta1_da = -jri1 * frame1.E.transpose();
        self.dtheta1_da = dtheta1_da;
        self.jri1 = jri1;
        self.inv_length = 1.0 / length;
        let ends = self;
        // The frame R_k = R_a exp(d_a) enters every F through the theta_a columns. Written
        // entry by entry (nalgebra's products and `scale_mut` stayed calls in the AVX2
        // build): each product entry summed as nalgebra's sums it (the k = 0 term, then
        // the k = 1 and k = 2 terms added in turn), each scaled entry the copy times 1 / L,
        // so the same bits.
        let inv_length = 1.0 / length;
        let dF0 = &mut ends.dF0;
        for i in 0..12 {
            for c in 0..3 {
                dF0[(i, c)] = p0.f_frame[(i, c)];
                dF0[(i, 3 + c)] = p0.f_y[(i, 6 + c)];
                dF0[(i, 6 + c)] = p0.f_y[(i, 9 + c)] * inv_length;
            }
        }
        let dF1 = &mut ends.dF1;
        let f1 = &p1.f_y;
        for c in 0..3 {
            for i in 0..12 {
                let product =
                    |m: &Matrix3<f64>| f1[(i, 3)] * m[(0, c)] + f1[(i, 4)] * m[(1, c)] + f1[(i, 5)] * m[(2, c)];
                dF1[(i, c)] = product(&dtheta1_da) + p1.f_frame[(i, c)];
                dF1[(i, 3 + c)] = product(&jri1);
                dF1[(i, 6 + c)] = f1[(i, 6 + c)];
                dF1[(i, 9 + c)] = f1[(i, 9 + c)] * inv_length;
            }
        }
    }

    /// y_0 at row `3 RB + r`, column `3 CB + c`.
    #[inline(always)]
    fn y0<const RB: usize, const CB: usize>(&self, r: usize, c: usize) -> f64 {
        match (RB, CB) {
            (ROW_V, A_V) if r == c => 1.0,
            (ROW_U, A_U) if r == c => self.inv_length,
            _ => 0.0,
        }
    }

    /// y_1 at row `3 RB + r`, column `3 CB + c`.
    #[inline(always)]
    fn y1<const RB: usize, const CB: usize>(&self, r: usize, c: usize) -> f64 {
        match (RB, CB) {
            (ROW_THETA, A_THETA) => self.dtheta1_da[(r, c)],
            (ROW_THETA, B_THETA) => self.jri1[(r, c)],
            (ROW_V, B_V) if r == c => 1.0,
            (ROW_U, B_U) if r == c => self.inv_length,
            _ => 0.0,
        }
    }

    /// F_0's column derivative at row `3 RB + r`, column `3 CB + c`.
    #[inline(always)]
    fn f0<const RB: usize, const CB: usize>(&self, r: usize, c: usize) -> f64 {
        if CB <= A_U {
            self.dF0[(3 * RB + r, 3 * CB + c)]
        } else {
            0.0
        }
    }

    /// F_1's column derivative at row `3 RB + r`, column `3 CB + c`.
    #[inline(always)]
    fn f1<const RB: usize, const CB: usize>(&self, r: usize, c: usize) -> f64 {
        match CB {
            A_THETA => self.dF1[(3 * RB + r, c)],
            A_V | A_U => 0.0,
            _ => self.dF1[(3 * RB + r, 3 * (CB - 2) + c)],
        }
    }

    /// One 3 x 3 block of the midpoint's columns (rows of row block `RB` >= 1).
    #[inline(always)]
    fn midpoint_block<const RB: usize, const CB: usize>(&self, c8: f64, out: &mut SMatrix<f64, 9, 18>) {
        for c in 0..3 {
            for r in 0..3 {
                out[(3 * (RB - 1) + r, 3 * CB + c)] = (self.y0::<RB, CB>(r, c) + self.y1::<RB, CB>(r, c)) * 0.5
                    + (self.f0::<RB, CB>(r, c) - self.f1::<RB, CB>(r, c)) * c8;
            }
        }
    }

    /// The midpoint's columns of one column block, rows theta, v, u.
    #[inline(always)]
    fn midpoint_column<const CB: usize>(&self, c8: f64, out: &mut SMatrix<f64, 9, 18>) {
        self.midpoint_block::<1, CB>(c8, out);
        self.midpoint_block::<2, CB>(c8, out);
        self.midpoint_block::<3, CB>(c8, out);
    }

    /// The columns of the midpoint y_m = (y_0 + y_1) / 2 + h/8 (F_0 - F_1), rows theta, v, u
    /// (the p rows are not needed: F does not depend on p). Entry by entry, without the
    /// temporaries of matrix expressions.
    #[inline(always)]
    pub(super) fn midpoint(&self, h: f64) -> SMatrix<f64, 9, 18> {
        let c8 = h / 8.0;
        let mut out = SMatrix::<f64, 9, 18>::zeros();
        self.midpoint_column::<A_THETA>(c8, &mut out);
        self.midpoint_column::<A_V>(c8, &mut out);
        self.midpoint_column::<A_U>(c8, &mut out);
        self.midpoint_column::<B_THETA>(c8, &mut out);
        self.midpoint_column::<B_V>(c8, &mut out);
        self.midpoint_column::<B_U>(c8, &mut out);
        out
    }

    /// One 3 x 3 block of J (row block `RB`, column block `CB`) into the row-major 12 x 24
    /// `jac`, row scale `scale`.
    #[inline(always)]
    fn write_block<const RB: usize, const CB: usize>(
        &self,
        dFm: &SMatrix<f64, 12, 18>,
        c6: f64,
        scale: f64,
        jac: &mut [f64],
    ) {
        let first = if CB < B_THETA { 3 + 3 * CB } else { 6 + 3 * CB };
        for c in 0..3 {
            for r in 0..3 {
                let (i, j) = (3 * RB + r, 3 * CB + c);
                let (y1, y0) = (self.y1::<RB, CB>(r, c), self.y0::<RB, CB>(r, c));
                let (f0, fm, f1) = (self.f0::<RB, CB>(r, c), dFm[(i, j)], self.f1::<RB, CB>(r, c));
                jac[24 * i + first + c] = scale * (y1 - y0 - c6 * (f0 + 4.0 * fm + f1));
            }
        }
    }

    /// The blocks of J of one column block, all row blocks.
    #[inline(always)]
    fn write_column<const CB: usize>(&self, dFm: &SMatrix<f64, 12, 18>, c6: f64, scales: [f64; 4], jac: &mut [f64]) {
        self.write_block::<0, CB>(dFm, c6, scales[0], jac);
        self.write_block::<ROW_THETA, CB>(dFm, c6, scales[1], jac);
        self.write_block::<ROW_V, CB>(dFm, c6, scales[2], jac);
        self.write_block::<ROW_U, CB>(dFm, c6, scales[3], jac);
    }

    /// Writes J = Y1 - Y0 - (dF0 + 4 dFm + dF1) h / 6 on the 18 columns, given the
    /// midpoint's columns `dFm`, straight into the row-major 12 x 24 block `jac` with the
    /// row scaling of the residual (p rows / L, u' rows * L); the p columns hold
    /// L (dp_b - dp_a) / L.
    #[inline(always)]
    pub(super) fn write(&self, dFm: &SMatrix<f64, 12, 18>, h: f64, length: f64, jac: &mut [f64]) {
        debug_assert_eq!(jac.len(), 12 * 24);
        let c6 = h / 6.0;
        let scales = [1.0 / length, 1.0, 1.0, length];
        for (i, row) in jac.chunks_exact_mut(24).enumerate() {
            row[..3].fill(0.0);
            row[12..15].fill(0.0);
            if i < 3 {
                row[i] = -1.0;
                row[12 + i] = 1.0;
            }
        }
        self.write_column::<A_THETA>(dFm, c6, scales, jac);
        self.write_column::<A_V>(dFm, c6, scales, jac);
        self.write_column::<A_U>(dFm, c6, scales, jac);
        self.write_column::<B_THETA>(dFm, c6, scales, jac);
        self.write_column::<B_V>(dFm, c6, scales, jac);
        self.write_column::<B_U>(dFm, c6, scales, jac);
    }
}
