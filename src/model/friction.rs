//! Friction between tendons and their channels in full slip (the capstan law along the
//! tendon, docs/friction.md): eq. 13 with the tangential part of the tendon's load on the
//! backbone, and the rate of the tension along the tendon.
//!
//! With friction the tension tau_i(s) varies along the tendon. The channels' force on the
//! backbone per unit s is then `-f_i = (tau_i t_i)' = tau_i t_i' + tau_i' t_i` (world
//! frame): the normal part `q_i = tau_i t_i'`, which eq. 13 already has (its body-frame form
//! is `A_i p_i^b''`), and the new tangential part `tau_i' t_i`. Coulomb's law in full slip
//! makes the tangential part mu_i times the normal part's magnitude, signed by the motion:
//!
//! ```text
//! tau_i' = w_i mu_i |q_i| = w_i mu_i tau_i kappa_i,   kappa_i = |t_i'|,   w_i = -1 (pull), +1 (release)
//! ```
//!
//! kappa_i is the turning rate of the tendon's path per unit s: the backbone's bending and
//! the routing's own turning (a helix) together. It depends on the rates (v', u') through
//! p_i^b'', and the rates depend on tau_i' through the tangential load, so eq. 13 is no
//! longer explicit. Here the rates with friction are
//!
//! ```text
//! x = x0 - sum_j g_j y_j,   y_j = M^-1 (t_j, r_j x t_j),   g_j = w_j mu_j |q_j(x)|
//! ```
//!
//! (x0 the rates without the tangential loads, M the matrix of eq. 13, t_j the body-frame
//! unit tangent), solved for the tangential loads g_j (N/m) by Newton on these k scalars.
//! The tangential loads change the normal forces only through the small moment r_j x t_j,
//! so the iteration contracts by about mu tau r^2 / (E I) per step (1e-3 for the prototype).
#![allow(non_snake_case)]

use crate::error::{Result, invalid};
use crate::model::equations::{Model, Site};
use crate::model::linearize;
use crate::model::robot::{Robot, TendonModel};
use crate::model::tendon::Tendon;
use crate::{Error, Readable};
use nalgebra::{Matrix3, Vector3, Vector6};

/// Newton iterations of the tangential loads at one point: each step contracts by the
/// square of the last (the iteration is smooth away from kappa = 0), and 1e-3 per step is
/// the linear rate from the module docs, so 30 covers any convergent case many times over.
const MAX_ITERATIONS: usize = 30;

/// Checks the friction of tendon `i`: a finite coefficient >= 0, and for a coefficient > 0
/// what the full-slip model needs: a tension input (the tension at the base entry), the
/// coupled tendon model, and no breakpoint (point load or another tendon's termination)
/// inside the tendon's span, where its path would have a corner.
///
/// # Errors
/// [`Error::InvalidInput`] naming `tendons[i].friction`.
pub(crate) fn validate(robot: &Robot, i: usize, t: &Tendon) -> Result<()> {
    let Some(friction) = t.friction else {
        return Ok(());
    };
    let field = format!("tendons[{i}].friction");
    let mu = friction.coefficient;
    if !(mu.is_finite() && mu >= 0.0) {
        return Err(invalid(
            field,
            format!("is {}", Readable(mu)),
            "give the friction coefficient as a finite number >= 0 (0.1 for steel in steel, 0 for none)",
        ));
    }
    if mu == 0.0 {
        return Ok(());
    }
    if t.displacement().is_some() {
        return Err(invalid(
            field,
            format!("is {} on a displacement-controlled tendon", Readable(mu)),
            "friction needs tension control for now: give the tendon a tension (the tension at its base \
             entry) instead of a pull-in, or set its friction to 0",
        ));
    }
    if robot.tendon_model != TendonModel::Coupled {
        return Err(invalid(
            field,
            format!("is {} with the point-moment tendon model", Readable(mu)),
            "friction needs the coupled tendon model (distributed tendon loads): use it, or set the friction to 0",
        ));
    }
    let end = t.end(robot.length());
    if let Some(s) = robot.breakpoints().into_iter().find(|&s| s > 0.0 && s < end) {
        return Err(invalid(
            field,
            format!(
                "is {} on a tendon that passes a point load or another tendon's termination at s = {} m",
                Readable(mu),
                Readable(s)
            ),
            "friction is supported on tendons whose span holds no breakpoint for now: move the point load or \
             termination past the tendon's end, or set its friction to 0",
        ));
    }
    Ok(())
}

/// Whether any tendon of `robot` has friction (a coefficient > 0).
pub fn any(robot: &Robot) -> bool {
    robot.tendons.iter().any(|t| t.active_friction().is_some())
}

/// One tendon with friction at one point (body frame).
struct Slip {
    /// Index of the tendon.
    tendon: usize,
    /// w_i mu_i: the signed friction coefficient.
    signed_mu: f64,
    /// r_i (m).
    r: Vector3<f64>,
    /// c_i = u x (p_i^b' + r_i') + r_i'', the state part of p_i^b'' (1/m).
    c: Vector3<f64>,
    /// t_i, the unit tangent.
    t: Vector3<f64>,
    /// 1 / |p_i^b'|.
    inv_speed: f64,
    /// The tension tau_i here, times the model's tension factor (N).
    tension: f64,
    /// y_i = M^-1 (t_i, r_i x t_i): the rates' change per unit tangential load (m/N).
    response: Vector6<f64>,
}

