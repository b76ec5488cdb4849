//! Fuzzing of the robot-file parser and of the command line (issue 7, item 2).
//!
//! The parser is driven through `tdcr::io::parse`, the function `tdcr solve`, `sweep` and
//! `check` call on a file's text, never through the binary (a process per input would be
//! far too slow). The inputs: arbitrary bytes read lossily as UTF-8, arbitrary strings,
//! TOML-looking junk, deeply nested arrays, tables and dotted keys, random TOML documents over
//! the file's own table and key names, and mutations of `tdcr example`'s text (lines deleted,
//! duplicated, swapped or uncommented, numbers replaced by random f64 or junk literals, keys
//! renamed, brackets dropped, truncation, CRLF line ends). Properties, for every input:
//!
//! - `parse` never panics (a panic is caught and turned into a failure that prints the input);
//! - a rejection lists at least one problem, each with a non-empty one-line message and a
//!   line and column inside the text, except the whole-file problems (empty, no `[rod]`,
//!   not TOML); a problem in a table names its field (`tendon[2].end`), a problem at the top
//!   level names the key in its message;
//! - an acceptance gives a robot that passes `Robot::validate` and solver settings within
//!   their documented rules.
//!
//! A second family breaks one field of the example against its documented rule
//! (docs/robot-file.md) and requires a rejection that names that field on that line, so an
//! invalid file that is accepted fails the test.
//!
//! A third family (issue 18) sets the `[solver]` counts to values up to u64::MAX (an accepted
//! file must hold them within the solvers' bounds), gives every vector field and the base
//! rotation's rows 0 to 6 entries (only 3 may be accepted: anything else is counted as a
//! silent truncation and fails), and reads files of 10^3 to 10^5 tendons and point loads.
//!
//! CI runs about 7 100 parser inputs (under a second in release, a few seconds in debug), the
//! 10^3 and 10^4 files, 50 random command lines and 35 with huge counts. The long run, 165 000
//! parser inputs and the 10^5 files (about 25 s in release), prints per input family how many
//! were accepted and where the others were rejected, then the panics, aborts and silent
//! truncations: `cargo test --release --test fuzz -- --ignored --nocapture long_`.
//! Every runner has a fixed seed and no failure persistence: runs are repeatable and write
//! no files. The five bugs the fuzzing found (huge counts that overflowed an allocation, a key
//! with an escaped newline that broke the one-line message format) are fixed; their
//! reproducers are the last tests of this file, with those of issue 18.

use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed, TestCaseError, TestRunner};
use std::io::Read;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};
use tdcr::collocation::{MAX_INTERVALS, MAX_ITERATIONS};
use tdcr::io::{FileError, RobotFile};

/// The file name given to `parse`; every message line must start with it.
const NAME: &str = "fuzz.toml";

/// A valid `[rod]` table: the only required one.
const ROD: &str = "[rod]\nlength = 0.2\nouter_radius = 0.001\nyoungs_modulus = 2e11\npoisson_ratio = 0.3\n";

/// Tables and keys a robot file knows (docs/robot-file.md), so random documents and renamed
/// keys often hit real fields.
const TABLE_NAMES: &[&str] = &["rod", "base", "loads", "tendon", "solver", "loads.point"];
const KEYS: &[&str] = &[
    "length",
    "outer_radius",
    "inner_radius",
    "youngs_modulus",
    "poisson_ratio",
    "shear_modulus",
    "precurvature",
    "position",
    "rotation",
    "euler_xyz_deg",
    "distributed_force",
    "distributed_moment",
    "tip_force",
    "tip_moment",
    "point",
    "s",
    "force",
    "moment",
    "routing",
    "tension",
    "end",
    "kind",
    "x",
    "y",
    "radius",
    "turns",
    "turns_per_rod_length",
    "phase",
    "method",
    "intervals",
    "nodes",
    "tolerance",
    "max_intervals",
    "max_nodes",
    "residual_tolerance",
    "max_iterations",
    "continuation",
    "integration_tolerance",
    "rod",
    "tendon",
    "tendons",
    "load",
];

/// Number-like literals that are not plain decimals: TOML's other number syntaxes, values
/// out of range, and malformed ones.
const NUMBER_JUNK: &[&str] = &[
    "nan",
    "+nan",
    "-nan",
    "inf",
    "+inf",
    "-inf",
    "NaN",
    "Infinity",
    "1e400",
    "-1e400",
    "1e-400",
    "4.9e-324",
    "2.2250738585072014e-308",
    "1.7976931348623157e308",
    "0x1F",
    "0o17",
    "0b101",
    "1_000",
    "1__0",
    "_1",
    "1_",
    "1.",
    ".5",
    "01",
    "-0",
    "+0.0",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775809",
    "99999999999999999999999999",
    "1e",
    "1e+",
    "--1",
    "1979-05-27",
    "07:32:00",
    "1979-05-27T07:32:00Z",
    "true",
    "\"1.0\"",
    "'0.3'",
    "[]",
    "{}",
    "[1.0, 2.0]",
    "[[1.0]]",
    "",
];

/// Tokens of TOML-looking junk.
const TOKENS: &[&str] = &[
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "=",
    ",",
    ".",
    "#",
    "\"",
    "'",
    "\"\"\"",
    "'''",
    "\n",
    "\r\n",
    "\r",
    " ",
    "\t",
    "\\",
    "\\u",
    "\\uD800",
    "\u{0}",
    "\u{feff}",
    "é",
    "🦀",
    "rod",
    "[rod]",
    "[[tendon]]",
    "[solver]",
    "[loads]",
    "[base]",
    "[[loads.point]]",
    "length",
    "tension",
    "routing",
    "kind",
    "\"straight\"",
    "\"helical\"",
    "x",
    "y",
    "intervals",
    "nodes",
    "true",
    "false",
    "0",
    "1",
    "-1",
    "0.5",
    "1e308",
    "-1e308",
    "5e-324",
    "nan",
    "inf",
    "-inf",
];

// ---------------------------------------------------------------------------------------
// The property

/// What the inputs of one run did: accepted, or rejected at which stage of the parser
/// (docs/robot-file.md, "Errors": empty or not TOML; a table that cannot be read; a value
/// against its rule or `Robot::validate`).
#[derive(Default)]
struct Stats {
    inputs: AtomicUsize,
    accepted: AtomicUsize,
    syntax: AtomicUsize,
    tables: AtomicUsize,
    values: AtomicUsize,
}

impl Stats {
    fn counts(&self) -> [usize; 5] {
        [&self.inputs, &self.accepted, &self.syntax, &self.tables, &self.values].map(|c| c.load(Ordering::Relaxed))
    }

    fn add(&self, other: &Stats) {
        let mine = [&self.inputs, &self.accepted, &self.syntax, &self.tables, &self.values];
        for (c, n) in mine.into_iter().zip(other.counts()) {
            c.fetch_add(n, Ordering::Relaxed);
        }
    }

    /// Counts a rejection by the earliest stage among its problems.
    fn rejected(&self, e: &FileError) {
        let stage = |p: &tdcr::io::Problem| {
            if p.position.is_none() || p.message.starts_with("is not valid TOML") {
                0
            } else if p.message.starts_with("in [")
                || p.message.contains(" in [")
                || p.message.contains("unknown key")
                || p.field == "tendon"
            {
                1
            } else {
                2
            }
        };
        let counter = match e.problems.iter().map(stage).min() {
            Some(0) => &self.syntax,
            Some(1) => &self.tables,
            _ => &self.values,
        };
        counter.fetch_add(1, Ordering::Relaxed);
    }

