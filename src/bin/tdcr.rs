//! The `tdcr` command.
fn main() {
    for (name, robot, tip) in [
        ("S", tdcr::cases::case_s(), tdcr::cases::TIP_S),
        ("H", tdcr::cases::case_h(), tdcr::cases::TIP_H),
    ] {
        for n in [4, 8, 16, 32, 64, 128] {
            let t = std::time::Instant::now();
            let o = tdcr::collocation::Options {
                intervals: n,
                ..Default::default()
            };
            match tdcr::collocation::solve(&robot, &o) {
                Ok(sol) => {
                    let p = sol.tip_position();
                    println!(
                        "{name} {n}: err {:.3e} iters {} steps {} time {:?} res {:.1e} orth {:.1e} {:?}",
                        (p - nalgebra::Vector3::from(tip)).norm(),
                        sol.report.iterations,
                        sol.report.load_steps,
                        t.elapsed(),
                        sol.report.residual,
                        sol.max_orthonormality_error(),
                        sol.report.history.iter().map(|h| h.damping).collect::<Vec<_>>()
                    );
                }
                Err(e) => println!("{name}: {e}"),
            }
        }
    }
}
