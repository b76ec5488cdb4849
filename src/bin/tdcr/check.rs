//! `tdcr check` and `tdcr example`.

use crate::failure::{Failure, emit};
use crate::robot_args::read_robot;
use tdcr::{Method, Readable, Routing, Tendon};

/// Tendons `check` describes one line each; a file with more (a stress test, not a robot)
/// gets a count for the rest.
const LISTED_TENDONS: usize = 32;

/// `tdcr check FILE`: reads and checks a robot file (with its fixed mesh, if any, against the
/// resolution rule), one line on success.
pub fn run(file: &str) -> Result<(), Failure> {
    let (name, parsed) = read_robot(file)?;
    let r = &parsed.robot;
    // The file's fixed mesh must resolve the robot, as `solve` would require.
    if parsed.solver.method == Method::Collocation {
        tdcr::collocation::check_resolution(r, &parsed.solver.collocation)
            .map_err(|e| Failure::Input(format!("{name}: {e}")))?;
    }
    // Tendons pulled by a tension, and those driven by their actuator's pull-in (pulled
    // in, held or let out: their tensions are solved for).
    let pulled = r
        .tendons
        .iter()
        .filter(|t| t.displacement().is_none() && t.tension() > 0.0)
        .count();
    let driven = r.tendons.iter().filter(|t| t.displacement().is_some()).count();
    let actuation = match driven {
        0 => format!("{pulled} pulled"),
        _ => format!("{pulled} pulled by tension, {driven} driven by displacement"),
    };
    let warnings: Vec<String> = parsed
        .warnings()
        .into_iter()
        .chain(r.plausibility().iter().map(ToString::to_string))
        .collect();
    // The disks' weights are point loads of the model; counted as disks here.
    let disks = parsed.disks.as_ref().filter(|d| d.others(&r.loads.point).is_some());
    let points = r.loads.point.len() - disks.map_or(0, |d| d.positions.len());
    let disks = disks.map_or(String::new(), |d| {
        // Computed: three significant digits, not 0.009810000000000001.
        let weight = tdcr::plot::significant(d.weight.norm());
        format!(", {} disk(s) of {weight} N", d.positions.len())
    });
    let tendon_model = match (r.tendon_model, r.corner_forces) {
        (tdcr::TendonModel::PointMoment, _) => "; model: point-moment tendons",
        (_, false) => "; model: the paper's jump conditions (no corner forces)",
        _ => "",
    };
    let rod_model = match r.rod_model {
        tdcr::RodModel::Kirchhoff => "; rod: Kirchhoff (inextensible, unshearable)",
        tdcr::RodModel::Cosserat => "",
    };
    let model = format!("{tendon_model}{rod_model}");
    let ends = r.rod.segment_ends();
    let segments = match ends.len() {
        0 => String::new(),
        k => format!(" of {} segments", k + 1),
    };
    let mut out = format!(
        "{name}: OK{}: a {:.4} m rod{segments} with {} tendon(s) ({actuation}), {points} point load(s){disks}{model}; solver: {}\n",
        match warnings.len() {
            0 => String::new(),
            1 => ", with 1 warning".to_string(),
            n => format!(", with {n} warnings"),
        },
        r.length(),
        r.tendons.len(),
        parsed.solver.method
    );
    if !ends.is_empty() {
        out.push_str(&segment_lines(&r.rod));
    }
    for (i, t) in r.tendons.iter().enumerate().take(LISTED_TENDONS) {
        let mut line = tendon(t, r.length());
        if let Some(k) = ends.iter().position(|&e| e == t.end(r.length())) {
            let at = format!("ends at s = {} m", Readable(ends[k]));
            line = line.replacen(&at, &format!("{at} (the end of segment {})", k + 1), 1);
        }
        out.push_str(&format!("  tendon {}: {line}\n", i + 1));
    }
    if r.tendons.len() > LISTED_TENDONS {
        out.push_str(&format!(
            "  ... and {} more tendon(s) (`tdcr solve --format json` gives each one's turns)\n",
            r.tendons.len() - LISTED_TENDONS
        ));
    }
    for w in &warnings {
        out.push_str(&format!("warning: {w}\n"));
    }
    emit(&out)
}