    fn print(&self, name: &str) {
        let [inputs, accepted, syntax, tables, values] = self.counts();
        eprintln!(
            "{name:>12}: {inputs:>6} inputs: {accepted:>6} accepted; rejected {syntax:>6} as not TOML or empty, \
             {tables:>6} at reading a table, {values:>6} at a value rule or Robot::validate"
        );
    }
}

/// Parses `text`, turning a panic into an error that shows the input.
fn parse(text: &str) -> Result<Result<RobotFile, FileError>, String> {
    catch_unwind(AssertUnwindSafe(|| tdcr::io::parse(text, NAME))).map_err(|panic| {
        PANICS.fetch_add(1, Ordering::Relaxed);
        let what = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        format!("parse panicked ({what}) on {text:?}")
    })
}

/// Panics of `parse` caught in this process (each also fails its test).
static PANICS: AtomicUsize = AtomicUsize::new(0);

/// Arrays of a wrong length that `parse` accepted (each also fails its test).
static TRUNCATIONS: AtomicUsize = AtomicUsize::new(0);

/// Whole-file problems: the only ones allowed without a place in the file.
fn whole_file(message: &str) -> bool {
    message.starts_with("is empty")
        || message.starts_with("has no [rod] table")
        || message.starts_with("is not valid TOML")
}

/// The number of lines of `text` as `tdcr::io::locate::position` counts them.
fn line_count(text: &str) -> usize {
    text.matches('\n').count() + 1
}

/// Checks a rejection: problems present, each one line with a message, a place and a field
/// (or a whole-file or top-level problem that says what it is).
fn check_rejection(text: &str, e: &FileError) -> Result<(), String> {
    if e.problems.is_empty() {
        return Err("rejected without any problem".into());
    }
    if e.file != NAME {
        return Err(format!("file name {:?} instead of {NAME:?}", e.file));
    }
    let shown = e.to_string();
    if shown.lines().count() != e.problems.len() {
        return Err(format!(
            "{} problems shown on {} lines:\n{shown}",
            e.problems.len(),
            shown.lines().count()
        ));
    }
    if let Some(line) = shown.lines().find(|l| !l.starts_with(NAME)) {
        return Err(format!("message line without the file name: {line:?}"));
    }
    let lines: Vec<&str> = text.split('\n').collect();
    for p in &e.problems {
        let message = p.message.trim();
        if message.is_empty() {
            return Err(format!("problem without a message: {p:?}"));
        }
        if p.message.contains(['\n', '\r']) {
            return Err(format!("message spans lines: {p:?}"));
        }
        match p.position {
            Some(at) => {
                if at.line < 1 || at.line > line_count(text) {
                    return Err(format!(
                        "line {} outside the text's {} lines: {p:?}",
                        at.line,
                        line_count(text)
                    ));
                }
                let width = lines[at.line - 1].chars().count();
                if at.column < 1 || at.column > width + 1 {
                    return Err(format!(
                        "column {} outside line {} of {width} characters: {p:?}",
                        at.column, at.line
                    ));
                }
            }
            None if whole_file(message) => {}
            None => {
                return Err(format!(
                    "problem without a line that is not about the whole file: {p:?}"
                ));
            }
        }
        if p.field.is_empty() {
            let top_level = message.starts_with("unknown key `") && message.contains("at the top level");
            if !(whole_file(message) || top_level) {
                return Err(format!("problem names no field: {p:?}"));
            }
        } else {
            let table = p.field.split(['.', '[']).next().unwrap_or_default();
            if !["rod", "base", "loads", "tendon", "model", "solver"].contains(&table) {
                return Err(format!("field outside the file's tables: {p:?}"));
            }
            // Shown with control characters escaped, as the message prints them.
            let printed: String = p
                .field
                .chars()
                .flat_map(|c| {
                    if c.is_control() {
                        c.escape_default().collect()
                    } else {
                        vec![c]
                    }
                })
                .collect();
            if !shown.contains(&format!("`{printed}`")) {
                return Err(format!("field not shown in the message:\n{shown}"));
            }
        }
    }
    Ok(())
}

/// Checks an acceptance: a valid robot and settings within their rules.
fn check_acceptance(file: &RobotFile) -> Result<(), String> {
    if let Err(e) = file.robot.validate() {
        return Err(format!("accepted a robot that Robot::validate rejects: {e}"));
    }
    let c = &file.solver.collocation;
    let s = &file.solver.shooting;
    if c.intervals < 1 || c.max_iterations < 1 || s.max_iterations < 1 {
        return Err(format!("accepted settings below 1: {:?}", file.solver));
    }
    // Every count that sizes an allocation within its documented bound (issue 18).
    if let Some(e) = c.validate().err().or(s.validate().err()) {
        return Err(format!("accepted settings the solvers reject: {e}"));
    }
    if c.max_iterations > MAX_ITERATIONS || c.max_intervals > MAX_INTERVALS || c.intervals > c.max_intervals {
        return Err(format!("accepted a count beyond its bound: {:?}", file.solver));
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(c.residual_tolerance) && positive(s.residual_tolerance) && positive(s.integration_tolerance))
        || c.tolerance.is_some_and(|t| !positive(t))
    {
        return Err(format!("accepted a tolerance that is not positive: {:?}", file.solver));
    }
    Ok(())
}

/// The whole property for one input.
fn check(text: &str, stats: &Stats) -> Result<(), TestCaseError> {
    stats.inputs.fetch_add(1, Ordering::Relaxed);
    let outcome = parse(text).map_err(TestCaseError::fail)?;
    let verdict = match &outcome {
        Ok(file) => {
            stats.accepted.fetch_add(1, Ordering::Relaxed);
            check_acceptance(file)
        }
        Err(e) => {
            stats.rejected(e);
            check_rejection(text, e)
        }
    };
    verdict.map_err(|why| TestCaseError::fail(format!("{why}\ninput: {text:?}")))
}

/// A runner with a fixed seed and no failure persistence (CI is repeatable, writes nothing).
fn runner(cases: u32, seed: u64) -> TestRunner {
    TestRunner::new(Config {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(seed),
        // Inputs are small; shrinking a failure to its core is worth a few thousand steps.
        max_shrink_iters: 4096,
        ..Config::default()
    })
}

/// Runs the property over `cases` inputs of `strategy`; panics with the (shrunk) failing input.
fn fuzz(name: &str, cases: u32, seed: u64, strategy: impl Strategy<Value = String>) -> Stats {
    let stats = Stats::default();
    let result = runner(cases, seed).run(&strategy, |text| check(&text, &stats));
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    stats
}

// ---------------------------------------------------------------------------------------
// Inputs

/// Random f64 with the edge cases over-represented: zeros, subnormals, extremes, NaN, inf.
fn float() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => any::<f64>(),
        2 => prop::sample::select(vec![
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            f64::MIN_POSITIVE,
            1e-300,
            1e-7,
            0.5,
            1.0,
            -1.0,
            1e308,
            -1e308,
            f64::MAX,
            f64::MIN,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ]),
        2 => -1e3f64..1e3,
        2 => 1e-6f64..1.0,
    ]
}

/// `x` as a TOML literal (`nan`, `inf`, `-inf` for the non-finite ones).
fn toml_float(x: f64) -> String {
    if x.is_nan() {
        if x.is_sign_negative() {
            "-nan".into()
        } else {
            "nan".into()
        }
    } else if x.is_infinite() {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        // Debug prints the shortest round-trip form, e.g. `1e308`, `5e-324`, `0.1`: all TOML.
        format!("{x:?}")
    }
}

/// A number literal: a random f64, an integer, or junk.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => float().prop_map(toml_float),
        1 => any::<i64>().prop_map(|i| i.to_string()),
        1 => (0i64..100).prop_map(|i| i.to_string()),
        2 => prop::sample::select(NUMBER_JUNK).prop_map(str::to_string),
    ]
}

