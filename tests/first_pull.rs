//! The tension column of a tendon with friction at 0 N (the one-sided derivative at 0+, the
//! response to its first pull: docs/friction.md section 3, "Sensitivities") against
//! differences of full solves at small tensions on the same mesh (64 intervals):
//! (tip(h) - tip(0)) / h at h = 1e-3, 1e-4 and 1e-5 N converges to it linearly in h, and its
//! Richardson extrapolation from the two smallest steps agrees with it. A straight tendon
//! (case S's second tendon, case S's own pulling) and a helical one (case H's fifth, its
//! first pulling), each pulled and released.

use nalgebra::Vector6;
use tdcr::collocation::sensitivity::{tip_jacobian, tip_sensitivities};
use tdcr::collocation::{self, Options};
use tdcr::{Friction, Motion, Parameter, Robot, Solution, cases, so3};

/// Tip noise of a full solve (m), 3e-12: measured over the columns of tests/sensitivity.rs
/// at this mesh and residual tolerance.
const NOISE: f64 = 3e-12;

fn options() -> Options {
    Options {
        intervals: 64,
        tolerance: None,
        // Newton to its rounding floor (about 1e-14), so that a step of 1e-5 N resolves
        // the tip's change (tests/sensitivity.rs).
        residual_tolerance: 1e-12,
        ..Default::default()
    }
}

/// Tip pose of `robot` relative to `reference`'s (position, then the world-frame rotation
/// vector weighted by the rod length, so both halves are in metres), solved warm from it on
/// its mesh.
fn tip_offset(robot: &Robot, reference: &Solution) -> Vector6<f64> {
    let solution = collocation::solve_from(robot, &options(), reference).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(solution.nodes.len(), reference.nodes.len(), "the mesh must not change");
    let (a, b) = (solution.tip(), reference.tip());
    let w = so3::log(&(a.R * b.R.transpose())) * robot.length();
    Vector6::new(a.p.x - b.p.x, a.p.y - b.p.y, a.p.z - b.p.z, w.x, w.y, w.z)
}

/// The rotation rows weighted by the rod length (as [`tip_offset`]).
fn weigh(mut v: Vector6<f64>, length: f64) -> Vector6<f64> {
    v.fixed_rows_mut::<3>(3).scale_mut(length);
    v
}

/// Checks tendon `tendon` (at 0 N, with friction `mu` in `motion`) of `robot`: the column of
/// `tip_sensitivities` and of `tip_jacobian` against the differences of solves.
fn check(name: &str, robot: &Robot, tendon: usize, mu: f64, motion: Motion) {
    let mut robot = robot.clone();
    robot.tendons[tendon].set_tension(0.0);
    robot.tendons[tendon].friction = Some(Friction {
        coefficient: mu,
        motion,
    });
    let reference = collocation::solve(&robot, &options()).unwrap_or_else(|e| panic!("{e}"));
    let length = robot.length();
    let column = weigh(
        Vector6::from_iterator(
            tip_sensitivities(&robot, &reference)
                .unwrap()
                .tension
                .column(tendon)
                .iter()
                .copied(),
        ),
        length,
    );
    let jacobian = tip_jacobian(&robot, &reference, &[Parameter::Tension(tendon)]).unwrap();
    assert_eq!(
        weigh(Vector6::from_iterator(jacobian.column(0).iter().copied()), length),
        column,
        "{name}: the control Jacobian's column is tip_sensitivities'"
    );
    let quotient = |h: f64| {
        let mut pulled = robot.clone();
        pulled.tendons[tendon].set_tension(h);
        tip_offset(&pulled, &reference) / h
    };
    let steps = [1e-3, 1e-4, 1e-5];
    let d: Vec<Vector6<f64>> = steps.iter().map(|&h| quotient(h)).collect();
    // Linear in h: d(h) = D + c h + O(h^2), so from steps 10 times apart the extrapolation
    // (10 d(h / 10) - d(h)) / 9 removes the c h term.
    let extrapolated = (d[2] * 10.0 - d[1]) / 9.0;
    let error = (column - extrapolated).norm() / extrapolated.norm();
    let coarse = ((d[1] * 10.0 - d[0]) / 9.0 - column).norm() / column.norm();
    let errors: Vec<f64> = d.iter().map(|x| (x - column).norm() / column.norm()).collect();
    eprintln!(
        "{name}: |column| = {:.4e} m/N; (tip(h) - tip(0)) / h off by {:.2e}, {:.2e}, {:.2e} at h = 1e-3, 1e-4, \
         1e-5 N; extrapolated {error:.2e} (from 1e-3 and 1e-4 N: {coarse:.2e})",
        column.norm(),
        errors[0],
        errors[1],
        errors[2]
    );
    // The quotients converge to the column linearly: a step 10 times smaller leaves an
    // error 10 times smaller (measured 9.96-10.03 from 1e-3 to 1e-4 N, where the solves'
    // rounding is 100 times below the error; 8 and 12 bound it). A column of another limit
    // (the log tensions left at 0) would leave an error that levels off instead.
    let ratio = errors[0] / errors[1];
    assert!(
        (8.0..=12.0).contains(&ratio),
        "{name}: errors {errors:?} do not fall linearly in h"
    );
    // The extrapolation's own error: its truncation, about the quotients' curvature times
    // h^2 (1e-10 relative at these steps), and the solves' rounding, up to NOISE on each tip
    // (m), which (10 d(1e-5) - d(1e-4)) / 9 carries as (10 / 1e-5 + 1 / 1e-4) / 9 NOISE;
    // 1e-7 relative adds the column's own forward difference of the residual (about 1e-8).
    let floor = (10.0 / steps[2] + 1.0 / steps[1]) / 9.0 * NOISE;
    assert!(
        (column - extrapolated).norm() <= 1e-7 * extrapolated.norm() + floor,
        "{name}: column {column:?} against {extrapolated:?} ({error:.2e}, rounding floor {:.1e})",
        floor / extrapolated.norm()
    );
    // The cleaner figure of docs/friction.md, from 1e-3 and 1e-4 N, where the rounding
    // carried (about 3e-12 m / 1e-4 N) is small beside the column: 2e-7, a margin of 2.7
    // over the largest measured (2.4e-8 to 7.5e-8 relative in the four cases).
    assert!(
        coarse <= 2e-7,
        "{name}: the extrapolation from 1e-3 and 1e-4 N is off by {coarse:.2e}"
    );
    // The friction matters: the column of the same tendon without friction (constant
    // tension along it) is another one, by far more than the tolerances above.
    let mut smooth = robot.clone();
    smooth.tendons[tendon].friction = None;
    let plain = tip_sensitivities(&smooth, &collocation::solve(&smooth, &options()).unwrap()).unwrap();
    let plain = weigh(
        Vector6::from_iterator(plain.tension.column(tendon).iter().copied()),
        length,
    );
    let moved = (plain - column).norm() / column.norm();
    eprintln!("  without friction on it the column differs by {moved:.2e}");
    assert!(moved > 1e-3, "{name}: friction moves the column by only {moved:.2e}");
}

