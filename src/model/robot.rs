//! The whole robot: backbone, tendons, loads and base pose, validated once.

use crate::Readable;
use crate::error::{Result, invalid};
use crate::model::length;
use crate::model::loads::{Field, Loads};
use crate::model::rod::{Geometry, ReferenceStrains, Rod, Stiffness};
use crate::model::routing::Routing;
use crate::model::tendon::Tendon;
use crate::{Error, so3};
use nalgebra::{Matrix3, Vector3};

/// A tendon-driven continuum robot: plain data in SI units. Call [`Robot::validate`] (the
/// solvers do) before use.
#[derive(Clone, Debug)]
pub struct Robot {
    /// The elastic backbone.
    pub rod: Rod,
    /// The tendons.
    pub tendons: Vec<Tendon>,
    /// External loads (world frame).
    pub loads: Loads,
    /// Base position p(0) (m), world frame.
    pub base_position: Vector3<f64>,
    /// Base orientation R(0), body to world.
    pub base_rotation: Matrix3<f64>,
    /// Include the point forces of tendons that bend at an interior termination of another
    /// tendon (docs/reference.md, corner forces). `true` is the physically consistent model;
    /// `false` reproduces the paper's jump conditions for comparison.
    pub corner_forces: bool,
    /// How the tendons load the backbone: the full coupled model (default) or, for
    /// comparison, the simpler point-moment model.
    pub tendon_model: TendonModel,
    /// How the backbone strains: the Cosserat rod of the paper (default, shear and
    /// extension by the constitutive law) or the inextensible, unshearable Kirchhoff rod.
    pub rod_model: RodModel,
}

/// How the backbone strains in shear and extension.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RodModel {
    /// The Cosserat rod of the paper: v = v* + K_se^-1 n_b (K_se = diag(GA, GA, EA)).
    #[default]
    Cosserat,
    /// The Kirchhoff rod: inextensible and unshearable, v = v* exactly, the internal force
    /// n a reaction of the constraint (docs/model.md, "Kirchhoff rods"). The section's GA
    /// and EA only scale the solvers' force unknown; they do not change the answer.
    Kirchhoff,
}

/// How tendons load the backbone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TendonModel {
    /// Rucker & Webster's coupled Cosserat rod/string model: distributed loads along the
    /// path, point loads where a path ends or bends.
    #[default]
    Coupled,
    /// The point-moment model (Jones et al., cited by the paper): each tendon acts only
    /// through the moment (R r_i) x F_i of its termination force F_i = -tau_i t_i; no
    /// distributed load, no force on the backbone, no corner forces.
    PointMoment,
}

/// Samples along each tendon used to look for a vanishing path tangent in validation (a
/// heuristic screen: the solvers still check every point they evaluate).
const ROUTING_SAMPLES: usize = 128;

impl Robot {
    /// A robot with the base at the origin, body z along world z, no tendons, no loads.
    pub fn new(rod: Rod) -> Self {
        Robot {
            rod,
            tendons: Vec::new(),
            loads: Loads::none(),
            base_position: Vector3::zeros(),
            base_rotation: Matrix3::identity(),
            corner_forces: true,
            tendon_model: TendonModel::Coupled,
            rod_model: RodModel::Cosserat,
        }
    }

    /// The same robot with one more tendon.
    pub fn with_tendon(mut self, tendon: Tendon) -> Self {
        self.tendons.push(tendon);
        self
    }

    /// The same robot with these loads.
    pub fn with_loads(mut self, loads: Loads) -> Self {
        self.loads = loads;
        self
    }

    /// The same robot with base pose (p0 in m, R0 body to world).
    pub fn with_base(mut self, position: Vector3<f64>, rotation: Matrix3<f64>) -> Self {
        self.base_position = position;
        self.base_rotation = rotation;
        self
    }

    /// Rod length L (m).
    pub fn length(&self) -> f64 {
        self.rod.length
    }

