//! The command line's model limits and partial outputs (docs/cli.md, "Exit codes"): a load
//! history step the stick/slip history does not model exits 4 ("outside the model"), not 2
//! (bad input), with a hint in the command line's words; the CSV and the loop of a history
//! that stopped say they hold only the steps before it; `--out -` is standard output.

mod common;

use common::cli::run;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    common::cli::scratch("cli-limits", name)
}

/// The example robot with friction 0.1 and E_t A_t = 2000 N on tendon 1.
fn robot(dir: &Path) {
    let out = run(dir, &["example"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let from = "tension = 2.94                   # N, >= 0\n";
    assert!(text.contains(from));
    std::fs::write(
        dir.join("robot.toml"),
        text.replacen(from, &format!("{from}friction = 0.1\nstiffness = 2000.0\n"), 1),
    )
    .unwrap();
}

/// user24's history: tendon 1 held at 2.94 N while a sideways tip force rises to 0.05 N and
/// falls back; step 2 would slide against friction away from the base entry, which the
/// stick/slip history does not model.
fn refused_history(dir: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "sweep",
        "robot.toml",
        "--tension",
        "1=2.94",
        "--param",
        "tip_force.y=0:0.05:5",
        "--history",
        "up-down",
    ];
    args.extend_from_slice(extra);
    run(dir, &args)
}

#[test]
fn a_history_step_outside_the_model_exits_4_and_says_the_csv_is_partial() {
    let dir = scratch("refused");
    robot(&dir);
    let out = refused_history(&dir, &["--out", "h.csv", "--plot", "h.svg"]);
    let err = String::from_utf8_lossy(&out.stderr);
    // Exit 4, "outside the model": main printed "invalid input" and exited 2 (bad input).
    assert_eq!(out.status.code(), Some(4), "{err}");
    assert!(err.contains("error: outside the model: `tendon[1].friction`"), "{err}");
    assert!(!err.contains("invalid input"), "{err}");
    // The CSV and the picture say they hold step 1 only (main: "wrote h.csv" alone).
    assert!(
        err.contains("wrote h.csv (step 1 only: the history stopped at step 2 of 9)"),
        "{err}"
    );
    assert!(
        err.contains("history step 2 of 9 is outside the model; the CSV holds only the steps before it"),
        "{err}"
    );
    let csv = std::fs::read_to_string(dir.join("h.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    let svg = std::fs::read_to_string(dir.join("h.svg")).unwrap();
    assert!(
        svg.contains("load history that STOPPED at step 2 of 9"),
        "title of {}",
        dir.display()
    );
}

#[test]
fn out_dash_is_standard_output_for_every_command() {
    let dir = scratch("dash");
    robot(&dir);
    // A trace does not model friction: it runs on the example as printed.
    std::fs::write(dir.join("plain.toml"), run(&dir, &["example"]).stdout).unwrap();
    let commands: [&[&str]; 4] = [
        &["solve", "robot.toml", "--out", "-"],
        &["sweep", "robot.toml", "--tension", "1=0:1:2", "--out", "-"],
        &["trace", "plain.toml", "--param", "tension.2=0:0.5", "--out", "-"],
        &[
            "sweep",
            "robot.toml",
            "--tension",
            "1=0:1:2",
            "--history",
            "up-down",
            "--out",
            "-",
        ],
    ];
    for args in commands {
        let out = run(&dir, args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        // Main wrote a file named `-` and said "wrote -".
        assert!(!out.stdout.is_empty(), "{args:?}");
        assert!(!err.contains("wrote -"), "{args:?}: {err}");
        assert!(!dir.join("-").exists(), "{args:?} wrote a file named -");
    }
    std::fs::write(dir.join("cases.csv"), "tension.1\n1.0\n2.0\n").unwrap();
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml", "--out", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 3);
    assert!(!dir.join("-").exists(), "batch wrote a file named -");
}

#[test]
fn a_robot_without_tendons_prints_no_tendon_table_and_no_empty_jacobian() {
    let dir = scratch("no-tendons");
    let text = String::from_utf8_lossy(&run(&dir, &["example"]).stdout).into_owned();
    let (from, to) = (text.find("[[tendon]]").unwrap(), text.find("[solver]").unwrap());
    std::fs::write(dir.join("bare.toml"), format!("{}{}", &text[..from], &text[to..])).unwrap();
    let out = run(&dir, &["solve", "bare.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let table = String::from_utf8_lossy(&out.stdout);
    // Main printed the tendon header with no rows under it.
    assert!(!table.contains("tension/N"), "{table}");
    assert!(table.contains("tip position (mm)"), "{table}");
    // Main printed a 6x0 Jacobian (the row labels alone).
    let out = run(&dir, &["solve", "bare.toml", "--jacobian=tension"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("the robot has no tendons"), "{err}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("rot.z"));
}
