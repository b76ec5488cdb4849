//! Text reports: solver diagnostics and summaries, the solution table, routing descriptions
//! and number formatting.

use std::fmt::Write as _;
use std::time::Duration;
use tdcr::Iteration;
use tdcr::io::{RobotFile, output};
use tdcr::{Method, PathTaken, Routing, Solution, SolveReport};

/// A duration in milliseconds.
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `x` with `decimals` decimals, right-aligned in `width`, without a minus sign on a
/// value that rounds to zero.
pub fn fixed(x: f64, width: usize, decimals: usize) -> String {
    let scale = 10f64.powi(decimals as i32);
    let x = if (x * scale).round() == 0.0 { 0.0 } else { x };
    format!("{x:>width$.decimals$}")
}

/// The Newton iterations of one run, one row each.
fn history_table(history: &[Iteration]) -> String {
    let mut out = String::from("   iter   residual       step    damping  jacobian\n");
    for (k, it) in history.iter().enumerate() {
        let _ = writeln!(
            out,
            "  {:>5}  {:>9.3e}  {:>9.3e}  {:>9.4}  {}",
            k + 1,
            it.residual,
            it.step,
            it.damping,
            if it.fresh_jacobian { "new" } else { "reused" }
        );
    }
    out
}

/// The iteration counts, each named: "3 Newton + 2 chord steps", with the load steps and
/// meshes when there were more than the direct solve's.
pub fn counts(report: &SolveReport) -> String {
    let mut out = format!("{} Newton", report.newton_steps);
    if report.chord_steps > 0 {
        let _ = write!(out, " + {} chord", report.chord_steps);
    }
    out.push_str(" steps");
    if report.load_steps > 0 {
        let _ = write!(out, " over {} load steps", report.load_steps);
    }
    if report.meshes > 1 {
        let _ = write!(out, " on {} meshes", report.meshes);
    }
    out
}

/// How the answer was reached, when it was not Newton from the guess.
fn path_note(report: &SolveReport) -> String {
    match &report.path {
        PathTaken::Direct => String::new(),
        PathTaken::Fallback => " (the load path could not be followed: Newton's root from the guess, not \
                                necessarily the state reached from rest)"
            .into(),
        PathTaken::LoadPath { folds, bifurcations } | PathTaken::FromWarmStart { folds, bifurcations } => {
            let at = |v: &[f64]| {
                v.iter()
                    .map(|f| format!("{:.1} %", 100.0 * f))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let mut out = String::from(" (followed the load path from rest");
            if !folds.is_empty() {
                let _ = write!(out, "; it SNAPS THROUGH at {} of the way", at(folds));
            }
            if !bifurcations.is_empty() {
                let _ = write!(out, "; it crosses a BIFURCATION at {} of the way", at(bifurcations));
            }
            out.push(')');
            out
        }
    }
}

/// What a solver did, for `-v` and for failures (indented: continuation lines).
pub fn diagnostics(report: &SolveReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "  termination: {}", report.termination);
    let _ = writeln!(
        out,
        "  {} iterations: {} Newton steps (fresh Jacobian) and {} chord steps, over {} load steps on {} mesh(es); final scaled residual {:.3e}",
        report.iterations, report.newton_steps, report.chord_steps, report.load_steps, report.meshes, report.residual
    );
    let _ = writeln!(out, "  equilibrium: {}{}", report.stability, path_note(report));
    let _ = writeln!(
        out,
        "  {} intervals, {} unknowns, {} Jacobian non-zeros{}",
        report.intervals,
        report.unknowns,
        report.nonzeros,
        report.error_estimate.map_or(String::new(), |e| format!(
            "; estimated errors: tip {:.2e} m, {:.2e} rad, backbone {:.2e} m",
            e.tip_position, e.tip_rotation, e.backbone_max
        ))
    );
    let e = &report.evaluations;
    let _ = writeln!(
        out,
        "  evaluations: {} residuals, {} Jacobians, {} of eq. 13",
        e.residual, e.jacobian, e.equations
    );
    let t = &report.timings;
    let _ = writeln!(
        out,
        "  time: assembly {:.2} ms, factorization {:.2} ms, solve {:.2} ms, error estimate {:.2} ms, stability {:.2} ms, total {:.2} ms",
        ms(t.assembly),
        ms(t.factorization),
        ms(t.solve),
        ms(t.estimate),
        ms(t.stability),
        ms(t.total)
    );
    if !report.history.is_empty() {
        let _ = writeln!(out, "  last Newton run (scaled max-norms):");
        out.push_str(&history_table(&report.history));
    }
    out
}

