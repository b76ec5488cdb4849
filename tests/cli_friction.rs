//! Friction through the `tdcr` command as a new user meets it (docs/friction.md, issue 24):
//! `--friction` on `sweep` as on `solve`, d(tip)/d(mu) in the JSON's `jacobian`, what
//! `check` says about friction and motion, and bad `--history` lists in the command's words.

mod common;

use common::cli::{example_with, run, stderr, stdout};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    common::cli::scratch("cli-friction", name)
}

/// `tdcr sweep --friction 1=0.1` on a file without friction gives the rows of the same
/// sweep on the file with `friction = 0.1`, as a history and as a plain sweep (before, sweep
/// refused the option, while the history's own message told the user to give it).
#[test]
fn sweep_takes_friction_as_solve_does() {
    let dir = scratch("sweep");
    std::fs::write(dir.join("plain.toml"), example_with(&dir, "stiffness = 2000.0\n")).unwrap();
    std::fs::write(
        dir.join("rough.toml"),
        example_with(&dir, "stiffness = 2000.0\nfriction = 0.1\n"),
    )
    .unwrap();
    for history in [true, false] {
        let mut args = vec!["sweep", "FILE", "--tension", "1=0:4.91:3"];
        if history {
            args.extend(["--history", "up-down"]);
        }
        let csv = |file: &str, extra: &[&str]| {
            let mut a = args.clone();
            a[1] = file;
            a.extend(extra);
            let out = run(&dir, &a);
            assert_eq!(out.status.code(), Some(0), "{a:?}: {}", stderr(&out));
            stdout(&out)
        };
        let by_option = csv("plain.toml", &["--friction", "1=0.1"]);
        let by_file = csv("rough.toml", &[]);
        if history {
            assert!(by_option.starts_with("step,direction,"), "{by_option}");
        } else {
            let frictionless = csv("plain.toml", &[]);
            // The frictionless sweep differs (the tip bends less with friction); the solve
            // times differ between runs, so compare up to the column before them.
            let tips = |csv: &str| {
                csv.lines()
                    .map(|l| l.split(',').take(10).collect::<Vec<_>>().join(","))
                    .collect::<Vec<_>>()
            };
            assert_eq!(tips(&by_option), tips(&by_file));
            assert_ne!(tips(&by_option), tips(&frictionless));
            // The delivered tension, last, as the history's CSV has it: below the input
            // (pulled in, friction takes its share), none without friction.
            let header = by_option.lines().next().unwrap();
            assert!(header.ends_with(",event,delivered_1"), "{header}");
            assert!(frictionless.lines().next().unwrap().ends_with(",event"));
            let last = by_option.lines().last().unwrap();
            let delivered: f64 = last.rsplit(',').next().unwrap().parse().unwrap();
            assert!(delivered > 3.5 && delivered < 4.91, "{last}");
            continue;
        }
        assert_eq!(by_option, by_file);
    }
    // Once per tendon, as for solve.
    let out = run(
        &dir,
        &[
            "sweep",
            "plain.toml",
            "--tension",
            "1=0:1:2",
            "--friction",
            "1=0.1",
            "--friction",
            "1=0.2",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("--friction 1=... is given twice"),
        "{}",
        stderr(&out)
    );
}

/// The full `--jacobian` JSON has `friction`: d(tip pose)/d(mu_i), 6 rows x one column per
/// tendon, the library's `TipSensitivities::friction` (zero for tendons without friction),
/// which a central difference of two solves confirms; the tendon's `delivered_tension`.
#[test]
fn the_json_jacobian_has_the_tip_sensitivity_to_friction() {
    let dir = scratch("jacobian");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "")).unwrap();
    let solve = |mu: f64, jacobian: bool| {
        let friction = format!("1={mu}");
        let mut args = vec![
            "solve",
            "robot.toml",
            "--friction",
            &friction,
            "--intervals",
            "64",
            "--format",
            "json",
        ];
        if jacobian {
            args.push("--jacobian");
        }
        let out = run(&dir, &args);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        serde_json::from_str::<serde_json::Value>(&stdout(&out)).unwrap()
    };
    let json = solve(0.1, true);
    let column = |c: usize| -> Vec<f64> {
        (0..6)
            .map(|r| json["jacobian"]["friction"][r][c].as_f64().unwrap())
            .collect()
    };
    let rows = json["jacobian"]["friction"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    assert!(rows.iter().all(|r| r.as_array().unwrap().len() == 5));
    // The library's column on the same robot and mesh.
    let mut robot = tdcr::io::parse(&example_with(&dir, ""), "robot.toml").unwrap().robot;
    robot.tendons[0].friction = Some(tdcr::Friction::pull(0.1));
    let solution = tdcr::collocation::solve(&robot, &tdcr::collocation::Options::fixed(64)).unwrap();
    // The tendon keeps `tension` (the input at the base entry) and has `delivered_tension`
    // (at its termination), the last of its `tensions` along the path.
    let tendon = &json["tendons"][0];
    assert_eq!(tendon["tension"].as_f64(), Some(2.94));
    let delivered = tendon["delivered_tension"].as_f64().unwrap();
    assert_eq!(delivered, solution.tendons[0].delivered_tension);
    assert!(delivered < 2.94);
    assert_eq!(
        tendon["tensions"].as_array().unwrap().last().unwrap().as_f64(),
        Some(delivered)
    );
    let want = tdcr::tip_sensitivities(&robot, &solution).unwrap().friction;
    let scale = want.column(0).norm();
    assert!(scale > 0.0);
    for (r, got) in column(0).iter().enumerate() {
        // 1e-12 of the column: the same robot, mesh and solve (the JSON prints in full)
        assert!(
            (got - want[(r, 0)]).abs() <= 1e-12 * scale,
            "row {r}: {got} vs {}",
            want[(r, 0)]
        );
    }
    // Tendons without friction: no derivative is taken.
    assert!((1..5).all(|c| column(c).iter().all(|&x| x == 0.0)));
    // Against a central difference of the tip position in mu (step 1e-3).
    let tip =
        |j: &serde_json::Value| -> Vec<f64> { (0..3).map(|i| j["tip"]["position"][i].as_f64().unwrap()).collect() };
    let (up, down) = (tip(&solve(0.101, false)), tip(&solve(0.099, false)));
    let exact = column(0);
    let difference: Vec<f64> = (0..3).map(|i| (up[i] - down[i]) / 0.002).collect();
    let norm = difference.iter().map(|x| x * x).sum::<f64>().sqrt();
    let off = (0..3).map(|i| (exact[i] - difference[i]).powi(2)).sum::<f64>().sqrt();
    // 1e-4 relative: the difference's truncation error at a step of 1e-3 (the column itself
    // is held to 1e-6 against sharper references in tests/sensitivity.rs)
    assert!(off <= 1e-4 * norm, "{exact:?} vs {difference:?}");
}

