//! Writing a robot file: the inverse of the reader, for robots built in code or edited
//! (Python pickles a robot as its file).

use super::tables::{EquilibriumKey, RodModelKey, TendonModelKey};
use super::{RobotFile, SolverSettings};
use crate::collocation::Equilibrium;
use crate::error::{Result, invalid};
use crate::model::loads::Field;
use crate::model::rod::{ReferenceStrains, Stiffness};
use crate::model::routing::Routing;
use crate::model::tendon::{Actuation, Motion};
use crate::report::Method;
use nalgebra::{Matrix3, Vector3};
use toml::{Table, Value};

fn vector(v: &Vector3<f64>) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

fn rows(r: &Matrix3<f64>) -> Value {
    Value::Array(
        (0..3)
            .map(|i| vector(&Vector3::new(r[(i, 0)], r[(i, 1)], r[(i, 2)])))
            .collect(),
    )
}

fn constant(field: &Field, name: &str) -> Result<Vector3<f64>> {
    match field {
        Field::Constant(v) => Ok(*v),
        Field::Varying(_) => Err(invalid(
            format!("loads.{name}"),
            "varies along the rod, which a robot file cannot hold",
            "keep such a robot in code",
        )),
    }
}

impl RobotFile {
    /// The robot file of this robot and its settings (docs/robot-file.md): every value
    /// written so that [`crate::io::parse`] of the text gives the same robot bitwise (TOML
    /// floats are written in their shortest round-trip form), the `[solver]` table with every
    /// key. The `[disks]` table is written (with its `positions` and `weight`) when the
    /// robot's last point loads are still the disks' weights; if they were changed since
    /// (a load scale, say), every point load is written as `[[loads.point]]` and the disks
    /// are left out, so the robot still reads back the same.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] on `robot` for what a robot file cannot hold: a rod
    /// given by its stiffnesses rather than its geometry, reference strains other than a
    /// constant precurvature, loads that vary along the rod, a custom routing, a
    /// displacement-controlled tendon with a starting tension other than 0.
    ///
    /// # Examples
    /// ```
    /// let file = tdcr::io::parse(&tdcr::io::example(), "example.toml").unwrap();
    /// let back = tdcr::io::parse(&file.to_toml().unwrap(), "again.toml").unwrap();
    /// assert_eq!(format!("{:?}", back.robot), format!("{:?}", file.robot));
    /// ```
    pub fn to_toml(&self) -> Result<String> {
        document(self)
    }
}

