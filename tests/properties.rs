//! Property tests over random physical robots at default settings: collocation either
//! returns a solution that is in global equilibrium, has orthonormal rotations and finite
//! values everywhere, a positive semi-definite tip compliance when it is reported stable, the
//! same verdict from the linearized dynamics as from the conjugate-point test, and is within its tolerance of a 4x finer mesh with an error estimate
//! that is never below a third of the true error, or a typed error. Never a panic.
//!
//! CI runs 300 cases (about 20 s). The long run (10 000 cases, about 5 minutes in release;
//! last run, with the load path and the stability verdict: 10 000 solved, no typed error,
//! true/estimate 0.983 to 1.034, all 10 000 within the tolerance, every stable one with a
//! positive semi-definite tip compliance, no failure):
//! `cargo test --release --test properties -- --ignored`.

mod common;

use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, TestRunner};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicUsize, Ordering};
use tdcr::analysis::equilibrium;
use tdcr::{Loads, Robot, Rod, Routing, Tendon, collocation};

/// Steel-like density (kg/m^3) and gravity (m/s^2) for the self weight of a random rod.
const DENSITY: f64 = 8000.0;
const GRAVITY: f64 = 9.81;

/// A random physical robot. Ranges (documented in docs/validation.md): length 0.05..1 m,
/// radius 0.2..2 mm, E 1..300 GPa, Poisson 0.25..0.45, 1..8 tendons at 1..10 mm (straight,
/// or helical with -2..2 turns), each ending in (0.3 L, L], tensions up to the one that bends
/// the whole rod through 2 pi, self weight 1..3 times the rod's own in a random direction,
/// a tip force up to 2 E I / L^2 in a random direction.
fn robot() -> impl Strategy<Value = Robot> {
    let rod = (0.05f64..1.0, 0.2e-3f64..2e-3, 1e9f64..300e9, 0.25f64..0.45);
    let tendon = (
        0.001f64..0.01,
        0.0..2.0 * PI,
        prop::bool::ANY,
        -2.0f64..2.0,
        0.3f64..1.0,
        prop::bool::ANY,
        0.0f64..1.0,
    );
    let direction = (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0);
    (
        rod,
        prop::collection::vec(tendon, 1..=8),
        1.0f64..3.0,
        direction.clone(),
        0.0f64..2.0,
        direction,
    )
        .prop_map(|((length, radius, e, nu), tendons, weight, down, tip, tip_dir)| {
            let rod = Rod::solid_circle(length, radius, e, nu);
            let ei = rod.section_at(0.0).section.kbt[0];
            let w = weight * DENSITY * GRAVITY * PI * radius * radius;
            let down = Vector3::new(down.0, down.1, down.2 - 1.5); // mostly downward, never zero
            let tip_dir = Vector3::new(tip_dir.0, tip_dir.1, tip_dir.2 + 1e-3);
            let mut robot = Robot::new(rod).with_loads(
                Loads::self_weight(w, down).with_tip_force(tip_dir.normalize() * tip * ei / (length * length)),
            );
            let count = tendons.len() as f64;
            for (offset, angle, helical, turns, end, at_tip, pull) in tendons {
                let routing = if helical {
                    Routing::helical(offset, turns, angle)
                } else {
                    Routing::straight(offset * angle.cos(), offset * angle.sin())
                };
                // Tension that bends the rod through 2 pi by itself, shared among the tendons.
                let tension = pull * 2.0 * PI * ei / (offset * length) / count;
                let mut t = Tendon::new(routing, tension);
                if !at_tip {
                    t = t.ending_at(end * length);
                }
                robot = robot.with_tendon(t);
            }
            robot
        })
}

/// How a solved robot's error compares with its estimate and the tolerance.
#[derive(Clone, Copy, Debug)]
struct Accuracy {
    /// Tip position error against the solution on a 4x finer mesh (m).
    error: f64,
    /// The solver's own estimate of it (m).
    estimate: f64,
    /// Whether the error is within the tolerance.
    within: bool,
}