/// `tdcr check` lists a tendon's friction with its motion, and warns that a `motion` on a
/// tendon without friction has no effect (as a `free_length` without `stiffness`).
#[test]
fn check_says_what_friction_and_motion_do() {
    let dir = scratch("check");
    std::fs::write(
        dir.join("rough.toml"),
        example_with(&dir, "friction = 0.1\nmotion = \"release\"\n"),
    )
    .unwrap();
    let out = run(&dir, &["check", "rough.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let line = text.lines().find(|l| l.contains("tendon 1:")).unwrap();
    assert!(line.ends_with("friction 0.1 (release)"), "{line}");
    assert!(!text.contains("warning"), "{text}");
    std::fs::write(dir.join("moved.toml"), example_with(&dir, "motion = \"release\"\n")).unwrap();
    let out = run(&dir, &["check", "moved.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out) + &stderr(&out);
    assert!(
        text.contains("`tendon[1].motion`") && text.contains("no friction") && text.contains("give `friction`"),
        "{text}"
    );
    // `solve` prints it too, and `--friction` gives the motion its effect.
    let out = run(&dir, &["solve", "moved.toml"]);
    assert!(stderr(&out).contains("`tendon[1].motion`"), "{}", stderr(&out));
    let out = run(&dir, &["solve", "moved.toml", "--friction", "1=0.1"]);
    assert!(!stderr(&out).contains("`tendon[1].motion`"), "{}", stderr(&out));
}

/// An empty `--history`, an empty value in its list, and a negative tension in it are bad
/// input (exit 2) whose message says so in the command's words.
#[test]
fn bad_history_lists_say_what_is_wrong() {
    let dir = scratch("history");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "friction = 0.1\n")).unwrap();
    for (list, says) in [
        ("", "--history is empty"),
        ("0,,2", "value 2 of --history 0,,2 is empty"),
        ("0,-1", "--history lists tension.1 = -1 N, a negative tension"),
    ] {
        let history = format!("--history={list}");
        let out = run(&dir, &["sweep", "robot.toml", "--tension", "1=0", &history]);
        assert_eq!(out.status.code(), Some(2), "{list}");
        let err = stderr(&out);
        assert!(err.contains(says) && !err.contains("tendons[0]"), "{list}: {err}");
    }
}

/// A library message names its field as robot files and Python's messages do
/// (`tendon[1].stiffness`), not by the library's index from 0 (`tendons[0]`).
#[test]
fn library_messages_name_fields_as_robot_files_do() {
    let dir = scratch("field");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "friction = 0.1\n")).unwrap();
    let out = run(
        &dir,
        &["sweep", "robot.toml", "--tension", "1=0:4.91:5", "--history", "up-down"],
    );
    // A stuck rigid tendon is a model limit (exit 4 since front25; 2 before).
    assert_eq!(out.status.code(), Some(4));
    let err = stderr(&out);
    assert!(
        err.contains("`tendon[1].stiffness` is not set (tendon 1 is rigid)") && !err.contains("tendons[0]"),
        "{err}"
    );
    let out = run(
        &dir,
        &["solve", "robot.toml", "--rod", "cosserat", "--tendons", "point_moment"],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("`tendon[1].friction` is 0.1") && !err.contains("tendons[0]"),
        "{err}"
    );
    // A batch row's robot, checked before any solve (user24: `tendons[0].friction`).
    std::fs::write(dir.join("cases.csv"), "friction.1,tension.1\n0.1,2\n-0.1,2\n").unwrap();
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("row 1: invalid input: `tendon[1].friction` is -0.1") && !err.contains("tendons[0]"),
        "{err}"
    );
}