fn document(file: &RobotFile) -> Result<String> {
    let robot = &file.robot;
    let rod = &robot.rod;
    let cannot = |what: &str| {
        invalid(
            "robot",
            format!("cannot be written as a robot file: {what}"),
            "keep such a robot in code, or give it the file's kinds of rod, loads and routing",
        )
    };
    let segments = segment_tables(rod).map_err(|what| cannot(&what))?;
    let mut rod_table = Table::new();
    if segments.is_none() {
        let (Some(g), Stiffness::Uniform(_)) = (rod.geometry, &rod.stiffness) else {
            return Err(cannot(
                "its rod is not given by `outer_radius`, `youngs_modulus` and `poisson_ratio` (a rod given by `shear_modulus` keeps no geometry)",
            ));
        };
        rod_table.insert("length".into(), Value::Float(rod.length));
        rod_table.insert("outer_radius".into(), Value::Float(g.outer_radius));
        rod_table.insert("inner_radius".into(), Value::Float(g.inner_radius));
        rod_table.insert("youngs_modulus".into(), Value::Float(g.youngs_modulus));
        rod_table.insert("poisson_ratio".into(), Value::Float(g.poisson_ratio));
        match &rod.reference {
            ReferenceStrains::Straight => {}
            ReferenceStrains::Constant { v_star, u_star } if *v_star == Vector3::z() => {
                rod_table.insert("precurvature".into(), vector(u_star));
            }
            _ => return Err(cannot("its reference strains are not a constant precurvature")),
        }
    }
    let mut base = Table::new();
    base.insert("position".into(), vector(&robot.base_position));
    base.insert("rotation".into(), rows(&robot.base_rotation));
    let loads_in = &robot.loads;
    let mut loads = Table::new();
    loads.insert(
        "distributed_force".into(),
        vector(&constant(&loads_in.distributed_force, "distributed_force")?),
    );
    loads.insert(
        "distributed_moment".into(),
        vector(&constant(&loads_in.distributed_moment, "distributed_moment")?),
    );
    loads.insert("tip_force".into(), vector(&loads_in.tip_force));
    loads.insert("tip_moment".into(), vector(&loads_in.tip_moment));
    // Follower loads only when present, so files without them read as before.
    if loads_in.follower_tip_force != Vector3::zeros() {
        loads.insert("follower_tip_force".into(), vector(&loads_in.follower_tip_force));
    }
    if loads_in.follower_tip_moment != Vector3::zeros() {
        loads.insert("follower_tip_moment".into(), vector(&loads_in.follower_tip_moment));
    }
    let follower = constant(&loads_in.follower_distributed_force, "follower_distributed_force")?;
    if follower != Vector3::zeros() {
        loads.insert("follower_distributed_force".into(), vector(&follower));
    }
    let (points, disks) = split_disks(file);
    let points = points
        .iter()
        .map(|p| {
            let mut t = Table::new();
            t.insert("s".into(), Value::Float(p.s));
            t.insert("force".into(), vector(&p.force));
            t.insert("moment".into(), vector(&p.moment));
            Value::Table(t)
        })
        .collect();
    loads.insert("point".into(), Value::Array(points));
    let mut tendons = Vec::new();
    for (i, t) in robot.tendons.iter().enumerate() {
        let mut routing = Table::new();
        match t.routing {
            Routing::Straight { x, y } => {
                routing.insert("kind".into(), Value::String("straight".into()));
                routing.insert("x".into(), Value::Float(x));
                routing.insert("y".into(), Value::Float(y));
            }
            Routing::Helical { radius, turns, phase } => {
                routing.insert("kind".into(), Value::String("helical".into()));
                routing.insert("radius".into(), Value::Float(radius));
                routing.insert("turns".into(), Value::Float(turns));
                routing.insert("phase".into(), Value::Float(phase));
            }
            Routing::Custom(_) => return Err(cannot(&format!("tendon {} has a custom routing", i + 1))),
        }
        let mut tendon = Table::new();
        tendon.insert("routing".into(), Value::Table(routing));
        match t.actuation {
            Actuation::Tension(tension) => {
                tendon.insert("tension".into(), Value::Float(tension));
            }
            // The file gives a displacement-controlled tendon no starting tension (the
            // solver estimates it, as it does from a start of 0), so only those are written.
            Actuation::PullIn { displacement, start } if start.unwrap_or(0.0) == 0.0 => {
                tendon.insert("displacement".into(), Value::Float(displacement));
            }
            Actuation::PullIn { start, .. } => {
                return Err(cannot(&format!(
                    "tendon {} is displacement-controlled with a starting tension of {} N, which a robot file cannot hold (set its tension to make it tension-controlled)",
                    i + 1,
                    start.unwrap_or(0.0)
                )));
            }
        }
        if let Some(end) = t.termination {
            tendon.insert("end".into(), Value::Float(end));
        }
        if let Some(k) = t.stiffness {
            tendon.insert("stiffness".into(), Value::Float(k));
        }
        if t.free_length != 0.0 {
            tendon.insert("free_length".into(), Value::Float(t.free_length));
        }
        if let Some(friction) = t.friction {
            tendon.insert("friction".into(), Value::Float(friction.coefficient));
            if friction.motion != Motion::Pull {
                tendon.insert("motion".into(), Value::String(friction.motion.name().into()));
            }
        }
        tendons.push(Value::Table(tendon));
    }
    let mut doc = Table::new();
    match segments {
        Some(segments) => doc.insert("segment".into(), Value::Array(segments)),
        None => doc.insert("rod".into(), Value::Table(rod_table)),
    };
    doc.insert("base".into(), Value::Table(base));
    doc.insert("loads".into(), Value::Table(loads));
    if !tendons.is_empty() {
        doc.insert("tendon".into(), Value::Array(tendons));
    }
    if let Some(d) = disks {
        doc.insert("disks".into(), Value::Table(disks_table(d)));
    }
    doc.insert("model".into(), Value::Table(model_table(robot)));
    doc.insert("solver".into(), Value::Table(solver_table(&file.solver)));
    toml::to_string(&doc).map_err(|e| {
        invalid(
            "robot",
            format!("cannot be written as TOML: {e}"),
            "report this as a bug",
        )
    })
}

