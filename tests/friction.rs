//! Friction between tendons and channels in full slip (docs/friction.md): the capstan law
//! on known paths, mu = 0 as the frictionless model, the inputs friction does not support.

use nalgebra::Vector3;
use tdcr::{Error, Friction, Motion, Robot, Rod, Routing, Tendon, cases, shooting};

/// A rod so stiff that tendon loads leave it in its reference shape: E = 1e22 Pa makes
/// tau r / (E I) about 1e-11 of the precurvature below, so the path is known to that level.
fn stiff_rod(u_star: Vector3<f64>) -> Rod {
    Rod::solid_circle(0.2, 0.0004, 1e22, 0.3).with_precurvature(u_star)
}

fn tight() -> shooting::Options {
    shooting::Options {
        integration_tolerance: 1e-12,
        ..Default::default()
    }
}

/// Delivered over input tension of a solved robot's tendon 0.
fn ratio(robot: &Robot, solve: impl Fn(&Robot) -> tdcr::Solution) -> f64 {
    let solution = solve(robot);
    let t = &solution.tendons[0];
    t.delivered_tension / t.tension
}

fn with_tendon(rod: Rod, routing: Routing, friction: Friction) -> Robot {
    Robot::new(rod).with_tendon(Tendon::new(routing, 2.0).with_friction(friction))
}

#[test]
fn capstan_law_on_a_planar_arc() {
    // A precurved arc of curvature 5 1/m over 0.2 m: a straight tendon's path turns through
    // theta = 1 rad (its tangent stays the backbone's).
    let (kappa, mu) = (5.0, 0.2);
    let theta = kappa * 0.2;
    for (motion, sign) in [(Motion::Pull, -1.0), (Motion::Release, 1.0)] {
        let robot = with_tendon(
            stiff_rod(Vector3::new(0.0, kappa, 0.0)),
            Routing::straight(0.008, 0.0),
            Friction {
                coefficient: mu,
                motion,
            },
        );
        let got = ratio(&robot, |r| shooting::solve(r, &tight()).unwrap());
        let want = (sign * mu * theta).exp();
        // 1e-8 relative: the path is the reference arc to ~1e-11, the integration at 1e-12
        assert!(
            (got / want - 1.0).abs() < 1e-8,
            "{motion:?}: ratio {got} against {want}"
        );
    }
}

#[test]
fn capstan_law_on_a_helix_counts_the_helix_turning() {
    // A straight rod and a helix of radius a and one turn per rod length: the path's tangent
    // turns at a w^2 / sqrt(1 + a^2 w^2) per unit s (w = 2 pi / L), with no bending at all.
    let (a, mu, length) = (0.008, 0.3, 0.2);
    let w = 2.0 * std::f64::consts::PI / length;
    let theta = length * a * w * w / (1.0 + a * a * w * w).sqrt();
    let robot = with_tendon(
        stiff_rod(Vector3::zeros()),
        Routing::helical(a, 1.0, 0.0),
        Friction::pull(mu),
    );
    let want = (-mu * theta).exp();
    let got = ratio(&robot, |r| shooting::solve(r, &tight()).unwrap());
    // 1e-8 relative: as for the arc
    assert!((got / want - 1.0).abs() < 1e-8, "shooting ratio {got} against {want}");
    let got = ratio(&robot, |r| tdcr::solve(r, &Default::default()).unwrap());
    // 1e-8 relative: as for the arc
    assert!(
        (got / want - 1.0).abs() < 1e-8,
        "collocation ratio {got} against {want}"
    );
    // The tension along the helix follows exp(-mu kappa s) at every point of the path.
    let solution = shooting::solve(&robot, &tight()).unwrap();
    for s in [0.05, 0.1, 0.15] {
        let tension = solution.tension_at(0, s).unwrap();
        let expected = 2.0 * (-mu * theta * s / length).exp();
        // 1e-8 relative: a constant turning rate, which the log-linear interpolation is exact for
        assert!(
            (tension / expected - 1.0).abs() < 1e-8,
            "s = {s}: {tension} against {expected}"
        );
    }
}

