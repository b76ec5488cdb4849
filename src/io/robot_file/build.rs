//! From checked tables to the library's types: the [`Robot`] and the [`SolverSettings`],
//! and back from a library validation error to the file field it is about.

use super::SolverSettings;
use super::tables::{
    BaseTable, DisksTable, EquilibriumKey, LoadsTable, MethodName, ModelTable, MotionName, RodModelKey, RodTable,
    RoutingTable, SolverTable, TendonModelKey, TendonTable, Vec3,
};
use crate::io::Problem;
use crate::io::locate::Locator;
use crate::model::loads::{Field, Loads, PointLoad};
use crate::model::rod::{Rod, Section};
use crate::model::routing::Routing;
use crate::model::tendon::{Actuation, Friction, Motion, Tendon};
use crate::report::Method;
use crate::{Disks, Error, Robot, RodModel, TendonModel, so3};
use nalgebra::{Matrix3, Vector3};

/// The matrix whose rows the file gives as `base.rotation`.
pub(super) fn rotation_from_rows(r: &[Vec3; 3]) -> Matrix3<f64> {
    Matrix3::new(
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    )
}

/// A vector of the file, zero if not given.
fn vector(v: &Option<Vec3>) -> Vector3<f64> {
    v.map_or_else(Vector3::zeros, Vector3::from)
}

/// The uniform rod of a `[rod]` table that passed its checks.
pub(super) fn uniform_rod(rod: &RodTable) -> Rod {
    let mut backbone = match (rod.poisson_ratio, rod.shear_modulus) {
        (Some(nu), _) => Rod::tube(rod.length, rod.outer_radius, rod.inner_radius, rod.youngs_modulus, nu),
        (None, g) => {
            let g = g.unwrap_or(f64::NAN);
            Rod::new(
                rod.length,
                Section::tube(rod.outer_radius, rod.inner_radius, rod.youngs_modulus, g),
            )
        }
    };
    if let Some(u) = rod.precurvature {
        backbone = backbone.with_precurvature(Vector3::from(u));
    }
    backbone
}

/// The robot of tables that passed every check (not yet validated by the library), on the
/// rod `backbone` built from `[rod]` or `[[segment]]`; `segment_ends` (m) are where its
/// segments end, for the tendons' `end_segment`.
pub(super) fn build(
    backbone: Rod,
    segment_ends: &[f64],
    base: &BaseTable,
    loads: &LoadsTable,
    tendons: &[TendonTable],
) -> Robot {
    let rotation = match (&base.rotation, &base.euler_xyz_deg) {
        (Some(rows), _) => rotation_from_rows(rows),
        (None, Some(angles)) => so3::euler_xyz(&Vector3::from(*angles).map(f64::to_radians)),
        (None, None) => Matrix3::identity(),
    };
    let loads = Loads {
        distributed_force: Field::Constant(vector(&loads.distributed_force)),
        distributed_moment: Field::Constant(vector(&loads.distributed_moment)),
        tip_force: vector(&loads.tip_force),
        tip_moment: vector(&loads.tip_moment),
        point: loads
            .point
            .iter()
            .map(|p| PointLoad {
                s: p.s,
                force: vector(&p.force),
                moment: vector(&p.moment),
            })
            .collect(),
        follower_tip_force: vector(&loads.follower_tip_force),
        follower_tip_moment: vector(&loads.follower_tip_moment),
        follower_distributed_force: Field::Constant(vector(&loads.follower_distributed_force)),
    };
    let mut robot = Robot::new(backbone)
        .with_loads(loads)
        .with_base(vector(&base.position), rotation);
    for t in tendons {
        let routing = match t.routing {
            RoutingTable::Straight {
                x: Some(x), y: Some(y), ..
            } => Routing::straight(x, y),
            RoutingTable::Straight { radius, angle_deg, .. } => {
                Routing::polar(radius.unwrap_or(f64::NAN), angle_deg.unwrap_or(f64::NAN))
            }
            RoutingTable::Helical {
                radius,
                turns_per_rod_length,
                turns,
                phase,
                angle_deg,
            } => {
                let phase = phase.or(angle_deg.map(f64::to_radians)).unwrap_or(0.0);
                Routing::helical(radius, turns_per_rod_length.or(turns).unwrap_or(f64::NAN), phase)
            }
        };
        let mut tendon = Tendon::new(routing, t.tension.unwrap_or(0.0));
        tendon.termination = t
            .end
            .or(t.end_segment.and_then(|k| segment_ends.get(k.wrapping_sub(1)).copied()));
        if let Some(displacement) = t.displacement {
            tendon.actuation = Actuation::PullIn {
                displacement,
                start: t.tension,
            };
        }
        tendon.stiffness = t.stiffness;
        tendon.free_length = t.free_length.unwrap_or(0.0);
        if t.friction.is_some() || t.motion.is_some() {
            tendon.friction = Some(Friction {
                coefficient: t.friction.unwrap_or(0.0),
                motion: match t.motion {
                    Some(MotionName::Release) => Motion::Release,
                    Some(MotionName::Pull) | None => Motion::Pull,
                },
            });
        }
        robot = robot.with_tendon(tendon);
    }
    robot
}

