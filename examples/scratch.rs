use tdcr::*;
fn main() {
    let mut bend = cases::prototype();
    bend.tendons[0].tension = 20.0;
    for (name, robot) in [("S", cases::case_s()), ("H", cases::case_h()), ("bend", bend)] {
        for n in [16, 32, 64, 128, 256] {
            let o = collocation::Options {
                intervals: n,
                ..Default::default()
            };
            let sol = collocation::solve(&robot, &o).unwrap();
            println!("{name} {n}: {:?}", equilibrium::imbalance(&robot, &sol));
        }
        let sol = shooting::solve(
            &robot,
            &shooting::Options {
                integration_tolerance: 1e-12,
                ..Default::default()
            },
        )
        .unwrap();
        println!("{name} shooting: {:?}", equilibrium::imbalance(&robot, &sol));
    }
}
