//! Arguments shared by the commands and the value parsers of every option.

use clap::{Args, ValueEnum};

/// Which solver `--method` picks.
#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    /// Sparse collocation with Newton (the main solver).
    Collocation,
    /// Shooting from the base (the independent cross-check).
    Shooting,
}

/// Which tendon model `--tendons` picks (the robot file's `[model] tendons`).
#[derive(Clone, Copy, ValueEnum)]
pub enum TendonsArg {
    /// The coupled Cosserat rod/string model (the default).
    Coupled,
    /// The point-moment model: each tendon acts only by its termination moment.
    #[value(name = "point_moment")]
    PointMoment,
}

/// Which rod model `--rod` picks (the robot file's `[model] rod`).
#[derive(Clone, Copy, ValueEnum)]
pub enum RodArg {
    /// The Cosserat rod: shear and extension by the constitutive law (the default).
    Cosserat,
    /// The Kirchhoff rod: inextensible and unshearable, v = v* exactly.
    Kirchhoff,
}

/// Options shared by `solve` and `sweep`.
#[derive(Args)]
pub struct SolverArgs {
    /// Tip force (N, world frame), replacing the file's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    pub tip_force: Option<[f64; 3]>,
    /// Tip moment (N m, world frame), replacing the file's.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    pub tip_moment: Option<[f64; 3]>,
    /// Follower tip force (N, tip body frame: it turns with the tip), replacing the file's
    /// `[loads] follower_tip_force`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    pub follower_tip_force: Option<[f64; 3]>,
    /// Follower tip moment (N m, tip body frame), replacing the file's
    /// `[loads] follower_tip_moment`.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vector, allow_hyphen_values = true)]
    pub follower_tip_moment: Option<[f64; 3]>,
    /// Solver, replacing the file's `[solver] method`.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// A fixed mesh of N intervals (no refinement; Newton still converges fully). With
    /// --tol, the starting mesh. `--nodes` is its old name: it counts intervals too.
    #[arg(long, visible_alias = "nodes", value_name = "N", value_parser = parse_count)]
    pub intervals: Option<usize>,
    /// Refine the mesh adaptively until the estimated tip error is at most T relative to the
    /// rod length: position error at most T L (m), orientation error at most T rad.
    #[arg(long, value_name = "T", value_parser = parse_positive)]
    pub tol: Option<f64>,
    /// Whether continuing tendons push on the backbone where another tendon ends or a point
    /// load acts (`true`, the default); `false` solves the paper's jump conditions. Replaces
    /// the file's `[model] corner_forces`.
    #[arg(long, value_name = "BOOL", action = clap::ArgAction::Set)]
    pub corner_forces: Option<bool>,
    /// How the tendons load the backbone, replacing the file's `[model] tendons`.
    #[arg(long, value_enum)]
    pub tendons: Option<TendonsArg>,
    /// How the backbone strains in shear and extension, replacing the file's `[model] rod`.
    #[arg(long, value_enum)]
    pub rod: Option<RodArg>,
    /// Return the equilibrium Newton reaches from the initial guess, whatever its stability,
    /// instead of the one on the load path from rest (docs/stability.md).
    #[arg(long)]
    pub nearest: bool,
    /// Print the solver's per-iteration table and counts to standard error.
    #[arg(short, long)]
    pub verbose: bool,
}

/// A finite number; `what` names it in the message.
fn parse_number(text: &str, what: &str) -> Result<f64, String> {
    let x: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number ({what})"))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("`{text}` is not finite ({what})"))
    }
}

/// `X,Y,Z`: three finite numbers (`--tip-force`, `--tip-moment`).
pub fn parse_vector(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("`{text}` needs three comma-separated numbers X,Y,Z"));
    }
    let mut v = [0.0; 3];
    for (x, part) in v.iter_mut().zip(parts) {
        *x = parse_number(part, "a component")?;
    }
    Ok(v)
}

/// The most values a count option accepts (sweep steps, output samples): each costs memory
/// and a line of output.
pub const MAX_COUNT: usize = 1_000_000;

/// A whole number from 1 to [`MAX_COUNT`] (`--intervals`, sweep COUNT).
pub fn parse_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (1..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(format!("`{text}` is not a whole number from 1 to {MAX_COUNT}")),
    }
}

/// The most spacer disks a picture draws (`--disks`).
pub const MAX_DISKS: usize = 1000;

/// A number of spacer disks from 0 to [`MAX_DISKS`] (`--disks`).
pub fn parse_disks(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n <= MAX_DISKS => Ok(n),
        _ => Err(format!("`{text}` is not a whole number from 0 to {MAX_DISKS}")),
    }
}

/// A whole number of output samples from 2 to [`MAX_COUNT`] (`--samples`).
pub fn parse_samples(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (2..=MAX_COUNT).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{text}` is not a whole number from 2 (the ends count) to {MAX_COUNT}"
        )),
    }
}

/// A positive tolerance, relative to the rod length (`--tol`).
pub fn parse_positive(text: &str) -> Result<f64, String> {
    let x = parse_number(text, "a tolerance relative to the rod length")?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("`{text}` must be positive"))
    }
}

/// Splits `I=VALUE` into the tendon number (from 1) and the value text; `form` is the
/// expected shape with an example (`I=NEWTONS, e.g. 1=2.94`), for the message.
fn parse_tendon<'a>(text: &'a str, form: &str) -> Result<(usize, &'a str), String> {
    let (index, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}` must look like {form}"))?;
    let index = parse_count(index.trim()).map_err(|_| format!("tendon number `{index}` must be 1 or more"))?;
    Ok((index, value))
}

