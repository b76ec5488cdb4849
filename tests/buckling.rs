//! The imperfect Euler column of issue 25: a 0.5 m steel rod (radius 1 mm) standing along +z
//! under a dead tip force (eps P, 0, -P), no gravity, no tendons. The default solve must
//! return the stable state, buckled towards the imperfection past Euler's load
//! (docs/stability.md, "Branch switching"); the buckled tips are compared with the elastica.

mod common;

use common::column_elastica as elastica;
use nalgebra::Vector3;
use std::f64::consts::PI;
use tdcr::collocation::{self, Options};
use tdcr::{Loads, Robot, Rod, Solution};

const LENGTH: f64 = 0.5;
const RATIOS: [f64; 12] = [0.5, 0.9, 0.99, 1.01, 1.05, 1.1, 1.2, 1.3, 1.5, 2.0, 3.0, 5.0];
const IMPERFECTIONS: [f64; 5] = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1];

fn column(p: f64, eps: f64) -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, 0.001, 200e9, 0.3)).with_loads(Loads::none().with_tip_force(Vector3::new(
        eps * p,
        0.0,
        -p,
    )))
}

/// Euler's load of the clamped-free column, pi^2 EI / (4 L^2).
fn euler_load() -> f64 {
    let ei = column(0.0, 0.0).rod.section_at(0.0).section.kbt[0];
    PI * PI * ei / (4.0 * LENGTH * LENGTH)
}

fn solve(ratio: f64, eps: f64) -> Solution {
    collocation::solve(&column(ratio * euler_load(), eps), &Options::default())
        .unwrap_or_else(|e| panic!("P/Pcr {ratio}, eps {eps}: {e}"))
}

#[test]
fn the_imperfect_column_returns_the_stable_state_on_the_imperfections_side() {
    /// Issue 25's goal for the Newton + chord steps of one solve.
    const GOAL: usize = 50;
    let (mut worst, mut total, mut over) = (0, 0, Vec::new());
    for ratio in RATIOS {
        for eps in IMPERFECTIONS {
            let s = solve(ratio, eps);
            let (tip, report) = (s.tip_position(), &s.report);
            let case = format!(
                "P/Pcr {ratio}, eps {eps}: tip {tip:?}, {} {:?}",
                report.stability, report.path
            );
            assert!(report.stability.is_stable(), "{case}");
            assert!(report.notes.is_empty(), "{case}: {:?}", report.notes);
            // The natural branch turns onto the buckled one without turning back in the load.
            assert!(report.path.folds().is_empty(), "{case}");
            // Towards the imperfection; past Euler's load buckled (0.18 L at 1.01 P_cr and
            // eps 1e-5, the least)
            assert!(tip.x > 0.0, "{case}");
            if ratio > 1.0 {
                assert!(tip.x > 0.1 * LENGTH, "{case}");
            }
            worst = worst.max(report.iterations);
            total += report.iterations;
            if report.iterations > GOAL {
                over.push(case.clone());
            }
        }
    }
    eprintln!("most iterations: {worst}, all 60: {total}, over {GOAL}: {over:#?}");
    // Issue 25's goal: at most 50 Newton + chord steps in every case (measured 2-38, 1 207
    // for all 60, with the corrector's first step a Newton step at the predicted point,
    // docs/numerics.md "Corrector"; before it 5 cases at 1.5-5 P_cr with eps 1e-2 and 1e-1
    // needed 53-61)
    assert!(over.is_empty(), "{over:#?}");
}

#[test]
fn the_buckled_tip_matches_the_elastica() {
    for ratio in RATIOS.into_iter().filter(|&r| r > 1.0) {
        let s = solve(ratio, 1e-5);
        let (x, z) = elastica(ratio);
        let tip = s.tip_position() / LENGTH;
        eprintln!(
            "P/Pcr {ratio}: tip ({:.5}, {:.5}) L, elastica ({x:.5}, {z:.5}) L",
            tip.x, tip.z
        );
        // 1e-3 L: the imperfection of 1e-5 moves the tip by up to 4e-4 L just past P_cr
        // (measured between eps = 1e-5 and 1e-4, scaled down); extension and shear, which
        // the elastica leaves out, by about P / EA = 1e-5
        assert!(
            (tip.x - x).abs() < 1e-3 && (tip.z - z).abs() < 1e-3,
            "P/Pcr {ratio}: {tip:?}"
        );
    }
}

