//! The Kirchhoff rod (`RodModel::Kirchhoff`: inextensible and unshearable, v = v* exactly,
//! the internal force a reaction; docs/model.md, "Kirchhoff rods"): an analytic case, the
//! limit of ever stiffer Cosserat rods, the two solvers against each other, the observed
//! order, global equilibrium and sensitivities.

use tdcr::analysis::equilibrium::imbalance;
use tdcr::cases::analytic::elastica_tip;
use tdcr::model::rod::{Section, Stiffness};
use tdcr::nalgebra::Vector3;
use tdcr::{Loads, Robot, Rod, RodModel, Routing, Solution, Tendon, cases, collocation, shooting};

/// `robot` as a Kirchhoff rod.
fn kirchhoff(robot: &Robot) -> Robot {
    let mut out = robot.clone();
    out.rod_model = RodModel::Kirchhoff;
    out
}

/// `robot` (of uniform section) with its shear and extension stiffness GA, EA times `k`.
fn stiffer(robot: &Robot, k: f64) -> Robot {
    let mut out = robot.clone();
    let Stiffness::Uniform(section) = robot.rod.stiffness.clone() else {
        panic!("a uniform section");
    };
    out.rod.stiffness = Stiffness::Uniform(Section {
        kse: section.kse * k,
        ..section
    });
    out
}

/// Collocation to a tip tolerance of `tol` L.
fn to(tol: f64) -> collocation::Options {
    collocation::Options {
        tolerance: Some(tol),
        ..Default::default()
    }
}

/// Shooting at its tightest supported integration tolerance.
fn tight_shooting() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

/// Case H (a helical tendon at 2.94 N under self-weight) with a tip load: the rod is both
/// bent and compressed, and the tip force has a component along the backbone.
fn loaded_helix() -> Robot {
    let mut robot = cases::case_h();
    robot.loads.tip_force = Vector3::new(0.05, -0.03, -0.098);
    robot
}

/// A two-segment robot: one tendon ends at mid-length (jump conditions at a termination),
/// one at the tip, with a point load and a tip force.
fn two_segments() -> Robot {
    let l = cases::LENGTH;
    let mut robot = cases::prototype();
    robot.tendons.clear();
    let mut robot = robot
        .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 2.0).ending_at(0.5 * l))
        .with_tendon(Tendon::new(Routing::straight(0.0, 0.008), 1.5));
    robot.loads.tip_force = Vector3::new(0.0, 0.02, -0.05);
    robot.loads.point.push(tdcr::PointLoad {
        s: 0.75 * l,
        force: Vector3::new(0.03, 0.0, 0.0),
        moment: Vector3::zeros(),
    });
    robot
}

fn tip_distance(a: &Solution, b: &Solution) -> f64 {
    (a.tip_position() - b.tip_position()).norm()
}

#[test]
fn kirchhoff_nodes_keep_the_reference_strain() {
    let robot = kirchhoff(&loaded_helix());
    let solution = collocation::solve(&robot, &Default::default()).unwrap();
    for node in &solution.nodes {
        assert_eq!(node.v, Vector3::z(), "s = {}", node.s);
        assert_eq!(node.v_s, Vector3::zeros(), "s = {}", node.s);
    }
    // the force is a reaction, not zero: the tendon compresses the rod by about its tension
    assert!(solution.nodes[0].n.norm() > 1.0, "{}", solution.nodes[0].n);
}

/// The Cosserat rod's tip distance from the Kirchhoff rod's falls as 1/k when GA and EA
/// are multiplied by k: k |tip_k - tip_kirchhoff| is constant. Beyond k = 100 the Cosserat
/// solve fails (its unknowns are strains, which carry the force to only rounding divided by
/// the strain; docs/validation.md), so the measured range is k = 1, 10, 100.
#[test]
fn stiff_cosserat_rods_converge_to_kirchhoff_as_one_over_the_stiffness() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let reference = collocation::solve(&kirchhoff(&robot), &to(1e-10)).unwrap();
        let scaled: Vec<f64> = [1.0, 10.0, 100.0]
            .iter()
            .map(|&k| {
                let stiff = collocation::solve(&stiffer(&robot, k), &to(1e-10)).unwrap();
                let d = tip_distance(&stiff, &reference);
                eprintln!(
                    "{name}: k = {k:e}: |tip - kirchhoff| = {d:.4e} m, k |tip - kirchhoff| = {:.6e} m",
                    k * d
                );
                k * d
            })
            .collect();
        // 1e-3 relative: the next term is O(1/k^2), relative to the first about the
        // strain n / EA (below 1e-4 here); the discretization errors (1e-10 L) are
        // below 1e-3 of the smallest distance (k = 100)
        for c in &scaled[1..] {
            assert!((c / scaled[0] - 1.0).abs() < 1e-3, "{name}: {scaled:?}");
        }
    }
}

