//! The tangential friction loads at one point (docs/friction.md, section 2): eq. 13 with
//! the tangential part of the loads of the tendons with friction, solved for those loads
//! (one tendon: in closed form; several: by Newton on their k scalars), for
//! [`super::friction`].
#![allow(non_snake_case)]

use crate::Error;
use crate::error::Result;
use crate::model::equations::{Model, Site};
use crate::model::linearize::{Point, TendonPoint};
use nalgebra::{Vector3, Vector6};

/// Newton iterations of the tangential loads at one point: each step contracts by the
/// square of the last (the iteration is smooth away from kappa = 0), and 1e-3 per step is
/// the linear rate from the module docs, so 30 covers any convergent case many times over.
const MAX_ITERATIONS: usize = 30;

/// One tendon with friction loading the backbone at one point (body frame).
#[derive(Clone, Debug)]
pub(super) struct Slip {
    /// Its place in [`slipping`]'s list.
    pub(super) slot: usize,
    /// w_i mu_i: the signed friction coefficient; for a `given` slip, its given relative
    /// rate tau_i' / tau_i (1/m).
    pub(super) signed_mu: f64,
    /// Whether its tangential load is given as a relative rate of its tension (a stuck link
    /// of a history step, docs/friction.md section 8, "Order 4 on stuck links"):
    /// g_i = signed_mu tau_i, explicit (no dependence on the rates), else w_i mu_i |q_i|.
    pub(super) given: bool,
    /// The tendon's point quantities (r_i, t_i, k_i = tau_i / |p_i^b'|, ...).
    pub(super) tp: TendonPoint,
    /// e_i = (t_i, r_i x t_i): the direction of its tangential load in eq. 13's rows.
    pub(super) e: Vector6<f64>,
    /// y_i = M^-1 e_i: the rates' change per unit tangential load (m/N).
    pub(super) y: Vector6<f64>,
    /// The tangential load g_i = tau_i' (N/m) at the solution.
    pub(super) g: f64,
    /// q_i, the normal load (N/m), and its direction q_i / |q_i| (0 where q_i = 0).
    pub(super) q: Vector3<f64>,
    pub(super) q_hat: Vector3<f64>,
}

impl Slip {
    /// Sets the normal load q_i and its direction at the rates x; returns |q_i| (N/m).
    pub(super) fn refresh(&mut self, x: &Vector6<f64>) -> f64 {
        self.q = self.normal(x);
        let magnitude = self.q.norm();
        self.q_hat = if magnitude > 0.0 {
            self.q / magnitude
        } else {
            Vector3::zeros()
        };
        magnitude
    }

    /// The normal load q_i = k_i (I - t t^T) p_i^b'' at the rates x (N/m).
    fn normal(&self, x: &Vector6<f64>) -> Vector3<f64> {
        self.normal_change(x) + self.project(&self.tp.c)
    }

    /// The part of q_i the rates x drive: k_i (I - t t^T) (x_v - r_i x x_u), without x_v on
    /// a Kirchhoff rod (its v' = v*' is in c_i, docs/model.md section 4b).
    pub(super) fn normal_change(&self, x: &Vector6<f64>) -> Vector3<f64> {
        let x_v = if self.tp.inextensible {
            Vector3::zeros()
        } else {
            Vector3::new(x[0], x[1], x[2])
        };
        let x_u = Vector3::new(x[3], x[4], x[5]);
        self.project(&(x_v - self.tp.r.cross(&x_u)))
    }

    /// k_i (I - t t^T) a.
    fn project(&self, a: &Vector3<f64>) -> Vector3<f64> {
        let t = &self.tp.t;
        (a - t * t.dot(a)) * self.tp.k
    }

    /// The tension tau_i = k_i |p_i^b'| (N).
    pub(super) fn tension(&self) -> f64 {
        self.tp.k / self.tp.inv_speed
    }

    /// The tangential load the slip's law sets at its current normal load: w_i mu_i |q_i|,
    /// or for a `given` slip its rate times its tension.
    fn target(&self) -> f64 {
        if self.given {
            self.signed_mu * self.tension()
        } else {
            self.signed_mu * self.q.norm()
        }
    }

    /// dg_i/dx = w_i mu_i k_i (q^, r_i x q^): the gradient of the tangential load in the
    /// rates (q^ is normal to t_i, so the projection drops out); (0, r_i x q^) on a
    /// Kirchhoff rod, whose q_i does not depend on x_v; 0 for a `given` slip.
    pub(super) fn gradient(&self) -> Vector6<f64> {
        if self.given {
            return Vector6::zeros();
        }
        let m = self.tp.r.cross(&self.q_hat);
        let h = if self.tp.inextensible {
            Vector3::zeros()
        } else {
            self.q_hat
        };
        Vector6::new(h[0], h[1], h[2], m[0], m[1], m[2]) * (self.signed_mu * self.tp.k)
    }
}

