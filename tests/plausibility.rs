//! Issue 17, point 6: implausible scales are warnings with their figures (`Robot::plausibility`,
//! `tdcr check`, `tdcr solve` on standard error), a failed solve names them as its likely
//! cause, and each tendon's turns are the ones it makes over its own length.

use std::path::PathBuf;
use std::process::{Command, Output};
use tdcr::model::scales::{LoadSite, Warning};
use tdcr::{cases, collocation};

const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

/// Writes `text` to a fresh scratch file and runs `tdcr ARGS FILE`.
fn run(name: &str, args: &[&str], text: &str) -> Output {
    let dir: PathBuf = std::env::temp_dir().join(format!("tdcr-plausibility-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("robot.toml");
    std::fs::write(&file, text).unwrap();
    let out = Command::new(TDCR).args(args).arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    out
}

fn text(out: &[u8]) -> String {
    String::from_utf8_lossy(out).into_owned()
}

/// The example robot file with `edits` (from, to) applied; each `from` must be there.
fn example(edits: &[(&str, &str)]) -> String {
    let mut t = tdcr::io::example();
    for (from, to) in edits {
        assert!(t.contains(from), "the example lost `{from}`");
        t = t.replacen(from, to, 1);
    }
    t
}

#[test]
fn the_prototype_and_its_experiments_have_ordinary_scales() {
    assert!(cases::case_s().plausibility().is_empty());
    assert!(cases::case_h().plausibility().is_empty());
    for e in cases::table2() {
        assert!(e.robot().plausibility().is_empty(), "{}", e.label());
    }
}

/// The 500 m rod of 1 m radius and E = 200 Pa: length, modulus and self weight.
#[test]
fn a_500_m_rod_of_200_pa_is_warned_about_three_times() {
    let mut robot = cases::case_s();
    robot.rod = tdcr::Rod::solid_circle(500.0, 1.0, 200.0, cases::POISSON_RATIO);
    let w = robot.plausibility();
    assert!(w.contains(&Warning::Length { length: 500.0 }), "{w:?}");
    assert!(w.contains(&Warning::Modulus { youngs_modulus: 200.0 }), "{w:?}");
    let weight = w
        .iter()
        .find(|x| matches!(x, Warning::SelfWeight { .. }))
        .expect("self weight");
    // w L^3 / EI = 0.47 * 500^3 / (200 pi / 4): the closed form, to rounding
    let expected = 0.47 * 500f64.powi(3) / (200.0 * std::f64::consts::PI / 4.0);
    assert!((weight.figure() / expected - 1.0).abs() < 1e-12, "{}", weight.figure());
    // L / r = 500 is a plausible slenderness.
    assert!(!w.iter().any(|x| matches!(x, Warning::Slenderness { .. })), "{w:?}");
}

/// The limit tau r^2 = EI: 0.97 of it converges without a warning, 1.1 of it has no
/// solution and is warned about.
#[test]
fn tension_past_the_geometric_limit_is_the_named_cause() {
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    let limit = ei / cases::TENDON_OFFSET.powi(2);
    robot.tendons[0].set_tension(0.97 * limit);
    assert!(robot.plausibility().is_empty());
    robot.tendons[0].set_tension(1.1 * limit);
    let w = robot.plausibility();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(matches!(w[0], Warning::TendonBend { tendon: 0, .. }), "{w:?}");
    // 1e-12: tau r^2 / EI = 1.1 by construction, to rounding
    assert!((w[0].figure() - 1.1).abs() < 1e-12);
    assert!(matches!(
        collocation::solve(&robot, &collocation::Options::fixed(64)),
        Err(tdcr::Error::NotConverged { .. })
    ));
}

/// The limit concerns the bend the tendons cause: four tendons pulled against each other at
/// 150 N (2.3 times one tendon's limit each) cause no bend, draw no warning and solve
/// straight; two tendons side by side at 0.6 of the limit each bend the rod as one at 1.2.
#[test]
fn the_bend_limit_sums_the_tendons_moments() {
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    let limit = ei / cases::TENDON_OFFSET.powi(2);
    for i in 0..4 {
        robot.tendons[i].set_tension(150.0);
    }
    assert!(150.0 > 2.0 * limit);
    assert!(robot.plausibility().is_empty(), "{:?}", robot.plausibility());
    let solution = collocation::solve(&robot, &Default::default()).unwrap();
    // 1e-9 m: the four moments cancel to rounding; the rod (along world x) only shortens
    assert!(
        solution.tip_position().yz().norm() < 1e-9,
        "{}",
        solution.tip_position()
    );
    // Tendons 1 and 2 are 90 degrees apart: their moments add to sqrt(2) 0.6 limit r, and
    // each lies r / sqrt(2) along it: kappa r = 0.6 (no warning); a second tendon on tendon
    // 1's side instead makes 1.2.
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    robot.tendons[0].set_tension(0.6 * limit);
    robot.tendons[1].set_tension(0.6 * limit);
    assert!(robot.plausibility().is_empty(), "{:?}", robot.plausibility());
    robot.tendons[1] = tdcr::Tendon::new(tdcr::Routing::straight(cases::TENDON_OFFSET, 0.0), 0.6 * limit);
    let w = robot.plausibility();
    assert!(matches!(w[..], [Warning::TendonBend { .. }]), "{w:?}");
    // 1e-12: 1.2 by construction, to rounding
    assert!((w[0].figure() - 1.2).abs() < 1e-12, "{}", w[0].figure());
    assert!(
        w[0].to_string().contains("curvature x offset = 1.2 is past 1"),
        "{}",
        w[0]
    );
}

#[test]
fn loads_are_compared_with_the_bending_stiffness() {
    let mut robot = cases::case_s();
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    let l = cases::LENGTH;
    // F L^2 / EI = 200 at the tip, a moment of 11 turns at a point load half-way.
    robot.loads.tip_force = nalgebra::Vector3::new(0.0, 0.0, -200.0 * ei / (l * l));
    robot.loads.point.push(tdcr::PointLoad {
        s: l / 2.0,
        force: nalgebra::Vector3::zeros(),
        moment: nalgebra::Vector3::new(0.0, 22.0 * std::f64::consts::PI * ei / (l / 2.0), 0.0),
    });
    let w = robot.plausibility();
    assert!(
        w.iter().any(|x| matches!(
            x,
            Warning::Force {
                site: LoadSite::Tip,
                ..
            }
        )),
        "{w:?}"
    );
    let moment = w
        .iter()
        .find(|x| {
            matches!(
                x,
                Warning::Moment {
                    site: LoadSite::Point(0),
                    ..
                }
            )
        })
        .expect("moment warning");
    assert!(moment.to_string().contains("(11 turns)"), "{moment}");
    assert!(
        moment.to_string().starts_with("point load 1 (loads.point[1]) moment"),
        "{moment}"
    );
}

/// `tdcr check` lists the warnings (exit 0: they are not errors); the before was a bare OK.
#[test]
fn check_prints_the_warnings_with_their_figures() {
    let file = example(&[
        ("length = 0.242", "length = 500.0"),
        ("outer_radius = 0.0004", "outer_radius = 1.0"),
        ("youngs_modulus = 210e9", "youngs_modulus = 200"),
    ]);
    let out = run("big", &["check"], &file);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    for fragment in [
        "OK, with 3 warnings",
        "warning: rod length 500 m is outside the plausible 0.001 to 10 m",
        "warning: Young's modulus 200 Pa is outside the plausible 1e4 to 1e12 Pa",
        "warning: self weight w L^3/(EI) = 0.47 N/m x (500 m)^3 / 157 N m^2 = 3.74e5 is above 1000",
    ] {
        assert!(stdout.contains(fragment), "`{fragment}` not in\n{stdout}");
    }
}

/// A tension typed in mN: `solve` warns before solving and its failure names the cause
/// with the issue's figures (before: only "stalled ...; refine the mesh or check for
/// buckling").
#[test]
fn a_failed_solve_names_the_tension_past_the_geometric_limit() {
    let file = example(&[("tension = 2.94 ", "tension = 2940 ")]);
    let out = run("mN", &["solve"], &file);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    let cause = "the tendons bend the rod at s = 0 m with a moment of 23.5 N m, a curvature of 5570 1/m \
                 over EI = 0.00422 N m^2 (bend radius 1.8e-4 m); tendon 1 runs 0.008 m inside that bend, so \
                 curvature x offset = 44.6 is past 1";
    // The warning comes first, before the solve's error.
    let warned = stderr.find(&format!("robot.toml: {cause}")).expect("the warning");
    assert!(warned < stderr.find("error:").expect("the error"), "{stderr}");
    assert!(stderr.contains(&format!("  likely cause:\n    {cause}")), "{stderr}");
    assert!(stderr.contains("did not converge"), "{stderr}");
}

/// A warned robot that converges: the warning on standard error, exit code 0, the output
/// unchanged.
#[test]
fn a_converging_solve_keeps_its_exit_code_with_warnings() {
    let file = example(&[("youngs_modulus = 210e9", "youngs_modulus = 2e12")]);
    let out = run("stiff", &["solve", "--format", "json"], &file);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("Young's modulus 2e12 Pa is outside"), "{stderr}");
    assert!(text(&out.stdout).contains("\"converged\": true"));
}

/// Issue 17, point 4: a tendon ending at L/2 on one turn per rod length makes half a turn,
/// and `check` and the JSON of `solve` say so.
#[test]
fn a_tendon_ending_half_way_reports_half_a_turn() {
    let file = example(&[(
        "routing = { kind = \"helical\", radius = 0.008, turns_per_rod_length = 1.0, phase = 0.0 }   # m, -, rad\ntension = 0.0",
        "routing = { kind = \"helical\", radius = 0.008, turns_per_rod_length = 1.0, phase = 0.0 }\ntension = 1.0\nend = 0.121",
    )]);
    let out = run("half", &["check"], &file);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(
        stdout.contains("tendon 5: helical, radius 0.008 m, phase 0 rad, 0.5 turns over its 0.121 m (turns_per_rod_length 1 counts over L = 0.242 m), ends at s = 0.121 m"),
        "{stdout}"
    );
    let out = run("half-json", &["solve", "--format", "json"], &file);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(json["tendons"][4]["turns"], 0.5);
    assert_eq!(json["tendons"][0]["turns"], 0.0);
}

/// Issue 25: the bend warning said "no equilibrium exists past 1" on robots that then
/// converge. The prototype's one-turn helix at 1.01 times its limit EI / r^2 solves (its path
/// winds around the rod, so it keeps a tangent across the backbone), and so does a straight
/// tendon at 1.2 times its limit on a rod precurved against its bend (u* = -60 1/m: the bend
/// left is 90 1/m, kappa r = 0.72). The warning stays (the figure is past 1) and says what is
/// true of each.
#[test]
fn the_bend_warning_does_not_deny_equilibria_that_exist() {
    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    let ei = robot.rod.section_at(0.0).section.kbt[0];
    let limit = ei / cases::TENDON_OFFSET.powi(2);
    robot.tendons[4].set_tension(1.01 * limit);
    let w = robot.plausibility();
    assert!(
        matches!(
            w[..],
            [Warning::TendonBend {
                tendon: 4,
                winds: true,
                ..
            }]
        ),
        "{w:?}"
    );
    let text = w[0].to_string();
    assert!(!text.contains("no equilibrium exists"), "{text}");
    assert!(
        text.contains("it winds around the rod, so the path need not fold"),
        "{text}"
    );
    assert!(collocation::solve(&robot, &Default::default()).is_ok());

    let mut robot = cases::prototype();
    robot.loads = tdcr::Loads::none();
    robot.rod = robot
        .rod
        .clone()
        .with_precurvature(nalgebra::Vector3::new(0.0, -60.0, 0.0));
    robot.tendons[0].set_tension(1.2 * limit);
    let w = robot.plausibility();
    assert!(
        matches!(
            w[..],
            [Warning::TendonBend {
                tendon: 0,
                precurved: true,
                winds: false,
                ..
            }]
        ),
        "{w:?}"
    );
    let text = w[0].to_string();
    assert!(
        text.contains("unless loads or the rod's precurvature hold the bend back"),
        "{text}"
    );
    assert!(collocation::solve(&robot, &Default::default()).is_ok());
}