/// A key: a known one, a random identifier, a quoted or a dotted key.
fn key() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => prop::sample::select(KEYS).prop_map(str::to_string),
        2 => "[a-z_][a-z0-9_]{0,10}",
        1 => "\"[ -~]{0,8}\"",
        1 => (prop::sample::select(TABLE_NAMES), prop::sample::select(KEYS)).prop_map(|(t, k)| format!("{t}.{k}")),
        1 => Just(String::new()),
    ]
}

/// A TOML value: numbers, strings the file knows, booleans, arrays and inline tables.
fn value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        6 => number(),
        1 => prop::sample::select(vec!["\"straight\"", "\"helical\"", "\"collocation\"", "\"shooting\"", "\"\""])
            .prop_map(str::to_string),
        1 => "\"[ -~]{0,10}\"",
        1 => prop::sample::select(vec!["true", "false"]).prop_map(str::to_string),
    ];
    leaf.prop_recursive(3, 24, 4, |inner| {
        prop_oneof![
            // Vectors, mostly of three numbers.
            3 => prop::collection::vec(number(), 3).prop_map(|v| format!("[{}]", v.join(", "))),
            2 => prop::collection::vec(inner.clone(), 0..5).prop_map(|v| format!("[{}]", v.join(", "))),
            2 => prop::collection::vec((key(), inner), 0..5).prop_map(|kv| {
                let fields: Vec<String> = kv.into_iter().map(|(k, v)| format!("{k} = {v}")).collect();
                format!("{{ {} }}", fields.join(", "))
            }),
        ]
    })
}

/// A random TOML document over the file's tables and keys.
fn document() -> impl Strategy<Value = String> {
    let header = prop_oneof![
        4 => prop::sample::select(TABLE_NAMES).prop_map(|t| format!("[{t}]")),
        3 => prop::sample::select(TABLE_NAMES).prop_map(|t| format!("[[{t}]]")),
        1 => key().prop_map(|k| format!("[{k}]")),
        1 => Just(String::new()),
    ];
    let line = (key(), value()).prop_map(|(k, v)| format!("{k} = {v}"));
    let section = (header, prop::collection::vec(line, 0..8));
    (any::<bool>(), prop::collection::vec(section, 0..6)).prop_map(|(rod, sections)| {
        // Half the documents start with a valid [rod], so the other tables get past reading.
        let mut text = if rod { ROD.to_string() } else { String::new() };
        for (header, lines) in sections {
            text.push_str(&header);
            text.push('\n');
            for l in lines {
                text.push_str(&l);
                text.push('\n');
            }
        }
        text
    })
}

/// TOML-looking junk: tokens and fragments of the example strung together.
fn junk() -> impl Strategy<Value = String> {
    let example = tdcr::io::example();
    let lines: Vec<String> = example.lines().map(str::to_string).collect();
    let piece = prop_oneof![
        4 => prop::sample::select(TOKENS).prop_map(str::to_string),
        2 => number(),
        1 => key(),
        1 => prop::sample::select(lines),
        1 => "[ -~]{0,6}",
    ];
    prop::collection::vec(piece, 0..60).prop_map(|pieces| pieces.concat())
}

/// Nesting past any sane depth: arrays, inline tables, dotted keys and table headers.
fn nested() -> impl Strategy<Value = String> {
    let depth = prop_oneof![0usize..100, 100usize..3000];
    (depth, 0u8..8, any::<bool>()).prop_map(|(n, shape, balanced)| {
        let close = |s: &str| if balanced { s.repeat(n) } else { s.repeat(n / 2) };
        match shape {
            0 => format!("{ROD}precurvature = {}1.0{}\n", "[".repeat(n), close("]")),
            1 => format!("{ROD}[loads]\ntip_force = {}{}\n", "[".repeat(n), close("]")),
            2 => format!(
                "{ROD}[[tendon]]\nrouting = {}{}\ntension = 1\n",
                "{ a = ".repeat(n),
                close("}")
            ),
            3 => format!("{ROD}[base]\nposition.{}x = 1\n", "a.".repeat(n)),
            4 => format!("{ROD}[{}]\n", vec!["rod"; n.max(1)].join(".")),
            5 => format!("{ROD}[[{}]]\n", vec!["tendon"; n.max(1)].join(".")),
            6 => format!("{ROD}tip = {}\n", "[[".repeat(n)),
            _ => format!("{}{ROD}", "[rod]\n".repeat(n)),
        }
    })
}

/// Ranges of `ident =` keys, table names and numbers in the example (outside comments).
struct Spots {
    numbers: Vec<(usize, usize)>,
    keys: Vec<(usize, usize)>,
    brackets: Vec<usize>,
}

fn spots(text: &str) -> Spots {
    let mut spots = Spots {
        numbers: Vec::new(),
        keys: Vec::new(),
        brackets: Vec::new(),
    };
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let code = &line[..line.find('#').unwrap_or(line.len())];
        let bytes = code.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            let after_word = i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
            if matches!(c, b'[' | b']' | b'{' | b'}') {
                spots.brackets.push(start + i);
                i += 1;
            } else if !after_word
                && (c.is_ascii_digit() || (c == b'-' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit)))
            {
                let j = i
                    + 1
                    + bytes[i + 1..]
                        .iter()
                        .take_while(|b| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'-' | b'+' | b'_'))
                        .count();
                spots.numbers.push((start + i, start + j));
                i = j;
            } else if !after_word && (c.is_ascii_alphabetic() || c == b'_') {
                let j = i + bytes[i..]
                    .iter()
                    .take_while(|b| b.is_ascii_alphanumeric() || **b == b'_')
                    .count();
                let rest = code[j..].trim_start();
                let before = code[..i].trim_end();
                if rest.starts_with('=') || before.ends_with('[') {
                    spots.keys.push((start + i, start + j));
                }
                i = j;
            } else {
                i += 1;
            }
        }
        start += line.len();
    }
    spots
}

