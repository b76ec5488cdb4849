//! `tdcr calibrate ROBOT.toml EXPERIMENTS.csv`: fit Young's modulus and the base XYZ Euler
//! angles (optionally the base position and the tendon offset scale) to measured tip
//! positions, as in the paper's section 5.1, and print the fitted values and the tip-error
//! statistics of its Table 3 (docs/calibration.md).

use super::{Failure, emit, note, parse_count, read_robot, solver_failure};
use clap::{Args, ValueEnum};
use nalgebra::Vector3;
use serde::Serialize;
use std::fmt::Write as _;
use std::io::Read;
use tdcr::fit::calibration::{
    Calibration, CalibrationOptions, Fit, NOISE_FACTOR, Parameters, PoorFit, TipErrorStatistics,
    UNSTATED_NOISE_FRACTION, calibrate,
};
use tdcr::io::experiments::{header_hint, parse_csv};

/// The CSV format, shown after `tdcr calibrate --help`.
const CSV_HELP: &str = "EXPERIMENTS.csv: a header row, then one row per experiment, comma-separated, SI units:\n  \
    tension.1,...,tension.k      tension of each tendon in file order (N, >= 0; k = the robot's tendon count)\n  \
    tip_force.x,tip_force.y,tip_force.z   tip force (N, world frame), replacing the robot file's\n  \
    measured_x,measured_y,measured_z      measured tip position (m, world frame)\n  \
    motion (optional)            pull (a loading step) or release (an unloading step) for the tendons with\n  \
                                 friction, empty for the robot file's motion\n\
    Columns may come in any order (tension_I and tip_force_x, the names before 2026-12, are read too);\n\
    blank lines and lines starting with # are skipped. Everything else\n\
    (geometry, Poisson's ratio, gravity, routings) and the starting E and base pose come from ROBOT.toml.\n\
    Euler angles: R0 = Rx(alpha) Ry(beta) Rz(gamma), as the robot file's euler_xyz_deg.\n\
    Exit codes: 0 converged, 2 bad input, 3 a solve or the fit did not converge, 1 anything else.\n\
    Details: docs/calibration.md.";

/// Options of `tdcr calibrate`.
#[derive(Args)]
#[command(after_help = CSV_HELP)]
pub struct CalibrateArgs {
    /// Robot file (TOML; `-` reads standard input): everything not fitted, and the start.
    robot: String,
    /// Experiments CSV (`-` reads standard input): tensions, tip force, measured tip.
    experiments: String,
    /// Parameters to fit, comma-separated: e (Young's modulus at fixed Poisson's ratio),
    /// euler (base XYZ Euler angles), position (base position), offset (tendon offset scale),
    /// mu (the friction coefficient of the robot's first tendon with friction; the others keep their ratios to it).
    #[arg(long, value_name = "LIST", default_value = "e,euler", value_parser = parse_fit)]
    fit: Fit,
    /// Mesh intervals of every solve (a fixed mesh). Default: the robot file's `intervals`.
    /// `--nodes` is its old name, still accepted: it counts intervals too.
    #[arg(long, visible_alias = "nodes", value_name = "N", value_parser = parse_count)]
    intervals: Option<usize>,
    /// Levenberg-Marquardt iteration limit.
    #[arg(long, value_name = "N", default_value_t = 50, value_parser = parse_count)]
    max_iterations: usize,
    /// Output format.
    #[arg(long, value_enum, default_value_t = CalibrateFormat::Table)]
    format: CalibrateFormat,
    /// Measurement noise of the tip positions, per coordinate (m, e.g. 1e-4 for 0.1 mm): a
    /// fit whose noise estimate is above 3 times it is reported as not explaining the data.
    /// Without it the limit is 1.5 % of the rod length.
    #[arg(long, value_name = "METRES", value_parser = parse_noise)]
    noise: Option<f64>,
    /// Print every Levenberg-Marquardt iteration to standard error.
    #[arg(short, long)]
    verbose: bool,
    #[command(flatten)]
    friction: crate::robot_args::FrictionArgs,
}

/// Output formats of `tdcr calibrate`.
#[derive(Clone, Copy, ValueEnum)]
enum CalibrateFormat {
    /// Tables for people.
    Table,
    /// JSON (fields in docs/calibration.md).
    Json,
}

