//! Continuation in the friction coefficients (docs/friction.md, "refuse21"): where Newton
//! with friction fails from the frictionless solution, every coefficient is scaled by a
//! factor `lambda` followed from 0 (the frictionless solution, constant tensions) to 1 (the
//! robot's own coefficients) on one mesh, each step's Newton starting from the last
//! converged step's states and log tensions, the log tensions scaled with `lambda` (the
//! capstan law's z is mu times the turning: exact for a shape that does not move).
//!
//! Released tendons with large mu deliver up to exp(mu theta) times their input, so the
//! frictionless shape can be far from the answer; the path from it by growing mu is the one
//! a robot takes as its channels' friction is switched on, and its steps are short where
//! the shape moves fast. A step whose Newton fails is halved; the continuation gives up
//! below [`SMALLEST_STEP`] or after [`MOST_STEPS`] Newton runs (then the caller's
//! refusal stands, with the work counted).

use super::*;

/// The first step in `lambda`.
const FIRST_STEP: f64 = 0.25;

/// The smallest step in `lambda`: a path that needs a shorter one turns back (a fold in
/// mu) or leaves the shapes Newton reaches, and the solve is refused.
const SMALLEST_STEP: f64 = 1.0 / 64.0;

/// Most Newton runs of one continuation (successful steps and halved ones): with steps
/// doubled after every success, a path that needs more is not going anywhere.
const MOST_STEPS: usize = 48;

/// Node states and log tensions (per slip, at every node) of a converged Newton with
/// friction, and the Newton runs it took.
type Solved = (Vec<State>, Vec<Vec<f64>>, usize);

/// `robot` with every friction coefficient scaled by `lambda` (> 0: the same tendons slip).
pub(super) fn scaled(robot: &Robot, lambda: f64) -> Robot {
    let mut scaled = robot.clone();
    for t in &mut scaled.tendons {
        if let Some(f) = &mut t.friction {
            f.coefficient *= lambda;
        }
    }
    scaled
}

/// Newton with friction for `robot` on `mesh` from the states `x` and the log tensions `z`
/// (per slip, at every node; None: the capstan start from `x`); the converged log tensions,
/// with `x` moved to the root, or where Newton failed its termination and the index of its
/// largest scaled residual (`x` is then undefined).
pub(super) fn newton_on(
    robot: &Robot,
    mesh: &Mesh,
    (x, z): (&mut Vec<State>, Option<&[Vec<f64>]>),
    (ws, settings): (&mut Workspace, &Settings),
    report: &mut SolveReport,
) -> std::result::Result<Vec<Vec<f64>>, (Termination, usize)> {
    let model = Model::new(robot);
    let mut system = System::new(model.clone(), mesh.clone());
    let mut profile = Profile::new(&model, &system.mesh);
    match z {
        Some(z) => profile.z = z.to_vec(),
        None => start::capstan_start(&model, &system.mesh, x, &mut profile, start::Settle::Guess),
    }
    system.friction = Some(profile);
    let mut border = Capstan::new(system);
    let (termination, worst) = newton::run_bordered(&mut border, ws, x, settings, report);
    if termination != Termination::Converged {
        return Err((termination, worst));
    }
    border.load(Point::Current);
    Ok(border.system.friction.as_ref().map(|p| p.z.clone()).unwrap_or_default())
}

/// Where a continuation gave up ([`in_friction`]).
pub(super) struct GaveUp {
    /// The largest fraction of the coefficients solved (0: none).
    pub(super) reached: f64,
    /// The fraction of the last Newton run, which failed.
    pub(super) tried: f64,
    /// That run's termination.
    pub(super) termination: Termination,
    /// The index of that run's largest scaled residual.
    pub(super) worst: usize,
    /// The node states at `reached` (the frictionless solution at 0).
    pub(super) x: Vec<State>,
    /// The log tensions there (per slip, at every node; None at 0: zero).
    pub(super) z: Option<Vec<Vec<f64>>>,
}

