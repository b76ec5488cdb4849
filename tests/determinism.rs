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
