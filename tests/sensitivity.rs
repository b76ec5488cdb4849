//! Sensitivities by the implicit function theorem against finite differences of full
//! collocation solves on the same mesh (64 intervals): central, or one-sided second order
//! for slack tendons, which can only be pulled. Cases: the prototype with a straight
//! tendon (case S), the helical tendon with a tip load (case H), and case H with a second
//! tendon ending at mid-length (jump conditions); gravity acts in all of them.
//!
//! Finite-difference steps are 1e-4 of each parameter's scale: the O(h^2) truncation is
//! then about 1e-8 relative, and the solve noise (about 3e-12 m at the residual tolerance
//! 1e-12 used here) divided by h stays below about 6e-7, so agreement to about 1e-6
//! relative tests the sensitivities, not the differences. Measured: 1e-9 to 2e-7.

use nalgebra::{Vector3, Vector6};
use tdcr::collocation::sensitivity::{
    Difference, NodeDerivative, RELATIVE_STEP, Sensitivity, TipSensitivities, backbone_tension_sensitivity,
    tip_sensitivities,
};
use tdcr::collocation::{self, Options};
use tdcr::model::rod::{Section, Stiffness, shear_modulus};
use tdcr::{Error, Friction, Motion, Robot, Solution, cases, so3};

/// Finite-difference step relative to the parameter's scale (module docs).
const FD_STEP: f64 = 1e-4;
/// Relative agreement required: 1e-6, ten times the finite-difference error bound above.
const AGREEMENT: f64 = 1e-6;
/// Tip noise of a full solve (m): 3e-12, the largest difference error times step measured
/// over all columns (tip force z in case S: 1.35e-7 x 2.8 m/N x 7.2e-6 N). Divided by the
/// step it bounds what differences can resolve; it decides only d(tip)/dG in case S, where
/// G acts through shear alone and moves the tip 2e-7 times as much as E does.
const NOISE: f64 = 3e-12;

fn options() -> Options {
    Options {
        intervals: 64,
        tolerance: None,
        // 1e-12 instead of the default 1e-11: a solve that stops at a scaled residual just
        // under 1e-11 can leave the tip 1e-8 m off (measured: 5e-12 after one iteration),
        // which a 1e-4 step would turn into 3e-4 relative; at 1e-12 Newton always takes the
        // step to its rounding floor (about 1e-14).
        residual_tolerance: 1e-12,
        ..Default::default()
    }
}

fn solve(robot: &Robot) -> Solution {
    collocation::solve(robot, &options()).unwrap_or_else(|e| panic!("{e}"))
}

/// Tip pose of `robot` relative to `reference`'s tip: (p - p_ref, log(R R_ref^T)), the
/// world-frame rotation vector, from a full solve warm-started at the reference.
fn tip_offset(robot: &Robot, reference: &Solution) -> Vector6<f64> {
    let solution = collocation::solve_from(robot, &options(), reference).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(solution.nodes.len(), reference.nodes.len(), "the mesh must not change");
    let (a, b) = (solution.tip(), reference.tip());
    let w = so3::log(&(a.R * b.R.transpose()));
    Vector6::new(a.p.x - b.p.x, a.p.y - b.p.y, a.p.z - b.p.z, w.x, w.y, w.z)
}

/// d(tip pose)/dq by differences of full solves: central, or the second-order forward
/// stencil (4 f(h) - f(2h)) / (2h) (f(0) = 0 by construction) for a parameter at a bound.
fn difference(
    robot: &Robot,
    reference: &Solution,
    h: f64,
    forward: bool,
    perturb: impl Fn(&mut Robot, f64),
) -> Vector6<f64> {
    let at = |dq: f64| {
        let mut r = robot.clone();
        perturb(&mut r, dq);
        tip_offset(&r, reference)
    };
    if forward {
        (at(h) * 4.0 - at(2.0 * h)) / (2.0 * h)
    } else {
        (at(h) - at(-h)) / (2.0 * h)
    }
}

/// Tip-pose column with the rotation rows weighted by L, so that both halves are in metres.
fn weigh(v: &Vector6<f64>, length: f64) -> Vector6<f64> {
    let mut w = *v;
    w.fixed_rows_mut::<3>(3).scale_mut(length);
    w
}

