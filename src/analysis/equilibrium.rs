//! Global equilibrium of a solved robot: a physics check independent of any solver.
//!
//! Cut the robot (backbone and tendons together) just after the base and look at the free
//! body s in (0, L]. Everything the backbone and the tendons do to each other (distributed
//! tendon loads of eq. 11, termination wrenches, corner forces of docs/model.md) is internal
//! to it and cancels. What remains acts from outside:
//!
//! - the base section pulls with -n(0), -m(0) (n, m: internal force and moment, world
//!   frame, exerted by the material at larger s on the material at smaller s);
//! - the external loads: F_tip, L_tip at p(L), point wrenches F_k, L_k at p(s_k), and the
//!   distributed f_e, l_e (world frame, per unit s);
//! - each tendon i, cut at the base where it leaves toward its actuator, carries its tension
//!   tau_i (with friction, its tension at the base entry: the input) along its unit path
//!   tangent t_i(0) = p_i'(0) / |p_i'(0)| with
//!   p_i' = R (u x r_i + r_i' + v) (eq. 12) taken at the base node; the actuator pulls the
//!   free body with -tau_i t_i(0), applied at p(0) + R(0) r_i(0).
//!
//! The free body is at rest, so with every moment taken about p0 = p(0)
//!
//! ```text
//! n(0) = F_tip + sum_k F_k + int_0^L f_e ds - sum_i tau_i t_i(0)
//! m(0) = L_tip + (p(L) - p0) x F_tip + sum_k (L_k + (p(s_k) - p0) x F_k)
//!        + int_0^L ((p(s) - p0) x f_e + l_e) ds - sum_i (R(0) r_i(0)) x tau_i t_i(0)
//! ```
//!
//! [`imbalance`] evaluates the difference between the two sides. The integrals use 4-point
//! Gauss-Legendre on every interval of positive length between consecutive solution nodes,
//! with p(s) from [`Solution::at`] (the cubic Hermite interpolant, 4th order), so for smooth
//! loads the quadrature error is far below the solvers' discretization error.
//!
//! Friction between a tendon and its channels (docs/friction.md) is internal to this free
//! body: the channel's tangential force on the tendon and the tendon's on the backbone
//! cancel, so the balance is the same with friction. It checks that the backbone receives
//! the tangential load that makes the tension fall (or rise) along the tendon: without it,
//! the tension change would be unbalanced.
//!
//! The balance holds exactly for the exact solution of the model with corner forces
//! (`Robot::corner_forces = true`); the paper's jump conditions (`false`) violate it where a
//! tendon bends at another tendon's interior termination.
#![allow(non_snake_case)]

use crate::model::robot::Robot;
use crate::solution::Solution;
use nalgebra::Vector3;

/// Relative errors of the global force and moment balance of a solved robot (see the
/// module docs for the balance and the scales).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Equilibrium {
    /// |n(0) - (sum of the external and actuator forces)| divided by the characteristic
    /// force (dimensionless).
    pub force: f64,
    /// |m(0) - (sum of their moments about p(0))| divided by the characteristic moment
    /// (dimensionless).
    pub moment: f64,
}

impl Equilibrium {
    /// The larger of the two relative errors.
    pub fn max(&self) -> f64 {
        self.force.max(self.moment)
    }
}

/// 4-point Gauss-Legendre abscissae on [-1, 1], +-sqrt(3/7 -+ 2/7 sqrt(6/5)) (exact for
/// polynomials of degree 7).
const GAUSS_X: [f64; 4] = [
    -0.861_136_311_594_052_6,
    -0.339_981_043_584_856_3,
    0.339_981_043_584_856_3,
    0.861_136_311_594_052_6,
];
/// Their weights, (18 -+ sqrt 30) / 36.
const GAUSS_W: [f64; 4] = [
    0.347_854_845_137_453_9,
    0.652_145_154_862_546_1,
    0.652_145_154_862_546_1,
    0.347_854_845_137_453_9,
];

