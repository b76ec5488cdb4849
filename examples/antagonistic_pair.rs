//! The worked antagonistic-pair example of docs/actuation.md: two elastic tendons
//! (E_t A_t = 2000 N, 0.1 m of free length) at (8 mm, 0) and (-8 mm, 0) on the prototype's
//! rod, without gravity. Both actuators first pull in by 0.1 mm (a pretension of about
//! 0.58 N); then actuator 1 pulls in a further q and actuator 2 lets out q, for q from 0 to
//! 6 mm; the same without pretension for comparison. Each solve is warm-started from the last. Writes the tensions against
//! q to docs/actuation_pair.svg and the tip's deflection against q to
//! docs/actuation_pair_tip.svg, and prints the table.
//!
//! `cargo run --release --example antagonistic_pair`

use tdcr::plot::{Chart, Mark, PALETTE, Segment};
use tdcr::{Loads, Robot, Routing, Solution, Tendon, cases, collocation};

/// Pretension pull-in of both actuators (m).
const PRETENSION: f64 = 0.0001;
/// Largest differential pull-in q (m) and the number of steps to it.
const Q_MAX: f64 = 0.006;
const STEPS: usize = 60;
/// Tendon axial stiffness E_t A_t (N) and free length (m): a compliance of
/// (0.242 + 0.1) / 2000 = 0.17 mm/N, so that the pretension is a usable number (an
/// inextensible pair pulled in by 0.1 mm would have to compress the rod, some 22 N).
const STIFFNESS: f64 = 2000.0;
const FREE_LENGTH: f64 = 0.1;

/// The elastic pair with actuator pull-ins `q1` and `q2` (m) on the prototype's rod,
/// weightless.
fn pair(q1: f64, q2: f64) -> Robot {
    let mut robot = cases::prototype();
    robot.loads = Loads::none();
    robot.tendons = vec![
        Tendon::pulled(Routing::straight(0.008, 0.0), q1).elastic(STIFFNESS, FREE_LENGTH),
        Tendon::pulled(Routing::straight(-0.008, 0.0), q2).elastic(STIFFNESS, FREE_LENGTH),
    ];
    robot
}

/// One solved step: q (m), the two tensions (N), the tip deflection along the base's body
/// x axis (m) and the slack of tendon 2 (m).
struct Step {
    q: f64,
    tensions: [f64; 2],
    deflection: f64,
    slack: f64,
}

/// Solves the sweep from pull-in `base` of both actuators, each step warm-started.
fn sweep(base: f64) -> Result<Vec<Step>, tdcr::Error> {
    let options = collocation::Options::default();
    let mut previous: Option<Solution> = None;
    let mut out = Vec::with_capacity(STEPS + 1);
    for k in 0..=STEPS {
        let q = Q_MAX * k as f64 / STEPS as f64;
        let robot = pair(base + q, base - q);
        let solution = match &previous {
            Some(warm) => collocation::solve_from(&robot, &options, warm)?,
            None => collocation::solve(&robot, &options)?,
        };
        let body_x = robot.base_rotation * tdcr::nalgebra::Vector3::x();
        out.push(Step {
            q,
            tensions: [solution.tendons[0].tension, solution.tendons[1].tension],
            deflection: (solution.tip_position() - robot.base_position).dot(&body_x),
            slack: solution.tendons[1].slack,
        });
        previous = Some(solution);
    }
    Ok(out)
}