struct Check<'a> {
    robot: &'a Robot,
    reference: &'a Solution,
    worst: f64,
}

impl Check<'_> {
    /// Asserts |ift - fd| <= AGREEMENT |fd| + NOISE / h (rotation rows weighted by L).
    fn column(&mut self, what: &str, ift: Vector6<f64>, h: f64, forward: bool, perturb: impl Fn(&mut Robot, f64)) {
        let fd = difference(self.robot, self.reference, h, forward, perturb);
        let length = self.robot.length();
        let (a, b) = (weigh(&ift, length), weigh(&fd, length));
        let err = (a - b).norm() / b.norm();
        let floor = NOISE / h / b.norm();
        eprintln!(
            "  {what:<16} |fd| = {:.3e}  relative difference {err:.2e}  (noise floor {floor:.1e})",
            fd.norm()
        );
        self.worst = self.worst.max(err);
        assert!(
            err <= AGREEMENT + floor,
            "{what}: sensitivity {ift:?} vs finite differences {fd:?} ({err:.2e})"
        );
    }
}

/// Every tip sensitivity of `robot` against differences of full solves.
fn check_tip(name: &str, robot: &Robot) -> TipSensitivities {
    let reference = solve(robot);
    let sens = tip_sensitivities(robot, &reference).unwrap();
    eprintln!("{name}");
    let mut c = Check {
        robot,
        reference: &reference,
        worst: 0.0,
    };
    let ei = robot.bending_stiffness();
    let length = robot.length();
    for (i, t) in robot.tendons.iter().enumerate() {
        // A slack tendon can only be pulled: one-sided differences, scaled by the tension
        // that bends the rod through about a radian, E I / (L r) (2.2 N).
        let slack = t.tension() == 0.0;
        let bend = ei / (length * t.routing.at(0.0, length).r.norm());
        let h = FD_STEP * if slack { bend } else { t.tension() };
        let ift = sens.tension.fixed_view::<6, 1>(0, i).into_owned();
        c.column(&format!("tension {i}"), ift, h, slack, |r, d| {
            let t = &mut r.tendons[i];
            t.set_tension(t.tension() + d)
        });
    }
    for (i, t) in robot.tendons.iter().enumerate() {
        let Some(friction) = t.active_friction() else {
            assert_eq!(sens.friction.column(i).norm(), 0.0, "tendon {i} has no friction");
            continue;
        };
        let mu = friction.coefficient;
        let ift = sens.friction.fixed_view::<6, 1>(0, i).into_owned();
        c.column(&format!("friction {i}"), ift, FD_STEP * mu, false, |r, d| {
            if let Some(f) = &mut r.tendons[i].friction {
                f.coefficient = mu + d;
            }
        });
    }
    // Scales of the load's effect on the shape: E I / L^2 for forces, E I / L for moments.
    let (force, moment) = (ei / length.powi(2), ei / length);
    for j in 0..3 {
        let col = |m: &nalgebra::Matrix6x3<f64>| m.column(j).into_owned();
        c.column(
            &format!("tip force {j}"),
            col(&sens.tip_force),
            FD_STEP * force,
            false,
            |r, d| r.loads.tip_force[j] += d,
        );
        c.column(
            &format!("tip moment {j}"),
            col(&sens.tip_moment),
            FD_STEP * moment,
            false,
            |r, d| r.loads.tip_moment[j] += d,
        );
        c.column(
            &format!("base position {j}"),
            col(&sens.base_position),
            FD_STEP * length,
            false,
            |r, d| r.base_position[j] += d,
        );
        c.column(
            &format!("base rotation {j}"),
            col(&sens.base_rotation),
            FD_STEP,
            false,
            |r, d| r.base_rotation = so3::exp(&Vector3::ith(j, d)) * r.base_rotation,
        );
    }
    let g = robot.rod.geometry.expect("the prototype is built from geometry");
    let moduli = sens.moduli.expect("moduli for a rod built from geometry");
    let (o, i, e, nu) = (g.outer_radius, g.inner_radius, g.youngs_modulus, g.poisson_ratio);
    let shear = shear_modulus(e, nu);
    c.column("E at fixed nu", moduli.youngs_modulus, FD_STEP * e, false, |r, d| {
        r.rod = tdcr::Rod::solid_circle(r.rod.length, o, e + d, nu)
    });
    c.column(
        "E at fixed G",
        moduli.youngs_modulus_fixed_shear,
        FD_STEP * e,
        false,
        |r, d| r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e + d, shear)),
    );
    c.column("G at fixed E", moduli.shear_modulus, FD_STEP * shear, false, |r, d| {
        r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e, shear + d))
    });
    eprintln!("  worst {:.2e}", c.worst);
    sens
}

