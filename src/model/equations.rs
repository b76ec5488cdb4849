//! Pointwise physics: the coupled rod-tendon equations (eq. 13 as corrected in
//! docs/model.md), the tendon point wrenches, and the internal force and moment.
//!
//! Everything that depends only on s (stiffness, reference strains, routings, external
//! loads) is evaluated once in f64 as a [`Site`]. The tendon pulls, point wrenches and
//! internal wrench are generic over the scalar, so the jump blocks of the collocation
//! Jacobian are taken exactly by forward-mode automatic differentiation (the base and tip
//! blocks are in closed form, `collocation::end_rows`, checked against it). Eq. 13
//! itself is in f64 only, in [`linearize`] with its exact linearization.
#![allow(non_snake_case)]

use crate::error::Result;
use crate::model::linearize;
use crate::model::parameter::Parameter;
use crate::model::robot::{Robot, RodModel, TendonModel};
use crate::model::rod::{SectionPoint, StrainPoint};
use crate::model::routing::RoutingPoint;
use crate::{Error, Real};
use nalgebra::{Matrix3, Vector3};

mod pulls;

/// Below this |p_i'| (body frame, dimensionless) a tendon's path has no usable tangent.
pub(crate) const MIN_TENDON_SPEED: f64 = 1e-9;

/// Lifts an f64 vector into the scalar type `T`.
pub fn lift<T: Real>(v: &Vector3<f64>) -> Vector3<T> {
    v.map(|x| T::from_f64(x).unwrap_or_else(T::zero))
}

/// Lifts an f64 matrix into the scalar type `T`.
pub fn lift_m<T: Real>(m: &Matrix3<f64>) -> Matrix3<T> {
    m.map(|x| T::from_f64(x).unwrap_or_else(T::zero))
}

/// The state-independent data at one arc length.
#[derive(Clone, Copy, Debug)]
pub struct Site {
    /// Arc length (m).
    pub s: f64,
    /// Stiffness and its derivative.
    pub section: SectionPoint,
    /// Reference strains and their derivatives.
    pub reference: StrainPoint,
    /// f_e: external distributed force (N/m), world frame, times the load factor.
    pub f_e: Vector3<f64>,
    /// l_e: external distributed moment (N m/m), world frame, times the load factor.
    pub l_e: Vector3<f64>,
    /// Follower force per unit length (N/m), body frame, times the load factor: it adds
    /// to R^T f_e in eq. 13 and does not turn with a perturbation of R.
    pub f_follower: Vector3<f64>,
    /// True on a Kirchhoff rod ([`RodModel::Kirchhoff`]): the strain is v = v* exactly and
    /// a node's translational coordinate carries the internal force ([`Site::strain`]).
    pub inextensible: bool,
}

impl Site {
    /// The shear and extension strain v (body frame) at a node whose translational
    /// coordinate is `v`. The coordinate is v* + K_se^-1 n_b, the body-frame internal force
    /// n_b in strain units: for a Cosserat rod that is the strain itself (the constitutive
    /// law), for a Kirchhoff rod the strain is v* whatever the force (docs/model.md,
    /// "Kirchhoff rods").
    pub fn strain<T: Real>(&self, v: &Vector3<T>) -> Vector3<T> {
        if self.inextensible {
            lift(&self.reference.v_star)
        } else {
            *v
        }
    }
}

/// Which tendons take part in a sum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Which {
    /// Tendons that reach the end `e` of the current segment (termination >= e).
    ActiveTo(f64),
    /// Tendons that end exactly at s (termination == s).
    EndingAt(f64),
    /// Tendons that continue past s (termination > s).
    Past(f64),
}

impl Which {
    /// Whether a tendon that ends at `end` (m) takes part.
    #[inline(always)]
    fn takes(self, end: f64) -> bool {
        match self {
            Which::ActiveTo(e) => end >= e,
            Which::EndingAt(x) => end == x,
            Which::Past(x) => end > x,
        }
    }
}

