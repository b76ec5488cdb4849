//! EXPERIMENT (issue 25, fold14; not for merge): the property generator's random robots
//! (tests/properties.rs, the same strategy and fixed seed), each solved once at default
//! settings; prints one line per robot whose load path folds: case (counted from 0), tip (mm),
//! verdict, iterations, load steps, folds, whether it landed from its folds (note "snaps at
//! the fold"). `cargo run --release --example fold_scan -- CASES [i,j,k]` (only those cases),
//! with `TDCR_FOLD_MOTION=<delta>` for the experiment's route.

use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, TestRunner};
use std::f64::consts::PI;
use tdcr::{Loads, PathTaken, Robot, Rod, Routing, Tendon, collocation};

const DENSITY: f64 = 8000.0;
const GRAVITY: f64 = 9.81;

/// tests/properties.rs's `robot()`, verbatim.
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
            let down = Vector3::new(down.0, down.1, down.2 - 1.5);
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

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let cases: u32 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(300);
    let only: Option<Vec<usize>> = args
        .get(2)
        .map(|a| a.split(',').filter_map(|v| v.parse().ok()).collect());
    let dump = std::env::var("FOLD_SCAN_DUMP").ok();
    let from: usize = std::env::var("FOLD_SCAN_FROM")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let config = Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(
        config,
        proptest::test_runner::TestRng::deterministic_rng(proptest::test_runner::RngAlgorithm::ChaCha),
    );
    let counter = std::sync::atomic::AtomicUsize::new(0);
    runner
        .run(&robot(), |robot| {
            let i = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if only.as_ref().is_some_and(|o| !o.contains(&i)) || i < from {
                return Ok(());
            }
            if let Some(dir) = &dump {
                let file = tdcr::io::RobotFile {
                    robot: robot.clone(),
                    solver: Default::default(),
                    disks: None,
                };
                let _ = std::fs::write(format!("{dir}/case{i}.toml"), file.to_toml().unwrap());
            }
            eprintln!("fold_scan: case {i}");
            match collocation::solve(&robot, &collocation::Options::default()) {
                Ok(s) => {
                    let folds = match &s.report.path {
                        PathTaken::LoadPath { folds, .. } => folds.clone(),
                        _ => Vec::new(),
                    };
                    let landed = s.report.notes.iter().any(|n| n.contains("snaps at the fold"));
                    if only.is_some() || !folds.is_empty() || landed {
                        let t = s.tip_position() * 1e3;
                        println!(
                            "case {i}: tip ({:.6}, {:.6}, {:.6}) mm; {}; {} iterations ({} Newton), {} load steps; path {:?}; landed {landed}; notes {:?}",
                            t.x,
                            t.y,
                            t.z,
                            s.report.stability,
                            s.report.iterations,
                            s.report.newton_steps,
                            s.report.load_steps,
                            s.report.path,
                            s.report.notes
                        );
                    }
                }
                Err(e) => {
                    if only.is_some() {
                        println!("case {i}: error {e}");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}