fn parse_fit(text: &str) -> Result<Fit, String> {
    let mut fit = Fit::none();
    for name in text.split(',').map(str::trim) {
        match name {
            "e" | "E" => fit.youngs_modulus = true,
            "euler" => fit.euler = true,
            "position" => fit.base_position = true,
            "offset" => fit.offset_scale = true,
            "mu" => fit.friction = true,
            _ => {
                return Err(format!(
                    "`{name}` is not a parameter; choose from e, euler, position, offset, mu (e.g. e,euler)"
                ));
            }
        }
    }
    Ok(fit)
}

fn parse_noise(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!(
            "`{text}` is not a noise level: give the measurement noise per coordinate in metres, a positive \
             number such as 1e-4 (0.1 mm)"
        )),
    }
}

fn read_csv(file: &str) -> Result<(String, String), Failure> {
    if file == "-" {
        let mut text = String::new();
        std::io::stdin()
            .read_to_string(&mut text)
            .map_err(|e| Failure::Input(format!("cannot read the experiments from standard input: {e}")))?;
        Ok(("<stdin>".into(), text))
    } else {
        let text = std::fs::read_to_string(file)
            .map_err(|e| Failure::Input(format!("cannot read experiments file {file}: {e}")))?;
        Ok((file.into(), text))
    }
}

/// Runs `tdcr calibrate`.
pub fn run(args: &CalibrateArgs) -> Result<(), Failure> {
    if args.robot == "-" && args.experiments == "-" {
        return Err(Failure::Input(
            "ROBOT and EXPERIMENTS cannot both be `-`: only one can come from standard input".into(),
        ));
    }
    let (name, mut file) = read_robot(&args.robot)?;
    args.friction.apply(&mut file.robot)?;
    let (csv_name, text) = read_csv(&args.experiments)?;
    let tendons = file.robot.tendons.len();
    let experiments = parse_csv(&text, &csv_name, tendons)
        .map_err(|e| Failure::Input(format!("{e}\n  {}", header_hint(tendons, &e))))?;
    let mut options = CalibrationOptions {
        fit: args.fit,
        max_iterations: args.max_iterations,
        ..Default::default()
    };
    let c = &mut options.collocation;
    c.intervals = args.intervals.unwrap_or(file.solver.collocation.intervals);
    c.max_intervals = c.max_intervals.max(c.intervals);
    // A fixed mesh in the file (no tolerance) is what calibrate does anyway: no note.
    let tolerance = file.solver.collocation.tolerance;
    if tolerance.is_some() && tolerance != tdcr::collocation::Options::default().tolerance {
        note("note: calibrate solves on a fixed mesh; the robot file's [solver] tolerance is ignored");
    }
    if file.solver.method == tdcr::Method::Shooting {
        note("note: calibrate needs the collocation solver (its sensitivities); the file's method is ignored");
    }
    let fit = calibrate(&file.robot, &experiments, &options).map_err(solver_failure)?;
    if args.verbose {
        note(&history(&fit));
    }
    let beta = fit.fitted.euler[1];
    if args.fit.euler && beta.cos().abs() < 0.1 {
        note(&format!(
            "note: beta = {:.2} deg is within {:.1} deg of the XYZ Euler singularity (+-90 deg), where only \
             alpha {} gamma is well determined (see the standard errors); docs/calibration.md shows how to \
             choose a world frame away from it",
            beta.to_degrees(),
            90.0 - beta.to_degrees().abs(),
            if beta > 0.0 { "+" } else { "-" }
        ));
    }
    let poor = fit.poor_fit(args.noise);
    let text = match args.format {
        CalibrateFormat::Table => table(&name, &csv_name, &fit, &options, poor.as_ref()),
        CalibrateFormat::Json => json(&name, &csv_name, &fit, &options, args.noise, poor.as_ref()),
    };
    if let Some(p) = &poor {
        note(&format!("warning: {p}"));
    }
    emit(&text)?;
    if fit.converged() {
        Ok(())
    } else {
        Err(Failure::NotConverged(format!(
            "calibration did not converge: {}; the output holds the last accepted parameters",
            fit.termination
        )))
    }
}