/// The robot's equations with its inputs: the tendon tensions, multiplied by
/// `tension_factor`, the external loads, multiplied by `load_factor` (1 and 1 is the robot as
/// given; smaller values are used by load continuation), and one input a trace replaces.
/// The model owns the inputs a solve changes, so that a solver changes them here, in place,
/// without cloning or changing the robot: the tensions of displacement-controlled tendons
/// (Newton's unknowns), the factors, the traced parameter.
#[derive(Clone, Debug)]
pub struct Model<'a> {
    /// The robot (validated): geometry, stiffness, routings, loads.
    pub robot: &'a Robot,
    /// The tension tau_i (N) of every tendon, in the robot's order: the robot's
    /// ([`crate::model::tendon::Tendon::tension`]: the input, or the starting tension of a
    /// displacement-controlled tendon) until a solver sets the unknown tensions.
    pub tensions: Vec<f64>,
    /// Multiplier on all tendon tensions, in [0, 1].
    pub tension_factor: f64,
    /// Multiplier on all external loads (distributed, point and tip), in [0, 1].
    pub load_factor: f64,
    /// One load or base input replaced by a value, with the meaning [`Parameter::apply`]
    /// gives it (a trace's parameter, set by [`Model::set`]; a tension is set in
    /// `tensions`, the load scale is the two factors).
    pub parameter: Option<(Parameter, f64)>,
}

impl<'a> Model<'a> {
    /// The model of a validated robot at full load.
    pub fn new(robot: &'a Robot) -> Self {
        Self::new_in(robot, Vec::with_capacity(robot.tendons.len()))
    }

    /// [`Model::new`] with the tensions written into `buffer` (its contents replaced), which
    /// a caller that keeps buffers passes so that no new one is allocated.
    pub(crate) fn new_in(robot: &'a Robot, mut buffer: Vec<f64>) -> Self {
        buffer.clear();
        buffer.extend(robot.tendons.iter().map(|t| t.tension()));
        Model {
            robot,
            tensions: buffer,
            tension_factor: 1.0,
            load_factor: 1.0,
            parameter: None,
        }
    }

    /// A clone of this model with its tensions copied into `buffer` (its contents
    /// replaced), as [`Model::new_in`].
    pub(crate) fn clone_in(&self, mut buffer: Vec<f64>) -> Self {
        buffer.clone_from(&self.tensions);
        Model {
            robot: self.robot,
            tensions: buffer,
            tension_factor: self.tension_factor,
            load_factor: self.load_factor,
            parameter: self.parameter,
        }
    }

    /// Sets `parameter` to `value` on the model, with the meaning [`Parameter::apply`] gives
    /// it on the robot: a tension in [`Model::tensions`], the load scale as both factors,
    /// any other input as [`Model::parameter`] (`youngs_modulus`, `displacement.I` and
    /// `routing.I.x|y` change the robot's sections, actuation or routings, which only a new
    /// robot has: set them with [`Parameter::apply`]; a trace refuses them). Returns whether the
    /// sites changed (external loads), which a system must then recompute.
    pub fn set(&mut self, parameter: Parameter, value: f64) -> bool {
        match parameter {
            Parameter::Tension(i) => {
                self.tensions[i] = value;
                false
            }
            Parameter::LoadScale => {
                self.tension_factor = value;
                self.load_factor = value;
                true
            }
            _ => {
                self.parameter = Some((parameter, value));
                true
            }
        }
    }

    /// The base position (m, world frame), with the parameter's value when it is a
    /// component of it.
    pub fn base_position(&self) -> Vector3<f64> {
        let mut p = self.robot.base_position;
        if let Some((Parameter::BasePosition(c), value)) = self.parameter {
            p[c] = value;
        }
        p
    }

