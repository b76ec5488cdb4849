//! `tdcr batch`: one robot file solved for every row of a parameter table (CSV with a header
//! of parameter names, or JSON lines), every row solved on its own on all cores
//! (`tdcr::collocation::solve_rows`), one result row per input row; `--shard K/N` takes one
//! contiguous share of the rows for a job array.

use clap::Args;
use rayon::prelude::*;
use std::io::Write as _;
use std::sync::Mutex;
use tdcr::io::csv_table::CsvTable;
use tdcr::io::number;
use tdcr::io::parameters;
use tdcr::io::row_outputs::{RowOutputs, quaternion, tip_error_estimate};
use tdcr::{Error, Method, Solution};

use crate::args::SolverArgs;
use crate::failure::{Failure, emit, note, write_file};
use crate::robot_args::{apply, read_robot};
use crate::sweep::Progress;

/// Rows per shard unit: `--shard K/N` splits the table into whole blocks of this many
/// rows. Every row is solved on its own (cold, `tdcr::collocation::solve_rows`), so the
/// blocks only fix where shards start: a sharded run computes every row exactly as the
/// unsharded run does.
pub const BLOCK: usize = 64;

/// The arguments of `tdcr batch`.
#[derive(Args)]
pub struct BatchArgs {
    /// Parameter table: CSV whose header names the parameters (`tension.1`, `tip_force.z`,
    /// ...; docs/cli.md), or JSON lines (`.jsonl`), one object of parameters per line.
    cases: String,
    /// Robot file (TOML) whose values the rows change.
    #[arg(long, value_name = "ROBOT.toml")]
    robot: String,
    /// Write the result CSV to FILE instead of standard output (`-`: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<std::path::PathBuf>,
    /// Solve only shard K of N (K = 0, ..., N-1): a contiguous range of rows (whole blocks
    /// of 64 rows, split evenly); the shards' outputs, concatenated in K order without their
    /// repeated headers, are the unsharded output.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
    /// Add the tip orientation as a unit quaternion: columns q_w, q_x, q_y, q_z (w >= 0).
    #[arg(long)]
    orientation: bool,
    /// Add the stability verdict: column `stability` (stable, unstable or unknown).
    #[arg(long)]
    stability: bool,
    /// Add the solver's estimate of the tip position error (m): column `error_estimate`.
    #[arg(long)]
    error_estimate: bool,
    /// Add K backbone points evenly spaced from base to tip (s = j L / (K - 1)): columns
    /// p1_x, p1_y, p1_z, ..., pK_z (m). K = 0 (the default) adds none; else K >= 2.
    #[arg(long, value_name = "K", default_value_t = 0)]
    points: usize,
    #[command(flatten)]
    friction: crate::robot_args::FrictionArgs,
    #[command(flatten)]
    solver: SolverArgs,
}

/// `K/N` with 0 <= K < N.
fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let bad = || format!("`{text}` must look like K/N with 0 <= K < N, e.g. 0/4");
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k < n { Ok((k, n)) } else { Err(bad()) }
}

/// The optional columns of a solved row, as `outputs` asks.
fn extra_fields(outputs: &RowOutputs, solution: &Solution) -> Vec<String> {
    let mut out = Vec::new();
    if outputs.orientation {
        out.extend(quaternion(&solution.tip().R).map(number));
    }
    if outputs.stability {
        out.push(solution.report.stability.verdict().to_string());
    }
    if outputs.error_estimate {
        let e = tip_error_estimate(solution);
        out.push(if e.is_finite() { number(e) } else { String::new() });
    }
    for p in outputs.points_of(solution) {
        out.extend(p.iter().map(|&x| number(x)));
    }
    out.extend(outputs.delivered_of(solution).into_iter().map(number));
    out
}

