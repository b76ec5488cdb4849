//! The main job (`tdcr` without a command): the paper's prototype under the 32 experiments of
//! Table 2, a table on standard output, a picture and a CSV in the output folder.

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};
use tdcr::io::output;
use tdcr::plot::{Figure, LegendEntry, PALETTE, Style};
use tdcr::{cases, collocation};

use crate::failure::{Failure, emit, write_file};
use crate::tables::{describe, fixed, ms};

/// Styles of the main job's picture: colour by tendon, dash by tip load.
fn table2_style(e: &cases::Experiment) -> Style {
    let color = e.tendon.map_or("#000000", |i| PALETTE[(i - 1) % PALETTE.len()]);
    let mut style = Style::new(color);
    style.dash = if e.tip_load == 0.0 {
        None
    } else if e.tip_load < 0.15 {
        Some("7 3".into())
    } else {
        Some("2 2".into())
    };
    style
}

/// Solves the 32 experiments, prints their table and writes `table2.svg` and `table2.csv` into
/// `out_dir`.
pub fn run(out_dir: &Path) -> Result<(), Failure> {
    let start = Instant::now();
    let experiments = cases::table2();
    let options = collocation::Options::default();
    let routings = cases::prototype_routings();
    emit(&format!(
        "The prototype of Rucker & Webster (2011, section 5) under the {} experiments of Table 2\n\
         collocation at the default settings (tip error estimated and held below {:.0e} L); tip in mm, world frame\n\n",
        experiments.len(),
        options.tolerance.unwrap_or(f64::NAN)
    ))?;
    let header = format!(
        "{:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>5} {:>7}\n\
         {:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>5} {:>7}\n",
        "#",
        "configuration",
        "tendon",
        "tension",
        "tip load",
        "tip x",
        "tip y",
        "tip z",
        "bend",
        "iters",
        "time",
        "",
        "",
        "",
        "N",
        "N",
        "mm",
        "mm",
        "mm",
        "deg",
        "",
        "ms"
    );
    emit(&header)?;
    let mut csv = String::from(
        "experiment,configuration,tendon,tension,tip_load,tip_x,tip_y,tip_z,bending_angle_deg,iterations,intervals,solve_time\n",
    );
    let mut figure = Figure::new("The prototype under the 32 experiments of Table 2 (Rucker & Webster 2011)");
    let mut failures = Vec::new();
    let mut solver_time = Duration::ZERO;
    let mut intervals = Vec::new();
    for (k, e) in experiments.iter().enumerate() {
        let robot = e.robot();
        let tendon = e
            .tendon
            .map_or("-".to_string(), |i| format!("{i}: {}", describe(&routings[i - 1])));
        let row = match collocation::solve(&robot, &options) {
            Ok(solution) => {
                let tip = solution.tip_position();
                let bend = output::bending_angle(&solution).to_degrees();
                let report = &solution.report;
                solver_time += report.timings.total;
                intervals.push(report.intervals);
                let _ = writeln!(
                    csv,
                    "{},\"{}\",{},{},{},{},{},{},{},{},{},{}",
                    k + 1,
                    e.label(),
                    e.tendon.map_or(String::new(), |i| i.to_string()),
                    e.tension,
                    e.tip_load,
                    output::number(tip.x),
                    output::number(tip.y),
                    output::number(tip.z),
                    bend,
                    report.iterations,
                    report.intervals,
                    report.timings.total.as_secs_f64()
                );
                let line = format!(
                    "{:>3}  {:<24} {:<27} {:>7.2} {:>8.3} {} {} {} {:>7.2} {:>5} {:>7.1}\n",
                    k + 1,
                    e.label(),
                    tendon,
                    e.tension,
                    e.tip_load,
                    fixed(tip.x * 1e3, 9, 2),
                    fixed(tip.y * 1e3, 9, 2),
                    fixed(tip.z * 1e3, 9, 2),
                    bend,
                    report.iterations,
                    ms(report.timings.total)
                );
                figure.add_shape(&robot, &solution, &table2_style(e));
                line
            }
            Err(err) => {
                failures.push(format!("experiment {} ({}): {err}", k + 1, e.label()));
                format!(
                    "{:>3}  {:<24} {:<27} {:>7.2} {:>8.3}  did not solve: {err}\n",
                    k + 1,
                    e.label(),
                    tendon,
                    e.tension,
                    e.tip_load
                )
            }
        };
        emit(&row)?;
    }
    intervals.sort_unstable();
    intervals.dedup();
    let mesh = match intervals.as_slice() {
        [n] => format!("{n} intervals each"),
        _ => format!("{:?} intervals", intervals),
    };
    emit(&format!(
        "\n{} of {} solved ({mesh}); solver time {:.0} ms, wall time {:.0} ms\n",
        experiments.len() - failures.len(),
        experiments.len(),
        ms(solver_time),
        ms(start.elapsed())
    ))?;

    figure.subtitle.push(format!(
        "collocation, {mesh}; colour: the tendon pulled (0.98 to 6.87 N); dash: the tip load"
    ));
    figure.legend.push(LegendEntry {
        label: "no tension".into(),
        color: "#000000".into(),
        dash: None,
    });
    for (i, routing) in routings.iter().enumerate() {
        figure.legend.push(LegendEntry {
            label: format!("tendon {}: {}", i + 1, describe(routing)),
            color: PALETTE[i].into(),
            dash: None,
        });
    }
    for (label, dash) in [
        ("no tip load", None),
        ("0.098 N tip load (10 g)", Some("7 3")),
        ("0.196 N tip load (20 g)", Some("2 2")),
    ] {
        figure.legend.push(LegendEntry {
            label: label.into(),
            color: "#666666".into(),
            dash: dash.map(Into::into),
        });
    }
    let svg_path = out_dir.join("table2.svg");
    let csv_path = out_dir.join("table2.csv");
    write_file(&svg_path, &figure.to_svg(), "picture")?;
    write_file(&csv_path, &csv, "table")?;
    emit(&format!(
        "picture of all shapes: {}\ntable as CSV (SI units): {}\n",
        svg_path.display(),
        csv_path.display()
    ))?;
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Failure::NotConverged(failures.join("\n")))
    }
}
