//! [`Solver`]: a collocation solver that keeps its Newton workspace, the mesh it was built
//! for and the factors of its last Newton matrix between solves.

use super::linear::LinearSolver;
use super::newton::Workspace;
use super::options::Options;
use super::pipeline::solve_impl;
use super::sensitivity::{
    Sensitivity, TipSensitivities, backbone_columns, tension_tips, tip_columns, tip_sensitivities_from,
};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::solution::{Solution, State};
use crate::{Parameter, Robot};
use nalgebra::DMatrix;

/// The Newton workspace of the last solve, the mesh and linear solver it was built for,
/// and the states that solve ended at (its factors belong to a Jacobian near them).
pub(crate) struct Cached {
    pub(crate) mesh: Mesh,
    pub(crate) solver: LinearSolver,
    pub(crate) workspace: Workspace,
    pub(crate) last: Option<Vec<State>>,
}

/// What a solve may reuse from the one before it: nothing, or its [`Cached`] workspace.
pub(crate) type Cache = Option<Cached>;

/// A collocation solver that keeps its Newton workspace (buffers and, on the sparse path,
/// the pattern and symbolic LU) between solves, so that repeated solves on the same mesh
/// (sweeps, control loops, calibration) skip the setup.
///
/// It also keeps the factors of the last Newton matrix: [`Solver::solve_from`] given the
/// solution this solver just returned (the usual step of a control loop) starts with chord
/// steps on those factors, which for a small change of tensions or loads converge without
/// evaluating a new Jacobian for the iteration; the stability verdict then evaluates one at
/// the solution, since the factors belong to the previous state (docs/stability.md, "Which
/// Jacobian").
///
/// [`Solver::tip_jacobian`] and [`Solver::backbone_jacobian`] give the columns a controller
/// asks for of the derivatives at a solution, factoring the Jacobian at the solution in the
/// same workspace (no new buffers or pattern); the next warm solve then starts its chord
/// steps on those factors, the Jacobian at the previous solution.
pub struct Solver {
    /// The options of every solve.
    pub options: Options,
    cache: Cache,
    /// Whether the stability verdict forms the tension columns' right-hand sides
    /// ([`Solver::keep_tension_columns`]).
    tension_columns: bool,
}

impl Solver {
    /// A solver with these options and an empty cache.
    pub fn new(options: Options) -> Self {
        Solver {
            options,
            cache: None,
            tension_columns: false,
        }
    }

    /// As [`super::solve`], reusing the workspace of the previous solve when the mesh is
    /// the same.
    ///
    /// # Errors
    /// As [`super::solve`].
    pub fn solve(&mut self, robot: &Robot) -> Result<Solution> {
        self.solved(robot, None)
    }

    /// As [`super::solve_from`], reusing the workspace of the previous solve when the mesh
    /// is the same, and its factors when `guess` is the solution it returned.
    ///
    /// # Errors
    /// As [`super::solve`].
    pub fn solve_from(&mut self, robot: &Robot, guess: &Solution) -> Result<Solution> {
        self.solved(robot, Some(guess))
    }

    /// For a control loop that asks for the tension columns after every solve (`on`): a
    /// solve whose stability verdict evaluates the Jacobian at its answer (a warm solve
    /// that converged by chord steps) then also forms the tension columns' right-hand sides
    /// -dF/dtau_i from the same evaluation of eq. 13 at every node and midpoint, and
    /// [`Solver::tip_jacobian`] in the tensions takes them instead of a pass over the mesh
    /// of its own (docs/sensitivity.md, "Tension columns formed with the verdict's
    /// Jacobian"). Such a solve costs a few per cent more; the answers are the same bits.
    /// Off by default. It applies from the next solve on, on every mesh it runs on.
    pub fn keep_tension_columns(&mut self, on: bool) {
        self.tension_columns = on;
        if let Some(c) = self.cache.as_mut() {
            c.workspace.keep_tension_columns(on);
        }
    }

    /// Solves `robot` from `guess` (or cold) with the cache, whose workspace keeps this
    /// solver's [`Solver::keep_tension_columns`] before and after.
    fn solved(&mut self, robot: &Robot, guess: Option<&Solution>) -> Result<Solution> {
        self.keep_tension_columns(self.tension_columns);
        let out = solve_impl(robot, &self.options, guess, &mut self.cache);
        self.keep_tension_columns(self.tension_columns);
        out
    }

    /// The columns `wrt` of d(tip pose)/dq at `solution`, a solution of `robot` (6 x
    /// `wrt.len()`, the layout of [`crate::TipSensitivities`]): as
    /// [`crate::collocation::sensitivity::tip_jacobian`], to rounding, factoring the
    /// Jacobian at the solution in this solver's workspace when the solution is on the mesh
    /// of its last solve.
    ///
    /// # Errors
    /// As [`crate::collocation::sensitivity::tip_jacobian`].
    ///
    /// # Examples
    /// ```
    /// use tdcr::{Parameter, Solver};
    /// let mut robot = tdcr::cases::case_s();
    /// let mut solver = Solver::new(Default::default());
    /// let first = solver.solve(&robot).unwrap();
    /// robot.tendons[0].set_tension(3.0);
    /// let next = solver.solve_from(&robot, &first).unwrap();
    /// let j = solver.tip_jacobian(&robot, &next, &[Parameter::Tension(0)]).unwrap();
    /// assert!(j[(0, 0)].abs() > 0.0);
    /// ```
    pub fn tip_jacobian(&mut self, robot: &Robot, solution: &Solution, wrt: &[Parameter]) -> Result<DMatrix<f64>> {
        let tips = tension_tips(robot, wrt);
        self.linearized(robot, solution, tips, |sens| tip_columns(sens, robot, solution, wrt))
    }