/// Case H with tendon 2 at 1.5 N ending at mid-length: a breakpoint with jump conditions.
fn two_segments() -> Robot {
    let mut robot = cases::case_h();
    robot.tendons[1].set_tension(1.5);
    robot.tendons[1].termination = Some(0.5 * cases::LENGTH);
    robot
}

#[test]
fn tip_sensitivities_match_finite_differences_straight_tendon() {
    check_tip("case S", &cases::case_s());
}

#[test]
fn tip_sensitivities_match_finite_differences_helix_tip_load() {
    let sens = check_tip("case H", &cases::case_h());
    // The force block of the compliance is symmetric: tendons at fixed tension, gravity and
    // a dead tip force are conservative, so it is the inverse Hessian of the potential
    // energy. The discrete system is not variational, so its asymmetry is discretization
    // error: measured 4.2e-5, 2.6e-6, 1.6e-7, 1.0e-8 at 16, 32, 64, 128 intervals (order 4);
    // 1e-6 bounds the 64-interval value.
    let block = sens.tip_force.fixed_rows::<3>(0).into_owned();
    let asym = (block - block.transpose()).norm() / block.norm();
    eprintln!("force compliance asymmetry {asym:.2e}");
    assert!(asym < 1e-6, "asymmetry {asym:.2e}");
}

#[test]
fn tip_sensitivities_match_finite_differences_across_a_termination() {
    check_tip("case H + tendon 2 ending at L/2", &two_segments());
}

/// Case S with friction mu = 0.1 on its tendon and on one at 0 N, case H with mu = 0.1 on its helix (pull)
/// and case H with mu = 0.2 on its helix, released: every column, d(tip)/d(mu) included,
/// through the bordered system of the log tensions.
#[test]
fn tip_sensitivities_match_finite_differences_with_friction() {
    let mut s = cases::case_s();
    s.tendons[0].friction = Some(Friction::pull(0.1));
    check_tip("case S, mu = 0.1", &s);
    // Tendon 2 at 0 N with friction too: its log tensions are not in its tensions (solved
    // from its capstan rows); its tension column is the first pull's (tests/first_pull.rs
    // checks it against solves), the others hold.
    s.tendons[1].friction = Some(Friction::pull(0.1));
    let solution = solve(&s);
    let sens = tip_sensitivities(&s, &solution).unwrap();
    assert!(sens.tension.column(1).iter().all(|x| x.is_finite()) && sens.tension.column(1).norm() > 0.0);
    assert_eq!(
        sens.friction.column(1).norm(),
        0.0,
        "an unloaded tendon's friction moves nothing"
    );
    let mut plain = cases::case_s();
    plain.tendons[0].friction = Some(Friction::pull(0.1));
    let reference = tip_sensitivities(&plain, &solve(&plain)).unwrap();
    // 1e-9 relative: the same shape, the unloaded tendon's border only adds rounding.
    let close = |a: &nalgebra::DMatrix<f64>, b: &nalgebra::DMatrix<f64>, c: usize| {
        (a.column(c) - b.column(c)).norm() <= 1e-9 * b.column(c).norm()
    };
    assert!(close(&sens.tension, &reference.tension, 0) && close(&sens.friction, &reference.friction, 0));
    let mut h = cases::case_h();
    h.tendons[4].friction = Some(Friction::pull(0.1));
    check_tip("case H, mu = 0.1", &h);
    h.tendons[4].friction = Some(Friction {
        coefficient: 0.2,
        motion: Motion::Release,
    });
    check_tip("case H, mu = 0.2, release", &h);
}

