//! The cost of the linearized-dynamics verdict against a default solve (docs/stability.md,
//! "Cost"): robots with a dead tip moment, the default solve's report timings.
use nalgebra::Vector3;
use tdcr::{Loads, Robot, Rod, Routing, Tendon, cases, collocation};

fn main() {
    let mut robots: Vec<(&str, Robot)> = Vec::new();
    let mut s = cases::case_s();
    s.loads.tip_moment = Vector3::new(0.0, 1e-3, 0.0);
    robots.push(("case S + 1 mN m dead tip moment", s));
    let mut proto = cases::prototype();
    proto.loads.tip_moment = Vector3::new(2e-3, 1e-3, 0.0);
    robots.push(("prototype + dead tip moment", proto));
    let beck = Robot::new(Rod::solid_circle(0.5, 1e-3, 200e9, 0.3))
        .with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.0, 0.0, -5.0)));
    robots.push(("Beck's column at 15.9 EI/L^2", beck));
    let bent = Robot::new(Rod::solid_circle(0.5, 1e-3, 200e9, 0.3))
        .with_tendon(Tendon::new(Routing::straight(0.01, 0.0), 20.0))
        .with_loads(Loads::none().with_follower_tip_force(Vector3::new(0.3, -0.1, -0.5)));
    robots.push(("bent rod + follower tip force", bent));
    for (name, robot) in &robots {
        let mut total = 0.0;
        let mut stability = 0.0;
        let runs: usize = std::env::var("RUNS").ok().and_then(|r| r.parse().ok()).unwrap_or(50);
        let mut last = None;
        for _ in 0..runs {
            let solution = collocation::solve(robot, &Default::default()).unwrap();
            total += solution.report.timings.total.as_secs_f64();
            stability += solution.report.timings.stability.as_secs_f64();
            last = Some(solution);
        }
        let last = last.unwrap();
        println!(
            "{name}: {} ({} intervals, {} Newton + {} chord): solve {:.3} ms, of which the verdict {:.3} ms ({:.0} % of the rest)",
            last.report.stability,
            last.report.intervals,
            last.report.newton_steps,
            last.report.chord_steps,
            1e3 * total / runs as f64,
            1e3 * stability / runs as f64,
            100.0 * stability / (total - stability)
        );
    }
}
