//! Reading robot files, applying the command-line overrides and running the chosen solver.

use std::io::Read;
use tdcr::io::RobotFile;
use tdcr::{Method, Robot, Solution, collocation, shooting};

use crate::args::{MethodArg, RodArg, SolverArgs, TendonsArg};
use crate::failure::{Failure, note, solver_failure, with_likely_causes};

/// Reads and checks a robot file (`-`: standard input); every problem is one message line.
pub fn read_robot(file: &str) -> Result<(String, RobotFile), Failure> {
    let (name, bytes) = if file == "-" {
        let mut bytes = Vec::new();
        std::io::stdin()
            .read_to_end(&mut bytes)
            .map_err(|e| Failure::Input(format!("cannot read the robot file from standard input: {e}")))?;
        ("<stdin>".to_string(), bytes)
    } else {
        let bytes = std::fs::read(file).map_err(|e| Failure::Input(format!("cannot read robot file {file}: {e}")))?;
        (file.to_string(), bytes)
    };
    let text = std::str::from_utf8(&bytes).map_err(|e| Failure::Input(not_utf8(&name, &bytes, &e)))?;
    let robot = tdcr::io::parse(text, &name).map_err(|e| Failure::Input(e.to_string()))?;
    Ok((name, robot))
}

/// Where a file stops being UTF-8: the line and byte offset of its first invalid byte.
fn not_utf8(name: &str, bytes: &[u8], e: &std::str::Utf8Error) -> String {
    let at = e.valid_up_to();
    let before = &bytes[..at];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    format!(
        "{name}:{line}: is not UTF-8 text: byte 0x{:02X} at byte offset {at} (byte {} of line {line}) \
         is not valid UTF-8; save the file as UTF-8 (robot files are TOML, which is UTF-8)",
        bytes[at],
        at - line_start + 1
    )
}

/// Makes tendon `index` (from 1) displacement-controlled with pull-in `displacement` (m)
/// (its tension becomes an unknown); a number past the last tendon is bad input.
pub fn set_displacement(robot: &mut Robot, index: usize, displacement: f64) -> Result<(), Failure> {
    let count = robot.tendons.len();
    match index.checked_sub(1).and_then(|i| robot.tendons.get_mut(i)) {
        Some(t) => {
            t.set_displacement(displacement);
            Ok(())
        }
        None => Err(Failure::Input(format!(
            "--displacement {index}=...: the robot has {count} tendon(s), numbered 1 to {count} in file order"
        ))),
    }
}

/// Sets the tension of tendon `index` (from 1); a number past the last tendon is bad input.
pub fn set_tension(robot: &mut Robot, index: usize, tension: f64) -> Result<(), Failure> {
    let count = robot.tendons.len();
    match robot.tendons.get_mut(index.wrapping_sub(1)) {
        Some(t) => {
            t.set_tension(tension);
            Ok(())
        }
        None => Err(Failure::Input(format!(
            "--tension {index}=...: the robot has {count} tendon(s), numbered 1 to {count} in file order"
        ))),
    }
}

/// Bad input if `values` (the `option`'s `I=VALUE` arguments) give a tendon twice: the
/// second would silently replace the first.
pub fn once<T: Copy, D: std::fmt::Display>(
    option: &str,
    values: &[(usize, T)],
    show: impl Fn(T) -> D,
) -> Result<(), Failure> {
    for (k, &(i, a)) in values.iter().enumerate() {
        if let Some(&(_, b)) = values[..k].iter().find(|&&(j, _)| j == i) {
            return Err(Failure::Input(format!(
                "{option} {i}=... is given twice ({option} {i}={} and {option} {i}={}): give each tendon one value",
                show(b),
                show(a)
            )));
        }
    }
    Ok(())
}

