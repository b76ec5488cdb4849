//! The `tdcr` command.
fn main() {
    for (name, robot, tip) in [
        ("S", tdcr::cases::case_s(), tdcr::cases::TIP_S),
        ("H", tdcr::cases::case_h(), tdcr::cases::TIP_H),
    ] {
        let t = std::time::Instant::now();
        match tdcr::shooting::solve(&robot, &Default::default()) {
            Ok(sol) => {
                let p = sol.tip_position();
                println!(
                    "{name}: tip {:?} err {:.3e} iters {} time {:?} n0 {:?} u0 {:?}",
                    p.as_slice(),
                    (p - nalgebra::Vector3::from(tip)).norm(),
                    sol.report.iterations,
                    t.elapsed(),
                    (sol.base().R.transpose() * sol.base().n).as_slice(),
                    sol.base().u.as_slice()
                );
            }
            Err(e) => println!("{name}: {e}"),
        }
    }
}
