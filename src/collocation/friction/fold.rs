//! Past the end of the continuation in the friction coefficients (docs/friction.md,
//! "fold22"): the branch of equilibria from the frictionless shape followed on one mesh by
//! pseudo-arclength, the coefficients' fraction `lambda` an unknown, which tells a fold (the
//! branch turning back in `lambda`) and the branch's end where a tendon's path degenerates
//! from a solve Newton merely failed.
//!
//! Natural-parameter continuation ([`super::continuation`]) fixes `lambda` and cannot pass
//! a point where the branch turns back: there the bordered Jacobian A of the residual
//! (backbone and capstan rows) in the states and log tensions y is singular, and
//! dy/dlambda = -A^-1 F_lambda runs away. Here each point solves
//!
//! ```text
//! F(y, lambda) = 0,   t . (y - y_b, lambda - lambda_b) = ds
//! ```
//!
//! from the tangent predictor at the last point b (t its unit tangent in the scaled
//! unknowns and `lambda`), by Newton on the extended system by block elimination with A's
//! staircase factors: w = A^-1 (-F), u = A^-1 F_lambda, dy = w - u dlambda with dlambda from
//! the constraint row (F_lambda by central differences in `lambda`). The tangent is
//! (-u, 1) normalized, oriented along the last one; its `lambda` component changes sign
//! exactly where A is singular on the branch (det A changes sign there while the extended
//! system stays regular): a sign change between two converged points is a fold, located by
//! regula falsi on that component over the arclength. Where `lambda` reaches 1 instead,
//! the robot is solved there from the branch. Where the corrector fails at every step
//! length while a tendon's path has all but vanished (its speed below [`DEGENERATE`] of the
//! backbone's), the branch ends at the model's own singularity.

use super::continuation::{self, scaled};
use super::*;
use crate::collocation::newton::STEP_TOLERANCE;

/// The first step's growth in lambda (along the tangent).
const FIRST_STEP: f64 = 0.02;

/// The largest step in arclength (scaled unknowns and lambda).
const LARGEST_STEP: f64 = 0.5;

/// The smallest step in arclength: a branch that needs a shorter one is left unknown.
const SMALLEST_STEP: f64 = 1e-4;

/// Most corrector runs of one branch (steps and halved steps).
const MOST_RUNS: usize = 80;

/// Newton iterations of one corrector run.
const CORRECTOR_ITERATIONS: usize = 30;

/// The largest log tension followed (a delivered tension e^30 times the input): a branch
/// that has not turned back by then is left unknown.
const LARGEST_LOG_TENSION: f64 = 30.0;

/// Half the step in `lambda` of the central difference F_lambda: its truncation error
/// (relative 1e-10 for rows smooth in `lambda`) and rounding (1e-16 / 1e-5 of the rows) are
/// both far below what the corrector needs (it converges on the residual, not on the
/// column).
const DIFFERENCE: f64 = 1e-5;

/// Regula falsi iterations that locate a fold, and the width it stops at (relative to the
/// step that crossed it).
const FOLD_ITERATIONS: usize = 12;
const FOLD_WIDTH: f64 = 1e-6;

/// A converged point of the branch: the fraction of the coefficients, the node states and
/// the log tensions (the border's unknowns, in [`Capstan`]'s order).
#[derive(Clone)]
pub(super) struct BranchPoint {
    /// The fraction of the coefficients.
    pub(super) lambda: f64,
    /// The node states.
    pub(super) x: Vec<State>,
    /// The log tensions, in the border's order.
    pub(super) z: Vec<f64>,
}

/// Where the branch ends before `lambda` = 1 ([`follow`]).
#[derive(Clone, Debug)]
pub(super) struct End {
    /// Whether it turns back there (a fold); else a tendon's path degenerates there.
    pub(super) folded: bool,
    /// The fraction of the coefficients there.
    pub(super) lambda: f64,
    /// The tendon concerned (index in the robot): at a fold the one whose delivered
    /// tension moves most along the branch, else the one whose path degenerates.
    pub(super) tendon: usize,
    /// Its coefficient there (its own times `lambda`).
    pub(super) coefficient: f64,
    /// Its delivered tension there (N).
    pub(super) tension: f64,
    /// The tendon with friction whose path is slowest there, and that speed over the
    /// backbone's ([`path_speed`]).
    pub(super) slowest: (usize, f64),
}

/// What following the branch past the natural continuation found.
pub(super) enum Beyond {
    /// The branch reaches `lambda` = 1: the robot's states and log tensions (per slip, at
    /// every node), and the corrector runs taken.
    Answer(Vec<State>, Vec<Vec<f64>>, usize),
    /// The branch ends before `lambda` = 1: it turns back, or a tendon's path degenerates.
    Ends(End),
    /// Neither shown (the corrector failed elsewhere, or the parameter ran past its bound).
    Unknown,
}

