//! Shared by the command-line tests: run `tdcr` in a scratch directory and read its output.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `tdcr` binary the tests run.
pub const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

/// A fresh scratch directory `tdcr-PREFIX-PID-NAME` under the system's temporary directory.
pub fn scratch(prefix: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tdcr-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `tdcr ARGS` run in `dir`; fails the test on a panic or a backtrace, whatever the exit code.
pub fn run(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(TDCR).args(args).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked") && !stderr.contains("RUST_BACKTRACE"),
        "{stderr}"
    );
    out
}

/// The standard output as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The standard error as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `tdcr example` with `added` (robot-file lines) after tendon 1's tension.
pub fn example_with(dir: &Path, added: &str) -> String {
    let text = stdout(&run(dir, &["example"]));
    let from = "tension = 2.94                   # N, >= 0\n";
    assert!(text.contains(from));
    text.replacen(from, &format!("{from}{added}"), 1)
}
