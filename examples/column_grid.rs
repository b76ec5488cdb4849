//! Issue 25's column grid: per case the stability, the tip, the path and where the
//! Newton + chord steps went (load steps, meshes).
//!
//! `cargo run --release --example column_grid [RATIO EPS]`

use nalgebra::Vector3;
use std::f64::consts::PI;
use tdcr::collocation::{self, Options};
use tdcr::{Loads, Robot, Rod};

const LENGTH: f64 = 0.5;
const RATIOS: [f64; 12] = [0.5, 0.9, 0.99, 1.01, 1.05, 1.1, 1.2, 1.3, 1.5, 2.0, 3.0, 5.0];
const IMPERFECTIONS: [f64; 6] = [0.0, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1];

fn column(p: f64, eps: f64) -> Robot {
    Robot::new(Rod::solid_circle(LENGTH, 0.001, 200e9, 0.3)).with_loads(Loads::none().with_tip_force(Vector3::new(
        eps * p,
        0.0,
        -p,
    )))
}

fn main() {
    let ei = column(0.0, 0.0).rod.section_at(0.0).section.kbt[0];
    let pcr = PI * PI * ei / (4.0 * LENGTH * LENGTH);
    let args: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let cases: Vec<(f64, f64)> = match args.as_slice() {
        [r, e] => vec![(*r, *e)],
        _ => IMPERFECTIONS
            .iter()
            .flat_map(|&e| RATIOS.iter().map(move |&r| (r, e)))
            .collect(),
    };
    let (mut total, mut worst) = (0, 0);
    println!("ratio eps stable tip_x tip_y tip_z iterations newton chord load_steps meshes path");
    for (ratio, eps) in cases {
        match collocation::solve(&column(ratio * pcr, eps), &Options::default()) {
            Ok(s) => {
                let (t, r) = (s.tip_position(), &s.report);
                total += r.iterations;
                worst = worst.max(r.iterations);
                println!(
                    "{ratio} {eps:e} {} {:.5} {:.5} {:.5} {} {} {} {} {} {:?} {}",
                    r.stability.is_stable(),
                    t.x,
                    t.y,
                    t.z,
                    r.iterations,
                    r.newton_steps,
                    r.chord_steps,
                    r.load_steps,
                    r.meshes,
                    r.path,
                    r.notes.len()
                );
            }
            Err(e) => println!("{ratio} {eps:e} FAILED {e}"),
        }
    }
    println!("total {total}, most {worst}");
}