/// A tendon with friction ending inside the rod (0.6 L, mu = 0.2): the delivered tension's
/// log tension is an unknown of an interior node and enters the termination's jump rows,
/// which the staircase factors take from link rows; every column against differences.
#[test]
fn tip_sensitivities_with_friction_on_a_tendon_ending_inside_the_rod() {
    let mut s = cases::case_s();
    let length = s.length();
    s.tendons[0] = s.tendons[0].clone().ending_at(0.6 * length);
    s.tendons[0].set_tension(4.0);
    s.tendons[0].friction = Some(Friction::pull(0.2));
    check_tip("case S, tendon 1 ending at 0.6 L, mu = 0.2", &s);
}

/// d p(s)/d tau at every node against differences of full solves, node by node.
fn check_backbone(robot: &Robot, tendon: usize) {
    let reference = solve(robot);
    let dp = backbone_tension_sensitivity(robot, &reference, tendon).unwrap();
    assert_eq!(dp.len(), reference.nodes.len());
    let tau = robot.tendons[tendon].tension();
    let h = FD_STEP * tau;
    let at = |d: f64| {
        let mut r = robot.clone();
        {
            let t = &mut r.tendons[tendon];
            t.set_tension(t.tension() + d);
        }
        collocation::solve_from(&r, &options(), &reference).unwrap()
    };
    let (plus, minus) = (at(h), at(-h));
    let fd: Vec<Vector3<f64>> = plus
        .nodes
        .iter()
        .zip(&minus.nodes)
        .map(|(a, b)| (a.p - b.p) / (2.0 * h))
        .collect();
    let scale = fd.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let worst = dp.iter().zip(&fd).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / scale;
    eprintln!("backbone, tendon {tendon}: max |dp/dtau| {scale:.3e} m/N, relative difference {worst:.2e}");
    assert!(worst < AGREEMENT, "backbone sensitivity differs by {worst:.2e}");
    assert!(dp[0].norm() == 0.0, "the base is clamped: {:?}", dp[0]);
    // The tip entry is the tension column of the tip sensitivities (the same computation).
    let tip = tip_sensitivities(robot, &reference).unwrap();
    let column = tip.tension.fixed_view::<3, 1>(0, tendon).into_owned();
    assert!((dp[dp.len() - 1] - column).norm() <= 1e-14 * column.norm());
}

#[test]
fn backbone_sensitivity_matches_finite_differences() {
    check_backbone(&cases::case_s(), 0);
    check_backbone(&cases::case_h(), 4);
    // Across the jump the two nodes at the termination share p and so their derivative.
    check_backbone(&two_segments(), 1);
}

/// The exact dF/dq of the tip wrench and base pose against differences of the residual
/// (the library's generic path): a check of their signs and frames free of the noise of
/// full solves. The residual is linear in the wrench and base position, and the base
/// rotation's truncation at a 1e-4 rad step is about 1e-8 of its rows' O(1e-4) curvature.
#[test]
fn exact_load_and_base_derivatives_match_differenced_ones() {
    for robot in [cases::case_s(), cases::case_h(), two_segments()] {
        let solution = solve(&robot);
        let mut sens = Sensitivity::new(&robot, &solution).unwrap();
        let step = RELATIVE_STEP;
        let mut worst: f64 = 0.0;
        for j in 0..3 {
            let pairs = [
                (
                    sens.tip_force(j).unwrap(),
                    sens.derivative(step, Difference::Central, |r, d| r.loads.tip_force[j] += d)
                        .unwrap(),
                ),
                (
                    sens.tip_moment(j).unwrap(),
                    sens.derivative(step * 0.01, Difference::Central, |r, d| r.loads.tip_moment[j] += d)
                        .unwrap(),
                ),
                (
                    sens.base_position(j).unwrap(),
                    sens.derivative(step * 0.1, Difference::Central, |r, d| r.base_position[j] += d)
                        .unwrap(),
                ),
                (
                    sens.base_rotation(j).unwrap(),
                    sens.derivative(step, Difference::Central, |r, d| {
                        r.base_rotation = so3::exp(&Vector3::ith(j, d)) * r.base_rotation
                    })
                    .unwrap(),
                ),
            ];
            for (exact, differenced) in &pairs {
                // Every node, every component of p, rotation, v and u.
                let flat = |d: &[NodeDerivative]| -> Vec<f64> {
                    d.iter()
                        .flat_map(|n| {
                            n.p.iter()
                                .chain(&n.rotation)
                                .chain(&n.v)
                                .chain(&n.u)
                                .copied()
                                .collect::<Vec<_>>()
                        })
                        .collect()
                };
                let (a, b) = (flat(exact), flat(differenced));
                let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale;
                worst = worst.max(err);
            }
        }
        eprintln!("exact against differenced dF/dq: {worst:.2e}");
        // 1e-8: thirty times the 2.9e-10 measured (rounding of the differenced residual).
        assert!(worst < 1e-8, "{worst:.2e}");
    }
}