#[test]
fn the_perfect_column_picks_a_buckled_plane_holds_it_and_says_so() {
    // Below Euler's load the straight column, directly.
    for ratio in [0.5, 0.9, 0.99] {
        let s = solve(ratio, 0.0);
        assert!(s.report.stability.is_stable() && s.report.notes.is_empty());
        // 1e-12 m: straight up to rounding
        assert!(s.tip_position().xy().norm() < 1e-12);
    }
    // Past it the path crosses the bifurcation, whose kernel is two-dimensional (a round rod
    // buckles in every plane alike), takes one plane and holds it by the phase condition
    // (docs/stability.md, "Families of equilibria").
    let (mut worst, mut azimuths) = (0, Vec::new());
    for ratio in RATIOS.into_iter().filter(|&r| r > 1.0) {
        let s = solve(ratio, 0.0);
        let report = &s.report;
        let tip = s.tip_position();
        let case = format!("P/Pcr {ratio}: tip {tip:?}, {} {:?}", report.stability, report.path);
        assert!(report.stability.is_stable(), "{case}");
        // The switch at the bifurcation is no fold (the load does not turn back), and the
        // bifurcation is recorded where it was located: at P_cr / P, to 1e-4 relative (the
        // model's extension and shear move Euler's load by about P / EA = 1e-5 relative;
        // measured 4e-6, the location being to 1e-6 of the path)
        assert!(report.path.folds().is_empty(), "{case}");
        let bifurcations = report.path.bifurcations();
        assert!(
            bifurcations.len() == 1 && (bifurcations[0] * ratio - 1.0).abs() < 1e-4,
            "{case}"
        );
        assert!(
            report.notes.len() == 1
                && report.notes[0].contains("every rotation of this state about the base axis")
                && report.notes[0].contains("mirror image"),
            "{case}: {:?}",
            report.notes
        );
        let (x, z) = elastica(ratio);
        // 1e-3 L as above (without the imperfection's part)
        assert!((tip.xy().norm() / LENGTH - x).abs() < 1e-3, "{case}");
        assert!((tip.z / LENGTH - z).abs() < 1e-3, "{case}");
        azimuths.push(tip.y.atan2(tip.x));
        worst = worst.max(report.iterations);
        eprintln!("{case}: {} iterations", report.iterations);
    }
    // One plane for every load: the phase condition holds it along the whole branch (1e-3
    // rad: measured within 1.6e-4 rad of each other, the side picked at the bifurcation
    // depending a little on the point the switch starts from; before it the plane turned by
    // 30 deg between loads)
    for a in &azimuths {
        assert!((a - azimuths[0]).abs() < 1e-3, "{azimuths:?}");
    }
    // Issue 25's goal: at most 50 Newton + chord steps (measured 17-29, at most at 5 P_cr;
    // 17-34 before the corrector's Newton step at the predicted point, 40-165 before the
    // switch at the located bifurcation)
    assert!(worst <= 50, "{worst} iterations");
}

#[test]
fn a_warm_start_from_a_buckled_column_is_kept_after_a_small_tension_change() {
    // The buckled column at 1.5 P_cr (eps = 1e-5) with a straight tendon at (15 mm, 0), from
    // 0 to 0.01 N. The straight rod balances the new loads more nearly than the buckled warm
    // start (a smaller residual), and Newton from it reaches the unstable straight state;
    // the warm start's predicted step is small, so it is kept.
    let p = 1.5 * euler_load();
    let robot = |t: f64| column(p, 1e-5).with_tendon(tdcr::Tendon::new(tdcr::Routing::straight(0.015, 0.0), t));
    let first = collocation::solve(&robot(0.0), &Options::default()).unwrap();
    assert!(first.report.stability.is_stable());
    let next = collocation::solve_from(&robot(0.01), &Options::default(), &first).unwrap();
    let report = &next.report;
    assert_eq!(report.path, tdcr::PathTaken::Direct, "{report:?}");
    assert_eq!(report.load_steps, 0);
    // Measured 3 chord steps (24 iterations over 5 load steps before).
    assert!(report.iterations <= 5, "{} iterations", report.iterations);
    assert!(report.stability.is_stable());
    // The same state the load path from rest reaches: 1e-9 m, the solve's tolerance (5e-8
    // m) being an error bound of the discretization, which both share, the rest is
    // Newton's residual
    let cold = collocation::solve(&robot(0.01), &Options::default()).unwrap();
    let gap = (next.tip_position() - cold.tip_position()).norm();
    assert!(gap < 1e-9, "{gap:e}");
}

