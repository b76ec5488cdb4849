//! The shooting solver, kept as an independent cross-check of collocation.
//!
//! Unknowns: the base strains (v(0), u(0)), 6 numbers. Each trial integrates eq. 13 from the
//! base with the Dormand-Prince 5(4) embedded Runge-Kutta pair, stepping the rotation on
//! SO(3) by Runge-Kutta-Munthe-Kaas (each step works in the local coordinates
//! R = R_n exp(theta), theta' = J_r(theta)^-1 u, so R stays orthonormal). At every interior
//! breakpoint the right-hand strains are found from the jump conditions by a small Newton
//! solve; the 6 tip conditions are the residual of an outer damped Newton iteration whose
//! Jacobian is taken by central differences. Displacement-controlled tendons add their
//! tensions to the unknowns and their complementarity (taut at its length or slack at 0 N,
//! in the Fischer-Burmeister form of collocation) to the residual, the path lengths
//! integrated along with the state (docs/actuation.md).
#![allow(non_snake_case)]

use crate::collocation::MAX_ITERATIONS;
use crate::error::{Result, invalid};
use crate::mesh::guess::{self, InitialGuess};
use crate::mesh::{Mesh, nodes};
use crate::model::equations::{Model, Site};
use crate::model::length;
use crate::report::{Iteration, Method, SolveReport, Termination};
use crate::solution::{Solution, State};
use crate::{Error, Readable, Robot, so3};
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector, Vector3};
use num_dual::DualSVec64;
use std::time::Instant;

/// Shooting options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Relative and absolute local error tolerance of the integrator on the scaled state
    /// (p / L, theta, v, u L). Default 1e-10; down to 1e-12 is supported.
    pub integration_tolerance: f64,
    /// Newton stops when the scaled tip residual is below this. Default 1e-9 (dimensionless).
    pub tolerance: f64,
    /// Newton iteration limit. Default 50; at most [`MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// Where Newton starts. Default: the rigid-equilibrium estimate.
    pub initial_guess: InitialGuess,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            integration_tolerance: 1e-10,
            tolerance: 1e-9,
            max_iterations: 50,
            initial_guess: InitialGuess::RigidEquilibrium,
        }
    }
}