/// A tendon's path whose speed falls below this fraction of the backbone's (its radius of
/// curvature within 1 % of the tendon's offset) ends the branch where the corrector fails
/// on: the tendon's load on the rod grows as the inverse cube of that speed (eq. 11's
/// |p_i'|^3), which vanishes where the rod's curvature reaches the inverse offset.
pub(super) const DEGENERATE: f64 = 0.01;

/// The border on `mesh` for `robot` at the log tensions `z` (its profile loaded).
fn border_at<'r>(robot: &'r Robot, mesh: &Mesh, z: &[f64]) -> Capstan<'r> {
    let model = Model::new(robot);
    let mut system = System::new(model.clone(), mesh.clone());
    system.friction = Some(Profile::new(&model, &system.mesh));
    let mut border = Capstan::new(system);
    border.z.copy_from_slice(z);
    border.trial_z.copy_from_slice(z);
    border.load(Point::Current);
    border
}

/// The residual (backbone rows, then capstan rows) of `robot` scaled by `lambda` at the
/// states `x` and log tensions `z` (counted in `report`); None on a model breakdown or a
/// value that is not finite.
fn residual(
    robot: &Robot,
    mesh: &Mesh,
    lambda: f64,
    (x, z): (&[State], &[f64]),
    report: &mut SolveReport,
) -> Option<Vec<f64>> {
    // At lambda <= 0 no tendon slips: not this border's system.
    if lambda <= 0.0 {
        return None;
    }
    let robot = scaled(robot, lambda);
    let mut border = border_at(&robot, mesh, z);
    let n = border.system.unknowns();
    let mut out = vec![0.0; n + z.len()];
    let ok = border.on(Point::Current, |s| {
        report.evaluations.residual += 1;
        report.evaluations.equations += s.rate_evaluations();
        s.residual(x, &mut out[..n]).is_ok()
    });
    border.rows(Point::Current, x);
    out[n..].copy_from_slice(border.residual(Point::Current));
    (ok && out.iter().all(|v| v.is_finite())).then_some(out)
}

/// The linearization at a point: the residual, F_lambda, and A's factors.
struct Linearized<'r> {
    border: Capstan<'r>,
    residual: Vec<f64>,
    /// F_lambda by central differences.
    column: Vec<f64>,
}

impl Linearized<'_> {
    /// Solves A d = `rhs` (backbone rows, then capstan rows): d's node unknowns, then its
    /// log tensions; None for a value that is not finite.
    fn solve(&mut self, rhs: &[f64]) -> Option<Vec<f64>> {
        let n = self.border.system.unknowns();
        let mut d = vec![0.0; n + self.border.z.len()];
        self.border.solve_factored(&rhs[..n], &rhs[n..], &mut d[..n])?;
        d[n..].copy_from_slice(&self.border.border_step);
        d.iter().all(|v| v.is_finite()).then_some(d)
    }
}

/// The Jacobian A of `robot` scaled by `point.lambda` at the point, factored, with the
/// residual there and F_lambda (counted in `report`); None on a model breakdown or a
/// singular matrix.
fn linearize<'r>(
    robot: &Robot,
    mesh: &Mesh,
    (at, point): (&'r Robot, &BranchPoint),
    report: &mut SolveReport,
) -> Option<Linearized<'r>> {
    // Central where lambda - DIFFERENCE > 0, else forward (no slip at lambda <= 0).
    let low = if point.lambda > DIFFERENCE {
        point.lambda - DIFFERENCE
    } else {
        point.lambda
    };
    let high = low + 2.0 * DIFFERENCE;
    let up = residual(robot, mesh, high, (&point.x, &point.z), report)?;
    let down = residual(robot, mesh, low, (&point.x, &point.z), report)?;
    let column = up.iter().zip(&down).map(|(a, b)| (a - b) / (high - low)).collect();
    let mut border = border_at(at, mesh, &point.z);
    let n = border.system.unknowns();
    let mut residual = vec![0.0; n + point.z.len()];
    let mut values = vec![0.0; unknowns::nonzeros(&border.system.mesh)];
    let ok = border.on(Point::Current, |s| {
        s.jacobian(&point.x, &mut residual[..n], &mut values).is_ok()
    });
    if !ok || !values.iter().all(|v| v.is_finite()) {
        return None;
    }
    border.rows(Point::Current, &point.x);
    residual[n..].copy_from_slice(border.residual(Point::Current));
    border.read_border(&point.x).ok()?;
    if !border.factor(&values) || !residual.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(Linearized {
        border,
        residual,
        column,
    })
}