/// The tendon inputs of `solve`, `trace` and `compare`: `--tension I=NEWTONS` and
/// `--displacement I=METRES`, each once per tendon, not both for one tendon.
#[derive(clap::Args)]
pub struct TendonArgs {
    /// Tension of tendon I (numbered from 1) in N, replacing the file's. Repeatable.
    #[arg(long, value_name = "I=NEWTONS", value_parser = crate::args::parse_tension)]
    tension: Vec<(usize, f64)>,
    /// Drive tendon I (numbered from 1) by its actuator's pull-in in m instead of a tension
    /// (its tension is then solved for; docs/actuation.md). Repeatable.
    #[arg(long, value_name = "I=METRES", value_parser = crate::args::parse_displacement)]
    displacement: Vec<(usize, f64)>,
}

impl TendonArgs {
    /// Sets the tensions, then the pull-ins, on `robot`; a tendon given twice, by both or
    /// past the last is bad input.
    pub fn apply(&self, robot: &mut Robot) -> Result<(), Failure> {
        once("--tension", &self.tension, tdcr::Readable)?;
        once("--displacement", &self.displacement, tdcr::Readable)?;
        for &(i, t) in &self.tension {
            set_tension(robot, i, t)?;
        }
        for &(i, q) in &self.displacement {
            if self.tension.iter().any(|&(j, _)| j == i) {
                return Err(Failure::Input(format!(
                    "--tension {i}=... and --displacement {i}=... both given: drive a tendon by its tension or by its displacement"
                )));
            }
            set_displacement(robot, i, q)?;
        }
        Ok(())
    }
}

/// The friction options of `solve` and `sweep`: `--friction I=MU` and `--motion
/// I=pull|release`, each once per tendon.
#[derive(clap::Args)]
pub struct FrictionArgs {
    /// Friction coefficient of tendon I (numbered from 1) in its channels, replacing the
    /// file's: full slip in the file's motion or --motion's (`pull` unless told `release`);
    /// with `sweep --history`, stick/slip decided per step (docs/friction.md). Repeatable.
    #[arg(long, value_name = "I=MU", value_parser = crate::args::parse_friction)]
    friction: Vec<(usize, f64)>,
    /// The motion tendon I's friction opposes in full slip, replacing the file's `motion`:
    /// `pull` (the actuator pulls in: tension falls toward the termination) or `release` (it
    /// lets out: tension rises). Repeatable.
    #[arg(long, value_name = "I=pull|release", value_parser = crate::args::parse_motion)]
    motion: Vec<(usize, tdcr::Motion)>,
}

impl FrictionArgs {
    /// Whether any `--motion` is given.
    pub fn gives_motion(&self) -> bool {
        !self.motion.is_empty()
    }

    /// Sets the coefficients, then the motions, on `robot`; a tendon given twice or past
    /// the last is bad input. A `--motion` on a tendon left without friction changes
    /// nothing (the motion says which way friction acts): a warning line says so.
    pub fn apply(&self, robot: &mut Robot) -> Result<(), Failure> {
        once("--friction", &self.friction, tdcr::Readable)?;
        for &(i, mu) in &self.friction {
            set_friction(robot, i, mu)?;
        }
        once("--motion", &self.motion, tdcr::Motion::name)?;
        for &(i, motion) in &self.motion {
            set_motion(robot, i, motion)?;
            if robot.tendons[i - 1].friction.is_none_or(|f| f.coefficient == 0.0) {
                note(&format!(
                    "warning: --motion {i}={} has no effect: tendon {i} has no friction; add --friction {i}=MU",
                    motion.name()
                ));
            }
        }
        Ok(())
    }
}

/// Sets the motion that tendon `index`'s (from 1) friction opposes, keeping its
/// coefficient (0 without friction: the motion then has no effect, which
/// [`FrictionArgs::apply`] warns about); a number past the last tendon is bad input.
fn set_motion(robot: &mut Robot, index: usize, motion: tdcr::Motion) -> Result<(), Failure> {
    let count = robot.tendons.len();
    match robot.tendons.get_mut(index.wrapping_sub(1)) {
        Some(t) => {
            let coefficient = t.friction.map_or(0.0, |f| f.coefficient);
            t.friction = Some(tdcr::Friction { coefficient, motion });
            Ok(())
        }
        None => Err(Failure::Input(format!(
            "--motion {index}=...: the robot has {count} tendon(s), numbered 1 to {count} in file order"
        ))),
    }
}

