//! Displacement control from rest on robots nobody hand-picked: the prototype, under its own
//! weight, with two neighbouring straight tendons pulled over a grid of pull-ins, their
//! antagonists either tension-controlled at 0 N or displacement-controlled and let out by
//! 1.2 or 2 times the pull (an inextensible antagonist let out by less would have to
//! compress the rod, EA = 1.6e5 N, by the difference: hundreds of newtons, past the
//! geometric limit EI / r^2 = 66 N), solved cold at default settings. Every solve must
//! converge, satisfy the complementarity (taut: no slack; slack: exactly 0 N), and equal
//! the tension-controlled solve at the tensions it found. (With psi = min(tau / T, phi / L)
//! instead of Fischer-Burmeister, 3 of these 48 failed, tendons 1 and 4 pulled by 2 mm and
//! 2, 4 or 6 mm with the antagonists free: the line search stalled at the kink between taut
//! and slack.)

use tdcr::{Robot, cases, collocation};

/// The prototype with its straight tendons pulled in by `q` (m; `None`: tension-controlled
/// at 0 N) and the helix unused.
fn pulled(q: [Option<f64>; 4]) -> Robot {
    let mut robot = cases::prototype();
    for (t, q) in robot.tendons.iter_mut().zip(q) {
        match q {
            Some(q) => t.set_displacement(q),
            None => t.set_tension(0.0),
        }
    }
    robot
}

#[test]
fn a_grid_of_pull_ins_converges_cold_and_matches_the_tension_solve() {
    let levels = [0.0, 0.002, 0.004, 0.006];
    let mut failures = Vec::new();
    let mut solved = 0;
    let mut cases = Vec::new();
    for &a in &levels {
        for &b in &levels {
            // Tendons 1 (x) and 4 (-y) pulled by a and b; their antagonists 3 and 2 free,
            // or let out by 1.2 and 2 times the pull.
            cases.push([Some(a), None, None, Some(b)]);
            for f in [1.2, 2.0] {
                cases.push([Some(a), Some(-f * b), Some(-f * a), Some(b)]);
            }
        }
    }
    for &q in &cases {
        {
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
                assert!(t.slack >= 0.0, "{q:?}: tendon {}", i + 1);
                if t.tension > 0.0 {
                    assert_eq!(t.slack, 0.0, "{q:?}: tendon {} taut with slack", i + 1);
                }
            }
            // The same mesh driven by the tensions found: the same shape to 1e-8 L
            // (2.4e-9 m): both Newton solves stop with a remaining error below 1e-10 L, and
            // the tensions they share are exact to about 1e-10 of their scale.
            let tensions = solution.tensions();
            let mut by_tension = cases::prototype();
            for (t, &tau) in by_tension.tendons.iter_mut().zip(&tensions) {
                t.set_tension(tau);
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
        cases.len(),
        failures.join("\n")
    );
    assert_eq!(solved, 48);
}