    /// Interior arc lengths in (0, L) where the solution may jump (tendon terminations,
    /// point loads and the ends of the rod's segments), sorted and without repeats.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b = Vec::new();
        self.breakpoints_into(&mut b);
        b
    }

    /// [`Robot::breakpoints`] written into `out` (its contents replaced), for a caller that
    /// keeps the buffer.
    pub(crate) fn breakpoints_into(&self, out: &mut Vec<f64>) {
        let l = self.length();
        out.clear();
        out.extend(
            self.tendons
                .iter()
                .map(|t| t.end(l))
                .chain(self.loads.point.iter().map(|p| p.s))
                .chain(self.rod.segment_end_points())
                .filter(|&s| s < l),
        );
        out.sort_by(f64::total_cmp);
        out.dedup();
    }

    /// Characteristic bending stiffness E I (N m^2) at the base, used for scaling.
    pub fn bending_stiffness(&self) -> f64 {
        let k = self.rod.section_at(0.0).section.kbt;
        k[0].max(k[1])
    }

    /// The tension scale T_i of tendon `i` (N): the tension that bends the rod through about
    /// a radian, E I / (L |r_i(0)|) at its offset at the base (E I / L^2 on the centreline,
    /// where a tension only compresses). The scale of tension unknowns in the solvers.
    pub fn tension_scale(&self, i: usize) -> f64 {
        let length = self.length();
        let offset = self.tendons[i].routing.at(0.0, length).r.norm();
        let bend = self.bending_stiffness() / length;
        if offset > 0.0 { bend / offset } else { bend / length }
    }

    /// Checks every field; returns the first problem with the path of the offending field.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for non-finite or out-of-range values, [`Error::SingularRouting`]
    /// for a tendon whose path tangent vanishes in the unloaded shape.
    pub fn validate(&self) -> Result<()> {
        let l = self.rod.length;
        if !(l.is_finite() && l > 0.0) {
            return Err(invalid(
                "rod.length",
                format!("is {}", Readable(l)),
                "give a positive, finite length in m",
            ));
        }
        if let Some(g) = &self.rod.geometry {
            validate_geometry(g)?;
        }
        self.rod.validate_segments()?;
        // A uniform section and constant reference strains give the same values at every
        // sample: the first (s = 0, the one the loop would report) checks them all.
        let uniform = matches!(self.rod.stiffness, Stiffness::Uniform(_))
            && matches!(
                self.rod.reference,
                ReferenceStrains::Straight | ReferenceStrains::Constant { .. }
            );
        for s in (0..=if uniform { 0 } else { 32 }).map(|k| l * k as f64 / 32.0) {
            let sp = self.rod.section_at(s);
            for (name, v) in [
                ("kse (GA, GA, EA)", sp.section.kse),
                ("kbt (EIxx, EIyy, GJ)", sp.section.kbt),
            ] {
                if v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                    return Err(invalid(
                        "rod.stiffness",
                        format!(
                            "{name} is ({}, {}, {}) at s = {} m",
                            Readable(v[0]),
                            Readable(v[1]),
                            Readable(v[2]),
                            Readable(s)
                        ),
                        "every stiffness must be positive and finite: check radius and moduli",
                    ));
                }
            }
            if !(sp.kse_s.iter().chain(sp.kbt_s.iter()).all(|x| x.is_finite())) {
                return Err(invalid(
                    "rod.stiffness",
                    format!("derivative is not finite at s = {} m", Readable(s)),
                    "fix the stiffness function",
                ));
            }
            let r = self.rod.reference_at(s);
            let all = [r.v_star, r.u_star, r.v_star_s, r.u_star_s];
            if all.iter().any(|v| v.iter().any(|x| !x.is_finite())) {
                return Err(invalid(
                    "rod.reference",
                    format!("is not finite at s = {} m", Readable(s)),
                    "fix v*, u* or their derivatives",
                ));
            }
            if r.v_star[2] <= 0.0 {
                return Err(invalid(
                    "rod.reference.v_star",
                    format!("has z = {} <= 0 at s = {} m", Readable(r.v_star[2]), Readable(s)),
                    "the reference axial strain v*_z must be positive (1 for an unstretched rod)",
                ));
            }
        }
        check_vec("base_position", &self.base_position)?;
        let r0 = &self.base_rotation;
        if r0.iter().any(|x| !x.is_finite()) || so3::orthonormality_error(r0) > 1e-6 {
            return Err(invalid(
                "base_rotation",
                format!(
                    "is not a rotation (|R^T R - I|, |det R - 1| = {:.2e})",
                    so3::orthonormality_error(r0)
                ),
                "give an orthonormal matrix with determinant +1 (rows are the body axes' world components transposed)",
            ));
        }
        self.validate_loads()?;
        for (i, t) in self.tendons.iter().enumerate() {
            self.validate_tendon(i, t)?;
            self.validate_actuation(i, t)?;
            crate::model::friction::validate(self, i, t)?;
        }
        Ok(())
    }

    /// Whether any tendon is displacement-controlled (its tension an unknown of the solve).
    pub fn has_displacement_inputs(&self) -> bool {
        self.tendons.iter().any(|t| t.displacement().is_some())
    }

    /// The robot with the tendon tensions `tensions` (N, one per tendon, as
    /// [`crate::Solution::tensions`] reports them), every tendon given one tension-controlled
    /// (as setting [`crate::Parameter::Tension`] does): a solved displacement-controlled robot
    /// becomes the tension-controlled robot with the same equilibrium, whose every tension
    /// the analyses (equilibrium, sensitivities) can read. Tendons past the end of
    /// `tensions` keep their actuation.
    ///
    /// # Examples
    /// ```
    /// let mut robot = tdcr::cases::case_s();
    /// robot.tendons[0].set_displacement(0.002);
    /// let held = robot.with_tensions(&[1.5, 0.0, 0.0, 0.0, 0.0]);
    /// assert_eq!((held.tendons[0].tension(), held.tendons[0].displacement()), (1.5, None));
    /// ```
    pub fn with_tensions(&self, tensions: &[f64]) -> Robot {
        let mut robot = self.clone();
        for (t, &tau) in robot.tendons.iter_mut().zip(tensions) {
            t.set_tension(tau);
        }
        robot
    }

    /// Checks a tendon's elasticity and displacement input (docs/actuation.md).
    fn validate_actuation(&self, i: usize, t: &Tendon) -> Result<()> {
        if let Some(k) = t.stiffness
            && !(k.is_finite() && k > 0.0)
        {
            return Err(invalid(
                format!("tendons[{i}].stiffness"),
                format!("is {} N", Readable(k)),
                "give the tendon's axial stiffness E_t A_t as a positive finite force in N, or none for an inextensible tendon",
            ));
        }
        if !(t.free_length.is_finite() && t.free_length >= 0.0) {
            return Err(invalid(
                format!("tendons[{i}].free_length"),
                format!("is {} m", Readable(t.free_length)),
                "give the length between the base and the actuator as a finite length >= 0 m",
            ));
        }
        let Some(q) = t.displacement() else {
            return Ok(());
        };
        if !q.is_finite() {
            return Err(invalid(
                format!("tendons[{i}].displacement"),
                format!("is {} m", Readable(q)),
                "give a finite pull-in in m",
            ));
        }
        // An inextensible tendon shortens its path by q: the path would have to be shorter
        // than nothing to take up its whole reference length.
        let reference = length::reference_length(self, i);
        if t.stiffness.is_none() && q >= reference {
            return Err(invalid(
                format!("tendons[{i}].displacement"),
                format!(
                    "is {} m, but the tendon's path is {} m long in the unloaded shape, and an inextensible \
                     tendon cannot be pulled in by its whole path or more (no shape takes it up)",
                    Readable(q),
                    // Computed, not given: 6 significant digits, not 0.24199999999999972.
                    Readable(significant(reference, 6))
                ),
                "give a pull-in smaller than the tendon's path length (in m: 0.003 for 3 mm)",
            ));
        }
        Ok(())
    }

    fn validate_loads(&self) -> Result<()> {
        let l = self.rod.length;
        check_vec("loads.tip_force", &self.loads.tip_force)?;
        check_vec("loads.tip_moment", &self.loads.tip_moment)?;
        check_vec("loads.follower_tip_force", &self.loads.follower_tip_force)?;
        check_vec("loads.follower_tip_moment", &self.loads.follower_tip_moment)?;
        // Constant fields give the same values at every sample: the first checks them all.
        let loads = &self.loads;
        let fields = [
            &loads.distributed_force,
            &loads.distributed_moment,
            &loads.follower_distributed_force,
        ];
        let constant = fields.iter().all(|f| matches!(f, Field::Constant(_)));
        for k in 0..=if constant { 0 } else { 32 } {
            let s = l * k as f64 / 32.0;
            check_vec("loads.distributed_force", &self.loads.distributed_force.at(s))?;
            check_vec("loads.distributed_moment", &self.loads.distributed_moment.at(s))?;
            check_vec(
                "loads.follower_distributed_force",
                &self.loads.follower_distributed_force.at(s),
            )?;
        }
        for (i, p) in self.loads.point.iter().enumerate() {
            if !(p.s.is_finite() && p.s > 0.0 && p.s <= l) {
                return Err(invalid(
                    format!("loads.point[{i}].s"),
                    format!("is {} m, outside (0, {}]", Readable(p.s), Readable(l)),
                    "place point loads on the rod, after the base",
                ));
            }
            check_vec(&format!("loads.point[{i}].force"), &p.force)?;
            check_vec(&format!("loads.point[{i}].moment"), &p.moment)?;
        }
        Ok(())
    }

    fn validate_tendon(&self, i: usize, t: &Tendon) -> Result<()> {
        let l = self.rod.length;
        if !(t.tension().is_finite() && t.tension() >= 0.0) {
            return Err(invalid(
                format!("tendons[{i}].tension"),
                format!("is {} N", Readable(t.tension())),
                "a tendon can only pull: give a finite tension >= 0",
            ));
        }
        let end = t.end(l);
        if !(end.is_finite() && end > 0.0 && end <= l) {
            return Err(invalid(
                format!("tendons[{i}].termination"),
                format!("is s = {} m, outside (0, {}]", Readable(end), Readable(l)),
                "set the termination to at most the rod length and above 0",
            ));
        }
        let parameters: &[f64] = match &t.routing {
            Routing::Straight { x, y } => &[*x, *y],
            Routing::Helical { radius, turns, phase } => &[*radius, *turns, *phase],
            Routing::Custom(_) => &[],
        };
        if parameters.iter().any(|x| !x.is_finite()) {
            return Err(invalid(
                format!("tendons[{i}].routing"),
                format!("is not finite ({:?})", t.routing),
                "give finite offsets (m), turns and phase (rad)",
            ));
        }
        // A built-in routing on a straight reference rod cannot lose its tangent: r' lies in
        // the cross-section, so |p_i'| = |e3 + r'| >= 1.
        if !matches!(t.routing, Routing::Custom(_)) && matches!(self.rod.reference, ReferenceStrains::Straight) {
            return Ok(());
        }
        // Look for a vanishing path tangent in the unloaded shape: |u* x r + r' + v*|.
        let n = ROUTING_SAMPLES;
        for k in 0..=n {
            let s = end * k as f64 / n as f64;
            let rp = t.routing.at(s, l);
            if [rp.r, rp.r_s, rp.r_ss].iter().any(|v| v.iter().any(|x| !x.is_finite())) {
                return Err(invalid(
                    format!("tendons[{i}].routing"),
                    format!("is not finite at s = {} m", Readable(s)),
                    "fix the routing function",
                ));
            }
            if rp.r[2] != 0.0 || rp.r_s[2] != 0.0 || rp.r_ss[2] != 0.0 {
                return Err(invalid(
                    format!("tendons[{i}].routing"),
                    format!("has a z component at s = {} m", Readable(s)),
                    "r(s) lies in the cross-section: z must be 0",
                ));
            }
            let rf = self.rod.reference_at(s);
            let speed = (rf.u_star.cross(&rp.r) + rp.r_s + rf.v_star).norm();
            // 1e-3: below this the tendon force per length exceeds a thousand times tau * curvature
            if speed < 1e-3 {
                return Err(Error::SingularRouting { tendon: i, s, speed });
            }
        }
        Ok(())
    }
}