#[test]
fn zero_friction_is_the_frictionless_model_bit_for_bit() {
    for robot in [cases::case_s(), cases::case_h()] {
        let mut zero = robot.clone();
        for t in &mut zero.tendons {
            t.friction = Some(Friction::pull(0.0));
        }
        let a = shooting::solve(&robot, &Default::default()).unwrap();
        let b = shooting::solve(&zero, &Default::default()).unwrap();
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.tendons, b.tendons);
        let a = tdcr::solve(&robot, &Default::default()).unwrap();
        let b = tdcr::solve(&zero, &Default::default()).unwrap();
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.tendons, b.tendons);
    }
}

#[test]
fn friction_lowers_the_delivered_tension_and_the_bending() {
    let robot = cases::case_s();
    let mut rough = robot.clone();
    rough.tendons[0].friction = Some(Friction::pull(0.1));
    let smooth = shooting::solve(&robot, &Default::default()).unwrap();
    let solved = shooting::solve(&rough, &Default::default()).unwrap();
    let t = &solved.tendons[0];
    assert_eq!(t.tension, 2.94);
    assert!(t.delivered_tension < t.tension);
    // The tendon turns through about the tip angle (~90 degrees here): exp(-0.1 * pi / 2) = 0.855
    // bounds the loss from below; curvature is largest at the base, so the loss is a bit less.
    assert!(
        t.delivered_tension > 2.94 * (-0.1 * 2.0_f64).exp(),
        "{}",
        t.delivered_tension
    );
    // Less tension bends less: the tip moves back toward the straight rod (+x).
    assert!(solved.tip_position().x > smooth.tip_position().x);
    // Releasing delivers more than the input.
    rough.tendons[0].friction = Some(Friction {
        coefficient: 0.1,
        motion: Motion::Release,
    });
    let released = shooting::solve(&rough, &Default::default()).unwrap();
    assert!(released.tendons[0].delivered_tension > 2.94);
}

#[test]
fn bad_friction_is_an_error_that_names_the_field() {
    let check = |robot: &Robot, fragment: &str| match robot.validate() {
        Err(Error::InvalidInput { field, problem, hint }) => {
            assert_eq!(field, "tendons[0].friction");
            let text = format!("{problem} {hint}");
            assert!(text.contains(fragment), "{text}");
        }
        other => panic!("expected an invalid friction, got {other:?}"),
    };
    for mu in [-0.1, f64::NAN, f64::INFINITY] {
        let mut robot = cases::case_s();
        robot.tendons[0].friction = Some(Friction::pull(mu));
        check(&robot, "finite number >= 0");
    }
    let mut robot = cases::case_s();
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    robot.tendons[1] = robot.tendons[1].clone().ending_at(0.1);
    check(&robot, "s = 0.1 m");
}

#[test]
fn collocation_agrees_with_shooting_with_friction() {
    let mut s = cases::case_s();
    s.tendons[0].friction = Some(Friction::pull(0.1));
    let mut h = cases::case_h();
    h.tendons[4].friction = Some(Friction::pull(0.1));
    let mut released = cases::case_h();
    released.tendons[4].friction = Some(Friction {
        coefficient: 0.2,
        motion: Motion::Release,
    });
    for robot in [s, h, released] {
        let c = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(128)).unwrap();
        let sh = shooting::solve(&robot, &tight()).unwrap();
        let d = (c.tip_position() - sh.tip_position()).norm();
        // 1e-8 m: collocation error ~1.4e-9 m at 128 intervals plus shooting at 1e-12
        assert!(d < 1e-8, "tips differ by {d:.3e} m");
        let (tc, ts) = (c.tendons.iter(), sh.tendons.iter());
        for (a, b) in tc.zip(ts) {
            // 4e-8 relative: the tips' 1e-8 m relative to the 0.24 m rod (the profile converges with the shape)
            let diff = (a.delivered_tension - b.delivered_tension).abs();
            assert!(
                diff <= 4e-8 * a.tension.max(1.0),
                "delivered {} vs {}",
                a.delivered_tension,
                b.delivered_tension
            );
        }
        // The linearized dynamics with the capstan rows (docs/stability.md, "Tendons with friction")
        assert_eq!(c.report.stability, tdcr::Stability::Stable);
    }
}