/// Follows the friction coefficients of `robot` from 0 to their values on `mesh`, from the
/// frictionless solution `x0` there ([module docs](self)): the states and log tensions
/// (per slip, at every node) of `robot` itself with the Newton runs taken, or where the
/// continuation gave up, how far it got and its last run's failure ([`GaveUp`]). Its Newton
/// counts go to `report`.
///
/// # Errors
/// A workspace that cannot be built for `mesh`.
pub(super) fn in_friction(
    robot: &Robot,
    options: &Options,
    mesh: &Mesh,
    x0: &[State],
    report: &mut SolveReport,
) -> Result<std::result::Result<Solved, GaveUp>> {
    let settings = fresh_settings(options);
    let mut ws = Workspace::new(&System::new(Model::new(robot), mesh.clone()), options.linear_solver)?;
    let (mut lambda, mut step) = (0.0, FIRST_STEP);
    let mut x = x0.to_vec();
    let mut z: Option<Vec<Vec<f64>>> = None;
    // The last failed run: its fraction, termination and worst residual's index.
    let mut failed = (0.0, Termination::MaxIterations, 0);
    for run in 1..=MOST_STEPS {
        let target = (lambda + step).min(1.0);
        let mut trial = x.clone();
        // The last step's log tensions grown with lambda; the capstan start on the first.
        let start = z.as_ref().map(|z| {
            let grow = target / lambda;
            z.iter()
                .map(|zj| zj.iter().map(|v| v * grow).collect())
                .collect::<Vec<Vec<f64>>>()
        });
        let owned;
        let robot_at = if target < 1.0 {
            owned = scaled(robot, target);
            &owned
        } else {
            robot
        };
        match newton_on(
            robot_at,
            mesh,
            (&mut trial, start.as_deref()),
            (&mut ws, &settings),
            report,
        ) {
            Ok(solved) => {
                if target >= 1.0 {
                    return Ok(Ok((trial, solved, run)));
                }
                (lambda, x, z) = (target, trial, Some(solved));
                step *= 2.0;
            }
            Err((termination, worst)) => {
                failed = (target, termination, worst);
                step /= 2.0;
                if step < SMALLEST_STEP {
                    break;
                }
            }
        }
    }
    let (tried, termination, worst) = failed;
    Ok(Err(GaveUp {
        reached: lambda,
        tried,
        termination,
        worst,
        x,
        z,
    }))
}

/// What following the friction coefficients on one mesh found ([`follow_on`]).
pub(super) enum Followed {
    /// The robot's node states and log tensions (per slip, at every node), and how they
    /// were reached (a clause for the report's note).
    Solved(Vec<State>, Vec<Vec<f64>>, String),
    /// Where the continuation gave up, and where the branch past it ends, if shown.
    Refused(GaveUp, Option<fold::End>),
}

/// The friction coefficients of `robot` followed from 0 on `mesh` from the frictionless
/// solution `x0` there: by [`in_friction`], and past where it gives up along the branch by
/// its arclength ([`fold::follow`]), to the robot's coefficients, or to where the branch
/// turns back or ends. Its Newton counts go to `report`.
///
/// # Errors
/// A workspace that cannot be built for `mesh`.
pub(super) fn follow_on(
    robot: &Robot,
    options: &Options,
    mesh: &Mesh,
    x0: &[State],
    report: &mut SolveReport,
) -> Result<Followed> {
    let mut gave_up = match in_friction(robot, options, mesh, x0, report)? {
        Ok((x, z, runs)) => {
            let how = format!("the friction coefficients were followed from 0 to their values in {runs} Newton runs");
            return Ok(Followed::Solved(x, z, how));
        }
        Err(gave_up) => gave_up,
    };
    let z = fold::flat(robot, mesh, gave_up.z.as_deref());
    let start = fold::BranchPoint {
        lambda: gave_up.reached,
        x: std::mem::take(&mut gave_up.x),
        z,
    };
    let ended = match fold::follow(robot, options, mesh, start, report)? {
        fold::Beyond::Answer(x, z, runs) => {
            let how = format!(
                "the friction coefficients were followed from 0 to {:.0} % of their values, and on to their values \
                 along the branch of equilibria by its arclength in {runs} corrector runs",
                100.0 * gave_up.reached
            );
            return Ok(Followed::Solved(x, z, how));
        }
        fold::Beyond::Ends(end) => Some(end),
        fold::Beyond::Unknown => None,
    };
    Ok(Followed::Refused(gave_up, ended))
}