#[test]
fn collocation_and_shooting_agree_on_kirchhoff_robots() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let robot = kirchhoff(&robot);
        let c = collocation::solve(&robot, &to(1e-10)).unwrap();
        let s = shooting::solve(&robot, &tight_shooting()).unwrap();
        let d = tip_distance(&c, &s);
        eprintln!("{name}: collocation - shooting = {d:.3e} m");
        // 1e-8 m: the cross-check's agreement on Cosserat robots (tests/cross_check.rs)
        assert!(d < 1e-8, "{name}: {d:e}");
    }
}

#[test]
fn kirchhoff_solutions_are_in_global_equilibrium() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let robot = kirchhoff(&robot);
        let solution = collocation::solve(&robot, &to(1e-10)).unwrap();
        let e = imbalance(&robot, &solution);
        eprintln!(
            "{name}: relative imbalance force {:.1e}, moment {:.1e}",
            e.force, e.moment
        );
        // 1e-9: as tests/analytic.rs's global balance (relative to the load scale), a
        // solve to 1e-10 L
        assert!(e.max() < 1e-9, "{name}: {e:?}");
    }
}

#[test]
fn observed_order_on_a_kirchhoff_robot_is_four() {
    for (name, robot) in [("loaded helix", loaded_helix()), ("two segments", two_segments())] {
        let robot = kirchhoff(&robot);
        let reference = collocation::solve(&robot, &collocation::Options::fixed(512)).unwrap();
        let errors: Vec<f64> = [8, 16, 32, 64]
            .iter()
            .map(|&n| {
                tip_distance(
                    &collocation::solve(&robot, &collocation::Options::fixed(n)).unwrap(),
                    &reference,
                )
            })
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        eprintln!("{name}: tip errors {errors:?} m, observed orders {orders:?}");
        // 0.1: the scheme's order is 4; the reference's own error is 2^-12 of the coarsest
        for p in orders {
            assert!((p - 4.0).abs() < 0.1, "{name}: {p}");
        }
    }
}

#[test]
fn a_force_along_the_axis_does_not_stretch_a_kirchhoff_rod() {
    let rod = Rod::solid_circle(0.2, 5e-4, 200e9, 0.3);
    let mut loads = Loads::none();
    loads.tip_force = Vector3::new(0.0, 0.0, 50.0);
    let robot = Robot::new(rod).with_loads(loads);
    let k = kirchhoff(&robot);
    let c = collocation::solve(&k, &Default::default()).unwrap();
    let s = shooting::solve(&k, &Default::default()).unwrap();
    let cosserat = collocation::solve(&robot, &Default::default()).unwrap();
    // 1e-15 m: the length is exact (v = e3), only rounding in p = int R e3 remains
    for p in [c.tip_position(), s.tip_position()] {
        assert!((p - Vector3::new(0.0, 0.0, 0.2)).norm() < 1e-15, "{p}");
    }
    // the Cosserat rod stretches by F L / EA = 0.2 x 50 / (E pi r^2) = 63.66 um (1e-8 m:
    // its strain is exact too, to rounding)
    let stretch = 0.2 * 50.0 / (200e9 * std::f64::consts::PI * 5e-4 * 5e-4);
    assert!((cosserat.tip_position().z - 0.2 - stretch).abs() < 1e-8);
    // the reaction is the load all along (1e-9 N: Newton's residual)
    for node in &c.nodes {
        assert!((node.n - Vector3::new(0.0, 0.0, 50.0)).norm() < 1e-9, "{}", node.n);
    }
}

