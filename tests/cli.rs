//! The `tdcr` command, run as a built binary: the main job, round trips through robot files,
//! JSON and CSV output, and one test per class of bad input with its exit code and message.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tdcr-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `tdcr args` in `dir`, feeding `stdin` if given.
fn run(dir: &Path, args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(TDCR)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    if let Some(text) = stdin {
        input.write_all(text.as_bytes()).unwrap();
    }
    drop(input);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked") && !stderr.contains("RUST_BACKTRACE"),
        "{stderr}"
    );
    out
}

/// Checks that `out` exited with `code`, showing its standard error otherwise.
#[track_caller]
fn exits(out: &Output, code: i32) {
    assert_eq!(out.status.code(), Some(code), "{}", stderr(out));
}

/// Checks that `text` contains `part`, showing `text` otherwise.
#[track_caller]
fn has(text: &str, part: &str) {
    assert!(text.contains(part), "{text}");
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn example() -> String {
    let out = run(&std::env::temp_dir(), &["example"], None);
    exits(&out, 0);
    stdout(&out)
}

/// The example with one line replaced (the line must exist).
fn edited(from: &str, to: &str) -> String {
    let text = example();
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

fn tip_of(json: &serde_json::Value) -> [f64; 3] {
    let p = &json["tip"]["position"];
    [0, 1, 2].map(|k| p[k].as_f64().unwrap())
}

#[test]
fn main_job_prints_all_table2_rows_and_draws_them() {
    let dir = scratch("main");
    let out = run(&dir, &[], None);
    exits(&out, 0);
    let text = stdout(&out);
    let rows: Vec<usize> = text
        .lines()
        .filter(|l| !l.contains(" of "))
        .filter_map(|l| l.split_whitespace().next()?.parse().ok())
        .collect();
    assert_eq!(rows, (1..=32).collect::<Vec<_>>(), "{text}");
    has(&text, "32 of 32 solved");
    assert!(text.contains("T5 4.91 N + 0.196 N tip"));
    let svg = std::fs::read_to_string(dir.join("out/table2.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("perspective") && svg.contains("side view (XZ)"));
    // Small multiples: a column per tendon, each with its four views.
    assert_eq!(svg.matches("side view (XZ)").count(), 5);
    assert!(svg.contains("tendon 5: helix of radius 8 mm, 1 turn"));
    // The prototype's 12 disks on the 31 shapes with a tendon pulled, in 4 views.
    assert_eq!(svg.matches(r#"class="disk""#).count(), 31 * 12 * 4);
    let png = std::fs::read(dir.join("out/table2.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    // The journal-column figure: side views only, 525 px wide (a 1050-pixel PNG).
    let compact = std::fs::read_to_string(dir.join("out/table2_compact.svg")).unwrap();
    assert!(compact.starts_with(r#"<svg xmlns="http://www.w3.org/2000/svg" width="525""#));
    assert_eq!(compact.matches("side view (XZ)").count(), 5);
    assert!(!compact.contains("top view") && !compact.contains("perspective"));
    let csv = std::fs::read_to_string(dir.join("out/table2.csv")).unwrap();
    assert_eq!(csv.lines().count(), 33);
}

#[test]
fn the_samples_run_the_readme_commands() {
    let dir = scratch("samples");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let cases = run(&dir, &["example", "cases"], None);
    std::fs::write(dir.join("cases.csv"), stdout(&cases)).unwrap();
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml"], None);
    exits(&out, 0);
    assert_eq!(stdout(&out).lines().count(), 22, "a header and 21 rows");
    for (sample, file) in [("paper-robot", "paper.toml"), ("experiments", "experiments.csv")] {
        let out = run(&dir, &["example", sample], None);
        exits(&out, 0);
        std::fs::write(dir.join(file), stdout(&out)).unwrap();
    }
    let out = run(&dir, &["calibrate", "paper.toml", "experiments.csv"], None);
    exits(&out, 0);
    // The synthetic tips come from E = 230 GPa: the fit finds it (0.1 mm noise moves it by
    // about 0.04 GPa, its standard error).
    let e_line = stdout(&out).lines().find(|l| l.starts_with("E ")).unwrap().to_string();
    let fitted: f64 = e_line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((fitted - 230.0).abs() < 0.2, "{e_line}");
    assert!(!stderr(&out).contains("tolerance is ignored"), "{}", stderr(&out));
}

#[test]
fn example_round_trips_through_standard_input() {
    let dir = scratch("roundtrip");
    let out = run(&dir, &["solve", "-", "--format", "json"], Some(&example()));
    exits(&out, 0);
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    // The example is case S with the library's default options, and JSON numbers read back
    // exactly; the stiffness may differ in the last bit (the compiler folds powi for the
    // constants of `cases`), which moves the tip by ~1e-17 m: 1e-12 m is rounding.
    let expected = tdcr::collocation::solve(&tdcr::cases::case_s(), &Default::default())
        .unwrap()
        .tip_position();
    let tip = tip_of(&json);
    for k in 0..3 {
        assert!((tip[k] - expected[k]).abs() < 1e-12, "{tip:?} vs {expected}");
    }
    assert_eq!(json["converged"], true);
    assert_eq!(json["method"], "collocation");
    assert_eq!(json["intervals"], 32);
    assert_eq!(json["tendons"].as_array().unwrap().len(), 5);
    assert_eq!(json["tendons"][0]["tension"], 2.94);
    let samples = json["samples"].as_array().unwrap();
    assert_eq!(samples[0]["s"], 0.0);
    assert_eq!(samples[0]["R"].as_array().unwrap().len(), 3);
}

#[test]
fn json_tip_equals_the_library_for_overrides_and_samples() {
    let dir = scratch("json");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let args = [
        "solve",
        "robot.toml",
        "--tension",
        "1=0",
        "--tension",
        "5=4.91",
        "--tip-force",
        "0,0,-0.196",
        "--intervals",
        "48",
        "--samples",
        "5",
        "--format",
        "json",
    ];
    let out = run(&dir, &args, None);
    exits(&out, 0);
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    // `--intervals` without `--tol`: a fixed mesh.
    let options = tdcr::collocation::Options::fixed(48);
    let expected = tdcr::collocation::solve(&tdcr::cases::case_h(), &options)
        .unwrap()
        .tip_position();
    let tip = tip_of(&json);
    for k in 0..3 {
        // Same robot (case H) and options; 1e-12 m as in the round-trip test.
        assert!((tip[k] - expected[k]).abs() < 1e-12, "{tip:?} vs {expected}");
    }
    let samples = json["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 5);
    assert_eq!(samples[2]["s"], 0.121);
    // The last sample is the tip itself.
    assert_eq!(samples[4]["p"], json["tip"]["position"]);
}

#[test]
fn csv_has_a_header_and_one_row_per_sample() {
    let dir = scratch("csv");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &[
            "solve",
            "robot.toml",
            "--samples",
            "7",
            "--format",
            "csv",
            "--out",
            "shape.csv",
        ],
        None,
    );
    exits(&out, 0);
    let csv = std::fs::read_to_string(dir.join("shape.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], tdcr::io::output::CSV_HEADER);
    assert_eq!(lines.len(), 8);
    assert!(lines.iter().all(|l| l.split(',').count() == 19));
}

#[test]
fn table_output_and_plot() {
    let dir = scratch("table");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &["solve", "robot.toml", "--tol", "1e-8", "-v", "--plot", "shape.svg"],
        None,
    );
    exits(&out, 0);
    let text = stdout(&out);
    assert!(
        text.contains("tip position (mm):") && text.contains("(error-controlled)") && text.contains("(met)"),
        "{text}"
    );
    has(&stderr(&out), "iter   residual");
    let svg = std::fs::read_to_string(dir.join("shape.svg")).unwrap();
    assert!(
        svg.contains("<polyline") && svg.contains("tendon 1 (thin line)"),
        "{svg}"
    );

    // The extension picks the format; --disks sets the disks drawn.
    let out = run(
        &dir,
        &["solve", "robot.toml", "--plot", "shape.png", "--disks", "5"],
        None,
    );
    exits(&out, 0);
    has(&stderr(&out), "wrote shape.png");
    let png = std::fs::read(dir.join("shape.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let out = run(
        &dir,
        &["solve", "robot.toml", "--plot", "shape.svg", "--disks", "5"],
        None,
    );
    exits(&out, 0);
    let svg = std::fs::read_to_string(dir.join("shape.svg")).unwrap();
    assert_eq!(svg.matches(r#"class="disk""#).count(), 5 * 4);
    let out = run(&dir, &["solve", "robot.toml", "--plot", "shape.jpg"], None);
    exits(&out, 2);
    has(&stderr(&out), "FILE.png");
    // Views, title, subtitle, width and text size for a paper.
    let args = [
        "solve",
        "robot.toml",
        "--plot",
        "paper.svg",
        "--views",
        "side,perspective",
        "--title",
        "",
        "--no-subtitle",
        "--width",
        "700",
        "--font-size",
        "10",
    ];
    let out = run(&dir, &args, None);
    exits(&out, 0);
    let svg = std::fs::read_to_string(dir.join("paper.svg")).unwrap();
    assert!(svg.starts_with(r#"<svg xmlns="http://www.w3.org/2000/svg" width="700""#));
    assert!(svg.contains("side view (XZ)") && svg.contains("perspective"));
    assert!(!svg.contains("top view") && !svg.contains("front view") && !svg.contains("solved shape"));
    assert!(!svg.contains("class=\"subtitle\""));
    let out = run(
        &dir,
        &["solve", "robot.toml", "--plot", "x.svg", "--views", "side,iso"],
        None,
    );
    exits(&out, 2);
    has(&stderr(&out), "`iso` is not a view");
}

#[test]
fn shooting_agrees_with_collocation_through_the_command() {
    let dir = scratch("shooting");
    let json = |method: &str| {
        let out = run(
            &dir,
            &["solve", "-", "--format", "json", "--method", method],
            Some(&example()),
        );
        exits(&out, 0);
        tip_of(&serde_json::from_str(&stdout(&out)).unwrap())
    };
    let (a, b) = (json("collocation"), json("shooting"));
    for k in 0..3 {
        // 1e-6 m: the 32-interval mesh's discretization error on case S is below 1e-7 m.
        assert!((a[k] - b[k]).abs() < 1e-6, "{a:?} vs {b:?}");
    }
}

#[test]
fn sweep_writes_csv_rows_and_a_trajectory_plot() {
    let dir = scratch("sweep");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &[
            "sweep",
            "robot.toml",
            "--tension",
            "1=0:3:7",
            "--tension",
            "2=0.5",
            "--plot",
            "tip.svg",
        ],
        None,
    );
    exits(&out, 0);
    let csv = stdout(&out);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("step,tension.1,tension.2"));
    assert_eq!(lines.len(), 8);
    assert!(lines[7].starts_with("7,3,0.5,"), "{}", lines[7]);
    // Pulling tendon 1 harder bends the tip down: z decreases along the sweep.
    let z: Vec<f64> = lines[1..]
        .iter()
        .map(|l| l.split(',').nth(8).unwrap().parse().unwrap())
        .collect();
    assert!(z.windows(2).all(|w| w[1] < w[0]), "{z:?}");
    assert!(
        std::fs::read_to_string(dir.join("tip.svg"))
            .unwrap()
            .contains("tip trajectory")
    );
}

#[test]
fn check_accepts_the_example() {
    let dir = scratch("check-ok");
    let out = run(&dir, &["check", "-"], Some(&example()));
    exits(&out, 0);
    assert!(stdout(&out).contains("OK"));
}

/// Runs `check` and `solve` on a robot file text; both must exit 2 and name `fragments`.
fn rejected(name: &str, text: &str, fragments: &[&str]) {
    let dir = scratch(name);
    std::fs::write(dir.join("robot.toml"), text).unwrap();
    for command in ["check", "solve"] {
        let out = run(&dir, &[command, "robot.toml"], None);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{command} {name}: {message}");
        for f in fragments {
            assert!(message.contains(f), "{command} {name}: `{f}` not in {message}");
        }
    }
}

#[test]
fn missing_field_is_named_with_its_table_line() {
    rejected(
        "missing",
        &edited("length = 0.242", "# no length"),
        &["robot.toml:5:1:", "`rod.length` is required but missing in [rod]"],
    );
}

#[test]
fn unknown_key_names_the_key_and_its_table() {
    rejected(
        "unknown",
        &edited("tension = 2.94", "tension = 2.94\ncolour = \"red\""),
        &["unknown field `colour`", "[[tendon]] #1", ":36:1:"],
    );
    rejected(
        "unknown-table",
        &format!("{}\n[motor]\nspeed = 1\n", example()),
        &["unknown key `motor` at the top level"],
    );
}

#[test]
fn wrong_type_names_field_and_line() {
    rejected(
        "type",
        &edited("length = 0.242", "length = \"long\""),
        &["robot.toml:6:10:", "`rod.length`", "expected a number"],
    );
}

#[test]
fn nan_and_infinity_are_rejected() {
    rejected(
        "nan",
        &edited("youngs_modulus = 210e9", "youngs_modulus = nan"),
        &[
            ":9:1:",
            "`rod.youngs_modulus` is nan Pa, but every number must be finite",
        ],
    );
    rejected(
        "inf",
        &edited("tip_force = [0.0, 0.0, 0.0]", "tip_force = [0.0, inf, 0.0]"),
        &["`loads.tip_force` has y = inf N"],
    );
}

#[test]
fn negative_and_out_of_range_values_are_rejected() {
    rejected(
        "negative",
        &edited("tension = 2.94", "tension = -1.0"),
        &[":35:1:", "`tendon[1].tension` is -1 N", "must be >= 0"],
    );
    rejected(
        "radius",
        &edited("outer_radius = 0.0004", "outer_radius = -0.0004"),
        &["`rod.outer_radius` is -0.0004 m, but must be positive"],
    );
    rejected(
        "poisson",
        &edited("poisson_ratio = 0.3125", "poisson_ratio = 0.7"),
        &["`rod.poisson_ratio` is 0.7, but must lie in (-1, 0.5]"],
    );
    rejected(
        "tube",
        &edited("# inner_radius = 0.0", "inner_radius = 0.0005"),
        &["`rod.inner_radius` is 0.0005 m, but must be below the outer radius"],
    );
}

#[test]
fn tendon_ending_past_the_tip_is_rejected() {
    rejected(
        "past-tip",
        &edited("# end = 0.242", "end = 0.3"),
        &[":36:1:", "`tendon[1].end` is 0.3 m, past the tip at 0.242 m"],
    );
}

#[test]
fn bad_rotation_and_routing_kind_are_rejected() {
    rejected(
        "rotation",
        &edited("[-1.0, 0.0, 0.0]]", "[-1.0, 0.0, 0.5]]"),
        &["`base.rotation` is not a rotation"],
    );
    rejected(
        "kind",
        &edited("kind = \"helical\"", "kind = \"spiral\""),
        &[
            "unknown variant `spiral`, expected `straight` or `helical`",
            "[[tendon]] #5",
        ],
    );
}

#[test]
fn every_problem_of_a_file_is_listed() {
    let text = edited("tension = 2.94", "tension = -1.0")
        .replacen("length = 0.242", "length = -0.242", 1)
        .replacen("poisson_ratio = 0.3125", "poisson_ratio = 2.0", 1);
    rejected(
        "many",
        &text,
        &[
            "`rod.length` is -0.242 m",
            "`rod.poisson_ratio` is 2",
            "`tendon[1].tension` is -1 N",
        ],
    );
}

#[test]
fn empty_unreadable_and_non_toml_files_are_rejected() {
    rejected("empty", "", &["robot.toml: is empty"]);
    rejected(
        "not-toml",
        "this is not a robot\n",
        &["robot.toml:1:", "is not valid TOML"],
    );
    let dir = scratch("unreadable");
    let out = run(&dir, &["solve", "no-such-robot.toml"], None);
    exits(&out, 2);
    has(&stderr(&out), "cannot read robot file no-such-robot.toml");
}

#[test]
fn bad_options_exit_2() {
    let dir = scratch("options");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    for (args, fragment) in [
        (
            &["solve", "robot.toml", "--tension", "9=1"][..],
            "the robot has 5 tendon(s)",
        ),
        (
            &["solve", "robot.toml", "--tension", "1=-2"][..],
            "a tendon can only pull",
        ),
        (
            &["solve", "robot.toml", "--tip-force", "1,2"][..],
            "three comma-separated numbers",
        ),
        (&["solve", "robot.toml", "--tol", "nan"][..], "not finite"),
        (&["solve", "robot.toml", "--intervals", "0"][..], "from 1 to"),
        (
            &["sweep", "robot.toml", "--tension", "1=0:1:3", "--tension", "2=0:1:4"][..],
            "the same COUNT",
        ),
        (&["solve", "robot.toml", "--frobnicate"][..], "unexpected argument"),
    ] {
        let out = run(&dir, args, None);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(fragment), "{args:?}: {}", stderr(&out));
    }
}

/// `--nodes` and the file keys `nodes` / `max_nodes` are the old names of `--intervals`,
/// `intervals` / `max_intervals`: still accepted, with the same meaning.
#[test]
fn old_names_of_intervals_still_work() {
    let dir = scratch("old-names");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let intervals = |out: &Output| -> serde_json::Value {
        assert_eq!(out.status.code(), Some(0), "{}", stderr(out));
        serde_json::from_str::<serde_json::Value>(&stdout(out)).unwrap()["intervals"].clone()
    };
    for flag in ["--intervals", "--nodes"] {
        let out = run(&dir, &["solve", "robot.toml", flag, "24", "--format", "json"], None);
        assert_eq!(intervals(&out), 24, "{flag}");
    }
    let text = edited("\n# intervals = 32 ", "\nnodes = 40 ");
    std::fs::write(dir.join("alias.toml"), &text).unwrap();
    let out = run(&dir, &["solve", "alias.toml", "--format", "json"], None);
    assert_eq!(intervals(&out), 40);
    // `max_nodes` is read as the cap: 20 is below `nodes` = 40.
    let capped = text.replacen("# max_intervals = 8192 ", "max_nodes = 20 ", 1);
    assert_ne!(capped, text);
    std::fs::write(dir.join("capped.toml"), capped).unwrap();
    let out = run(&dir, &["check", "capped.toml"], None);
    exits(&out, 2);
    let message = stderr(&out);
    assert!(
        message.contains("`solver.nodes` is 40, above `max_intervals` = 20"),
        "{message}"
    );
}

/// A key given together with its old name is bad input, and the message names both.
#[test]
fn a_key_and_its_old_name_together_exit_2_naming_both() {
    let dir = scratch("both-names");
    let text = edited("\n# intervals = 32 ", "\nintervals = 32\nnodes = 32 ").replacen(
        "# max_intervals = 8192 ",
        "max_intervals = 64\nmax_nodes = 64 ",
        1,
    );
    std::fs::write(dir.join("robot.toml"), text).unwrap();
    for command in ["check", "solve"] {
        let out = run(&dir, &[command, "robot.toml"], None);
        assert_eq!(out.status.code(), Some(2), "{command}: {}", stderr(&out));
        let message = stderr(&out);
        for (alias, name) in [("nodes", "intervals"), ("max_nodes", "max_intervals")] {
            assert!(
                message.lines().any(|l| l.starts_with("error: robot.toml:")
                    && l.contains(&format!("`solver.{alias}` is given together with `{name}`"))),
                "{command}: {message}"
            );
        }
    }
}

#[test]
fn forced_non_convergence_exits_3_with_diagnostics() {
    // One Newton iteration and no load continuation cannot reach the residual tolerance of
    // 1e-11 under a 20 N pull and a 0.5 N tip load.
    let text = edited("# max_iterations = 30", "max_iterations = 1").replacen(
        "# continuation = true",
        "continuation = false",
        1,
    );
    let dir = scratch("no-convergence");
    std::fs::write(dir.join("robot.toml"), text).unwrap();
    let out = run(
        &dir,
        &["solve", "robot.toml", "--tension", "1=20", "--tip-force", "0,0,-0.5"],
        None,
    );
    exits(&out, 3);
    let message = stderr(&out);
    assert!(
        message.contains("did not converge") && message.contains("iteration limit"),
        "{message}"
    );
    has(&message, "iter   residual");
    assert!(stdout(&out).is_empty());
}

#[test]
fn bench_reports_both_cases_cold_and_warm_as_json() {
    let dir = scratch("bench");
    let out = run(&dir, &["bench", "--repeats", "1", "--format", "json"], None);
    exits(&out, 0);
    let rows: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for (row, (case, start)) in rows
        .iter()
        .zip([("S", "cold"), ("S", "warm"), ("H", "cold"), ("H", "warm")])
    {
        assert_eq!(row["case"], case);
        assert_eq!(row["start"], start);
        assert!(row["median_seconds"].as_f64().unwrap() > 0.0);
        // Thread CPU time where tdcr bench reads it (64-bit Linux), null elsewhere.
        if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            assert!(row["median_cpu_seconds"].as_f64().unwrap() > 0.0);
        } else {
            assert!(row["median_cpu_seconds"].is_null());
        }
        assert!(row["iterations"].as_u64().unwrap() >= 1);
        // 1e-7 m: the default target error, met against the published reference tips
        assert!(row["tip_error_m"].as_f64().unwrap() <= 1e-7);
        assert!(row["nodes"].as_u64().unwrap() >= 9);
        // Intervals and nodes name their own counts; iterations are Newton plus chord steps.
        assert_eq!(row["nodes"].as_u64(), row["intervals"].as_u64().map(|n| n + 1));
        assert_eq!(
            row["iterations"].as_u64(),
            Some(row["newton_steps"].as_u64().unwrap() + row["chord_steps"].as_u64().unwrap())
        );
        // The solver's own estimate, asymptotically exact: within 30 % of the true error
        // (the reference tips themselves are good to 5e-10 m, 10 % of S's error of 5e-9 m)
        let (estimate, error) = (
            row["error_estimate_m"].as_f64().unwrap(),
            row["tip_error_m"].as_f64().unwrap(),
        );
        assert!((estimate / error - 1.0).abs() < 0.3, "{row}");
    }
}

#[test]
fn jacobian_in_json_matches_the_library_and_a_finite_difference() {
    let dir = scratch("jacobian");
    let solve = |tension: &str| {
        let out = run(
            &dir,
            &["solve", "-", "--format", "json", "--jacobian", "--tension", tension],
            Some(&example()),
        );
        exits(&out, 0);
        serde_json::from_str::<serde_json::Value>(&stdout(&out)).unwrap()
    };
    let json = solve("1=2.94");
    let jacobian = &json["jacobian"];
    assert_eq!(jacobian["tension"].as_array().unwrap().len(), 6);
    assert_eq!(jacobian["tension"][0].as_array().unwrap().len(), 5);
    assert_eq!(jacobian["tip_force"][5].as_array().unwrap().len(), 3);
    assert_eq!(jacobian["tip_moment"][0].as_array().unwrap().len(), 3);
    // d tip / d tau_1 against a central difference of two solves 1e-3 N apart: agreement to
    // 1e-4 relative (the difference's truncation error, tau^2 terms over a 2.94 N base)
    let (a, b) = (tip_of(&solve("1=2.939")), tip_of(&solve("1=2.941")));
    for row in 0..3 {
        let fd = (b[row] - a[row]) / 2e-3;
        let exact = jacobian["tension"][row][0].as_f64().unwrap();
        assert!(
            (fd - exact).abs() <= 1e-4 * exact.abs().max(1e-3),
            "row {row}: {fd} vs {exact}"
        );
    }
}

/// With a displacement-controlled tendon, `--jacobian` has its pull-in column (the review:
/// it used to fail with "leaves a scaled residual"): against a central difference of two
/// solves 2e-5 m apart.
#[test]
fn jacobian_of_a_displacement_controlled_tendon() {
    let dir = scratch("jacobian_displacement");
    let solve = |q: &str| {
        let out = run(
            &dir,
            &[
                "solve",
                "-",
                "--format",
                "json",
                "--jacobian",
                "--tension",
                "1=0",
                "--displacement",
                q,
            ],
            Some(&example()),
        );
        exits(&out, 0);
        serde_json::from_str::<serde_json::Value>(&stdout(&out)).unwrap()
    };
    let json = solve("2=0.005");
    let jacobian = &json["jacobian"];
    assert_eq!(jacobian["displacement"][0].as_array().unwrap().len(), 5);
    let (a, b) = (tip_of(&solve("2=0.00499")), tip_of(&solve("2=0.00501")));
    for row in 0..3 {
        let fd = (b[row] - a[row]) / 2e-5;
        let exact = jacobian["displacement"][row][1].as_f64().unwrap();
        assert_eq!(jacobian["tension"][row][1].as_f64().unwrap(), 0.0);
        // 3e-3 m/m: default error-controlled solves, whose tips carry up to the 2.4e-8 m
        // tolerance each, over the 2e-5 m difference (2.4e-3), plus rounding
        assert!((fd - exact).abs() <= 3e-3, "row {row}: {fd} vs {exact}");
    }
}

/// The first line of `tdcr solve` states the mesh, the iterations, the time and the estimated
/// tip error against the tolerance; the JSON carries the estimate, the tolerance and whether
/// it is met, on fixed meshes too.
#[test]
fn solve_reports_its_error_estimate_against_the_tolerance() {
    let dir = scratch("estimate");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(&dir, &["solve", "robot.toml"], None);
    exits(&out, 0);
    let first = stdout(&out).lines().next().unwrap_or_default().to_string();
    for part in [
        "intervals (error-controlled)",
        " Newton",
        " ms; stable;",
        "estimated tip error",
        "against tolerance 2.4e-8 m",
        "(met)",
    ] {
        assert!(first.contains(part), "{part}: {first}");
    }
    let out = run(&dir, &["solve", "robot.toml", "--format", "json"], None);
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let estimate = &json["error_estimate"];
    for key in ["tip_position_m", "tip_rotation_rad", "backbone_max_m"] {
        assert!(estimate[key].as_f64().unwrap() > 0.0, "{key}: {estimate}");
    }
    // The counts are separate and add up: iterations = Newton steps + chord steps; a direct
    // solve takes no load steps.
    let counts = &json["counts"];
    let count = |k: &str| counts[k].as_u64().unwrap_or_else(|| panic!("{k}: {counts}"));
    assert_eq!(
        json["iterations"].as_u64(),
        Some(count("newton_steps") + count("chord_steps"))
    );
    assert!(count("newton_steps") >= 1 && count("jacobian_evaluations") >= count("newton_steps"));
    assert_eq!(count("load_steps"), 0);
    assert!(count("meshes") >= 1);
    assert_eq!(json["stability"]["verdict"], "stable");
    assert_eq!(json["stability"]["path"], "direct");
    assert_eq!(json["tolerance"].as_f64(), Some(1e-7));
    assert_eq!(json["tolerance_met"].as_bool(), Some(true));
    assert_eq!(json["tip_error_estimate"], estimate["tip_position_m"]);
    // A fixed mesh: no tolerance, still an estimate.
    let out = run(
        &dir,
        &["solve", "robot.toml", "--intervals", "8", "--format", "json"],
        None,
    );
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert!(json["tolerance"].is_null() && json["tolerance_met"].is_null(), "{json}");
    assert!(json["error_estimate"]["tip_position_m"].as_f64().unwrap() > 1e-7);
    let out = run(&dir, &["solve", "robot.toml", "--intervals", "8"], None);
    assert!(stdout(&out).lines().next().unwrap_or_default().contains("(fixed mesh)"));
}

/// Issue 18: counts that size allocations are bounded before use. `max_iterations` of 2^63 - 1
/// panicked with a capacity overflow; 1e9 and 2^32 aborted on a 137 GB allocation.
#[test]
fn huge_iteration_counts_exit_2_naming_the_bound() {
    for n in ["9223372036854775807", "1000000000", "4294967296", "10001"] {
        let text = edited("# max_iterations = 30 ", &format!("max_iterations = {n} "));
        let line = 1 + text.lines().position(|l| l.starts_with("max_iterations")).unwrap();
        let at = format!("robot.toml:{line}:1: `solver.max_iterations`");
        rejected(
            &format!("iterations-{n}"),
            &text,
            &[&at, &format!("is {n}, above the limit of 10000")],
        );
    }
}

/// Issue 18: arrays longer than 3 were cut to their first 3 entries (even with NaN, strings or
/// tables in the rest); a wrong length names the field, the length found and the expected.
#[test]
fn arrays_of_the_wrong_length_exit_2_naming_both_lengths() {
    for (value, found) in [
        ("[1.0, 2.0, 3.0, nan]", 4),
        ("[1.0, 2.0, 3.0, \"x\"]", 4),
        ("[1.0, 2.0, 3.0, { a = 1 }]", 4),
        ("[1.0, 2.0]", 2),
        ("[]", 0),
        ("[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]", 6),
    ] {
        let text = edited("tip_force = [0.0, 0.0, 0.0]", &format!("tip_force = {value}"));
        rejected(
            &format!("tip-force-{found}"),
            &text,
            &[
                "`loads.tip_force`",
                &format!("has {found} entries, but must have 3 (numbers x, y, z)"),
            ],
        );
    }
    let rod = "[rod]\nlength = 0.2\nouter_radius = 0.001\nyoungs_modulus = 2e11\npoisson_ratio = 0.3\n";
    for (table, line, field) in [
        ("rod", "precurvature = [0.0, 0.0, 0.0, 0.0]", "rod.precurvature"),
        ("base", "position = [0.0, 0.0, 0.0, 0.0]", "base.position"),
        ("base", "euler_xyz_deg = [0.0, 0.0]", "base.euler_xyz_deg"),
    ] {
        let text = if table == "rod" {
            format!("{rod}{line}\n")
        } else {
            format!("{rod}[{table}]\n{line}\n")
        };
        rejected(field, &text, &[&format!("`{field}`"), "entries, but must have 3"]);
    }
    let rows =
        format!("{rod}[base]\nrotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]\n");
    rejected(
        "rotation-rows",
        &rows,
        &["`base.rotation`", "has 4 entries, but must have 3 (rows of 3 numbers)"],
    );
    let row = format!("{rod}[base]\nrotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 0.0]]\n");
    rejected(
        "rotation-row",
        &row,
        &[
            "`base.rotation[3]`",
            "has 4 entries, but must have 3 (numbers in each row)",
        ],
    );
}

/// Issue 18: a sweep given the same tendon twice took the last range silently.
#[test]
fn a_sweep_with_a_tendon_given_twice_exits_2() {
    let dir = scratch("sweep-twice");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &["sweep", "robot.toml", "--tension", "1=0:1:3", "--tension", "1=0:2:3"],
        None,
    );
    exits(&out, 2);
    has(
        &stderr(&out),
        "error: --tension 1=... is given twice: give each tendon one range or value",
    );
}

/// Issue 18: `--intervals 8192 --tol 1e-12` reported "an estimated tip error of NaN m"; now
/// every mesh carries its estimate and a cap names it (here 64 intervals cannot reach
/// 1e-13 L: no mesh can, the order-6 answer's estimate carries 4e-13 L of rounding).
#[test]
fn an_interval_cap_names_its_estimate_and_exits_3() {
    let dir = scratch("cap-estimate");
    let text = edited("# max_intervals = 8192 ", "max_intervals = 64 ");
    std::fs::write(dir.join("robot.toml"), text).unwrap();
    let out = run(&dir, &["solve", "robot.toml", "--tol", "1e-13"], None);
    exits(&out, 3);
    let message = stderr(&out);
    assert!(!message.contains("NaN"), "{message}");
    assert!(
        message.contains("needs more than the cap of 64 intervals")
            && message.contains("estimated tip position error of"),
        "{message}"
    );
}

/// Issue 18: a file that is not UTF-8 was rejected without a position.
#[test]
fn a_file_that_is_not_utf8_names_the_line_and_byte() {
    let dir = scratch("not-utf8");
    let mut bytes = example().into_bytes();
    let at = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
    bytes.insert(at + 2, 0xFF);
    std::fs::write(dir.join("robot.toml"), &bytes).unwrap();
    for command in ["check", "solve"] {
        let out = run(&dir, &[command, "robot.toml"], None);
        exits(&out, 2);
        let expected = format!(
            "error: robot.toml:2: is not UTF-8 text: byte 0xFF at byte offset {} (byte 3 of line 2)",
            at + 2
        );
        assert!(stderr(&out).starts_with(&expected), "{}", stderr(&out));
    }
}

/// Issue 18: extreme values printed as hundreds of digits (`is -1000...0 m`).
#[test]
fn extreme_values_are_printed_in_scientific_notation() {
    let text = edited("length = 0.242 ", "length = -1e300 ");
    rejected("extreme", &text, &["`rod.length` is -1e300 m, but must be positive"]);
    let dir = scratch("extreme-tension");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(&dir, &["solve", "robot.toml", "--tension", "1=-1e300"], None);
    exits(&out, 2);
    has(&stderr(&out), "tension -1e300 N is negative");
}

/// Issue 18: a helix of 100 turns on the file's fixed 32 intervals exited 0 with a tip 18 cm
/// (76 % of L) off; now exit 2 with the intervals that resolve it, and a solve on those.
#[test]
fn a_fixed_mesh_that_aliases_a_helix_exits_2_with_the_intervals_needed() {
    // The file fixes its mesh (`intervals` without `tolerance`).
    let text = edited("turns_per_rod_length = 1.0,", "turns_per_rod_length = 100.0,").replacen(
        "\n# intervals = 32 ",
        "\nintervals = 32 ",
        1,
    );
    let dir = scratch("aliased");
    std::fs::write(dir.join("robot.toml"), &text).unwrap();
    let out = run(&dir, &["solve", "robot.toml", "--tension", "5=2"], None);
    exits(&out, 2);
    let message = stderr(&out);
    for fragment in [
        "`options.intervals` is 32 intervals",
        "cannot resolve the robot",
        "400 intervals resolve it",
        "--tol",
    ] {
        assert!(message.contains(fragment), "no `{fragment}` in {message}");
    }
    // `check` gives the same verdict without solving.
    let out = run(&dir, &["check", "robot.toml"], None);
    exits(&out, 2);
    assert!(stderr(&out).starts_with("error: robot.toml: invalid input: `options.intervals` is 32 intervals"));
    has(&stderr(&out), "400 intervals resolve it");
    let out = run(
        &dir,
        &["solve", "robot.toml", "--tension", "5=2", "--intervals", "400"],
        None,
    );
    exits(&out, 0);
    // A tolerance instead of the fixed mesh lets refinement choose it.
    let tolerant = text.replacen("\nintervals = 32 ", "\ntolerance = 1e-4\nintervals = 32 ", 1);
    assert_ne!(tolerant, text);
    std::fs::write(dir.join("robot.toml"), &tolerant).unwrap();
    let out = run(&dir, &["check", "robot.toml"], None);
    exits(&out, 0);
}

#[test]
fn trace_writes_the_branch_with_stability_and_a_picture() {
    let dir = scratch("trace");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &[
            "trace",
            "robot.toml",
            "--param",
            "tension.1=0:4",
            "--plot",
            "branch.svg",
        ],
        None,
    );
    exits(&out, 0);
    let csv = stdout(&out);
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("point,tension.1,tip_x,tip_y,tip_z,stability,unstable_directions,fold,iterations")
    );
    let rows: Vec<&str> = lines.collect();
    // At least 20 points on a branch that runs straight from 0 to 4 N (steps of at most
    // 0.05 in the normalized arclength), all stable, the last at 4 N.
    assert!(rows.len() >= 20, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r.contains(",stable,0,0,")), "{csv}");
    assert!(rows.last().unwrap().starts_with(&format!("{},4,", rows.len())), "{csv}");
    let svg = std::fs::read_to_string(dir.join("branch.svg")).unwrap();
    assert!(svg.contains("tension.1 (N)") && svg.contains("stable equilibria"));
    // A parameter that does not exist is bad input, named with the accepted forms; E is one
    // that only a sweep varies, and the message says so.
    let out = run(&dir, &["trace", "robot.toml", "--param", "poisson_ratio=0.3:0.4"], None);
    exits(&out, 2);
    has(&stderr(&out), "tension.I");
    let out = run(
        &dir,
        &["trace", "robot.toml", "--param", "youngs_modulus=1e11:2e11"],
        None,
    );
    exits(&out, 2);
    has(&stderr(&out), "sweep E instead");
}

#[test]
fn trace_and_compare_take_the_tendon_inputs_solve_takes() {
    // user25: `trace --tension` and `compare --tension` were unknown options (clap pointed
    // at `--tendons`), and trace's refusal of friction could only be answered in the file.
    let dir = scratch("trace-inputs");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let first_tip = |out: &Output| -> Vec<f64> {
        let csv = stdout(out);
        let row = csv.lines().nth(1).unwrap().to_string();
        row.split(',').skip(2).take(3).map(|x| x.parse().unwrap()).collect()
    };
    let args = ["trace", "robot.toml", "--param", "tension.1=0:1"];
    let plain = run(&dir, &args, None);
    exits(&plain, 0);
    let with = run(&dir, &[&args[..], &["--tension", "2=0.5"]].concat(), None);
    exits(&with, 0);
    let out = run(
        &dir,
        &[
            "solve",
            "robot.toml",
            "--tension",
            "1=0",
            "--tension",
            "2=0.5",
            "--format",
            "json",
        ],
        None,
    );
    exits(&out, 0);
    let solved = tip_of(&serde_json::from_str(&stdout(&out)).unwrap());
    let traced = first_tip(&with);
    // The trace's first point is the solve of the same inputs; both converge to Newton's
    // tolerance (1e-11 scaled), far below 1e-9 m.
    for k in 0..3 {
        assert!((traced[k] - solved[k]).abs() < 1e-9, "{traced:?} {solved:?}");
    }
    assert!(
        (first_tip(&plain)[1] - traced[1]).abs() > 1e-3,
        "tendon 2 bends the rod sideways"
    );
    let rough = example().replacen("# friction = 0.1 ", "friction = 0.1 ", 1);
    assert_ne!(rough, example());
    std::fs::write(dir.join("rough.toml"), rough).unwrap();
    let refused = run(&dir, &["trace", "rough.toml", "--param", "tension.1=0:1"], None);
    // A trace does not model friction: a model limit (exit 4), not bad input.
    exits(&refused, 4);
    has(&stderr(&refused), "--friction I=0");
    let out = run(
        &dir,
        &["trace", "rough.toml", "--param", "tension.1=0:1", "--friction", "1=0"],
        None,
    );
    exits(&out, 0);
    assert_eq!(stdout(&out), stdout(&plain));
    let out = run(
        &dir,
        &["compare", "robot.toml", "--tension", "1=1", "--displacement", "1=0.001"],
        None,
    );
    exits(&out, 2);
    has(&stderr(&out), "both given");
    let out = run(&dir, &["compare", "robot.toml", "--tension", "1=1"], None);
    exits(&out, 0);
}

#[test]
fn sweep_reports_a_jump_and_varies_any_input() {
    let dir = scratch("sweep-jump");
    // About twice Euler's load on a 0.5 m rod buckled towards -x by a 10 mN imperfection; a
    // tendon on the +x side makes that state unstable out of plane at 0.13 N, and the robot
    // ends bent towards +x: the tip jumps by about 0.8 m.
    let robot = "[rod]\nlength = 0.5\nouter_radius = 0.001\nyoungs_modulus = 200e9\npoisson_ratio = 0.3\n\
                 [loads]\ndistributed_force = [0.0, 0.0, -0.24]\ntip_force = [-0.01, 0.0, -3.0]\n\
                 [[tendon]]\nrouting = { kind = \"straight\", x = 0.015, y = 0.0 }\ntension = 0.0\n";
    std::fs::write(dir.join("robot.toml"), robot).unwrap();
    let out = run(&dir, &["sweep", "robot.toml", "--tension", "1=0:2:3"], None);
    exits(&out, 0);
    has(&stderr(&out), "sweep step 2: snap at tension.1 = ");
    let csv = stdout(&out);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(&header[header.len() - 3..], ["stability", "path", "event"]);
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    // The events located between steps 1 and 2: the bifurcation out of the plane, then the
    // snap, each with its tension.
    let event = rows[1].last().unwrap().trim_matches('"');
    assert!(event.starts_with("bifurcation at tension.1 = 0.124"), "{event:?}");
    assert!(event.contains("; snap at tension.1 = "), "{csv}");
    assert!(rows[2].last().unwrap().is_empty(), "{csv}");
    // The picture marks the snap: the shapes either side and the tip's jump, in the legend.
    let args = ["sweep", "robot.toml", "--tension", "1=0:2:3", "--out", "s.csv"];
    let out = run(
        &dir,
        &[&args[..], &["--plot", "snap.svg", "--shapes", "all"]].concat(),
        None,
    );
    exits(&out, 0);
    let svg = std::fs::read_to_string(dir.join("snap.svg")).unwrap();
    has(&svg, "step 2: snap at tension.1 = ");
    has(&svg, "1 shape in between");
    // --param varies E: a stiffer rod bends less under the same tendon.
    std::fs::write(dir.join("ex.toml"), example()).unwrap();
    let out = run(
        &dir,
        &["sweep", "ex.toml", "--param", "youngs_modulus=100e9:300e9:3"],
        None,
    );
    exits(&out, 0);
    let csv = stdout(&out);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let angle = header.iter().position(|h| *h == "bending_angle_deg").unwrap();
    let angles: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(angle).unwrap().parse().unwrap())
        .collect();
    assert!(angles.windows(2).all(|w| w[1] < w[0]), "{angles:?}");
}

#[test]
fn a_saved_solution_warm_starts_solve_and_sweep() {
    let dir = scratch("start");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(
        &dir,
        &["solve", "robot.toml", "--format", "json", "--out", "saved.json"],
        None,
    );
    exits(&out, 0);
    // From its own solution a solve has nothing left to do: one step, the same tip.
    let out = run(
        &dir,
        &["solve", "robot.toml", "--start", "saved.json", "--format", "json"],
        None,
    );
    exits(&out, 0);
    let again: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("saved.json")).unwrap()).unwrap();
    assert!(again["iterations"].as_u64().unwrap() <= 2, "{}", again["iterations"]);
    let (a, b) = (tip_of(&again), tip_of(&saved));
    // 1e-10 m: the same discrete solution, read back from 17-digit JSON
    assert!((0..3).all(|i| (a[i] - b[i]).abs() < 1e-10), "{a:?} {b:?}");
    let out = run(
        &dir,
        &[
            "sweep",
            "robot.toml",
            "--start",
            "saved.json",
            "--tension",
            "1=2.94:3.5:3",
        ],
        None,
    );
    exits(&out, 0);
    // A solution of another robot (a longer rod) is bad input, with the lengths.
    std::fs::write(dir.join("long.toml"), edited("length = 0.242", "length = 0.3")).unwrap();
    let out = run(&dir, &["solve", "long.toml", "--start", "saved.json"], None);
    exits(&out, 2);
    has(&stderr(&out), "0.3 m long");
}

/// Issue 16: `sweep --displacement` pulls tendon 1 of an antagonistic pair in and lets
/// tendon 2 out by the same amount; the CSV has the pull-ins and the solved tensions.
#[test]
fn a_sweep_over_pull_ins_reports_solved_tensions_and_slack() {
    let dir = scratch("sweep-displacement");
    let robot = "[rod]\nlength = 0.242\nouter_radius = 0.0004\nyoungs_modulus = 210e9\npoisson_ratio = 0.3125\n\
                 [[tendon]]\nrouting = { kind = \"straight\", x = 0.008, y = 0.0 }\ntension = 0.0\n\
                 [[tendon]]\nrouting = { kind = \"straight\", x = -0.008, y = 0.0 }\ntension = 0.0\n";
    std::fs::write(dir.join("pair.toml"), robot).unwrap();
    let out = run(
        &dir,
        &[
            "sweep",
            "pair.toml",
            "--displacement",
            "1=0:0.004:5",
            "--displacement",
            "2=0:-0.004:5",
        ],
        None,
    );
    exits(&out, 0);
    let csv = stdout(&out);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        &header[..5],
        ["step", "tension.1", "tension.2", "displacement.1", "displacement.2"]
    );
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(5).map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 5);
    for (k, row) in rows.iter().enumerate() {
        // 1e-15 m: the pull-ins are the inputs, printed in full
        assert!((row[3] - 0.001 * k as f64).abs() < 1e-15, "{row:?}");
        assert!((row[4] + 0.001 * k as f64).abs() < 1e-15, "{row:?}");
        // The released tendon goes slack (tension exactly 0) once the rod bends.
        if k > 0 {
            assert_eq!(row[2], 0.0, "{row:?}");
        }
    }
    // At no pull-in the weightless rod stays straight with both tendons just taut: 1e-6 N,
    // the semismooth Newton's residual scale on zero tensions (measured 7e-11 N).
    assert!(rows[0][1].abs() < 1e-6 && rows[0][2].abs() < 1e-6, "{csv}");
    // The pulled tendon's solved tension grows with its pull-in.
    assert!(rows.windows(2).all(|w| w[1][1] > w[0][1]), "{csv}");
    // Both by tension and by displacement for one tendon: bad input.
    let out = run(
        &dir,
        &[
            "sweep",
            "pair.toml",
            "--tension",
            "1=0:1:3",
            "--displacement",
            "1=0:0.001:3",
        ],
        None,
    );
    exits(&out, 2);
    has(&stderr(&out), "both given");
}

/// A weightless antagonistic pair (tendons at +-8 mm on the prototype's rod), both driven by
/// tension 0 unless a command line or an edit says otherwise.
const PAIR: &str = "[rod]\nlength = 0.242\nouter_radius = 0.0004\nyoungs_modulus = 210e9\npoisson_ratio = 0.3125\n\
                    [[tendon]]\nrouting = { kind = \"straight\", x = 0.008, y = 0.0 }\ntension = 0.0\n\
                    [[tendon]]\nrouting = { kind = \"straight\", x = -0.008, y = 0.0 }\ntension = 0.0\n";

/// The prototype with tendon 1 pulled in by `pull` (m) and every other tendon held by its
/// actuator at `others` (m).
fn pulled_prototype(pull: &str, others: &str) -> String {
    example()
        .replacen("tension = 2.94", &format!("displacement = {pull}"), 1)
        .replace("tension = 0.0", &format!("displacement = {others}"))
}

/// Review item 1: a displacement solve that converges to tensions past the geometric limit
/// (actuators holding the antagonists the pull stretches) says so, as a tension input
/// would; letting the antagonists out gives no warning.
#[test]
fn solved_tensions_past_the_geometric_limit_are_warned_about() {
    let dir = scratch("solved-tension");
    std::fs::write(dir.join("held.toml"), pulled_prototype("0.03", "0.0")).unwrap();
    let out = run(&dir, &["solve", "held.toml"], None);
    exits(&out, 0);
    let err = stderr(&out);
    // Tendons 1 and 3 (opposite it) both at about 3270 N, against EI/r^2 = 66 N.
    for tendon in [1, 3] {
        let head = format!("warning: held.toml: tendon {tendon}: solved tension 32");
        has(&err, &head);
    }
    assert!(
        !err.contains("tendon 2: solved") && !err.contains("tendon 5: solved"),
        "{err}"
    );
    for words in [
        "past the geometric limit EI/r^2 = 66 N",
        "antagonistic",
        "Let the antagonists out",
    ] {
        assert!(err.contains(words), "`{words}` not in {err}");
    }
    // The same pull with every other tendon let out by as much: no such tensions.
    std::fs::write(dir.join("free.toml"), pulled_prototype("0.03", "-0.03")).unwrap();
    let out = run(&dir, &["solve", "free.toml"], None);
    exits(&out, 0);
    assert!(!stderr(&out).contains("solved tension"), "{}", stderr(&out));
    // A tension input past the limit keeps its own warning, not this one.
    std::fs::write(dir.join("pair.toml"), PAIR).unwrap();
    let out = run(
        &dir,
        &["solve", "pair.toml", "--tension", "1=70", "--format", "csv"],
        None,
    );
    assert!(!stderr(&out).contains("solved tension"), "{}", stderr(&out));
}

/// Review item 1 in `sweep`: the warning comes once per tendon, at its first step past the
/// limit, and a last line counts the steps and gives the largest tension.
#[test]
fn a_sweep_warns_about_solved_tensions_once_per_tendon() {
    let dir = scratch("sweep-solved-tension");
    std::fs::write(dir.join("pair.toml"), PAIR).unwrap();
    let args = [
        "sweep",
        "pair.toml",
        "--displacement",
        "1=0:0.03:4",
        "--displacement",
        "2=0",
    ];
    let out = run(&dir, &args, None);
    exits(&out, 0);
    let err = stderr(&out);
    for tendon in [1, 2] {
        let warning = format!("tendon {tendon}: solved tension");
        assert_eq!(err.matches(&warning).count(), 1, "{err}");
        let total = format!(
            "tendon {tendon}: the solved tension was at or past the geometric limit (66 N) in 3 of the 4 steps \
             solved, from step 2; the largest 32"
        );
        has(&err, &total);
    }
    has(&err, "sweep step 2: tendon 1: solved tension");
    // Tendon 2 let out as tendon 1 is pulled in: slack, no warning.
    let args = [
        "sweep",
        "pair.toml",
        "--displacement",
        "1=0:0.03:4",
        "--displacement",
        "2=0:-0.03:4",
    ];
    let out = run(&dir, &args, None);
    exits(&out, 0);
    assert!(!stderr(&out).contains("solved tension"), "{}", stderr(&out));
}

/// Review items 2 and 6: a sweep step that is not a valid robot (a pull-in longer than the
/// tendon's path) is bad input, exit 2 as for `solve`, found before any solve; the message
/// names each tendon's input and prints the path length readably.
#[test]
fn a_sweep_step_with_invalid_input_exits_2() {
    let dir = scratch("sweep-invalid");
    std::fs::write(dir.join("pair.toml"), PAIR).unwrap();
    let out = run(&dir, &["sweep", "pair.toml", "--displacement", "1=0:0.3:4"], None);
    exits(&out, 2);
    let err = stderr(&out);
    assert!(
        err.contains("sweep step 4 of 4 (tendon 1 pull-in 0.3 m, tendon 2 tension 0 N) is not a valid robot"),
        "{err}"
    );
    has(&err, "path is 0.242 m long");
    assert!(!err.contains("0.2419999"), "{err}");
    assert_eq!(stdout(&out), "", "no step is solved");
    // `solve` on the same input: exit 2, the same readable length.
    let out = run(&dir, &["solve", "pair.toml", "--displacement", "1=0.3"], None);
    exits(&out, 2);
    has(&stderr(&out), "path is 0.242 m long");
    // In the file: at its line, the same message.
    let text = PAIR.replacen("tension = 0.0", "displacement = 0.3", 1);
    std::fs::write(dir.join("long.toml"), text).unwrap();
    let out = run(&dir, &["check", "long.toml"], None);
    exits(&out, 2);
    assert!(
        stderr(&out)
            .contains("long.toml:8:1: `tendon[1].displacement` is 0.3 m, but the tendon's path is 0.242 m long"),
        "{}",
        stderr(&out)
    );
}

/// Review items 3 and 8: `--displacement` without a value asks for metres, `--tension` for
/// newtons; a tendon given twice to `solve` is bad input, as in `sweep`.
#[test]
fn solve_option_messages_name_their_units_and_refuse_repeats() {
    let dir = scratch("solve-options");
    std::fs::write(dir.join("pair.toml"), PAIR).unwrap();
    let out = run(&dir, &["solve", "pair.toml", "--displacement", "1"], None);
    exits(&out, 2);
    has(&stderr(&out), "must look like I=METRES, e.g. 1=0.002");
    assert!(!stderr(&out).contains("NEWTONS"), "{}", stderr(&out));
    let out = run(&dir, &["solve", "pair.toml", "--tension", "1"], None);
    exits(&out, 2);
    has(&stderr(&out), "must look like I=NEWTONS, e.g. 1=2.94");
    let out = run(&dir, &["sweep", "pair.toml", "--displacement", "1"], None);
    exits(&out, 2);
    has(&stderr(&out), "I=START:STOP:COUNT or I=METRES");
    for option in ["--displacement", "--tension"] {
        let args = ["solve", "pair.toml", option, "1=0.001", option, "1=0.002"];
        let out = run(&dir, &args, None);
        assert_eq!(out.status.code(), Some(2), "{option}: {}", stderr(&out));
        let message = format!("{option} 1=... is given twice ({option} 1=0.001 and {option} 1=0.002)");
        has(&stderr(&out), &message);
        assert_eq!(stdout(&out), "");
    }
    // Different tendons are fine.
    let out = run(
        &dir,
        &[
            "solve",
            "pair.toml",
            "--displacement",
            "1=0.001",
            "--displacement",
            "2=-0.001",
        ],
        None,
    );
    exits(&out, 0);
}

/// Review item 4: `check` shows a displacement-controlled tendon's pull-in (and an elastic
/// tendon's stiffness and free length) and counts it.
#[test]
fn check_shows_pull_ins_and_elastic_tendons() {
    let dir = scratch("check-displacement");
    let text = PAIR
        .replacen(
            "tension = 0.0",
            "displacement = 0.002\nstiffness = 2000.0\nfree_length = 0.1",
            1,
        )
        .replacen("tension = 0.0", "displacement = -0.002", 1);
    std::fs::write(dir.join("pair.toml"), text).unwrap();
    let out = run(&dir, &["check", "pair.toml"], None);
    exits(&out, 0);
    let text = stdout(&out);
    assert!(
        text.contains("2 tendon(s) (0 pulled by tension, 2 driven by displacement)"),
        "{text}"
    );
    assert!(
        text.contains("tendon 1: straight at (0.008, 0) m, ends at the tip (0.242 m), displacement-controlled, pull-in 0.002 m, elastic: stiffness 2000 N, free length 0.1 m"),
        "{text}"
    );
    has(
        &text,
        "tendon 2: straight at (-0.008, 0) m, ends at the tip (0.242 m), displacement-controlled, pull-in -0.002 m (let out)\n",
    );
    assert!(!text.contains("tension 0 N"), "{text}");
    // Without displacement-controlled tendons the count reads as before.
    let out = run(&dir, &["check", "-"], Some(&example()));
    has(&stdout(&out), "5 tendon(s) (1 pulled), ");
}

/// Review item 5: `free_length` without `stiffness` has no effect (the tendon is
/// inextensible): `check` and `solve` warn, and the solve is that of the tendon without it.
#[test]
fn a_free_length_without_stiffness_is_warned_about() {
    let dir = scratch("free-length");
    let text = PAIR.replacen("tension = 0.0", "displacement = 0.002\nfree_length = 0.1", 1);
    std::fs::write(dir.join("pair.toml"), &text).unwrap();
    let warning = "`tendon[1].free_length` is 0.1 m, but the tendon has no `stiffness`, so it is inextensible \
                   and its free length has no effect";
    let out = run(&dir, &["check", "pair.toml"], None);
    exits(&out, 0);
    has(&stdout(&out), "pair.toml: OK, with 1 warning:");
    has(&stdout(&out), &format!("warning: {warning}"));
    let out = run(&dir, &["solve", "pair.toml", "--format", "csv"], None);
    exits(&out, 0);
    has(&stderr(&out), &format!("warning: pair.toml: {warning}"));
    let with = stdout(&out);
    let plain = PAIR.replacen("tension = 0.0", "displacement = 0.002", 1);
    std::fs::write(dir.join("plain.toml"), plain).unwrap();
    let out = run(&dir, &["solve", "plain.toml", "--format", "csv"], None);
    exits(&out, 0);
    assert!(!stderr(&out).contains("free_length"), "{}", stderr(&out));
    assert_eq!(with, stdout(&out), "the free length changed the solve");
    // With a stiffness it counts, and there is no warning.
    let elastic = text.replacen("free_length = 0.1", "free_length = 0.1\nstiffness = 2000.0", 1);
    std::fs::write(dir.join("elastic.toml"), elastic).unwrap();
    let out = run(&dir, &["check", "elastic.toml"], None);
    assert!(!stdout(&out).contains("warning"), "{}", stdout(&out));
}

/// Review item 7: a tendon with neither `tension` nor `displacement` gets one message that
/// offers both, not also "`tension` is required".
#[test]
fn a_tendon_without_tension_or_displacement_gets_one_message() {
    let dir = scratch("no-actuation");
    let text = PAIR.replacen("tension = 0.0\n", "", 1);
    std::fs::write(dir.join("pair.toml"), text).unwrap();
    let out = run(&dir, &["check", "pair.toml"], None);
    exits(&out, 2);
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(
            "pair.toml:6:1: `tendon[1]` in [[tendon]] #1 has neither `tension` nor `displacement`: give `tension` (N)"
        ),
        "{err}"
    );
    assert!(err.contains("`displacement` (m, the actuator's pull-in"), "{err}");
    assert!(!err.contains("is required"), "{err}");
    // A misspelling of one of them is pointed at.
    let text = PAIR.replacen("tension = 0.0", "tensoin = 0.0", 1);
    std::fs::write(dir.join("typo.toml"), text).unwrap();
    let out = run(&dir, &["check", "typo.toml"], None);
    exits(&out, 2);
    has(&stderr(&out), "(the table has `tensoin`: a misspelling of `tension`?)");
}

/// A sweep over a pull-in that takes up a slack tendon's slack: the step where it goes taut
/// is an event `tendon 1 taut`, not a snap-through warning (the review: the tip's rate
/// changes there because the tendon engages).
#[test]
fn a_sweep_names_the_step_where_a_tendon_goes_taut() {
    let dir = scratch("sweep_taut");
    // The prototype's tendon 1 driven by its pull-in: under the rod's weight it is slack up
    // to about 2.06 mm.
    let text = example().replacen("tension = 2.94", "displacement = 0.0", 1);
    std::fs::write(dir.join("robot.toml"), text).unwrap();
    let out = run(&dir, &["sweep", "robot.toml", "--displacement", "1=0:0.01:6"], None);
    exits(&out, 0);
    assert!(!stderr(&out).contains("snap"), "{}", stderr(&out));
    let csv = stdout(&out);
    let events: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap_or(""))
        .collect();
    let taut: Vec<bool> = events
        .iter()
        .map(|e| e.starts_with("tendon 1 taut at displacement.1 = 0.00205"))
        .collect();
    assert_eq!(taut, [false, false, true, false, false, false], "{csv}");
    assert!(events.iter().filter(|e| !e.is_empty()).count() == 1, "{csv}");
}

/// Issue 27: `--corner-forces` and `--tendons` set what the file's `[model]` table sets,
/// bitwise, and replace it.
#[test]
fn model_flags_equal_the_model_table() {
    let dir = scratch("model");
    // Tendon 1 ends mid-way, tendon 2 goes on at 1 N and a tip force shears the rod: the
    // corner forces of tendon 2 matter.
    let base = edited("# end = 0.242 ", "end = 0.121 #")
        .replace("tip_force = [0.0, 0.0, 0.0]", "tip_force = [0.0, 0.1, -0.05]")
        .replacen("tension = 0.0", "tension = 1.0", 1);
    let tip = |text: &str, flags: &[&str]| {
        let args = [&["solve", "-", "--format", "json"], flags].concat();
        let out = run(&dir, &args, Some(text));
        exits(&out, 0);
        tip_of(&serde_json::from_str(&stdout(&out)).unwrap())
    };
    let with_table = |table: &str| format!("{base}\n[model]\n{table}\n");
    let coupled = tip(&base, &[]);
    let paper = tip(&with_table("corner_forces = false"), &[]);
    assert_ne!(paper, coupled);
    assert_eq!(tip(&base, &["--corner-forces", "false"]), paper);
    // The flag replaces the file's key.
    assert_eq!(
        tip(&with_table("corner_forces = false"), &["--corner-forces", "true"]),
        coupled
    );
    let point_moment = tip(&with_table("tendons = \"point_moment\""), &[]);
    assert_ne!(point_moment, coupled);
    assert_eq!(tip(&base, &["--tendons", "point_moment"]), point_moment);
    let out = run(&dir, &["solve", "robot.toml", "--tendons", "pointmoment"], None);
    exits(&out, 2);
    has(&stderr(&out), "point_moment");
    let kirchhoff = tip(&with_table("rod = \"kirchhoff\""), &[]);
    assert_ne!(kirchhoff, coupled);
    assert_eq!(tip(&base, &["--rod", "kirchhoff"]), kirchhoff);
    assert_eq!(tip(&with_table("rod = \"kirchhoff\""), &["--rod", "cosserat"]), coupled);
    let out = run(&dir, &["solve", "robot.toml", "--rod", "kirchoff"], None);
    exits(&out, 2);
    has(&stderr(&out), "kirchhoff");
}

/// Issue 27: `tdcr compare` prints each model's tip and its distance from the first's and
/// draws the shapes overlaid; `--methods` compares the two solvers the same way.
#[test]
fn compare_prints_and_draws_models_and_methods() {
    let dir = scratch("compare");
    let text = edited("# end = 0.242 ", "end = 0.121 #")
        .replace("tip_force = [0.0, 0.0, 0.0]", "tip_force = [0.0, 0.1, -0.05]")
        .replacen("tension = 0.0", "tension = 1.0", 1);
    std::fs::write(dir.join("robot.toml"), &text).unwrap();
    let out = run(&dir, &["compare", "robot.toml", "--plot", "compare.svg"], None);
    exits(&out, 0);
    let table = stdout(&out);
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .take(5)
        .map(|l| l.split_whitespace().collect())
        .collect();
    let names: Vec<&str> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(
        names,
        [
            "coupled",
            "point_moment",
            "constant_curvature",
            "paper_jumps",
            "kirchhoff"
        ],
        "{table}"
    );
    assert_eq!(rows[0][4..], ["0.000000", "0.000000"], "{table}");
    for row in &rows[1..] {
        assert!(row[4].parse::<f64>().unwrap() > 0.0, "{table}");
    }
    let svg = std::fs::read_to_string(dir.join("compare.svg")).unwrap();
    for name in [
        "coupled (reference)",
        "point_moment: tip",
        "constant_curvature: tip",
        "paper_jumps: tip",
        "kirchhoff: tip",
    ] {
        assert!(svg.contains(name), "{name}");
    }
    let out = run(
        &dir,
        &["compare", "robot.toml", "--methods", "collocation,shooting"],
        None,
    );
    exits(&out, 0);
    let table = stdout(&out);
    let shooting: Vec<&str> = table.lines().nth(2).unwrap().split_whitespace().collect();
    assert_eq!(shooting[0], "shooting", "{table}");
    // 1e-5 mm: the solvers agree to about 1e-8 m at their default tolerances (cross_check.rs)
    assert!(shooting[4].parse::<f64>().unwrap() < 1e-5, "{table}");
    let out = run(&dir, &["compare", "robot.toml", "--models", "coupled,kirchoff"], None);
    exits(&out, 2);
    has(&stderr(&out), "`kirchoff`, which is not a model");
    let out = run(
        &dir,
        &["compare", "robot.toml", "--models", "coupled", "--methods", "shooting"],
        None,
    );
    exits(&out, 2);
}

/// Issue 27: `check` counts a file's disks apart from its point loads and names a model
/// variant other than the default.
#[test]
fn check_names_disks_and_the_model() {
    let dir = scratch("check-model");
    let text = format!(
        "{}\n[disks]\ncount = 12\nmass = 0.001\ngravity = [0.0, 0.0, -9.81]\n[model]\ncorner_forces = false\n",
        example()
    );
    let out = run(&dir, &["check", "-"], Some(&text));
    exits(&out, 0);
    assert!(
        stdout(&out).contains(
            "0 point load(s), 12 disk(s) of 0.00981 N; model: the paper's jump conditions (no corner forces); solver"
        ),
        "{}",
        stdout(&out)
    );
    let text = format!("{}\n[model]\nrod = \"kirchhoff\"\n", example());
    let out = run(&dir, &["check", "-"], Some(&text));
    exits(&out, 0);
    has(
        &stdout(&out),
        "point load(s); rod: Kirchhoff (inextensible, unshearable); solver",
    );
}

/// `--jacobian=COLUMNS` (issue 26): only the columns asked for, named, in the JSON and as a
/// table, equal to the full Jacobian's columns; a bad name is bad input (exit 2).
#[test]
fn jacobian_columns_are_the_full_jacobians_columns() {
    let dir = scratch("jacobian_columns");
    let json = |jacobian: &str| {
        let out = run(&dir, &["solve", "-", "--format", "json", jacobian], Some(&example()));
        exits(&out, 0);
        serde_json::from_str::<serde_json::Value>(&stdout(&out)).unwrap()
    };
    let full = json("--jacobian");
    let some = json("--jacobian=tension,tip_force.z");
    let tip = &some["tip_jacobian"];
    assert!(some.get("jacobian").is_none());
    let columns: Vec<&str> = tip["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    assert_eq!(
        columns,
        [
            "tension.1",
            "tension.2",
            "tension.3",
            "tension.4",
            "tension.5",
            "tip_force.z"
        ]
    );
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let scale = (0..6).fold(0.0f64, |m, row| {
        m.max(number(&full["jacobian"]["tip_force"][row][2]).abs())
    });
    for row in 0..6 {
        for c in 0..5 {
            assert_eq!(tip["rows"][row][c], full["jacobian"]["tension"][row][c]);
        }
        // 1e-10 of the column: the full form takes the tip force's column from the six tip
        // multipliers (transposed solves), the column form from a forward solve; they differ
        // by rounding times the condition number (tests/control_jacobian.rs).
        let (a, b) = (
            number(&tip["rows"][row][5]),
            number(&full["jacobian"]["tip_force"][row][2]),
        );
        assert!((a - b).abs() <= 1e-10 * scale, "row {row}: {a} vs {b}");
    }
    let out = run(&dir, &["solve", "-", "--jacobian=tension"], Some(&example()));
    exits(&out, 0);
    has(&stdout(&out), "tip Jacobian");
    let out = run(&dir, &["solve", "-", "--jacobian=tension.9"], Some(&example()));
    exits(&out, 2);
    has(&stderr(&out), "names tendon 9");
}

/// A tight tolerance returns the order-6 answer, and both the summary line and the JSON say
/// which order the estimate belongs to (docs/cli.md, `error_estimate.order`).
#[test]
fn the_order_of_the_answer_is_reported() {
    let dir = scratch("order6");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let out = run(&dir, &["solve", "robot.toml", "--tol", "1e-10"], None);
    exits(&out, 0);
    let text = stdout(&out);
    assert!(
        text.lines()
            .next()
            .unwrap()
            .contains("order-6 answer, estimated tip error"),
        "{text}"
    );
    for (tol, order) in [("1e-10", 6), ("1e-7", 4)] {
        let out = run(&dir, &["solve", "robot.toml", "--tol", tol, "--format", "json"], None);
        let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(json["error_estimate"]["order"], order, "--tol {tol}");
    }
}

/// `--jacobian=displacement.1` at a pull-in held with friction (docs/friction.md section
/// 3b, "Derivatives at a held pull-in"): the library's column, through the command.
#[test]
fn the_jacobian_holds_a_pull_in_with_friction() {
    let dir = scratch("jacobian_friction");
    std::fs::write(dir.join("robot.toml"), example()).unwrap();
    let args = [
        "solve",
        "robot.toml",
        "--displacement",
        "1=0.0114",
        "--friction",
        "1=0.1",
        "--intervals",
        "48",
        "--format",
        "json",
        "--jacobian=displacement.1,tip_force.z",
    ];
    let out = run(&dir, &args, None);
    exits(&out, 0);
    let json: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    // The robot the command reads (the example file, not `case_s()`: its printed digits
    // differ from the case's in the last bit, which moves where the held loop stops).
    let mut robot = tdcr::io::parse(&example(), "robot.toml").unwrap().robot;
    robot.tendons[0].set_displacement(0.0114);
    robot.tendons[0].friction = Some(tdcr::Friction::pull(0.1));
    let solution = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(48)).unwrap();
    let wrt = [tdcr::Parameter::Displacement(0), tdcr::Parameter::TipForce(2)];
    let want = tdcr::collocation::sensitivity::tip_jacobian(&robot, &solution, &wrt).unwrap();
    for c in 0..2 {
        for row in 0..6 {
            let got = json["tip_jacobian"]["rows"][row][c].as_f64().unwrap();
            // 1e-12 of the column: the same robot, mesh and solves (the JSON prints in full)
            let scale = want.column(c).norm();
            assert!(
                (got - want[(row, c)]).abs() <= 1e-12 * scale,
                "row {row} column {c}: {got} vs {}",
                want[(row, c)]
            );
        }
    }
}
