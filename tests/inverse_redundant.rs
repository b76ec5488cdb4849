//! Issue 17, point 7: with more free tendons than target coordinates, inverse statics returns
//! the tensions it reaches from the start, which keep the start's co-contraction (the
//! statement `InverseSolution::explain` makes); they are not the least-norm tensions.

use nalgebra::{DMatrix, DVector};
use tdcr::fit::inverse::{InverseOptions, Target, solve_tensions};
use tdcr::{cases, collocation};

/// The prototype without its helix, the four straight tendons at `tensions`.
fn robot(tensions: [f64; 4]) -> tdcr::Robot {
    let mut robot = cases::prototype();
    for (t, x) in robot.tendons.iter_mut().zip(tensions) {
        t.set_tension(x);
    }
    robot
}

#[test]
fn redundant_tendons_keep_the_starting_co_contraction() {
    let options = InverseOptions {
        free_tendons: Some(vec![0, 1, 2, 3]),
        // 1e-5 m: with a free direction the iteration may stop a few micrometres short
        // (`NoProgress`), which does not change which solution it heads for
        tolerance: 1e-5,
        ..InverseOptions::new(10.0)
    };
    let goal = collocation::solve(&robot([0.2, 2.5, 1.5, 0.4]), &options.solver)
        .unwrap()
        .tip_position();
    let target = Target::position(goal);
    let mut found = Vec::new();
    for start in [[1.0, 1.0, 1.0, 1.0], [1.5, 1.5, 1.5, 1.5]] {
        let solution = solve_tensions(&robot(start), &target, &options).unwrap();
        assert!(solution.reachable, "{}", solution.explain());
        let text = solution.explain();
        assert!(
            text.contains("4 free tendons for 3 target coordinates") && text.contains("not the least-norm tensions"),
            "{text}"
        );
        // The change from the start against the null space of d(tip)/d(tension) there.
        let robot = robot([0.0; 4]);
        let mut at = robot.clone();
        for (t, &x) in at.tendons.iter_mut().zip(&solution.tensions) {
            t.set_tension(x);
        }
        let j = tdcr::tip_sensitivities(&at, &solution.solution).unwrap().tension;
        let j = DMatrix::from_fn(3, 4, |r, c| j[(r, c)]);
        let svd = j.transpose().svd(true, false);
        // The right singular vector of the smallest (zero) singular value of J: column 3 of
        // U of J^T, ordered by singular value.
        let u = svd.u.unwrap();
        let (k, _) = svd.singular_values.argmin();
        let null = u.column(k).into_owned();
        let change = DVector::from_iterator(4, solution.tensions[..4].iter().zip(start).map(|(t, s)| t - s));
        let cosine = null.dot(&change).abs() / change.norm();
        // 0.05: exact (0) for a linear tip map; the tip is nonlinear in the tensions along
        // the path, and the null space turns with them
        // 0.1: exactly 0 for a linear tip map; the tip is nonlinear in the tensions along the
        // path and the null space turns with them (measured 0.05 from the 1 N start)
        assert!(
            cosine < 0.1,
            "start {start:?}: change {change:?} has cosine {cosine} with the null space"
        );
        // Least-norm tensions would be orthogonal to the null space (pulling all four
        // together adds to every tension): these are far from it.
        let tau = DVector::from_column_slice(&solution.tensions[..4]);
        let share = null.dot(&tau).abs() / tau.norm();
        assert!(share > 0.3, "start {start:?}: {tau:?} is nearly least-norm ({share})");
        found.push(DVector::from_column_slice(&solution.tensions[..4]));
    }
    // Two starts, two answers that differ by co-contraction: the higher start keeps higher
    // tensions (0.1 N: far above what the 1e-6 m tolerance leaves open).
    let difference = &found[1] - &found[0];
    assert!(difference.sum() / 4.0 > 0.1, "{found:?}");
}
