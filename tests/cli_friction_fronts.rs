//! Friction on every front end a user reaches (issue 24, docs/friction.md's last section):
//! `friction.I` as a parameter name (`solve --jacobian=friction.1`), the tension along each
//! tendon in `solve`'s CSV and JSON samples, `--friction` and `--motion` on `batch`,
//! `compare` and `calibrate`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tdcr-cli-fronts-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(TDCR).args(args).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked") && !stderr.contains("RUST_BACKTRACE"),
        "{stderr}"
    );
    out
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `tdcr example` with `added` (robot-file lines) after tendon 1's tension.
fn example_with(dir: &Path, added: &str) -> String {
    let text = stdout(&run(dir, &["example"]));
    let from = "tension = 2.94                   # N, >= 0\n";
    assert!(text.contains(from));
    text.replacen(from, &format!("{from}{added}"), 1)
}

/// Runs `args` in `dir`, requires exit 0 and returns standard output as JSON.
fn json(dir: &Path, args: &[&str]) -> serde_json::Value {
    let out = run(dir, args);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

/// `--jacobian=friction.1` names tendon 1's friction coefficient as the other parameters
/// are named, and its column is the full `--jacobian`'s `jacobian.friction` column; a
/// tendon without friction has no such derivative (exit 2 naming it), and the table form
/// heads the column `friction.1`.
#[test]
fn friction_is_a_jacobian_column_by_name() {
    let dir = scratch("jacobian");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "friction = 0.1\n")).unwrap();
    let base = ["solve", "robot.toml", "--intervals", "64", "--format", "json"];
    let full = json(&dir, &[&base[..], &["--jacobian"]].concat());
    let named = json(&dir, &[&base[..], &["--jacobian=friction.1,tension.1"]].concat());
    assert_eq!(
        named["tip_jacobian"]["columns"],
        serde_json::json!(["friction.1", "tension.1"])
    );
    let rows = named["tip_jacobian"]["rows"].as_array().unwrap();
    let want: Vec<f64> = (0..6)
        .map(|r| full["jacobian"]["friction"][r][0].as_f64().unwrap())
        .collect();
    let scale = want.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!(scale > 0.0);
    for (r, row) in rows.iter().enumerate() {
        let got = row[0].as_f64().unwrap();
        // 1e-12 of the column: the same solve and difference stencil, solved with the same
        // factors (the JSON prints in full); only the order of the sums may differ
        assert!((got - want[r]).abs() <= 1e-12 * scale, "row {r}: {got} vs {}", want[r]);
    }
    let out = run(
        &dir,
        &["solve", "robot.toml", "--intervals", "64", "--jacobian=friction.1"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("friction.1"), "{}", stdout(&out));
    let out = run(
        &dir,
        &["solve", "robot.toml", "--intervals", "64", "--jacobian=friction.2"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let text = stderr(&out);
    assert!(
        text.contains("--jacobian=friction.2") && text.contains("tendon[2].friction") && text.contains("positive"),
        "{text}"
    );
    let out = run(&dir, &["solve", "robot.toml", "--jacobian=friction.6"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("names tendon 6, but the robot has 5 tendon(s)"),
        "{}",
        stderr(&out)
    );
}
