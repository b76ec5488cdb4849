//! The stability verdict of tendons with friction held at their pull-ins (docs/stability.md,
//! "Tendons with friction", "Friction with displacement control"): the linearized dynamics
//! of the system bordered by the capstan (or stick) rows of [`super::friction`] and, per
//! taut displacement-controlled tendon j, its length condition Q_j(x, z, tau_j(0)) = q_j
//! with the base-entry tension tau_j(0) as a massless unknown, as `collocation/constrained.rs`
//! borders the frictionless system.
//!
//! Each Arnoldi step solves
//!
//! ```text
//! [ B     b_tau ] [a]   [M phi]
//! [ dQ    C     ] [t] = [  0  ]
//! ```
//!
//! with B the bordered Jacobian of [`super::friction`] (factored at the answer), b_tau its
//! columns in the base tensions at fixed (x, z), dQ the pull-ins' change along (x, z) at fixed
//! base tensions and C their compliances (docs/friction.md section 3b). With
//! a0 = B^-1 M phi and D_m = -B^-1 b_tau_m = d(x, z)/dtau_m (one bordered solve per held
//! tendon, once), S = C + dQ D = dQ/dtau (the Schur complement of the held derivatives,
//! [`TensionDirections`]) gives t = -S^-1 dQ a0 and a = a0 + D t: the state follows the
//! tensions the pull-ins hold.

use super::Vibration;
use crate::Robot;
use crate::collocation::friction::{Capstan, Profile};
use crate::collocation::sensitivity::TensionDirections;
use crate::collocation::system::System;
use crate::mesh::Mesh;
use crate::model::equations::Model;
use crate::report::{SolveReport, Stability};
use crate::solution::{Solution, State};
use std::time::Instant;

/// Relative step of the central difference of the residual in a held base tension: the
/// rows are linear in it but for the stick rows' ln(tau_stuck / tau(0)), whose truncation is
/// 1e-10 relative at this step, and the rounding of rows of order 1 about 1e-11 / tau.
const STEP: f64 = 1e-5;

/// The taut displacement-controlled tendons of `robot` at `solution`: those whose pull-in
/// holds (a slack one, at 0 N, constrains nothing and stays slack for small motions).
fn held(robot: &Robot, solution: &Solution) -> Vec<usize> {
    (0..robot.tendons.len())
        .filter(|&i| {
            let state = &solution.tendons[i];
            robot.tendons[i].displacement().is_some() && state.slack == 0.0 && state.tension > 0.0
        })
        .collect()
}

/// The residual (F, psi) of `border`'s system at `x` with tendon `i`'s base tension `tension`
/// (the same mesh, log tensions and stick/slip pattern) into `out`.
fn moved_residual(border: &Capstan, x: &[State], i: usize, tension: f64, out: &mut [f64]) -> crate::Result<()> {
    let own = border.system();
    let mut model = Model::new(own.model.robot);
    model.tensions[i] = tension;
    let mut system = System::new(model.clone(), own.mesh.clone());
    if let Some(profile) = &own.friction {
        let mut moved = Profile::new(&model, &system.mesh);
        moved.z.clone_from(&profile.z);
        moved.grips.clone_from(&profile.grips);
        moved.deliver(&mut system.model);
        system.friction = Some(moved);
    }
    border.residual_of(&system, x, out)
}

/// The verdict of the equilibrium `x` of `border`'s system (`robot`'s at the solved tensions,
/// tension-controlled) with `original`'s taut displacement-controlled tendons held at their
/// pull-ins (module docs), `solution` the answer (its tendon states and nodes): the bordered
/// Jacobian evaluated and factored at `x` (counted in `report`).
pub(crate) fn assess(
    original: &Robot,
    solution: &Solution,
    border: &mut Capstan,
    x: &[State],
    report: &mut SolveReport,
) -> Stability {
    held_modes(original, solution, border, x, report, super::KRYLOV, false).stability
}

