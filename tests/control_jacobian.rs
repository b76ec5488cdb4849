//! The control Jacobians (issue 26 item 1, issue 29 item 3): the columns a controller asks
//! for, from a `Solver`'s workspace, equal the stateless `tip_sensitivities` columns; the
//! backbone Jacobian equals the node derivatives at nodes and the derivative of
//! `Solution::at` between them.

use tdcr::collocation::Options;
use tdcr::collocation::sensitivity::{backbone_jacobian, tip_jacobian};
use tdcr::nalgebra::DMatrix;
use tdcr::{Parameter, Robot, Solution, Solver, TipSensitivities, cases};

/// Largest entry of `a - b` relative to the largest of `b`.
fn relative(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax()
}

/// A control step: a solver that solved `robot`, then `robot` with tendon 1 pulled harder,
/// warm-started (the chord steps run on the first solve's factors).
fn stepped(robot: &Robot) -> (Solver, Robot, Solution) {
    let mut solver = Solver::new(Options::default());
    let first = solver.solve(robot).unwrap();
    let mut next = robot.clone();
    let t = next.tendons[0].tension();
    next.tendons[0].set_tension(t + 0.05);
    let warm = solver.solve_from(&next, &first).unwrap();
    (solver, next, warm)
}

#[test]
fn solver_jacobian_equals_the_stateless_columns() {
    for robot in [cases::case_s(), cases::case_h()] {
        let (mut solver, robot, warm) = stepped(&robot);
        let tensions: Vec<Parameter> = (0..robot.tendons.len()).map(Parameter::Tension).collect();
        let j = solver.tip_jacobian(&robot, &warm, &tensions).unwrap();
        let full = tdcr::tip_sensitivities(&robot, &warm).unwrap();
        // 1e-12: the same Jacobian, right-hand sides and solves; only the factoring
        // workspace differs (rounding).
        assert!(relative(&j, &full.tension) <= 1e-12, "{j} vs {}", full.tension);
        // Only the columns asked for, in the order asked.
        let some = [Parameter::TipForce(2), Parameter::Tension(4), Parameter::YoungsModulus];
        let j = solver.tip_jacobian(&robot, &warm, &some).unwrap();
        let mut expected = DMatrix::zeros(6, 3);
        expected.set_column(0, &full.tip_force.column(2));
        expected.set_column(1, &full.tension.column(4));
        expected.set_column(2, &full.moduli.unwrap().youngs_modulus);
        for c in 0..3 {
            let (a, b) = (j.column(c).into_owned(), expected.column(c).into_owned());
            // 1e-10 relative per column: tip_sensitivities' tip force and E columns contract
            // the six tip multipliers (transposed solves) with the right-hand sides, which
            // differs from the forward solve here by rounding amplified by the condition
            // number (~1e5; tests/adjoint.rs).
            assert!((a - &b).amax() <= 1e-10 * b.amax(), "column {c}: {j} vs {expected}");
        }
        // The stateless function gives the same (both forward solves: 1e-12, rounding of
        // the factoring workspace only).
        let stateless = tip_jacobian(&robot, &warm, &some).unwrap();
        assert!(relative(&stateless, &j) <= 1e-12);
    }
}

/// After a warm solve that converged by chord steps alone (1 % more tension), the solver's
/// Jacobian factors the Jacobian its stability verdict evaluated at the solution instead of
/// assembling it again: the columns equal the stateless ones (which assemble it) to rounding.
/// The tension columns are solved for the tip alone (no back substitution through the
/// other nodes); they are bitwise the tip of the full solve for every node state.
#[test]
fn tension_columns_are_the_tip_of_the_full_solve() {
    for robot in [cases::case_s(), cases::case_h()] {
        let solution = tdcr::solve(&robot, &Options::default()).unwrap();
        let wrt: Vec<Parameter> = (0..robot.tendons.len()).map(Parameter::Tension).collect();
        let j = tip_jacobian(&robot, &solution, &wrt).unwrap();
        let mut sens = tdcr::collocation::sensitivity::Sensitivity::new(&robot, &solution).unwrap();
        for (i, _) in wrt.iter().enumerate() {
            let full = sens.tension(i).unwrap();
            let tip = full.last().unwrap().pose();
            // Bitwise: the same factors, the same replay, the same last-node substitution.
            assert_eq!(
                j.column(i).clone_owned(),
                tdcr::nalgebra::DMatrix::from_column_slice(6, 1, tip.as_slice())
            );
        }
    }
}

