fn main() {
    let robot = tdcr::cases::case_s();
    for n in [32, 64] {
        let o = tdcr::collocation::Options {
            intervals: n,
            continuation: false,
            ..Default::default()
        };
        match tdcr::collocation::solve(&robot, &o) {
            Ok(sol) => println!("{:?}", sol.report.history),
            Err(tdcr::Error::NotConverged { report, worst_s, .. }) => {
                println!("{} {worst_s} {:#?}", report.termination, report.history)
            }
            Err(e) => println!("{e}"),
        }
    }
}
