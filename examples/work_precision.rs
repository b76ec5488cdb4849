//! Work-precision study: tip error against a very fine reference versus solve time, for
//! collocation (several meshes) and shooting (several tolerances), on the prototype's cases
//! S and H.
//!
//! `cargo run --release --example work_precision` prints a Markdown table and writes
//! `out/work_precision.csv` and `out/work_precision.svg` (log-log, one line per solver and case).

use std::fmt::Write as _;
use std::time::{Duration, Instant};
use tdcr::{Robot, Solution, cases, collocation, shooting};

/// Median wall time of `solve` over repeated runs (at least 5, until about 0.3 s).
fn median_time(mut solve: impl FnMut() -> Solution) -> (Duration, Solution) {
    let mut times = Vec::new();
    let start = Instant::now();
    let mut last = None;
    while times.len() < 5 || (start.elapsed() < Duration::from_millis(300) && times.len() < 1000) {
        let t = Instant::now();
        let s = solve();
        times.push(t.elapsed());
        last = Some(s);
    }
    times.sort();
    (times[times.len() / 2], last.expect("at least one run"))
}

struct Point {
    case: &'static str,
    method: &'static str,
    setting: String,
    seconds: f64,
    error: f64,
    iterations: usize,
}

fn study(case: &'static str, robot: &Robot, out: &mut Vec<Point>) {
    // Reference: collocation on 2048 intervals (order 4: error ~1e-14 m on these cases).
    let reference = collocation::solve(robot, &collocation::Options::fixed(2048))
        .expect("reference solve")
        .tip_position();
    for intervals in [4, 8, 16, 32, 64, 128, 256] {
        let options = collocation::Options {
            intervals,
            tolerance: None,
            ..Default::default()
        };
        let (t, s) = median_time(|| collocation::solve(robot, &options).expect("collocation"));
        out.push(Point {
            case,
            method: "collocation",
            setting: format!("{intervals} intervals"),
            seconds: t.as_secs_f64(),
            error: (s.tip_position() - reference).norm(),
            iterations: s.report.iterations,
        });
    }
    for tolerance in [1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
        let options = shooting::Options {
            integration_tolerance: tolerance,
            ..Default::default()
        };
        let Ok(first) = shooting::solve(robot, &options) else {
            continue;
        };
        let (t, s) = median_time(|| shooting::solve(robot, &options).unwrap_or_else(|_| first.clone()));
        out.push(Point {
            case,
            method: "shooting",
            setting: format!("tol {tolerance:.0e}"),
            seconds: t.as_secs_f64(),
            error: (s.tip_position() - reference).norm(),
            iterations: s.report.iterations,
        });
    }
}

fn svg(points: &[Point]) -> String {
    let (w, h, m) = (720.0, 480.0, 70.0);
    let (tmin, tmax) = (1e-5f64.log10(), 1e-0f64.log10());
    let (emin, emax) = (1e-14f64.log10(), 1e-2f64.log10());
    let x = |t: f64| m + (t.log10().clamp(tmin, tmax) - tmin) / (tmax - tmin) * (w - 1.5 * m);
    let y = |e: f64| h - m - (e.max(1e-14).log10().clamp(emin, emax) - emin) / (emax - emin) * (h - 1.5 * m);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    for k in -5..=0 {
        let t = 10f64.powi(k);
        let _ = writeln!(
            s,
            r##"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="#ddd"/><text x="{0}" y="{3}" text-anchor="middle">1e{k} s</text>"##,
            x(t),
            m / 2.0,
            h - m,
            h - m + 18.0
        );
    }
    for k in (-14..=-2).step_by(2) {
        let e = 10f64.powi(k);
        let _ = writeln!(
            s,
            r##"<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="#ddd"/><text x="{3}" y="{1}" text-anchor="end">1e{k} m</text>"##,
            m,
            y(e),
            w - m / 2.0,
            m - 6.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">solve time (median)</text>"#,
        w / 2.0,
        h - 20.0
    );
    let _ = writeln!(
        s,
        r#"<text x="16" y="{}" transform="rotate(-90 16 {})" text-anchor="middle">tip error</text>"#,
        h / 2.0,
        h / 2.0
    );
    let styles = [
        ("collocation", "S", "#1f77b4", ""),
        ("collocation", "H", "#1f77b4", "6,3"),
        ("shooting", "S", "#d62728", ""),
        ("shooting", "H", "#d62728", "6,3"),
    ];
    for (i, (method, case, color, dash)) in styles.iter().enumerate() {
        let pts: Vec<String> = points
            .iter()
            .filter(|p| p.method == *method && p.case == *case)
            .map(|p| format!("{:.1},{:.1}", x(p.seconds), y(p.error)))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="2" stroke-dasharray="{dash}"/>"#,
            pts.join(" ")
        );
        for p in &pts {
            let (px, py) = p.split_once(',').unwrap_or(("0", "0"));
            let _ = writeln!(s, r#"<circle cx="{px}" cy="{py}" r="3" fill="{color}"/>"#);
        }
        let ly = m / 2.0 + 16.0 * i as f64 + 10.0;
        let _ = writeln!(
            s,
            r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2" stroke-dasharray="{dash}"/><text x="{}" y="{}">{method}, case {case}</text>"#,
            w - 230.0,
            w - 200.0,
            w - 194.0,
            ly + 4.0
        );
    }
    s.push_str("</svg>\n");
    s
}

fn main() -> std::io::Result<()> {
    let mut points = Vec::new();
    study("S", &cases::case_s(), &mut points);
    study("H", &cases::case_h(), &mut points);
    println!("| case | method | setting | median solve time | tip error (m) | Newton iterations |");
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut csv = String::from("case,method,setting,median_seconds,tip_error_m,iterations\n");
    for p in &points {
        println!(
            "| {} | {} | {} | {:.3} ms | {:.2e} | {} |",
            p.case,
            p.method,
            p.setting,
            p.seconds * 1e3,
            p.error,
            p.iterations
        );
        let _ = writeln!(
            csv,
            "{},{},{},{:.6e},{:.3e},{}",
            p.case, p.method, p.setting, p.seconds, p.error, p.iterations
        );
    }
    std::fs::create_dir_all("out")?;
    std::fs::write("out/work_precision.csv", csv)?;
    std::fs::write("out/work_precision.svg", svg(&points))?;
    println!("\nwrote out/work_precision.csv and out/work_precision.svg");
    Ok(())
}