/// One line per segment of a rod of segments for `check`: where it runs, its stiffnesses
/// (three significant digits) and its precurvature.
fn segment_lines(rod: &tdcr::Rod) -> String {
    let significant = tdcr::plot::significant;
    let mut bounds = vec![0.0];
    bounds.extend(rod.segment_ends());
    bounds.push(rod.length);
    let mut out = String::new();
    for (k, w) in bounds.windows(2).enumerate() {
        let mid = 0.5 * (w[0] + w[1]);
        let section = rod.section_at(mid).section;
        let u_star = rod.reference_at(mid).u_star;
        let shape = if u_star == tdcr::nalgebra::Vector3::zeros() {
            "straight".to_string()
        } else {
            format!(
                "precurvature ({}, {}, {}) rad/m",
                Readable(u_star[0]),
                Readable(u_star[1]),
                Readable(u_star[2])
            )
        };
        out.push_str(&format!(
            "  segment {}: s = {} to {} m, E I {} N m^2, G J {} N m^2, E A {} N, G A {} N, {shape}\n",
            k + 1,
            Readable(w[0]),
            Readable(w[1]),
            significant(section.kbt[0]),
            significant(section.kbt[2]),
            significant(section.kse[2]),
            significant(section.kse[0]),
        ));
    }
    out
}

/// `x` (m) rounded to the nanometre.
fn nm(x: f64) -> f64 {
    (x * 1e9).round() / 1e9
}

/// A tendon in a few words for `check`: its routing with the turns it makes over its own
/// length, its end, its tension or pull-in, its stiffness and free length when set, and its
/// friction coefficient with the motion it models when it has friction.
fn tendon(t: &Tendon, length: f64) -> String {
    let end = t.end(length);
    let at = if end < length {
        format!("ends at s = {} m", Readable(end))
    } else {
        format!("ends at the tip ({} m)", Readable(end))
    };
    let routing = match &t.routing {
        // To the nanometre: an offset from polar coordinates, (-0.0025, 0.00433013) m, not
        // every digit of its cosine.
        Routing::Straight { x, y } => format!("straight at ({}, {}) m", Readable(nm(*x)), Readable(nm(*y))),
        Routing::Helical { radius, turns, phase } => {
            let own = t.turns(length);
            let plural = if own.abs() == 1.0 { "" } else { "s" };
            let rate = if end < length {
                format!(
                    " (turns_per_rod_length {} counts over L = {} m)",
                    Readable(*turns),
                    Readable(length)
                )
            } else {
                String::new()
            };
            format!(
                "helical, radius {} m, phase {} rad, {} turn{plural} over its {} m{rate}",
                Readable(*radius),
                Readable(*phase),
                Readable((own * 1e6).round() / 1e6),
                Readable(end)
            )
        }
        Routing::Custom(_) => "custom routing".into(),
    };
    let actuation = match t.displacement() {
        Some(q) => format!(
            "displacement-controlled, pull-in {} m{}",
            Readable(q),
            if q < 0.0 { " (let out)" } else { "" }
        ),
        None => format!("tension {} N", Readable(t.tension())),
    };
    let elastic = match t.stiffness {
        Some(k) => format!(
            ", elastic: stiffness {} N, free length {} m",
            Readable(k),
            Readable(t.free_length)
        ),
        None if t.free_length != 0.0 => format!(
            ", inextensible (free length {} m, no effect without stiffness)",
            Readable(t.free_length)
        ),
        None => String::new(),
    };
    let friction = match t.friction {
        Some(f) if f.coefficient > 0.0 => format!(", friction {} ({})", Readable(f.coefficient), f.motion.name()),
        _ => String::new(),
    };
    format!("{routing}, {at}, {actuation}{elastic}{friction}")
}

/// `tdcr example`: the prototype as a commented robot file.
/// The sample files of `tdcr example`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Sample {
    /// The commented robot file.
    Robot,
    /// A parameter table for `tdcr batch` with the robot file.
    Cases,
    /// The prototype in the paper's frame, for `tdcr calibrate`.
    PaperRobot,
    /// Synthetic measured tips of the paper-frame prototype (0.1 mm noise).
    Experiments,
}

pub fn example(sample: Sample) -> Result<(), Failure> {
    match sample {
        Sample::Robot => emit(&tdcr::io::example()),
        Sample::Cases => emit(&tdcr::io::example_cases()),
        Sample::PaperRobot => emit(&tdcr::io::paper_frame_example()),
        Sample::Experiments => {
            let experiments = tdcr::io::example_experiments(1e-4).map_err(crate::solver_failure)?;
            emit(&tdcr::io::experiments::to_csv(&experiments))
        }
    }
}
