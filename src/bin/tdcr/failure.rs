//! Why a command stopped (its exit code and message), and writing to standard output,
//! standard error and files.

use std::io::Write;
use std::path::Path;
use tdcr::plot::{Figure, Format};
use tdcr::{Error, Robot};

use crate::tables::diagnostics;

/// Why the command stopped, and its exit code.
pub enum Failure {
    /// Bad input: a file, an option, a value (exit 2).
    Input(String),
    /// A solver did not converge (exit 3).
    NotConverged(String),
    /// Valid input the model cannot answer, e.g. a load history step whose stick/slip
    /// pattern the history does not model (`Error::ModelLimit`, exit 4).
    Limit(String),
    /// Anything else, e.g. an output file that cannot be written (exit 1).
    Other(String),
    /// Standard output was closed by the reader (`tdcr | head`): stop quietly (exit 0).
    BrokenPipe,
}

impl Failure {
    /// The exit code.
    pub fn code(&self) -> u8 {
        match self {
            Failure::Input(_) => 2,
            Failure::NotConverged(_) => 3,
            Failure::Limit(_) => 4,
            Failure::Other(_) => 1,
            Failure::BrokenPipe => 0,
        }
    }

    /// The failure of one step of several, its message headed by `head` (`sweep step 2 of
    /// 9`): `HEAD: MESSAGE` for bad input, and for the others a first line saying what
    /// happened at `head` and `then` (what the output holds), the message after it.
    pub fn headed(self, head: &str, then: &str) -> Failure {
        match self {
            Failure::Input(t) => Failure::Input(format!("{head}: {t}")),
            Failure::NotConverged(t) => Failure::NotConverged(format!("{head} failed; {then}\n{t}")),
            Failure::Limit(t) => Failure::Limit(format!("{head} is outside the model; {then}\n{t}")),
            Failure::Other(t) => Failure::Other(format!("{head} failed; {then}\n{t}")),
            Failure::BrokenPipe => Failure::BrokenPipe,
        }
    }

    /// Prints the message to standard error, each line after `error: ` unless indented.
    pub fn print(&self) {
        let text = match self {
            Failure::Input(t) | Failure::NotConverged(t) | Failure::Limit(t) | Failure::Other(t) => t,
            Failure::BrokenPipe => return,
        };
        let mut err = std::io::stderr().lock();
        for line in text.lines() {
            // Indented lines continue the message above them (diagnostics, hints).
            let prefix = if line.starts_with(' ') { "" } else { "error: " };
            let _ = writeln!(err, "{prefix}{line}");
        }
    }
}

/// The command-line flags that set the solver option `field` of a library message (the
/// library names options, not flags), for the options whose message suggests a change.
fn flags(field: &str) -> Option<&'static str> {
    match field {
        "options.intervals" | "options.mesh" => Some("--intervals N, or --tol TOL for a tip tolerance"),
        _ => None,
    }
}

/// A library error's message in the command line's words: a field path numbered as in
/// robot files (`tendon[1].stiffness` for the library's `tendons[0].stiffness`), as
/// Python's messages number it ([`tdcr::io::user_message`]). A `base_rotation` error is
/// named `base.rotation` even for a file that gives `base.euler_xyz_deg`, but none reaches
/// here: the file's rotation is checked when the file is read (named as the file spells it),
/// no option replaces it, and calibration only turns it by another rotation.
pub fn message(e: &Error) -> String {
    tdcr::io::user_message(e, tdcr::io::Front::CommandLine)
}

/// A solver error as a failure: input problems exit 2, solver failures 3, model limits 4,
/// the rest 1.
pub fn solver_failure(e: Error) -> Failure {
    let text = message(&e);
    if let Error::NotConverged { report, .. } = &e {
        return Failure::NotConverged(format!("{text}\n{}", diagnostics(report)));
    }
    if matches!(e, Error::IntervalCap { .. } | Error::Breakdown { .. }) {
        Failure::NotConverged(text)
    } else if let Error::InvalidInput { field, .. } = &e {
        Failure::Input(match flags(field) {
            Some(flags) => format!("{text} (on the command line: {flags})"),
            None => text,
        })
    } else if matches!(e, Error::ModelLimit { .. }) {
        Failure::Limit(text)
    } else if matches!(e, Error::SingularRouting { .. }) {
        Failure::Input(text)
    } else {
        Failure::Other(text)
    }
}

/// A solver failure with the robot's implausible scales ([`Robot::plausibility`]) named as
/// its likely cause, after the failure's first line
/// ([`tdcr::model::scales::with_likely_causes`]); other failures unchanged.
pub fn with_likely_causes(failure: Failure, robot: &Robot) -> Failure {
    let Failure::NotConverged(text) = failure else {
        return failure;
    };
    Failure::NotConverged(tdcr::model::scales::with_likely_causes(&text, &robot.plausibility()))
}