/// Eq. 13 with friction solved at one point, with the frictionless eq. 13 there
/// assembled in `point`: the tendons with friction that load the backbone here, with their
/// tangential loads, and the rates (v', u') with the tangential loads. Every tendon is at the
/// tension the model holds for it here ([`Model::tensions`]; for a tendon with friction, its
/// tension at this s), with the friction multiplier w_j of each tendon of `slipping` from
/// `multipliers` when given (a stick/slip history, docs/friction.md section 8), else its
/// motion's sign. Where `multipliers` holds twice as many entries as `slipping`, its
/// second half flags (nonzero) the slips whose tangential load is given as the relative
/// rate in the first half, `tau_j' / tau_j = multipliers[j] mu_j` (a stuck link's
/// pointwise load, [`Slip::given`]). The large [`Point`] stays with the caller, so that it
/// is not copied; the slips go into `slips` (cleared first, its capacity kept).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn solve(
    model: &Model,
    point: &Point,
    site: &Site,
    segment_end: f64,
    (v, u): (&Vector3<f64>, &Vector3<f64>),
    slipping: &[usize],
    multipliers: Option<&[f64]>,
    slips: &mut Vec<Slip>,
) -> Result<Vector6<f64>> {
    let x0 = point.rates();
    let tendons = &model.robot.tendons;
    slips.clear();
    for (c, (i, tension, rp)) in model.distributed_tendons(site.s, segment_end).enumerate() {
        let (Some(friction), Some(slot)) = (tendons[i].active_friction(), slipping.iter().position(|&j| j == i)) else {
            continue;
        };
        // The tendon as assembling M evaluated it (the same inputs), else evaluated here.
        let tp = match point.tendon(c) {
            Some(tp) => *tp,
            None => TendonPoint::new(i, tension, &rp, site, v, u)?,
        };
        let m = tp.r.cross(&tp.t);
        let e = Vector6::new(tp.t[0], tp.t[1], tp.t[2], m[0], m[1], m[2]);
        let mut row = e.transpose();
        if !point.solve_rows(&mut row) {
            return Err(breakdown(site.s));
        }
        let given = multipliers.is_some_and(|w| w.len() > slipping.len() && w[slipping.len() + slot] != 0.0);
        slips.push(Slip {
            slot,
            signed_mu: multipliers.map_or(friction.motion.sign(), |w| w[slot]) * friction.coefficient,
            given,
            tp,
            e,
            y: row.transpose(),
            g: 0.0,
            q: Vector3::zeros(),
            q_hat: Vector3::zeros(),
        });
    }
    // One tendon with friction here (the usual case) in closed form, else (or where the
    // closed form does not apply) Newton on the tangential loads.
    if let [slip] = slips.as_mut_slice()
        && let Some(x) = single(slip, &x0)
    {
        return Ok(x);
    }
    newton(slips, x0, site.s)
}

/// The tangential loads g_j of `slips` (each from g_j = 0) by Newton on
/// h_j(g) = g_j - w_j mu_j |q_j(x(g))|, x(g) = x0 - sum_l g_l y_l, and the rates x(g) with
/// them (`s`: the arc length, for an error).
fn newton(slips: &mut [Slip], x0: Vector6<f64>, s: f64) -> Result<Vector6<f64>> {
    let k = slips.len();
    let mut x = x0;
    // The k x k Newton matrix and the step, on the stack for up to 4 tendons here.
    let mut stack = [0.0; 20];
    let mut heap = Vec::new();
    let buffer: &mut [f64] = if k * (k + 1) <= stack.len() {
        &mut stack[..k * (k + 1)]
    } else {
        heap.resize(k * (k + 1), 0.0);
        &mut heap
    };
    let (matrix, step) = buffer.split_at_mut(k * k);
    for iteration in 0..=MAX_ITERATIONS {
        // h_j(g) = g_j - w_j mu_j |q_j(x(g))|, x(g) = x0 - sum_l g_l y_l, and its Jacobian
        // dh_j/dg_l = delta_jl + dg_j/dx . y_l.
        let mut size = 0.0_f64;
        for sl in slips.iter_mut() {
            size = size.max(sl.refresh(&x));
            if sl.given {
                size = size.max(sl.target().abs());
            }
        }
        if k == 0 || size == 0.0 {
            break;
        }
        for (j, sl) in slips.iter().enumerate() {
            step[j] = sl.target() - sl.g;
            let gradient = sl.gradient();
            for (l, other) in slips.iter().enumerate() {
                matrix[j * k + l] = f64::from(u8::from(j == l)) + gradient.dot(&other.y);
            }
        }
        if !crate::dense::solve_dense(matrix, step, k) {
            return Err(breakdown(s));
        }
        let mut change = 0.0_f64;
        for (sl, d) in slips.iter_mut().zip(step.iter()) {
            sl.g += d;
            change = change.max(d.abs());
        }
        x = x0;
        for sl in slips.iter() {
            x -= sl.y * sl.g;
        }
        // Converged to rounding: the last change below 1e-15 of the normal loads' size.
        // (One more pass refreshes q at the final x.)
        if change <= 1e-15 * size {
            for sl in slips.iter_mut() {
                sl.refresh(&x);
            }
            break;
        }
        if iteration == MAX_ITERATIONS || !change.is_finite() {
            return Err(Error::Breakdown {
                s,
                what: "the tangential friction loads did not converge".into(),
            });
        }
    }
    Ok(x)
}

