//! Plausibility of the robot's scales: the figures of [`crate::model::scales`], checked
//! against a robot that passed [`Robot::validate`], and the tendons' geometric limits.

use crate::model::robot::Robot;
use crate::model::scales::{
    FORCE_LIMIT, FRICTION_LIMIT, FRICTION_TURNING_LIMIT, LENGTH_RANGE, LoadSite, MODULUS_RANGE, MOMENT_LIMIT,
    OFFSET_LIMIT, PATH_LIMIT, SELF_WEIGHT_LIMIT, SLENDERNESS_RANGE, TENDON_LIMIT, Warning,
};
use nalgebra::Vector3;

/// Pieces of a custom routing's path integrals on the straight rod ([`Robot::path_figures`]):
/// 1024 trapezoids, far finer than any routing a channel follows.
const PATH_PIECES: usize = 1024;

/// Arc lengths where the stiffness and distributed loads are sampled: 33 evenly spaced.
fn samples(length: f64) -> impl Iterator<Item = f64> {
    (0..=32).map(move |k| length * f64::from(k) / 32.0)
}

impl Robot {
    /// The smallest bending stiffness min(E Ixx, E Iyy) (N m^2) over 33 evenly spaced
    /// arc lengths in [0, `end`] (m).
    fn weakest_bending(&self, end: f64) -> f64 {
        samples(end)
            .map(|s| {
                let k = self.rod.section_at(s).section.kbt;
                k[0].min(k[1])
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The geometric limit of tendon `i` (N): EI / r^2 with r its largest offset and EI the
    /// smallest bending stiffness along it, the tension at which the bend radius
    /// EI / (tau r) falls to the offset; past it no equilibrium exists (module docs).
    /// Infinite for a tendon on the centreline.
    pub fn geometric_limit(&self, i: usize) -> f64 {
        let length = self.length();
        let t = &self.tendons[i];
        let end = t.end(length);
        let offset = t.routing.max_offset(end, length);
        self.weakest_bending(end) / (offset * offset)
    }

    /// Tendon `i`'s path on the straight rod (no precurvature counted): its length (m) and
    /// its total turning theta = integral of |t'| ds (rad) over the rod it spans, with
    /// p' = e3 + r', p'' = r'' and |t'| = |p' x p''| / |p'|^2 per unit s. Exact for straight
    /// and helical routings (constant integrands), trapezoids for a custom one.
    fn path_figures(&self, i: usize) -> (f64, f64) {
        let length = self.length();
        let t = &self.tendons[i];
        let end = t.end(length);
        let rates = |s: f64| {
            let r = t.routing.at(s, length);
            let speed = Vector3::z() + r.r_s;
            let turning = speed.cross(&r.r_ss).norm() / speed.norm_squared();
            (speed.norm(), turning)
        };
        let pieces = match t.routing {
            crate::model::routing::Routing::Custom(_) => PATH_PIECES,
            _ => 1,
        };
        let h = end / pieces as f64;
        (0..=pieces).fold((0.0, 0.0), |(path, turning), k| {
            let weight = if k == 0 || k == pieces { 0.5 * h } else { h };
            let (v, w) = rates(h * k as f64);
            (path + weight * v, turning + weight * w)
        })
    }

    /// The displacement-controlled tendons whose solved tensions are at or past their
    /// geometric limit EI / r^2, one [`Warning::SolvedTension`] each. `tensions` are the
    /// solution's, one per tendon ([`crate::Solution::tensions`]); tension-controlled
    /// tendons are left to [`Robot::plausibility`], which checks their inputs.
    ///
    /// A displacement solve can converge to such tensions: actuators that hold antagonistic
    /// tendons which the pull stretches make the tendons fight, compressing the rod.
    ///
    /// # Examples
    /// ```
    /// use tdcr::model::scales::Warning;
    /// let mut robot = tdcr::cases::case_s();
    /// robot.tendons[0].set_displacement(0.03);
    /// // Tension 3270 N on the displacement-controlled tendon, 2 N on a tension-controlled one.
    /// let warnings = robot.solved_tensions(&[3270.0, 2.0, 0.0, 0.0, 0.0]);
    /// assert!(matches!(warnings[..], [Warning::SolvedTension { tendon: 0, .. }]));
    /// assert!(warnings[0].to_string().contains("solved tension 3270 N"));
    /// ```
    pub fn solved_tensions(&self, tensions: &[f64]) -> Vec<Warning> {
        let length = self.length();
        self.tendons
            .iter()
            .zip(tensions)
            .enumerate()
            .filter_map(|(i, (t, &tension))| {
                let displacement = t.displacement()?;
                let end = t.end(length);
                let w = Warning::SolvedTension {
                    tendon: i,
                    tension,
                    displacement,
                    offset: t.routing.max_offset(end, length),
                    bending_stiffness: self.weakest_bending(end),
                };
                (w.figure() >= TENDON_LIMIT).then_some(w)
            })
            .collect()
    }

    /// The robot's figures outside their plausible ranges (module [`crate::model::scales`], whose docs give every figure's range and source):
    /// length, slenderness, modulus, self weight, each tendon's tension against its
    /// geometric limit: the bend the tendons cause, and the tip and point loads against EI. Empty for a robot
    /// of ordinary scales such as the paper's prototype. Not a validation: call it on a
    /// robot that passed [`Robot::validate`] (non-finite values give no warnings).
    ///
    /// # Examples
    /// ```
    /// use tdcr::model::scales::Warning;
    /// let mut robot = tdcr::cases::case_s();
    /// assert!(robot.plausibility().is_empty());
    /// robot.tendons[0].set_tension(2940.0); // 2.94 N typed in mN
    /// let warnings = robot.plausibility();
    /// assert!(matches!(warnings[0], Warning::TendonBend { tendon: 0, .. }));
    /// assert!(warnings[0].to_string().contains("alone reaches the limit at EI/r^2 = 66 N"));
    /// ```
    pub fn plausibility(&self) -> Vec<Warning> {
        let mut out = Vec::new();
        let length = self.length();
        let ei = self.weakest_bending(length);
        if !(length.is_finite() && length > 0.0 && ei.is_finite() && ei > 0.0) {
            return out;
        }
        if !(LENGTH_RANGE.0..=LENGTH_RANGE.1).contains(&length) {
            out.push(Warning::Length { length });
        }
        let radius = match &self.rod.geometry {
            Some(g) => g.outer_radius,
            None => {
                // A solid circle has EI / EA = r^2 / 4.
                let k = self.rod.section_at(0.0).section;
                2.0 * (k.kbt[0].min(k.kbt[1]) / k.kse[2]).sqrt()
            }
        };
        if radius > 0.0 && !(SLENDERNESS_RANGE.0..=SLENDERNESS_RANGE.1).contains(&(length / radius)) {
            out.push(Warning::Slenderness { length, radius });
        }
        if let Some(g) = &self.rod.geometry
            && !(MODULUS_RANGE.0..=MODULUS_RANGE.1).contains(&g.youngs_modulus)
        {
            out.push(Warning::Modulus {
                youngs_modulus: g.youngs_modulus,
            });
        }
        let w = samples(length)
            .map(|s| self.loads.distributed_force.at(s).norm())
            .fold(0.0, f64::max);
        let self_weight = Warning::SelfWeight {
            weight_per_length: w,
            length,
            bending_stiffness: ei,
        };
        if self_weight.figure() > SELF_WEIGHT_LIMIT {
            out.push(self_weight);
        }
        out.extend(crate::model::scales::tendon_bend(self));
        let points = self.loads.point.iter().enumerate();
        let sites = std::iter::once((LoadSite::Tip, length, self.loads.tip_force, self.loads.tip_moment))
            .chain(points.map(|(i, p)| (LoadSite::Point(i), p.s, p.force, p.moment)));
        for (site, arm, force, moment) in sites {
            let bending_stiffness = self.weakest_bending(arm);
            let force = Warning::Force {
                site,
                force: force.norm(),
                arm,
                bending_stiffness,
            };
            if force.figure() > FORCE_LIMIT {
                out.push(force);
            }
            let moment = Warning::Moment {
                site,
                moment: moment.norm(),
                arm,
                bending_stiffness,
            };
            if moment.figure() > MOMENT_LIMIT {
                out.push(moment);
            }
        }
        for (i, t) in self.tendons.iter().enumerate() {
            let span = t.end(length);
            if span.is_nan() || span <= 0.0 {
                continue;
            }
            let (path, turning) = self.path_figures(i);
            let turns = t.routing.turns_between(0.0, span, length);
            let w = Warning::PathLength {
                tendon: i,
                path,
                span,
                turns,
            };
            if w.figure() > PATH_LIMIT {
                out.push(w);
            }
            let w = Warning::Offset {
                tendon: i,
                offset: t.routing.max_offset(span, length),
                length,
            };
            if w.figure() > OFFSET_LIMIT {
                out.push(w);
            }
            let Some(f) = t.active_friction() else { continue };
            let w = Warning::Friction {
                tendon: i,
                coefficient: f.coefficient,
            };
            if w.figure() > FRICTION_LIMIT {
                out.push(w);
            }
            let w = Warning::FrictionTurning {
                tendon: i,
                coefficient: f.coefficient,
                turning,
            };
            if w.figure() > FRICTION_TURNING_LIMIT {
                out.push(w);
            }
        }
        out
    }
}