fn history(fit: &Calibration) -> String {
    let mut out = String::from("   iter   sum sq. error (m^2)   step       damping    gain     \n");
    for (k, it) in fit.history.iter().enumerate() {
        let _ = writeln!(
            out,
            "  {:>5}   {:>17.6e}   {:>8.2e}   {:>8.1e}   {:>6.3}   {}",
            k + 1,
            it.cost,
            it.step,
            it.damping,
            it.gain,
            if it.accepted { "accepted" } else { "rejected" }
        );
    }
    out.trim_end().to_string()
}

/// Rows of the parameter table: name, start, fitted, standard error (display units), unit.
fn parameter_rows(fit: &Calibration) -> Vec<(String, f64, f64, f64, &'static str)> {
    let se = fit.standard_errors.unwrap_or(Parameters {
        youngs_modulus: f64::NAN,
        euler: Vector3::repeat(f64::NAN),
        base_position: Vector3::repeat(f64::NAN),
        offset_scale: f64::NAN,
        friction: f64::NAN,
    });
    let (a, b) = (&fit.start, &fit.fitted);
    let mut rows = Vec::new();
    let f = &fit.fit;
    if f.youngs_modulus {
        rows.push((
            "E".into(),
            a.youngs_modulus / 1e9,
            b.youngs_modulus / 1e9,
            se.youngs_modulus / 1e9,
            "GPa",
        ));
    }
    if f.euler {
        for (i, n) in ["alpha", "beta", "gamma"].iter().enumerate() {
            rows.push((
                n.to_string(),
                a.euler[i].to_degrees(),
                b.euler[i].to_degrees(),
                se.euler[i].to_degrees(),
                "deg",
            ));
        }
    }
    if f.base_position {
        for (i, n) in ["x0", "y0", "z0"].iter().enumerate() {
            rows.push((
                n.to_string(),
                a.base_position[i] * 1e3,
                b.base_position[i] * 1e3,
                se.base_position[i] * 1e3,
                "mm",
            ));
        }
    }
    if f.offset_scale {
        rows.push((
            "offset scale".into(),
            a.offset_scale,
            b.offset_scale,
            se.offset_scale,
            "-",
        ));
    }
    if f.friction {
        rows.push(("mu".into(), a.friction, b.friction, se.friction, "-"));
    }
    rows
}