/// The spacer disks of a checked `[disks]` table on a rod of `length` (m): at `positions`
/// or `count` evenly spaced, each weighing `mass` times `gravity` or `weight`.
pub(super) fn disks(table: &DisksTable, length: f64) -> Disks {
    let weight = match (table.mass, table.weight) {
        (Some(mass), _) => vector(&table.gravity) * mass,
        (None, weight) => vector(&weight),
    };
    let mut out = match &table.positions {
        Some(positions) => Disks {
            positions: positions.clone(),
            weight,
            radius: None,
        },
        None => Disks::evenly(table.count.unwrap_or(0), length, weight),
    };
    out.radius = table.radius;
    out
}

/// Sets the model variant of the `[model]` table on `robot`; keys not given keep the
/// library's defaults (corner forces, the coupled tendon model, the Cosserat rod).
pub(super) fn model(robot: &mut Robot, model: &ModelTable) {
    if let Some(corners) = model.corner_forces {
        robot.corner_forces = corners;
    }
    match model.tendons {
        Some(TendonModelKey::Coupled) => robot.tendon_model = TendonModel::Coupled,
        Some(TendonModelKey::PointMoment) => robot.tendon_model = TendonModel::PointMoment,
        None => {}
    }
    match model.rod {
        Some(RodModelKey::Cosserat) => robot.rod_model = RodModel::Cosserat,
        Some(RodModelKey::Kirchhoff) => robot.rod_model = RodModel::Kirchhoff,
        None => {}
    }
}

/// The solver settings: the library defaults, changed by the `[solver]` table.
pub(super) fn settings(solver: &SolverTable) -> SolverSettings {
    let mut out = SolverSettings::default();
    if let Some(MethodName::Shooting) = solver.method {
        out.method = Method::Shooting;
    }
    let c = &mut out.collocation;
    c.intervals = solver.intervals.or(solver.nodes).unwrap_or(c.intervals);
    // `intervals` without `tolerance` asks for a fixed mesh, as `--intervals` does.
    c.tolerance = match (solver.tolerance, solver.intervals.or(solver.nodes)) {
        (Some(t), _) => Some(t),
        (None, Some(_)) => None,
        (None, None) => c.tolerance,
    };
    c.max_intervals = solver.max_intervals.or(solver.max_nodes).unwrap_or(c.max_intervals);
    c.residual_tolerance = solver.residual_tolerance.unwrap_or(c.residual_tolerance);
    c.max_iterations = solver.max_iterations.unwrap_or(c.max_iterations);
    c.continuation = solver.continuation.unwrap_or(c.continuation);
    c.equilibrium = match solver.equilibrium {
        Some(EquilibriumKey::Nearest) => crate::collocation::Equilibrium::Nearest,
        Some(EquilibriumKey::LoadPath) => crate::collocation::Equilibrium::LoadPath,
        None => c.equilibrium,
    };
    let s = &mut out.shooting;
    s.residual_tolerance = solver.residual_tolerance.unwrap_or(s.residual_tolerance);
    s.max_iterations = solver.max_iterations.unwrap_or(s.max_iterations);
    s.integration_tolerance = solver.integration_tolerance.unwrap_or(s.integration_tolerance);
    out
}

/// The file path of a field path of the library (`tendons[0].termination` ->
/// `tendon[1].end`): tendons and point loads numbered from 1, as in robot files.
pub fn file_field(field: &str, euler: bool) -> String {
    let renumber = |prefix: &str, to: &str| -> Option<String> {
        let rest = field.strip_prefix(prefix)?;
        let close = rest.find(']')?;
        let index: usize = rest[..close].parse().ok()?;
        let tail = rest[close + 1..].replace(".termination", ".end");
        Some(format!("{to}[{}]{tail}", index + 1))
    };
    if let Some(f) = renumber("tendons[", "tendon").or_else(|| renumber("loads.point[", "loads.point")) {
        return f;
    }
    match field {
        "base_position" => "base.position".into(),
        "base_rotation" if euler => "base.euler_xyz_deg".into(),
        "base_rotation" => "base.rotation".into(),
        "rod.stiffness" => "rod".into(),
        f if f.starts_with("rod.reference") => "rod.precurvature".into(),
        f => f.into(),
    }
}

/// A library validation error as a problem at the line of the field it names.
pub(super) fn library_problem(locator: &Locator, e: &Error, euler: bool) -> Problem {
    let (field, message) = match e {
        Error::InvalidInput { field, problem, hint } => (file_field(field, euler), format!("{problem}; {hint}")),
        Error::SingularRouting { tendon, .. } => (format!("tendon[{}].routing", tendon + 1), e.to_string()),
        other => (String::new(), other.to_string()),
    };
    Problem {
        position: locator.find(&field),
        field,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_paths_map_to_file_paths() {
        assert_eq!(file_field("tendons[0].termination", false), "tendon[1].end");
        assert_eq!(file_field("tendons[4].tension", false), "tendon[5].tension");
        assert_eq!(file_field("loads.point[2].s", false), "loads.point[3].s");
        assert_eq!(file_field("base_rotation", true), "base.euler_xyz_deg");
        assert_eq!(file_field("rod.length", false), "rod.length");
    }
}