#[test]
fn kirchhoff_sensitivities_match_finite_differences() {
    let robot = kirchhoff(&two_segments());
    let options = collocation::Options::fixed(32);
    let solution = collocation::solve(&robot, &options).unwrap();
    let sens = tdcr::tip_sensitivities(&robot, &solution).unwrap();
    let tip = |r: &Robot| collocation::solve(r, &options).unwrap().tip_position();
    for i in 0..2 {
        let h = 1e-4;
        let (mut a, mut b) = (robot.clone(), robot.clone());
        a.tendons[i].set_tension(robot.tendons[i].tension() + h);
        b.tendons[i].set_tension(robot.tendons[i].tension() - h);
        let fd = (tip(&a) - tip(&b)) / (2.0 * h);
        let exact = sens.tension.fixed_view::<3, 1>(0, i).into_owned();
        eprintln!(
            "tension {i}: exact {:.6e}, differenced {:.6e}",
            exact.transpose(),
            fd.transpose()
        );
        // 1e-6 relative: central differences of h = 1e-4 N err by h^2 |x'''| and by
        // Newton's tolerance / h
        assert!((exact - fd).norm() < 1e-6 * fd.norm(), "tension {i}");
    }
    for axis in 0..3 {
        let h = 1e-5;
        let (mut a, mut b) = (robot.clone(), robot.clone());
        a.loads.tip_force[axis] += h;
        b.loads.tip_force[axis] -= h;
        let fd = (tip(&a) - tip(&b)) / (2.0 * h);
        let exact = sens.tip_force.fixed_view::<3, 1>(0, axis).into_owned();
        // 1e-6 relative, as above
        assert!(
            (exact - fd).norm() < 1e-6 * fd.norm(),
            "tip force {axis}: {exact} vs {fd}"
        );
    }
}

#[test]
fn kirchhoff_warm_starts_and_stability() {
    let robot = kirchhoff(&loaded_helix());
    let cold = collocation::solve(&robot, &Default::default()).unwrap();
    assert!(cold.report.stability.is_stable(), "{:?}", cold.report.stability);
    let mut moved = robot.clone();
    moved.tendons[1].set_tension(robot.tendons[1].tension() * 0.9);
    let warm = collocation::solve_from(&moved, &Default::default(), &cold).unwrap();
    let again = collocation::solve(&moved, &Default::default()).unwrap();
    eprintln!(
        "warm - cold = {:.1e} m, {} vs {} iterations",
        tip_distance(&warm, &again),
        warm.report.iterations,
        again.report.iterations
    );
    // 1e-9 m: both are solves to the default tolerance
    assert!(tip_distance(&warm, &again) < 1e-9);
}

#[test]
fn displacement_controlled_tendons_on_a_kirchhoff_rod() {
    let mut robot = kirchhoff(&two_segments());
    let tensioned = collocation::solve(&robot, &to(1e-10)).unwrap();
    // hold tendon 2 at the pull-in its tension needs plus 2 mm
    let q = tensioned.tendons[1].displacement + 2e-3;
    robot.tendons[1] = Tendon::pulled(robot.tendons[1].routing.clone(), q);
    let c = collocation::solve(&robot, &to(1e-10)).unwrap();
    let s = shooting::solve(&robot, &tight_shooting()).unwrap();
    let d = tip_distance(&c, &s);
    eprintln!(
        "pull-in {:.4} mm: tension {:.6} N (collocation), {:.6} N (shooting), tips {d:.1e} m apart",
        q * 1e3,
        c.tendons[1].tension,
        s.tendons[1].tension
    );
    // pulling further needs more than the 1.5 N it had
    assert!(c.tendons[1].tension > 1.5);
    // 1e-8 m: the cross-check's agreement elsewhere (tests/cross_check.rs)
    assert!(d < 1e-8, "{d:e}");
}

/// The inextensible elastica: a cantilever under a dead tip force P perpendicular to its
/// axis, alpha = P L^2 / EI, in Bisshopp and Drucker's closed form
/// (`cases::analytic::elastica_tip`, docs/validation.md). The Kirchhoff rod is that model
/// exactly; the Cosserat rod with the same section stretches by about P / EA.
#[test]
fn kirchhoff_cantilever_matches_the_inextensible_elastica() {
    let (length, ei) = (0.5, 2.0e-3);
    // EA and GA only scale the force unknown of the Kirchhoff rod; the Cosserat rod with
    // them stretches by P / EA = 4e-7 to 8e-6
    let rod = Rod::new(length, Section::explicit(1e4, 1e4, ei, ei, 1.5e-3));
    for alpha in [0.5, 3.0, 10.0] {
        let (x, z) = elastica_tip(alpha);
        let mut loads = Loads::none();
        loads.tip_force = Vector3::new(alpha * ei / (length * length), 0.0, 0.0);
        let robot = Robot::new(rod.clone()).with_loads(loads);
        let expected = Vector3::new(x * length, 0.0, z * length);
        let k = kirchhoff(&robot);
        let c = collocation::solve(&k, &to(1e-11)).unwrap();
        let s = shooting::solve(&k, &tight_shooting()).unwrap();
        let default = collocation::solve(&k, &Default::default()).unwrap();
        let cosserat = collocation::solve(&robot, &to(1e-11)).unwrap();
        let off = |p: Vector3<f64>| (p - expected).norm() / length;
        eprintln!(
            "alpha {alpha}: tip ({x:.12}, {z:.12}) L; collocation {:.1e} L (default settings {:.1e} L), \
             shooting {:.1e} L, Cosserat {:.1e} L",
            off(c.tip_position()),
            off(default.tip_position()),
            off(s.tip_position()),
            off(cosserat.tip_position())
        );
        // 1e-10 L: both solvers are asked for about 1e-11 L, the elastica is exact
        assert!(off(c.tip_position()) < 1e-10, "collocation, alpha {alpha}");
        assert!(off(s.tip_position()) < 1e-10, "shooting, alpha {alpha}");
        // 2e-7 L: the default tip tolerance, 1e-7 L, with the estimate's margin
        assert!(off(default.tip_position()) < 2e-7, "default settings, alpha {alpha}");
        // the stretch of the Cosserat rod is resolved: the test tells the models apart
        assert!(off(cosserat.tip_position()) > 1e-7, "Cosserat, alpha {alpha}");
    }
}