/// A tendon with friction that ends inside the rod: its termination's jump rows carry the
/// delivered tension, whose log tension is then an unknown of an interior node (the
/// staircase's termination columns in link rows); collocation against shooting, and the
/// default solve's global equilibrium.
#[test]
fn a_tendon_with_friction_that_ends_inside_the_rod_agrees_with_shooting() {
    let mut robot = cases::case_s();
    let length = robot.length();
    robot.tendons[0] = robot.tendons[0].clone().ending_at(0.6 * length);
    robot.tendons[0].set_tension(4.0);
    robot.tendons[0].friction = Some(Friction::pull(0.2));
    let c = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(128)).unwrap();
    let sh = shooting::solve(&robot, &tight()).unwrap();
    let d = (c.tip_position() - sh.tip_position()).norm();
    // 1e-8 m: as for the tendons ending at the tip above (collocation at 128 intervals,
    // shooting at 1e-12)
    assert!(d < 1e-8, "tips differ by {d:.3e} m");
    let (a, b) = (&c.tendons[0], &sh.tendons[0]);
    // 4e-8 relative, as above
    assert!(
        (a.delivered_tension - b.delivered_tension).abs() <= 4e-8 * a.tension,
        "delivered {} vs {}",
        a.delivered_tension,
        b.delivered_tension
    );
    assert!(a.delivered_tension < 0.99 * a.tension, "friction holds back tension");
    let solved = tdcr::solve(&robot, &Default::default()).unwrap();
    let e = tdcr::analysis::equilibrium::imbalance(&robot, &solved);
    // 1e-8: the bound of global_equilibrium_holds_with_friction (the solver's tolerance in
    // the wrenches relative to the tension)
    assert!(e.max() < 1e-8, "imbalance {e:?}");
}

/// Case S with friction on its tendon and case H with friction on its helix (mu = 0.1).
fn rough_cases() -> [Robot; 2] {
    let mut s = cases::case_s();
    s.tendons[0].friction = Some(Friction::pull(0.1));
    let mut h = cases::case_h();
    h.tendons[4].friction = Some(Friction::pull(0.1));
    [s, h]
}

#[test]
fn collocation_with_friction_converges_at_order_four() {
    for robot in rough_cases() {
        let reference = shooting::solve(&robot, &tight()).unwrap();
        let error = |intervals: usize| {
            let c = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(intervals)).unwrap();
            let tension = c
                .tendons
                .iter()
                .zip(&reference.tendons)
                .map(|(a, b)| (a.delivered_tension - b.delivered_tension).abs());
            (
                (c.tip_position() - reference.tip_position()).norm(),
                tension.fold(0.0, f64::max),
            )
        };
        let (coarse, fine) = (error(16), error(32));
        let order = (coarse.0 / fine.0).log2();
        // 3.7..4.5: h^4 with the pre-asymptotic drift of 16 -> 32 intervals
        assert!(
            (3.7..4.5).contains(&order),
            "tip order {order:.2} ({:.2e} -> {:.2e})",
            coarse.0,
            fine.0
        );
        let order = (coarse.1 / fine.1).log2();
        assert!(
            (3.5..4.7).contains(&order),
            "tension order {order:.2} ({:.2e} -> {:.2e})",
            coarse.1,
            fine.1
        );
    }
}