/// One edit of a file's text.
#[derive(Clone, Debug)]
enum Mutation {
    DeleteLine(Index),
    DuplicateLine(Index),
    SwapLines(Index, Index),
    Uncomment(Index),
    InsertLine(Index, String),
    ReplaceNumber(Index, String),
    RenameKey(Index, String),
    DropBracket(Index),
    Truncate(Index),
    /// Windows line ends everywhere.
    CrLf,
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let junk_line = prop_oneof![
        (key(), value()).prop_map(|(k, v)| format!("{k} = {v}")),
        prop::sample::select(TABLE_NAMES).prop_map(|t| format!("[{t}]")),
        prop::sample::select(TABLE_NAMES).prop_map(|t| format!("[[{t}]]")),
        "[ -~]{0,20}",
    ];
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::DeleteLine),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        2 => any::<Index>().prop_map(Mutation::Uncomment),
        1 => (any::<Index>(), junk_line).prop_map(|(i, l)| Mutation::InsertLine(i, l)),
        6 => (any::<Index>(), number()).prop_map(|(i, n)| Mutation::ReplaceNumber(i, n)),
        2 => (any::<Index>(), key()).prop_map(|(i, k)| Mutation::RenameKey(i, k)),
        1 => any::<Index>().prop_map(Mutation::DropBracket),
        1 => any::<Index>().prop_map(Mutation::Truncate),
        1 => Just(Mutation::CrLf),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let joined = |lines: Vec<String>| lines.join("\n") + "\n";
    let splice = |(a, b): (usize, usize), with: &str| format!("{}{with}{}", &text[..a], &text[b..]);
    match m {
        Mutation::DeleteLine(i) if !lines.is_empty() => {
            lines.remove(i.index(lines.len()));
            joined(lines)
        }
        Mutation::DuplicateLine(i) if !lines.is_empty() => {
            let k = i.index(lines.len());
            lines.insert(k, lines[k].clone());
            joined(lines)
        }
        Mutation::SwapLines(a, b) if !lines.is_empty() => {
            let n = lines.len();
            lines.swap(a.index(n), b.index(n));
            joined(lines)
        }
        Mutation::Uncomment(i) => {
            let commented: Vec<usize> = (0..lines.len())
                .filter(|&k| lines[k].trim_start().starts_with('#'))
                .collect();
            if commented.is_empty() {
                return text.to_string();
            }
            let k = commented[i.index(commented.len())];
            lines[k] = lines[k].trim_start().trim_start_matches('#').trim_start().to_string();
            joined(lines)
        }
        Mutation::InsertLine(i, line) => {
            lines.insert(i.index(lines.len() + 1), line.clone());
            joined(lines)
        }
        Mutation::ReplaceNumber(i, n) => match spots(text).numbers.as_slice() {
            [] => text.to_string(),
            s => splice(s[i.index(s.len())], n),
        },
        Mutation::RenameKey(i, k) => match spots(text).keys.as_slice() {
            [] => text.to_string(),
            s => splice(s[i.index(s.len())], k),
        },
        Mutation::DropBracket(i) => match spots(text).brackets.as_slice() {
            [] => text.to_string(),
            s => {
                let at = s[i.index(s.len())];
                splice((at, at + 1), "")
            }
        },
        Mutation::Truncate(i) => {
            let mut at = i.index(text.len() + 1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            text[..at].to_string()
        }
        Mutation::CrLf => text.replace("\r\n", "\n").replace('\n', "\r\n"),
        _ => text.to_string(),
    }
}

/// The example with one to four random edits.
fn mutated_example() -> impl Strategy<Value = String> {
    let example = tdcr::io::example();
    prop::collection::vec(mutation(), 1..=4)
        .prop_map(move |edits| edits.iter().fold(example.clone(), |t, m| apply(&t, m)))
}

/// The example with numbers only replaced (1 to 6 of them): the deeper stages (value rules,
/// `Robot::validate`) see most of these.
fn renumbered_example() -> impl Strategy<Value = String> {
    let example = tdcr::io::example();
    let edit = (any::<Index>(), float().prop_map(toml_float)).prop_map(|(i, n)| Mutation::ReplaceNumber(i, n));
    let uncomment = prop::collection::vec(any::<Index>().prop_map(Mutation::Uncomment), 0..3);
    (uncomment, prop::collection::vec(edit, 1..=6))
        .prop_map(move |(u, edits)| u.iter().chain(&edits).fold(example.clone(), |t, m| apply(&t, m)))
}

fn bytes() -> impl Strategy<Value = String> {
    prop::collection::vec(any::<u8>(), 0..400).prop_map(|b| String::from_utf8_lossy(&b).into_owned())
}

fn strings() -> impl Strategy<Value = String> {
    prop_oneof![any::<String>(), "[ -~\n\t]{0,200}", "\\PC{0,100}"]
}

// ---------------------------------------------------------------------------------------
// Field rules: a value that breaks a documented rule must be rejected at that field's line

/// One field of the example and values that break its rule (docs/robot-file.md).
struct Rule {
    /// The example's line, as a prefix (after uncommenting).
    line: &'static str,
    /// The value's text on that line.
    value: &'static str,
    /// The field path the problem must name.
    field: &'static str,
    /// Whether `x` breaks the rule.
    breaks: fn(f64) -> bool,
}

fn not_positive(x: f64) -> bool {
    !(x.is_finite() && x > 0.0)
}

fn not_finite(x: f64) -> bool {
    !x.is_finite()
}

const RULES: &[Rule] = &[
    Rule {
        line: "length = ",
        value: "0.242",
        field: "rod.length",
        breaks: not_positive,
    },
    Rule {
        line: "outer_radius = ",
        value: "0.0004",
        field: "rod.outer_radius",
        breaks: not_positive,
    },
    Rule {
        line: "inner_radius = ",
        value: "0.0",
        field: "rod.inner_radius",
        breaks: |x| !(x.is_finite() && (0.0..0.0004).contains(&x)),
    },
    Rule {
        line: "youngs_modulus = ",
        value: "210e9",
        field: "rod.youngs_modulus",
        breaks: not_positive,
    },
    Rule {
        line: "poisson_ratio = ",
        value: "0.3125",
        field: "rod.poisson_ratio",
        breaks: |x| !(x > -1.0 && x <= 0.5),
    },
    Rule {
        line: "precurvature = ",
        value: "0.0",
        field: "rod.precurvature",
        breaks: not_finite,
    },
    Rule {
        line: "position = ",
        value: "0.0",
        field: "base.position",
        breaks: not_finite,
    },
    // One entry of a rotation moved by more than the 1e-6 tolerance breaks orthonormality.
    Rule {
        line: "rotation = ",
        value: "1.0",
        field: "base.rotation",
        breaks: |x| x.is_nan() || (x - 1.0).abs() >= 1e-3,
    },
    Rule {
        line: "distributed_force = ",
        value: "-0.47",
        field: "loads.distributed_force",
        breaks: not_finite,
    },
    Rule {
        line: "tip_force = ",
        value: "0.0",
        field: "loads.tip_force",
        breaks: not_finite,
    },
    Rule {
        line: "tip_moment = ",
        value: "0.0",
        field: "loads.tip_moment",
        breaks: not_finite,
    },
    Rule {
        line: "tension = ",
        value: "2.94",
        field: "tendon[1].tension",
        breaks: |x| !(x.is_finite() && x >= 0.0),
    },
    Rule {
        line: "end = ",
        value: "0.242",
        field: "tendon[1].end",
        breaks: |x| !(x.is_finite() && x > 0.0 && x <= 0.242),
    },
    Rule {
        line: "routing = { kind = \"straight\", x = 0.008",
        value: "0.008",
        field: "tendon[1].routing.x",
        breaks: not_finite,
    },
    Rule {
        line: "routing = { kind = \"helical\"",
        value: "0.008",
        field: "tendon[5].routing.radius",
        breaks: not_positive,
    },
    Rule {
        line: "routing = { kind = \"helical\"",
        value: "1.0",
        field: "tendon[5].routing.turns_per_rod_length",
        breaks: not_finite,
    },
    Rule {
        line: "residual_tolerance = ",
        value: "1e-11",
        field: "solver.residual_tolerance",
        breaks: not_positive,
    },
    Rule {
        line: "tolerance = ",
        value: "1e-7",
        field: "solver.tolerance",
        breaks: not_positive,
    },
];

/// The example with every comment-only line uncommented where it is a plain `key = value`
/// line of a table that stays consistent (inner radius, precurvature, end, tolerances).
fn rules_example() -> String {
    let mut text = tdcr::io::example();
    for line in [
        "# inner_radius = 0.0",
        "# precurvature = [0.0, 0.0, 0.0]",
        "# end = 0.242",
        "# tolerance = 1e-7",
        "# residual_tolerance = 1e-11",
    ] {
        assert!(text.contains(line), "the example lost `{line}`");
        text = text.replacen(line, &line[2..], 1);
    }
    text
}