/// The `[[segment]]` tables of a rod of segments (each by its four stiffnesses, with its
/// precurvature), `None` for another rod, or what keeps it from a file: lengths whose sums
/// do not give back the segment ends bitwise, or stiffnesses that differ between the two
/// bending axes or the two shear directions.
fn segment_tables(rod: &crate::Rod) -> std::result::Result<Option<Vec<Value>>, String> {
    let (Stiffness::Segments { ends, sections }, ReferenceStrains::Segments { ends: same, u_star }) =
        (&rod.stiffness, &rod.reference)
    else {
        return Ok(None);
    };
    let mut out = Vec::with_capacity(ends.len());
    let (mut start, mut sum) = (0.0, 0.0);
    for (k, ((&end, section), u)) in ends.iter().zip(sections).zip(u_star).enumerate() {
        let length = end - start;
        sum += length;
        let (kse, kbt) = (section.kse, section.kbt);
        if sum != end || same.get(k) != Some(&end) || kbt[0] != kbt[1] || kse[0] != kse[1] {
            return Err(format!(
                "segment {} is not one a file can give (its lengths must add up to its end exactly, \
                 its bending and shear stiffnesses be the same about both axes)",
                k + 1
            ));
        }
        let mut t = Table::new();
        t.insert("length".into(), Value::Float(length));
        t.insert("bending_stiffness".into(), Value::Float(kbt[0]));
        t.insert("torsion_stiffness".into(), Value::Float(kbt[2]));
        t.insert("axial_stiffness".into(), Value::Float(kse[2]));
        t.insert("shear_stiffness".into(), Value::Float(kse[0]));
        t.insert("precurvature".into(), vector(u));
        out.push(Value::Table(t));
        start = end;
    }
    Ok(Some(out))
}

/// The robot's point loads that the file gives as `[[loads.point]]`, and the disks it gives
/// as `[disks]`: the disks only if the last point loads are still exactly their weights.
fn split_disks(file: &RobotFile) -> (&[crate::PointLoad], Option<&crate::Disks>) {
    let all = &file.robot.loads.point[..];
    match file.disks.as_ref().and_then(|d| Some((d.others(all)?, d))) {
        Some((others, d)) => (others, Some(d)),
        None => (all, None),
    }
}

/// The `[disks]` table of `d`: positions, weight and the radius if given.
fn disks_table(d: &crate::Disks) -> Table {
    let mut t = Table::new();
    let positions = d.positions.iter().map(|&s| Value::Float(s)).collect();
    t.insert("positions".into(), Value::Array(positions));
    t.insert("weight".into(), vector(&d.weight));
    if let Some(r) = d.radius {
        t.insert("radius".into(), Value::Float(r));
    }
    t
}

/// The `[model]` table of `robot`: every key.
fn model_table(robot: &crate::Robot) -> Table {
    let mut t = Table::new();
    t.insert("corner_forces".into(), Value::Boolean(robot.corner_forces));
    let tendons = match robot.tendon_model {
        crate::TendonModel::Coupled => TendonModelKey::Coupled,
        crate::TendonModel::PointMoment => TendonModelKey::PointMoment,
    };
    // The key's own name, as the reader spells it (tables.rs).
    if let Ok(name) = Value::try_from(tendons) {
        t.insert("tendons".into(), name);
    }
    let rod = match robot.rod_model {
        crate::RodModel::Cosserat => RodModelKey::Cosserat,
        crate::RodModel::Kirchhoff => RodModelKey::Kirchhoff,
    };
    if let Ok(name) = Value::try_from(rod) {
        t.insert("rod".into(), name);
    }
    t
}