/// Says on standard error what a user must not miss about the equilibrium returned: that
/// it is unstable, or that the load path snapped through a fold or crossed a bifurcation on
/// the way (docs/stability.md).
pub fn warn_equilibrium(name: &str, report: &tdcr::SolveReport) {
    for n in &report.notes {
        note(&format!("note: {name}: {n}"));
    }
    if let tdcr::Stability::Unstable { .. } | tdcr::Stability::Growing { .. } = report.stability {
        note(&format!(
            "warning: {name}: the equilibrium returned is {}: a real robot would not stay in it",
            report.stability
        ));
    }
    if let tdcr::PathTaken::LoadPath { folds, bifurcations } | tdcr::PathTaken::FromWarmStart { folds, bifurcations } =
        &report.path
    {
        let at = |v: &[f64]| {
            v.iter()
                .map(|f| format!("{:.1} %", 100.0 * f))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !folds.is_empty() {
            note(&format!(
                "warning: {name}: on its way the robot SNAPS THROUGH (the path folds at {} of the way): \
                 the state returned is the one after the snap",
                at(folds)
            ));
        }
        if !bifurcations.is_empty() {
            note(&format!(
                "warning: {name}: the path crossed a bifurcation at {} of the way (a symmetric robot \
                 can leave it either way; an imperfection decides)",
                at(bifurcations)
            ));
        }
    }
}

/// Prints the robot's implausible scales ([`Robot::plausibility`]) to standard error, one
/// `warning:` line each.
pub fn warn_scales(name: &str, robot: &Robot) {
    for w in robot.plausibility() {
        note(&format!("warning: {name}: {w}"));
    }
}

/// Prints what the robot file gives that has no effect (`RobotFile::warnings`, e.g. a
/// `free_length` without `stiffness`) to standard error, one `warning:` line each:
/// `read` are the warnings of the file as read, `file` is it with the command-line options
/// applied, and only the warnings of both are printed. A warning only the options cause
/// (`--motion` on a tendon without friction) names a field the file does not have, so the
/// options warn about themselves; one the options clear (`--friction` on a tendon whose
/// file gives only `motion`) no longer holds.
pub fn warn_file(name: &str, read: &[String], file: &tdcr::io::RobotFile) {
    let now = file.warnings();
    for w in read.iter().filter(|w| now.contains(w)) {
        note(&format!("warning: {name}: {w}"));
    }
}

/// The solved tensions of displacement-controlled tendons at or past their geometric
/// limit ([`Robot::solved_tensions`]), one warning line each, headed by `at` (`FILE` or
/// `FILE: sweep step K`); `skip(i)` leaves tendon `i` out (a sweep warns once per tendon).
/// Returns the tendons warned about.
pub fn warn_solved_tensions(
    at: &str,
    robot: &Robot,
    solution: &tdcr::Solution,
    skip: impl Fn(usize) -> bool,
) -> Vec<usize> {
    let mut warned = Vec::new();
    for w in robot.solved_tensions(&solution.tensions()) {
        if let tdcr::model::scales::Warning::SolvedTension { tendon, .. } = w
            && !skip(tendon)
        {
            note(&format!("warning: {at}: {w}"));
            warned.push(tendon);
        }
    }
    warned
}

/// Standard error, ignoring write errors (there is nowhere left to report them).
pub fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// Writes to standard output; a closed pipe stops the command quietly.
pub fn emit(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(Failure::BrokenPipe),
        Err(e) => Err(Failure::Other(format!("cannot write to standard output: {e}"))),
    }
}

/// The file `--out FILE` names, or None for standard output: without `--out`, and for
/// `--out -`.
pub fn out_path(out: &Option<std::path::PathBuf>) -> Option<&Path> {
    out.as_deref().filter(|p| p.as_os_str() != "-")
}

/// Writes `text` to `path`, creating its folder; `what` names the file in messages.
pub fn write_file(path: &Path, text: impl AsRef<[u8]>, what: &str) -> Result<(), Failure> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::Other(format!("cannot create folder {} for the {what}: {e}", dir.display())))?;
    }
    std::fs::write(path, text)
        .map_err(|e| Failure::Other(format!("cannot write the {what} to {}: {e}", path.display())))
}

/// The picture format `path` asks for (`.png`: PNG, else SVG), checked before any work.
pub fn picture_format(path: &Path) -> Result<Format, Failure> {
    Format::from_path(path).map_err(|e| Failure::Input(e.to_string()))
}

/// Writes `figure` to `path` in the format its extension names and says so on standard
/// error, with a warning if a PNG could not get its text (no fonts on the system).
pub fn write_picture(path: &Path, figure: &Figure, what: &str) -> Result<(), Failure> {
    let (bytes, text) = figure
        .render(picture_format(path)?)
        .map_err(|e| Failure::Other(format!("cannot draw the {what}: {e}")))?;
    write_file(path, bytes, what)?;
    if !text {
        note(&format!(
            "warning: no fonts found on this system, so {} has no text; install a font (for \
             example fonts-dejavu-core) or write SVG",
            path.display()
        ));
    }
    note(&format!("wrote {}", path.display()));
    Ok(())
}
