//! The `tdcr` command: solve robot files from the shell (docs/cli.md).
//!
//! With no arguments it runs the main job: the paper's prototype under all 32 experiments of
//! Table 2, one table on standard output and a picture of all shapes in `./out/`.
//! Exit codes: 0 success, 2 bad input, 3 did not converge, 4 outside the model (valid input
//! the model cannot answer), 1 anything else.
//!
//! This file holds the command line and the dispatch; each command has its own module.

mod args;
mod batch;
mod bench;
mod calibrate;
mod check;
mod compare;
mod failure;
mod history;
mod picture;
mod robot_args;
mod solve;
mod sweep;
mod sweep_csv;
mod sweep_picture;
mod table2;
mod tables;
mod trace;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

// The helpers `calibrate` reaches through `super::`.
use args::parse_count;
use failure::{Failure, emit, note, solver_failure};
use robot_args::read_robot;

/// Shape of tendon-driven continuum robots under load.
#[derive(Parser)]
#[command(
    name = "tdcr",
    version,
    args_conflicts_with_subcommands = true,
    after_help = "Without a command: solve the paper's prototype under the 32 experiments of Table 2, \
                  print a table and draw every shape into OUT_DIR.\n\
                  Exit codes: 0 success, 2 bad input, 3 did not converge, 4 outside the model, 1 anything \
                  else.\n\
                  Robot files: docs/robot-file.md; this command: docs/cli.md."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Folder for the main job's picture and table (created if missing).
    #[arg(long, value_name = "DIR", default_value = "out")]
    out_dir: PathBuf,
}

#[derive(Subcommand)]
enum Command {
    /// Solve one robot file.
    Solve(solve::SolveArgs),
    /// Solve a sequence of robots (tension ranges), each warm-started from the last; CSV out.
    Sweep(sweep::SweepArgs),
    /// Trace a branch of equilibria in one input (a tension, a load component or the load
    /// scale) through folds, with the stability of every point; CSV or JSON out.
    Trace(trace::TraceArgs),
    /// Solve one robot file for every row of a parameter table (CSV or JSON lines), on all
    /// cores; `--shard K/N` for job arrays; CSV out.
    Batch(batch::BatchArgs),
    /// Solve one robot file as several models (or by both solvers) and compare the tips.
    Compare(compare::CompareArgs),
    /// Check a robot file and explain every problem.
    Check {
        /// Robot file (TOML; `-` reads standard input).
        file: String,
    },
    /// Print a sample file: the prototype (tendon 1 at 2.94 N) as a commented robot file to
    /// start from (default), a parameter table for `batch`, or a robot and experiments for
    /// `calibrate`.
    Example {
        /// Which sample: `robot` (the commented robot file), `cases` (a parameter table for
        /// `tdcr batch CASES --robot ROBOT`), `paper-robot` (the prototype in the paper's frame,
        /// for `calibrate`) or `experiments` (32 synthetic measured tips of `paper-robot`).
        #[arg(value_enum, default_value_t = check::Sample::Robot)]
        sample: check::Sample,
    },
    /// Time the reference cases S and H, cold and warm (docs/benchmarks.md).
    Bench(bench::BenchArgs),
    /// Fit E and the base XYZ Euler angles to measured tip positions (docs/calibration.md).
    Calibrate(calibrate::CalibrateArgs),
}

fn main() -> ExitCode {
    // clap prints usage errors and exits 2 itself (0 for --help and --version).
    let cli = Cli::parse();
    let result = match cli.command {
        None => table2::run(&cli.out_dir),
        Some(Command::Solve(args)) => solve::run(&args),
        Some(Command::Sweep(args)) => sweep::run(&args),
        Some(Command::Batch(args)) => batch::run(&args),
        Some(Command::Trace(args)) => trace::run(&args),
        Some(Command::Compare(args)) => compare::run(&args),
        Some(Command::Check { file }) => check::run(&file),
        Some(Command::Example { sample }) => check::example(sample),
        Some(Command::Bench(args)) => bench::run(&args)
            .map_err(Failure::NotConverged)
            .and_then(|text| emit(&text)),
        Some(Command::Calibrate(args)) => calibrate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            failure.print();
            ExitCode::from(failure.code())
        }
    }
}