/// [`assess`] with the eigenvalues, from `krylov` Arnoldi steps as [`super::modes`] takes
/// them.
fn held_modes(
    original: &Robot,
    solution: &Solution,
    border: &mut Capstan,
    x: &[State],
    report: &mut SolveReport,
    krylov: usize,
    all: bool,
) -> Vibration {
    let unknown = |reason: String| Vibration {
        stability: Stability::Unknown { reason },
        eigenvalues: Vec::new(),
    };
    let multipliers = match super::friction::factor_at(border, x, report) {
        Ok(m) => m,
        Err(stability) => {
            return Vibration {
                stability,
                eigenvalues: Vec::new(),
            };
        }
    };
    let tendons = held(original, solution);
    let k = tendons.len();
    let n = border.system().unknowns();
    let rows = border.border_rows();
    let mut directions = TensionDirections::layout(solution, border, tendons.clone());
    let mut columns: Vec<Vec<f64>> = Vec::with_capacity(k);
    let (mut plus, mut minus) = (vec![0.0; n + rows], vec![0.0; n + rows]);
    for (m, &i) in tendons.iter().enumerate() {
        let tension = solution.tendons[i].tension;
        let h = STEP * tension;
        if let Err(e) = moved_residual(border, x, i, tension + h, &mut plus)
            .and_then(|()| moved_residual(border, x, i, tension - h, &mut minus))
        {
            return unknown(format!("the residual at a held tension could not be evaluated: {e}"));
        }
        // B D_m = -b_tau_m, b_tau_m = d(F, psi)/dtau_m at fixed (x, z).
        let rhs: Vec<f64> = plus.iter().zip(&minus).map(|(p, q)| -(p - q) / (2.0 * h)).collect();
        let mut dx = vec![0.0; n];
        if !border.solve_with_factors(&rhs[..n], &rhs[n..], &mut dx) {
            return unknown("the bordered solve for a held tension's direction failed".into());
        }
        directions.set_direction(m, &dx, x, border);
        columns.push(dx);
    }
    let Some(schur) = (k > 0).then(|| directions.displacement_by_tension().lu()) else {
        return super::friction::modes_held(border, x, krylov, all, Some(&multipliers), &mut |_, _| true);
    };
    let mut project = |border: &Capstan, a: &mut [f64]| -> bool {
        let change = directions.change_along(a, x, border);
        let Some(t) = schur.solve(&change) else {
            return false;
        };
        for (column, t) in columns.iter().zip(t.iter()) {
            for (a, d) in a.iter_mut().zip(column) {
                *a += d * t;
            }
        }
        true
    };
    super::friction::modes_held(border, x, krylov, all, Some(&multipliers), &mut project)
}