#[test]
fn a_perfect_column_with_two_bending_stiffnesses_buckles_in_its_weak_plane() {
    // The column's section with E Iyy 1.5 times E Ixx: Euler's load of the weak plane is the
    // round column's, the other 1.5 times it. The bifurcation at the first is simple (a
    // one-dimensional kernel), so the path picks a side but holds no family: bending about
    // body x, the tip moves along y only, and the note names the mirror state (the other
    // sign), not a family of rotations.
    let round = column(0.0, 0.0).rod.section_at(0.0).section;
    let (kse, kbt) = (round.kse, round.kbt);
    let section = tdcr::Section::explicit(kse[2], kse[0], kbt[0], 1.5 * kbt[1], kbt[2]);
    for ratio in [1.2, 2.0, 3.0] {
        let p = ratio * euler_load();
        let robot =
            Robot::new(Rod::new(LENGTH, section)).with_loads(Loads::none().with_tip_force(Vector3::new(0.0, 0.0, -p)));
        let s = collocation::solve(&robot, &Options::default()).unwrap_or_else(|e| panic!("P/Pcr {ratio}: {e}"));
        let (tip, report) = (s.tip_position(), &s.report);
        let case = format!(
            "P/Pcr {ratio}: tip {tip:?}, {} {:?}: {:?}",
            report.stability, report.path, report.notes
        );
        eprintln!("{case}: {} iterations", report.iterations);
        assert!(report.stability.is_stable(), "{case}");
        assert!(
            report.notes.len() == 1
                && report.notes[0].contains("mirror state")
                && !report.notes[0].contains("every rotation"),
            "{case}"
        );
        // The bifurcation where it was located: Euler's load of the weak plane,
        // pi^2 E Imin / (4 L^2), which is the round column's, to 1e-3 relative (issue 25; the
        // model's extension and shear move it by about 1e-5, measured 4e-6); no fold
        assert!(report.path.folds().is_empty(), "{case}");
        let bifurcations = report.path.bifurcations();
        assert!(
            bifurcations.len() == 1 && (bifurcations[0] * p / euler_load() - 1.0).abs() < 1e-3,
            "{case}"
        );
        // In the weak plane: 1e-9 L across it (rounding of a symmetric solve; the strong
        // plane's Euler load, 1.5 P_cr, is passed at 2 and 3 P_cr on the straight branch only)
        assert!(tip.x.abs() < 1e-9 * LENGTH, "{case}");
        let (x, z) = elastica(ratio);
        // 1e-3 L as for the round column
        assert!(
            (tip.y.abs() / LENGTH - x).abs() < 1e-3 && (tip.z / LENGTH - z).abs() < 1e-3,
            "{case}"
        );
    }
}

