//! Eq. 13 at one point, assembled and factored for work beyond the linearization
//! (`super` module docs name the symbols): the factored M a linearization keeps
//! ([`Factored`], the linearized dynamics' mass), a point that keeps pass 1 for what
//! friction adds ([`Point`]), and the rates with solves for further right-hand sides
//! ([`rates_and_solve`]).
#![allow(non_snake_case)]

use super::factor::Factor;
use super::{Assembled, TendonCache, TendonPoint, assemble, breakdown, derivative};
use crate::error::Result;
use crate::model::equations::{Model, Site};
use nalgebra::{Matrix3, Matrix6, SMatrix, Vector3, Vector6};

/// Eq. 13's 6x6 matrix M at one point, factored ([`linearize_keeping`] keeps it): solves
/// with it give the bits [`rates_and_solve`] gives at the same site and strains (M does not
/// depend on the orientation).
#[derive(Clone)]
pub(crate) struct Factored(pub(super) Factor);

impl Factored {
    /// A placeholder (the factors of the identity) for a buffer that
    /// [`linearize_keeping`] fills.
    pub(crate) fn identity() -> Self {
        Factored(Factor::new(&Matrix6::identity(), true))
    }

    /// Overwrites each row of `bt` (a right-hand side of M, transposed) with the row of
    /// the solution, as [`rates_and_solve`] does; false when M is singular.
    #[inline(always)]
    pub(crate) fn solve_rows<const C: usize>(&self, bt: &mut SMatrix<f64, C, 6>) -> bool {
        self.0.solve_transposed_mut(bt)
    }
}

/// Eq. 13 (corrected) at one point, assembled and factored (pass 1 of [`linearize`]) for
/// what friction adds (docs/friction.md): the rates, solves with M for further right-hand
/// sides, and dF (the partial derivative of M x - rhs with x held fixed) at any rates x.
pub(crate) struct Point {
    assembled: Assembled,
    cache: TendonCache,
}

impl std::fmt::Debug for Point {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Point")
            .field("tendons", &self.assembled.count)
            .finish_non_exhaustive()
    }
}

impl Point {
    /// Assembles and factors eq. 13 at (R, v, u).
    ///
    /// # Errors
    /// As [`rates`].
    pub(crate) fn new(
        model: &Model,
        site: &Site,
        segment_end: f64,
        (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    ) -> Result<Self> {
        let mut cache = TendonCache::new();
        let assembled = assemble(model, site, segment_end, (R, v, u), Some(&mut cache), None)?;
        Ok(Point { assembled, cache })
    }

    /// [`Point::new`] in place: the tendon points kept in this point's own cache instead of
    /// one moved in (a point is about 1.3 kB), for a caller that evaluates many points. On
    /// an error the point holds no valid evaluation (the next refill starts over).
    ///
    /// # Errors
    /// As [`Point::new`].
    #[inline(always)]
    pub(crate) fn refill(
        &mut self,
        model: &Model,
        site: &Site,
        segment_end: f64,
        (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    ) -> Result<()> {
        self.cache.clear();
        self.assembled = assemble(model, site, segment_end, (R, v, u), Some(&mut self.cache), None)?;
        Ok(())
    }

    /// The c-th tendon loading the backbone here (in [`Model::distributed_tendons`]' order),
    /// as assembling M evaluated it, if it was kept.
    pub(crate) fn tendon(&self, c: usize) -> Option<&TendonPoint> {
        self.cache.points().get(c)
    }

    /// The rates (v', u') of eq. 13.
    pub(crate) fn rates(&self) -> Vector6<f64> {
        let x = &self.assembled.x;
        Vector6::from_fn(|i, _| x[i])
    }

    /// Overwrites each row of `bt` (a right-hand side of M, transposed) with the row of
    /// the solution; false when M is singular.
    #[inline(always)]
    pub(crate) fn solve_rows<const C: usize>(&self, bt: &mut SMatrix<f64, C, 6>) -> bool {
        self.assembled.factor.solve_transposed_mut(bt)
    }

    /// dF^T at the rates `x` (a row): row k is direction k of (v, u, phi), column j row j of
    /// F = M x - rhs (module docs), x held fixed.
    ///
    /// # Errors
    /// [`Error::SingularRouting`] for a tendon beyond the cached ones without a tangent.
    #[inline(always)]
    pub(crate) fn derivative(
        &self,
        model: &Model,
        site: &Site,
        segment_end: f64,
        (v, u): (&Vector3<f64>, &Vector3<f64>),
        x: &SMatrix<f64, 1, 6>,
    ) -> Result<SMatrix<f64, 9, 6>> {
        derivative(model, site, segment_end, (v, u), x, &self.assembled, &self.cache)
    }
}

/// Eq. 13 (corrected) at (R, v, u), assembled and factored without the tendons' quantities
/// that [`Point`] keeps for dF, and the rows of `bt` (a right-hand side of M, transposed)
/// overwritten with those of the solution: the rates (v', u') and M^-1 bt^T with the
/// operations of [`Point::new`], [`Point::rates`] and [`Point::solve_rows`] (the same
/// bits), the factors never moved out of the call (the mass of the linearized dynamics,
/// `collocation/dynamics.rs`).
///
/// # Errors
/// As [`rates`].
pub(crate) fn rates_and_solve<const C: usize>(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    bt: &mut SMatrix<f64, C, 6>,
) -> Result<Vector6<f64>> {
    let assembled = assemble(model, site, segment_end, (R, v, u), None, None)?;
    if !assembled.factor.solve_transposed_mut(bt) {
        return Err(breakdown(site.s));
    }
    let x = &assembled.x;
    Ok(Vector6::from_fn(|i, _| x[i]))
}