/// Relative global-equilibrium errors of `solution` as a solution of `robot` at full load.
///
/// Scales: the characteristic force F is the largest of |F_tip|, sum_i tau_i,
/// int |f_e| ds and sum_k |F_k|; the characteristic moment is
/// F L + |L_tip| + sum_k |L_k| + int |l_e| ds. When F is zero (pure moment loading) the force error is divided by the
/// characteristic moment over L instead. Both scales have a floor of the smallest positive
/// f64, so an unloaded robot gives 0 when n(0) and m(0) are exactly zero.
///
/// `solution` must have at least two nodes and belong to `robot` (same tendons, s from 0
/// to L).
///
/// # Examples
/// ```
/// use tdcr::analysis::equilibrium;
/// use tdcr::{Robot, Rod, Routing, Tendon, shooting};
/// let robot = Robot::new(Rod::solid_circle(0.2, 0.0005, 200e9, 0.3))
///     .with_tendon(Tendon::new(Routing::straight(0.005, 0.0), 1.0));
/// let solution = shooting::solve(&robot, &Default::default()).unwrap();
/// let e = equilibrium::imbalance(&robot, &solution);
/// assert!(e.force < 1e-8 && e.moment < 1e-8);
/// ```
pub fn imbalance(robot: &Robot, solution: &Solution) -> Equilibrium {
    let loads = &robot.loads;
    let length = robot.length();
    let base = solution.base();
    let (p0, R0) = (base.p, base.R);

    // Tip and point wrenches.
    let tip = solution.tip();
    // Follower tip wrench: fixed in the tip body frame.
    let tip_force = loads.tip_force + tip.R * loads.follower_tip_force;
    let tip_moment = loads.tip_moment + tip.R * loads.follower_tip_moment;
    let mut force = tip_force;
    let mut moment = tip_moment + (tip.p - p0).cross(&tip_force);
    let mut point_force_sum = 0.0;
    let mut point_moment_sum = 0.0;
    for load in &loads.point {
        let p = solution.at(load.s).p;
        force += load.force;
        moment += load.moment + (p - p0).cross(&load.force);
        point_force_sum += load.force.norm();
        point_moment_sum += load.moment.norm();
    }

    // Distributed loads, Gauss-Legendre on each interval of positive length.
    let mut f_abs = 0.0;
    let mut l_abs = 0.0;
    let mut f_int = Vector3::zeros();
    for pair in solution.nodes.windows(2) {
        let (a, b) = (pair[0].s, pair[1].s);
        if b <= a {
            continue;
        }
        let (mid, half) = ((a + b) / 2.0, (b - a) / 2.0);
        for (x, w) in GAUSS_X.iter().zip(GAUSS_W) {
            let s = mid + half * x;
            let weight = w * half;
            let at = solution.at(s);
            let f_e = loads.distributed_force.at(s) + at.R * loads.follower_distributed_force.at(s);
            let l_e = loads.distributed_moment.at(s);
            let p = at.p;
            f_int += f_e * weight;
            moment += ((p - p0).cross(&f_e) + l_e) * weight;
            f_abs += f_e.norm() * weight;
            l_abs += l_e.norm() * weight;
        }
    }
    force += f_int;

    // Actuators pull every tensioned tendon back along its path at the base.
    let mut tension_sum = 0.0;
    for tendon in robot.tendons.iter().filter(|t| t.tension() > 0.0) {
        let rp = tendon.routing.at(base.s, length);
        let tangent = R0 * (base.u.cross(&rp.r) + rp.r_s + base.v);
        let pull = tangent * (tendon.tension() / tangent.norm());
        force -= pull;
        moment -= (R0 * rp.r).cross(&pull);
        tension_sum += tendon.tension();
    }

    let force_scale = [tip_force.norm(), tension_sum, f_abs, point_force_sum]
        .into_iter()
        .fold(0.0, f64::max);
    let moment_scale = force_scale * length + tip_moment.norm() + point_moment_sum + l_abs;
    let force_scale = if force_scale > 0.0 {
        force_scale
    } else {
        moment_scale / length
    };
    Equilibrium {
        force: (base.n - force).norm() / force_scale.max(f64::MIN_POSITIVE),
        moment: (base.m - moment).norm() / moment_scale.max(f64::MIN_POSITIVE),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::loads::{Field, Loads, PointLoad};
    use crate::model::rod::{Rod, Section};
    use crate::model::routing::Routing;
    use crate::model::tendon::Tendon;
    use crate::report::{Method, SolveReport};
    use crate::solution::Node;
    use nalgebra::Matrix3;

    /// A circular arc in the world xz plane (curvature `kappa` about body y) sampled at
    /// `count + 1` nodes, with n(0) and m(0) left at zero for the caller to fill.
    fn arc(length: f64, kappa: f64, count: usize) -> Solution {
        let nodes = (0..=count)
            .map(|k| {
                let s = length * k as f64 / count as f64;
                let (sin, cos) = (kappa * s).sin_cos();
                Node {
                    s,
                    p: Vector3::new((1.0 - cos) / kappa, 0.0, sin / kappa),
                    R: Matrix3::new(cos, 0.0, sin, 0.0, 1.0, 0.0, -sin, 0.0, cos),
                    v: Vector3::z(),
                    u: Vector3::new(0.0, kappa, 0.0),
                    v_s: Vector3::zeros(),
                    u_s: Vector3::zeros(),
                    n: Vector3::zeros(),
                    m: Vector3::zeros(),
                }
            })
            .collect();
        Solution {
            nodes,
            tendon_paths: Vec::new(),
            tendon_tensions: Vec::new(),
            tendons: Vec::new(),
            report: SolveReport::new(Method::Shooting),
        }
    }

    #[test]
    fn balance_of_a_hand_made_arc_with_every_kind_of_load() {
        let (length, kappa, r, tau) = (0.3, 4.0, 0.01, 2.0);
        let f_e = Vector3::new(0.5, -0.2, -1.0);
        let l_e = Vector3::new(0.01, 0.02, -0.03);
        let (tip_force, tip_moment) = (Vector3::new(0.1, 0.3, -0.2), Vector3::new(0.0, 0.05, 0.01));
        let point = PointLoad {
            s: length / 3.0,
            force: Vector3::new(-0.4, 0.1, 0.2),
            moment: Vector3::new(0.02, 0.0, 0.01),
        };
        let robot = Robot::new(Rod::new(length, Section::explicit(1e4, 1e4, 1.0, 1.0, 0.8)))
            .with_tendon(Tendon::new(Routing::straight(r, 0.0), tau))
            .with_tendon(Tendon::new(Routing::straight(-r, 0.0), 0.0))
            .with_loads(Loads {
                distributed_force: Field::Constant(f_e),
                distributed_moment: Field::Constant(l_e),
                tip_force,
                tip_moment,
                point: vec![point],
                ..Loads::none()
            });
        let mut solution = arc(length, kappa, 64);
        // Exact integrals on the arc p(s) = ((1 - cos ks) / k, 0, sin(ks) / k).
        let (sin, cos) = (kappa * length).sin_cos();
        let p_int = Vector3::new((length - sin / kappa) / kappa, 0.0, (1.0 - cos) / (kappa * kappa));
        let p_at = |s: f64| Vector3::new((1.0 - (kappa * s).cos()) / kappa, 0.0, (kappa * s).sin() / kappa);
        // The tendon at body (r, 0) leaves the base along +z: p_i' = (0, 0, 1 - kappa r).
        let pull = Vector3::z() * tau;
        let n0 = tip_force + point.force + f_e * length - pull;
        let m0 = tip_moment
            + p_at(length).cross(&tip_force)
            + point.moment
            + p_at(point.s).cross(&point.force)
            + p_int.cross(&f_e)
            + l_e * length
            - Vector3::new(r, 0.0, 0.0).cross(&pull);
        solution.nodes[0].n = n0;
        solution.nodes[0].m = m0;
        let e = imbalance(&robot, &solution);
        // 1e-9: the Hermite interpolant of the arc is off by at most h^4 kappa^3 / 384 = 8e-11 m
        // (h = L/64), which moves the moment integrals by less than that (measured 9e-12)
        assert!(e.max() < 1e-9, "{e:?}");

        // A force error of 1e-3 N against a characteristic force of max(|F_tip|, tau,
        // int |f_e|, |F_k|) = tau = 2 N.
        solution.nodes[0].n += Vector3::new(1e-3, 0.0, 0.0);
        let e = imbalance(&robot, &solution);
        // 1e-9: rounding of the sums above
        assert!((e.force - 5e-4).abs() < 1e-9, "{e:?}");

        // Forgetting the actuators' pull (a wrong sign convention) is a gross error.
        solution.nodes[0].n = n0 + pull * 2.0;
        solution.nodes[0].m = m0;
        assert!(imbalance(&robot, &solution).force > 0.5);
    }
}
