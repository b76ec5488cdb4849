//! Files in and out of the `tdcr` command and the Python package: the TOML robot file
//! (docs/robot-file.md, feature `files`), read with every problem reported by file, line,
//! field and rule; the solution JSON, written and read back bitwise (docs/cli.md); the
//! experiments and result CSVs, through the `csv` crate, every number written by [`number`].
//!
//! ```
//! # #[cfg(feature = "files")] {
//! let file = tdcr::io::parse(&tdcr::io::example(), "example.toml").unwrap();
//! let solution = tdcr::collocation::solve(&file.robot, &file.solver.collocation).unwrap();
//! let json = tdcr::io::output::json(&file.robot, &solution, None, None);
//! assert!(json.contains("\"converged\": true"));
//! # }
//! ```

pub mod csv_table;
#[cfg(feature = "files")]
mod example;
pub mod experiments;
mod json_layout;
#[cfg(feature = "files")]
pub mod locate;
pub mod output;
pub mod parameters;
#[cfg(feature = "files")]
mod robot_file;
pub mod row_outputs;
mod solution_file;

pub use csv_table::number;
#[cfg(feature = "files")]
pub use example::{calibration_truth, example, example_cases, example_experiments, paper_frame_example};
#[cfg(feature = "files")]
pub use robot_file::{Front, RobotFile, SolverSettings, file_field, parse, user_message};
pub use solution_file::{parse_solution, read_solution};

/// A 1-based line and column in the source text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Position {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub column: usize,
}

use std::fmt;

/// One problem in a robot file: where it is, which field, and the rule it breaks.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Line and column (from 1) when the problem has a place in the file.
    pub position: Option<Position>,
    /// Field path in the file, e.g. `tendon[2].end` (array elements numbered from 1, as
    /// on the command line); empty for problems of the whole file.
    pub field: String,
    /// What is wrong, with the value, and the rule.
    pub message: String,
}

/// Everything wrong with one robot file, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct FileError {
    /// The file's name as given (`<stdin>` for standard input).
    pub file: String,
    /// The problems, at least one.
    pub problems: Vec<Problem>,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = self.position {
            write!(f, "{}:{}: ", p.line, p.column)?;
        }
        if !self.field.is_empty() {
            write!(f, "`{}` ", self.field)?;
        }
        f.write_str(&self.message)
    }
}

/// `text` with control characters (newlines, terminal escapes) written as escapes, so that a
/// key read from a file can neither break the one-line-per-problem format nor reach the
/// terminal raw.
pub(crate) fn printable(text: &str) -> String {
    text.chars()
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect()
            } else {
                vec![c]
            }
        })
        .collect()
}

impl fmt::Display for FileError {
    /// One line per problem: `FILE:LINE:COLUMN: `FIELD` MESSAGE`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, p) in self.problems.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            if p.position.is_some() {
                write!(f, "{}:{p}", self.file)?;
            } else {
                write!(f, "{}: {p}", self.file)?;
            }
        }
        Ok(())
    }
}

impl std::error::Error for FileError {}
