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

/// `solve --format csv` has a column `tension_I` per tendon with friction (its tension at
/// each sample, blank past its end) and the JSON's samples a `tensions` list (every tendon,
/// null past its end); both equal the library's `Solution::tension_at`, and without friction
/// neither is there (the CSV's header is the frictionless one).
#[test]
fn the_csv_and_json_samples_have_the_tension_along_each_tendon() {
    let dir = scratch("samples");
    // Tendon 1 with friction ends at mid-length; tendon 2 (no friction) pulled too.
    let text = example_with(&dir, "friction = 0.1\nend = 0.121\n");
    std::fs::write(dir.join("rough.toml"), &text).unwrap();
    std::fs::write(dir.join("plain.toml"), example_with(&dir, "")).unwrap();
    let args = ["--tension", "2=1", "--samples", "5", "--intervals", "32"];
    let out = run(&dir, &[&["solve", "rough.toml", "--format", "csv"][..], &args].concat());
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let csv = stdout(&out);
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert_eq!(header, format!("{},tension_1", tdcr::io::output::CSV_HEADER));
    let rough = json(
        &dir,
        &[&["solve", "rough.toml", "--format", "json"][..], &args].concat(),
    );
    let mut robot = tdcr::io::parse(&text, "rough.toml").unwrap().robot;
    robot.tendons[1].set_tension(1.0);
    let solution = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(32)).unwrap();
    let samples = rough["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 5);
    for (k, (line, sample)) in lines.zip(samples).enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let s: f64 = cells[0].parse().unwrap();
        let tensions = sample["tensions"].as_array().unwrap();
        assert_eq!(tensions.len(), 5);
        // Tendon 2 has no friction: its constant tension, up to the tip.
        assert_eq!(tensions[1].as_f64(), Some(1.0));
        if s <= 0.121 {
            let want = solution.tension_at(0, s).unwrap();
            // Bitwise: the same robot, mesh and solve, numbers printed in full.
            assert_eq!(cells[19].parse::<f64>().unwrap(), want, "sample {k}");
            assert_eq!(tensions[0].as_f64(), Some(want), "sample {k}");
            // The capstan loss of a pull: below the base entry's 2.94 N past it.
            assert!(want <= 2.94 && (s == 0.0 || want < 2.94), "sample {k}: {want}");
        } else {
            assert_eq!(cells[19], "", "sample {k}: past the tendon's end");
            assert!(tensions[0].is_null(), "sample {k}");
        }
    }
    let delivered = rough["tendons"][0]["delivered_tension"].as_f64().unwrap();
    assert_eq!(solution.tension_at(0, 0.121), Some(delivered));
    // The JSON reads back (the samples are output only).
    let back = tdcr::io::read_solution(&serde_json::to_string(&rough).unwrap(), &robot).unwrap();
    assert_eq!(back.tip().p, solution.tip().p);
    // Without friction: the frictionless columns and no `tensions`.
    let out = run(&dir, &[&["solve", "plain.toml", "--format", "csv"][..], &args].concat());
    assert_eq!(stdout(&out).lines().next(), Some(tdcr::io::output::CSV_HEADER));
    let plain = json(
        &dir,
        &[&["solve", "plain.toml", "--format", "json"][..], &args].concat(),
    );
    assert!(plain["samples"][0].get("tensions").is_none());
}