/// `I=NEWTONS` (`solve --tension`): a tendon number and a tension >= 0.
pub fn parse_tension(text: &str) -> Result<(usize, f64), String> {
    let (index, value) = parse_tendon(text, "I=NEWTONS, e.g. 1=2.94")?;
    let tension = parse_number(value, "a tension in N")?;
    if tension < 0.0 {
        return Err(format!(
            "tension {} N is negative: a tendon can only pull",
            tdcr::Readable(tension)
        ));
    }
    Ok((index, tension))
}

/// `I=MU` (`solve --friction`): a tendon number and a friction coefficient >= 0.
pub fn parse_friction(text: &str) -> Result<(usize, f64), String> {
    let (index, value) = parse_tendon(text, "I=MU, e.g. 1=0.1")?;
    let mu = parse_number(value, "a friction coefficient")?;
    if mu < 0.0 {
        return Err(format!(
            "friction coefficient {} is negative: give 0 (none) or more",
            tdcr::Readable(mu)
        ));
    }
    Ok((index, mu))
}

/// `I=pull|release` (`--motion`): a tendon number and the motion its friction opposes.
pub fn parse_motion(text: &str) -> Result<(usize, tdcr::Motion), String> {
    let (index, value) = parse_tendon(text, "I=pull or I=release, e.g. 1=release")?;
    let name = value.trim();
    tdcr::Motion::from_name(name)
        .map(|motion| (index, motion))
        .ok_or_else(|| {
            format!(
                "motion `{name}` is neither `pull` nor `release`; give {}",
                tdcr::Motion::CHOICES
            )
        })
}

/// `I=METRES` (`--displacement`): a tendon number from 1 and its actuator pull-in in m
/// (negative lets the tendon out).
pub fn parse_displacement(text: &str) -> Result<(usize, f64), String> {
    let (index, value) = parse_tendon(text, "I=METRES, e.g. 1=0.002 (a pull-in in m; negative lets it out)")?;
    Ok((index, parse_number(value, "a displacement in m")?))
}

/// The values of `START:STOP:COUNT` (COUNT evenly spaced from START to STOP) or of a single
/// value; `text` is the whole argument and `form` its expected shape, for the messages.
fn range_values(value: &str, text: &str, form: &str, what: &str) -> Result<Vec<f64>, String> {
    match value.split(':').collect::<Vec<_>>().as_slice() {
        [single] => Ok(vec![parse_number(single, what)?]),
        [start, stop, count] => {
            let (a, b) = (parse_number(start, "START")?, parse_number(stop, "STOP")?);
            let count = parse_count(count).map_err(|e| format!("COUNT: {e}"))?;
            if count == 1 {
                Ok(vec![a])
            } else {
                Ok((0..count)
                    .map(|k| a + (b - a) * k as f64 / (count - 1) as f64)
                    .collect())
            }
        }
        _ => Err(format!("`{text}` must look like {form}")),
    }
}

/// `NAME=START:STOP:COUNT` or `NAME=VALUE` (`sweep --param`): the name as written (checked
/// against the robot later) and the values.
pub fn parse_param_sweep(text: &str) -> Result<(String, Vec<f64>), String> {
    let form = "NAME=START:STOP:COUNT or NAME=VALUE";
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}` must look like {form}"))?;
    Ok((name.trim().to_string(), range_values(value, text, form, "a value")?))
}

/// `I=START:STOP:COUNT` or `I=NEWTONS` (`sweep --tension`): a tendon number and its
/// tensions, COUNT evenly spaced values from START to STOP, all >= 0.
pub fn parse_sweep(text: &str) -> Result<(usize, Vec<f64>), String> {
    let (index, values) = parse_range(text, "a tension in N", "NEWTONS")?;
    if values.iter().any(|&t| t < 0.0) {
        return Err(format!("`{text}` has negative tensions: a tendon can only pull"));
    }
    Ok((index, values))
}

/// `I=START:STOP:COUNT` or `I=METRES` (`sweep --displacement`): actuator pull-ins in m,
/// negative ones (releases) allowed.
pub fn parse_displacement_sweep(text: &str) -> Result<(usize, Vec<f64>), String> {
    parse_range(text, "a displacement in m", "METRES")
}

/// A tendon number and COUNT evenly spaced values from START to STOP, or one value
/// (`what` names it in messages, `unit` is the single value's placeholder).
fn parse_range(text: &str, what: &str, unit: &str) -> Result<(usize, Vec<f64>), String> {
    let form = format!("I=START:STOP:COUNT or I={unit}");
    let (index, value) = parse_tendon(text, &form)?;
    Ok((index, range_values(value, text, &form, what)?))
}
