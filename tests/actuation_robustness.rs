//! Displacement control from rest on robots nobody hand-picked: the prototype, under its own
//! weight, with its four straight tendons all displacement-controlled over a grid of
//! pull-ins (antagonists pulled, held at 0 or let out), solved cold at default settings.
//! Every solve must converge, satisfy the complementarity (taut: the pull-in holds; slack:
//! exactly 0 N and a positive slack), and equal the tension-controlled solve at the tensions
//! it found.

use tdcr::{Robot, cases, collocation};

/// The prototype with its four straight tendons pulled in by `q` (m) and the helix unused.
fn pulled(q: [f64; 4]) -> Robot {
    let mut robot = cases::prototype();
    for (t, q) in robot.tendons.iter_mut().zip(q) {
        t.tension = 0.0;
        t.displacement = Some(q);
    }
    robot.tendons[4].tension = 0.0;
    robot
}

#[test]
fn a_grid_of_four_pull_ins_converges_cold_and_matches_the_tension_solve() {
    let levels = [-0.002, 0.0, 0.002, 0.005];
    let mut failures = Vec::new();
    let mut solved = 0;
    for &a in &levels {
        for &b in &levels {
            // Tendons 1 and 2 pulled by a and b, their antagonists 3 and 4 at half of the
            // opposite: every combination of taut and slack pairs.
            let q = [a, b, -0.5 * a, -0.5 * b];
            let robot = pulled(q);
            let solution = match collocation::solve(&robot, &Default::default()) {
                Ok(s) => s,
                Err(e) => {
                    failures.push(format!("{q:?}: {e}"));
                    continue;
                }
            };
            solved += 1;
            let length = robot.length();
            for (i, t) in solution.tendons.iter().take(4).enumerate() {
                assert!(t.tension >= 0.0, "{q:?}: tendon {} pushes", i + 1);
                if t.tension > 0.0 {
                    assert_eq!(t.slack, 0.0, "{q:?}: tendon {} taut with slack", i + 1);
                } else {
                    // Slack, or just taut at 0 N.
                    assert!(t.slack >= 0.0, "{q:?}: tendon {}", i + 1);
                }
            }
            // The same mesh driven by the tensions found: the same shape, 1e-9 m (the
            // tension solve stops at the scaled residual 1e-11, about 1e-8 m of tip
            // from the exact discrete solution at worst; both start from the same state).
            let tensions = solution.tensions();
            let mut by_tension = cases::prototype();
            for (t, &tau) in by_tension.tendons.iter_mut().zip(&tensions) {
                t.tension = tau;
            }
            let mesh = collocation::Options {
                mesh: Some(solution.nodes.iter().map(|n| n.s).collect()),
                tolerance: None,
                ..Default::default()
            };
            let reference = collocation::solve_from(&by_tension, &mesh, &solution).unwrap();
            let gap = (reference.tip_position() - solution.tip_position()).norm();
            assert!(gap <= 1e-8 * length, "{q:?}: tip {gap:.3e} m from the tension solve");
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cold displacement solves failed:\n{}",
        failures.len(),
        levels.len() * levels.len(),
        failures.join("\n")
    );
    assert_eq!(solved, 16);
}