/// With the sparse LU as the solver's linear solver, the tip-only solve of the tension
/// columns takes the last node of a full sparse solve: the same columns as the structured
/// elimination's.
#[test]
fn tension_columns_from_the_sparse_lu_equal_the_structured_ones() {
    let robot = cases::case_h();
    let options = Options {
        linear_solver: tdcr::collocation::LinearSolver::SparseLu,
        ..Options::default()
    };
    let mut solver = Solver::new(options);
    let solution = solver.solve(&robot).unwrap();
    let wrt: Vec<Parameter> = (0..robot.tendons.len()).map(Parameter::Tension).collect();
    let sparse = solver.tip_jacobian(&robot, &solution, &wrt).unwrap();
    let blocks = tip_jacobian(&robot, &solution, &wrt).unwrap();
    // 1e-9: two factorizations of one matrix with other pivots, rounding times the
    // condition number (~1e5, tests/adjoint.rs).
    assert!(relative(&sparse, &blocks) <= 1e-9, "{sparse} vs {blocks}");
}

/// A solver that solved `robot` at 0.99 times its tensions (`before`, solution `first`) and
/// then `robot` from there (`warm`), which converges by chord steps, so its verdict evaluated
/// the Jacobian at the solution (checked): (solver, before, first, warm).
fn chord_only_warm(robot: &Robot) -> (Solver, Robot, Solution, Solution) {
    let mut solver = Solver::new(Options::default());
    let mut before = robot.clone();
    for t in before.tendons.iter_mut() {
        t.set_tension(t.tension() * 0.99);
    }
    let first = solver.solve(&before).unwrap();
    let warm = solver.solve_from(robot, &first).unwrap();
    assert_eq!(
        warm.report.newton_steps, 0,
        "chord steps only: the verdict evaluated the Jacobian"
    );
    (solver, before, first, warm)
}

#[test]
fn jacobian_after_a_chord_only_warm_solve_equals_the_stateless_one() {
    for robot in [cases::case_s(), cases::case_h()] {
        let (mut solver, _, _, warm) = chord_only_warm(&robot);
        let wrt: Vec<Parameter> = (0..robot.tendons.len())
            .map(Parameter::Tension)
            .chain([Parameter::TipForce(0), Parameter::YoungsModulus])
            .collect();
        let j = solver.tip_jacobian(&robot, &warm, &wrt).unwrap();
        let stateless = tip_jacobian(&robot, &warm, &wrt).unwrap();
        for c in 0..wrt.len() {
            let (a, b) = (j.column(c).into_owned(), stateless.column(c).into_owned());
            // 1e-12 relative per column: the same Jacobian values and right-hand sides; only
            // the factoring workspace differs (rounding).
            assert!((a - &b).amax() <= 1e-12 * b.amax(), "column {c}: {j} vs {stateless}");
        }
        // A second call (the values are now factored) gives the same again.
        let again = solver.tip_jacobian(&robot, &warm, &wrt).unwrap();
        assert!(relative(&again, &stateless) <= 1e-12);
    }
}

/// Every matrix of a [`TipSensitivities`], named, as 6-row matrices.
fn fields(t: &TipSensitivities) -> Vec<(&'static str, DMatrix<f64>)> {
    let m = |x: &[f64]| DMatrix::from_column_slice(6, 3, x);
    let mut out = vec![
        ("tension", t.tension.clone()),
        ("displacement", t.displacement.clone()),
        ("friction", t.friction.clone()),
        ("tip_force", m(t.tip_force.as_slice())),
        ("tip_moment", m(t.tip_moment.as_slice())),
        ("base_position", m(t.base_position.as_slice())),
        ("base_rotation", m(t.base_rotation.as_slice())),
    ];
    let moduli = t.moduli.expect("S and H are built from geometry");
    for (name, v) in [
        ("youngs_modulus", moduli.youngs_modulus),
        ("youngs_modulus_fixed_shear", moduli.youngs_modulus_fixed_shear),
        ("shear_modulus", moduli.shear_modulus),
    ] {
        out.push((name, DMatrix::from_column_slice(6, 1, v.as_slice())));
    }
    out
}