/// The max-norm of a slice.
fn max_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m: f64, x| m.max(x.abs()))
}

/// `point` moved by `alpha` times the step (node unknowns, log tensions; `dlambda`).
fn moved(point: &BranchPoint, step: &[f64], dlambda: f64, alpha: f64, length: f64) -> BranchPoint {
    let n = step.len() - point.z.len();
    let mut x = Vec::with_capacity(point.x.len());
    unknowns::retract(&point.x, &step[..n], alpha, length, &mut x);
    BranchPoint {
        lambda: point.lambda + alpha * dlambda,
        x,
        z: point.z.iter().zip(&step[n..]).map(|(z, d)| z + alpha * d).collect(),
    }
}

/// The unit tangent (dy, dlambda) of the branch from u = A^-1 F_lambda, (-u, 1) normalized,
/// its sign such that its product with `along` is positive (with no `along`: lambda grows).
fn tangent(u: &[f64], along: Option<&[f64]>) -> Vec<f64> {
    let mut t: Vec<f64> = u.iter().map(|v| -v).chain([1.0]).collect();
    let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
    let dot = along.map_or(1.0, |a| a.iter().zip(&t).map(|(a, b)| a * b).sum::<f64>());
    let scale = if dot < 0.0 { -1.0 / norm } else { 1.0 / norm };
    t.iter_mut().for_each(|v| *v *= scale);
    t
}

/// Newton on the extended system F(y, lambda) = 0, t . (y - y_b, lambda - lambda_b) = `ds`
/// from the tangent predictor at `base` (the module docs; `t` the unit tangent there, the
/// difference in y the sum of the steps taken, in scaled unknowns): the converged point and
/// its unit tangent (oriented along `t`), its Newton iterations and evaluations counted in
/// `report`; None where it fails.
fn correct(
    robot: &Robot,
    mesh: &Mesh,
    (base, t): (&BranchPoint, &[f64]),
    ds: f64,
    tolerance: f64,
    report: &mut SolveReport,
) -> Option<(BranchPoint, Vec<f64>)> {
    let length = robot.length();
    let last = t.len() - 1;
    // The steps taken from the base, the last entry lambda's.
    let mut taken: Vec<f64> = t.iter().map(|v| v * ds).collect();
    let mut point = moved(base, &taken[..last], taken[last], 1.0, length);
    for _ in 0..CORRECTOR_ITERATIONS {
        let at = scaled(robot, point.lambda);
        let mut linear = linearize(robot, mesh, (&at, &point), report)?;
        let minus: Vec<f64> = linear.residual.iter().map(|f| -f).collect();
        let w = linear.solve(&minus)?;
        let column = std::mem::take(&mut linear.column);
        let u = linear.solve(&column)?;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        // t . (taken + (w - u dlambda, dlambda)) = ds.
        let ahead: Vec<f64> = taken[..last].iter().zip(&w).map(|(a, b)| a + b).collect();
        let denominator = t[last] - dot(&t[..last], &u);
        let dlambda = (ds - dot(&t[..last], &ahead) - t[last] * taken[last]) / denominator;
        let step: Vec<f64> = w.iter().zip(&u).map(|(w, u)| w - u * dlambda).collect();
        let size = max_norm(&step).max(dlambda.abs());
        if !size.is_finite() {
            return None;
        }
        // The step that remains bounds the error (Newton converges quadratically here).
        if max_norm(&linear.residual) <= tolerance && size <= STEP_TOLERANCE {
            return Some((point, tangent(&u, Some(t))));
        }
        report.iterations += 1;
        report.newton_steps += 1;
        // The merit 0.5 |(F, constraint)|^2 with Armijo's test (its slope along the Newton
        // step is -2 merit).
        let constraint = |taken: &[f64]| dot(t, taken) - ds;
        let merit = |r: &[f64], c: f64| 0.5 * (r.iter().map(|v| v * v).sum::<f64>() + c * c);
        let phi = merit(&linear.residual, constraint(&taken));
        let mut alpha = 1.0;
        loop {
            let trial = moved(&point, &step, dlambda, alpha, length);
            let trial_taken: Vec<f64> = taken
                .iter()
                .zip(step.iter().chain([&dlambda]))
                .map(|(a, d)| a + alpha * d)
                .collect();
            if let Some(r) = residual(robot, mesh, trial.lambda, (&trial.x, &trial.z), report)
                && merit(&r, constraint(&trial_taken)) <= (1.0 - 2e-4 * alpha) * phi
            {
                (point, taken) = (trial, trial_taken);
                break;
            }
            alpha *= 0.5;
            if alpha < 1.0 / 1024.0 {
                return None;
            }
        }
    }
    None
}

