//! The shooting problem: the unknowns (scaled base strains and the tensions of
//! displacement-controlled tendons), their length constraints in the Fischer-Burmeister form,
//! the residual by one integration and the Newton matrix by central differences.
#![allow(non_snake_case)]

use super::integrate::shoot;
use super::{Options, Point};
use crate::Robot;
use crate::error::Result;
use crate::model::equations::Model;
use crate::model::length;
use crate::model::tension_guess::starting_tensions;
use crate::report::SolveReport;
use nalgebra::{DMatrix, DVector, SVector, Vector3};

/// A displacement-controlled tendon's length constraint.
pub(super) struct Constraint {
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
pub(super) struct Problem {
    /// The robot, its displacement-controlled tendons at the current tensions.
    pub(super) robot: Robot,
    /// One per displacement-controlled tendon, in tendon order.
    pub(super) displaced: Vec<Constraint>,
    pub(super) scale: Scale,
}

impl Problem {
    pub(super) fn new(robot: &Robot) -> Self {
        let mut work = robot.clone();
        let length = robot.length();
        if robot.has_displacement_inputs() {
            starting_tensions(&mut work, None);
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
    pub(super) fn unknowns(&self, base: &SVector<f64, 6>) -> DVector<f64> {
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
    pub(super) fn project(&self, mut x: DVector<f64>) -> DVector<f64> {
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
    pub(super) fn bounded_step(&self, J: &DMatrix<f64>, x: &DVector<f64>, res: &DVector<f64>) -> Option<DVector<f64>> {
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
    pub(super) fn set_tensions(&mut self, x: &DVector<f64>) {
        for (j, (c, t)) in self.displaced.iter().zip(&self.scale.tension_scales).enumerate() {
            self.robot.tendons[c.tendon].hold_tension(x[6 + j] * t);
        }
    }

    /// After convergence at `x`, with `smooth` the residual there: a tendon on the slack
    /// side (b > a) gets exactly 0 N (its iterate is then within the tolerance of 0), a
    /// taut one at least 0. Whether a tension changed.
    pub(super) fn finish(&mut self, x: &DVector<f64>, smooth: &DVector<f64>) -> bool {
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
    pub(super) fn residual(
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
        let (tip, lengths) = shoot(&model, &self.scale, &base, &paths, options, traj, None, report)?;
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
    pub(super) fn complementarity(&self, x: &DVector<f64>, smooth: &DVector<f64>) -> DVector<f64> {
        let mut out = smooth.clone();
        for j in 0..self.displaced.len() {
            out[6 + j] = fischer_burmeister(x[6 + j], smooth[6 + j]).0;
        }
        out
    }
}

/// The unknowns: the base strains (v, u L) and tau_j / T_j of the
/// displacement-controlled tendons, T_j = E I / (L |r_j(0)|) the tension that bends the
/// rod through about a radian (E I / L^2 on the centreline). Central differences in these
/// units with step 1e-6 keep the Jacobian well above the integration noise for the
/// strains of ordinary rods; for rods extremely stiff in shear and extension (EA L^2 / EI
/// above about 1e6) the v columns become noise-limited, one reason shooting is only a
/// cross-check.
pub(super) struct Scale {
    /// L (m).
    pub(super) length: f64,
    /// T_j (N), one per displacement-controlled tendon.
    tension_scales: Vec<f64>,
}

impl Scale {
    pub(super) fn to_unknowns(&self, v: &Vector3<f64>, u: &Vector3<f64>) -> SVector<f64, 6> {
        SVector::<f64, 6>::from_iterator(v.iter().copied().chain(u.iter().map(|x| x * self.length)))
    }
    pub(super) fn strains(&self, x: &SVector<f64, 6>) -> (Vector3<f64>, Vector3<f64>) {
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
pub(super) fn jacobian(
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
