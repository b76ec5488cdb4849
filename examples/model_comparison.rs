//! How far the simpler tendon models are from the coupled model on the paper's 32
//! experiments: tip distance of the point-moment model and of the constant-curvature model
//! from the coupled model's tip.
//!
//! `cargo run --release --example model_comparison`

use tdcr::analysis::comparison::constant_curvature;
use tdcr::{TendonModel, cases, collocation};

fn main() -> Result<(), tdcr::Error> {
    let options = collocation::Options::fixed(64);
    println!("| experiment | coupled tip (mm) | point-moment model (mm off) | constant curvature (mm off) |");
    println!("| --- | --- | --- | --- |");
    for experiment in cases::table2() {
        let robot = experiment.robot();
        let full = collocation::solve(&robot, &options)?.tip_position();
        let mut pm = robot.clone();
        pm.tendon_model = TendonModel::PointMoment;
        let point_moment = collocation::solve(&pm, &options)?.tip_position();
        let cc = constant_curvature(&robot, 1)?.last().map(|s| s.p).unwrap_or(full);
        println!(
            "| {} | ({:.1}, {:.1}, {:.1}) | {:.3} | {:.1} |",
            experiment.label(),
            full.x * 1e3,
            full.y * 1e3,
            full.z * 1e3,
            (point_moment - full).norm() * 1e3,
            (cc - full).norm() * 1e3
        );
    }
    Ok(())
}