/// Tendons with friction (docs/friction.md) on the Kirchhoff rod: the two solvers agree, and
/// the capstan law holds on a precurved arc whose path friction does not change.
#[test]
fn friction_on_a_kirchhoff_rod() {
    let mut h = kirchhoff(&loaded_helix());
    h.tendons[4].friction = Some(tdcr::Friction::pull(0.1));
    let mut released = kirchhoff(&two_segments());
    released.tendons[0].friction = Some(tdcr::Friction {
        coefficient: 0.2,
        motion: tdcr::Motion::Release,
    });
    // The sensitivities' bordered system with friction (docs/friction.md) on this rod too.
    let options = collocation::Options::fixed(64);
    let solved = collocation::solve(&h, &options).unwrap();
    let exact = tdcr::tip_sensitivities(&h, &solved)
        .unwrap()
        .tension
        .fixed_view::<3, 1>(0, 4)
        .into_owned();
    let tip = |tau: f64| {
        let mut r = h.clone();
        r.tendons[4].set_tension(tau);
        collocation::solve(&r, &options).unwrap().tip_position()
    };
    let (tau, step) = (h.tendons[4].tension(), 1e-4);
    let differenced = (tip(tau + step) - tip(tau - step)) / (2.0 * step);
    // 1e-6 relative: as the frictionless sensitivities above
    assert!(
        (exact - differenced).norm() < 1e-6 * differenced.norm(),
        "{exact} vs {differenced}"
    );
    for (name, robot) in [("helix, pulled", h), ("two segments, released", released)] {
        let c = collocation::solve(&robot, &collocation::Options::fixed(128)).unwrap();
        let s = shooting::solve(&robot, &tight_shooting()).unwrap();
        let d = tip_distance(&c, &s);
        let delivered = |x: &Solution| x.tendons.iter().map(|t| t.delivered_tension).collect::<Vec<_>>();
        eprintln!(
            "{name}: collocation - shooting {d:.1e} m, delivered {:?} vs {:?} N",
            delivered(&c),
            delivered(&s)
        );
        // 1e-8 m: as tests/friction.rs on the Cosserat rod (collocation at 128 intervals)
        assert!(d < 1e-8, "{name}: {d:e}");
        for (a, b) in c.tendons.iter().zip(&s.tendons) {
            // 4e-8 relative: as tests/friction.rs
            assert!((a.delivered_tension - b.delivered_tension).abs() <= 4e-8 * a.tension.max(1.0));
        }
    }
    // A precurved arc of curvature 5 1/m over 0.2 m, stiff in bending (E = 1e22 Pa keeps it
    // in its reference shape to 1e-11), and inextensible: the straight tendon's path turns
    // through exactly 1 rad, and the delivered tension is exp(-mu) of the input
    let rod = Rod::solid_circle(0.2, 0.0004, 1e22, 0.3).with_precurvature(Vector3::new(0.0, 5.0, 0.0));
    let robot = kirchhoff(
        &Robot::new(rod)
            .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 2.0).with_friction(tdcr::Friction::pull(0.2))),
    );
    let s = shooting::solve(&robot, &tight_shooting()).unwrap();
    let ratio = s.tendons[0].delivered_tension / s.tendons[0].tension;
    // 1e-8 relative: as tests/friction.rs's capstan law
    assert!((ratio / (-0.2f64).exp() - 1.0).abs() < 1e-8, "{ratio}");
}