/// `Solver::tip_sensitivities` after a warm solve that converged by chord steps factors the
/// Jacobian the verdict evaluated at the solution (no assembly) and equals the stateless
/// `tip_sensitivities`, which assembles it, to rounding; for a solution that is not the
/// solver's last it assembles the Jacobian, as the stateless function does: the same bits.
#[test]
fn solver_tip_sensitivities_equal_the_stateless_ones() {
    for robot in [cases::case_s(), cases::case_h()] {
        let (mut solver, before, first, warm) = chord_only_warm(&robot);
        let ours = solver.tip_sensitivities(&robot, &warm).unwrap();
        let stateless = tdcr::tip_sensitivities(&robot, &warm).unwrap();
        for ((name, a), (_, b)) in fields(&ours).into_iter().zip(fields(&stateless)) {
            // 1e-12 relative per matrix: the same Jacobian values, right-hand sides and
            // solves; only the factored values' origin (the verdict's evaluation, not an
            // assembly) and the workspace differ (rounding).
            let scale = b.amax();
            assert!((&a - &b).amax() <= 1e-12 * scale, "{name}: {a} vs {b}");
            if name != "displacement" && name != "friction" {
                assert!(scale > 0.0, "{name} is not all zero");
            }
        }
        // A second call (the values are now factored) gives the same bits as the first.
        assert_eq!(solver.tip_sensitivities(&robot, &warm).unwrap(), ours);
        // The first solution, on the same mesh but not the one the last solve ended at:
        // the Jacobian is assembled in the solver's workspace, as the stateless function
        // assembles it in its own: the same code path, the same bits.
        let other = solver.tip_sensitivities(&before, &first).unwrap();
        assert_eq!(other, tdcr::tip_sensitivities(&before, &first).unwrap());
        assert_ne!(other.tension, ours.tension, "a different solution");
    }
}

#[test]
fn warm_solves_after_a_jacobian_equal_stateless_warm_solves() {
    let (mut solver, mut robot, warm) = stepped(&cases::case_h());
    let tensions: Vec<Parameter> = (0..5).map(Parameter::Tension).collect();
    solver.tip_jacobian(&robot, &warm, &tensions).unwrap();
    let t = robot.tendons[4].tension();
    robot.tendons[4].set_tension(t + 0.05);
    // The next warm solve runs its chord steps on the factors the Jacobian left (at the
    // previous solution); the stateless one builds its own.
    let stateful = solver.solve_from(&robot, &warm).unwrap();
    let stateless = tdcr::solve_from(&robot, &Options::default(), &warm).unwrap();
    assert_eq!(stateful.nodes.len(), stateless.nodes.len());
    // 1e-12 m on a 0.24 m rod: both converge on the same mesh to the Newton stop's
    // rounding-level step (STEP_TOLERANCE), far below the discretization error.
    let gap = (stateful.tip_position() - stateless.tip_position()).norm();
    assert!(gap <= 1e-12, "tips {gap:e} m apart");
    let j = solver.tip_jacobian(&robot, &stateful, &tensions).unwrap();
    let full = tdcr::tip_sensitivities(&robot, &stateful).unwrap();
    // 1e-12: as in solver_jacobian_equals_the_stateless_columns.
    assert!(relative(&j, &full.tension) <= 1e-12);
}

#[test]
fn reset_forgets_the_workspace() {
    let (mut solver, robot, warm) = stepped(&cases::case_s());
    solver.reset();
    let again = solver.solve_from(&robot, &warm).unwrap();
    let fresh = Solver::new(Options::default()).solve_from(&robot, &warm).unwrap();
    assert_eq!(again.tip_position(), fresh.tip_position());
}