impl Slip {
    /// The normal load q_i = tau_i |p_i^b'|^-1 (I - t t^T) p_i^b'' at the rates x (N/m).
    fn normal(&self, x: &Vector6<f64>) -> Vector3<f64> {
        let x_v = Vector3::new(x[0], x[1], x[2]);
        let x_u = Vector3::new(x[3], x[4], x[5]);
        let z = x_v - self.r.cross(&x_u) + self.c;
        (z - self.t * self.t.dot(&z)) * (self.tension * self.inv_speed)
    }

    /// dq_i/dx along the rate change `dx`.
    fn normal_change(&self, dx: &Vector6<f64>) -> Vector3<f64> {
        let d_v = Vector3::new(dx[0], dx[1], dx[2]);
        let d_u = Vector3::new(dx[3], dx[4], dx[5]);
        let dz = d_v - self.r.cross(&d_u);
        (dz - self.t * self.t.dot(&dz)) * (self.tension * self.inv_speed)
    }
}

/// Eq. 13 with friction at a site: the rates (v', u') for the state (R, v, u), with every
/// tendon at the tension the model holds for it here ([`Model::tensions`]: for a tendon
/// with friction its tension at this s), and in `turning` (one entry per tendon) the
/// relative rate of each tension, tau_i' / tau_i = w_i mu_i kappa_i (1/m; 0 for tendons
/// without friction, at zero tension or not loading this segment).
///
/// # Errors
/// As [`linearize::rates`], and [`Error::Breakdown`] when the tangential loads do not
/// converge.
pub(crate) fn rates(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    turning: &mut [f64],
) -> Result<Vector6<f64>> {
    turning.fill(0.0);
    let tendons = &model.robot.tendons;
    let mut slips: Vec<Slip> = model
        .distributed_tendons(site.s, segment_end)
        .filter_map(|(i, tension, rp)| {
            let friction = tendons[i].active_friction()?;
            let pb_s = u.cross(&rp.r) + rp.r_s + v;
            let inv_speed = 1.0 / pb_s.norm();
            let t = pb_s * inv_speed;
            Some(Slip {
                tendon: i,
                signed_mu: friction.motion.sign() * friction.coefficient,
                r: rp.r,
                c: u.cross(&(pb_s + rp.r_s)) + rp.r_ss,
                t,
                inv_speed,
                tension,
                response: Vector6::new(t[0], t[1], t[2], 0.0, 0.0, 0.0),
            })
        })
        .collect();
    let mut loads: Vec<Vector6<f64>> = slips
        .iter()
        .map(|sl| {
            let m = sl.r.cross(&sl.t);
            Vector6::new(sl.t[0], sl.t[1], sl.t[2], m[0], m[1], m[2])
        })
        .collect();
    let x0 = linearize::rates_and_responses(model, site, segment_end, (R, v, u), &mut loads)?;
    if slips.is_empty() {
        return Ok(x0);
    }
    for (sl, y) in slips.iter_mut().zip(&loads) {
        sl.response = *y;
    }
    let k = slips.len();
    let mut g = vec![0.0; k];
    let mut matrix = vec![0.0; k * k];
    let mut step = vec![0.0; k];
    let mut x = x0;
    for iteration in 0.. {
        // h_j(g) = g_j - w_j mu_j |q_j(x(g))| and its Jacobian
        // dh_j/dg_l = delta_jl + w_j mu_j (q_j / |q_j|) . dq_j/dx y_l.
        let mut size = 0.0_f64;
        for (j, sl) in slips.iter().enumerate() {
            let q = sl.normal(&x);
            let magnitude = q.norm();
            step[j] = -(g[j] - sl.signed_mu * magnitude);
            let direction = if magnitude > 0.0 {
                q / magnitude
            } else {
                Vector3::zeros()
            };
            for (l, other) in slips.iter().enumerate() {
                let dq = sl.normal_change(&other.response);
                matrix[j * k + l] = f64::from(u8::from(j == l)) + sl.signed_mu * direction.dot(&dq);
            }
            size = size.max(magnitude);
        }
        if !crate::dense::solve_dense(&mut matrix, &mut step, k) {
            return Err(Error::Breakdown {
                s: site.s,
                what: "the friction loads' Newton matrix is singular".into(),
            });
        }
        let mut change = 0.0_f64;
        for (gj, dj) in g.iter_mut().zip(&step) {
            *gj += dj;
            change = change.max(dj.abs());
        }
        x = x0;
        for (sl, gj) in slips.iter().zip(&g) {
            x -= sl.response * *gj;
        }
        // Converged to rounding: the change is below 1e-15 of the normal load's size.
        if change <= 1e-15 * size || size == 0.0 {
            break;
        }
        if iteration >= MAX_ITERATIONS || !change.is_finite() {
            return Err(Error::Breakdown {
                s: site.s,
                what: "the tangential friction loads did not converge".into(),
            });
        }
    }
    for (sl, gj) in slips.iter().zip(&g) {
        turning[sl.tendon] = if sl.tension > 0.0 { gj / sl.tension } else { 0.0 };
    }
    Ok(x)
}