/// The gallery's snapping column (docs/gallery/column.toml: this rod under 3 N and its own
/// weight, buckled towards -x by a 10 mN imperfection, a tendon on the +x side) solved from
/// rest at tensions past the out-of-plane bifurcation of the buckled state (0.124 N in the
/// gallery's sweep): the load path crosses it with no stable branch to follow, and the robot
/// snaps (docs/stability.md, "Snapping from a bifurcation"). Every such tension gives the
/// stable state on the tendon's side; at 0.2 N the path ended on the unstable state on the
/// imperfection's side (tip x -400 mm) before, and at 0.13 and 0.15 N it went round the
/// swing of the bending plane for 400 load steps.
#[test]
fn the_snapping_column_past_its_bifurcation_is_stable_on_the_tendon_side_from_rest() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/gallery/column.toml")).unwrap();
    for tension in [0.13, 0.15, 0.2, 0.5] {
        let text = text.replace("tension = 0.0", &format!("tension = {tension}"));
        let robot = tdcr::io::parse(&text, "column.toml").unwrap().robot;
        let s = collocation::solve(&robot, &Options::default()).unwrap();
        let (tip, report) = (s.tip_position(), &s.report);
        let case = format!(
            "{tension} N: tip {tip:?}, {} {:?}: {:?}",
            report.stability, report.path, report.notes
        );
        eprintln!(
            "{case}: {} iterations, {} load steps",
            report.iterations, report.load_steps
        );
        assert!(report.stability.is_stable(), "{case}");
        assert!(matches!(report.path, tdcr::PathTaken::LoadPath { .. }), "{case}");
        // On the tendon's side, in the plane of the loads: measured 399.2-399.6 mm (0.8 L);
        // y is rounding of a solve symmetric about the x-z plane
        assert!(tip.x > 0.39 && tip.y.abs() < 1e-9, "{case}");
        // No crawl round the swing of the bending plane: measured 6-71 load steps (400 before)
        assert!(report.load_steps < 100, "{case}");
    }
}

/// Issue 25: a solve whose load path cannot be followed returns Newton's root from its guess
/// and says so, in its label (`fallback`, once `direct`) and in a note. Since the corrector's
/// first step became a Newton step at the predicted point (2026-12-06) no default solve of the
/// sweep tests' payload robot, warm or cold, and none of 10 000 random robots
/// (tests/properties.rs) falls back; this case limits Newton through the public options. The
/// perfect column at 5 P_cr, from a 4-interval mesh with one Newton iteration per solve:
/// Newton from the straight guess converges at once to the straight column, unstable in both
/// bending planes, so the load path is followed; past Euler's load (20 % of the way) the
/// buckled shape needs a finer mesh, where one iteration cannot converge the interpolated
/// shape, and the path stops there.
#[test]
fn a_fallback_root_is_labelled_as_one() {
    let robot = column(5.0 * euler_load(), 0.0);
    let options = Options {
        intervals: 4,
        max_iterations: 1,
        ..Default::default()
    };
    let s = collocation::solve(&robot, &options).unwrap();
    let report = &s.report;
    assert_eq!(report.path, tdcr::PathTaken::Fallback, "{report:?}");
    assert_eq!(report.path.name(), "fallback");
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("the load path could not be followed") && n.contains("could not move to a finer mesh")),
        "{:?}",
        report.notes
    );
    // The answer is the fallback root, with its own verdict: Newton's root from the guess,
    // which `nearest` returns with the same options (the straight column; 1e-12 m: both are
    // straight up to rounding), unstable in both bending planes.
    let nearest = Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..options.clone()
    };
    let root = collocation::solve(&robot, &nearest).unwrap();
    assert!((s.tip_position() - root.tip_position()).norm() < 1e-12);
    assert!(s.tip_position().xy().norm() < 1e-12, "{:?}", s.tip_position());
    assert!(
        matches!(report.stability, tdcr::Stability::Unstable { directions: 2, .. }),
        "{}",
        report.stability
    );
    // With two or three iterations the path moves to the finer mesh and reaches a buckled
    // state. These solves panicked before 2026-12-06, with either corrector (index out of
    // bounds): the landing on the family's branch built its point with the unknowns of the
    // path's first mesh.
    for (ratio, intervals, max_iterations) in [(5.0, 4, 2), (5.0, 4, 3), (5.0, 8, 2), (50.0, 4, 2), (50.0, 8, 2)] {
        let robot = column(ratio * euler_load(), 0.0);
        let options = Options {
            intervals,
            max_iterations,
            ..Default::default()
        };
        let s = collocation::solve(&robot, &options).unwrap();
        let case = format!("{ratio} P_cr, {intervals} intervals, {max_iterations} iterations");
        assert!(s.report.stability.is_stable(), "{case}: {}", s.report.stability);
        assert!(matches!(s.report.path, tdcr::PathTaken::LoadPath { .. }), "{case}");
    }
}