/// Every node derivative of `d` flattened: p, rotation, v, u per node.
fn flat(d: &[NodeDerivative]) -> Vec<f64> {
    d.iter()
        .flat_map(|n| {
            n.p.iter()
                .chain(&n.rotation)
                .chain(&n.v)
                .chain(&n.u)
                .copied()
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Largest difference of `a` from `b` relative to `b`'s largest entry.
fn relative_to(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// The exact tension columns (dF/dtau from eq. 13's linearity in each tension) against the
/// differenced residual they replace (central at 1e-4 of the tension, or the second-order
/// one-sided stencil for a slack tendon, at 1e-4 of E I / (L r)), at every node: taut and
/// slack tendons, a termination at L/2 (jump rows), the point-moment model and a tension
/// factor below 1 are covered by case S (four slack tendons), case H, case H with a tendon
/// ending at L/2, and that robot in the point-moment model.
#[test]
fn exact_tension_columns_match_differenced_ones() {
    let mut point_moment = two_segments();
    point_moment.tendon_model = tdcr::model::robot::TendonModel::PointMoment;
    let mut worst: f64 = 0.0;
    for robot in [cases::case_s(), cases::case_h(), two_segments(), point_moment] {
        let solution = solve(&robot);
        let mut sens = Sensitivity::new(&robot, &solution).unwrap();
        let length = robot.length();
        for (i, t) in robot.tendons.iter().enumerate() {
            let tension = t.tension();
            let bend = robot.bending_stiffness() / (length * t.routing.at(0.0, length).r.norm());
            let step = RELATIVE_STEP * tension.max(bend);
            let stencil = if tension > step {
                Difference::Central
            } else {
                Difference::Forward
            };
            let differenced = sens
                .derivative(step, stencil, |r, d| r.tendons[i].set_tension(tension + d))
                .unwrap();
            let exact = sens.tension(i).unwrap();
            let err = relative_to(&flat(&exact), &flat(&differenced));
            eprintln!("tension {i} ({tension} N): exact against differenced {err:.2e}");
            worst = worst.max(err);
        }
    }
    // 1e-6 (measured 2e-13 to 1e-7): the differenced residual's own error, about 1e-8 to 1e-7
    // (the module docs of sensitivity: truncation 1e-8 at this step, rounding 1e-11 / h_rel),
    // with a margin of 15.
    assert!(worst < 1e-6, "{worst:.2e}");
}

/// The exact modulus derivatives (eq. 13 and the point-load rows linear in each section
/// stiffness) against the differenced residual they replace, at every node: E at fixed
/// Poisson's ratio and G at fixed E, on case S, case H and case H with a tendon ending at L/2.
#[test]
fn exact_modulus_derivatives_match_differenced_ones() {
    let mut worst: f64 = 0.0;
    for robot in [cases::case_s(), cases::case_h(), two_segments()] {
        let solution = solve(&robot);
        let mut sens = Sensitivity::new(&robot, &solution).unwrap();
        let g = robot.rod.geometry.unwrap();
        let (o, i, e, nu) = (g.outer_radius, g.inner_radius, g.youngs_modulus, g.poisson_ratio);
        let shear = shear_modulus(e, nu);
        let exact_e = sens.parameter(tdcr::Parameter::YoungsModulus).unwrap();
        let differenced_e = sens
            .derivative(RELATIVE_STEP * e, Difference::Central, |r, d| {
                r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e + d, shear_modulus(e + d, nu)));
            })
            .unwrap();
        let unit_g = Section::tube(o, i, 0.0, 1.0);
        let (a, b) = (unit_g.kse, unit_g.kbt);
        let exact_g = sens.stiffness(&[a[0], a[1], a[2], b[0], b[1], b[2]]).unwrap();
        let differenced_g = sens
            .derivative(RELATIVE_STEP * shear, Difference::Central, |r, d| {
                r.rod.stiffness = Stiffness::Uniform(Section::tube(o, i, e, shear + d));
            })
            .unwrap();
        // Per relative change of the modulus: G's effect is measured against E's (in case S,
        // planar bending with no shear or torsion, d/dG is 1e-17 per Pa, rounding on both sides).
        let size = |d: &[f64], modulus: f64| d.iter().fold(0.0f64, |m, x| m.max(x.abs())) * modulus;
        let scale = size(&flat(&differenced_e), e);
        for (name, a, b, modulus) in [
            ("E", &exact_e, &differenced_e, e),
            ("G", &exact_g, &differenced_g, shear),
        ] {
            let (a, b) = (flat(a), flat(b));
            let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) * modulus
                / scale.max(size(&b, modulus));
            eprintln!("{name}: exact against differenced {err:.2e}");
            worst = worst.max(err);
        }
    }
    // 1e-6: the differenced residual's own error (1e-8 to 6e-8 for moduli, module docs of
    // sensitivity), with a wide margin; measured 9e-9 to 1.7e-8.
    assert!(worst < 1e-6, "{worst:.2e}");
}

#[test]
fn moduli_are_absent_without_geometry() {
    let mut robot = cases::case_s();
    robot.rod = tdcr::Rod::new(cases::LENGTH, Section::solid_circle(cases::RADIUS, 210e9, 80e9));
    let sens = tip_sensitivities(&robot, &solve(&robot)).unwrap();
    assert!(sens.moduli.is_none());
}

fn invalid_field(result: tdcr::Result<impl std::fmt::Debug>) -> (String, String) {
    match result {
        Err(Error::InvalidInput { field, problem, .. }) => (field, problem),
        other => panic!("expected InvalidInput, got {other:?}"),
    }
}

#[test]
fn errors_name_the_problem() {
    let robot = cases::case_s();
    let solution = solve(&robot);
    let (field, problem) = invalid_field(backbone_tension_sensitivity(&robot, &solution, 5));
    assert_eq!(field, "tendon");
    assert!(problem.contains("5 tendons"), "{problem}");
    let mut sens = Sensitivity::new(&robot, &solution).unwrap();
    let (field, _) = invalid_field(sens.tip_force(3));
    assert_eq!(field, "axis");
    let (field, _) = invalid_field(sens.derivative(0.0, Difference::Central, |r, d| {
        let t = &mut r.tendons[0];
        t.set_tension(t.tension() + d)
    }));
    assert_eq!(field, "step");
    let (field, problem) = invalid_field(sens.derivative(1e-3, Difference::Central, |r, d| {
        r.tendons[0].termination = Some(0.1 + d)
    }));
    assert_eq!(field, "perturbation");
    assert!(problem.contains("breakpoint"), "{problem}");
    // A solution of another robot: its mesh lacks the breakpoint.
    let (field, problem) = invalid_field(tip_sensitivities(&two_segments(), &solution));
    assert_eq!(field, "solution");
    assert!(problem.contains("breakpoints"), "{problem}");
    // Same mesh, other loads: the solution does not solve this robot.
    let (field, problem) = invalid_field(tip_sensitivities(&cases::case_h(), &solution));
    assert_eq!(field, "solution");
    assert!(problem.contains("residual"), "{problem}");
}