fn table(
    name: &str,
    csv_name: &str,
    fit: &Calibration,
    options: &CalibrationOptions,
    poor: Option<&PoorFit>,
) -> String {
    let mut out = String::new();
    let n = fit.residuals.len();
    let _ = writeln!(
        out,
        "{name} + {csv_name}: {n} experiments; fitting {} by Levenberg-Marquardt on the sum of squared tip errors",
        fit.fit.names().join(", ")
    );
    let _ = writeln!(
        out,
        "{}\n{} iterations, {} solves on a fixed mesh of {} intervals; {:.2} s (solves {:.2} s, sensitivities {:.2} s)\n",
        fit.termination,
        fit.iterations,
        fit.solves,
        options.collocation.intervals,
        fit.timings.total.as_secs_f64(),
        fit.timings.solves.as_secs_f64(),
        fit.timings.sensitivities.as_secs_f64()
    );
    let _ = writeln!(
        out,
        "{:<14} {:>12} {:>12} {:>11}  unit",
        "parameter", "start", "fitted", "std. error"
    );
    for (label, a, b, se, unit) in parameter_rows(fit) {
        let _ = writeln!(out, "{label:<14} {a:>12.4} {b:>12.4} {se:>11.4}  {unit}");
    }
    let length = fit.robot.length();
    let (s, f) = (&fit.start_errors, &fit.errors);
    let _ = writeln!(out, "\n{:<22} {:>10} {:>10}", "tip error (Table 3)", "start", "fitted");
    let rows: [(&str, Statistic); 5] = [
        ("mean (mm)", |t| t.mean),
        ("min (mm)", |t| t.min),
        ("max (mm)", |t| t.max),
        ("std. dev. (mm)", |t| t.std_dev),
        ("rms (mm)", |t| t.rms),
    ];
    for (label, get) in rows {
        let _ = writeln!(out, "{label:<22} {:>10.4} {:>10.4}", get(s) * 1e3, get(f) * 1e3);
    }
    let _ = writeln!(
        out,
        "{:<22} {:>9.3}% {:>9.3}%",
        "mean (% of length)",
        s.mean / length * 100.0,
        f.mean / length * 100.0
    );
    let _ = writeln!(
        out,
        "noise estimate from the fitted residuals: {:.4} mm per coordinate\n",
        fit.noise_estimate * 1e3
    );
    if let Some(p) = poor {
        let _ = writeln!(out, "warning: {p}\n");
    }
    let _ = writeln!(
        out,
        "{:>4} {:>12} {:>12}   {:>9} {:>9} {:>9}",
        "#", "start (mm)", "fitted (mm)", "dx (mm)", "dy (mm)", "dz (mm)"
    );
    for (k, (r0, r)) in fit.start_residuals.iter().zip(&fit.residuals).enumerate() {
        let _ = writeln!(
            out,
            "{:>4} {:>12.4} {:>12.4}   {:>9.4} {:>9.4} {:>9.4}",
            k + 1,
            r0.norm() * 1e3,
            r.norm() * 1e3,
            r.x * 1e3,
            r.y * 1e3,
            r.z * 1e3
        );
    }
    let _ = writeln!(
        out,
        "(tip error at the start and at the fit; d = model tip - measured tip at the fit)\n"
    );
    let p = &fit.fitted;
    let _ = writeln!(out, "robot file lines for the fitted values:");
    if fit.fit.youngs_modulus {
        let _ = writeln!(out, "  [rod]  youngs_modulus = {:.6e}", p.youngs_modulus);
    }
    if fit.fit.euler {
        let d = p.euler_deg();
        let _ = writeln!(out, "  [base] euler_xyz_deg = [{:.6}, {:.6}, {:.6}]", d.x, d.y, d.z);
    }
    if fit.fit.base_position {
        let q = p.base_position;
        let _ = writeln!(out, "  [base] position = [{:.9}, {:.9}, {:.9}]", q.x, q.y, q.z);
    }
    if fit.fit.offset_scale {
        let _ = writeln!(out, "  every tendon offset (x, y, radius) times {:.6}", p.offset_scale);
    }
    if fit.fit.friction {
        // mu is the first tendon with friction's; the others moved with it in proportion, so
        // each gets its own line.
        for (i, f) in fit.robot.tendons.iter().enumerate() {
            if let Some(f) = f.active_friction() {
                let mu = f.coefficient;
                // Six significant digits (fixed-point hides a coefficient fitted toward 0).
                let value = if mu >= 1e-3 {
                    format!("{mu:.6}")
                } else {
                    format!("{mu:.5e}")
                };
                let _ = writeln!(out, "  [[tendon]] {}: friction = {value}", i + 1);
            }
        }
    }
    out
}

/// Calibration parameters in the JSON: every one for the start and the fit; for the standard
/// errors only the fitted ones (the others are null: they were held, not known exactly).
#[derive(Serialize)]
struct ParametersJson {
    youngs_modulus: Option<f64>,
    euler_xyz_rad: Option<[f64; 3]>,
    euler_xyz_deg: Option<[f64; 3]>,
    base_position: Option<[f64; 3]>,
    offset_scale: Option<f64>,
    /// The first tendon with friction's coefficient (the fitted mu; the others keep their
    /// ratios to it, see `fitted_frictions`); null without friction.
    friction: Option<f64>,
}

impl ParametersJson {
    /// `p`'s values, those of the parameters `fitted` selects only (all where `None`).
    fn of(p: &Parameters, fitted: Option<&Fit>) -> Self {
        let keep = |selected: bool| fitted.is_none_or(|_| selected);
        let f = fitted.copied().unwrap_or_else(Fit::none);
        ParametersJson {
            youngs_modulus: keep(f.youngs_modulus).then_some(p.youngs_modulus),
            euler_xyz_rad: keep(f.euler).then(|| p.euler.into()),
            euler_xyz_deg: keep(f.euler).then(|| p.euler_deg().into()),
            base_position: keep(f.base_position).then(|| p.base_position.into()),
            offset_scale: keep(f.offset_scale).then_some(p.offset_scale),
            friction: (keep(f.friction) && p.friction.is_finite() && p.friction > 0.0).then_some(p.friction),
        }
    }
}