/// A polyline of (x, y) points as chart segments.
fn polyline(chart: &mut Chart, points: &[(f64, f64)], color: &str, dashed: bool) {
    for w in points.windows(2) {
        chart.segments.push(Segment {
            ends: [w[0], w[1]],
            dashed,
            color: color.into(),
        });
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let pretensioned = sweep(PRETENSION)?;
    let loose = sweep(0.0)?;
    if let (Some(a), Some(b)) = (pretensioned.last(), loose.last()) {
        println!(
            "at q = {:.1} mm the tip deflects {:.3} mm pretensioned, {:.3} mm without",
            a.q * 1e3,
            a.deflection * 1e3,
            b.deflection * 1e3
        );
    }
    println!("q (mm)  tension 1 (N)  tension 2 (N)  tip deflection (mm)  slack 2 (mm)");
    for s in &pretensioned {
        println!(
            "{:>6.2}  {:>13.4}  {:>13.4}  {:>19.3}  {:>12.4}",
            s.q * 1e3,
            s.tensions[0],
            s.tensions[1],
            s.deflection * 1e3,
            s.slack * 1e3
        );
    }
    // Where the released tendon's tension reaches 0: the line through its last two taut
    // steps (the tension falls linearly there), crossed before the first slack step.
    let slack_from = pretensioned
        .windows(3)
        .find(|w| w[2].tensions[1] == 0.0 && w[1].tensions[1] > 0.0)
        .map(|w| {
            let t = w[1].tensions[1] / (w[0].tensions[1] - w[1].tensions[1]);
            let q = w[1].q + t * (w[1].q - w[0].q);
            let (w, t) = (&w[1..], t);
            println!("tendon 2 goes slack at q = {:.3} mm", q * 1e3);
            (q, w[0].deflection + t * (w[1].deflection - w[0].deflection))
        });

    let subtitle = vec![
        format!(
            "tendons at (8 mm, 0), (-8 mm, 0) on the prototype's rod, no gravity, E_t A_t = {STIFFNESS} N, \
             free length {FREE_LENGTH} m;"
        ),
        format!(
            "pull-ins {} mm + q and {} mm - q (solid), q and -q (dashed, no pretension)",
            PRETENSION * 1e3,
            PRETENSION * 1e3
        ),
    ];
    let mm = |f: &dyn Fn(&Step) -> f64, steps: &[Step]| -> Vec<(f64, f64)> {
        steps.iter().map(|s| (s.q * 1e3, f(s))).collect()
    };
    let mut tensions = Chart {
        title: "Antagonistic pair: tendon tensions against the differential pull-in q".into(),
        subtitle: subtitle.clone(),
        x_label: "differential pull-in q (mm)".into(),
        y_label: "tension (N)".into(),
        ..Default::default()
    };
    let (one, two) = (PALETTE[0], PALETTE[3]);
    polyline(&mut tensions, &mm(&|s| s.tensions[0], &pretensioned), one, false);
    polyline(&mut tensions, &mm(&|s| s.tensions[1], &pretensioned), two, false);
    polyline(&mut tensions, &mm(&|s| s.tensions[0], &loose), one, true);
    polyline(&mut tensions, &mm(&|s| s.tensions[1], &loose), two, true);
    tensions.legend = vec![
        ("tendon 1 (pulled in by q)".into(), one.into(), Some(false)),
        ("tendon 2 (let out by q)".into(), two.into(), Some(false)),
        ("without pretension".into(), "#555555".into(), Some(true)),
    ];
    if let Some((q, _)) = slack_from {
        tensions.marks.push(Mark {
            at: (q * 1e3, 0.0),
            label: format!("tendon 2 slack from q = {:.2} mm", q * 1e3),
            color: two.into(),
        });
    }
    std::fs::write("docs/actuation_pair.svg", tensions.to_svg())?;

    let mut tip = Chart {
        title: "Antagonistic pair: tip deflection against the differential pull-in q".into(),
        subtitle,
        x_label: "differential pull-in q (mm)".into(),
        y_label: "tip deflection towards tendon 1 (mm)".into(),
        ..Default::default()
    };
    polyline(&mut tip, &mm(&|s| s.deflection * 1e3, &pretensioned), one, false);
    polyline(&mut tip, &mm(&|s| s.deflection * 1e3, &loose), one, true);
    tip.legend = vec![
        ("pretensioned (0.1 mm pull-in each)".into(), one.into(), Some(false)),
        ("without pretension".into(), one.into(), Some(true)),
    ];
    if let Some((q, deflection)) = slack_from {
        tip.marks.push(Mark {
            at: (q * 1e3, deflection * 1e3),
            label: format!("tendon 2 slack from q = {:.2} mm", q * 1e3),
            color: two.into(),
        });
    }
    std::fs::write("docs/actuation_pair_tip.svg", tip.to_svg())?;
    println!("wrote docs/actuation_pair.svg and docs/actuation_pair_tip.svg");
    Ok(())
}
