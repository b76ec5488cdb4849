//! Friction on every front end a user reaches (issue 24, docs/friction.md's last section):
//! `friction.I` as a parameter name (`solve --jacobian=friction.1`), the tension along each
//! tendon in `solve`'s CSV and JSON samples, `--friction` and `--motion` on `batch`,
//! `compare` and `calibrate`.

mod common;

use common::cli::{example_with, run, stderr, stdout};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    common::cli::scratch("cli-fronts", name)
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

/// `solve --format csv` has a column `tension.I` per tendon with friction (its tension at
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
    assert_eq!(header, format!("{},tension.1", tdcr::io::output::CSV_HEADER));
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

/// `batch`, `compare` and `calibrate` take `--friction I=MU` and `--motion I=pull|release`
/// as `solve` and `sweep` do: the same output as the same friction in the robot file, and
/// another than without it.
#[test]
fn batch_compare_and_calibrate_take_friction_and_motion() {
    let dir = scratch("commands");
    let plain = stdout(&run(&dir, &["example"]));
    std::fs::write(dir.join("plain.toml"), &plain).unwrap();
    std::fs::write(
        dir.join("rough.toml"),
        example_with(&dir, "friction = 0.1\nmotion = \"release\"\n"),
    )
    .unwrap();
    std::fs::write(dir.join("cases.csv"), stdout(&run(&dir, &["example", "cases"]))).unwrap();
    let output = |args: &[&str]| {
        let out = run(&dir, args);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
        stdout(&out)
    };
    let options = ["--friction", "1=0.1", "--motion", "1=release"];
    // batch: every row as with the file's friction (the error estimate column is output,
    // solve times are not, so the rows compare whole).
    let batch = |robot: &str, extra: &[&str]| {
        output(&[&["batch", "cases.csv", "--robot", robot, "--error-estimate"][..], extra].concat())
    };
    let by_option = batch("plain.toml", &options);
    assert_eq!(by_option, batch("rough.toml", &[]));
    assert_ne!(by_option, batch("plain.toml", &[]));
    assert_ne!(
        by_option,
        batch("plain.toml", &options[..2]),
        "release differs from pull"
    );
    // compare (on a fixed mesh: the Kirchhoff rod with friction needs one, docs/friction.md).
    let compare = |robot: &str, extra: &[&str]| {
        output(
            &[
                &["compare", robot, "--models", "coupled,paper_jumps", "--intervals", "32"][..],
                extra,
            ]
            .concat(),
        )
    };
    assert_eq!(compare("plain.toml", &options), compare("rough.toml", &[]));
    assert_ne!(compare("plain.toml", &options), compare("plain.toml", &[]));
    // calibrate: the paper's robot and experiments; E and the angles fitted with friction.
    std::fs::write(dir.join("paper.toml"), stdout(&run(&dir, &["example", "paper-robot"]))).unwrap();
    let paper = stdout(&run(&dir, &["example", "paper-robot"]));
    let first = "tension = 0.0\n";
    assert!(paper.contains(first));
    std::fs::write(
        dir.join("paper_rough.toml"),
        paper.replacen(first, &format!("{first}friction = 0.05\nmotion = \"release\"\n"), 1),
    )
    .unwrap();
    std::fs::write(
        dir.join("experiments.csv"),
        stdout(&run(&dir, &["example", "experiments"])),
    )
    .unwrap();
    let calibrate = |robot: &str, extra: &[&str]| {
        output(&[&["calibrate", robot, "experiments.csv", "--format", "json"][..], extra].concat())
    };
    let fitted = |text: &str| {
        let json: serde_json::Value = serde_json::from_str(text).unwrap();
        json["fitted"].to_string()
    };
    let mu = ["--friction", "1=0.05", "--motion", "1=release"];
    let by_option = fitted(&calibrate("paper.toml", &mu));
    assert_eq!(by_option, fitted(&calibrate("paper_rough.toml", &[])));
    assert_ne!(by_option, fitted(&calibrate("paper.toml", &[])));
    // Bad values are the options' errors, as for solve.
    let out = run(
        &dir,
        &["batch", "cases.csv", "--robot", "plain.toml", "--friction", "9=0.1"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("--friction 9=...: the robot has 5 tendon(s)"),
        "{}",
        stderr(&out)
    );
    let out = run(
        &dir,
        &["calibrate", "paper.toml", "experiments.csv", "--motion", "1=sideways"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

/// `tdcr compare` of a robot with friction and the default models leaves out the
/// point-moment model, which the library refuses with friction, with a note saying why,
/// and compares the others; asked for by name it is the library's error (exit 2).
#[test]
fn compare_leaves_out_the_models_that_refuse_friction() {
    let dir = scratch("compare");
    std::fs::write(dir.join("rough.toml"), example_with(&dir, "friction = 0.1\n")).unwrap();
    // A fixed mesh: the Kirchhoff rod with friction needs one (docs/friction.md).
    let out = run(&dir, &["compare", "rough.toml", "--intervals", "64"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let models: Vec<&str> = text
        .lines()
        .skip(1)
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert_eq!(
        models,
        ["coupled", "constant_curvature", "paper_jumps", "kirchhoff", "(off:"],
        "{text}"
    );
    let note = stderr(&out);
    assert!(
        note.contains("compare leaves out point_moment")
            && note.contains("`tendon[1].friction` is 0.1 with the point-moment tendon model"),
        "{note}"
    );
    // Without friction nothing is left out.
    let out = run(
        &dir,
        &["compare", "rough.toml", "--intervals", "64", "--friction", "1=0"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("point_moment") && !stderr(&out).contains("leaves out"));
    let out = run(
        &dir,
        &[
            "compare",
            "rough.toml",
            "--intervals",
            "64",
            "--models",
            "coupled,point_moment",
        ],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("point-moment tendon model"), "{}", stderr(&out));
}

/// `calibrate --fit mu` with two tendons with friction moves both in proportion (mu is the
/// first one's): the robot-file lines give each tendon its own coefficient, the JSON lists
/// them per tendon, and the standard errors of parameters that were not fitted are null.
/// The measurements are the paper robot's tips with friction 0.08 and 0.16 on tendons 1
/// and 2 (`tdcr batch`), fitted from 0.05 and 0.1.
#[test]
fn calibrating_mu_gives_each_tendon_its_own_line_and_held_parameters_no_standard_error() {
    let dir = scratch("calibrate_mu");
    std::fs::write(dir.join("paper.toml"), stdout(&run(&dir, &["example", "paper-robot"]))).unwrap();
    let experiments = stdout(&run(&dir, &["example", "experiments"]));
    let cases: Vec<String> = experiments
        .lines()
        .map(|l| l.split(',').take(8).collect::<Vec<_>>().join(","))
        .collect();
    let head = cases[0]
        .replace("tension_", "tension.")
        .replace("tip_force_", "tip_force.");
    std::fs::write(dir.join("cases.csv"), [&[head][..], &cases[1..]].concat().join("\n")).unwrap();
    let batch = run(
        &dir,
        &[
            "batch",
            "cases.csv",
            "--robot",
            "paper.toml",
            "--friction",
            "1=0.08",
            "--friction",
            "2=0.16",
        ],
    );
    assert_eq!(batch.status.code(), Some(0), "{}", stderr(&batch));
    let rows = stdout(&batch);
    let names: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let column = |name: &str| names.iter().position(|n| *n == name).unwrap();
    let tips = [column("tip_x"), column("tip_y"), column("tip_z")];
    let mut measured = format!("{},measured_x,measured_y,measured_z\n", cases[0]);
    for (case, row) in cases[1..].iter().zip(rows.lines().skip(1)) {
        let values: Vec<&str> = row.split(',').collect();
        measured += &format!("{case},{},{},{}\n", values[tips[0]], values[tips[1]], values[tips[2]]);
    }
    std::fs::write(dir.join("experiments.csv"), measured).unwrap();
    let args = [
        "calibrate",
        "paper.toml",
        "experiments.csv",
        "--fit",
        "e,mu",
        "--friction",
        "1=0.05",
        "--friction",
        "2=0.1",
    ];
    let out = run(&dir, &args);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let line = |i: usize| -> f64 {
        let head = format!("  [[tendon]] {i}: friction = ");
        let found = text.lines().find_map(|l| l.strip_prefix(head.as_str()));
        found
            .unwrap_or_else(|| panic!("no line for tendon {i}: {text}"))
            .parse()
            .unwrap()
    };
    // Each tendon its own recovered coefficient; 1e-4 covers the six printed digits and the
    // fit's convergence on exact data.
    assert!((line(1) - 0.08).abs() < 1e-4 && (line(2) - 0.16).abs() < 1e-4, "{text}");
    let out = run(&dir, &[&args[..], &["--format", "json"]].concat());
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let frictions = json["fitted_frictions"].as_array().unwrap();
    let mu = |i: usize| frictions[i].as_f64().unwrap();
    assert_eq!(mu(0), json["fitted"]["friction"].as_f64().unwrap());
    // Exactly the ratio the start gave (0.1 / 0.05 = 2), to rounding.
    assert!((mu(1) / mu(0) - 2.0).abs() < 1e-12, "{frictions:?}");
    assert!(frictions[2].is_null(), "{frictions:?}");
    let se = &json["standard_errors"];
    assert!(se["youngs_modulus"].as_f64().unwrap() > 0.0, "{se}");
    assert!(se["friction"].as_f64().unwrap() > 0.0, "{se}");
    assert!(
        se["base_position"].is_null() && se["offset_scale"].is_null() && se["euler_xyz_deg"].is_null(),
        "{se}"
    );
}