/// Breaks one field and checks the rejection names it on its line.
fn check_rule(base: &str, rule: &Rule, x: f64, stats: &Stats) -> Result<(), TestCaseError> {
    stats.inputs.fetch_add(1, Ordering::Relaxed);
    let (number, line) = base
        .lines()
        .enumerate()
        .find(|(_, l)| l.starts_with(rule.line))
        .unwrap_or_else(|| panic!("the example has no line `{}`", rule.line));
    let at = base.lines().take(number).map(|l| l.len() + 1).sum::<usize>();
    let column = line
        .find(rule.value)
        .unwrap_or_else(|| panic!("no `{}` in `{line}`", rule.value));
    let text = format!(
        "{}{}{}",
        &base[..at + column],
        toml_float(x),
        &base[at + column + rule.value.len()..]
    );
    let outcome = parse(&text).map_err(TestCaseError::fail)?;
    match outcome {
        Ok(file) => {
            stats.accepted.fetch_add(1, Ordering::Relaxed);
            if (rule.breaks)(x) {
                return Err(TestCaseError::fail(format!(
                    "accepted `{}` = {} against its rule\nline {}: {}",
                    rule.field,
                    toml_float(x),
                    number + 1,
                    text.lines().nth(number).unwrap_or_default()
                )));
            }
            check_acceptance(&file).map_err(TestCaseError::fail)
        }
        Err(e) => {
            stats.rejected(&e);
            check_rejection(&text, &e).map_err(|why| TestCaseError::fail(format!("{why}\ninput: {text:?}")))?;
            let named = e
                .problems
                .iter()
                .any(|p| p.field == rule.field && p.position.is_some_and(|q| q.line == number + 1));
            if (rule.breaks)(x) && !named {
                return Err(TestCaseError::fail(format!(
                    "`{}` = {} was rejected, but no problem names it on line {}:\n{e}",
                    rule.field,
                    toml_float(x),
                    number + 1
                )));
            }
            Ok(())
        }
    }
}

fn fuzz_rules(cases: u32, seed: u64) -> Stats {
    let base = rules_example();
    // The base must be valid, or every check below would be vacuous.
    if let Err(e) = tdcr::io::parse(&base, NAME) {
        panic!("the uncommented example is rejected:\n{e}");
    }
    let stats = Stats::default();
    let strategy = (0..RULES.len(), float());
    let result = runner(cases, seed).run(&strategy, |(k, x)| check_rule(&base, &RULES[k], x, &stats));
    if let Err(e) = result {
        panic!("field rules: {e}");
    }
    stats
}

// ---------------------------------------------------------------------------------------
// Counts and array lengths (issue 18)

/// The `[solver]` keys whose values are counts that size allocations.
const SOLVER_COUNTS: &[&str] = &["intervals", "nodes", "max_intervals", "max_nodes", "max_iterations"];

/// A count from 0 to u64::MAX, the bounds and the powers of two over-represented (TOML
/// integers stop at 2^63 - 1: larger ones must be syntax errors, not panics).
fn big_count() -> impl Strategy<Value = u64> {
    prop_oneof![
        2 => any::<u64>(),
        2 => (0u32..64).prop_map(|k| 1u64 << k),
        1 => (0u32..64).prop_map(|k| (1u64 << k) - 1),
        3 => prop::sample::select(vec![
            0,
            1,
            30,
            8192,
            MAX_ITERATIONS as u64,
            MAX_ITERATIONS as u64 + 1,
            MAX_INTERVALS as u64,
            MAX_INTERVALS as u64 + 1,
            1_000_000_000,
            (1 << 32) - 1,
            1 << 32,
            i64::MAX as u64,
            i64::MAX as u64 + 1,
            u64::MAX,
        ]),
    ]
}

/// A file whose `[solver]` table sets one to three count keys to [`big_count`]s.
fn solver_counts() -> impl Strategy<Value = String> {
    prop::collection::btree_map(prop::sample::select(SOLVER_COUNTS), big_count(), 1..4).prop_map(|keys| {
        let lines: String = keys.iter().map(|(k, n)| format!("{k} = {n}\n")).collect();
        format!("{ROD}[solver]\n{lines}")
    })
}

/// Every vector field of a robot file: its table header (`None`: in `[rod]`), the lines
/// before it and its field path.
const VECTOR_FIELDS: &[(Option<&str>, &str, &str)] = &[
    (None, "precurvature", "rod.precurvature"),
    (Some("[base]"), "position", "base.position"),
    (Some("[base]"), "euler_xyz_deg", "base.euler_xyz_deg"),
    (Some("[loads]"), "distributed_force", "loads.distributed_force"),
    (Some("[loads]"), "distributed_moment", "loads.distributed_moment"),
    (Some("[loads]"), "tip_force", "loads.tip_force"),
    (Some("[loads]"), "tip_moment", "loads.tip_moment"),
    (Some("[[loads.point]]\ns = 0.1"), "force", "loads.point[1].force"),
    (Some("[[loads.point]]\ns = 0.1"), "moment", "loads.point[1].moment"),
];

/// An array entry: mostly a small number, sometimes NaN, a string, a table or an array (the
/// issue's truncated extras).
fn entry() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => (-1.0f64..1.0).prop_map(|x| format!("{x:?}")),
        1 => prop::sample::select(vec!["nan", "\"x\"", "{ a = 1 }", "[1.0]", "true", "inf"]).prop_map(str::to_string),
    ]
}

/// One array-length case: the file, the field path, the lengths given (one for a vector;
/// the row count then each row's length for the rotation) and whether every entry is a
/// finite number.
#[derive(Clone, Debug)]
struct LengthCase {
    text: String,
    field: &'static str,
    lengths: Vec<usize>,
    numbers: bool,
}

/// A vector field with 0 to 6 entries, or `base.rotation` with 0 to 6 rows of 0 to 6 entries
/// (the identity's entries where it has them, so that 3 x 3 is a rotation).
fn array_lengths() -> impl Strategy<Value = LengthCase> {
    let vector = (0..VECTOR_FIELDS.len(), prop::collection::vec(entry(), 0..=6)).prop_map(|(k, entries)| {
        let (table, key, field) = VECTOR_FIELDS[k];
        let numbers = entries.iter().all(|e| e.parse::<f64>().is_ok_and(f64::is_finite));
        let header = table.map_or(String::new(), |t| format!("{t}\n"));
        LengthCase {
            text: format!("{ROD}{header}{key} = [{}]\n", entries.join(", ")),
            field,
            lengths: vec![entries.len()],
            numbers,
        }
    });
    let matrix = prop::collection::vec(0usize..=6, 0..=6).prop_map(|rows| {
        let text: Vec<String> = rows
            .iter()
            .enumerate()
            .map(|(i, &n)| {
                let row: Vec<&str> = (0..n).map(|j| if i == j { "1.0" } else { "0.0" }).collect();
                format!("[{}]", row.join(", "))
            })
            .collect();
        let mut lengths = vec![rows.len()];
        lengths.extend(&rows);
        LengthCase {
            text: format!("{ROD}[base]\nrotation = [{}]\n", text.join(", ")),
            field: "base.rotation",
            lengths,
            numbers: true,
        }
    });
    prop_oneof![3 => vector, 1 => matrix]
}

/// The property of one length case: the general one, and a wrong length is never accepted
/// (that would be a silent truncation or padding); with numbers only, a problem at the field
/// (or its row) gives the length found and the 3 expected.
fn check_length(case: &LengthCase, stats: &Stats) -> Result<(), TestCaseError> {
    check(&case.text, stats)?;
    let right = case.lengths.iter().all(|&n| n == 3);
    match parse(&case.text).map_err(TestCaseError::fail)? {
        Ok(_) if !right => {
            TRUNCATIONS.fetch_add(1, Ordering::Relaxed);
            Err(TestCaseError::fail(format!(
                "accepted `{}` with lengths {:?}:\n{}",
                case.field, case.lengths, case.text
            )))
        }
        Err(e) if !right && case.numbers => {
            // The rotation's rows are read first: the problem is at the first wrong one.
            let named = e.problems.iter().any(|p| {
                p.field.starts_with(case.field)
                    && p.position.is_some()
                    && case
                        .lengths
                        .iter()
                        .any(|&n| n != 3 && p.message.contains(&format!("has {n} entries, but must have 3")))
            });
            if named {
                Ok(())
            } else {
                Err(TestCaseError::fail(format!(
                    "`{}` with lengths {:?} rejected without naming the length:\n{e}",
                    case.field, case.lengths
                )))
            }
        }
        Err(e) if right && case.numbers => Err(TestCaseError::fail(format!(
            "rejected `{}` of the right length:\n{e}\n{}",
            case.field, case.text
        ))),
        _ => Ok(()),
    }
}