#[test]
fn the_error_estimate_covers_friction_at_default_settings() {
    for robot in rough_cases() {
        let reference = shooting::solve(&robot, &tight()).unwrap();
        let c = tdcr::solve(&robot, &Default::default()).unwrap();
        let estimate = c.report.error_estimate.expect("an estimate");
        let truth = (c.tip_position() - reference.tip_position()).norm();
        // The tolerance 1e-7 L is met, and the estimate is within a factor 3 of the truth
        // (deferred correction is asymptotically exact; shooting at 1e-12 is ~1e-11 m off)
        assert!(truth <= 1e-7 * robot.length(), "true error {truth:.2e} m");
        assert!(
            truth <= 3.0 * estimate.tip_position + 1e-10 && estimate.tip_position <= 3.0 * truth + 1e-10,
            "estimate {:.2e} against {truth:.2e}",
            estimate.tip_position
        );
    }
}

/// Where Newton with friction goes straight from the initial guess to a stable answer and
/// the first mesh is final (S at mu = 0.1), the solve runs no frictionless Newton
/// (docs/friction.md section 3, "Which start"): the report counts one mesh and one Newton
/// run, the one with friction. The answer is the one Newton with friction reaches from the
/// frictionless solution (`nearest`, whose frictionless start counts a mesh of its own) on
/// the same mesh.
#[test]
fn a_direct_solve_with_friction_runs_no_frictionless_newton() {
    use tdcr::collocation::{Equilibrium, Options};
    let [s, _] = rough_cases();
    let direct = tdcr::collocation::solve(&s, &Options::default()).unwrap();
    let report = &direct.report;
    assert_eq!(report.stability, tdcr::Stability::Stable, "{report:?}");
    assert_eq!(report.meshes, 1, "{report:?}");
    assert_eq!(report.iterations, report.history.len(), "{report:?}");
    let nearest = Options {
        equilibrium: Equilibrium::Nearest,
        ..Default::default()
    };
    let from_smooth = tdcr::collocation::solve(&s, &nearest).unwrap();
    assert_eq!(from_smooth.report.meshes, 2, "{:?}", from_smooth.report);
    assert_eq!(from_smooth.report.intervals, report.intervals);
    // 1e-10 m: the same discrete solution from two starts, each within Newton's stopping
    // test of it (extrapolated error below 1e-10 in the scaled unknowns, p / L with L =
    // 0.242 m); measured 4e-13 m.
    let apart = (direct.tip_position() - from_smooth.tip_position()).norm();
    assert!(apart < 1e-10, "{apart:e} m");
}

#[test]
fn global_equilibrium_holds_with_friction() {
    let mut released = cases::case_h();
    released.tendons[4].friction = Some(Friction {
        coefficient: 0.3,
        motion: Motion::Release,
    });
    let [s, h] = rough_cases();
    for robot in [s, h, released] {
        for solution in [
            tdcr::solve(&robot, &Default::default()).unwrap(),
            shooting::solve(&robot, &tight()).unwrap(),
        ] {
            let e = tdcr::analysis::equilibrium::imbalance(&robot, &solution);
            // 1e-8: the solvers' tolerance (1e-7 L of tip error at default settings) in the
            // wrenches relative to the tension
            assert!(e.max() < 1e-8, "imbalance {e:?}");
        }
        // The tangential load matters: the frictionless shape is out of balance with the
        // input tension when the tendon loses a few percent of it along the way.
        let mut smooth = robot.clone();
        smooth.tendons.iter_mut().for_each(|t| t.friction = None);
        let solved = tdcr::solve(&robot, &Default::default()).unwrap();
        let delivered: Vec<f64> = solved.tendons.iter().map(|t| t.delivered_tension).collect();
        let held = tdcr::solve(&smooth.with_tensions(&delivered), &Default::default()).unwrap();
        assert!(tdcr::analysis::equilibrium::imbalance(&robot, &held).max() > 1e-3);
    }
}

