//! A load path under a dead tip moment keeps to its branch (docs/stability.md, "Loads that
//! are not conservative: events on the load path"): random robot 254 of the sixth session's
//! run (a 0.335 m rod of radius 0.25 mm, four tendons, self weight mostly along -z) with a
//! dead tip moment of 7e-11 N m. Its path's long steps jumped to an upright state (tip
//! z +307 mm, unstable by divergence at 10.7 1/s, 2 conjugate points without the moment),
//! which nothing on a path under a dead moment could see; without the moment the same path
//! retries such a step shorter and ends on the stable hanging state.

use tdcr::collocation::{self, Options};
use tdcr::{PathTaken, Robot};

fn robot(name: &str) -> Robot {
    let path = format!("{}/tests/data/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    tdcr::io::parse(&text, &path).unwrap().robot
}

#[test]
fn a_tiny_dead_tip_moment_ends_the_load_path_where_the_conservative_one_does() {
    let with = robot("case254_1e-6");
    let without = robot("case254_0");
    let moved = collocation::solve(&with, &Options::default()).unwrap();
    let hanging = collocation::solve(&without, &Options::default()).unwrap();
    assert!(hanging.report.stability.is_stable(), "{}", hanging.report.stability);
    assert!(moved.report.stability.is_stable(), "{}", moved.report.stability);
    assert!(
        matches!(moved.report.path, PathTaken::LoadPath { .. }),
        "{:?}",
        moved.report.path
    );
    // It hangs (tip 236 mm below the base) where the jump stood upright (307 mm above).
    assert!(moved.tip_position().z < -0.2, "tip {:?}", moved.tip_position());
    // The moment moves the tip by at most about M L^2 / EI (2.3e-7 m), and each answer is
    // within the solve's tolerance (1e-7 L) of its exact state: measured 1.2e-8 m apart.
    let ei = with.rod.section_at(0.0).section.kbt[0];
    let l = with.length();
    let bound = with.loads.tip_moment.norm() * l * l / ei + 2.0 * 1e-7 * l;
    let apart = (moved.tip_position() - hanging.tip_position()).norm();
    assert!(apart < bound, "{apart:e} m apart, bound {bound:e} m");
    // Measured 30 Newton + 29 chord steps over 14 load steps (51 without the moment; 24
    // before, on the unstable state): a fifth to spare.
    assert!(moved.report.iterations <= 72, "{} iterations", moved.report.iterations);
}
