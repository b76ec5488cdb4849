//! Issue 17, point 7: the `control_loop` example converges to its goal. `cargo test` builds
//! examples but does not run them, so this runs the example's own loop.

#[allow(dead_code)]
#[path = "../examples/control_loop.rs"]
mod control_loop;

#[test]
fn control_loop_reaches_its_goal() {
    let records = control_loop::run().unwrap();
    let last = records.last().unwrap();
    assert!(
        last.error < control_loop::GOAL_TOLERANCE,
        "ended {} m from the goal after {} steps",
        last.error,
        last.step
    );
    // With the reference at the goal, every step lowers the error (Newton-like).
    let holding: Vec<f64> = records
        .iter()
        .filter(|r| r.step >= control_loop::TRACKING_STEPS)
        .map(|r| r.error)
        .collect();
    assert!(holding.windows(2).all(|w| w[1] < w[0]), "{holding:?}");
    // No tendon ran slack, and the co-contraction stayed near the pre-tension (3 N: twice it).
    for r in &records {
        assert!(
            r.tensions
                .iter()
                .all(|&t| t > 0.0 && t < 2.0 * control_loop::PRETENSION),
            "step {}: {:?}",
            r.step,
            r.tensions
        );
    }
}
