//! Load continuation for a robot whose direct Newton solve failed: ramp the loads from an
//! easier problem, each step warm-started from the last.

use super::newton::{self, Settings, Workspace};
use super::system::System;
use crate::mesh::guess::rigid_estimate;
use crate::report::{SolveReport, Termination};
use crate::solution::State;

/// What load continuation ramps.
#[derive(Clone, Copy, PartialEq)]
enum Ramp {
    /// External loads, with the tendons at full tension.
    Loads,
    /// Tensions and external loads together.
    All,
}

/// Load continuation on `system` (whose direct solve failed). First, when the robot has
/// both tendons and external loads, the tensions stay and the external loads are ramped:
/// the tendon-only shape is the one the rigid estimate gets (nearly) right. Failing that,
/// everything is ramped from the unloaded shape. Each step warm-starts from the last; the
/// step halves on failure and grows by half after a success. Returns the states, or a hint
/// and the worst residual row.
pub(super) fn run(
    system: &mut System,
    ws: &mut Workspace,
    settings: &Settings,
    report: &mut SolveReport,
) -> std::result::Result<Vec<State>, (String, usize)> {
    let robot = system.model.robot;
    let loaded = system.model.point_wrench(robot.length()) != Default::default()
        || !robot.loads.point.is_empty()
        || system.mesh.nodes.iter().any(|n| {
            let site = system.model.site(n.s);
            site.f_e != nalgebra::Vector3::zeros() || site.l_e != nalgebra::Vector3::zeros()
        });
    let pulled = robot.tendons.iter().any(|t| t.tension > 0.0);
    let ramps: &[Ramp] = if loaded && pulled {
        &[Ramp::Loads, Ramp::All]
    } else {
        &[Ramp::All]
    };
    let factors = |ramp: Ramp, lambda: f64| {
        if ramp == Ramp::Loads {
            (1.0, lambda)
        } else {
            (lambda, lambda)
        }
    };
    let mut failure = (String::new(), 0);
    for &ramp in ramps {
        let (t, l) = factors(ramp, 0.0);
        system.set_factors(t, l);
        let mut x = rigid_estimate(&system.model, &system.mesh.nodes);
        report.load_steps += 1;
        let (start, row) = newton::run(system, ws, &mut x, settings, report);
        if start != Termination::Converged {
            report.termination = start;
            failure = (
                "the starting problem of load continuation did not converge: refine the mesh".into(),
                row,
            );
            continue;
        }
        // Each load step starts from the last converged one, whose factors are in `ws`.
        let step_settings = Settings {
            reuse_factors: true,
            ..*settings
        };
        let (mut lambda, mut dl): (f64, f64) = (0.0, 0.25);
        while lambda < 1.0 {
            let target = (lambda + dl).min(1.0);
            let (t, l) = factors(ramp, target);
            system.set_factors(t, l);
            let mut trial = x.clone();
            report.load_steps += 1;
            let (term, row) = newton::run(system, ws, &mut trial, &step_settings, report);
            report.termination = term;
            if term == Termination::Converged {
                lambda = target;
                x = trial;
                dl *= 1.5;
            } else {
                dl *= 0.5;
                // 1e-4 of the full load: the solution is not continuous in the load, or
                // there is none nearby (buckling, a tendon losing its tangent).
                if dl < 1e-4 {
                    failure = (
                        format!(
                            "load continuation stalled at {:.1} % of the load; refine the mesh or check for buckling",
                            lambda * 100.0
                        ),
                        row,
                    );
                    break;
                }
            }
        }
        if lambda >= 1.0 {
            return Ok(x);
        }
    }
    Err(failure)
}