    /// State-independent data at arc length s; at the end of one of the rod's segments,
    /// the segment that ends there (the left limit: [`Model::site_on`] chooses the side).
    pub fn site(&self, s: f64) -> Site {
        self.site_on(s, s)
    }

    /// State-independent data at arc length s on the stretch of backbone that ends at
    /// `segment_end` (m): a mesh node's site, on its side of a breakpoint where the rod's
    /// section or precurvature jumps ([`crate::model::rod::Rod::section_on`]).
    pub fn site_on(&self, s: f64, segment_end: f64) -> Site {
        let loads = &self.robot.loads;
        Site {
            s,
            section: self.robot.rod.section_on(s, segment_end),
            reference: self.robot.rod.reference_on(s, segment_end),
            f_e: {
                let f = loads.distributed_force.at(s);
                let f = self.parameter.map_or(f, |(p, value)| p.distributed_force(f, value));
                f * self.load_factor
            },
            l_e: loads.distributed_moment.at(s) * self.load_factor,
            f_follower: loads.follower_distributed_force.at(s) * self.load_factor,
            inextensible: self.robot.rod_model == RodModel::Kirchhoff,
        }
    }

    /// (tension tau_i in N, routing point) for the selected tendons at s.
    pub fn tendons(&self, s: f64, which: Which) -> impl Iterator<Item = (usize, f64, RoutingPoint)> + '_ {
        let (l, factor) = (self.robot.length(), self.tension_factor);
        let tendons = self.robot.tendons.iter().zip(&self.tensions);
        tendons.enumerate().filter_map(move |(i, (t, &tension))| {
            let take = which.takes(t.end(l)) && tension > 0.0;
            take.then(|| (i, tension * factor, t.routing.at(s, l)))
        })
    }

    /// As [`Model::tendons`], slack tendons (tension 0) included: the tendons whose
    /// tension would act at s, for the derivative in a tension (right derivative at 0).
    pub(crate) fn reaching(&self, s: f64, which: Which) -> impl Iterator<Item = (usize, f64, RoutingPoint)> + '_ {
        let (l, factor) = (self.robot.length(), self.tension_factor);
        let tendons = self.robot.tendons.iter().zip(&self.tensions);
        tendons.enumerate().filter_map(move |(i, (t, &tension))| {
            let take = which.takes(t.end(l));
            take.then(|| (i, tension * factor, t.routing.at(s, l)))
        })
    }

    /// As [`Model::distributed_tendons`], slack tendons included ([`Model::reaching`]).
    #[cfg(test)]
    pub(crate) fn distributed_reaching(
        &self,
        s: f64,
        segment_end: f64,
    ) -> impl Iterator<Item = (usize, f64, RoutingPoint)> + '_ {
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        self.reaching(s, Which::ActiveTo(segment_end)).filter(move |_| coupled)
    }

    /// The tendons of [`Model::distributed_reaching`] without their routing points: (index,
    /// whether the tendon is taut, the tendon), so that a caller that has a taut tendon's
    /// point already evaluates only the others'.
    pub(crate) fn distributed_reaching_tendons(
        &self,
        segment_end: f64,
    ) -> impl Iterator<Item = (usize, bool, &crate::model::tendon::Tendon)> + '_ {
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        let l = self.robot.length();
        let which = Which::ActiveTo(segment_end);
        let tendons = self.robot.tendons.iter().zip(&self.tensions).enumerate();
        tendons
            .filter(move |(_, (t, _))| coupled && which.takes(t.end(l)))
            .map(|(i, (t, &tension))| (i, tension > 0.0, t))
    }

    /// The tendons whose distributed loads act on the segment ending at `segment_end` (none in
    /// the point-moment model): (index, tension tau_i in N, routing point).
    pub fn distributed_tendons(
        &self,
        s: f64,
        segment_end: f64,
    ) -> impl Iterator<Item = (usize, f64, RoutingPoint)> + '_ {
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        self.tendons(s, Which::ActiveTo(segment_end)).filter(move |_| coupled)
    }

    /// Eq. 13 (corrected): the rates (v', u') of the node coordinates at a site for the
    /// state (R, v, u) (v' the rate of the translational coordinate, [`Site::strain`]),
    /// with the tendons that reach `segment_end` loading the backbone. This is
    /// [`linearize::rates`] (the one f64 implementation of eq. 13, shared with the exact
    /// linearization), split into its v' and u' parts.
    ///
    /// # Errors
    /// [`Error::SingularRouting`] where a tendon's path tangent vanishes,
    /// [`Error::Breakdown`] where the 6x6 system is singular.
    pub fn strain_rates(
        &self,
        site: &Site,
        segment_end: f64,
        R: &Matrix3<f64>,
        v: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> Result<(Vector3<f64>, Vector3<f64>)> {
        let x = linearize::rates(self, site, segment_end, R, v, u)?;
        Ok((x.fixed_rows::<3>(0).into(), x.fixed_rows::<3>(3).into()))
    }

    /// Internal force n = R D (v - v*) (N) and moment m = R C (u - u*) (N m), world frame
    /// (eq. 3), for the node coordinates (v, u): on a Kirchhoff rod v is the translational
    /// coordinate v* + D^-1 n_b ([`Site::strain`]), so this is its force, not eq. 3's.
    pub fn internal_wrench<T: Real>(
        &self,
        site: &Site,
        R: &Matrix3<T>,
        v: &Vector3<T>,
        u: &Vector3<T>,
    ) -> (Vector3<T>, Vector3<T>) {
        let nb = (v - lift::<T>(&site.reference.v_star)).component_mul(&lift(&site.section.section.kse));
        let mb = (u - lift::<T>(&site.reference.u_star)).component_mul(&lift(&site.section.section.kbt));
        (R * nb, R * mb)
    }

    /// Body-frame node coordinates (v, u) that carry the body-frame internal wrench
    /// (n_b, m_b): the inverse of [`Model::internal_wrench`] (the strains on a Cosserat rod).
    pub fn strains_for_wrench<T: Real>(
        &self,
        site: &Site,
        n_b: &Vector3<T>,
        m_b: &Vector3<T>,
    ) -> (Vector3<T>, Vector3<T>) {
        let v = lift::<T>(&site.reference.v_star) + n_b.component_div(&lift(&site.section.section.kse));
        let u = lift::<T>(&site.reference.u_star) + m_b.component_div(&lift(&site.section.section.kbt));
        (v, u)
    }
}

