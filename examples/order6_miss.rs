//! Diagnosis of an order-6 estimate below the true error (docs/numerics.md, "The order-6
//! answer", "Why the estimate was low on some random robots"): for the robot file given, the
//! 1e-10 L solve (or `TOL`), then the order-4 and order-6 answers (with the unreported order-8
//! estimate, before its factor and rounding term) on the mesh that solve ends on and on that
//! mesh with every interval split into k, against order-4 references on 32x and 64x that
//! mesh (warm, from the solve, and cold, from the default guess), and each order-6 answer's
//! distance from the one on the finest split (which does not carry those references' rounding).
//!
//! `cargo run --release --example order6_miss -- [ROBOT.toml]` (default
//! tests/data/order6-miss-slender.toml, a robot of the 600-robot property run);
//! `SPLITS=1,2,4` chooses k, `NODES=1` prints the solve's mesh and the error node by node on it,
//! `INTERVALS=32` solves on that fixed uniform mesh instead, `TOL=1e-7` at that tolerance (relative to L; at the default 1e-7 the solve
//! is the order-4 answer, and split 1 shows the order-6 answer the default would return,
//! tests/data/order6-default-miss.toml: docs/numerics.md, "Why the default keeps order 4").

use tdcr::advanced::{deferred, equations::Model, guess, mesh::Mesh, newton, system::System};
use tdcr::collocation::{self, LinearSolver};
use tdcr::{Method, Robot, Solution, SolveReport, State, so3};

/// The arc lengths of `nodes` with every interval split into `k`.
fn split(nodes: &[f64], k: usize) -> Vec<f64> {
    let mut s: Vec<f64> = nodes
        .windows(2)
        .flat_map(|w| (0..k).map(move |i| w[0] + i as f64 / k as f64 * (w[1] - w[0])))
        .collect();
    s.push(*nodes.last().unwrap());
    s
}