#[test]
fn friction_in_the_robot_file_and_on_the_command_line() {
    let text = tdcr::io::example();
    let with = text.replacen(
        "tension = 2.94",
        "tension = 2.94\nfriction = 0.1\nmotion = \"release\"",
        1,
    );
    let file = tdcr::io::parse(&with, "friction.toml").unwrap();
    assert_eq!(
        file.robot.tendons[0].friction,
        Some(Friction {
            coefficient: 0.1,
            motion: Motion::Release
        })
    );
    // Written back and read again: the same friction.
    let again = tdcr::io::parse(&file.to_toml().unwrap(), "again.toml").unwrap();
    assert_eq!(again.robot.tendons[0].friction, file.robot.tendons[0].friction);
    // A bad coefficient is reported at its line, a bad motion by name.
    let bad = text.replacen("tension = 2.94", "tension = 2.94\nfriction = -1.0", 1);
    let message = tdcr::io::parse(&bad, "bad.toml").unwrap_err().to_string();
    assert!(
        message.contains("tendon[1].friction") && message.contains("finite number >= 0"),
        "{message}"
    );
    let bad = text.replacen("tension = 2.94", "tension = 2.94\nfriction = 0.1\nmotion = \"push\"", 1);
    assert!(tdcr::io::parse(&bad, "bad.toml").is_err());

    // `tdcr solve --friction 1=0.1 --format json`: the input and the delivered tension.
    let path = std::env::temp_dir().join(format!("tdcr-friction-{}.toml", std::process::id()));
    std::fs::write(&path, &text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tdcr"))
        .args([
            "solve",
            path.to_str().unwrap(),
            "--friction",
            "1=0.1",
            "--format",
            "json",
        ])
        .output()
        .unwrap();
    std::fs::remove_file(&path).ok();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tendon = &json["tendons"][0];
    assert_eq!(tendon["tension"], 2.94);
    let delivered = tendon["delivered_tension"].as_f64().unwrap();
    let mut robot = tdcr::io::parse(&text, "x.toml").unwrap().robot;
    robot.tendons[0].friction = Some(Friction::pull(0.1));
    let solved = tdcr::solve(&robot, &Default::default()).unwrap();
    // The JSON's number is the solution's, printed in full
    assert_eq!(delivered, solved.tendons[0].delivered_tension);
    // The linearized dynamics with the capstan rows (docs/stability.md, "Tendons with friction")
    assert_eq!(json["stability"]["verdict"], "stable");
}

#[test]
fn inverse_statics_with_friction_in_the_forward_model() {
    // Case S's tip with mu = 0.1 reached from tendon 1 at 1 N: the tension found is the
    // one that made it (the inverse model has the same friction), not the frictionless one.
    let [s, _] = rough_cases();
    let options = tdcr::fit::inverse::InverseOptions::new(5.0);
    let goal = tdcr::collocation::solve(&s, &options.solver).unwrap().tip_position();
    let mut start = s.clone();
    start.tendons[0].set_tension(1.0);
    let target = tdcr::fit::inverse::Target::position(goal);
    let found = tdcr::fit::inverse::solve_tensions(&start, &target, &options).unwrap();
    assert!(found.reachable);
    assert!((found.tip_position() - goal).norm() <= options.tolerance);
    let tension = found.solution.tendons[0].tension;
    // The tip moves about 0.3 m/N (tests/sensitivity.rs), so a tip within the tolerance
    // 1e-6 m (InverseOptions) holds the tension to a few 1e-6 N.
    assert!((tension - 2.94).abs() < 1e-4, "{tension}");
    // The frictionless model reaches the same tip with less tension (friction costs some).
    let mut smooth = start.clone();
    smooth.tendons[0].friction = None;
    let frictionless = tdcr::fit::inverse::solve_tensions(&smooth, &target, &options).unwrap();
    let needed = frictionless.solution.tendons[0].tension;
    assert!(needed < 2.9, "{needed}");
}

#[test]
fn branch_tracing_without_friction_says_so() {
    let [s, _] = rough_cases();
    // A model limit (front25): the robot is valid, the trace does not model its friction.
    match tdcr::collocation::trace(&s, tdcr::Parameter::Tension(0), 0.0, 2.94, &Default::default()) {
        Err(Error::ModelLimit { field, problem, .. }) => {
            assert_eq!(field, "tendons[0].friction");
            assert!(problem.contains("does not model friction yet"), "{problem}");
        }
        other => panic!("expected an error, got {other:?}"),
    }
    // Every tendon with friction is named (user24: the second was found only on the next try).
    let mut both = s.clone();
    both.tendons[3].friction = Some(tdcr::Friction::pull(0.2));
    match tdcr::collocation::trace(&both, tdcr::Parameter::Tension(0), 0.0, 2.94, &Default::default()) {
        Err(Error::ModelLimit { problem, hint, .. }) => {
            assert!(problem.contains("tendon 4's 0.2"), "{problem}");
            assert!(hint.contains("every tendon with friction to 0"), "{hint}");
        }
        other => panic!("expected an error, got {other:?}"),
    }
}

#[test]
fn an_elastic_tendon_with_friction_stretches_by_its_varying_tension() {
    // The stiff arc of the capstan test with an elastic straight tendon at r = 8 mm in the
    // bending plane: tau(s) = tau0 exp(-mu kappa s) along a reference path of speed
    // 1 - kappa r, so the stretch is tau0 (1 - kappa r) (1 - exp(-mu kappa L)) / (mu kappa E_t A_t).
    let (kappa, mu, r, tau0, stiffness, length) = (5.0, 0.2, 0.008, 2.0, 2000.0, 0.2);
    let robot = Robot::new(stiff_rod(Vector3::new(0.0, kappa, 0.0))).with_tendon(
        Tendon::new(Routing::straight(r, 0.0), tau0)
            .elastic(stiffness, 0.0)
            .with_friction(Friction::pull(mu)),
    );
    let want = tau0 * (1.0 - kappa * r) * (1.0 - (-mu * kappa * length).exp()) / (mu * kappa * stiffness);
    for solution in [
        tdcr::solve(&robot, &Default::default()).unwrap(),
        shooting::solve(&robot, &tight()).unwrap(),
    ] {
        let t = &solution.tendons[0];
        let stretch = t.displacement - (t.reference_length - t.length);
        // 1e-8 relative: the node quadrature is exact for cubics (h^4 on the exponential)
        assert!(
            (stretch / want - 1.0).abs() < 1e-8,
            "stretch {stretch:e} against {want:e}"
        );
    }
}

/// Where the rod's bending reverses inside it, each tendon's path stops turning: its turning
/// rate |t'| has a V there and its sliding tension, tau' = -+ mu tau |t'|, a jump in its
/// second derivative. The full-slip solve places a node at each such point
/// (docs/friction.md section 8, "honest19"), so its estimate covers its true error and its
/// mesh stays near a smooth solve's 32 intervals. Without the nodes, the first case's
/// estimate was 2.0 times below its true error (8.9e-11 m against 1.8e-10 m, on 46
/// intervals) and the second's 1.5 times (8.4e-10 m against 1.3e-9 m, 46 intervals).
#[test]
fn a_full_slip_solve_whose_bending_reverses_has_an_honest_estimate() {
    // Tendon 3 pulled at 1.47 N against tendon 1 held at 1 N and the rod's weight (both with
    // friction): the rod bends down near the base and up beyond. Tendon 1 at 2 N against a
    // tip moment of 0.02 N m: it bends down near the base and up near the tip.
    let mut opposite = cases::prototype().with_tensions(&[1.0, 0.0, 1.47, 0.0, 0.0]);
    for i in [0, 2] {
        opposite.tendons[i].friction = Some(Friction::pull(0.1));
    }
    let mut moment = cases::prototype().with_tensions(&[2.0, 0.0, 0.0, 0.0, 0.0]);
    moment.tendons[0].friction = Some(Friction::pull(0.1));
    moment.loads.tip_moment = Vector3::new(0.0, -0.02, 0.0);
    for robot in [opposite, moment] {
        let solution = tdcr::solve(&robot, &Default::default()).unwrap();
        // A fixed mesh of 8192 intervals, without nodes at the points or error control:
        // its error is the kink's, first order in h, measured within 1e-12 m of the
        // solve at 1e-11 L here (and the shooting solver at 1e-12 is ~1e-11 m off)
        let fine = tdcr::collocation::Options::fixed(8192);
        let reference = tdcr::collocation::solve(&robot, &fine).unwrap();
        let report = &solution.report;
        let estimate = report.error_estimate.expect("an estimate").tip_position;
        let error = (solution.tip_position() - reference.tip_position()).norm();
        assert_eq!(report.tolerance_met, Some(true));
        // a sliding solve's deferred correction is its error to a fraction of a percent
        // (measured 0.99 to 1.01 with the nodes), and the reference's 1e-12 m
        assert!(
            error <= 1.01 * estimate + 1e-12,
            "error {error:.3e} m against estimate {estimate:.3e} m ({} intervals)",
            report.intervals
        );
        // one node per tendon with friction at the point on the smooth solve's 32 intervals
        // (34 measured; without the nodes 46 and 98 for tendon 3 at 2.46 N)
        assert!(report.intervals <= 36, "{} intervals", report.intervals);
    }
}

/// A vanishing mu solves as mu = 0 does (issue 24: "At mu = 0 everything reduces to today's
/// model exactly"): where a kink of the sliding tension cannot move the answer by 1e-3 of
/// the tolerance, no node is placed at it (docs/friction.md section 8, "kinks20"), so the
/// mesh is the frictionless solve's and the tip moves by friction's own effect alone. On main
/// the kink nodes gave 34 intervals and moved the tip by 6.5e-12 m at mu = 1e-12.
#[test]
fn a_vanishing_mu_solves_on_the_frictionless_mesh() {
    // Tendon 3 at 1.47 N against tendon 1 at 1 N: the bending reverses, so each tendon with
    // friction has a point where it stops turning (honest19's first case).
    let frictionless = cases::prototype().with_tensions(&[1.0, 0.0, 1.47, 0.0, 0.0]);
    let plain = tdcr::solve(&frictionless, &Default::default()).unwrap();
    let mut vanishing = frictionless.clone();
    for i in [0, 2] {
        vanishing.tendons[i].friction = Some(Friction::pull(1e-12));
    }
    let solution = tdcr::solve(&vanishing, &Default::default()).unwrap();
    let nodes = |s: &tdcr::Solution| s.nodes.iter().map(|n| n.s).collect::<Vec<_>>();
    assert_eq!(solution.report.intervals, plain.report.intervals);
    assert_eq!(nodes(&solution), nodes(&plain));
    // friction's own effect is 2.4e-3 m per unit mu (2.4e-15 m here); the rest is Newton's
    // rounding, far below 1e-12 m
    let moved = (solution.tip_position() - plain.tip_position()).norm();
    assert!(moved < 1e-12, "tip moved by {moved:.2e} m");
    assert_eq!(solution.report.tolerance_met, Some(true));
    // the estimate widened by the kinks' bound (4.7e-17 m here) stays the frictionless one's
    // to the friction estimate's own rounding (measured 2.5e-4 relative)
    let estimate = |s: &tdcr::Solution| s.report.error_estimate.expect("an estimate").tip_position;
    assert!((estimate(&solution) / estimate(&plain) - 1.0).abs() < 1e-2);
}