/// Sets the friction coefficient of tendon `index` (from 1), keeping the motion the file
/// gives it (`pull` by default); a number past the last tendon is bad input.
fn set_friction(robot: &mut Robot, index: usize, coefficient: f64) -> Result<(), Failure> {
    let count = robot.tendons.len();
    match robot.tendons.get_mut(index.wrapping_sub(1)) {
        Some(t) => {
            let motion = t.friction.map_or(tdcr::Motion::Pull, |f| f.motion);
            t.friction = Some(tdcr::Friction { coefficient, motion });
            Ok(())
        }
        None => Err(Failure::Input(format!(
            "--friction {index}=...: the robot has {count} tendon(s), numbered 1 to {count} in file order"
        ))),
    }
}

/// Applies the overrides shared by `solve` and `sweep` (loads, model, method, mesh) to the
/// file.
pub fn apply(file: &mut RobotFile, args: &SolverArgs) {
    let robot = &mut file.robot;
    if let Some(f) = args.tip_force {
        robot.loads.tip_force = f.into();
    }
    if let Some(m) = args.tip_moment {
        robot.loads.tip_moment = m.into();
    }
    if let Some(f) = args.follower_tip_force {
        robot.loads.follower_tip_force = f.into();
    }
    if let Some(m) = args.follower_tip_moment {
        robot.loads.follower_tip_moment = m.into();
    }
    if let Some(corners) = args.corner_forces {
        robot.corner_forces = corners;
    }
    match args.tendons {
        Some(TendonsArg::Coupled) => robot.tendon_model = tdcr::TendonModel::Coupled,
        Some(TendonsArg::PointMoment) => robot.tendon_model = tdcr::TendonModel::PointMoment,
        None => {}
    }
    match args.rod {
        Some(RodArg::Cosserat) => robot.rod_model = tdcr::RodModel::Cosserat,
        Some(RodArg::Kirchhoff) => robot.rod_model = tdcr::RodModel::Kirchhoff,
        None => {}
    }
    let settings = &mut file.solver;
    match args.method {
        Some(MethodArg::Collocation) => settings.method = Method::Collocation,
        Some(MethodArg::Shooting) => settings.method = Method::Shooting,
        None => {}
    }
    let c = &mut settings.collocation;
    if let Some(n) = args.intervals {
        c.intervals = n;
        c.max_intervals = c.max_intervals.max(n);
        // --intervals alone means a fixed mesh, even if the file asks for refinement.
        if args.tol.is_none() {
            c.tolerance = None;
        }
    }
    if let Some(t) = args.tol {
        c.tolerance = Some(t);
    }
    if args.nearest {
        c.equilibrium = collocation::Equilibrium::Nearest;
    }
    if settings.method == Method::Shooting && (args.intervals.is_some() || args.tol.is_some()) {
        note("note: --intervals and --tol apply to collocation only; shooting integrates adaptively");
    }
}

/// Reads a saved solution (`--start`) of `robot` as a warm start.
pub fn read_start(path: &std::path::Path, robot: &Robot) -> Result<Solution, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::Input(format!("cannot read the start solution {}: {e}", path.display())))?;
    tdcr::io::read_solution(&text, robot).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))
}

/// Solves `robot` with the file's solver settings, warm-started from `warm` (collocation
/// only; shooting always starts cold).
pub fn run_solver(robot: &Robot, file: &RobotFile, warm: Option<&Solution>) -> Result<Solution, Failure> {
    let s = &file.solver;
    match (s.method, warm) {
        (Method::Collocation, None) => collocation::solve(robot, &s.collocation),
        (Method::Collocation, Some(w)) => collocation::solve_from(robot, &s.collocation, w),
        (Method::Shooting, _) => shooting::solve(robot, &s.shooting),
    }
    .map_err(|e| with_likely_causes(solver_failure(e), robot))
}