/// The error estimate with friction on a Kirchhoff rod (docs/friction.md, "Error estimate"):
/// case S with mu = 0.1 on its tendon solves at default settings, with an estimate that
/// meets the tolerance, matches the true error against a fine mesh and converges at order 4
/// (the order-6 rows once took the position rate from the force coordinate instead of v*,
/// a mesh-independent 5.6e-6 m that drove the refinement to its interval cap).
#[test]
fn the_error_estimate_with_friction_on_a_kirchhoff_rod() {
    let mut robot = kirchhoff(&cases::case_s());
    robot.tendons[0].friction = Some(tdcr::Friction::pull(0.1));
    let c = tdcr::solve(&robot, &Default::default()).unwrap();
    let estimate = c.report.error_estimate.expect("an estimate").tip_position;
    let fine = collocation::solve(&robot, &collocation::Options::fixed(1024)).unwrap();
    let truth = tip_distance(&c, &fine);
    let s = shooting::solve(&robot, &tight_shooting()).unwrap();
    eprintln!(
        "{} intervals: estimate {estimate:.6e} m, true error {truth:.6e} m, shooting {:.1e} m",
        c.report.intervals,
        tip_distance(&c, &s)
    );
    // The tolerance 1e-7 L, met on the first or second mesh (32 or 64 intervals) as on the
    // frictionless rod: an estimate that converges needs no finer mesh
    assert!(estimate <= 1e-7 * robot.length(), "estimate {estimate:.2e} m");
    assert!(c.report.intervals <= 64, "{} intervals", c.report.intervals);
    // 1%: deferred correction is asymptotically exact (measured 5.0960e-9 against
    // 5.0963e-9 m, an O(h^6) difference; the 1024-interval reference is ~5e-14 m off)
    assert!(
        (estimate - truth).abs() <= 0.01 * truth,
        "estimate {estimate:.6e} against {truth:.6e} m"
    );
    // 1e-7 L: shooting's full slip agrees with the default solve to the solve's tolerance
    assert!(tip_distance(&c, &s) <= 1e-7 * robot.length());
    // Order 4: the estimate falls 16-fold per halving (12 to 20: the ratio 2^4 up to the
    // O(h^6) terms, measured 16.0 and 15.9 on 32/64/128 intervals)
    let estimates: Vec<f64> = [32, 64, 128]
        .iter()
        .map(|&n| {
            let x = collocation::solve(&robot, &collocation::Options::fixed(n)).unwrap();
            x.report.error_estimate.expect("an estimate").tip_position
        })
        .collect();
    eprintln!("estimates on 32/64/128 intervals: {estimates:?}");
    for w in estimates.windows(2) {
        assert!((12.0..20.0).contains(&(w[0] / w[1])), "estimates {estimates:?}");
    }
}

/// Beck's column (a cantilever under a follower tip force P) is the classical problem of an
/// inextensible, unshearable rod: it loses stability by flutter at P L^2 / EI = 20.051
/// (Euler-Bernoulli, uniform mass). The linearized dynamics (docs/stability.md) of the
/// Kirchhoff rod, with its force unknowns, finds it by bisection on the verdict.
#[test]
fn becks_column_on_a_kirchhoff_rod_flutters_at_20_05() {
    use tdcr::{Growth, Stability};
    let (length, radius, e): (f64, f64, f64) = (0.5, 1e-3, 200e9);
    let ei = e * std::f64::consts::PI * radius.powi(4) / 4.0;
    let verdict = |load: f64| {
        let mut loads = Loads::none();
        loads.follower_tip_force = Vector3::new(0.0, 0.0, -load * ei / (length * length));
        let robot = kirchhoff(&Robot::new(Rod::solid_circle(length, radius, e, 0.3)).with_loads(loads));
        let solution = collocation::solve(&robot, &collocation::Options::fixed(64)).unwrap();
        collocation::vibration(&robot, &solution).unwrap().stability
    };
    let (mut lo, mut hi) = (15.0, 25.0);
    assert!(verdict(lo).is_stable());
    for _ in 0..14 {
        let mid = 0.5 * (lo + hi);
        match verdict(mid) {
            Stability::Stable => lo = mid,
            Stability::Growing {
                growth: Growth::Flutter { .. },
                ..
            } => hi = mid,
            other => panic!("Beck's column at {mid}: {other}"),
        }
    }
    eprintln!("Beck's Kirchhoff column flutters at P L^2 / EI = {lo:.5}..{hi:.5}");
    // 1 %: as the Cosserat column's bound (tests/dynamics.rs): the mass's O(h^2)
    // interpolation and rotary inertia move it far less
    assert!((0.5 * (lo + hi) / 20.051 - 1.0).abs() < 0.01);
}
