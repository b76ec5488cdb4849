//! The main job (`tdcr` without a command): the paper's prototype under the 32 experiments of
//! Table 2, a table on standard output, a picture (SVG and PNG) and a CSV in the output folder.

use std::path::Path;
use std::time::{Duration, Instant};
use tdcr::Routing;
use tdcr::analysis::comparison::{Variant, constant_curvature};
use tdcr::io::csv_table::CsvTable;
use tdcr::io::{number, output};
use tdcr::plot::{FORCE_COLOR, Figure, Format, LegendEntry, Style, Symbol, View, routing_label};
use tdcr::{cases, collocation};

use crate::failure::{Failure, emit, note, write_file};
use crate::tables::{describe, fixed, ms};

/// Spacer disks of the paper's prototype, drawn on every shape of the main job's picture.
const PROTOTYPE_DISKS: usize = 12;

/// The tensions of Table 2 (N) and their colours in the main job's picture: Okabe-Ito
/// colours, distinct for colour-blind readers and apart from the tip-load arrows' wine.
const TENSION_COLORS: [(f64, &str); 5] = [
    (0.98, "#E69F00"),
    (1.96, "#56B4E9"),
    (2.94, "#009E73"),
    (4.91, "#D55E00"),
    (6.87, "#0072B2"),
];

/// Tip loads of Table 2 (N), their dash patterns and legend labels.
const TIP_LOAD_DASHES: [(f64, Option<&str>, &str); 3] = [
    (0.0, None, "no tip load"),
    (0.098, Some("7 3"), "0.098 N tip load (10 g)"),
    (0.196, Some("2 2"), "0.196 N tip load (20 g)"),
];

/// Styles of the main job's picture: colour by tension, dash by tip load, the prototype's
/// disks, arrows for the tip loads; self weight is said in the subtitle, not drawn.
fn table2_style(e: &cases::Experiment) -> Style {
    let color = match e.tendon {
        None => "#000000",
        Some(_) => TENSION_COLORS
            .iter()
            .find(|(t, _)| (t - e.tension).abs() < 1e-9)
            .map_or("#000000", |(_, c)| c),
    };
    let mut style = Style::new(color);
    style.dash = TIP_LOAD_DASHES
        .iter()
        .find(|(load, _, _)| (load - e.tip_load).abs() < 1e-9)
        .and_then(|(_, dash, _)| dash.map(Into::into));
    style.disks = Some(if e.tendon.is_none() { 0 } else { PROTOTYPE_DISKS });
    style.distributed_load = false;
    style
}

/// The main job's picture: small multiples, a column per tendon with the experiments that pull
/// it, the unloaded prototype in every column for reference.
fn picture(solved: &[(cases::Experiment, tdcr::Robot, tdcr::Solution)], routings: &[Routing], mesh: &str) -> Figure {
    let mut figure = Figure::new("The prototype under the 32 experiments of Table 2 (Rucker & Webster 2011)");
    figure.subtitle.push(format!(
        "collocation, {mesh}. A column per tendon pulled; colour: its tension; dash: the tip load (arrows); \
         the unloaded prototype in black in every column; self weight 0.47 N/m along -z on every shape (not drawn)"
    ));
    let length = cases::LENGTH;
    for (i, routing) in routings.iter().enumerate() {
        let tendon = tdcr::Tendon::new(routing.clone(), 0.0);
        figure.add_panel(&format!("tendon {}: {}", i + 1, routing_label(&tendon, length)));
        for (e, robot, solution) in solved {
            if e.tendon.is_none_or(|t| t == i + 1) {
                figure.add_shape(robot, solution, &table2_style(e));
            }
        }
    }
    figure
        .legend
        .push(LegendEntry::line("no tension (experiment 1)", "#000000"));
    for (tension, color) in TENSION_COLORS {
        let only = if tension == 6.87 { " (tendon 5 only)" } else { "" };
        figure
            .legend
            .push(LegendEntry::line(&format!("tendon pulled at {tension} N{only}"), color));
    }
    figure
        .legend
        .extend(tip_load_entries(TIP_LOAD_DASHES.map(|(_, _, label)| label)));
    figure
        .legend
        .push(LegendEntry::line("the pulled tendon (thin line)", "#666666").width(1.2));
    figure.legend.push(LegendEntry::new(
        Symbol::Disk,
        &format!("{PROTOTYPE_DISKS} spacer disks, evenly spaced, as on the prototype"),
        "#6b6b6b",
    ));
    figure.legend.push(LegendEntry::new(
        Symbol::Arrow,
        "tip load (N), arrow length proportional to force",
        FORCE_COLOR,
    ));
    figure
}

