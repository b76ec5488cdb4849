//! The opposite-tendon histories' honesty (docs/friction.md section 8, "Opposite tendons"):
//! the prototype with tendons 1 and 3 both with friction (mu = 0.1, E_t A_t = 2000 N), one
//! held at 1 N and the other pulled to 4.91 N and let back out, at the default tolerance and
//! against the same history at 1e-11 L. Prints each step's contacts, intervals, estimate,
//! `tolerance_met` and true error / estimate.
//!
//! `opposite_history SWEPT STEPS [REFERENCE]`: SWEPT is the swept tendon (1 or 3), STEPS the
//! steps each way (10: tests/history.rs; 50: the 101-step history), REFERENCE the tight
//! history's tolerance in L (1e-11 unless given; `none` skips it). With REFERENCE_ZONES
//! set, each step's line is preceded by the reference step's contacts.

use tdcr::Motion;
use tdcr::analysis::history::{Contact, history};
use tdcr::analysis::sweep::{Input, Ranges};
use tdcr::{Friction, Parameter, cases, collocation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let swept: usize = args.first().map_or(3, |a| a.parse().expect("SWEPT is 1 or 3")) - 1;
    let count: usize = args.get(1).map_or(10, |a| a.parse().expect("STEPS is a count"));
    let reference: Option<f64> = match args.get(2).map(String::as_str) {
        Some("none") => None,
        Some(a) => Some(a.parse().expect("REFERENCE is a number")),
        None => Some(1e-11),
    };
    let held = 2 - swept;
    let mut robot = cases::prototype().with_tensions(&[0.0; 5]);
    for i in [0, 2] {
        robot.tendons[i].friction = Some(Friction::pull(0.1));
        robot.tendons[i].stiffness = Some(2000.0);
    }
    robot.tendons[held].set_tension(1.0);
    let length = robot.length();
    let values: Vec<f64> = (0..=count).map(|k| 4.91 * k as f64 / count as f64).collect();
    let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(swept)), values)])
        .expect("valid ranges")
        .up_down();
    let solve = |tolerance: Option<f64>| {
        let options = collocation::Options {
            tolerance,
            ..Default::default()
        };
        let result = history(&ranges, &options).expect("a valid history");
        if let Some((k, e)) = &result.failure {
            println!("tolerance {tolerance:?}: step {} fails: {e}", k + 1);
        }
        result.steps
    };
    let steps = solve(collocation::Options::default().tolerance);
    let exact = reference.map(|r| solve(Some(r)));
    println!("tolerance {:.2e} m", 1e-7 * length);
    for (k, step) in steps.iter().enumerate() {
        let report = &step.solution.report;
        let estimate = report.error_estimate.map_or(f64::NAN, |e| e.tip_position);
        let error = exact.as_ref().and_then(|e| e.get(k)).map_or(f64::NAN, |e| {
            (step.solution.tip_position() - e.solution.tip_position()).norm()
        });
        let zones_of = |step: &tdcr::analysis::history::HistoryStep| -> String {
            step.zones
                .iter()
                .map(|t| {
                    t.zones
                        .iter()
                        .map(|z| format!("{} {:.4}-{:.4}", z.contact.name(), z.start, z.end))
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .collect::<Vec<_>>()
                .join(" | ")
        };
        if std::env::var_os("REFERENCE_ZONES").is_some()
            && let Some(e) = exact.as_ref().and_then(|e| e.get(k))
        {
            println!("      reference zones: {}", zones_of(e));
        }
        let tight = exact.as_ref().and_then(|e| e.get(k)).map_or(String::new(), |e| {
            let r = &e.solution.report;
            format!(
                "ref {:5} int est {:.1e} met {:?}  ",
                r.intervals,
                r.error_estimate.map_or(f64::NAN, |e| e.tip_position),
                r.tolerance_met
            )
        });
        println!(
            "step {:3} {:5.3} N  {:5} int  est {estimate:.2e}  met {:?}  err {error:.2e}  ratio {:.3}  {tight}| {}",
            k + 1,
            step.solution.tendons[swept].tension,
            report.intervals,
            report.tolerance_met,
            error / estimate,
            zones_of(step)
        );
        // A step that slides all along is the full-slip solve with each tendon's motion:
        // an independent reference, with the mesh chosen by its own adaptive refinement.
        if std::env::var_os("FULL_SLIP").is_some() && step.zones.iter().all(|t| t.zones.len() == 1) {
            let mut robot = ranges.robot(k as f64).expect("a valid step");
            for t in &step.zones {
                if let Some(f) = robot.tendons[t.tendon].friction.as_mut() {
                    f.motion = match t.zones[0].contact {
                        Contact::Release => Motion::Release,
                        _ => Motion::Pull,
                    };
                }
            }
            let options = collocation::Options {
                tolerance: Some(1e-11),
                ..Default::default()
            };
            let full = tdcr::solve(&robot, &options).expect("the full-slip solve");
            let distance = (full.tip_position() - step.solution.tip_position()).norm();
            println!(
                "      full slip at 1e-11 L on {} intervals: error {distance:.2e}, ratio {:.3}",
                full.report.intervals,
                distance / estimate
            );
        }
        if std::env::var_os("PRINT_TIPS").is_some() {
            println!("      tip {:?}", step.solution.tip_position());
        }
        if std::env::var_os("INFLECTIONS").is_some() {
            let nodes = &step.solution.nodes;
            for c in 0..3 {
                let flips: Vec<String> = nodes
                    .windows(2)
                    .filter(|w| w[0].u[c] * w[1].u[c] < 0.0)
                    .map(|w| {
                        format!(
                            "{:.4}",
                            w[0].s - w[0].u[c] * (w[1].s - w[0].s) / (w[1].u[c] - w[0].u[c])
                        )
                    })
                    .collect();
                if !flips.is_empty() {
                    println!("      u[{c}] changes sign at s = {}", flips.join(", "));
                }
            }
        }
    }
}