/// The real part of a scalar (its value for f64, the value without derivatives for duals).
pub fn to_f64<T: Real>(x: T) -> f64 {
    // `to_subset` keeps only the real part for the dual types of num-dual.
    x.to_subset().unwrap_or(f64::NAN)
}

/// One side of a point-load condition: the site and the state (R, v, u) there.
pub type Side<'s, T> = (&'s Site, &'s Matrix3<T>, &'s Vector3<T>, &'s Vector3<T>);

impl Model<'_> {
    /// Sum of the external point force and moment (world frame, N and N m) applied exactly
    /// at s, including the tip wrench when s is the tip. Scaled by the load factor.
    pub fn point_wrench(&self, s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let loads = &self.robot.loads;
        let (mut f, mut l) = if s == self.robot.length() {
            let (mut f, mut l) = (loads.tip_force, loads.tip_moment);
            match self.parameter {
                Some((Parameter::TipForce(c), value)) => f[c] = value,
                Some((Parameter::TipMoment(c), value)) => l[c] = value,
                _ => {}
            }
            (f, l)
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        for p in loads.point.iter().filter(|p| p.s == s) {
            f += p.force;
            l += p.moment;
        }
        (f * self.load_factor, l * self.load_factor)
    }

    /// The follower tip force and moment (tip body frame, N and N m), times the load factor.
    pub fn follower_tip(&self) -> (Vector3<f64>, Vector3<f64>) {
        let loads = &self.robot.loads;
        (
            loads.follower_tip_force * self.load_factor,
            loads.follower_tip_moment * self.load_factor,
        )
    }

    /// Imbalance of the point-load condition at s (jump conditions and tip boundary
    /// condition, docs/model.md section 5):
    ///
    /// n(s-) = n(s+) + F_ext + sum_i tau_i (t_i(s+) - t_i(s-)),
    /// m(s-) = m(s+) + L_ext + sum_i (R r_i) x tau_i (t_i(s+) - t_i(s-)),
    ///
    /// with t_i(s+) = 0 for a tendon that ends at s, n(s+) = m(s+) = 0 at the tip
    /// (`right = None`), and the bend term of continuing tendons only when
    /// `robot.corner_forces`. Returned in strain units in the left body frame:
    /// (D^-1 R^T dn, C^-1 R^T dm), zero when balanced.
    ///
    /// # Errors
    /// [`Error::SingularRouting`] where a tendon has no tangent.
    pub fn wrench_balance<T: Real>(
        &self,
        s: f64,
        left: Side<T>,
        right: Option<Side<T>>,
    ) -> Result<(Vector3<T>, Vector3<T>)> {
        let (site_a, Ra, va, ua) = left;
        let (mut dn, mut dm) = self.internal_wrench(site_a, Ra, va, ua);
        let (f_ext, l_ext) = self.point_wrench(s);
        dn -= lift::<T>(&f_ext);
        dm -= lift::<T>(&l_ext);
        let va = &site_a.strain(va);
        let (fe, me) = self.tendon_pull(s, Which::EndingAt(s), Ra, va, ua)?;
        dn += fe;
        dm += me;
        if right.is_none() && s == self.robot.length() {
            // Follower tip wrench: fixed in the tip body frame, R(L) times it in the world.
            let (f_b, l_b) = self.follower_tip();
            dn -= *Ra * lift::<T>(&f_b);
            dm -= *Ra * lift::<T>(&l_b);
        }
        if let Some((site_b, Rb, vb, ub)) = right {
            let (nb, mb) = self.internal_wrench(site_b, Rb, vb, ub);
            dn -= nb;
            dm -= mb;
            if self.robot.corner_forces && self.robot.tendon_model == TendonModel::Coupled {
                let (fa, ma) = self.tendon_pull(s, Which::Past(s), Ra, va, ua)?;
                let (fb, mb) = self.tendon_pull(s, Which::Past(s), Rb, &site_b.strain(vb), ub)?;
                dn += fa - fb;
                dm += ma - mb;
            }
        }
        let Rt = Ra.transpose();
        Ok((
            (Rt * dn).component_div(&lift(&site_a.section.section.kse)),
            (Rt * dm).component_div(&lift(&site_a.section.section.kbt)),
        ))
    }

    /// The derivative of [`Model::wrench_balance`] in the six diagonal stiffnesses k_j of a
    /// section that is the same on both sides (kse = (GA, GA, EA), then kbt = (EIxx, EIyy,
    /// GJ)) at fixed states, into `out[j]` (force rows, then moment rows, strain units). With
    /// the rows W = (R_a^T dn) / kse, the internal force n = R D (v - v*) enters dn as
    /// n(s-) - n(s+), so dW/dkse_j = R_a^T (R_a e_j dv_a,j - R_b e_j dv_b,j) / kse
    /// - e_j W_j / kse_j (no right side at the tip), and the moment rows likewise in kbt.
    ///
    /// # Errors
    /// [`Error::SingularRouting`] where a tendon has no tangent.
    pub(crate) fn wrench_balance_stiffness(
        &self,
        s: f64,
        left: Side<f64>,
        right: Option<Side<f64>>,
        out: &mut [(Vector3<f64>, Vector3<f64>)],
    ) -> Result<()> {
        let (f, m) = self.wrench_balance(s, left, right)?;
        let (site, Ra, va, ua) = left;
        let section = &site.section.section;
        let (dv_a, du_a) = (va - site.reference.v_star, ua - site.reference.u_star);
        let right_strains =
            right.map(|(site_b, Rb, vb, ub)| (Rb, vb - site_b.reference.v_star, ub - site_b.reference.u_star));
        for j in 0..3 {
            let e = Vector3::ith(j, 1.0);
            let (mut dn, mut dm) = (Ra * e * dv_a[j], Ra * e * du_a[j]);
            if let Some((Rb, dv_b, du_b)) = &right_strains {
                dn -= *Rb * e * dv_b[j];
                dm -= *Rb * e * du_b[j];
            }
            out[j].0 += Ra.tr_mul(&dn).component_div(&section.kse) - e * (f[j] / section.kse[j]);
            out[3 + j].1 += Ra.tr_mul(&dm).component_div(&section.kbt) - e * (m[j] / section.kbt[j]);
        }
        Ok(())
    }

    /// The derivative of [`Model::wrench_balance`] in each tendon's tension tau_i at fixed
    /// states, added into `out[i]` (force rows, then moment rows; strain units, left body
    /// frame). The balance is linear in each tension: tendon i contributes
    /// tau_i f (t_i, (R r_i) x t_i) (f the tension factor, t_i = p_i' / |p_i'| in the world
    /// frame) where it ends, and, with corner forces, the difference of that term on the two
    /// sides where it continues, so its derivative is the same term per unit of tau_i. A
    /// slack tendon gets the right derivative (the term it would add under a pull).
    ///
    /// # Errors
    /// [`Error::SingularRouting`] where a tendon has no tangent.
    pub(crate) fn wrench_balance_tensions(
        &self,
        s: f64,
        left: Side<f64>,
        right: Option<Side<f64>>,
        out: &mut [(Vector3<f64>, Vector3<f64>)],
    ) -> Result<()> {
        let (site_a, Ra, va, ua) = left;
        let coupled = self.robot.tendon_model == TendonModel::Coupled;
        let scale = |dn: Vector3<f64>, dm: Vector3<f64>| {
            (
                Ra.tr_mul(&dn).component_div(&site_a.section.section.kse),
                Ra.tr_mul(&dm).component_div(&site_a.section.section.kbt),
            )
        };
        // One tendon's pull per unit of tension at (R, v, u): world force and moment.
        let unit_pull = |i: usize, rp: &RoutingPoint, R: &Matrix3<f64>, v: &Vector3<f64>, u: &Vector3<f64>| {
            let pb_s = u.cross(&rp.r) + rp.r_s + v;
            let speed = pb_s.norm();
            if speed < MIN_TENDON_SPEED {
                return Err(Error::SingularRouting { tendon: i, s, speed });
            }
            let t = pb_s * (self.tension_factor / speed);
            let force = if coupled { R * t } else { Vector3::zeros() };
            Ok((force, R * rp.r.cross(&t)))
        };
        // The tendons' tangents see the strain (v* on a Kirchhoff rod), as in the balance.
        let va = &site_a.strain(va);
        for (i, _, rp) in self.reaching(s, Which::EndingAt(s)) {
            let (f, m) = unit_pull(i, &rp, Ra, va, ua)?;
            let (f, m) = scale(f, m);
            out[i].0 += f;
            out[i].1 += m;
        }
        if let Some((site_b, Rb, vb, ub)) = right
            && self.robot.corner_forces
            && coupled
        {
            let vb = &site_b.strain(vb);
            for (i, _, rp) in self.reaching(s, Which::Past(s)) {
                let (fa, ma) = unit_pull(i, &rp, Ra, va, ua)?;
                let (fb, mb) = unit_pull(i, &rp, Rb, vb, ub)?;
                let (f, m) = scale(fa - fb, ma - mb);
                out[i].0 += f;
                out[i].1 += m;
            }
        }
        Ok(())
    }
}
