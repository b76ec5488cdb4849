//! Many independent solves on all cores: [`solve_batch`] (robots given) and [`solve_rows`]
//! (robots built row by row, each result reduced to what the caller keeps), what `tdcr
//! batch`, Python's `solve_batch`, `solve_parameters` and `tdcr.dataset` run.
//!
//! Every worker thread keeps one [`Solver`] for all the rows it solves: the Newton
//! workspace (buffers, block pattern, factors) is built once per thread and mesh instead of
//! once per row. Every row is solved cold, from the rigid-equilibrium guess, exactly as
//! [`super::solve`] solves it alone: the answers are bitwise those of one-by-one solves
//! whatever the order of the rows, the number of threads or the sharding. A warm start
//! from a neighbouring row is not taken: on the prototype (random tensions, and tensions
//! with tip forces) it costs more instructions than the cold start, sorted or not, and it
//! can reach another equilibrium than the row's own solve (docs/benchmarks.md, "Batch
//! throughput").

use super::options::Options;
use super::solver::Solver;
use crate::Robot;
use crate::error::Result;
use crate::solution::Solution;
use rayon::prelude::*;
use std::ops::Range;

/// Solves many independent robots in parallel on rayon's current thread pool, one result
/// per robot in input order. Each solve is the same deterministic computation as
/// [`super::solve`], so results are bitwise identical to solving them one by one; each
/// worker thread reuses one [`Solver`]'s workspace.
pub fn solve_batch(robots: &[Robot], options: &Options) -> Vec<Result<Solution>> {
    robots
        .par_iter()
        .map_init(|| Solver::new(options.clone()), |solver, robot| solver.solve(robot))
        .collect()
}

/// Solves the robots `robot(i)` for the rows `i` in `rows` in parallel on rayon's current
/// thread pool and returns `keep(i, result)` for each, in row order: the solution is
/// reduced to what the caller keeps (a result row, a few numbers) as soon as it is solved,
/// so memory holds the kept values, never the solutions. A row whose robot cannot be built
/// gets that error as its result. Each solve is [`super::solve`]'s computation, bitwise,
/// with each worker thread's [`Solver`] workspace reused.
///
/// # Examples
/// ```
/// let rows = tdcr::collocation::solve_rows(0..4, &Default::default(), |i| {
///     let mut robot = tdcr::cases::prototype();
///     robot.tendons[0].set_tension(0.5 * i as f64);
///     Ok(robot)
/// }, |_, result| result.map(|s| s.tip_position().z));
/// assert!(rows.iter().all(|z| z.is_ok()));
/// ```
pub fn solve_rows<T: Send>(
    rows: Range<usize>,
    options: &Options,
    robot: impl Fn(usize) -> Result<Robot> + Sync,
    keep: impl Fn(usize, Result<Solution>) -> T + Sync,
) -> Vec<T> {
    rows.into_par_iter()
        .map_init(
            || Solver::new(options.clone()),
            |solver, i| keep(i, robot(i).and_then(|r| solver.solve(&r))),
        )
        .collect()
}