/// The CSV fields of one row's result after its input columns: `converged`, `iterations`,
/// the tip, the optional columns (`extra` of them) and `error`; and whether it failed.
fn result_fields(result: tdcr::Result<Solution>, outputs: &RowOutputs, extra: usize) -> (Vec<String>, bool) {
    match result {
        Ok(solution) => {
            let mut fields = vec!["true".to_string(), solution.report.iterations.to_string()];
            fields.extend(solution.tip_position().iter().map(|&x| number(x)));
            fields.extend(extra_fields(outputs, &solution));
            fields.push(String::new());
            (fields, false)
        }
        Err(e) => {
            let iterations = match &e {
                Error::NotConverged { report, .. } => report.iterations.to_string(),
                _ => String::new(),
            };
            let mut fields = vec!["false".to_string(), iterations];
            fields.extend(std::iter::repeat_n(String::new(), 3 + extra));
            // One line per row: a multi-line message joined with "; ".
            fields.push(crate::failure::message(&e).replace('\n', "; "));
            (fields, true)
        }
    }
}

/// The progress bar and the rows done of the total.
struct Counted {
    bar: Progress,
    done: usize,
    total: usize,
}

impl Counted {
    /// Counts one more row done.
    fn tick(progress: &Mutex<Counted>) {
        if let Ok(mut p) = progress.lock() {
            p.done += 1;
            let (done, total) = (p.done, p.total);
            p.bar.update(done, total);
        }
    }
}

/// Rows solved between two writes of results, per thread: enough that the wait for the
/// slowest row of a wave (while the other thread idles) is rare, few enough that the
/// result rows in memory stay a few hundred kilobytes whatever the table's length.
const WAVE_ROWS_PER_THREAD: usize = 1024;

/// Where the result rows go, written as each wave of rows is solved.
enum Sink {
    Stdout,
    File(std::path::PathBuf, std::io::BufWriter<std::fs::File>),
}

impl Sink {
    fn open(out: Option<&std::path::Path>) -> Result<Sink, Failure> {
        let Some(path) = out else {
            return Ok(Sink::Stdout);
        };
        // The folder and an empty file first, so a bad path fails before any solve.
        write_file(path, "", "results")?;
        let file = std::fs::File::create(path)
            .map_err(|e| Failure::Other(format!("cannot write the results to {}: {e}", path.display())))?;
        Ok(Sink::File(path.to_path_buf(), std::io::BufWriter::new(file)))
    }

    fn write(&mut self, text: &str) -> Result<(), Failure> {
        match self {
            Sink::Stdout => emit(text),
            Sink::File(path, file) => file
                .write_all(text.as_bytes())
                .and_then(|()| file.flush())
                .map_err(|e| Failure::Other(format!("cannot write the results to {}: {e}", path.display()))),
        }
    }
}

