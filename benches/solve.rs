//! Solve-time benchmarks: `cargo bench --bench solve`.
//!
//! - `default_settings`: what users get: cases S and H at the default error control (tip to
//!   1e-7 L) and at 1e-9 L, cold and warm with a `Solver` that has just solved 0.99x the
//!   tension (its stored factors start chord steps). The mesh is the solver's choice.
//! - `reference`: S and H on the fixed meshes earlier versions were timed on (16 and 48
//!   intervals), kept for comparisons across versions: cold, warm with a `Solver`, and warm
//!   through the stateless `solve_from` (no stored factors).
//! - `prototype_s`: the prototype with tendon 1 at 2.94 N plus self weight; collocation at
//!   16..128 intervals from a cold start and warm-started from the solution at 0.99x the
//!   tension; shooting at integration tolerances giving comparable tip accuracy.
//! - `newton_iteration`: one full Newton iteration (Jacobian, factorization, solve, line
//!   search) on case H from 64 to 10 000 intervals: the cost must grow linearly.
//! - `linear_solve`: the Newton linear solve alone, structured elimination and sparse LU.
//! - `tendon_count`: a solve with 1..32 tendons.
//! - `batch`: 10 000 independent solves over all cores with `collocation::solve_batch`.
//! - `displacement`: S and H at default settings, cold, driven by the tension and by the
//!   pull-in that tension holds (docs/actuation.md: the goal is at most 1.5x).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use tdcr::advanced::equations::Model;
use tdcr::advanced::guess::rigid_estimate;
use tdcr::advanced::mesh::Mesh;
use tdcr::advanced::newton::{self, Settings, Workspace};
use tdcr::advanced::system::System;
use tdcr::collocation::LinearSolver;
use tdcr::{Method, SolveReport};
use tdcr::{cases, collocation, shooting};

/// The robot with every tension scaled by `factor`.
fn scaled(robot: &tdcr::Robot, factor: f64) -> tdcr::Robot {
    let mut r = robot.clone();
    for t in r.tendons.iter_mut() {
        t.set_tension(t.tension() * factor);
    }
    r
}

/// A timed warm solve per iteration, each after an untimed solve of `previous` by the same
/// solver (its stored factors then belong to that solution).
fn warm_solves(
    solver: &mut collocation::Solver,
    previous: &tdcr::Robot,
    robot: &tdcr::Robot,
    iterations: u64,
) -> std::time::Duration {
    let mut total = std::time::Duration::ZERO;
    for _ in 0..iterations {
        let guess = solver.solve(previous).unwrap();
        let t = std::time::Instant::now();
        black_box(solver.solve_from(robot, &guess).unwrap());
        total += t.elapsed();
    }
    total
}

fn default_settings(c: &mut Criterion) {
    let mut group = c.benchmark_group("default_settings");
    for (case, robot) in [("S", cases::case_s()), ("H", cases::case_h())] {
        for tolerance in [1e-7, 1e-9] {
            let options = collocation::Options {
                tolerance: Some(tolerance),
                ..Default::default()
            };
            let previous = scaled(&robot, 0.99);
            let id = format!("{case}/{tolerance:.0e}");
            group.bench_function(BenchmarkId::new("cold", &id), |b| {
                b.iter(|| black_box(collocation::solve(&robot, &options).unwrap()))
            });
            let mut solver = collocation::Solver::new(options.clone());
            group.bench_function(BenchmarkId::new("warm_solver", &id), |b| {
                b.iter_custom(|iterations| warm_solves(&mut solver, &previous, &robot, iterations))
            });
        }
    }
    group.finish();
}

fn reference(c: &mut Criterion) {
    let mut group = c.benchmark_group("reference");
    for (case, robot, intervals) in [("S", cases::case_s(), 16), ("H", cases::case_h(), 48)] {
        let options = collocation::Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        let previous = scaled(&robot, 0.99);
        group.bench_function(BenchmarkId::new("cold", case), |b| {
            b.iter(|| black_box(collocation::solve(&robot, &options).unwrap()))
        });
        // Each timed solve follows an untimed solve of the robot at 0.99x the tension.
        let mut solver = collocation::Solver::new(options.clone());
        group.bench_function(BenchmarkId::new("warm_solver", case), |b| {
            b.iter_custom(|iterations| warm_solves(&mut solver, &previous, &robot, iterations))
        });
        let guess = collocation::solve(&previous, &options).unwrap();
        group.bench_function(BenchmarkId::new("warm_stateless", case), |b| {
            b.iter(|| black_box(collocation::solve_from(&robot, &options, &guess).unwrap()))
        });
    }
    group.finish();
}

fn prototype_s(c: &mut Criterion) {
    let robot = cases::case_s();
    let mut previous = robot.clone();
    {
        let t = &mut previous.tendons[0];
        t.set_tension(t.tension() * 0.99);
    }
    let mut group = c.benchmark_group("prototype_s");
    for intervals in [16, 32, 64, 128] {
        let options = collocation::Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        group.bench_with_input(BenchmarkId::new("collocation_cold", intervals), &options, |b, o| {
            b.iter(|| black_box(collocation::solve(&robot, o).unwrap()))
        });
        let guess = collocation::solve(&previous, &options).unwrap();
        group.bench_with_input(BenchmarkId::new("collocation_warm", intervals), &options, |b, o| {
            b.iter(|| black_box(collocation::solve_from(&robot, o, &guess).unwrap()))
        });
    }
    for tolerance in [1e-6, 1e-8, 1e-10] {
        let options = shooting::Options {
            integration_tolerance: tolerance,
            ..Default::default()
        };
        group.bench_with_input(BenchmarkId::new("shooting", tolerance), &options, |b, o| {
            b.iter(|| black_box(shooting::solve(&robot, o).unwrap()))
        });
    }
    group.finish();
}