/// Follows the branch of `robot`'s equilibria on `mesh` from `start` (a converged point of
/// the natural continuation) past where the natural continuation gave up ([module
/// docs](self)): a fold with where it is, the answer at `lambda` = 1 where the branch
/// reaches it (the robot solved there by the plain bordered Newton from the branch), or
/// neither. Its Newton iterations and evaluations are counted in `report`.
///
/// # Errors
/// A workspace that cannot be built for `mesh`.
pub(super) fn follow(
    robot: &Robot,
    options: &Options,
    mesh: &Mesh,
    start: BranchPoint,
    report: &mut SolveReport,
) -> Result<Beyond> {
    let tolerance = options.residual_tolerance;
    // From the frictionless solution (no step converged) there is no border to follow.
    if start.lambda <= 0.0 {
        return Ok(Beyond::Unknown);
    }
    let at = scaled(robot, start.lambda);
    let Some(mut first) = linearize(robot, mesh, (&at, &start), report) else {
        return Ok(Beyond::Unknown);
    };
    let column = std::mem::take(&mut first.column);
    let Some(u) = first.solve(&column) else {
        return Ok(Beyond::Unknown);
    };
    let mut t = tangent(&u, None);
    let last = t.len() - 1;
    // The first step: FIRST_STEP in lambda along the tangent.
    let mut ds = FIRST_STEP / t[last];
    let mut point = start;
    let mut runs = 0;
    while runs < MOST_RUNS && point.lambda > 0.0 && max_norm(&point.z) < LARGEST_LOG_TENSION {
        runs += 1;
        let Some((next, next_t)) = correct(robot, mesh, (&point, &t), ds, tolerance, report) else {
            ds /= 2.0;
            if ds < SMALLEST_STEP {
                // Where a tendon's path has all but vanished, the model ends there.
                let (tendon, speed) = path_speed(robot, mesh, &point);
                if speed < DEGENERATE {
                    let (_, coefficient, tension) = delivered(robot, mesh, &point, Some(tendon), &t);
                    return Ok(Beyond::Ends(End {
                        folded: false,
                        lambda: point.lambda,
                        tendon,
                        coefficient: coefficient * point.lambda,
                        tension,
                        slowest: (tendon, speed),
                    }));
                }
                return Ok(Beyond::Unknown);
            }
            continue;
        };
        if next.lambda >= 1.0 {
            // The branch reaches the robot's own coefficients: Newton at lambda = 1 from
            // the branch's nearest point.
            return at_one(robot, options, mesh, [&next, &point], (runs, report));
        }
        if next_t[last] <= 0.0 && t[last] > 0.0 {
            let top = locate(robot, mesh, (&point, &t), (ds, next_t[last]), tolerance, report);
            let (tendon, coefficient, tension) = delivered(robot, mesh, &top, None, &next_t);
            let slowest = path_speed(robot, mesh, &top);
            return Ok(Beyond::Ends(End {
                folded: true,
                lambda: top.lambda,
                tendon,
                coefficient: coefficient * top.lambda,
                tension,
                slowest,
            }));
        }
        (point, t) = (next, next_t);
        ds = (2.0 * ds).min(LARGEST_STEP);
    }
    Ok(Beyond::Unknown)
}

/// The robot (`lambda` = 1) solved by the bordered Newton from the nearer of `points` to
/// `lambda` = 1, then the other (its Newton counts to `report`).
///
/// # Errors
/// A workspace that cannot be built for `mesh`.
fn at_one(
    robot: &Robot,
    options: &Options,
    mesh: &Mesh,
    points: [&BranchPoint; 2],
    (runs, report): (usize, &mut SolveReport),
) -> Result<Beyond> {
    let settings = fresh_settings(options);
    let mut ws = Workspace::new(&System::new(Model::new(robot), mesh.clone()), options.linear_solver)?;
    let mut order = points;
    order.sort_by(|a, b| (a.lambda - 1.0).abs().total_cmp(&(b.lambda - 1.0).abs()));
    for p in order {
        let mut x = p.x.clone();
        let z = per_slip(robot, mesh, &p.z);
        if let Ok(z) = continuation::newton_on(robot, mesh, (&mut x, Some(&z)), (&mut ws, &settings), report) {
            return Ok(Beyond::Answer(x, z, runs + 1));
        }
    }
    Ok(Beyond::Unknown)
}