#[derive(Serialize)]
struct StatisticsJson {
    mean: f64,
    min: f64,
    max: f64,
    std_dev: f64,
    rms: f64,
}

impl From<&TipErrorStatistics> for StatisticsJson {
    fn from(t: &TipErrorStatistics) -> Self {
        StatisticsJson {
            mean: t.mean,
            min: t.min,
            max: t.max,
            std_dev: t.std_dev,
            rms: t.rms,
        }
    }
}

#[derive(Serialize)]
struct ExperimentJson {
    start_error: f64,
    error: f64,
    model_tip: [f64; 3],
    residual: [f64; 3],
}

#[derive(Serialize)]
struct Statistics {
    start: StatisticsJson,
    fitted: StatisticsJson,
}

/// Whether the fitted residuals are at the measurement noise.
#[derive(Serialize)]
struct FitQuality {
    /// The stated measurement noise per coordinate (m), `--noise`, if given.
    stated_noise: Option<f64>,
    /// The noise estimate the fit may reach before it is a misfit (m per coordinate).
    limit: f64,
    /// Whether the noise estimate is above `limit`.
    poor: bool,
    /// The warning's text when `poor`.
    warning: Option<String>,
}

#[derive(Serialize)]
struct CalibrationJson<'a> {
    robot_file: &'a str,
    experiments_file: &'a str,
    fit: Vec<&'static str>,
    converged: bool,
    termination: String,
    iterations: usize,
    solves: usize,
    sensitivity_evaluations: usize,
    intervals: usize,
    time: f64,
    start: ParametersJson,
    fitted: ParametersJson,
    standard_errors: Option<ParametersJson>,
    /// The fitted robot's friction coefficient per tendon (null: no friction).
    fitted_frictions: Vec<Option<f64>>,
    noise_estimate: f64,
    /// The fit's residuals against the measurement noise ([`Calibration::poor_fit`]).
    fit_quality: FitQuality,
    tip_errors: Statistics,
    experiments: Vec<ExperimentJson>,
}

/// The JSON output; `noise` is `--noise`, `poor` the fit's warning.
fn json(
    name: &str,
    csv_name: &str,
    fit: &Calibration,
    options: &CalibrationOptions,
    noise: Option<f64>,
    poor: Option<&PoorFit>,
) -> String {
    let value = CalibrationJson {
        robot_file: name,
        experiments_file: csv_name,
        fit: fit.fit.names(),
        converged: fit.converged(),
        termination: fit.termination.to_string(),
        iterations: fit.iterations,
        solves: fit.solves,
        sensitivity_evaluations: fit.sensitivity_evaluations,
        intervals: options.collocation.intervals,
        time: fit.timings.total.as_secs_f64(),
        start: ParametersJson::of(&fit.start, None),
        fitted: ParametersJson::of(&fit.fitted, None),
        standard_errors: fit
            .standard_errors
            .as_ref()
            .map(|e| ParametersJson::of(e, Some(&fit.fit))),
        fitted_frictions: fit
            .robot
            .tendons
            .iter()
            .map(|t| t.active_friction().map(|f| f.coefficient))
            .collect(),
        noise_estimate: fit.noise_estimate,
        fit_quality: FitQuality {
            stated_noise: noise,
            limit: noise.map_or(UNSTATED_NOISE_FRACTION * fit.robot.length(), |n| NOISE_FACTOR * n),
            poor: poor.is_some(),
            warning: poor.map(ToString::to_string),
        },
        tip_errors: Statistics {
            start: (&fit.start_errors).into(),
            fitted: (&fit.errors).into(),
        },
        experiments: fit
            .tips
            .iter()
            .zip(&fit.residuals)
            .zip(&fit.start_residuals)
            .map(|((tip, r), r0)| ExperimentJson {
                start_error: r0.norm(),
                error: r.norm(),
                model_tip: (*tip).into(),
                residual: (*r).into(),
            })
            .collect(),
    };
    // Serializing plain numbers and strings cannot fail.
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    text
}

/// One statistic of a [`TipErrorStatistics`] (m).
type Statistic = fn(&TipErrorStatistics) -> f64;