/// Case S with its tendon 1 pulled (2.94 N, mu = 0.1) and tendon 2 (straight, 90 degrees
/// round) unloaded with friction, pulled and released.
#[test]
fn first_pull_of_a_straight_tendon_matches_solves_at_small_tensions() {
    let mut s = cases::case_s();
    s.tendons[0].friction = Some(Friction::pull(0.1));
    check("case S, tendon 2, pull", &s, 1, 0.1, Motion::Pull);
    check("case S, tendon 2, release", &s, 1, 0.1, Motion::Release);
}

/// Case H with its helical tendon 5 unloaded with friction (mu = 0.2) and tendon 1 pulling
/// (2 N): the helix turns by itself, so z* falls (pull) or rises (release) even where the
/// backbone is straight.
#[test]
fn first_pull_of_a_helical_tendon_matches_solves_at_small_tensions() {
    let mut h = cases::case_h();
    h.tendons[0].set_tension(2.0);
    check("case H, tendon 5, pull", &h, 4, 0.2, Motion::Pull);
    check("case H, tendon 5, release", &h, 4, 0.2, Motion::Release);
}

/// Inverse statics with friction on every tendon, all free, starting with two of them at
/// 0 N: the linearization there takes their first-pull columns (it refused before), and the
/// tensions that made the target are found.
#[test]
fn inverse_statics_starts_from_unloaded_tendons_with_friction() {
    use tdcr::fit::inverse::{InverseOptions, Target, solve_tensions};
    let mut robot = cases::case_s();
    for (i, mu) in [(0, 0.1), (1, 0.1), (2, 0.2)] {
        robot.tendons[i].friction = Some(Friction::pull(mu));
    }
    robot.tendons[0].set_tension(2.0);
    robot.tendons[1].set_tension(0.5);
    let options = InverseOptions::new(5.0);
    let goal = collocation::solve(&robot, &options.solver).unwrap().tip_position();
    robot.tendons[0].set_tension(0.5);
    robot.tendons[1].set_tension(0.0);
    assert_eq!(robot.tendons[2].tension(), 0.0);
    let found = solve_tensions(&robot, &Target::position(goal), &options).unwrap_or_else(|e| panic!("{e}"));
    eprintln!(
        "inverse: tensions {:?}, reachable {}, position error {:.2e} m, {} iterations",
        found.tensions, found.reachable, found.position_error, found.iterations
    );
    assert!(found.reachable, "{:?}", found.termination);
    assert!((found.tip_position() - goal).norm() <= options.tolerance);
}