/// `tdcr batch`: reads the robot and the table, solves the shard's rows, writes one result
/// row per input row as the rows are solved (in waves of blocks, in row order, so memory
/// stays flat); exit code 3 when any row failed (after writing all of them).
pub fn run(args: &BatchArgs) -> Result<(), Failure> {
    let mut outputs = RowOutputs {
        orientation: args.orientation,
        stability: args.stability,
        error_estimate: args.error_estimate,
        points: args.points,
        delivered: Vec::new(),
    };
    outputs
        .check()
        .map_err(|e| Failure::Input(format!("--points {}: {e}", args.points)))?;
    let (_, mut file) = read_robot(&args.robot)?;
    args.friction.apply(&mut file.robot)?;
    apply(&mut file, &args.solver);
    let text = std::fs::read_to_string(&args.cases)
        .map_err(|e| Failure::Input(format!("cannot read parameter table {}: {e}", args.cases)))?;
    let table = parameters::read(&args.cases, &text).map_err(|e| Failure::Input(e.to_string()))?;
    drop(text);
    outputs.delivered = RowOutputs::tendons_with_friction(&file.robot, &table.parameters);
    let blocks = table.len().div_ceil(BLOCK);
    let (first, end) = match args.shard {
        // The blocks b with K B / N <= b < (K+1) B / N (docs/cli.md): the first shards
        // are the ones that hold rows when there are fewer blocks than shards.
        Some((k, n)) => ((k * blocks).div_ceil(n), ((k + 1) * blocks).div_ceil(n)),
        None => (0, blocks),
    };
    let rows = (first * BLOCK).min(table.len())..(end * BLOCK).min(table.len());
    if let Some((k, n)) = args.shard
        && rows.is_empty()
        && !table.is_empty()
    {
        note(&format!(
            "shard {k}/{n} holds none of the {} rows: shards are made of whole blocks of {BLOCK} rows ({blocks} \
             here), so with fewer blocks than shards some shards are empty",
            table.len()
        ));
    }
    // Every row's robot is checked before any solve, so bad input stops the run before it
    // spends time; each is built again when it is solved.
    for row in rows.clone().map(|i| table.row(i)) {
        table.robot(&row, &file.robot).map_err(|e| {
            let e = crate::failure::message(&e);
            Failure::Input(format!("{}:{}:1: row {}: {e}", args.cases, row.line, row.index))
        })?;
    }
    let mut sink = Sink::open(crate::failure::out_path(&args.out))?;
    let mut header = vec!["row".to_string()];
    header.extend(table.parameters.iter().map(ToString::to_string));
    header.extend(["converged", "iterations", "tip_x", "tip_y", "tip_z"].map(String::from));
    let extra_columns = outputs.header();
    let extra_count = extra_columns.len();
    header.extend(extra_columns);
    header.push("error".into());
    sink.write(&CsvTable::new(header).finish())?;
    let progress = Mutex::new(Counted {
        bar: Progress::new(),
        done: 0,
        total: rows.len(),
    });
    let wave = WAVE_ROWS_PER_THREAD * rayon::current_num_threads();
    // Checked above: the solve validates it again, a third check would only repeat it.
    let robot_of = |i: usize| table.robot_unchecked(&table.row(i), &file.robot);
    // A row's CSV line is written by the thread that solved it; the lines of a wave are
    // then written in row order.
    let line = |i: usize, result: tdcr::Result<Solution>| {
        let row = table.row(i);
        let mut fields = vec![row.index.to_string()];
        fields.extend(row.values.iter().map(|x| x.map_or(String::new(), number)));
        let (rest, failed) = result_fields(result, &outputs, extra_count);
        fields.extend(rest);
        let mut csv = CsvTable::rows_only();
        csv.row(fields);
        Counted::tick(&progress);
        (csv.finish(), failed)
    };
    let settings = &file.solver;
    let mut failed = 0;
    for start in rows.clone().step_by(wave) {
        let range = start..rows.end.min(start + wave);
        let lines: Vec<(String, bool)> = match settings.method {
            Method::Collocation => tdcr::collocation::solve_rows(range, &settings.collocation, robot_of, line),
            Method::Shooting => range
                .into_par_iter()
                .map(|i| {
                    line(
                        i,
                        robot_of(i).and_then(|r| tdcr::shooting::solve(&r, &settings.shooting)),
                    )
                })
                .collect(),
        };
        failed += lines.iter().filter(|(_, f)| *f).count();
        sink.write(&lines.into_iter().map(|(text, _)| text).collect::<String>())?;
    }
    if let Ok(mut p) = progress.lock() {
        p.bar.finish();
    }
    if let Some(path) = crate::failure::out_path(&args.out) {
        note(&format!("wrote {} ({} rows)", path.display(), rows.len()));
    }
    if failed > 0 {
        return Err(Failure::NotConverged(format!(
            "{failed} of {} rows did not solve; their `error` column says why",
            rows.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_bad_ones_say_the_form() {
        assert_eq!(parse_shard("1/4"), Ok((1, 4)));
        for bad in ["4/4", "1", "a/2", "1/0"] {
            assert!(parse_shard(bad).unwrap_err().contains("K/N"), "{bad}");
        }
    }
}