/// Legend lines for the tip loads of Table 2, in their dash patterns, with these labels.
fn tip_load_entries(labels: [&str; 3]) -> impl Iterator<Item = LegendEntry> + '_ {
    TIP_LOAD_DASHES.iter().zip(labels).map(|((_, dash, _), label)| {
        let entry = LegendEntry::line(label, "#666666");
        match dash {
            Some(d) => entry.dash(d),
            None => entry,
        }
    })
}

/// The main job's picture for a journal column: side views only, three panels a row, 525 px
/// wide (a 1050-pixel PNG: 3.5 in at 300 dpi), a one-line legend of what tells the shapes
/// apart, no subtitle.
fn compact(full: &Figure) -> Figure {
    let mut figure = full.clone();
    figure.title = "Table 2, side views (XZ)".into();
    figure.subtitle.clear();
    figure.views = Some(vec![View::Side]);
    figure.columns = Some(3);
    figure.width = Some(525.0);
    for panel in &mut figure.panels {
        if let Some((tendon, _)) = panel.title.split_once(':') {
            panel.title = tendon.to_string();
        }
        // Two tip loads per column at this size: the legend tells them apart, not labels.
        for arrow in &mut panel.arrows {
            arrow.label = None;
        }
    }
    // Short labels, so that the legend takes three columns.
    figure.legend = vec![LegendEntry::line("no tension", "#000000")];
    for (tension, color) in TENSION_COLORS {
        figure.legend.push(LegendEntry::line(&format!("{tension} N"), color));
    }
    figure.legend.extend(tip_load_entries(["no tip load", "10 g", "20 g"]));
    figure
        .legend
        .push(LegendEntry::new(Symbol::Arrow, "tip load", FORCE_COLOR));
    figure
}

/// The tip distances (m) of the point-moment and constant-curvature models and of the
/// Kirchhoff rod of `robot` from the coupled model's tip `tip` (`None` where the variant
/// does not solve), and the largest distance of the paper's jump conditions so far in
/// `paper_jumps` (or the first failure).
fn variant_distances(
    robot: &tdcr::Robot,
    tip: tdcr::nalgebra::Vector3<f64>,
    options: &collocation::Options,
    paper_jumps: &mut Result<f64, String>,
) -> [Option<f64>; 3] {
    let solved = |v: Variant| collocation::solve(&v.robot(robot), options).map(|s| (s.tip_position() - tip).norm());
    let pm = solved(Variant::PointMoment).ok();
    let kh = solved(Variant::Kirchhoff).ok();
    let cc = constant_curvature(robot, 1)
        .ok()
        .and_then(|states| states.last().map(|state| (state.p - tip).norm()));
    if let Ok(largest) = paper_jumps {
        match solved(Variant::PaperJumps) {
            Ok(d) => *largest = largest.max(d),
            Err(e) => *paper_jumps = Err(e.to_string()),
        }
    }
    [pm, cc, kh]
}