impl Options {
    /// Checks the options: the integration tolerance in [1e-14, 1e-2], a positive Newton
    /// tolerance, from one to [`MAX_ITERATIONS`] iterations.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field.
    pub fn validate(&self) -> Result<()> {
        // 1e-14: below this the local error test is pure rounding and steps collapse
        if !(self.integration_tolerance.is_finite() && (1e-14..=1e-2).contains(&self.integration_tolerance)) {
            return Err(invalid(
                "shooting.integration_tolerance",
                format!("is {}", Readable(self.integration_tolerance)),
                "use a value in [1e-14, 1e-2] (1e-10 by default)",
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(invalid(
                "shooting.tolerance",
                format!("is {}", Readable(self.tolerance)),
                "use a positive value (1e-9 by default)",
            ));
        }
        if self.max_iterations == 0 {
            return Err(invalid(
                "shooting.max_iterations",
                "is 0",
                "allow at least one Newton iteration",
            ));
        }
        if self.max_iterations > MAX_ITERATIONS {
            return Err(invalid(
                "shooting.max_iterations",
                format!("is {}, above the limit of {MAX_ITERATIONS}", self.max_iterations),
                "Newton converges in a few dozen iterations or not at all, so more only costs memory; the default is 50",
            ));
        }
        Ok(())
    }
}

/// A point of the integrated trajectory.
type Point = State;

/// Local-coordinate state (p, theta, v, u) of one integration step.
type Local = SVector<f64, 12>;

/// Solves `robot` by shooting.
///
/// Displacement-controlled tendons (docs/actuation.md) add their tensions to the unknowns
/// and one complementarity row each to the residual, in the Fischer-Burmeister form of the
/// collocation solve: psi_j = sqrt(a^2 + b^2) - a - b with a = tau_j / T_j and
/// b = phi_j / L, phi_j = l_ref_j - l_j - q_j + c_j tau_j the gap, the path lengths l_j
/// integrated along with the state. psi_j = 0 exactly when the tendon is taut (phi_j = 0,
/// tau_j >= 0) or slack (tau_j = 0, phi_j >= 0), so one semismooth Newton iteration finds
/// which tendons are slack; at convergence a tendon on the slack side gets exactly 0 N.
///
/// # Errors
/// Invalid input, a model breakdown, or [`Error::NotConverged`] with the report.
pub fn solve(robot: &Robot, options: &Options) -> Result<Solution> {
    robot.validate()?;
    options.validate()?;
    let start = Instant::now();
    let mut problem = Problem::new(robot);
    let mut report = SolveReport::new(Method::Shooting);
    report.meshes = 1;
    report.load_steps = 1;

    // Initial guess: base strains of the rigid-equilibrium estimate at the starting tensions.
    let base = guess::initial(
        &Model::new(&problem.robot),
        &Mesh::uniform(robot, 64)?.nodes,
        options.initial_guess,
    )[0];
    let base_x = problem.scale.to_unknowns(&base.v, &base.u);
    let x0 = problem.unknowns(&base_x);
    report.unknowns = x0.len();
    let (x, smooth, mut trajectory) = newton(&mut problem, x0, options, &mut report)?;
    if problem.finish(&x, &smooth) {
        // A slack tendon's tension went from its iterate (within the tolerance of 0) to
        // exactly 0: integrate once more, so that the shape is the one of the tensions
        // reported, and report the residual there.
        let at = problem.unknowns(&x.fixed_rows::<6>(0).into_owned());
        let mut traj = Vec::new();
        let g = problem.residual(&at, options, &mut traj, &mut report)?;
        report.residual = problem.complementarity(&at, &g).amax();
        trajectory = traj;
    }
    report.intervals = trajectory.len().saturating_sub(1);
    report.timings.total = start.elapsed();
    let model = Model::new(&problem.robot);
    let ends = segment_ends(&model, &trajectory);
    nodes::solution(&model, &trajectory, &ends, None, report)
}

/// The merit a trial step must decrease: the residual's max-norm for tension inputs (as
/// before displacement inputs), its Euclidean norm with complementarity rows, since the
/// semismooth Newton step is a descent direction of 0.5 |F|^2 (De Luca, Facchinei & Kanzow
/// 1996) but need not decrease the max-norm.
fn merit(res: &DVector<f64>, complementarity: bool) -> f64 {
    if complementarity { res.norm() } else { res.amax() }
}

/// The Newton iteration from `x`: the converged unknowns, the smooth residual there
/// ([`Problem::residual`]) and the trajectory.
fn newton(
    problem: &mut Problem,
    mut x: DVector<f64>,
    options: &Options,
    report: &mut SolveReport,
) -> Result<(DVector<f64>, DVector<f64>, Vec<Point>)> {
    let length = problem.robot.length();
    let bordered = !problem.displaced.is_empty();
    let mut trajectory = Vec::new();
    let mut smooth = problem.residual(&x, options, &mut trajectory, report)?;
    let mut res = problem.complementarity(&x, &smooth);
    let mut norm = res.amax();
    report.termination = Termination::MaxIterations;
    for _ in 0..options.max_iterations {
        if norm < options.tolerance {
            report.termination = Termination::Converged;
            break;
        }
        // A breakdown while differencing (a trial state where a tendon loses its tangent,
        // say) ends the iteration: the state is unphysical, not the input.
        let Ok(J) = jacobian(problem, &x, &smooth, options, report) else {
            report.termination = Termination::NonFinite;
            break;
        };
        let Some(step) = problem.bounded_step(&J, &x, &res) else {
            report.termination = Termination::SingularJacobian;
            break;
        };
        if !step.iter().all(|v| v.is_finite()) {
            report.termination = Termination::SingularJacobian;
            break;
        }
        // Backtracking: halve until the merit decreases (Armijo-free: the cross-check
        // only needs robustness, not efficiency).
        let current = merit(&res, bordered);
        let mut damping = 1.0;
        let mut accepted = false;
        while damping > 1e-4 {
            let trial = problem.project(&x + &step * damping);
            let mut traj = Vec::new();
            if let Ok(g) = problem.residual(&trial, options, &mut traj, report) {
                let r = problem.complementarity(&trial, &g);
                if r.amax().is_finite() && (merit(&r, bordered) < current || r.amax() <= options.tolerance) {
                    report.iterations += 1;
                    report.newton_steps += 1;
                    report.history.push(Iteration {
                        residual: norm,
                        step: step.amax(),
                        damping,
                        fresh_jacobian: true,
                    });
                    x = trial;
                    norm = r.amax();
                    res = r;
                    smooth = g;
                    trajectory = traj;
                    accepted = true;
                    break;
                }
            }
            damping *= 0.5;
        }
        if !accepted {
            report.termination = Termination::LineSearchFailed;
            break;
        }
    }
    if norm < options.tolerance {
        report.termination = Termination::Converged;
        // One more full Newton step, kept only if it lowers the residual: at quadratic
        // convergence it takes the residual from the tolerance down to the noise floor.
        let J = jacobian(problem, &x, &smooth, options, report)?;
        if let Some(step) = problem.bounded_step(&J, &x, &res) {
            let trial = problem.project(&x + &step);
            let mut traj = Vec::new();
            if let Ok(g) = problem.residual(&trial, options, &mut traj, report) {
                let r = problem.complementarity(&trial, &g);
                if r.amax() < norm {
                    report.iterations += 1;
                    report.newton_steps += 1;
                    report.history.push(Iteration {
                        residual: norm,
                        step: step.amax(),
                        damping: 1.0,
                        fresh_jacobian: true,
                    });
                    norm = r.amax();
                    x = trial;
                    smooth = g;
                    trajectory = traj;
                }
            }
        }
    }
    problem.set_tensions(&x);
    report.residual = norm;
    if report.termination != Termination::Converged {
        report.intervals = trajectory.len().saturating_sub(1);
        return Err(Error::NotConverged {
            method: Method::Shooting,
            report: Box::new(report.clone()),
            worst_s: length,
            hint: "shooting is a cross-check; use collocation (with load continuation) for hard cases".into(),
        });
    }
    Ok((x, smooth, trajectory))
}

/// A displacement-controlled tendon's length constraint.
struct Constraint {
    /// Index of the tendon in the robot.
    tendon: usize,
    /// Pull-in q_j (m).
    displacement: f64,
    /// l_ref_j (m).
    reference_length: f64,
    /// c_j (m/N).
    compliance: f64,
    /// Where the tendon ends (m): its path length is integrated up to here.
    end: f64,
}

impl Constraint {
    /// phi_j (m) at path length `l` and tension `tau`.
    fn gap(&self, l: f64, tau: f64) -> f64 {
        self.reference_length - l - self.displacement + self.compliance * tau
    }
}

/// psi(a, b) = sqrt(a^2 + b^2) - a - b and (dpsi/da, dpsi/db) = (a / r - 1, b / r - 1),
/// r = sqrt(a^2 + b^2); at a = b = 0, where psi is not differentiable, the element
/// (1/sqrt 2 - 1)(1, 1) of its generalized gradient (as collocation, docs/actuation.md).
fn fischer_burmeister(a: f64, b: f64) -> (f64, f64, f64) {
    let r = a.hypot(b);
    if r == 0.0 {
        let g = std::f64::consts::FRAC_1_SQRT_2 - 1.0;
        (0.0, g, g)
    } else {
        (r - a - b, a / r - 1.0, b / r - 1.0)
    }
}

/// The shooting problem: the robot at the current tensions, the length constraints and
/// the scaling of the unknowns.
struct Problem {
    /// The robot, its displacement-controlled tendons at the current tensions.
    robot: Robot,
    /// One per displacement-controlled tendon, in tendon order.
    displaced: Vec<Constraint>,
    scale: Scale,
}

impl Problem {
    fn new(robot: &Robot) -> Self {
        let mut work = robot.clone();
        let length = robot.length();
        if robot.has_displacement_inputs() {
            crate::collocation::actuation::starting_tensions(&mut work, None);
        }
        let displaced: Vec<Constraint> = (0..robot.tendons.len())
            .filter(|&i| robot.tendons[i].displacement().is_some())
            .map(|i| {
                let t = &work.tendons[i];
                let reference_length = length::reference_length(robot, i);
                Constraint {
                    tendon: i,
                    displacement: t.displacement().unwrap_or(0.0),
                    reference_length,
                    compliance: t.compliance(reference_length),
                    end: t.end(length),
                }
            })
            .collect();
        let tension_scales = displaced.iter().map(|c| robot.tension_scale(c.tendon)).collect();
        Problem {
            robot: work,
            displaced,
            scale: Scale { length, tension_scales },
        }
    }

    /// The unknowns: the scaled base strains, then tau_j / T_j of every
    /// displacement-controlled tendon at its current tension.
    fn unknowns(&self, base: &SVector<f64, 6>) -> DVector<f64> {
        let tensions = self
            .displaced
            .iter()
            .zip(&self.scale.tension_scales)
            .map(|(c, t)| self.robot.tendons[c.tendon].tension() / t);
        DVector::from_iterator(6 + self.displaced.len(), base.iter().copied().chain(tensions))
    }

    /// `x` with its tensions at least 0. The model drops a tendon at a tension <= 0 (a
    /// string cannot push), so the tip residual does not depend on a negative tension
    /// and a Newton step that makes one negative predicts an effect that does not occur;
    /// the iterates are kept at tau >= 0, where the residual is smooth (projected
    /// semismooth Newton). A slack tendon's psi row then drives its tension to 0 exactly.
    fn project(&self, mut x: DVector<f64>) -> DVector<f64> {
        for j in 6..x.len() {
            x[j] = x[j].max(0.0);
        }
        x
    }

    /// The Newton step from `x` (Newton matrix `J`, residual `res`) with the tensions at
    /// their bound 0 that the step would make negative held there: their columns and psi
    /// rows are dropped and the rest solved again, until no held tension remains to add.
    /// Projecting such a step instead would spoil it: the other components count on the
    /// tension's (non-existent) negative effect, which for a tendon's axial load is
    /// enormous (a change of v at the base of E A L^2 / E I times the tip's response).
    /// `None` when a system is singular.
    fn bounded_step(&self, J: &DMatrix<f64>, x: &DVector<f64>, res: &DVector<f64>) -> Option<DVector<f64>> {
        let n = x.len();
        let mut held = vec![false; n];
        loop {
            let free: Vec<usize> = (0..n).filter(|&j| !held[j]).collect();
            let Jr = DMatrix::from_fn(free.len(), free.len(), |r, c| J[(free[r], free[c])]);
            let rr = DVector::from_iterator(free.len(), free.iter().map(|&r| -res[r]));
            let reduced = Jr.lu().solve(&rr)?;
            let mut step = DVector::zeros(n);
            for (&j, &d) in free.iter().zip(reduced.iter()) {
                step[j] = d;
            }
            let mut more = false;
            for j in 6..n {
                if !held[j] && x[j] <= 0.0 && step[j] < 0.0 {
                    held[j] = true;
                    more = true;
                }
            }
            if !more {
                return Some(step);
            }
        }
    }

    /// Sets the tensions of the displacement-controlled tendons from the unknowns `x`.
    fn set_tensions(&mut self, x: &DVector<f64>) {
        for (j, (c, t)) in self.displaced.iter().zip(&self.scale.tension_scales).enumerate() {
            self.robot.tendons[c.tendon].hold_tension(x[6 + j] * t);
        }
    }

    /// After convergence at `x`, with `smooth` the residual there: a tendon on the slack
    /// side (b > a) gets exactly 0 N (its iterate is then within the tolerance of 0), a
    /// taut one at least 0. Whether a tension changed.
    fn finish(&mut self, x: &DVector<f64>, smooth: &DVector<f64>) -> bool {
        self.set_tensions(x);
        let mut changed = false;
        for (j, c) in self.displaced.iter().enumerate() {
            let tendon = &mut self.robot.tendons[c.tendon];
            let tension = tendon.tension();
            let exact = if smooth[6 + j] > x[6 + j] {
                0.0
            } else {
                tension.max(0.0)
            };
            if exact != tension {
                tendon.hold_tension(exact);
                changed = true;
            }
        }
        changed
    }

    /// The smooth residual at `x`: the scaled tip wrench (f in N, m L) and phi_j / L of
    /// every displacement-controlled tendon. Sets the tensions to those of `x`.
    fn residual(
        &mut self,
        x: &DVector<f64>,
        options: &Options,
        traj: &mut Vec<Point>,
        report: &mut SolveReport,
    ) -> Result<DVector<f64>> {
        self.set_tensions(x);
        let paths: Vec<(usize, f64)> = self.displaced.iter().map(|c| (c.tendon, c.end)).collect();
        let model = Model::new(&self.robot);
        let base = x.fixed_rows::<6>(0).into_owned();
        let (tip, lengths) = shoot(&model, &self.scale, &base, &paths, options, traj, report)?;
        let length = self.scale.length;
        let gaps = self
            .displaced
            .iter()
            .zip(&lengths)
            .map(|(c, &l)| c.gap(l, self.robot.tendons[c.tendon].tension()) / length);
        Ok(DVector::from_iterator(x.len(), tip.iter().copied().chain(gaps)))
    }

    /// The Newton residual from the smooth one `smooth` at `x`: the tip rows, then
    /// psi(tau_j / T_j, phi_j / L) of each displacement-controlled tendon.
    fn complementarity(&self, x: &DVector<f64>, smooth: &DVector<f64>) -> DVector<f64> {
        let mut out = smooth.clone();
        for j in 0..self.displaced.len() {
            out[6 + j] = fischer_burmeister(x[6 + j], smooth[6 + j]).0;
        }
        out
    }
}

/// The end of the segment each trajectory point belongs to (a breakpoint appears twice:
/// left limit, then right limit).
fn segment_ends(model: &Model, traj: &[Point]) -> Vec<f64> {
    let length = model.robot.length();
    let breaks = model.robot.breakpoints();
    let mut out = Vec::with_capacity(traj.len());
    for (k, pt) in traj.iter().enumerate() {
        let is_right_limit = k > 0 && traj[k - 1].s == pt.s;
        let end = breaks
            .iter()
            .copied()
            .find(|&b| if is_right_limit { b > pt.s } else { b >= pt.s })
            .unwrap_or(length);
        out.push(end);
    }
    out
}

/// The unknowns: the base strains (v, u L) and tau_j / T_j of the
/// displacement-controlled tendons, T_j = E I / (L |r_j(0)|) the tension that bends the
/// rod through about a radian (E I / L^2 on the centreline). Central differences in these
/// units with step 1e-6 keep the Jacobian well above the integration noise for the
/// strains of ordinary rods; for rods extremely stiff in shear and extension (EA L^2 / EI
/// above about 1e6) the v columns become noise-limited, one reason shooting is only a
/// cross-check.
struct Scale {
    /// L (m).
    length: f64,
    /// T_j (N), one per displacement-controlled tendon.
    tension_scales: Vec<f64>,
}

impl Scale {
    fn to_unknowns(&self, v: &Vector3<f64>, u: &Vector3<f64>) -> SVector<f64, 6> {
        SVector::<f64, 6>::from_iterator(v.iter().copied().chain(u.iter().map(|x| x * self.length)))
    }
    fn strains(&self, x: &SVector<f64, 6>) -> (Vector3<f64>, Vector3<f64>) {
        (x.fixed_rows::<3>(0).into(), x.fixed_rows::<3>(3) / self.length)
    }
}

/// The Newton matrix at `x`, `smooth` the smooth residual there: central differences of
/// the smooth residual (tip wrench and gaps, [`Problem::residual`]), then each gap row
/// turned into the row of psi_j by the chain rule with the (generalized) gradient of the
/// Fischer-Burmeister function. Differencing psi itself would straddle its kink at
/// a = b = 0 (a slack tendon just reaching its length at 0 N); the chain rule keeps the
/// row of a slack tendon -e_j (its tension 0, whatever its effect on the tip) and that of
/// a taut one the gap's gradient.
fn jacobian(
    problem: &mut Problem,
    x: &DVector<f64>,
    smooth: &DVector<f64>,
    options: &Options,
    report: &mut SolveReport,
) -> Result<DMatrix<f64>> {
    report.evaluations.jacobian += 1;
    let n = x.len();
    let mut J = DMatrix::<f64>::zeros(n, n);
    let mut scratch = Vec::new();
    for j in 0..n {
        // Central differences; 1e-6 balances truncation (h^2) and integration noise (tol / h).
        // The shear and extension strains v of a slender rod change the base force by E A
        // per unit, so the residual is strongly nonlinear in them: with E A L^2 / E I of
        // 1e6 (the prototype), d f / d v_z changes by 12 % between h = 1e-9 and 1e-6,
        // enough to stall the Newton with tension unknowns; h = 1e-8 errs by 0.04 %.
        // Tension inputs alone keep 1e-6 (their Newton converges with it; 1e-8 would also
        // change which hard cases the cross-check reaches, tests/hard.rs).
        let h = if j < 3 && n > 6 { 1e-8 } else { 1e-6 };
        let mut xp = x.clone();
        xp[j] += h;
        let rp = problem.residual(&xp, options, &mut scratch, report)?;
        if j >= 6 && x[j] < h {
            // A tension within h of 0: the model drops a tendon at tau <= 0, so the
            // residual has a kink there and a central difference would halve the slope.
            // The one-sided second-order difference (-3 r(x) + 4 r(x + h) - r(x + 2h)) / 2h
            // stays at tau >= 0, where the residual is smooth.
            let mut xpp = x.clone();
            xpp[j] += 2.0 * h;
            let rpp = problem.residual(&xpp, options, &mut scratch, report)?;
            J.set_column(j, &((rp * 4.0 - rpp - smooth * 3.0) / (2.0 * h)));
        } else {
            let mut xm = x.clone();
            xm[j] -= h;
            let rm = problem.residual(&xm, options, &mut scratch, report)?;
            J.set_column(j, &((rp - rm) / (2.0 * h)));
        }
    }
    problem.set_tensions(x);
    for j in 6..n {
        let (_, da, db) = fischer_burmeister(x[j], smooth[j]);
        let mut row = J.row(j) * db;
        row[j] += da;
        J.set_row(j, &row);
    }
    Ok(J)
}

/// Integrates from the base with base strains `x` (scaled) and returns the scaled tip
/// residual and the path lengths of the tendons `paths` ((tendon index, end) each,
/// integrated over the segments up to its end); `traj` receives every accepted step.
fn shoot(
    model: &Model,
    scale: &Scale,
    x: &SVector<f64, 6>,
    paths: &[(usize, f64)],
    options: &Options,
    traj: &mut Vec<Point>,
    report: &mut SolveReport,
) -> Result<(SVector<f64, 6>, Vec<f64>)> {
    report.evaluations.residual += 1;
    traj.clear();
    let robot = model.robot;
    let length = robot.length();
    let (v, u) = scale.strains(x);
    let mut state = State {
        s: 0.0,
        p: robot.base_position,
        R: robot.base_rotation,
        v,
        u,
    };
    traj.push(state);
    let mut lengths = vec![0.0; paths.len()];
    let mut seg_start = 0.0;
    let breaks = robot.breakpoints();
    for seg_end in breaks.iter().copied().chain(std::iter::once(length)) {
        // The tendons whose paths run over this segment (terminations are breakpoints).
        let slots: Vec<usize> = (0..paths.len()).filter(|&j| seg_end <= paths[j].1).collect();
        state = integrate(
            model,
            seg_start,
            seg_end,
            state,
            options.integration_tolerance,
            Paths {
                paths,
                slots: &slots,
                lengths: &mut lengths,
            },
            traj,
            report,
        )?;
        if seg_end < length {
            let (v_b, u_b) = jump(model, seg_end, &state)?;
            state = State {
                s: seg_end,
                v: v_b,
                u: u_b,
                ..state
            };
            traj.push(state);
        }
        seg_start = seg_end;
    }
    let site = model.site(length);
    let State { s, R, v, u, .. } = state;
    let (f, m) = model.wrench_balance(s, (&site, &R, &v, &u), None)?;
    Ok((
        SVector::<f64, 6>::from_iterator(f.iter().copied().chain(m.iter().map(|x| x * length))),
        lengths,
    ))
}

/// Right-limit strains at breakpoint s from the jump conditions (Newton on 6 unknowns with
/// an exact dual-number Jacobian; p and R are continuous).
fn jump(model: &Model, s: f64, left: &Point) -> Result<(Vector3<f64>, Vector3<f64>)> {
    type D6 = DualSVec64<6>;
    let site = model.site(s);
    let State { R, v: va, u: ua, .. } = *left;
    let (mut v, mut u) = (va, ua);
    let lift3 = |x: &Vector3<f64>| x.map(D6::from);
    let (Rd, vad, uad) = (R.map(D6::from), lift3(&va), lift3(&ua));
    for _ in 0..30 {
        let mut vd = lift3(&v);
        let mut ud = lift3(&u);
        for i in 0..3 {
            vd[i] = D6::from(v[i]).derivative(i);
            ud[i] = D6::from(u[i]).derivative(i + 3);
        }
        let (fr, mr) = model.wrench_balance(s, (&site, &Rd, &vad, &uad), Some((&site, &Rd, &vd, &ud)))?;
        let r = SVector::<f64, 6>::from_iterator(fr.iter().chain(mr.iter()).map(|d| d.re));
        let mut J = SMatrix::<f64, 6, 6>::zeros();
        for (row, d) in fr.iter().chain(mr.iter()).enumerate() {
            if let Some(eps) = d.eps.0.as_ref() {
                J.set_row(row, &eps.transpose());
            }
        }
        let step = J.lu().solve(&(-r)).ok_or_else(|| Error::Breakdown {
            s,
            what: "the jump conditions are singular".into(),
        })?;
        v += step.fixed_rows::<3>(0);
        u += step.fixed_rows::<3>(3);
        // 1e-15 relative to the strains: converged to rounding
        if step.amax() <= 1e-15 * (1.0 + v.amax() + u.amax()) {
            break;
        }
    }
    Ok((v, u))
}

/// Scaled local state: p / L, theta, v, u L.
fn scaled(y: &Local, length: f64) -> Local {
    let mut z = *y;
    for i in 0..3 {
        z[i] /= length;
        z[9 + i] *= length;
    }
    z
}

/// d/ds of the local state (p, theta, v, u) of a step that started at rotation `R_n`.
fn local_rhs(model: &Model, site: &Site, seg_end: f64, R_n: &Matrix3<f64>, y: &Local) -> Result<Local> {
    let theta: Vector3<f64> = y.fixed_rows::<3>(3).into();
    let v: Vector3<f64> = y.fixed_rows::<3>(6).into();
    let u: Vector3<f64> = y.fixed_rows::<3>(9).into();
    let R = R_n * so3::exp(&theta);
    let (v_s, u_s) = model.strain_rates(site, seg_end, &R, &v, &u)?;
    let mut d = Local::zeros();
    d.fixed_rows_mut::<3>(0).copy_from(&(R * v));
    d.fixed_rows_mut::<3>(3)
        .copy_from(&(so3::right_jacobian_inv(&theta) * u));
    d.fixed_rows_mut::<3>(6).copy_from(&v_s);
    d.fixed_rows_mut::<3>(9).copy_from(&u_s);
    Ok(d)
}

// Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett & Wanner, table II.5.2).
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// 5th-order weights (the last row of A).
const B5: [f64; 7] = {
    // First same as last: the 5th-order weights are the last row of A, with 0 for stage 7.
    let last = A[6];
    [last[0], last[1], last[2], last[3], last[4], last[5], 0.0]
};
/// 4th-order embedded weights.
const B4: [f64; 7] = [
    5179.0 / 57600.0,
    0.0,
    7571.0 / 16695.0,
    393.0 / 640.0,
    -92097.0 / 339200.0,
    187.0 / 2100.0,
    1.0 / 40.0,
];

/// The tendon path lengths integrated along with the state over one segment.
struct Paths<'a> {
    /// (tendon index, end) of every tracked tendon.
    paths: &'a [(usize, f64)],
    /// The entries of `paths` whose tendons run over this segment.
    slots: &'a [usize],
    /// The path length so far of each entry of `paths` (m).
    lengths: &'a mut [f64],
}

/// Integrates one segment [s0, s1] with adaptive steps, pushing every accepted step; the
/// path lengths of `paths` grow by the integral of |v + u x r_j + r_j'| with the same
/// stages, their error (relative to L) in the step control.
#[allow(clippy::too_many_arguments)]
fn integrate(
    model: &Model,
    s0: f64,
    s1: f64,
    start: Point,
    tol: f64,
    paths: Paths,
    traj: &mut Vec<Point>,
    report: &mut SolveReport,
) -> Result<Point> {
    let length = model.robot.length();
    let State {
        mut p,
        mut R,
        mut v,
        mut u,
        ..
    } = start;
    let mut s = s0;
    // First step: a few percent of the segment; the controller adapts it at once.
    let mut h = (s1 - s0) * 0.02;
    let mut steps = 0usize;
    let mut speeds = Vec::with_capacity(7 * paths.slots.len());
    while s < s1 {
        steps += 1;
        // 1e6 steps means the tolerance cannot be met: report instead of looping
        if steps > 1_000_000 || !h.is_finite() {
            return Err(Error::Breakdown {
                s,
                what: "the integrator's step size collapsed".into(),
            });
        }
        let last = s + h >= s1 - 1e-14 * length;
        if last {
            h = s1 - s;
        }
        let mut y0 = Local::zeros();
        y0.fixed_rows_mut::<3>(0).copy_from(&p);
        y0.fixed_rows_mut::<3>(6).copy_from(&v);
        y0.fixed_rows_mut::<3>(9).copy_from(&u);
        let mut k = [Local::zeros(); 7];
        // Speeds |w_j| of the tracked tendon paths at each stage.
        speeds.clear();
        for i in 0..7 {
            let mut yi = y0;
            for (j, kj) in k.iter().enumerate().take(i) {
                yi += kj * (h * A[i][j]);
            }
            let si = s + C[i] * h;
            let site = model.site(si);
            k[i] = local_rhs(model, &site, s1, &R, &yi)?;
            report.evaluations.equations += 1;
            let (vi, ui): (Vector3<f64>, Vector3<f64>) = (yi.fixed_rows::<3>(6).into(), yi.fixed_rows::<3>(9).into());
            for &j in paths.slots {
                let rp = model.robot.tendons[paths.paths[j].0].routing.at(si, length);
                speeds.push(length::speed(&rp, &vi, &ui));
            }
        }
        let tracked = paths.slots.len();
        let step_lengths =
            |b: &[f64; 7], slot: usize| -> f64 { (0..7).map(|i| b[i] * speeds[i * tracked + slot]).sum::<f64>() * h };
        let mut y5 = y0;
        let mut y4 = y0;
        for i in 0..7 {
            y5 += k[i] * (h * B5[i]);
            y4 += k[i] * (h * B4[i]);
        }
        let (z0, z5, z4) = (scaled(&y0, length), scaled(&y5, length), scaled(&y4, length));
        let mut err: f64 = 0.0;
        for i in 0..12 {
            let sc = tol * (1.0 + z0[i].abs().max(z5[i].abs()));
            err = err.max(((z5[i] - z4[i]) / sc).abs());
        }
        for (slot, &j) in paths.slots.iter().enumerate() {
            let (l0, dl5) = (paths.lengths[j] / length, step_lengths(&B5, slot) / length);
            let sc = tol * (1.0 + l0.abs().max((l0 + dl5).abs()));
            err = err.max(((dl5 - step_lengths(&B4, slot) / length) / sc).abs());
        }
        if !err.is_finite() {
            h *= 0.25;
            continue;
        }
        if err <= 1.0 {
            s = if last { s1 } else { s + h };
            p = y5.fixed_rows::<3>(0).into();
            R *= so3::exp(&y5.fixed_rows::<3>(3).into());
            v = y5.fixed_rows::<3>(6).into();
            u = y5.fixed_rows::<3>(9).into();
            for (slot, &j) in paths.slots.iter().enumerate() {
                paths.lengths[j] += step_lengths(&B5, slot);
            }
            traj.push(State { s, p, R, v, u });
        }
        // Standard controller: safety 0.9, exponent 1/5, growth limited to [0.2, 5].
        h *= (0.9 * err.powf(-0.2)).clamp(0.2, 5.0);
    }
    Ok(State { s, p, R, v, u })
}