/// Counts of (stable, unstable) states whose two verdicts agreed.
static AGREED: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// The verdict of the linearized dynamics agrees with the conjugate-point test's: stable
/// with stable, divergence with unstable (a conservative system cannot flutter).
fn agree_with_dynamics(robot: &Robot, solution: &tdcr::Solution) -> Result<(), TestCaseError> {
    let modes = collocation::vibration(robot, solution).map_err(|e| TestCaseError::fail(format!("vibration: {e}")))?;
    use tdcr::{Growth, Stability};
    match (&solution.report.stability, &modes.stability) {
        (Stability::Stable, Stability::Stable) => AGREED[0].fetch_add(1, Ordering::Relaxed),
        (
            Stability::Unstable { .. },
            Stability::Growing {
                growth: Growth::Divergence,
                ..
            },
        ) => AGREED[1].fetch_add(1, Ordering::Relaxed),
        (Stability::Unknown { .. }, _) => 0,
        (a, b) => {
            return Err(TestCaseError::fail(format!(
                "conjugate points say {a}, the linearized dynamics {b} (eigenvalues {:?})",
                &modes.eigenvalues[..modes.eigenvalues.len().min(4)]
            )));
        }
    };
    Ok(())
}

/// States solved, and stable, with every tendon held at the pull-in of the tension solve.
static HELD: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// The same state with every tendon held at its solved pull-in (displacement control) is an
/// equilibrium whose verdict (docs/stability.md, "Displacement-controlled tendons") has at
/// most the constant-tension state's unstable directions (a length constraint can only
/// stabilize): stable where the tension solve is stable.
fn held_at_pull_ins(robot: &Robot, solution: &tdcr::Solution) -> Result<(), TestCaseError> {
    let mut held = robot.clone();
    for (t, state) in held.tendons.iter_mut().zip(&solution.tendons) {
        t.set_displacement(state.displacement);
    }
    let Ok(other) = collocation::solve_from(&held, &Default::default(), solution) else {
        return Ok(());
    };
    // 1e-6 L: the same state, to the two solves' tolerances (1e-7 L each) with room.
    if (other.tip_position() - solution.tip_position()).norm() > 1e-6 * robot.length() {
        return Ok(());
    }
    use tdcr::Stability;
    let directions = |s: &Stability| match s {
        Stability::Stable => Some(0),
        Stability::Unstable { directions, .. } => Some(*directions),
        _ => None,
    };
    HELD[0].fetch_add(1, Ordering::Relaxed);
    if let (Some(tension), Some(pulled)) = (
        directions(&solution.report.stability),
        directions(&other.report.stability),
    ) {
        prop_assert!(
            pulled <= tension,
            "held at the pull-ins {}, at constant tensions {}",
            other.report.stability,
            solution.report.stability
        );
        if pulled == 0 {
            HELD[1].fetch_add(1, Ordering::Relaxed);
        }
    } else if directions(&solution.report.stability).is_some() {
        return Err(TestCaseError::fail(format!(
            "no verdict held at the pull-ins: {}",
            other.report.stability
        )));
    }
    Ok(())
}