#[test]
fn backbone_jacobian_matches_node_derivatives_and_differences() {
    let robot = cases::case_h();
    let options = Options {
        tolerance: None,
        intervals: 32,
        ..Default::default()
    };
    let solution = tdcr::solve(&robot, &options).unwrap();
    let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let wrt = [Parameter::Tension(4), Parameter::TipForce(0)];
    let j = backbone_jacobian(&robot, &solution, &wrt, &s).unwrap();
    let nodes = tdcr::backbone_tension_sensitivity(&robot, &solution, 4).unwrap();
    for (k, dp) in nodes.iter().enumerate() {
        let row = j.fixed_view::<3, 1>(3 * k, 0).into_owned();
        // 1e-12 relative: the node derivative itself (Hermite weights 1 and 0).
        assert!((row - dp).norm() <= 1e-12 * dp.norm().max(1e-3), "node {k}");
    }
    // Between nodes: central differences of solution.at(s).p over full solves on the same
    // mesh (fixed intervals), step 1e-4 of the tension.
    let between: Vec<f64> = s.windows(2).step_by(5).map(|w| 0.37 * w[0] + 0.63 * w[1]).collect();
    let j = backbone_jacobian(&robot, &solution, &wrt, &between).unwrap();
    let h = 1e-4 * robot.tendons[4].tension();
    let moved = |dq: f64| {
        let mut r = robot.clone();
        let t = r.tendons[4].tension();
        r.tendons[4].set_tension(t + dq);
        tdcr::solve(&r, &options).unwrap()
    };
    let (plus, minus) = (moved(h), moved(-h));
    for (i, &si) in between.iter().enumerate() {
        let fd = (plus.at(si).p - minus.at(si).p) / (2.0 * h);
        let row = j.fixed_view::<3, 1>(3 * i, 0).into_owned();
        // 1e-6 relative: the difference's truncation (h_rel^2 = 1e-8) and the solves'
        // Newton stop (residual 1e-11 over h = 5e-4 N) leave about 1e-7.
        assert!((row - fd).norm() <= 1e-6 * fd.norm(), "s = {si}: {row} vs {fd}");
    }
}

#[test]
fn control_jacobian_errors_name_the_problem() {
    let robot = cases::case_s();
    let solution = tdcr::solve(&robot, &Options::default()).unwrap();
    let err = tip_jacobian(&robot, &solution, &[Parameter::LoadScale]).unwrap_err();
    assert!(err.to_string().contains("not a column"), "{err}");
    let err = tip_jacobian(&robot, &solution, &[Parameter::Tension(7)]).unwrap_err();
    assert!(err.to_string().contains("tendon 8"), "{err}");
    let err = backbone_jacobian(&robot, &solution, &[Parameter::Tension(0)], &[0.5]).unwrap_err();
    assert!(err.to_string().contains("outside the rod"), "{err}");
}

/// With `keep_tension_columns`, a warm solve that converged by chord steps forms the
/// tension columns' right-hand sides with its verdict's Jacobian, and the solver's tension
/// Jacobian takes them: the solve's answer is the same bits as without, the columns equal
/// the stateless ones to rounding, on S and H, in a loop of control steps and for columns
/// asked for with others.
#[test]
fn tension_columns_formed_by_the_verdict_equal_the_stateless_ones() {
    for robot in [cases::case_s(), cases::case_h()] {
        let mut kept = Solver::new(Options::default());
        kept.keep_tension_columns(true);
        let mut plain = Solver::new(Options::default());
        let mut before = robot.clone();
        for t in before.tendons.iter_mut() {
            t.set_tension(t.tension() * 0.99);
        }
        let (mut a, mut b) = (kept.solve(&before).unwrap(), plain.solve(&before).unwrap());
        let tensions: Vec<Parameter> = (0..robot.tendons.len()).map(Parameter::Tension).collect();
        let mut next = robot.clone();
        for step in 0..3 {
            if step > 0 {
                let t = next.tendons[step].tension();
                next.tendons[step].set_tension(t + 0.02);
            }
            (a, b) = (
                kept.solve_from(&next, &a).unwrap(),
                plain.solve_from(&next, &b).unwrap(),
            );
            // The same answer, bit for bit: the columns are formed beside the Jacobian.
            assert_eq!(a.nodes, b.nodes, "step {step}");
            let j = kept.tip_jacobian(&next, &a, &tensions).unwrap();
            // The same factors for both solvers' next warm solves (the Jacobian at this
            // answer).
            plain.tip_jacobian(&next, &b, &tensions).unwrap();
            let stateless = tip_jacobian(&next, &a, &tensions).unwrap();
            // 1e-12: the same Jacobian and factoring; the right-hand sides differ in
            // rounding (the midpoints' chain rule, docs/sensitivity.md).
            assert!(relative(&j, &stateless) <= 1e-12, "step {step}: {j} vs {stateless}");
            let some = [Parameter::TipForce(1), Parameter::Tension(2)];
            let j = kept.tip_jacobian(&next, &a, &some).unwrap();
            let stateless = tip_jacobian(&next, &a, &some).unwrap();
            // 1e-12: as above.
            assert!(relative(&j, &stateless) <= 1e-12, "step {step}: {j} vs {stateless}");
        }
        assert_eq!(
            a.report.newton_steps, 0,
            "chord steps only: the verdict evaluated the Jacobian"
        );
    }
}