/// The `[solver]` table of `s`: every key, except `residual_tolerance` and `max_iterations`
/// where both solvers keep their own defaults (the file sets both at once).
fn solver_table(s: &SolverSettings) -> Table {
    let defaults = SolverSettings::default();
    let (c, d) = (&s.collocation, &defaults.collocation);
    let mut t = Table::new();
    let method = if s.method == Method::Shooting {
        "shooting"
    } else {
        "collocation"
    };
    t.insert("method".into(), Value::String(method.into()));
    t.insert("intervals".into(), Value::Integer(c.intervals as i64));
    if let Some(tol) = c.tolerance {
        t.insert("tolerance".into(), Value::Float(tol));
    }
    t.insert("max_intervals".into(), Value::Integer(c.max_intervals as i64));
    if c.residual_tolerance != d.residual_tolerance
        || s.shooting.residual_tolerance != defaults.shooting.residual_tolerance
    {
        t.insert("residual_tolerance".into(), Value::Float(c.residual_tolerance));
    }
    if c.max_iterations != d.max_iterations || s.shooting.max_iterations != defaults.shooting.max_iterations {
        t.insert("max_iterations".into(), Value::Integer(c.max_iterations as i64));
    }
    t.insert("continuation".into(), Value::Boolean(c.continuation));
    let equilibrium = match c.equilibrium {
        Equilibrium::LoadPath => EquilibriumKey::LoadPath,
        Equilibrium::Nearest => EquilibriumKey::Nearest,
    };
    // The key's own name, as the reader spells it (tables.rs).
    if let Ok(name) = Value::try_from(equilibrium) {
        t.insert("equilibrium".into(), name);
    }
    t.insert(
        "integration_tolerance".into(),
        Value::Float(s.shooting.integration_tolerance),
    );
    t
}

#[cfg(test)]
mod tests {
    use crate::io::parse;

    /// A robot file with every kind of value the writer writes.
    const FULL: &str = r#"
[rod]
length = 0.25
outer_radius = 0.0007
inner_radius = 0.0002
youngs_modulus = 60e9
poisson_ratio = 0.33
precurvature = [1.5, 0.0, 0.1]
[base]
position = [0.01, 0.0, 0.0]
euler_xyz_deg = [0.0, 90.0, 10.0]
[loads]
distributed_force = [0.0, 0.0, -0.3]
tip_force = [0.0, 0.1, 0.0]
point = [{ s = 0.1, force = [0.0, 0.2, 0.0], moment = [0.0, 0.0, 0.001] }]
[[tendon]]
routing = { kind = "straight", x = 0.008, y = 0.0 }
tension = 2.94
end = 0.125
[[tendon]]
routing = { kind = "helical", radius = 0.008, turns = 0.5, phase = 1.0 }
displacement = 0.001
stiffness = 1.0e4
free_length = 0.01
[solver]
method = "shooting"
intervals = 24
tolerance = 1e-8
residual_tolerance = 1e-11
max_iterations = 40
continuation = false
equilibrium = "nearest"
integration_tolerance = 1e-10
[model]
corner_forces = false
tendons = "point_moment"
rod = "kirchhoff"
[disks]
count = 3
mass = 0.002
gravity = [0.0, 0.0, -9.81]
radius = 0.012
"#;

    #[test]
    fn a_written_robot_file_reads_back_as_the_same_robot() {
        for text in [FULL.to_string(), crate::io::example()] {
            let file = parse(&text, "robot.toml").unwrap();
            let written = file.to_toml().unwrap();
            let back = parse(&written, "written.toml").unwrap();
            assert_eq!(format!("{:?}", back.robot), format!("{:?}", file.robot));
            assert_eq!(format!("{:?}", back.solver), format!("{:?}", file.solver));
            assert_eq!(back.disks, file.disks);
            assert_eq!(back.to_toml().unwrap(), written);
        }
        // Disks whose weights were changed since (a load scale) are written as point loads.
        let mut scaled = parse(FULL, "robot.toml").unwrap();
        assert!(scaled.to_toml().unwrap().contains("[disks]"));
        crate::Parameter::LoadScale.apply(&mut scaled.robot, 0.5).unwrap();
        let written = scaled.to_toml().unwrap();
        assert!(!written.contains("[disks]"), "{written}");
        let back = parse(&written, "scaled.toml").unwrap();
        assert_eq!(format!("{:?}", back.robot), format!("{:?}", scaled.robot));
        // What a file cannot hold is bad input, not a panic.
        let mut custom = crate::cases::case_s();
        custom.tendons[0].routing = crate::Routing::from_dual(|s, _| [s * 0.0 + 0.008, s * 0.01]);
        let file = crate::io::RobotFile {
            robot: custom,
            solver: Default::default(),
            disks: None,
        };
        let e = file.to_toml().unwrap_err().to_string();
        assert!(e.contains("tendon 1 has a custom routing"), "{e}");
    }
}