/// Checks the property for one robot; returns its accuracy if it was solved.
fn check(robot: &Robot) -> Result<Option<Accuracy>, TestCaseError> {
    let length = robot.length();
    // The default error control (tip to 1e-7 L and 1e-7 rad, from 32 intervals, cap 8192).
    let options = collocation::Options::default();
    let tolerance = options.tolerance.unwrap();
    let solution = match collocation::solve(robot, &options) {
        Ok(s) => s,
        // A typed error is an acceptable outcome, but its message must say something.
        Err(e) => {
            prop_assert!(!e.to_string().is_empty());
            prop_assert!(
                !matches!(e, tdcr::Error::InvalidInput { .. }),
                "valid robot rejected: {e}"
            );
            return Ok(None);
        }
    };
    for n in &solution.nodes {
        let values =
            n.p.iter()
                .chain(n.R.iter())
                .chain(n.v.iter())
                .chain(n.u.iter())
                .chain(n.n.iter())
                .chain(n.m.iter());
        prop_assert!(values.clone().all(|x| x.is_finite()), "non-finite value at s = {}", n.s);
    }
    // 1e-12: every R is built through exp from R0, never projected
    prop_assert!(solution.max_orthonormality_error() < 1e-12);
    // Equilibrium holds to the discretization error or the rounding floor of tiny loads
    // relative to the axial stiffness (30 eps EA over the load scale). The mesh controls the
    // tip to 1e-6 L, which bounds the balances near 1e-5 relative, ten times more for hanging
    // rods whose curvature bunches up (one such robot measured 1.1e-5); hence 1e-4.
    let e = equilibrium::imbalance(robot, &solution);
    let ea = robot.rod.section_at(0.0).section.kse.max();
    let floor = 30.0 * f64::EPSILON * ea
        / robot
            .tendons
            .iter()
            .map(|t| t.tension())
            .fold(robot.loads.tip_force.norm(), f64::max)
            .max(1e-12);
    prop_assert!(e.max() < 1e-4f64.max(floor), "imbalance {e:?}");
    // A state reported stable is a local minimum of the energy, so its tip compliance
    // d p(L) / d F(L) (dead tip force: conservative) is positive semi-definite. 1e-6 of the
    // largest eigenvalue: the sensitivities are differenced to about 1e-8 relative.
    if solution.report.stability.is_stable() {
        let c = tdcr::collocation::sensitivity::tip_sensitivities(robot, &solution)
            .map_err(|e| TestCaseError::fail(format!("sensitivities: {e}")))?
            .compliance();
        let block = c.fixed_view::<3, 3>(0, 0).into_owned();
        let eig = (0.5 * (block + block.transpose())).symmetric_eigenvalues();
        prop_assert!(
            eig.min() >= -1e-6 * eig.amax(),
            "stable but compliance eigenvalues {eig:?}"
        );
    }
    // The linearized dynamics (docs/stability.md, "Loads that are not conservative") agrees
    // with the conjugate-point test on these conservative loads: on the default answer
    // and on Newton's nearest equilibrium, which is unstable for some robots.
    agree_with_dynamics(robot, &solution)?;
    let nearest = collocation::Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    if let Ok(other) = collocation::solve(robot, &nearest) {
        agree_with_dynamics(robot, &other)?;
    }
    held_at_pull_ins(robot, &solution)?;
    // Agreement with a mesh 4x finer (its error is 256x smaller at order 4): within 3x the
    // tolerance on every robot, and never more than 3x the solver's own estimate where the
    // error is above rounding (1e-12 m); `run` asserts the tolerance itself on 99 %.
    let finer: Vec<f64> = solution
        .nodes
        .windows(2)
        .flat_map(|w| (0..4).map(move |i| w[0].s + 0.25 * i as f64 * (w[1].s - w[0].s)))
        .collect();
    let refined = collocation::solve_from(
        robot,
        &collocation::Options {
            mesh: Some(finer),
            tolerance: None,
            ..options.clone()
        },
        &solution,
    );
    let Ok(refined) = refined else {
        return Ok(None);
    };
    let error = (refined.tip_position() - solution.tip_position()).norm();
    let estimate = solution.report.error_estimate.map_or(f64::NAN, |e| e.tip_position);
    prop_assert!(
        error < 3.0 * tolerance * length,
        "true tip error {error:.3e} m above 3x the tolerance {:.3e} m",
        tolerance * length
    );
    prop_assert!(
        error <= 1e-12 || estimate >= error / 3.0,
        "estimate {estimate:.3e} m below a third of the true error {error:.3e} m"
    );
    Ok(Some(Accuracy {
        error,
        estimate,
        within: error <= tolerance * length,
    }))
}

