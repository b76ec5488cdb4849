//! What inverse statics adjusts, tensions or actuator pull-ins: the start, the unknowns, the
//! constraints of each step, the finish and where each input ended up.
//!
//! Both iterate on the free tendons' tensions tau, where the tip is a smooth function of the
//! unknowns (a slack tendon is one at tau = 0, the bound). For pull-ins the stroke becomes a
//! constraint on the tensions: the pull-in that holds tendon j just taut at tension tau_j,
//! q_j(tau) = l_ref_j - l_j(tau) + c_j tau_j (docs/actuation.md), must stay within
//! [q_min, q_max], linearized in each step by dq/dtau = C - dl/dtau from the same solves as
//! the tip's derivative. At the end each free tendon is given its pull-in q_j(tau) (for a
//! slack tendon, at tau_j = 0: the largest pull-in that leaves it slack, just taut) and the
//! robot is solved once more under displacement control.
#![allow(non_snake_case)]

use super::problem::Adjusted;
use super::qp::Constraints;
use super::result::Bound;
use crate::collocation::Solver;
use crate::collocation::sensitivity::TensionDirections;
use crate::error::{Result, invalid};
use crate::model::robot::Robot;
use crate::solution::Solution;
use nalgebra::{DMatrix, DVector};

/// How close to a bound (relative to the bounds' span) an input counts as at it, 1e-9: a
/// step that puts a pull-in on its stroke limit by the linearized constraint misses it by
/// the second-order change of q(tau) (2e-14 m measured on the prototype), and a 1e-9 share
/// of a 1 cm stroke moves the tip by about 3e-10 m, below the solve noise.
const BOUND_SNAP: f64 = 1e-9;

/// A tension at or below this share of the tendon's [`Robot::tension_scale`] counts as
/// slack, 1e-9: a displacement-controlled solve resolves tensions to about 1e-10 of their
/// scale (the round trips of tests/actuation.rs), so a tendon let out to just taut at 0 N
/// lands within that of 0 (1.7e-12 N of a 2.2 N scale measured).
const SLACK_TENSION: f64 = 1e-9;

/// Share of the geometric limit EI / r^2 that bounds the tensions of [`super::solve_displacements`],
/// 0.9: past the limit no equilibrium exists, and forward solves converge up to about 0.97
/// of it (tests/hard.rs), so every trial stays where they do.
pub const GEOMETRIC_SHARE: f64 = 0.9;

/// The adjusted inputs: which, within which bounds, of which tendons.
pub(super) struct Inputs {
    /// Tensions or pull-ins, with their bounds.
    pub(super) adjusted: Adjusted,
    /// The free tendons (0-based), the order of the unknowns.
    pub(super) free: Vec<usize>,
    /// Each free tendon's upper tension bound (N): `max_tension` for tensions; for pull-ins
    /// [`GEOMETRIC_SHARE`] of its geometric limit, or `max_tension` when set and lower.
    limits: Vec<f64>,
}

/// The linearization of one iterate: the tip's derivative and the step's constraints.
pub(super) struct Linearization {
    /// d(tip pose)/dtau (6 x free): tip position, then the world-frame rotation vector.
    pub(super) tip: DMatrix<f64>,
    /// The constraints of the step d in the tensions.
    pub(super) constraints: Constraints,
}

impl Inputs {
    /// The inputs `adjusted` of the tendons `free` of `robot`, with `max_tension` (N, 0 for
    /// none with pull-ins).
    pub(super) fn new(robot: &Robot, adjusted: Adjusted, free: Vec<usize>, max_tension: f64) -> Self {
        let limits = free
            .iter()
            .map(|&i| match adjusted {
                Adjusted::Tensions { max } => max,
                Adjusted::Displacements { .. } => {
                    let geometric = GEOMETRIC_SHARE * robot.geometric_limit(i);
                    if max_tension > 0.0 {
                        geometric.min(max_tension)
                    } else {
                        geometric
                    }
                }
            })
            .collect();
        Inputs { adjusted, free, limits }
    }