fn validate_geometry(g: &Geometry) -> Result<()> {
    let positive = |field: &str, x: f64, unit: &str| {
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(invalid(
                field,
                format!("is {} {unit}", Readable(x)),
                format!("give a positive, finite value in {unit}"),
            ))
        }
    };
    positive("rod.outer_radius", g.outer_radius, "m")?;
    positive("rod.youngs_modulus", g.youngs_modulus, "Pa")?;
    if !(g.inner_radius.is_finite() && g.inner_radius >= 0.0 && g.inner_radius < g.outer_radius) {
        return Err(invalid(
            "rod.inner_radius",
            format!(
                "is {} m with outer radius {} m",
                Readable(g.inner_radius),
                Readable(g.outer_radius)
            ),
            "the inner radius must be >= 0 and below the outer radius",
        ));
    }
    let nu = g.poisson_ratio;
    if !(nu.is_finite() && nu > -1.0 && nu <= 0.5) {
        return Err(invalid(
            "rod.poisson_ratio",
            format!("is {}", Readable(nu)),
            "Poisson's ratio must lie in (-1, 0.5]",
        ));
    }
    Ok(())
}

fn check_vec(field: &str, v: &Vector3<f64>) -> Result<()> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("is ({}, {}, {})", Readable(v[0]), Readable(v[1]), Readable(v[2])),
            "every component must be a finite number",
        ))
    }
}

/// `x` rounded to `digits` significant digits, for computed values in messages.
fn significant(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    let rounded = (x * scale).round() / scale;
    if rounded.is_finite() { rounded } else { x }
}