/// Runs the property on `cases` random robots (a fixed seed) and asserts that the ratio of
/// true error to estimate lies in `band` on every robot whose error is above rounding.
fn run(cases: u32, band: (f64, f64)) {
    let solved = AtomicUsize::new(0);
    let accuracy = std::sync::Mutex::new(Vec::new());
    let config = Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    };
    // A fixed seed: the same robots every run, so CI is deterministic.
    let mut runner = TestRunner::new_with_rng(
        config,
        proptest::test_runner::TestRng::deterministic_rng(config_algorithm()),
    );
    runner
        .run(&robot(), |robot| {
            if let Some(a) = check(&robot)? {
                solved.fetch_add(1, Ordering::Relaxed);
                accuracy.lock().unwrap().push(a);
            }
            Ok(())
        })
        .unwrap();
    let solved = solved.load(Ordering::Relaxed);
    eprintln!("{solved} of {cases} random robots solved, the rest returned typed errors");
    let agreed = AGREED.each_ref().map(|a| a.load(Ordering::Relaxed));
    eprintln!(
        "the linearized dynamics agreed with the conjugate-point test on {} stable and {} unstable states",
        agreed[0], agreed[1]
    );
    let held = HELD.each_ref().map(|a| a.load(Ordering::Relaxed));
    eprintln!(
        "held at their pull-ins, {} states solved again, {} of them stable",
        held[0], held[1]
    );
    let accuracy = accuracy.into_inner().unwrap();
    let within = accuracy.iter().filter(|a| a.within).count();
    let mut ratios: Vec<f64> = accuracy
        .iter()
        .filter(|a| a.error > 1e-12)
        .map(|a| a.error / a.estimate)
        .collect();
    ratios.sort_by(f64::total_cmp);
    if let (Some(&lo), Some(&hi)) = (ratios.first(), ratios.last()) {
        eprintln!(
            "true/estimate over {} robots with errors above 1e-12 m: min {lo:.3}, median {:.3}, \
             99th percentile {:.3}, max {hi:.3}; {within} of {solved} within the tolerance",
            ratios.len(),
            ratios[ratios.len() / 2],
            ratios[(ratios.len() * 99) / 100]
        );
        // The estimate is asymptotically exact (docs/numerics.md, "Error control"): the
        // band docs/numerics.md and docs/validation.md give for these robots.
        assert!(
            band.0 <= lo && hi <= band.1,
            "true/estimate from {lo:.3} to {hi:.3}, outside {band:?}"
        );
    }
    // The default tolerance holds on at least 99 % of the solved robots (issue 13).
    assert!(
        within as f64 >= 0.99 * accuracy.len() as f64,
        "only {within} of {} within the tolerance",
        accuracy.len()
    );
    // Most random robots are well within reach: a test where nothing converges proves nothing.
    assert!(solved as f64 >= 0.8 * cases as f64, "only {solved} of {cases} solved");
}

fn config_algorithm() -> proptest::test_runner::RngAlgorithm {
    proptest::test_runner::RngAlgorithm::ChaCha
}

#[test]
fn random_robots_are_solved_or_fail_cleanly() {
    // Measured 0.986 to 1.012 on these 300 robots; 0.98 to 1.02 leaves room for the rounding
    // differences between CPUs with and without FMA, which move the smallest errors.
    run(300, (0.98, 1.02));
}

/// The long run: `cargo test --release --test properties -- --ignored`.
#[test]
#[ignore = "long: 10 000 random robots, about 5 minutes in release"]
fn ten_thousand_random_robots() {
    // The last long run measured 0.983 to 1.034 (module docs); the same room as above.
    run(10_000, (0.97, 1.05));
}