/// The table of `solve` gives the tension along each tendon with friction at every sample
/// (`T1/N`: the input at s = 0, the delivered tension at the termination, falling between
/// while pulled), and no such column without friction.
#[test]
fn the_table_has_the_tension_along_a_tendon_with_friction() {
    let dir = scratch("table");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "")).unwrap();
    let out = run(&dir, &["solve", "robot.toml", "--friction", "1=0.1", "--samples", "5"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let lines: Vec<&str> = text.lines().collect();
    let head = lines.iter().position(|l| l.trim_start().starts_with("s/mm")).unwrap();
    assert!(lines[head].ends_with("T1/N"), "{}", lines[head]);
    let column: Vec<f64> = lines[head + 1..head + 6]
        .iter()
        .map(|l| l.split_whitespace().last().unwrap().parse().unwrap())
        .collect();
    let delivered: f64 = lines
        .iter()
        .find(|l| l.split_whitespace().next() == Some("1"))
        .and_then(|l| l.split_whitespace().nth(2))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(column[0], 2.94);
    assert_eq!(column[4], delivered);
    assert!(column.windows(2).all(|w| w[1] < w[0]), "{column:?}");
    let out = run(&dir, &["solve", "robot.toml", "--samples", "5"]);
    assert!(!stdout(&out).contains("T1/N"));
}

/// `--motion 1=release` gives the answer of `motion = "release"` in the file (the tension
/// rises toward the termination); a bad motion is bad input naming both; without friction
/// it has no effect, and the warning says so.
#[test]
fn motion_on_the_command_line_is_the_files_motion() {
    let dir = scratch("motion");
    std::fs::write(dir.join("pull.toml"), example_with(&dir, "friction = 0.1\n")).unwrap();
    std::fs::write(
        dir.join("release.toml"),
        example_with(&dir, "friction = 0.1\nmotion = \"release\"\n"),
    )
    .unwrap();
    let json = |args: &[&str]| {
        let mut a = vec!["solve"];
        a.extend(args);
        a.extend(["--format", "json"]);
        let out = run(&dir, &a);
        assert_eq!(out.status.code(), Some(0), "{a:?}: {}", stderr(&out));
        let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
        (
            v["tip"]["position"].clone(),
            v["tendons"][0]["delivered_tension"].as_f64().unwrap(),
        )
    };
    let by_option = json(&["pull.toml", "--motion", "1=release"]);
    assert_eq!(by_option, json(&["release.toml"]));
    assert!(by_option.1 > 2.94, "{}", by_option.1);
    assert_eq!(json(&["release.toml", "--motion", "1=pull"]), json(&["pull.toml"]));
    let out = run(&dir, &["solve", "pull.toml", "--motion", "1=up"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("`up` is neither `pull`"), "{}", stderr(&out));
    // The same names and meanings as the experiments file's motion column.
    assert!(stderr(&out).contains("give `pull` (the actuator pulls the tendon in: a loading step) or `release` (it lets it out: an unloading step)"), "{}", stderr(&out));
    // Blanks around the name are trimmed, as in the experiments file.
    assert_eq!(json(&["pull.toml", "--motion", "1= release "]), json(&["release.toml"]));
    // A motion on a tendon without friction changes nothing: the warning names the option
    // (for `pull` too), and no file field the file does not have.
    for motion in ["2=release", "2=pull"] {
        let out = run(&dir, &["solve", "pull.toml", "--motion", motion]);
        assert_eq!(out.status.code(), Some(0));
        let err = stderr(&out);
        let want = format!("warning: --motion {motion} has no effect: tendon 2 has no friction; add --friction 2=MU");
        assert!(err.contains(&want), "{err}");
        assert!(!err.contains("`tendon[2].motion`"), "{err}");
    }
    let out = run(
        &dir,
        &["sweep", "pull.toml", "--tension", "1=0:1:2", "--motion", "2=pull"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("warning: --motion 2=pull has no effect"),
        "{}",
        stderr(&out)
    );
}

/// A load history decides stick and slip per step, so `--motion` would be ignored: bad input.
#[test]
fn history_refuses_motion() {
    let dir = scratch("history_motion");
    std::fs::write(
        dir.join("rough.toml"),
        example_with(&dir, "stiffness = 2000.0\nfriction = 0.1\n"),
    )
    .unwrap();
    let args = [
        "sweep",
        "rough.toml",
        "--tension",
        "1=0:1:2",
        "--history",
        "up-down",
        "--motion",
        "1=release",
    ];
    let out = run(&dir, &args);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(
            "--motion has no effect with --history: each step decides stick and slip from the last step's tendon state"
        ),
        "{}",
        stderr(&out)
    );
}

/// A sweep whose released helical tendon makes the state flutter (the verdict of the
/// linearized dynamics with friction) names the event as a loss of stability, on standard
/// error too, where it said "stable to unknown" and the rows said `unstable`.
#[test]
fn a_sweep_into_flutter_says_it_became_unstable() {
    let dir = scratch("flutter");
    // A 0.3 m nitinol rod, tendon 3 helical (half a turn) with mu = 0.2 (a user's robot).
    std::fs::write(
        dir.join("robot.toml"),
        "[rod]\nlength = 0.3\nouter_radius = 0.0005\nyoungs_modulus = 60e9\npoisson_ratio = 0.33\n\n\
         [[tendon]]\nrouting = { kind = \"straight\", x = 0.006, y = 0.0 }\ntension = 0.0\n\n\
         [[tendon]]\nrouting = { kind = \"helical\", radius = 0.006, turns_per_rod_length = 0.5, phase = 4.1887902047863905 }\n\
         tension = 0.0\nfriction = 0.2\nstiffness = 1500.0\n",
    )
    .unwrap();
    let out = run(
        &dir,
        &["sweep", "robot.toml", "--tension", "2=0:3:16", "--motion", "2=release"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let csv = stdout(&out);
    let unstable = csv.lines().filter(|l| l.contains(",unstable,")).count();
    assert!(unstable > 0, "{csv}");
    assert!(csv.contains("stable to unstable (flutter"), "{csv}");
    assert!(!csv.contains("to unknown"), "{csv}");
    assert!(stderr(&out).contains("warning: sweep step"), "{}", stderr(&out));
}

/// Tendon 2 with friction at 0 N (tendon 1 pulled with friction): its tension column is the
/// first pull's (docs/friction.md section 3, "Sensitivities") in every output of `tdcr
/// solve`: numbers in `--jacobian --format json` (null before), the same bits in
/// `--jacobian=tension --format json`, the same to print precision in the table (exit 2
/// before), and the table prints an exact 0 without a sign (`-0.000000e0` before).
#[test]
fn jacobian_of_an_unloaded_tendon_with_friction_is_the_first_pulls_everywhere() {
    let dir = scratch("first-pull");
    std::fs::write(dir.join("robot.toml"), example_with(&dir, "")).unwrap();
    let base = ["solve", "robot.toml", "--friction", "1=0.1", "--friction", "2=0.1"];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend(extra);
        let out = run(&dir, &a);
        assert_eq!(out.status.code(), Some(0), "{a:?}: {}", stderr(&out));
        stdout(&out)
    };
    let parse = |text: &str| -> serde_json::Value { serde_json::from_str(text).unwrap() };
    let all = parse(&with(&["--jacobian", "--format", "json"]));
    let chosen = parse(&with(&["--jacobian=tension", "--format", "json"]));
    let table = with(&["--jacobian=tension"]);
    assert!(!table.contains("-0.000000e0"), "{table}");
    let printed: Vec<Vec<f64>> = table
        .lines()
        .skip_while(|l| !l.starts_with("tip Jacobian"))
        .skip(2)
        .take(6)
        .map(|l| l.split_whitespace().skip(1).map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(printed.len(), 6, "{table}");
    for row in 0..6 {
        for column in 0..5 {
            let value = all["jacobian"]["tension"][row][column]
                .as_f64()
                .unwrap_or_else(|| panic!("row {row}, column {column}: {}", all["jacobian"]["tension"]));
            assert!(value.is_finite());
            assert_eq!(
                chosen["tip_jacobian"]["rows"][row][column].as_f64(),
                Some(value),
                "row {row}, column {column}"
            );
            // The table's 7 significant digits.
            assert!(
                (printed[row][column] - value).abs() <= 5e-7 * value.abs(),
                "row {row}, column {column}"
            );
        }
    }
    // Tendon 2 (at 90 degrees) bends the tip toward +y: its column is no zero placeholder.
    assert!(all["jacobian"]["tension"][1][1].as_f64().unwrap() > 1e-2);
}