/// The tangential load of a point loaded by one tendon with friction, in closed form, and
/// the rates with it; None where the closed form does not apply (then Newton solves it).
/// The normal load is affine in the rates, and the rates are affine in the tangential
/// load g: q(g) = q0 - g a with q0 = q(x0) and a = k (I - t t^T)(y_v - r x y_u) (y_v
/// dropped on a Kirchhoff rod). So g = s |q0 - g a| (s = w mu) squared is the quadratic
///
/// ```text
/// (1 - s^2 |a|^2) g^2 + 2 s^2 (q0 . a) g - s^2 |q0|^2 = 0
/// ```
///
/// whose roots have opposite signs (their product is -s^2 |q0|^2 / (1 - s^2 |a|^2) <= 0
/// while s |a| < 1, which is the contraction of the fixed-point iteration: about 1e-3 for
/// the prototype), and g is the root with the sign of s. It is computed without
/// cancellation (the root of the larger magnitude from the sum of like signs, the other
/// from the product), and the normal load refreshed at the rates x0 - g y.
fn single(slip: &mut Slip, x0: &Vector6<f64>) -> Option<Vector6<f64>> {
    if slip.given {
        // An explicit load: the rates follow from it directly.
        slip.g = slip.target();
        let x = x0 - slip.y * slip.g;
        slip.refresh(&x);
        return Some(x);
    }
    let q0 = slip.normal(x0);
    let s = slip.signed_mu;
    if q0 == Vector3::zeros() || s == 0.0 {
        // No normal load or no friction multiplier: no tangential load.
        slip.g = 0.0;
        slip.refresh(x0);
        return Some(*x0);
    }
    let a = slip.normal_change(&slip.y);
    let s2 = s * s;
    let leading = 1.0 - s2 * a.norm_squared();
    if leading.is_nan() || leading <= 0.0 {
        return None;
    }
    let linear = 2.0 * s2 * q0.dot(&a);
    let constant = -s2 * q0.norm_squared();
    let root = (linear * linear - 4.0 * leading * constant).sqrt();
    let t = if linear >= 0.0 {
        -0.5 * (linear + root)
    } else {
        0.5 * (root - linear)
    };
    let (first, second) = (t / leading, constant / t);
    let g = if s > 0.0 { first.max(second) } else { first.min(second) };
    if !g.is_finite() {
        return None;
    }
    slip.g = g;
    let x = x0 - slip.y * g;
    slip.refresh(&x);
    Some(x)
}

/// The error of eq. 13 with friction singular at arc length `s`.
fn breakdown(s: f64) -> Error {
    Error::Breakdown {
        s,
        what: "eq. 13 with friction is singular".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::model::friction::slipping;
    use crate::model::tendon::{Friction, Motion};
    use crate::so3;

    /// One tendon with friction (case H's helix, pulled and released, on a rod bent and
    /// twisted at a generic rotation): the closed form's g is the fixed point
    /// g = w mu |q(x0 - g y)| that Newton converges to.
    #[test]
    fn closed_form_is_newtons_fixed_point() {
        for (mu, motion) in [(0.1, Motion::Pull), (0.3, Motion::Release), (0.05, Motion::Pull)] {
            let mut robot = cases::case_h();
            robot.tendons[4].friction = Some(Friction {
                coefficient: mu,
                motion,
            });
            let model = Model::new(&robot);
            let site = model.site(0.07);
            let (R, v, u) = (
                so3::exp(&Vector3::new(0.3, -0.7, 0.4)),
                Vector3::new(0.01, -0.02, 0.98),
                Vector3::new(4.0, 9.0, -3.0),
            );
            let point = Point::new(&model, &site, robot.length(), (&R, &v, &u)).unwrap();
            let mut slips = Vec::new();
            solve(
                &model,
                &point,
                &site,
                robot.length(),
                (&v, &u),
                &slipping(&robot),
                None,
                &mut slips,
            )
            .unwrap();
            assert_eq!(slips.len(), 1);
            let (mut closed, mut iterated) = (slips[0].clone(), slips.clone());
            closed.g = 0.0;
            iterated[0].g = 0.0;
            let x = single(&mut closed, &point.rates()).expect("the closed form applies");
            let x_newton = newton(&mut iterated, point.rates(), site.s).unwrap();
            let g = closed.g;
            assert!(g != 0.0 && g.signum() == closed.signed_mu.signum(), "g = {g}");
            // 1e-14 relative: both solve the same scalar equation to rounding (Newton stops
            // below 1e-15 of |q|; the closed form's root carries a few ulps).
            assert!(
                (g - iterated[0].g).abs() <= 1e-14 * g.abs(),
                "{g} against {}",
                iterated[0].g
            );
            assert!((x - x_newton).amax() <= 1e-14 * x.amax());
            // The fixed point itself, at the rates the closed form returned.
            assert!((g - closed.signed_mu * closed.q.norm()).abs() <= 1e-14 * g.abs());
        }
    }
}