    /// Every tip sensitivity at `solution`, a solution of `robot`: as
    /// [`crate::tip_sensitivities`] (the same [`TipSensitivities`], to rounding), with this
    /// solver's workspace as in [`Solver::tip_jacobian`]: after a warm solve that converged
    /// by chord steps, the Jacobian its stability verdict evaluated at the solution is
    /// factored instead of assembled again; for a solution on another mesh the Jacobian is
    /// assembled in a new workspace and the cached one is kept.
    ///
    /// # Errors
    /// As [`crate::tip_sensitivities`].
    ///
    /// # Examples
    /// ```
    /// use tdcr::Solver;
    /// let mut robot = tdcr::cases::case_s();
    /// let mut solver = Solver::new(Default::default());
    /// let first = solver.solve(&robot).unwrap();
    /// robot.tendons[0].set_tension(3.0);
    /// let next = solver.solve_from(&robot, &first).unwrap();
    /// let sens = solver.tip_sensitivities(&robot, &next).unwrap();
    /// assert_eq!(sens.tension.shape(), (6, robot.tendons.len()));
    /// ```
    pub fn tip_sensitivities(&mut self, robot: &Robot, solution: &Solution) -> Result<TipSensitivities> {
        // Without pull-ins to hold, the tension columns' tips come out of the factoring.
        let tips = !robot.has_displacement_inputs();
        self.linearized(robot, solution, tips, |sens| {
            tip_sensitivities_from(sens, robot, solution)
        })
    }

    /// The columns `wrt` of d p(s_j)/dq at the arc lengths `s` (3 `s.len()` x `wrt.len()`):
    /// as [`crate::collocation::sensitivity::backbone_jacobian`], with this solver's
    /// workspace as in [`Solver::tip_jacobian`].
    ///
    /// # Errors
    /// As [`crate::collocation::sensitivity::backbone_jacobian`].
    pub fn backbone_jacobian(
        &mut self,
        robot: &Robot,
        solution: &Solution,
        wrt: &[Parameter],
        s: &[f64],
    ) -> Result<DMatrix<f64>> {
        self.linearized(robot, solution, false, |sens| {
            backbone_columns(sens, robot, solution, wrt, s)
        })
    }

    /// Forgets the cached workspace and factors: the next solve starts as a new solver's.
    pub fn reset(&mut self) {
        self.cache = None;
    }

    /// Runs `f` on the sensitivity of `robot` linearized at `solution`, factored in the
    /// cached workspace when that was built for the solution's mesh (and put back after);
    /// `tips` as [`Sensitivity::with_workspace`] takes it.
    fn linearized<T>(
        &mut self,
        robot: &Robot,
        solution: &Solution,
        tips: bool,
        f: impl FnOnce(&mut Sensitivity) -> Result<T>,
    ) -> Result<T> {
        // A displacement-controlled tendon's tension is the solved one.
        let solved = robot.with_tensions(&solution.tensions());
        let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
        let mesh = Mesh::from_points(&solved, &s)?;
        // The last solve's stability verdict may have left the Jacobian at this very
        // solution in the workspace (a warm solve that converged by chord steps): then it is
        // factored as it is. Only for tension inputs without friction, whose system is the
        // plain one the verdict evaluated.
        let plain = !robot.has_displacement_inputs() && !crate::model::friction::any(robot);
        let (workspace, kept, evaluated) = match self.cache.take() {
            Some(c) if c.mesh == mesh => {
                let at = c.last.as_ref().is_some_and(|x| {
                    x.len() == solution.nodes.len() && x.iter().zip(&solution.nodes).all(|(x, n)| *x == n.state())
                });
                (Some(c.workspace), Some((c.mesh, c.solver, c.last)), plain && at)
            }
            other => {
                self.cache = other;
                (None, None, false)
            }
        };
        let mut sens = Sensitivity::with_workspace(&solved, solution, workspace, Some(mesh), evaluated, tips)?;
        let out = f(&mut sens);
        if let Some((mesh, solver, last)) = kept {
            self.cache = Some(Cached {
                mesh,
                solver,
                workspace: sens.into_workspace(),
                last,
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;

    /// A `Solver` can be shared across threads (the Python package's solver object needs it,
    /// and batches share robots): a cache inside it that is not `Sync` fails to compile here
    /// rather than in the Python build.
    #[test]
    fn a_solver_is_send_and_sync() {
        fn shared<T: Send + Sync>() {}
        shared::<Solver>();
    }

    /// With [`Solver::keep_tension_columns`], a warm solve that ends on chord steps leaves the
    /// tension columns its verdict formed with the Jacobian at the answer, for
    /// [`Solver::tip_jacobian`] to take; without the flag it leaves none. (The pass over the
    /// mesh gives the same columns to 1e-12, so the answers alone cannot tell which path ran.)
    #[test]
    fn a_warm_solve_leaves_the_tension_columns_its_verdict_formed_only_when_asked() {
        for keep in [true, false] {
            let mut solver = Solver::new(Default::default());
            solver.keep_tension_columns(keep);
            let mut robot = cases::case_s();
            let first = solver.solve(&robot).unwrap();
            let tension = robot.tendons[0].tension();
            robot.tendons[0].set_tension(tension + 0.01);
            let second = solver.solve_from(&robot, &first).unwrap();
            let len = second.report.unknowns * robot.tendons.len();
            let cached = solver.cache.as_mut().unwrap();
            assert_eq!(cached.workspace.take_tension_rhs(len).is_some(), keep, "keep {keep}");
        }
    }
}
