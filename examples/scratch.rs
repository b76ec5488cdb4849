use tdcr::*;
fn main() {
    let robot = cases::case_h();
    for n in [32, 128, 512] {
        let o = collocation::Options {
            intervals: n,
            ..Default::default()
        };
        let sol = collocation::solve(&robot, &o).unwrap();
        let r = &sol.report;
        println!(
            "{n}: iters {} total {:?} assembly {:?} factor {:?} solve {:?} res evals {} jac {}",
            r.iterations,
            r.timings.total,
            r.timings.assembly,
            r.timings.factorization,
            r.timings.solve,
            r.evaluations.residual,
            r.evaluations.jacobian
        );
    }
}
