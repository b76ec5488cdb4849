mod common;
use common::try_solve_all;
use nalgebra::Vector3;
use tdcr::*;
#[test]
fn dbg() {
    for experiment in cases::table2() {
        let robot = experiment.robot();
        for (name, s) in try_solve_all(&robot) {
            let s = s.unwrap();
            let e = equilibrium::imbalance(&robot, &s);
            println!(
                "{name} {:30} f {:.2e} m {:.2e} res {:.2e} it {} steps {}",
                experiment.label(),
                e.force,
                e.moment,
                s.report.residual,
                s.report.iterations,
                s.report.intervals
            );
        }
    }
    let (length, ei) = (0.5, 2.0);
    for fac in [1e5, 1e6, 1e7, 1e8] {
        let stiff = fac * ei / (length * length);
        for lambda in [1.0, 2.0, 5.0, 10.0] {
            let force = lambda * ei / (length * length);
            let robot = Robot::new(Rod::new(length, Section::explicit(stiff, stiff, ei, ei, 0.75 * ei)))
                .with_loads(Loads::none().with_tip_force(Vector3::new(force, 0.0, 0.0)));
            for (name, s) in try_solve_all(&robot) {
                match s {
                    Ok(s) => {
                        let e = equilibrium::imbalance(&robot, &s);
                        println!(
                            "{fac:e} {lambda} {name} tip {:?} f {:.2e} m {:.2e} res {:.2e} it {}",
                            s.tip_position().as_slice(),
                            e.force,
                            e.moment,
                            s.report.residual,
                            s.report.iterations
                        )
                    }
                    Err(e) => println!("{fac:e} {lambda} {name} ERR {e}"),
                }
            }
        }
    }
}