/// The border's log tensions `z` on `mesh`, per slip at every node (the profile's).
fn per_slip(robot: &Robot, mesh: &Mesh, z: &[f64]) -> Vec<Vec<f64>> {
    let border = border_at(robot, mesh, z);
    border.system.friction.as_ref().map(|p| p.z.clone()).unwrap_or_default()
}

/// The border's log tensions on `mesh` from the profile's `z` (per slip, at every node;
/// None: zero).
pub(super) fn flat(robot: &Robot, mesh: &Mesh, z: Option<&[Vec<f64>]>) -> Vec<f64> {
    let model = Model::new(robot);
    let mut system = System::new(model.clone(), mesh.clone());
    let mut profile = Profile::new(&model, &system.mesh);
    if let Some(z) = z {
        profile.z = z.to_vec();
    }
    system.friction = Some(profile);
    Capstan::new(system).z
}

/// Regula falsi (Illinois) on dlambda/ds over the arclength from `a` (tangent `t`, lambda
/// rising) to `ds`, where it is `end` (not rising): the point of the branch with the largest
/// lambda met.
fn locate(
    robot: &Robot,
    mesh: &Mesh,
    (a, t): (&BranchPoint, &[f64]),
    (ds, end): (f64, f64),
    tolerance: f64,
    report: &mut SolveReport,
) -> BranchPoint {
    let last = t.len() - 1;
    let mut best = a.clone();
    let (mut low, mut g_low, mut high, mut g_high) = (0.0, t[last], ds, end);
    // Which end was replaced last (for Illinois' halving of the other's value).
    let mut moved_low = None;
    for _ in 0..FOLD_ITERATIONS {
        if high - low <= FOLD_WIDTH * ds {
            break;
        }
        let s = low + g_low / (g_low - g_high) * (high - low);
        let Some((c, tc)) = correct(robot, mesh, (a, t), s, tolerance, report) else {
            break;
        };
        let g = tc[last];
        if c.lambda > best.lambda {
            best = c;
        }
        if g > 0.0 {
            if moved_low == Some(true) {
                g_high /= 2.0;
            }
            (low, g_low, moved_low) = (s, g, Some(true));
        } else {
            if moved_low == Some(false) {
                g_low /= 2.0;
            }
            (high, g_high, moved_low) = (s, g, Some(false));
        }
    }
    best
}

/// The slip of `tendon` (None: the one whose delivered tension moves most along the tangent
/// `t`, in newtons) at `point` on `mesh`: its tendon (index in the robot), its coefficient in
/// `robot`, and its delivered tension at `point` (N).
fn delivered(robot: &Robot, mesh: &Mesh, point: &BranchPoint, tendon: Option<usize>, t: &[f64]) -> (usize, f64, f64) {
    let border = border_at(robot, mesh, &point.z);
    let Some(profile) = border.system.friction.as_ref() else {
        return (0, f64::NAN, f64::NAN);
    };
    let n = t.len() - 1 - point.z.len();
    let end = |j: usize| border.offsets[j] + profile.spans[j] - 1;
    let j = match tendon.and_then(|i| profile.slipping.iter().position(|&s| s == i)) {
        Some(j) => j,
        None => {
            let moves = |j: usize| t[n + end(j)].abs() * profile.tension(j, point.z[end(j)]);
            (0..profile.count())
                .max_by(|&a, &b| moves(a).total_cmp(&moves(b)))
                .unwrap_or(0)
        }
    };
    let tendon = profile.slipping[j];
    let coefficient = robot.tendons[tendon].friction.map_or(f64::NAN, |f| f.coefficient);
    (tendon, coefficient, profile.tension(j, point.z[end(j)]))
}

/// The tendon with friction whose path is slowest at a node of `point`, and that speed
/// over the backbone's: |v + u x r + r'| / |v + r'| in the body frame (eq. 11's p_i'
/// against its value without bending), smallest over the nodes in its span.
fn path_speed(robot: &Robot, mesh: &Mesh, point: &BranchPoint) -> (usize, f64) {
    let model = Model::new(robot);
    let length = robot.length();
    let mut slowest = (0, f64::INFINITY);
    for (i, t) in robot.tendons.iter().enumerate() {
        if t.active_friction().is_none() {
            continue;
        }
        for (state, node) in point.x.iter().zip(&mesh.nodes) {
            if state.s > t.end(length) {
                continue;
            }
            let site = model.site_on(state.s, node.segment_end);
            let v = site.strain(&state.v);
            let at = t.routing.at(state.s, length);
            let speed = (v + state.u.cross(&at.r) + at.r_s).norm() / (v + at.r_s).norm();
            if speed < slowest.1 {
                slowest = (i, speed);
            }
        }
    }
    slowest
}