/// One line about a solve: method, mesh, iterations, time, and the estimated tip error
/// against the tolerance (collocation on a rod of length `length`, m).
pub fn summary(report: &SolveReport, length: f64) -> String {
    let head = format!(
        "{} on {} {}: {}, {:.2} ms; {}{}",
        report.method,
        report.intervals,
        if report.method == Method::Shooting {
            "integration steps"
        } else if report.tolerance.is_some() {
            "intervals (error-controlled)"
        } else {
            "intervals (fixed mesh)"
        },
        counts(report),
        ms(report.timings.total),
        report.stability,
        path_note(report)
    );
    let accuracy = match (report.method, report.error_estimate, report.tolerance) {
        (Method::Shooting, ..) => "tip error not estimated (shooting controls its local integration error)".to_string(),
        (_, None, _) => "no error estimate: the Jacobian is singular at the solution".to_string(),
        (_, Some(e), None) => format!(
            "estimated tip error {:.1e} m, {:.1e} rad (no tolerance)",
            e.tip_position, e.tip_rotation
        ),
        (_, Some(e), Some(t)) => format!(
            "estimated tip error {:.1e} m, {:.1e} rad against tolerance {:.1e} m, {t:.1e} rad ({})",
            e.tip_position,
            e.tip_rotation,
            t * length,
            if report.tolerance_met == Some(true) {
                "met"
            } else {
                "NOT met"
            }
        ),
    };
    // Tight tolerances return the deferred-corrected answer (docs/numerics.md, "The order-6
    // answer"): the line says so, since its estimate comes from another residual.
    match report.error_estimate {
        Some(e) if e.order != 4 => format!("{head}; order-{} answer, {accuracy}", e.order),
        _ => format!("{head}; {accuracy}"),
    }
}

/// The table of `tdcr solve`: the summary, the tip pose, the tendons, and one row per
/// sample, with the tension along each tendon with friction.
pub fn solution_table(name: &str, file: &RobotFile, solution: &Solution, samples: &[output::Sample]) -> String {
    let tip = solution.tip();
    let tangent = tip.R.column(2);
    let mut out = String::new();
    let _ = writeln!(out, "{name}: {}", summary(&solution.report, file.robot.length()));
    let row = |v: [f64; 3], w: usize, d: usize| v.map(|x| fixed(x, w, d)).join(" ");
    let _ = writeln!(out, "tip position (mm):     {}", row((tip.p * 1e3).into(), 10, 4));
    let _ = writeln!(
        out,
        "tip tangent R(L) e3:   {}",
        row(tangent.into_owned().into(), 10, 6)
    );
    let _ = writeln!(
        out,
        "bending angle (deg):   {}",
        fixed(output::bending_angle(solution).to_degrees(), 10, 4)
    );
    // With friction, the tension a tendon delivers at its termination (docs/friction.md).
    let friction = solution.tendons.iter().any(|t| t.delivered_tension != t.tension);
    // No tendons: no tendon table (an empty header says nothing).
    if !solution.tendons.is_empty() {
        let _ = writeln!(
            out,
            "\n{:>7} {:>12}{} {:>12} {:>12} {:>12} {:>9}",
            "tendon",
            "tension/N",
            if friction {
                format!(" {:>12}", "delivered/N")
            } else {
                String::new()
            },
            "pull-in/mm",
            "length/mm",
            "ref len/mm",
            "slack/mm"
        );
    }
    for (i, t) in solution.tendons.iter().enumerate() {
        let _ = writeln!(
            out,
            "{:>7} {}{} {} {} {} {}",
            i + 1,
            fixed(t.tension, 12, 5),
            if friction {
                format!(" {}", fixed(t.delivered_tension, 12, 5))
            } else {
                String::new()
            },
            fixed(t.displacement * 1e3, 12, 5),
            fixed(t.length * 1e3, 12, 4),
            fixed(t.reference_length * 1e3, 12, 4),
            fixed(t.slack * 1e3, 9, 4)
        );
    }
    // With friction, the tension along each tendon with friction at every sample, up to
    // its end (`Solution::tension_at`; docs/friction.md).
    let varying = tdcr::io::output::friction_tendons(&file.robot);
    let heads: String = varying
        .iter()
        .map(|i| format!(" {:>10}", format!("T{}/N", i + 1)))
        .collect();
    let _ = writeln!(
        out,
        "\n{:>9} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}{heads}",
        "s/mm", "x/mm", "y/mm", "z/mm", "nx/N", "ny/N", "nz/N", "mx/N mm", "my/N mm", "mz/N mm"
    );
    for x in samples {
        let tensions: String = varying
            .iter()
            .map(
                |&i| match tdcr::io::output::tension_at_sample(&file.robot, solution, i, x.s) {
                    Some(t) => format!(" {}", fixed(t, 10, 5)),
                    None => format!(" {:>10}", ""),
                },
            )
            .collect();
        let _ = writeln!(
            out,
            "{} {} {} {}{}",
            fixed(x.s * 1e3, 9, 3),
            row((x.p * 1e3).into(), 10, 4),
            row(x.n.into(), 10, 5),
            row((x.m * 1e3).into(), 10, 4),
            tensions.trim_end()
        );
    }
    out
}

/// A routing in a few words (`straight (8, 0) mm`, `helix, 1 turn, 8 mm`).
pub fn describe(routing: &Routing) -> String {
    match routing {
        Routing::Straight { x, y } => format!("straight ({:.3}, {:.3}) mm", x * 1e3, y * 1e3)
            .replace(".000", "")
            .replace("-0)", "0)"),
        Routing::Helical { radius, turns, .. } => {
            let plural = if turns.abs() == 1.0 { "" } else { "s" };
            format!("helix, {turns} turn{plural}, {:.3} mm", radius * 1e3).replace(".000", "")
        }
        Routing::Custom(_) => "custom routing".into(),
    }
}