/// The order-4 states (Newton to `tolerance` from `from`), the order-6 states and their
/// reported estimate on the mesh through `points`.
fn order6(
    robot: &Robot,
    from: &Solution,
    points: &[f64],
    tolerance: f64,
) -> (Vec<State>, Vec<State>, tdcr::ErrorEstimate) {
    let mesh = Mesh::from_points(robot, points).unwrap();
    let system = System::new(Model::new(robot), mesh);
    let mut ws = newton::Workspace::new(&system, LinearSolver::Blocks).unwrap();
    let mut x = guess::interpolate(&system.model, from, &system.mesh);
    let settings = newton::Settings {
        tolerance,
        max_iterations: 30,
        reuse_factors: false,
        stop_when_damped: false,
    };
    let mut report = SolveReport::new(Method::Collocation);
    let (t, _) = newton::run(&system, &mut ws, &mut x, &settings, &mut report);
    eprintln!("Newton: {t:?} after {} iterations", report.iterations);
    let (x6, e) = deferred::corrected(&system, &mut ws, &x, &mut report).unwrap().unwrap();
    (x, x6, e)
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "tests/data/order6-miss-slender.toml".to_string());
    let text = std::fs::read_to_string(&path).unwrap();
    let robot = tdcr::io::parse(&text, &path).unwrap().robot;
    let length = robot.length();
    println!("breakpoints {:?}, L {length}", robot.breakpoints());
    let tolerance = std::env::var("TOL").map_or(1e-10, |t| t.parse().unwrap());
    let options = match std::env::var("INTERVALS") {
        Ok(n) => collocation::Options::fixed(n.parse().unwrap()),
        Err(_) => collocation::Options {
            tolerance: Some(tolerance),
            ..Default::default()
        },
    };
    let solution = collocation::solve(&robot, &options).unwrap();
    let nodes: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mut dedup = nodes.clone();
    dedup.dedup();
    println!("{} intervals", solution.report.intervals);
    if std::env::var("NODES").is_ok() {
        println!("mesh {dedup:?}");
    }
    let reference = |k: usize| {
        let fine = collocation::Options {
            mesh: Some(split(&dedup, k)),
            tolerance: None,
            residual_tolerance: 1e-13,
            max_intervals: 100_000,
            ..Default::default()
        };
        collocation::solve_from(&robot, &fine, &solution).unwrap()
    };
    let (r32, r64) = (reference(32), reference(64));
    let rot =
        |a: &tdcr::nalgebra::Matrix3<f64>, b: &tdcr::nalgebra::Matrix3<f64>| so3::log(&(a.transpose() * b)).norm();
    for k in [32, 64] {
        let cold = collocation::solve(
            &robot,
            &collocation::Options {
                mesh: Some(split(&dedup, k)),
                tolerance: None,
                residual_tolerance: 1e-13,
                max_intervals: 100_000,
                ..Default::default()
            },
        )
        .unwrap();
        println!(
            "cold reference {k}x vs warm 64x: {:.2e} L, {:.2e} rad; vs warm 32x {:.2e} L",
            (cold.tip_position() - r64.tip_position()).norm() / length,
            rot(&cold.tip().R, &r64.tip().R),
            (cold.tip_position() - r32.tip_position()).norm() / length,
        );
    }
    println!(
        "reference 32x vs 64x: {:.2e} L, {:.2e} rad",
        (r32.tip_position() - r64.tip_position()).norm() / length,
        rot(&r32.tip().R, &r64.tip().R)
    );
    let e = solution.report.error_estimate.unwrap();
    println!(
        "solve: true {:.3e} L / est {:.3e} L, {:.3e} rad / {:.3e} rad",
        (solution.tip_position() - r64.tip_position()).norm() / length,
        e.tip_position / length,
        rot(&solution.tip().R, &r64.tip().R),
        e.tip_rotation
    );
    let splits: Vec<usize> =
        std::env::var("SPLITS").map_or(vec![1, 2, 4], |t| t.split(',').map(|k| k.parse().unwrap()).collect());
    let mut tips6 = Vec::new();
    for &k in &splits {
        let (x4, x6, est) = order6(&robot, &solution, &split(&dedup, k), 1e-12);
        let t4 = x4.last().unwrap();
        println!(
            "split {k}: order 4 true {:.3e} L, {:.3e} rad",
            (t4.p - r64.tip_position()).norm() / length,
            rot(&t4.R, &r64.tip().R)
        );
        let tip = x6.last().unwrap();
        tips6.push((k, tip.p, tip.R));
        // Unreported: the order-8 estimate itself (SAFETY 1.25, ROUNDING 4e-13).
        let raw_p = (est.tip_position - 4e-13 * length) / 1.25;
        let raw_r = (est.tip_rotation - 4e-13) / 1.25;
        let tp = (tip.p - r64.tip_position()).norm();
        let tr = rot(&tip.R, &r64.tip().R);
        println!(
            "split {k}: position true {:.3e} L raw est {:.3e} ratio {:.3}; rotation true {:.3e} raw est {:.3e} ratio {:.3}",
            tp / length,
            raw_p / length,
            tp / raw_p,
            tr,
            raw_r,
            tr / raw_r
        );
        println!(
            "split {k}: true / reported estimate: position {:.3}, rotation {:.3}",
            tp / est.tip_position,
            tr / est.tip_rotation
        );
        if k == 1 && std::env::var("NODES").is_ok() {
            // Node by node: the position error of x6 against the reference.
            let mut j = 0;
            for (i, n) in x6.iter().enumerate() {
                while (r64.nodes[j].s - nodes[i]).abs() > 1e-15 * length {
                    j += 1;
                }
                let d = (n.p - r64.nodes[j].p).norm() / length;
                let dr = rot(&n.R, &r64.nodes[j].R);
                println!("  node {i} s/L {:.4}: dp {d:.3e} dtheta {dr:.3e}", nodes[i] / length);
            }
        }
    }
    // The order-6 answers against the finest one: a reference that does not carry the
    // order-4 references' rounding on 32x and 64x the mesh.
    if let Some(&(kf, pf, rf)) = tips6.last() {
        for &(k, p, r) in &tips6 {
            println!(
                "order 6 split {k} vs split {kf}: {:.3e} L, {:.3e} rad",
                (p - pf).norm() / length,
                rot(&r, &rf)
            );
        }
    }
}