/// Runs [`check_length`] over `cases` inputs.
fn fuzz_lengths(cases: u32, seed: u64) -> Stats {
    let stats = Stats::default();
    let result = runner(cases, seed).run(&array_lengths(), |case| check_length(&case, &stats));
    if let Err(e) = result {
        panic!("array lengths: {e}");
    }
    stats
}

/// A robot file with `n` straight tendons (the last with `last_tension`) and `points` point
/// loads.
fn big_file(n: usize, points: usize, last_tension: f64) -> String {
    let mut text = format!("{ROD}[loads]\n");
    for k in 0..points {
        text.push_str(&format!(
            "[[loads.point]]\ns = {}\nforce = [0.0, 0.0, {}]\n",
            0.1 + 1e-7 * k as f64,
            -1e-3 * (k % 7) as f64
        ));
    }
    for k in 0..n {
        let tension = if k + 1 == n { last_tension } else { 0.0 };
        text.push_str(&format!(
            "[[tendon]]\nrouting = {{ kind = \"straight\", x = 0.008, y = {:?} }}\ntension = {tension:?}\n",
            1e-9 * k as f64
        ));
    }
    text
}

/// Parses the big file of `n` tendons and point loads: every one is read (none dropped), and
/// a bad last tension is found on its line. Returns the seconds the valid file took.
fn check_big_file(n: usize) -> f64 {
    let text = big_file(n, n, 1.0);
    let start = Instant::now();
    let file = match parse(&text) {
        Ok(Ok(file)) => file,
        Ok(Err(e)) => panic!("{n} tendons: rejected:\n{e}"),
        Err(why) => panic!("{n} tendons: {why}"),
    };
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!((file.robot.tendons.len(), file.robot.loads.point.len()), (n, n));
    assert_eq!(file.robot.tendons[n - 1].tension(), 1.0);
    let bad = big_file(n, n, -1.0);
    let line = bad.lines().count();
    let e = match parse(&bad) {
        Ok(Err(e)) => e,
        Ok(Ok(_)) => panic!("{n} tendons: a negative tension is accepted"),
        Err(why) => panic!("{n} tendons: {why}"),
    };
    check_rejection(&bad, &e).unwrap_or_else(|why| panic!("{n} tendons: {why}"));
    let field = format!("tendon[{n}].tension");
    assert!(
        e.problems
            .iter()
            .any(|p| p.field == field && p.position.is_some_and(|q| q.line == line)),
        "{n} tendons: no problem at `{field}` on line {line}:\n{e}"
    );
    seconds
}

#[test]
fn solver_counts_up_to_u64_max_are_bounded() {
    let stats = fuzz("solver counts", 600, 11, solver_counts());
    assert!(stats.accepted.load(Ordering::Relaxed) > 0);
}

#[test]
fn arrays_of_every_length_from_0_to_6_are_never_truncated() {
    let stats = fuzz_lengths(1000, 12);
    assert!(stats.accepted.load(Ordering::Relaxed) > 0);
}

#[test]
fn thousands_of_tendons_and_point_loads_are_all_read() {
    for n in [1000, 10_000] {
        check_big_file(n);
    }
}

// ---------------------------------------------------------------------------------------
// The parser tests: CI sizes

#[test]
fn parser_survives_arbitrary_bytes() {
    fuzz("bytes", 500, 1, bytes());
}

#[test]
fn parser_survives_arbitrary_strings() {
    fuzz("strings", 500, 2, strings());
}

#[test]
fn parser_survives_toml_looking_junk() {
    fuzz("junk", 800, 3, junk());
}

#[test]
fn parser_survives_deep_nesting() {
    fuzz("nested", 200, 4, nested());
}

#[test]
fn parser_survives_random_documents() {
    fuzz("documents", 800, 5, document());
}

#[test]
fn parser_survives_mutations_of_the_example() {
    let stats = fuzz("mutations", 1200, 6, mutated_example());
    // Single edits leave many files valid; a run where none is accepted would test only the
    // rejection path.
    assert!(stats.accepted.load(Ordering::Relaxed) > 0);
}

#[test]
fn parser_survives_random_numbers_in_the_example() {
    let stats = fuzz("numbers", 800, 7, renumbered_example());
    assert!(stats.accepted.load(Ordering::Relaxed) > 0);
}

#[test]
fn parser_rejects_every_value_that_breaks_its_rule_at_its_line() {
    let stats = fuzz_rules(600, 8);
    assert!(stats.accepted.load(Ordering::Relaxed) > 0);
}