    /// The free tendons' tensions in `robot` (N).
    pub(super) fn tensions(&self, robot: &Robot) -> DVector<f64> {
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&i| robot.tendons[i].tension()))
    }

    /// Sets the free tendons' tensions in `robot` to `tau`, within [0, their limit] (a value
    /// within [`BOUND_SNAP`] of the limit on it).
    pub(super) fn set(&self, robot: &mut Robot, tau: &DVector<f64>) {
        for (k, &i) in self.free.iter().enumerate() {
            // A step the QP ends on a bound lands there to rounding (tau + (limit - tau));
            // within BOUND_SNAP of the limit it is the limit.
            let (limit, tension) = (self.limits[k], tau[k].clamp(0.0, self.limits[k]));
            let snapped = if tension >= limit - BOUND_SNAP * limit {
                limit
            } else {
                tension
            };
            robot.tendons[i].hold_tension(snapped);
        }
    }

    /// How close to a bound an input counts as at it: [`BOUND_SNAP`] of the bounds' span.
    fn snap(&self) -> f64 {
        let (lo, hi) = self.adjusted.range();
        BOUND_SNAP * (hi - lo)
    }

    /// The tension scale of the step test (N): the tension bound, or for pull-ins the
    /// largest of the free tendons' [`Robot::tension_scale`].
    pub(super) fn tension_scale(&self, robot: &Robot) -> f64 {
        match self.adjusted {
            Adjusted::Tensions { max } => max,
            Adjusted::Displacements { .. } => self.free.iter().map(|&i| robot.tension_scale(i)).fold(0.0, f64::max),
        }
    }

    /// The starting robot, with the free tendons tension-controlled, and its solution: the
    /// robot's tensions clamped into the bounds; for pull-ins, the robot solved with its
    /// free tendons' pull-ins (a tension-controlled tendon's is the one its tension holds)
    /// clamped into the stroke, then held at the tensions found (the same state). Returns
    /// the robot, its solution and the forward solves.
    pub(super) fn start(&self, robot: &Robot, solver: &mut Solver) -> Result<(Robot, Solution, usize)> {
        let mut current = robot.clone();
        let Adjusted::Displacements { min, max } = self.adjusted else {
            let start = self.tensions(&current);
            self.set(&mut current, &start);
            let solution = solver.solve(&current)?;
            return Ok((current, solution, 1));
        };
        let mut solution = solver.solve(&current)?;
        let mut solves = 1;
        // The tendons the stroke moved: (0-based index, pull-in before, after).
        let mut moved = Vec::new();
        for &i in &self.free {
            // The pull-in that holds the tendon's state: its input, or for a
            // tension-controlled tendon the one its tension holds.
            let q = solution.tendons[i].displacement;
            let clamped = q.clamp(min, max);
            if clamped != q {
                moved.push((i, q, clamped));
            }
            current.tendons[i].set_displacement(clamped);
        }
        if !moved.is_empty() {
            solution = solver.solve_from(&current, &solution)?;
            solves += 1;
            self.check_start(&solution, &moved)?;
        }
        for &i in &self.free {
            let t = &mut current.tendons[i];
            t.set_tension(solution.tendons[i].tension);
        }
        Ok((current, solution, solves))
    }

    /// Checks that the start the stroke imposed (`moved`: tendon, pull-in before and after
    /// clamping) stays within the tension limits: an actuator that cannot let out as far as
    /// the robot's state needs makes its tendon fight the others (the rod only compresses,
    /// at EA), and no iteration starts sensibly past the limits.
    fn check_start(&self, solution: &Solution, moved: &[(usize, f64, f64)]) -> Result<()> {
        let over: Vec<usize> = (0..self.free.len())
            .filter(|&k| solution.tendons[self.free[k]].tension > self.limits[k])
            .collect();
        let Some(&k) = over.first() else {
            return Ok(());
        };
        // The tendon the stroke moved farthest.
        let (i, before, after) = moved
            .iter()
            .copied()
            .max_by(|a, b| (a.1 - a.2).abs().total_cmp(&(b.1 - b.2).abs()))
            .unwrap_or(moved[0]);
        let (lo, _) = self.adjusted.range();
        let field = if after == lo {
            "options.min_displacement"
        } else {
            "options.max_displacement"
        };
        Err(invalid(
            field,
            format!(
                "puts tendon {} at {after} m where the robot's state needs {before:.6} m, and with that start tendon {} \
                 pulls {:.1} N, past its limit {:.1} N ({GEOMETRIC_SHARE} of its geometric limit EI/r^2)",
                i + 1,
                self.free[k] + 1,
                solution.tendons[self.free[k]].tension,
                self.limits[k],
            ),
            "widen the stroke so that the actuators can let the tendons out as far as the unactuated robot needs \
             (its own weight lengthens the paths on one side): for example min_displacement = -max_displacement",
        ))
    }

    /// The linearization at `solution`, the solution of `robot` (free tendons
    /// tension-controlled at `tau`).
    pub(super) fn linearize(&self, robot: &Robot, solution: &Solution, tau: &DVector<f64>) -> Result<Linearization> {
        let directions = TensionDirections::new(robot, solution, self.free.clone())?;
        let lower = -tau;
        let upper = DVector::from_fn(tau.len(), |k, _| self.limits[k] - tau[k]);
        let mut constraints = Constraints::bounds(&lower, &upper);
        if let Adjusted::Displacements { min, max } = self.adjusted {
            let Q = directions.displacement_by_tension();
            for (k, &i) in self.free.iter().enumerate() {
                let q = solution.tendons[i].displacement;
                let snap = |margin: f64| if margin.abs() <= self.snap() { 0.0 } else { margin };
                constraints.between(&Q.row(k).transpose(), snap(min - q), snap(max - q));
            }
        }
        Ok(Linearization {
            tip: directions.tip,
            constraints,
        })
    }

    /// The robot and solution to report: for tensions the last iterate; for pull-ins the
    /// free tendons displacement-controlled at the pull-ins that hold the iterate's
    /// tensions, clamped into the stroke, solved warm from the iterate. Returns them and the
    /// forward solves it took.
    pub(super) fn finish(
        &self,
        robot: Robot,
        solution: Solution,
        solver: &mut Solver,
    ) -> Result<(Robot, Solution, usize)> {
        let Adjusted::Displacements { min, max } = self.adjusted else {
            return Ok((robot, solution, 0));
        };
        let mut displaced = robot;
        for &i in &self.free {
            let q = solution.tendons[i].displacement;
            let q = if q >= max - self.snap() {
                max
            } else if q <= min + self.snap() {
                min
            } else {
                q
            };
            displaced.tendons[i].set_displacement(q);
        }
        let solved = solver.solve_from(&displaced, &solution)?;
        Ok((displaced, solved, 1))
    }

    /// Where tendon `i`'s input ended up in `robot`, solved as `solution`.
    pub(super) fn bound(&self, i: usize, robot: &Robot, solution: &Solution) -> Bound {
        if !self.free.contains(&i) {
            return Bound::Held;
        }
        let (lo, hi) = self.adjusted.range();
        let tension = solution.tendons[i].tension;
        let value = match self.adjusted {
            Adjusted::Tensions { .. } => tension,
            Adjusted::Displacements { .. } => robot.tendons[i].displacement().unwrap_or(0.0),
        };
        let k = self.free.iter().position(|&j| j == i).unwrap_or(0);
        if tension <= SLACK_TENSION * robot.tension_scale(i) {
            Bound::Slack
        } else if matches!(self.adjusted, Adjusted::Displacements { .. }) && tension >= self.limits[k] {
            Bound::TensionLimit
        } else if value >= hi - self.snap() {
            Bound::Saturated
        } else if value <= lo + self.snap() {
            Bound::Released
        } else {
            Bound::Inside
        }
    }
}