/// Solves the 32 experiments, prints their table and writes `table2.svg`, `table2.png` and
/// `table2.csv` into `out_dir`.
pub fn run(out_dir: &Path) -> Result<(), Failure> {
    let start = Instant::now();
    let experiments = cases::table2();
    let options = collocation::Options::default();
    let routings = cases::prototype_routings();
    emit(&format!(
        "The prototype of Rucker & Webster (2011, section 5) under the {} experiments of Table 2\n\
         collocation at the default settings (tip error estimated and held below {:.0e} L); tip in mm, world frame;\n\
         pm, cc, kh: how far (mm) the tip of the point-moment tendon model, of the constant-curvature model\n\
         (which ignores the tip load and self weight) and of the Kirchhoff (inextensible, unshearable) rod is\n\
         from the coupled model's (`tdcr compare`, docs/validation.md)\n\n",
        experiments.len(),
        options.tolerance.unwrap_or(f64::NAN)
    ))?;
    let header = format!(
        "{:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>6} {:>6} {:>6} {:>5} {:>7}\n\
         {:>3}  {:<24} {:<27} {:>7} {:>8} {:>9} {:>9} {:>9} {:>7} {:>6} {:>6} {:>6} {:>5} {:>7}\n",
        "#",
        "configuration",
        "tendon",
        "tension",
        "tip load",
        "tip x",
        "tip y",
        "tip z",
        "bend",
        "pm",
        "cc",
        "kh",
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
        "mm",
        "mm",
        "mm",
        "",
        "ms"
    );
    emit(&header)?;
    let mut csv = CsvTable::new(
        "experiment,configuration,tendon,tension,tip_load,tip_x,tip_y,tip_z,bending_angle_deg,point_moment_tip_distance,constant_curvature_tip_distance,kirchhoff_tip_distance,iterations,intervals,solve_time"
            .split(','),
    );
    let mut solved = Vec::new();
    let mut failures = Vec::new();
    let mut solver_time = Duration::ZERO;
    let mut intervals = Vec::new();
    // The largest tip distance of the paper's jump conditions from the coupled model (m).
    let mut paper_jumps: Result<f64, String> = Ok(0.0);
    for (k, e) in experiments.iter().enumerate() {
        let robot = e.robot();
        let tendon = e
            .tendon
            .map_or("-".to_string(), |i| format!("{i}: {}", describe(&routings[i - 1])));
        let row = match collocation::solve(&robot, &options) {
            Ok(solution) => {
                let tip = solution.tip_position();
                let bend = output::bending_angle(&solution).to_degrees();
                let [pm, cc, kh] = variant_distances(&robot, tip, &options, &mut paper_jumps);
                let report = &solution.report;
                solver_time += report.timings.total;
                intervals.push(report.intervals);
                csv.row([
                    (k + 1).to_string(),
                    e.label(),
                    e.tendon.map_or(String::new(), |i| i.to_string()),
                    number(e.tension),
                    number(e.tip_load),
                    number(tip.x),
                    number(tip.y),
                    number(tip.z),
                    number(bend),
                    pm.map_or(String::new(), number),
                    cc.map_or(String::new(), number),
                    kh.map_or(String::new(), number),
                    report.iterations.to_string(),
                    report.intervals.to_string(),
                    number(report.timings.total.as_secs_f64()),
                ]);
                let line = format!(
                    "{:>3}  {:<24} {:<27} {:>7.2} {:>8.3} {} {} {} {:>7.2} {} {} {} {:>5} {:>7.1}\n",
                    k + 1,
                    e.label(),
                    tendon,
                    e.tension,
                    e.tip_load,
                    fixed(tip.x * 1e3, 9, 2),
                    fixed(tip.y * 1e3, 9, 2),
                    fixed(tip.z * 1e3, 9, 2),
                    bend,
                    pm.map_or(format!("{:>6}", "-"), |d| fixed(d * 1e3, 6, 2)),
                    cc.map_or(format!("{:>6}", "-"), |d| fixed(d * 1e3, 6, 2)),
                    kh.map_or(format!("{:>6}", "-"), |d| fixed(d * 1e3, 6, 3)),
                    report.iterations,
                    ms(report.timings.total)
                );
                solved.push((*e, robot, solution));
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
    emit(&match paper_jumps {
        Ok(0.0) => "the paper's jump conditions (no corner forces) give the coupled model's tips, bitwise: every \
                    tendon of the prototype ends at the tip, so no tendon turns at another's end\n"
            .to_string(),
        Ok(d) => format!(
            "the paper's jump conditions (no corner forces) put every tip within {:.1e} mm of the coupled \
             model's\n",
            d * 1e3
        ),
        Err(e) => format!("the paper's jump conditions: {e}\n"),
    })?;

    let figure = picture(&solved, &routings, &mesh);
    let mut text = true;
    for (name, figure) in [("table2", &figure), ("table2_compact", &compact(&figure))] {
        write_file(&out_dir.join(format!("{name}.svg")), figure.to_svg(), "picture")?;
        let (png, fonts) = figure
            .render(Format::Png)
            .map_err(|e| Failure::Other(format!("cannot draw the picture: {e}")))?;
        write_file(&out_dir.join(format!("{name}.png")), png, "picture")?;
        text &= fonts;
    }
    if !text {
        note("warning: no fonts found on this system, so the PNGs have no text; the SVGs have it");
    }
    let csv_path = out_dir.join("table2.csv");
    write_file(&csv_path, csv.finish(), "table")?;
    let d = out_dir.display();
    emit(&format!(
        "picture of all shapes: {d}/table2.svg and {d}/table2.png; for a journal column (side views): \
         {d}/table2_compact.svg and .png\ntable as CSV (SI units): {}\n",
        csv_path.display()
    ))?;
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Failure::NotConverged(failures.join("\n")))
    }
}