fn newton_iteration(c: &mut Criterion) {
    let robot = cases::case_h();
    let model = Model::new(&robot);
    let mut group = c.benchmark_group("newton_iteration");
    group.sample_size(10);
    for intervals in [64, 256, 1024, 4096, 10_000] {
        let system = System::new(model.clone(), Mesh::uniform(&robot, intervals).unwrap());
        let mut ws = Workspace::new(&system, LinearSolver::Blocks).unwrap();
        let start = rigid_estimate(&model, &system.mesh.nodes);
        // Tolerance 0 and one iteration: exactly one Newton step per call.
        let settings = Settings {
            tolerance: 0.0,
            max_iterations: 1,
            reuse_factors: false,
            stop_when_damped: false,
        };
        let mut report = SolveReport::new(Method::Collocation);
        let mut x = start.clone();
        group.bench_function(BenchmarkId::from_parameter(intervals), |b| {
            b.iter(|| {
                x.clone_from(&start);
                black_box(newton::run(&system, &mut ws, &mut x, &settings, &mut report))
            })
        });
    }
    group.finish();
}

/// The Newton linear solve alone (factorization and solve of the Jacobian at the initial
/// guess of case H) with the structured elimination and with faer's sparse LU: per node,
/// against the flop floor of 22.6 kflop per node.
fn linear_solve(c: &mut Criterion) {
    let robot = cases::case_h();
    let model = Model::new(&robot);
    let mut group = c.benchmark_group("linear_solve");
    for intervals in [48, 1024] {
        let system = System::new(model.clone(), Mesh::uniform(&robot, intervals).unwrap());
        let x = rigid_estimate(&model, &system.mesh.nodes);
        let mut rhs = vec![0.0; system.unknowns()];
        let mut values = vec![0.0; tdcr::advanced::unknowns::nonzeros(&system.mesh)];
        system.jacobian(&x, &mut rhs, &mut values).unwrap();
        for (name, solver) in [("blocks", LinearSolver::Blocks), ("sparse_lu", LinearSolver::SparseLu)] {
            let mut ws = Workspace::new(&system, solver).unwrap();
            group.bench_function(BenchmarkId::new(name, intervals), |b| {
                b.iter(|| black_box(ws.solve_linear(&values, &rhs).is_some()))
            });
        }
    }
    group.finish();
}

/// Cost against the number of tendons: 1..32 straight tendons evenly spaced around the
/// prototype's backbone at 8 mm, each at 2.94 N / count, with self weight.
fn tendon_count(c: &mut Criterion) {
    let mut group = c.benchmark_group("tendon_count");
    for count in [1usize, 2, 4, 8, 16, 32] {
        let mut robot = cases::prototype();
        robot.tendons.clear();
        for k in 0..count {
            let angle = 0.3 + std::f64::consts::TAU * k as f64 / count as f64;
            let routing = tdcr::Routing::straight(0.008 * angle.cos(), 0.008 * angle.sin());
            robot.tendons.push(tdcr::Tendon::new(
                routing,
                2.94 / count as f64 * (1.0 + 0.5 * (k == 0) as u8 as f64),
            ));
        }
        let options = collocation::Options::default();
        group.bench_function(BenchmarkId::from_parameter(count), |b| {
            b.iter(|| black_box(collocation::solve(&robot, &options).unwrap()))
        });
    }
    group.finish();
}

/// Throughput of independent solves over all cores: 10 000 random tension vectors on the
/// prototype's four straight tendons (0..3 N each), solved by `solve_batch`.
fn batch(c: &mut Criterion) {
    // A fixed linear congruential sequence: the same robots every run.
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let robots: Vec<tdcr::Robot> = (0..10_000)
        .map(|_| {
            let mut robot = cases::prototype();
            for t in robot.tendons.iter_mut().take(4) {
                t.set_tension(3.0 * next());
            }
            robot
        })
        .collect();
    let options = collocation::Options::default();
    let mut group = c.benchmark_group("batch");
    group.sample_size(10);
    group.throughput(criterion::Throughput::Elements(robots.len() as u64));
    group.bench_function("10000_random_tensions", |b| {
        b.iter(|| black_box(collocation::solve_batch(&robots, &options)))
    });
    group.finish();
}

fn displacement(c: &mut Criterion) {
    let mut group = c.benchmark_group("displacement");
    for (case, robot, tendon) in [("S", cases::case_s(), 0), ("H", cases::case_h(), 4)] {
        let options = collocation::Options::default();
        let solved = collocation::solve(&robot, &options).unwrap();
        let mut pulled = robot.clone();
        pulled.tendons[tendon].set_displacement(solved.tendons[tendon].displacement);
        group.bench_function(BenchmarkId::new("tension", case), |b| {
            b.iter(|| black_box(collocation::solve(&robot, &options).unwrap()))
        });
        group.bench_function(BenchmarkId::new("displacement", case), |b| {
            b.iter(|| black_box(collocation::solve(&pulled, &options).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    default_settings,
    reference,
    prototype_s,
    newton_iteration,
    linear_solve,
    tendon_count,
    batch,
    displacement
);
criterion_main!(benches);
