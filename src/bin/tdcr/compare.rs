//! `tdcr compare`: one robot file solved as several models (or by both solvers), the tips
//! compared with the first's, the shapes drawn overlaid.

use clap::Args;
use std::path::PathBuf;
use tdcr::analysis::comparison::{Compared, Variant, compare, compare_models, shape};
use tdcr::io::RobotFile;
use tdcr::plot::{Curve, Figure, LegendEntry, Marker, PALETTE};
use tdcr::{Method, Robot, Solution, collocation, shooting};

use crate::args::SolverArgs;
use crate::failure::{Failure, emit, note, solver_failure, write_picture};
use crate::robot_args::{apply, read_robot};

/// The arguments of `tdcr compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// Robot file (TOML; `-` reads standard input).
    file: String,
    /// The models to solve, comma-separated, the first the reference: coupled, point_moment,
    /// constant_curvature, paper_jumps, kirchhoff. Default: all five, in this order.
    #[arg(long, value_name = "M1,M2,...", value_delimiter = ',', conflicts_with = "methods")]
    models: Vec<String>,
    /// Compare solvers instead, on the file's model: collocation and/or shooting.
    #[arg(long, value_name = "S1,S2", value_delimiter = ',', value_enum)]
    methods: Vec<crate::args::MethodArg>,
    #[command(flatten)]
    tendons: crate::robot_args::TendonArgs,
    #[command(flatten)]
    friction: crate::robot_args::FrictionArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Draw the shapes overlaid into FILE: PNG if its name ends in .png, else SVG.
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    plot: Option<PathBuf>,
}

/// Runs `tdcr compare`.
pub fn run(args: &CompareArgs) -> Result<(), Failure> {
    let (name, mut file) = read_robot(&args.file)?;
    args.tendons.apply(&mut file.robot)?;
    args.friction.apply(&mut file.robot)?;
    apply(&mut file, &args.solver);
    let robot = file.robot.clone();
    let shapes = if args.methods.is_empty() {
        let variants = if args.models.is_empty() {
            defaults(&name, &robot)
        } else {
            args.models
                .iter()
                .map(|m| Variant::from_name(m.trim()))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| Failure::Input(format!("--models: {e}")))?
        };
        compare_models(&robot, &variants, |r| solve(r, &file, file.solver.method)).map_err(solver_failure)?
    } else {
        let mut shapes = Vec::new();
        for m in &args.methods {
            let method = match m {
                crate::args::MethodArg::Collocation => Method::Collocation,
                crate::args::MethodArg::Shooting => Method::Shooting,
            };
            let solution = solve(&robot, &file, method).map_err(solver_failure)?;
            shapes.push((method.to_string(), shape(&solution)));
        }
        compare(shapes)
    };
    emit(&table(&shapes))?;
    if let Some(path) = &args.plot {
        write_picture(path, &figure(&name, &robot, &shapes), "plot")?;
    }
    Ok(())
}

/// The default models for `robot`: every [`Variant`], but those whose robot the library
/// refuses for its tendons' friction (the point-moment model), each left out with a note
/// saying why. Other refusals stay errors (the solve reports them).
fn defaults(name: &str, robot: &Robot) -> Vec<Variant> {
    let mut kept = Vec::new();
    for v in Variant::ALL {
        match v.robot(robot).validate() {
            Err(e @ tdcr::Error::InvalidInput { .. }) if friction_field(&e) => note(&format!(
                "note: {name}: compare leaves out {}: {}",
                v.name(),
                crate::failure::message(&e)
            )),
            _ => kept.push(v),
        }
    }
    kept
}

/// Whether `e` names a tendon's friction (`tendons[I].friction`).
fn friction_field(e: &tdcr::Error) -> bool {
    matches!(e, tdcr::Error::InvalidInput { field, .. } if field.starts_with("tendons[") && field.ends_with("].friction"))
}

/// `robot` solved by `method` with the file's options.
fn solve(robot: &Robot, file: &RobotFile, method: Method) -> tdcr::Result<Solution> {
    match method {
        Method::Collocation => collocation::solve(robot, &file.solver.collocation),
        Method::Shooting => shooting::solve(robot, &file.solver.shooting),
    }
}

/// One row per shape: its tip and how far it is from the first's.
fn table(shapes: &[Compared]) -> String {
    let reference = shapes.first().map_or("", |c| c.name.as_str());
    let mut out = format!(
        "{:<20} {:>12} {:>12} {:>12} {:>15} {:>15}\n",
        "model", "tip x (mm)", "tip y (mm)", "tip z (mm)", "off tip (mm)", "off angle (deg)"
    );
    for c in shapes {
        let p = c.tip_position() * 1e3;
        out += &format!(
            "{:<20} {:>12.4} {:>12.4} {:>12.4} {:>15.6} {:>15.6}\n",
            c.name,
            p.x,
            p.y,
            p.z,
            c.tip_distance * 1e3,
            c.tip_angle.to_degrees()
        );
    }
    out + &format!("(off: distance and rotation angle of the tip from {reference}'s)\n")
}

/// The shapes overlaid, one colour each, their tips marked.
fn figure(name: &str, robot: &Robot, shapes: &[Compared]) -> Figure {
    let mut figure = Figure::new(&format!("{name}: compared shapes"));
    let panel = figure.panel_mut();
    panel.origin = Some(robot.base_position);
    let mut legend = Vec::new();
    for (i, c) in shapes.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let points = c.states.iter().map(|s| s.p).collect();
        let dash = (i > 0).then(|| "6 3".to_string());
        panel.curves.push(Curve {
            points,
            color: color.into(),
            width: 2.0,
            dash: dash.clone(),
            opacity: 1.0,
        });
        panel.markers.push(Marker {
            point: c.tip_position(),
            color: color.into(),
            radius: 2.5,
        });
        let label = if i == 0 {
            format!("{} (reference)", c.name)
        } else {
            format!(
                "{}: tip {:.3} mm and {:.3} deg off",
                c.name,
                c.tip_distance * 1e3,
                c.tip_angle.to_degrees()
            )
        };
        let entry = LegendEntry::line(&label, color).width(2.0);
        legend.push(match &dash {
            Some(d) => entry.dash(d),
            None => entry,
        });
    }
    figure.legend = legend;
    figure
}