/// At a tight tolerance the answer is the order-6 one with its estimate (docs/numerics.md,
/// "The order-6 answer"). For each of `cases` random robots solved at `tolerance` (relative
/// to L): (true error, what the reference cannot resolve, estimate), for the tip position
/// (relative to L) and the tip rotation (rad), against the same solution re-solved on a mesh 32x finer
/// (order 4: 32^4 ~ 1e6 times smaller truncation errors); the reference's own uncertainty
/// is its distance from a 16x finer mesh (mostly rounding). Also the final meshes.
fn tight_errors(cases: u32, tolerance: f64) -> (Vec<[f64; 3]>, Vec<usize>) {
    let errors = std::sync::Mutex::new(Vec::new());
    let meshes = std::sync::Mutex::new(Vec::new());
    let config = Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(
        config,
        proptest::test_runner::TestRng::deterministic_rng(config_algorithm()),
    );
    runner
        .run(&robot(), |robot| {
            let options = collocation::Options {
                tolerance: Some(tolerance),
                ..Default::default()
            };
            let Ok(solution) = collocation::solve(&robot, &options) else {
                return Ok(());
            };
            let refined = |k: usize| common::on_split_mesh(&robot, &solution, k).ok();
            let (Some(reference), Some(check)) = (refined(32), refined(16)) else {
                return Ok(());
            };
            let e = solution.report.error_estimate.expect("an estimate");
            let rotation =
                |a: &tdcr::Solution, b: &tdcr::Solution| tdcr::so3::log(&(a.tip().R.transpose() * b.tip().R)).norm();
            let position = |a: &tdcr::Solution, b: &tdcr::Solution| (a.tip_position() - b.tip_position()).norm();
            meshes.lock().unwrap().push(solution.report.intervals);
            let mut out = errors.lock().unwrap();
            let length = robot.length();
            // The robots whose estimate is below their error, as robot files for the
            // order6_miss example (docs/numerics.md, "Why the estimate was low ...").
            if let Ok(dir) = std::env::var("TDCR_DUMP_MISSES") {
                let pe = (position(&reference, &solution) - position(&reference, &check)) / e.tip_position;
                let re = (rotation(&reference, &solution) - rotation(&reference, &check)) / e.tip_rotation;
                if pe > 1.0 || re > 1.0 {
                    let file = tdcr::io::RobotFile {
                        robot: robot.clone(),
                        solver: Default::default(),
                        disks: None,
                    };
                    let name = format!("{dir}/miss-{}.toml", out.len());
                    std::fs::write(&name, file.to_toml().unwrap()).unwrap();
                    eprintln!(
                        "MISS {name}: intervals {} position {pe:.3} rotation {re:.3}",
                        solution.report.intervals
                    );
                }
            }
            out.push([
                position(&reference, &solution) / length,
                position(&reference, &check) / length,
                e.tip_position / length,
            ]);
            out.push([
                rotation(&reference, &solution),
                rotation(&reference, &check),
                e.tip_rotation,
            ]);
            Ok(())
        })
        .unwrap();
    (errors.into_inner().unwrap(), meshes.into_inner().unwrap())
}

#[test]
fn tight_tolerances_get_an_estimate_never_below_the_true_error() {
    tight(60);
}

/// The long run of the order-6 answer: `cargo test --release --test properties -- --ignored`.
/// With `TDCR_DUMP_MISSES=DIR` every robot whose estimate is below its error is written to DIR
/// as a robot file, for `cargo run --release --example order6_miss -- FILE`.
#[test]
#[ignore = "long: 600 random robots at 1e-10 L, about 60 s in release"]
fn tight_tolerances_on_six_hundred_random_robots() {
    tight(600);
}

/// Runs the order-6 property on `cases` random robots at 1e-10 L.
fn tight(cases: u32) {
    let tolerance = 1e-10;
    let (errors, meshes) = tight_errors(cases, tolerance);
    // Most robots are solved: a test where nothing converges proves nothing.
    assert!(
        meshes.len() as f64 >= 0.8 * cases as f64,
        "only {} of {cases} solved",
        meshes.len()
    );
    // The true error beyond what the reference resolves is never above the estimate.
    let mut beyond: Vec<f64> = errors.iter().map(|[e, n, est]| (e - n).max(0.0) / est).collect();
    beyond.sort_by(f64::total_cmp);
    // Where the error is resolved (above 5e-12 L or rad and 20x the reference's
    // uncertainty), the plain ratio, which shows how sharp the estimate is.
    let mut sharp: Vec<f64> = errors
        .iter()
        .filter(|[e, n, _]| *e > 5e-12 && *e > 20.0 * n)
        .map(|[e, _, est]| e / est)
        .collect();
    sharp.sort_by(f64::total_cmp);
    let mut sorted = meshes.clone();
    sorted.sort_unstable();
    eprintln!(
        "{} robots at {tolerance:.0e} L: intervals median {}, max {}; (true - unresolved) / estimate median {:.3}, \
         max {:.3}; true / estimate where resolved ({} of {}): median {:.3}, max {:.3}",
        meshes.len(),
        sorted[sorted.len() / 2],
        sorted[sorted.len() - 1],
        beyond[beyond.len() / 2],
        beyond[beyond.len() - 1],
        sharp.len(),
        errors.len(),
        sharp[sharp.len() / 2],
        sharp[sharp.len() - 1],
    );
    assert!(
        beyond[beyond.len() - 1] <= 1.0,
        "an estimate below the true error: {:.3}",
        beyond[beyond.len() - 1]
    );
    // Every answer meets its tolerance in truth, beyond what the reference resolves.
    for [e, n, _] in &errors {
        assert!(
            e - n <= tolerance,
            "a true error of {e:.3e} (L or rad) above the tolerance"
        );
    }
}
