//! The same input gives bitwise-identical output, run after run and in parallel batches.

use tdcr::{cases, collocation};

fn robots() -> Vec<tdcr::Robot> {
    (0..24)
        .map(|k| {
            let mut robot = cases::prototype();
            robot.tendons[k % 5].set_tension(0.5 + 0.2 * k as f64);
            robot.loads.tip_force.z = -0.01 * (k % 3) as f64;
            robot
        })
        .collect()
}

fn bits(solution: &tdcr::Solution) -> Vec<u64> {
    solution
        .nodes
        .iter()
        .flat_map(|n| {
            n.p.iter()
                .chain(n.R.iter())
                .chain(n.v.iter())
                .chain(n.u.iter())
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn repeated_and_batched_solves_are_bitwise_identical() {
    let robots = robots();
    let options = collocation::Options::default();
    let sequential: Vec<Vec<u64>> = robots
        .iter()
        .map(|r| bits(&collocation::solve(r, &options).unwrap()))
        .collect();
    let again: Vec<Vec<u64>> = robots
        .iter()
        .map(|r| bits(&collocation::solve(r, &options).unwrap()))
        .collect();
    let batched: Vec<Vec<u64>> = collocation::solve_batch(&robots, &options)
        .iter()
        .map(|r| bits(r.as_ref().unwrap()))
        .collect();
    assert_eq!(sequential, again);
    assert_eq!(sequential, batched);
}

#[test]
fn reusing_a_solver_changes_nothing_but_the_setup() {
    let options = collocation::Options {
        linear_solver: collocation::LinearSolver::SparseLu,
        ..Default::default()
    };
    let mut solver = collocation::Solver::new(options.clone());
    for robot in robots().iter().take(6) {
        let fresh = bits(&collocation::solve(robot, &options).unwrap());
        assert_eq!(bits(&solver.solve(robot).unwrap()), fresh);
    }
}

/// Random inputs from a fixed linear congruential sequence, uniform in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// 300 rows of the prototype: random tensions on its five tendons (0..3 N), every third
/// row with a random tip force (up to 0.3 N sideways and down), a few with every tension
/// zero (where Newton may stop without a step), solved by `solve_rows` on two threads and
/// on one: every answer (nodes, iterations, stability, estimate) is bitwise the one
/// `solve` gives the row alone, in row order, whatever the thread count.
#[test]
fn solve_rows_gives_each_row_its_own_cold_solve_bitwise() {
    let mut state = 2026;
    let robots: Vec<tdcr::Robot> = (0..300)
        .map(|k| {
            let mut robot = cases::prototype();
            for t in 0..5 {
                let tension = if k % 50 == 7 { 0.0 } else { 3.0 * uniform(&mut state) };
                robot.tendons[t].set_tension(tension);
            }
            if k % 3 == 0 {
                robot.loads.tip_force.x = 0.4 * uniform(&mut state) - 0.2;
                robot.loads.tip_force.z = -0.3 * uniform(&mut state);
            }
            robot
        })
        .collect();
    let options = collocation::Options::default();
    let summary = |s: &tdcr::Solution| {
        (
            bits(s),
            s.report.iterations,
            s.report.stability.verdict(),
            s.report.error_estimate.map(|e| format!("{e:?}")),
        )
    };
    let alone: Vec<_> = robots
        .iter()
        .map(|r| summary(&collocation::solve(r, &options).unwrap()))
        .collect();
    let rows = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            collocation::solve_rows(
                0..robots.len(),
                &options,
                |i| Ok(robots[i].clone()),
                |_, r| summary(&r.unwrap()),
            )
        })
    };
    assert_eq!(rows(2), alone);
    assert_eq!(rows(1), alone);
    // A row whose robot cannot be built keeps its place with its error.
    let built = collocation::solve_rows(
        0..3,
        &options,
        |i| {
            let mut robot = robots[i].clone();
            if i == 1 {
                robot.tendons[0].set_tension(-1.0);
                robot.validate()?;
            }
            Ok(robot)
        },
        |i, r| (i, r.is_ok()),
    );
    assert_eq!(built, [(0, true), (1, false), (2, true)]);
}

/// A stateless solve takes the workspace an earlier solve on its thread left behind (the
/// kept workspaces of `collocation::solve`): its answer and verdict are bitwise those of a
/// thread that never solved, on both linear solvers, on a one-mesh (S) and a two-mesh (H)
/// error-controlled solve, after solves of the same and of other robots.
#[test]
fn kept_workspaces_change_nothing_but_the_setup() {
    let robots = [cases::case_s(), cases::case_h(), robots().swap_remove(7)];
    for linear_solver in [collocation::LinearSolver::Blocks, collocation::LinearSolver::SparseLu] {
        let options = collocation::Options {
            linear_solver,
            ..Default::default()
        };
        for robot in &robots {
            let (r, o) = (robot.clone(), options.clone());
            // A new thread has no kept workspaces.
            let fresh = std::thread::spawn(move || {
                let s = collocation::solve(&r, &o).unwrap();
                (bits(&s), format!("{:?}", s.report.stability))
            })
            .join()
            .unwrap();
            for other in &robots {
                collocation::solve(other, &options).unwrap();
            }
            for _ in 0..2 {
                let s = collocation::solve(robot, &options).unwrap();
                assert_eq!((bits(&s), format!("{:?}", s.report.stability)), fresh);
            }
        }
    }
}
