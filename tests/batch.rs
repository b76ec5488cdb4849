//! `tdcr batch`, run as a built binary: results against `tdcr solve`, input order, shards
//! that add up to the unsharded run exactly, JSON lines, bad input with file:line:column and
//! exit code 2, failed rows with exit code 3.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const TDCR: &str = env!("CARGO_BIN_EXE_tdcr");

/// A fresh scratch folder holding the example robot file.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tdcr-batch-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("robot.toml"), tdcr::io::example()).unwrap();
    dir
}

fn run(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(TDCR).args(args).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    out
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `rows` rows of four tensions in [0, 3] N from a fixed linear congruential sequence.
fn tensions(rows: usize) -> Vec<[f64; 4]> {
    let mut state: u64 = 12345;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 * 3000.0).round() / 1000.0
    };
    (0..rows).map(|_| [next(), next(), next(), next()]).collect()
}

fn write_csv(dir: &Path, rows: &[[f64; 4]]) {
    let mut csv = String::from("tension.1,tension.2,tension.3,tension.4\n");
    for r in rows {
        csv.push_str(&format!("{},{},{},{}\n", r[0], r[1], r[2], r[3]));
    }
    std::fs::write(dir.join("cases.csv"), csv).unwrap();
}

#[test]
fn rows_come_back_in_order_with_the_tips_of_solve() {
    let dir = scratch("order");
    let rows = tensions(5);
    write_csv(&dir, &rows);
    let out = run(
        &dir,
        &["batch", "cases.csv", "--robot", "robot.toml", "--out", "results.csv"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let results = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let lines: Vec<&str> = results.lines().collect();
    assert_eq!(
        lines[0],
        "row,tension.1,tension.2,tension.3,tension.4,converged,iterations,tip_x,tip_y,tip_z,error"
    );
    assert_eq!(lines.len(), 6);
    for (k, (line, r)) in lines[1..].iter().zip(&rows).enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[0], k.to_string());
        assert_eq!(cells[5], "true");
        let mut args = vec![
            "solve".to_string(),
            "robot.toml".into(),
            "--format".into(),
            "json".into(),
        ];
        for (i, t) in r.iter().enumerate() {
            args.push("--tension".into());
            args.push(format!("{}={t}", i + 1));
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let solved: serde_json::Value = serde_json::from_str(&text(&run(&dir, &args).stdout)).unwrap();
        for axis in 0..3 {
            let alone = solved["tip"]["position"][axis].as_f64().unwrap();
            let batch: f64 = cells[7 + axis].parse().unwrap();
            // Exact: every row is solved cold, as `tdcr solve` solves it, and both files
            // write numbers that read back to the same f64.
            assert_eq!(batch, alone, "row {k}");
        }
    }
}

/// 300 random rows of four tensions and a tip force: every row's tip, iterations,
/// stability and error estimate are those of the library's `tdcr::solve` of that row
/// alone, exactly, on both threads; Python's `solve_parameters` runs the same solves
/// (python/tests/test_dataset.py checks it against `tdcr batch`).
#[test]
fn a_few_hundred_random_rows_give_each_row_its_own_solve_exactly() {
    let dir = scratch("random");
    let rows = tensions(300);
    let mut csv = String::from("tension.1,tension.2,tension.3,tension.4,tip_force.x\n");
    for (k, r) in rows.iter().enumerate() {
        let force = 0.001 * ((k * 37) % 200) as f64 - 0.1;
        csv.push_str(&format!("{},{},{},{},{force}\n", r[0], r[1], r[2], r[3]));
    }
    std::fs::write(dir.join("cases.csv"), csv).unwrap();
    let out = run(
        &dir,
        &[
            "batch",
            "cases.csv",
            "--robot",
            "robot.toml",
            "--stability",
            "--error-estimate",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let file = tdcr::io::parse(&tdcr::io::example(), "robot.toml").unwrap();
    let table =
        tdcr::io::parameters::read("cases.csv", &std::fs::read_to_string(dir.join("cases.csv")).unwrap()).unwrap();
    let results = text(&out.stdout);
    assert_eq!(results.lines().count(), 301);
    for (k, line) in results.lines().skip(1).enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let robot = table.robot(&table.row(k), &file.robot).unwrap();
        let alone = tdcr::solve(&robot, &file.solver.collocation).unwrap();
        assert_eq!(cells[0], k.to_string());
        assert_eq!(cells[7], alone.report.iterations.to_string(), "row {k}");
        let tip: Vec<f64> = cells[8..11].iter().map(|c| c.parse().unwrap()).collect();
        // Exact: the same cold solve, written in a format that reads back bitwise.
        assert_eq!(tip, alone.tip_position().iter().copied().collect::<Vec<_>>(), "row {k}");
        assert_eq!(cells[11], alone.report.stability.verdict(), "row {k}");
        let estimate = tdcr::io::row_outputs::tip_error_estimate(&alone);
        assert_eq!(cells[12].parse::<f64>().unwrap(), estimate, "row {k}");
    }
}

#[test]
fn shards_add_up_to_the_unsharded_run_and_json_lines_read_the_same() {
    let dir = scratch("shards");
    let rows = tensions(150);
    write_csv(&dir, &rows);
    let solve = |extra: &[&str]| {
        let mut args = vec!["batch", "cases.csv", "--robot", "robot.toml", "--intervals", "8"];
        args.extend_from_slice(extra);
        let out = run(&dir, &args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    let all = solve(&[]);
    let mut joined = String::new();
    for k in 0..3 {
        let shard = solve(&["--shard", &format!("{k}/3")]);
        let body = if k == 0 {
            &shard[..]
        } else {
            &shard[shard.find('\n').unwrap() + 1..]
        };
        joined.push_str(body);
    }
    assert_eq!(joined, all);
    assert_eq!(all.lines().count(), 151);
    let mut jsonl = String::new();
    for r in &rows {
        jsonl.push_str(&format!(
            "{{\"tension.1\": {}, \"tension.2\": {}, \"tension.3\": {}, \"tension.4\": {}}}\n",
            r[0], r[1], r[2], r[3]
        ));
    }
    std::fs::write(dir.join("cases.jsonl"), jsonl).unwrap();
    let out = run(
        &dir,
        &["batch", "cases.jsonl", "--robot", "robot.toml", "--intervals", "8"],
    );
    assert_eq!(text(&out.stdout), all);
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml", "--shard", "3/3"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("K/N"), "{}", text(&out.stderr));
    // 150 rows are 3 blocks: of 4 shards the first three hold one block each (K B / N <= b <
    // (K+1) B / N, as docs/cli.md says; user25: shard 0/4, the docs' "first of 4 parts", was
    // the empty one) and the last is empty, and says why (user24: an empty shard wrote only a
    // header, with no word).
    let out = run(
        &dir,
        &[
            "batch",
            "cases.csv",
            "--robot",
            "robot.toml",
            "--shard",
            "0/4",
            "--intervals",
            "8",
        ],
    );
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(
        text(&out.stdout),
        all.lines().take(65).map(|l| format!("{l}\n")).collect::<String>()
    );
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml", "--shard", "3/4"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(text(&out.stdout).lines().count(), 1);
    assert!(
        text(&out.stderr).contains("shard 3/4 holds none of the 150 rows: shards are made of whole blocks of 64 rows"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn bad_tables_name_file_line_and_column_and_exit_2() {
    let dir = scratch("bad");
    for (name, table, expected) in [
        (
            "a.csv",
            "tension.1, mass\n1,2\n",
            "a.csv:1:12: unknown parameter `mass`",
        ),
        (
            "b.csv",
            "tension.1,tip_force.z\n1,0\n2,heavy\n",
            "b.csv:3:3: `tip_force.z` value `heavy` is not a number",
        ),
        (
            "c.csv",
            "tension.1\n-1\n",
            "c.csv:2:1: `tension.1` is -1 N, but a tendon can only pull",
        ),
        (
            "d.csv",
            "tension.1,tension.2\n1\n",
            "d.csv:2:1: has 1 fields, but the header names 2 parameters",
        ),
        (
            "e.csv",
            "tension.9\n1\n",
            "e.csv:2:1: row 0: invalid input: `tension.9` names tendon 9, but the robot has 5",
        ),
        (
            "f.jsonl",
            "{\"tension.1\": 1}\n{\"tension.1\": 1, \"tip_mass\": 2}\n",
            "f.jsonl:2:18: unknown parameter `tip_mass`",
        ),
        (
            "g.jsonl",
            "{\"tension.1\": 1\n",
            "g.jsonl:1:15: is not a JSON object of parameters",
        ),
    ] {
        std::fs::write(dir.join(name), table).unwrap();
        let out = run(&dir, &["batch", name, "--robot", "robot.toml"]);
        assert_eq!(out.status.code(), Some(2), "{name}");
        let err = text(&out.stderr);
        assert!(err.starts_with(&format!("error: {expected}")), "{name}: {err}");
    }
}

#[test]
fn failed_rows_keep_their_place_and_exit_3() {
    let dir = scratch("failed");
    let robot = tdcr::io::example().replace(
        "intervals = 32",
        "intervals = 32\nmax_iterations = 1\ncontinuation = false",
    );
    std::fs::write(dir.join("robot.toml"), robot).unwrap();
    std::fs::write(dir.join("cases.csv"), "tension.1\n0\n4.9\n").unwrap();
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml"]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let results = text(&out.stdout);
    let failed: Vec<&str> = results.lines().filter(|l| l.contains(",false,")).collect();
    assert!(!failed.is_empty(), "{results}");
    assert!(failed.iter().all(|l| l.contains("did not converge")), "{results}");
    assert!(text(&out.stderr).contains("rows did not solve"));
}

/// A `tension.1` column sets tendon 1's tension and makes it tension-controlled, also when
/// the robot file drives it by a pull-in (issue 23: the column used to set only the
/// starting guess of the displacement-controlled tendon's tension): each row's tip is the
/// tip of `tdcr solve` on the file with that tension, and not the tip of the pull-in.
#[test]
fn a_tension_column_makes_a_displacement_controlled_tendon_tension_controlled() {
    let dir = scratch("tension_column");
    let pulled = tdcr::io::example().replacen("tension = 2.94 ", "displacement = 0.002 ", 1);
    assert_ne!(pulled, tdcr::io::example(), "the example's first tendon is at 2.94 N");
    std::fs::write(dir.join("pulled.toml"), pulled).unwrap();
    std::fs::write(dir.join("cases.csv"), "tension.1\n1.0\n2.5\n").unwrap();
    let out = run(&dir, &["batch", "cases.csv", "--robot", "pulled.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let tip = |args: &[&str]| -> Vec<f64> {
        let out = run(&dir, args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let json: serde_json::Value = serde_json::from_str(&text(&out.stdout)).unwrap();
        (0..3).map(|k| json["tip"]["position"][k].as_f64().unwrap()).collect()
    };
    let held = tip(&["solve", "pulled.toml", "--format", "json"]);
    let results = text(&out.stdout);
    for (line, tension) in results.lines().skip(1).zip(["1", "2.5"]) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[2], "true", "{line}");
        let batch: Vec<f64> = cells[4..7].iter().map(|c| c.parse().unwrap()).collect();
        let solved = tip(&[
            "solve",
            "robot.toml",
            "--format",
            "json",
            "--tension",
            &format!("1={tension}"),
        ]);
        for k in 0..3 {
            // 1e-8 m: both solves stop at the scaled residual 1e-11 from different starts,
            // which leaves the tip about 1e-8 m from the exact discrete solution.
            assert!(
                (batch[k] - solved[k]).abs() < 1e-8,
                "{tension} N: {batch:?} vs {solved:?}"
            );
        }
        // The pull-in's tip is millimetres away: the column did change the actuation.
        assert!(
            (batch[2] - held[2]).abs() > 1e-4,
            "{tension} N: {batch:?} vs the pull-in's {held:?}"
        );
    }
}

#[test]
fn optional_columns_carry_the_quaternion_stability_estimate_and_points() {
    let dir = scratch("columns");
    write_csv(&dir, &tensions(3));
    let out = run(
        &dir,
        &[
            "batch",
            "cases.csv",
            "--robot",
            "robot.toml",
            "--orientation",
            "--stability",
            "--error-estimate",
            "--points",
            "3",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let results = text(&out.stdout);
    let lines: Vec<&str> = results.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let extra = [
        "q_w",
        "q_x",
        "q_y",
        "q_z",
        "stability",
        "error_estimate",
        "p1_x",
        "p1_y",
        "p1_z",
        "p2_x",
        "p2_y",
        "p2_z",
        "p3_x",
        "p3_y",
        "p3_z",
    ];
    assert_eq!(&header[10..25], &extra);
    assert_eq!(header[25], "error");
    for line in &lines[1..] {
        let cells: Vec<&str> = line.split(',').collect();
        let q: Vec<f64> = cells[10..14].iter().map(|c| c.parse().unwrap()).collect();
        // 1e-12: a unit quaternion written with the CSV's round-trip number format
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12 && q[0] >= 0.0);
        assert_eq!(cells[14], "stable");
        assert!(cells[15].parse::<f64>().unwrap() > 0.0);
        // The last point is the tip, the first the base (at the origin in the example).
        assert_eq!(&cells[22..25], &cells[7..10]);
        for c in &cells[16..19] {
            assert!(c.parse::<f64>().unwrap().abs() < 1e-12);
        }
    }
    let out = run(&dir, &["batch", "cases.csv", "--robot", "robot.toml", "--points", "1"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("at least 2"), "{}", text(&out.stderr));
}

#[test]
fn tendons_with_friction_get_their_delivered_tension_as_solve_gives_it() {
    // Tendon 1 has friction from --friction, tendon 3 from a `friction.3` column (0 in one
    // row: that row delivers its tension); tendons 2 and 4 have none and get no column.
    let dir = scratch("delivered");
    std::fs::write(
        dir.join("cases.csv"),
        "tension.1,tension.3,friction.3\n2.0,1.5,0.2\n1.0,2.5,0.0\n",
    )
    .unwrap();
    let out = run(
        &dir,
        &["batch", "cases.csv", "--robot", "robot.toml", "--friction", "1=0.1"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let results = text(&out.stdout);
    let lines: Vec<&str> = results.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(&header[9..], &["delivered_1", "delivered_3", "error"]);
    for (line, (t1, t3, mu3)) in lines[1..].iter().zip([("2.0", "1.5", "0.2"), ("1.0", "2.5", "0.0")]) {
        let cells: Vec<&str> = line.split(',').collect();
        let solved = run(
            &dir,
            &[
                "solve",
                "robot.toml",
                "--friction",
                "1=0.1",
                "--friction",
                &format!("3={mu3}"),
                "--tension",
                &format!("1={t1}"),
                "--tension",
                &format!("3={t3}"),
                "--format",
                "json",
            ],
        );
        assert_eq!(solved.status.code(), Some(0), "{}", text(&solved.stderr));
        let json: serde_json::Value = serde_json::from_slice(&solved.stdout).unwrap();
        let delivered = |i: usize| json["tendons"][i]["delivered_tension"].as_f64().unwrap();
        // Exact: one computation (each row solved as `tdcr solve` solves it), written in a
        // format that reads back bitwise.
        assert_eq!(cells[9].parse::<f64>().unwrap(), delivered(0), "{line}");
        assert_eq!(cells[10].parse::<f64>().unwrap(), delivered(2), "{line}");
        // Friction holds tendon 1 back (pulled in); a coefficient of 0 delivers the tension.
        assert!(delivered(0) < t1.parse::<f64>().unwrap());
        if mu3 == "0.0" {
            assert_eq!(cells[10].parse::<f64>().unwrap(), t3.parse::<f64>().unwrap());
        }
    }
}