/// Hand-picked inputs the strategies reach only by luck.
#[test]
fn parser_survives_hand_picked_edge_cases() {
    let stats = Stats::default();
    let mut inputs: Vec<String> = [
        "",
        " ",
        "\n\n\n",
        "\u{feff}",
        "\u{0}",
        "#",
        "[",
        "]",
        "[[",
        "=",
        "a",
        "a =",
        "= 1",
        "rod = 1",
        "[rod]",
        "[[rod]]",
        "[rod]\n[rod]",
        "rod = []",
        "rod = [{}]",
        "tendon = 1",
        "tendon = []",
        "tendon = [1]",
        "[[tendon]]",
        "[[tendon]]\n[[tendon]]",
        "[solver]",
        "[loads]\npoint = 1",
        "[[loads.point]]",
        "\r",
        "\r\n",
        "[rod]\r",
        "[rod]\rlength=1",
        "a=1\r\nb=2\r\n",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for tail in [
        "[solver]\nintervals = 0",
        "[solver]\nintervals = -1",
        "[solver]\nintervals = 1.5",
        "[solver]\nintervals = 9223372036854775807",
        "[solver]\nmax_intervals = 1\nintervals = 2",
        "[solver]\nmax_intervals = 1",
        "[solver]\nnodes = 0",
        "[solver]\nmax_nodes = 1\nnodes = 2",
        "[solver]\nnodes = 2\nintervals = 2",
        "[solver]\nmax_nodes = 0\nmax_intervals = 0",
        "[solver]\nmethod = \"newton\"",
        "[solver]\nmax_iterations = 0",
        "[solver]\ncontinuation = 1",
        "[[tendon]]\nrouting = { kind = \"helical\", radius = 0.001, turns = 1e300 }\ntension = 1",
        "[[tendon]]\nrouting = { kind = \"helical\", radius = 1e300, turns = 1 }\ntension = 1",
        "[[tendon]]\nrouting = { kind = \"helical\", radius = 5e-324, turns = 5e-324 }\ntension = 1",
        "[[tendon]]\nrouting = { kind = \"straight\", x = 1e308, y = 1e308 }\ntension = 1e308",
        "[[tendon]]\nrouting = { kind = \"straight\", x = 0, y = 0 }\ntension = 0\nend = 5e-324",
        "[[tendon]]\nrouting = { kind = \"bent\" }\ntension = 1",
        "[[tendon]]\nrouting = { x = 0, y = 0 }\ntension = 1",
        "[[tendon]]\nrouting = \"straight\"\ntension = 1",
        "[[tendon]]\nrouting.kind = \"straight\"\nrouting.x = 0\nrouting.y = 0\ntension = 1",
        "[[tendon]]\n[tendon.routing]\nkind = \"straight\"\nx = 0\ny = 0",
        "[[loads.point]]\ns = 5e-324",
        "[[loads.point]]\ns = 0.2\nforce = [1e308, 1e308, 1e308]",
        "[loads]\ndistributed_force = [1e308, -1e308, 0]",
        "[base]\nrotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\neuler_xyz_deg = [0, 0, 0]",
        "[base]\nrotation = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]",
        "[base]\nrotation = [[1, 0, 0], [0, 1, 0]]",
        "[base]\nrotation = [[nan, 0, 0], [0, 1, 0], [0, 0, 1]]",
        "[base]\neuler_xyz_deg = [1e308, 1e308, 1e308]",
        "[base]\neuler_xyz_deg = [inf, 0, 0]",
        "[unknown]",
        "tendons = 1",
        "load = 1",
        "[rod.extra]",
        "[rod]",
    ] {
        inputs.push(format!("{ROD}{tail}\n"));
    }
    for rod_line in [
        "length = 5e-324",
        "length = 1e308",
        "outer_radius = 5e-324",
        "outer_radius = 1e308",
        "youngs_modulus = 5e-324",
        "youngs_modulus = 1e308",
        "poisson_ratio = -0.9999999999999999",
        "shear_modulus = 1",
        "inner_radius = 0.000999999999999",
        "precurvature = [1e308, 1e308, 1e308]",
    ] {
        let key = rod_line.split(' ').next().unwrap_or_default();
        let mut text: String = ROD
            .lines()
            .filter(|l| !l.starts_with(&format!("{key} ")))
            .map(|l| format!("{l}\n"))
            .collect();
        text.push_str(rod_line);
        text.push_str("\n[[tendon]]\nrouting = { kind = \"helical\", radius = 0.0005, turns = 3 }\ntension = 1\n");
        inputs.push(text);
    }
    for text in &inputs {
        if let Err(e) = check(text, &stats) {
            panic!("{e}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// The long run

/// 165 000 parser inputs over every strategy above (25 times the CI sizes, other seeds) and
/// the files of 10^3 to 10^5 tendons and point loads, with counts and time printed. Run it with
/// `cargo test --release --test fuzz -- --ignored --nocapture long_`.
#[test]
#[ignore = "long: 165 000 inputs; cargo test --release --test fuzz -- --ignored --nocapture long_"]
fn long_parser_fuzz() {
    let start = Instant::now();
    let total = Stats::default();
    let scale = 25;
    let runs: Vec<(&str, Stats)> = vec![
        ("bytes", fuzz("bytes", 500 * scale, 101, bytes())),
        ("strings", fuzz("strings", 500 * scale, 102, strings())),
        ("junk", fuzz("junk", 800 * scale, 103, junk())),
        ("nested", fuzz("nested", 200 * scale, 104, nested())),
        ("documents", fuzz("documents", 800 * scale, 105, document())),
        ("mutations", fuzz("mutations", 1200 * scale, 106, mutated_example())),
        ("numbers", fuzz("numbers", 800 * scale, 107, renumbered_example())),
        ("field rules", fuzz_rules(200 * scale, 108)),
        ("counts", fuzz("solver counts", 600 * scale, 109, solver_counts())),
        ("lengths", fuzz_lengths(1000 * scale, 110)),
    ];
    for (name, stats) in &runs {
        stats.print(name);
        total.add(stats);
    }
    total.print("total");
    for n in [1000, 10_000, 100_000] {
        let seconds = check_big_file(n);
        // Printed, not asserted: wall time depends on the machine's load. That the work
        // grows linearly is asserted by tests/parse_time.rs (allocations and bytes).
        eprintln!("{n:>7} tendons and {n} point loads: parsed and checked in {seconds:.2} s");
    }
    let inputs = total.counts()[0];
    let (panics, truncations) = (PANICS.load(Ordering::Relaxed), TRUNCATIONS.load(Ordering::Relaxed));
    // An abort (a failed allocation) would have ended this process before this line.
    eprintln!(
        "{inputs} inputs in {:.1} s: {panics} panics, 0 aborts, {truncations} silent truncations",
        start.elapsed().as_secs_f64()
    );
    assert!(inputs >= 100_000, "{inputs} inputs");
    assert_eq!((panics, truncations), (0, 0));
}

// ---------------------------------------------------------------------------------------
// The command line

const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tdcr-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    dir
}

/// Runs `tdcr args` in `dir`; exit code (None when killed by a signal) and standard error.
/// A run longer than a minute is killed and fails the test.
fn run(dir: &std::path::Path, args: &[String]) -> (Option<i32>, String) {
    let mut child = Command::new(TDCR)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {TDCR}: {e}"));
    let mut stderr = child.stderr.take().expect("stderr is piped");
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for tdcr") {
            break status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("tdcr {args:?} ran for over a minute");
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    (status.code(), reader.join().unwrap_or_default())
}

/// Whether a run ended as the command documents for bad or good input: exit 0, 2 or 3, an
/// `error:` line when it failed, and no panic.
fn clean_exit(args: &[String], code: Option<i32>, stderr: &str) -> Result<(), String> {
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") || stderr.contains("stack backtrace") {
        return Err(format!("tdcr {args:?} panicked (exit {code:?}):\n{stderr}"));
    }
    if !matches!(code, Some(0 | 2 | 3)) {
        return Err(format!("tdcr {args:?} exited with {code:?}:\n{stderr}"));
    }
    // `warning:` lines (implausible scales, before a solve) may precede the error.
    let first = stderr.lines().find(|l| !l.starts_with("warning: ")).unwrap_or("");
    if code != Some(0) && !first.starts_with("error: ") {
        return Err(format!(
            "tdcr {args:?} exited with {code:?} without an error line:\n{stderr}"
        ));
    }
    Ok(())
}

/// A number for the command line: plain, extreme or junk.
fn cli_number() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (0.0f64..10.0).prop_map(|x| format!("{x}")),
        2 => float().prop_map(|x| format!("{x}")),
        2 => prop::sample::select(NUMBER_JUNK).prop_map(str::to_string),
        1 => "[-+0-9.eE_ a-z]{0,6}",
    ]
}

fn tension_arg() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (0usize..8, cli_number()).prop_map(|(i, v)| format!("{i}={v}")),
        1 => (cli_number(), cli_number()).prop_map(|(i, v)| format!("{i}={v}")),
        1 => "[-+=:,0-9.eE a-z]{0,10}",
        1 => prop::sample::select(vec!["", "=", "1=", "=1", "1==1", " 1 = 2 ", "1=2=3", "-1=1", "\u{661}=1", "1=\u{661}"])
            .prop_map(str::to_string),
    ]
}

fn vector_arg() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => prop::collection::vec(cli_number(), 3).prop_map(|v| v.join(",")),
        2 => prop::collection::vec(cli_number(), 0..6).prop_map(|v| v.join(",")),
        1 => "[-+,0-9.eE a-z]{0,12}",
    ]
}

/// One `tdcr solve` command line: the file, then tensions and tip forces in either spelling.
fn solve_args(file: String) -> impl Strategy<Value = Vec<String>> {
    let option = prop_oneof![
        3 => (tension_arg(), any::<bool>()).prop_map(|(v, joined)| ("--tension", v, joined)),
        2 => (vector_arg(), any::<bool>()).prop_map(|(v, joined)| ("--tip-force", v, joined)),
        1 => (vector_arg(), any::<bool>()).prop_map(|(v, joined)| ("--tip-moment", v, joined)),
    ];
    prop::collection::vec(option, 0..4).prop_map(move |options| {
        let mut args = vec!["solve".to_string(), file.clone(), "--format".into(), "json".into()];
        for (flag, value, joined) in options {
            if joined {
                args.push(format!("{flag}={value}"));
            } else {
                args.push(flag.to_string());
                args.push(value);
            }
        }
        args
    })
}

