//! One cold default solve of each of the first N random robots of tests/properties.rs's
//! generator (the same ranges and fixed seed): what docs/benchmarks.md's "300 random
//! robots" column measures with callgrind (`--toggle-collect='tdcr::collocation::solve'`),
//! with one line per robot (meshes, intervals, iterations, verdict, tolerance met, tip) to
//! compare two builds' answers.
//!
//! `cargo run --release --example random_robots [N] [predicted|calibrate]` (default 300;
//! `predicted`: with `Options::first_mesh_from_guess`; `calibrate`: each robot solved again
//! on its fixed starting mesh, with the estimate's miss of the default tolerance, against
//! which docs/numerics.md "The first mesh from the guess" compares its prediction).

use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, RngAlgorithm, TestRng, TestRunner};
use std::f64::consts::PI;
use tdcr::{Loads, Robot, Rod, Routing, Tendon, collocation};

/// As tests/properties.rs.
const DENSITY: f64 = 8000.0;
/// As tests/properties.rs.
const GRAVITY: f64 = 9.81;

/// tests/properties.rs's generator, verbatim.
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
    let cases: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(300);
    let mode = std::env::args().nth(2).unwrap_or_default();
    let calibrate = mode == "calibrate";
    let config = Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    let index = std::cell::Cell::new(0);
    let result = runner.run(&robot(), |robot| {
        index.set(index.get() + 1);
        let index = index.get();
        let options = collocation::Options {
            first_mesh_from_guess: mode == "predicted",
            ..Default::default()
        };
        match collocation::solve(&robot, &options) {
            Ok(s) => {
                let r = &s.report;
                let tip = s.tip_position();
                let e = r.error_estimate.map_or([f64::NAN; 2], |e| [e.tip_position, e.tip_rotation]);
                println!(
                    "{index} meshes {} intervals {} iterations {} stability {} met {:?} estimate {:.3e} {:.3e} tip {:.12e} {:.12e} {:.12e}",
                    r.meshes,
                    r.intervals,
                    r.iterations,
                    r.stability,
                    r.tolerance_met,
                    e[0],
                    e[1],
                    tip[0],
                    tip[1],
                    tip[2]
                );
            }
            Err(e) => println!("{index} error {e}"),
        }
        if calibrate {
            let fixed = collocation::Options {
                tolerance: None,
                ..Default::default()
            };
            let length = robot.length();
            match collocation::solve(&robot, &fixed) {
                Ok(s) => {
                    let e = s.report.error_estimate.map_or([f64::NAN; 2], |e| [e.tip_position, e.tip_rotation]);
                    println!(
                        "{index} CALIB intervals {} ratio {:.3e} pos {:.3e} rot {:.3e}",
                        s.report.intervals,
                        (e[0] / (1e-7 * length)).max(e[1] / 1e-7),
                        e[0] / (1e-7 * length),
                        e[1] / 1e-7
                    );
                }
                Err(_) => println!("{index} CALIB error"),
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        eprintln!("{e}");
    }
}