/// [`assess`] for a full-slip solve with friction and displacement control: `solution` of
/// `robot` (its pull-ins held), linearized at its solved tensions on its own mesh, with the
/// note of the full-slip verdict's scope; the time goes to the report's stability timing.
pub(crate) fn assess_solution(robot: &Robot, solution: &mut Solution) {
    let t = Instant::now();
    let solved = robot.with_tensions(&solution.tensions());
    let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mut report = solution.report.clone();
    report.stability = match Mesh::from_points(&solved, &s) {
        Ok(mesh) => {
            let mut border = Capstan::at_solution(Model::new(&solved), mesh, solution);
            let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
            assess(robot, solution, &mut border, &x, &mut report)
        }
        Err(e) => Stability::Unknown {
            reason: format!("the solution's mesh could not be rebuilt: {e}"),
        },
    };
    if !matches!(report.stability, Stability::Unknown { .. }) {
        report.notes.push(super::friction::SLIP_HELD.into());
    }
    let spent = t.elapsed();
    report.timings.stability += spent;
    report.timings.total += spent;
    solution.report = report;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::constrained::Border;
    use crate::collocation::dynamics::{KRYLOV_MODES, modes, vibration};
    use crate::model::tendon::Friction;
    use crate::report::Method;

    /// The lowest modes of the frictionless `robot`'s `solution` with its taut pull-ins held
    /// (`collocation/constrained.rs`'s border in the linearized dynamics).
    fn constrained_modes(robot: &Robot, solution: &Solution) -> Vibration {
        let (system, x, mut ws, mut report) = crate::collocation::test_support::linearized_at(robot, solution);
        let border = Border::new(&system, &x, &mut ws, &mut report).unwrap();
        modes(
            &system,
            &x,
            &mut ws,
            KRYLOV_MODES,
            true,
            &mut |a| border.project(&x, a),
            false,
        )
    }

    /// The held modes of a solution with friction, as [`assess_solution`] computes them.
    fn friction_modes(robot: &Robot, solution: &Solution) -> Vibration {
        let solved = robot.with_tensions(&solution.tensions());
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(&solved, &s).unwrap();
        let mut border = Capstan::at_solution(Model::new(&solved), mesh, solution);
        let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
        let mut report = SolveReport::new(Method::Collocation);
        held_modes(robot, solution, &mut border, &x, &mut report, KRYLOV_MODES, true)
    }

    #[test]
    fn vanishing_friction_held_at_a_pull_in_gives_the_constrained_frictionless_modes() {
        // Case S's tendon 1 held at 5 mm, rigid and elastic (E_t A_t = 2000 N).
        for stiffness in [None, Some(2000.0)] {
            let mut robot = crate::cases::case_s();
            robot.tendons[0].stiffness = stiffness;
            robot.tendons[0].set_displacement(0.005);
            let frictionless = crate::collocation::solve(&robot, &Default::default()).unwrap();
            assert_eq!(frictionless.report.stability, Stability::Stable);
            let want = constrained_modes(&robot, &frictionless);
            let free = vibration(&robot.with_tensions(&frictionless.tensions()), &frictionless).unwrap();
            let mut rough = robot.clone();
            rough.tendons[0].friction = Some(Friction::pull(1e-9));
            let solution = crate::collocation::solve(&rough, &Default::default()).unwrap();
            assert_eq!(solution.report.stability, Stability::Stable, "{stiffness:?}");
            let notes = &solution.report.notes;
            assert!(
                notes.iter().any(|n| n == super::super::friction::SLIP_HELD),
                "{notes:?}"
            );
            let got = friction_modes(&rough, &solution);
            for ((g, w), f) in got
                .eigenvalues
                .iter()
                .zip(&want.eigenvalues)
                .zip(&free.eigenvalues)
                .take(4)
            {
                eprintln!("{stiffness:?}: held with friction {g}, held frictionless {w}, free tension {f}");
                // 1e-7 relative (measured 6.4e-10): the two borders' tension columns are
                // differenced (forward there, central here) and mu = 1e-9 moves the modes
                // by about 1e-9
                assert!((g - w).norm() <= 1e-7 * w.norm(), "{stiffness:?}: {g} against {w}");
            }
            // The pull-in matters: held, the bending mode in the tendon's plane is more than
            // twice as stiff as at constant tension (measured 10162 against 4218 1/s^2 rigid,
            // 9709 against 4212 elastic).
            assert!(
                got.eigenvalues[1].re > 2.0 * free.eigenvalues[1].re,
                "{got:?} against {free:?}"
            );
        }
    }

    /// The held tension directions' Schur complement S = dQ/dtau from this module's
    /// differenced tension columns (one bordered solve each, at the answer's own factors)
    /// is the one [`TensionDirections::new`] forms through [`crate::collocation::sensitivity`]
    /// (checked there against central differences of held pull-in solves,
    /// tests/friction_pull_in.rs): case S held at 12 mm with tendon 2 at 1 N, mu 0.1 pull and
    /// release, elastic.
    #[test]
    fn the_held_directions_are_the_sensitivities_ones() {
        for motion in [
            crate::model::tendon::Motion::Pull,
            crate::model::tendon::Motion::Release,
        ] {
            let mut robot = crate::cases::case_s();
            robot.tendons[0].friction = Some(Friction {
                coefficient: 0.1,
                motion,
            });
            robot.tendons[0].stiffness = Some(2000.0);
            robot.tendons[0].set_displacement(0.012);
            robot.tendons[1].set_tension(1.0);
            let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
            let solved = robot.with_tensions(&solution.tensions());
            let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
            let mesh = Mesh::from_points(&solved, &s).unwrap();
            let mut border = Capstan::at_solution(Model::new(&solved), mesh, &solution);
            let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
            let mut report = SolveReport::new(Method::Collocation);
            assert!(border.factor_at(&x, &mut report).unwrap());
            let tendons = held(&robot, &solution);
            assert_eq!(tendons, vec![0]);
            let mut ours = TensionDirections::layout(&solution, &border, tendons.clone());
            let n = border.system().unknowns();
            let (mut plus, mut minus) = (vec![0.0; n + border.border_rows()], vec![0.0; n + border.border_rows()]);
            let tension = solution.tendons[0].tension;
            let h = STEP * tension;
            moved_residual(&border, &x, 0, tension + h, &mut plus).unwrap();
            moved_residual(&border, &x, 0, tension - h, &mut minus).unwrap();
            let rhs: Vec<f64> = plus.iter().zip(&minus).map(|(p, q)| -(p - q) / (2.0 * h)).collect();
            let mut dx = vec![0.0; n];
            assert!(border.solve_with_factors(&rhs[..n], &rhs[n..], &mut dx));
            ours.set_direction(0, &dx, &x, &border);
            let theirs = TensionDirections::new(&robot, &solution, tendons).unwrap();
            let (a, b) = (ours.displacement_by_tension(), theirs.displacement_by_tension());
            let tip = (&ours.tip - &theirs.tip).norm() / theirs.tip.norm();
            eprintln!(
                "{motion:?}: S {} against {}, tip column {tip:e} relative",
                a[(0, 0)],
                b[(0, 0)]
            );
            // 1e-6 relative (measured 5e-8 and 3e-8): both tension columns are differenced
            // residuals (this one central with step 1e-5 tau, the sensitivities' their own)
            assert!(((a[(0, 0)] - b[(0, 0)]) / b[(0, 0)]).abs() < 1e-6, "{a} against {b}");
            assert!(tip < 1e-6, "{tip}");
        }
    }
}