/// Random `--tension I=V`, `--tip-force X,Y,Z` and `--tip-moment` values with junk, on the
/// example (without load continuation, so huge loads stop in bounded time with exit 3):
/// exit code 0, 2 or 3, never a panic (101) nor a backtrace.
#[test]
fn cli_survives_random_tension_and_force_arguments() {
    let dir = scratch("args");
    let text = tdcr::io::example().replacen("# continuation = true", "continuation = false", 1);
    assert!(text.contains("\ncontinuation = false"));
    let file = dir.join("robot.toml");
    std::fs::write(&file, &text).unwrap_or_else(|e| panic!("cannot write {}: {e}", file.display()));
    let strategy = solve_args(file.display().to_string());
    let codes: [AtomicUsize; 4] = Default::default();
    let result = runner(50, 9).run(&strategy, |args| {
        let (code, stderr) = run(&dir, &args);
        clean_exit(&args, code, &stderr).map_err(TestCaseError::fail)?;
        codes[code.unwrap_or(1).clamp(0, 3) as usize].fetch_add(1, Ordering::Relaxed);
        Ok(())
    });
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(e) = result {
        panic!("{e}");
    }
    let [ok, _, bad, unconverged] = codes.map(|c| c.load(Ordering::Relaxed));
    eprintln!("command lines: exit 0 {ok}, exit 2 {bad}, exit 3 {unconverged}");
    // Both a success and a bad-input exit must be among 50 runs, or the strategy is broken.
    assert!(ok > 0 && bad > 0);
}

// ---------------------------------------------------------------------------------------
// Bugs found by fuzzing, kept as failing tests until fixed

/// Runs `tdcr` on the example with `args` after the file and checks a clean exit.
fn example_run(name: &str, file_text: &str, command: &str, args: &[&str]) -> Result<(), String> {
    let dir = scratch(name);
    let file = dir.join("robot.toml");
    std::fs::write(&file, file_text).unwrap_or_else(|e| panic!("cannot write {}: {e}", file.display()));
    let mut all = vec![command.to_string(), file.display().to_string()];
    all.extend(args.iter().map(|a| a.to_string()));
    let (code, stderr) = run(&dir, &all);
    let _ = std::fs::remove_dir_all(&dir);
    clean_exit(&all, code, &stderr)
}

/// `COUNT` near `usize::MAX` makes `parse_sweep` collect that many tensions: capacity
/// overflow panic inside clap's value parser (exit 101); a large but representable COUNT
/// (1e9) allocates gigabytes instead.
#[test]
fn sweep_with_a_huge_count_is_bad_input() {
    let result = example_run(
        "sweep-count",
        &tdcr::io::example(),
        "sweep",
        &["--tension", "1=0:1:18446744073709551615"],
    );
    result.unwrap_or_else(|e| panic!("{e}"));
}

/// `--samples` near `usize::MAX` panics with a capacity overflow in the output sampling
/// (exit 101); `--samples 1000000000000` aborts on a failed allocation (exit 134).
#[test]
fn solve_with_huge_samples_is_bad_input() {
    let result = example_run(
        "samples",
        &tdcr::io::example(),
        "solve",
        &["--samples", "18446744073709551615"],
    );
    result.unwrap_or_else(|e| panic!("{e}"));
}

/// `--intervals` (then `--nodes`) near `usize::MAX` panics with a capacity overflow while
/// building the mesh (exit 101); `--intervals 1000000000000` aborts on a failed allocation
/// (exit 134).
#[test]
fn solve_with_huge_intervals_is_bad_input() {
    let result = example_run(
        "intervals",
        &tdcr::io::example(),
        "solve",
        &["--intervals", "18446744073709551615"],
    );
    result.unwrap_or_else(|e| panic!("{e}"));
}

/// `[solver] intervals = 9223372036854775807` (then `nodes`) is accepted by `tdcr::io::parse`
/// (and `tdcr check` says OK), then `tdcr solve` panics with a capacity overflow building the
/// mesh (exit 101); `intervals = 100000000` aborts on a 4.8 GB allocation (exit 134). The file
/// should be rejected with a bound on `intervals` (or the solve fail with a typed error).
#[test]
fn file_with_huge_intervals_is_bad_input() {
    let text = tdcr::io::example();
    assert!(text.contains("\n# intervals = 32 "));
    let text = text.replacen("\n# intervals = 32 ", "\nintervals = 9223372036854775807 ", 1);
    let result = example_run("file-intervals", &text, "solve", &[]);
    result.unwrap_or_else(|e| panic!("{e}"));
}

/// A quoted key with an escaped newline is echoed raw: as a top-level key in the message, as
/// a nested table key in the field path (`base.a<newline>b`), so the problem takes two lines
/// (the command prints the second as its own `error:` line). docs/robot-file.md promises one
/// line per problem. Reproducers: `[["a\nb"]]` and `[base]` + `"a\nb" = {x = 1}`.
#[test]
fn a_key_with_a_newline_stays_on_its_message_line() {
    for tail in ["[[\"a\\nb\"]]", "[base]\n\"a\\nb\" = { x = 1 }"] {
        let text = format!("{ROD}{tail}\n");
        let e = match tdcr::io::parse(&text, NAME) {
            Ok(_) => panic!("accepted {text:?}"),
            Err(e) => e,
        };
        let shown = e.to_string();
        assert_eq!(shown.lines().count(), e.problems.len(), "{text:?} gives:\n{shown}");
    }
}

/// Issue 18: `[solver] max_iterations = 9223372036854775807` (and 2^64 - 1) panicked with a
/// capacity overflow, 1e9, 2^32 - 1 and 2^32 aborted on a 137 GB allocation. Every count key
/// of `[solver]`, one at a time, at values up to u64::MAX beyond its bound: `tdcr solve`
/// exits 2 naming a `[solver]` key, never 101 (panic) or 134 (abort).
#[test]
fn solve_with_huge_solver_counts_exits_2() {
    // The example fixes `intervals = 32`: without it, `nodes` is not given twice.
    let example = tdcr::io::example().replacen("\nintervals = 32 ", "\n# intervals = 32 ", 1);
    assert!(example.contains("\nmethod = \"collocation\""));
    let dir = scratch("counts");
    let file = dir.join("robot.toml");
    for key in SOLVER_COUNTS {
        for n in [
            "0",
            "100001",
            "1000000000",
            "4294967295",
            "4294967296",
            "9223372036854775807",
            "18446744073709551615",
        ] {
            // 100001: just beyond MAX_INTERVALS (and MAX_ITERATIONS); 0 is below every rule.
            let text = example.replacen("\nmethod = ", &format!("\n{key} = {n}\nmethod = "), 1);
            std::fs::write(&file, &text).unwrap_or_else(|e| panic!("cannot write {}: {e}", file.display()));
            let args = vec!["solve".to_string(), file.display().to_string()];
            let (code, stderr) = run(&dir, &args);
            clean_exit(&args, code, &stderr).unwrap_or_else(|e| panic!("{key} = {n}: {e}"));
            assert_eq!(code, Some(2), "{key} = {n}: {stderr}");
            assert!(
                stderr.contains("robot.toml:") && stderr.contains("`solver."),
                "{key} = {n}: {stderr}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
