//! The verdicts of the linearized dynamics, printed exactly, for a before/after comparison
//! of a change to them (docs/stability.md, "Cost"): 79 robots whose loads are not
//! conservative (the prototype with random tensions and dead tip moments, case S with dead
//! tip moments, Beck's column from 15 to 30 EI/L^2, a bent rod with follower tip forces,
//! robot r1 of tests/dynamics.rs with dead tip moments), each solved by default and by
//! Newton's nearest root: the solve's verdict, path, steps, Jacobian count and tip, and the
//! verdict and lowest eigenvalues of `collocation::vibration` there.
//!
//! ```text
//! cargo run --release --example dynamics_dump > before.txt   # build, change, run again
//! ```
use nalgebra::Vector3;
use tdcr::{Loads, Robot, Rod, Routing, Tendon, cases, collocation};

/// Uniform in [0, 1) from a fixed linear congruential sequence.
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn main() {
    let mut robots: Vec<(String, Robot)> = Vec::new();
    let mut state = 31;
    for i in 0..40 {
        let mut robot = cases::prototype();
        for t in robot.tendons.iter_mut() {
            t.set_tension(3.0 * uniform(&mut state));
        }
        let m = 5e-3 * uniform(&mut state);
        robot.loads.tip_moment = Vector3::new(
            m * (uniform(&mut state) - 0.5),
            m * (uniform(&mut state) - 0.5),
            m * (uniform(&mut state) - 0.5),
        );
        robots.push((format!("proto{i}"), robot));
    }
    for i in 0..10 {
        let mut s = cases::case_s();
        s.loads.tip_moment = Vector3::new(1e-3 * i as f64, 2e-3, -0.5e-3 * i as f64);
        robots.push((format!("S{i}"), s));
    }
    let ei = 200e9 * std::f64::consts::PI * 1e-12 / 4.0;
    for k in [15.0, 19.0, 19.9, 20.2, 21.0, 25.0, 30.0] {
        let beck = Robot::new(Rod::solid_circle(0.5, 1e-3, 200e9, 0.3))
            .with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.0, 0.0, -k * ei / 0.25)));
        robots.push((format!("beck{k}"), beck));
    }
    for i in 0..10 {
        let f = 0.1 * i as f64;
        let bent = Robot::new(Rod::solid_circle(0.5, 1e-3, 200e9, 0.3))
            .with_tendon(Tendon::new(Routing::straight(0.01, 0.0), 20.0))
            .with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.3, -0.1 * f, -0.5 - f)));
        robots.push((format!("bent{i}"), bent));
    }
    for i in 0..12 {
        let moment = Vector3::new(2e-3 * i as f64, 1e-3 * (i % 3) as f64, 0.0);
        let mut robot = Robot::new(Rod::solid_circle(0.5, 0.001, 200e9, 0.3)).with_loads(
            Loads::self_weight(0.24, -Vector3::z())
                .with_tip_force(Vector3::new(0.0, 0.0, -3.0))
                .with_tip_moment(moment),
        );
        for (j, (x, y)) in [(0.015, 0.0), (0.0, 0.015), (-0.015, 0.0), (0.0, -0.015)]
            .into_iter()
            .enumerate()
        {
            robot = robot.with_tendon(Tendon::new(Routing::straight(x, y), if j == 0 { 15.0 } else { 0.0 }));
        }
        robots.push((format!("r1-{i}"), robot));
    }
    let nearest = collocation::Options {
        equilibrium: collocation::Equilibrium::Nearest,
        ..Default::default()
    };
    for (name, robot) in &robots {
        for (tag, options) in [("", collocation::Options::default()), (" nearest", nearest.clone())] {
            let name = format!("{name}{tag}");
            match collocation::solve(robot, &options) {
                Ok(s) => {
                    let r = &s.report;
                    println!(
                        "{name}: {:?} path {:?} n{} c{} j{} tip {:?}",
                        r.stability,
                        r.path,
                        r.newton_steps,
                        r.chord_steps,
                        r.evaluations.jacobian,
                        s.tip_position().as_slice()
                    );
                    match collocation::vibration(robot, &s) {
                        Ok(v) => println!(
                            "{name} vib: {:?} {:?}",
                            v.stability,
                            &v.eigenvalues[..v.eigenvalues.len().min(4)]
                        ),
                        Err(e) => println!("{name} vib err {e}"),
                    }
                }
                Err(e) => println!("{name}: error {e}"),
            }
        }
    }
}
