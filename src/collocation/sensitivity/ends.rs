//! The exact right-hand sides at the rod's two ends: the tip force and moment (they enter
//! only the tip rows) and the base position and rotation (only the base rows); module docs
//! of `sensitivity`, "dF/dq".

use super::{NodeDerivative, Sensitivity};
use crate::collocation::unknowns::{TIP_ROWS, tip_row};
use crate::error::{Result, invalid};
use crate::so3;
use nalgebra::{Matrix3, Vector3};

impl Sensitivity<'_> {
    /// Checks a Cartesian axis index: [`crate::Error::InvalidInput`] unless 0, 1 or 2.
    fn check_axis(axis: usize) -> Result<()> {
        if axis < 3 {
            Ok(())
        } else {
            Err(invalid("axis", format!("is {axis}"), "give 0, 1 or 2 for x, y or z"))
        }
    }

    /// The right-hand side buffer, zeroed.
    fn zeroed_rhs(&mut self) -> &mut [f64] {
        let rhs = &mut self.scratch[0];
        rhs.fill(0.0);
        rhs
    }

    /// The derivative of every node state with respect to component `axis` (0, 1, 2 for
    /// x, y, z) of the tip force (per N, world frame). Exact: the residual is linear in the
    /// tip force, which enters only the tip rows, as -D^-1 R^T e_axis (strain units).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for an axis other than 0, 1, 2 or a singular Jacobian.
    pub fn tip_force(&mut self, axis: usize) -> Result<Vec<NodeDerivative>> {
        self.tip_force_rhs(axis)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::tip_force`] into the right-hand side buffer.
    pub(super) fn tip_force_rhs(&mut self, axis: usize) -> Result<()> {
        Self::check_axis(axis)?;
        let (R, kse, _) = self.tip_frame();
        let column = R.transpose().column(axis).component_div(&kse);
        let force_rows = tip_row(self.states.len());
        let rhs = self.zeroed_rhs();
        for i in 0..3 {
            rhs[force_rows + i] = column[i];
        }
        Ok(())
    }

    /// As [`Sensitivity::tip_force`] for the tip moment (per N m, world frame): the tip's
    /// moment rows carry -L C^-1 R^T e_axis.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for an axis other than 0, 1, 2 or a singular Jacobian.
    pub fn tip_moment(&mut self, axis: usize) -> Result<Vec<NodeDerivative>> {
        self.tip_moment_rhs(axis)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::tip_moment`] into the right-hand side buffer.
    pub(super) fn tip_moment_rhs(&mut self, axis: usize) -> Result<()> {
        Self::check_axis(axis)?;
        let (R, _, kbt) = self.tip_frame();
        let column = R.transpose().column(axis).component_div(&kbt) * self.robot().length();
        let moment_rows = tip_row(self.states.len()) + TIP_ROWS / 2;
        let rhs = self.zeroed_rhs();
        for i in 0..3 {
            rhs[moment_rows + i] = column[i];
        }
        Ok(())
    }

    /// Tip orientation and section stiffness (kse, kbt) there.
    fn tip_frame(&self) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
        let tip = &self.states[self.states.len() - 1];
        let section = self.robot().rod.section_at(tip.s).section;
        (tip.R, section.kse, section.kbt)
    }

    /// The derivative of every node state with respect to component `axis` of the base
    /// position p0 (per m, world frame). Exact: the base rows (p(0) - p0) / L give
    /// dF/dp0 = -e_axis / L.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for an axis other than 0, 1, 2 or a singular Jacobian.
    pub fn base_position(&mut self, axis: usize) -> Result<Vec<NodeDerivative>> {
        self.base_position_rhs(axis)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::base_position`] into the right-hand side buffer.
    pub(super) fn base_position_rhs(&mut self, axis: usize) -> Result<()> {
        Self::check_axis(axis)?;
        let length = self.robot().length();
        self.zeroed_rhs()[axis] = 1.0 / length;
        Ok(())
    }

    /// The derivative of every node state with respect to component `axis` of a world-frame
    /// rotation vector phi turning the base, R0 -> exp(hat(phi)) R0 (per rad). Exact: the
    /// base rows log(R0^T R(0)) = eps become log(exp(-hat(R0^T phi)) exp(hat(eps))), whose
    /// derivative is -J_l(eps)^-1 R0^T, with J_l(eps)^-1 = J_r(-eps)^-1 (eps is the
    /// residual, about 0).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for an axis other than 0, 1, 2 or a singular Jacobian.
    pub fn base_rotation(&mut self, axis: usize) -> Result<Vec<NodeDerivative>> {
        self.base_rotation_rhs(axis)?;
        self.respond()
    }

    /// Writes -dF/dq of [`Sensitivity::base_rotation`] into the right-hand side buffer.
    pub(super) fn base_rotation_rhs(&mut self, axis: usize) -> Result<()> {
        Self::check_axis(axis)?;
        let R0 = self.robot().base_rotation;
        let eps = so3::log(&(R0.transpose() * self.states[0].R));
        let column = so3::right_jacobian_inv(&(-eps)) * R0.transpose().column(axis);
        let rhs = self.zeroed_rhs();
        for i in 0..3 {
            rhs[3 + i] = column[i];
        }
        Ok(())
    }
}
