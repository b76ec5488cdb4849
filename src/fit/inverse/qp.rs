//! The quadratic program of each inverse-statics step, solved exactly by a primal active-set
//! method: a strictly convex quadratic over a few unknowns under linear inequalities (the
//! tension bounds, and for pull-ins their linearized stroke limits).
#![allow(non_snake_case)]

use nalgebra::{DMatrix, DVector};

/// The linear constraints of a step d: rows a_i^T d <= b_i with b_i >= 0, so that d = 0 is
/// feasible.
pub(super) struct Constraints {
    /// The rows a_i^T, one per constraint.
    rows: Vec<DVector<f64>>,
    /// The right-hand sides b_i.
    bounds: Vec<f64>,
}

impl Constraints {
    /// Box constraints lower <= d <= upper (lower <= 0 <= upper; infinite sides are left out).
    pub(super) fn bounds(lower: &DVector<f64>, upper: &DVector<f64>) -> Self {
        let n = lower.len();
        let mut c = Constraints {
            rows: Vec::new(),
            bounds: Vec::new(),
        };
        for i in 0..n {
            let unit = DVector::from_fn(n, |j, _| if i == j { 1.0 } else { 0.0 });
            c.between(&unit, lower[i], upper[i]);
        }
        c
    }

    /// The constraints active at d = 0 (b_i = 0), those that bound the first-order moves.
    pub(super) fn active(&self) -> Self {
        let keep: Vec<usize> = (0..self.rows.len()).filter(|&i| self.bounds[i] <= 0.0).collect();
        Constraints {
            rows: keep.iter().map(|&i| self.rows[i].clone()).collect(),
            bounds: vec![0.0; keep.len()],
        }
    }

    /// Adds lower <= a^T d <= upper; a side that d = 0 violates (the iterate is already past
    /// it) becomes a^T d <= 0 or >= 0: the step may not make it worse.
    pub(super) fn between(&mut self, a: &DVector<f64>, lower: f64, upper: f64) {
        if upper.is_finite() {
            self.rows.push(a.clone());
            self.bounds.push(upper.max(0.0));
        }
        if lower.is_finite() {
            self.rows.push(-a);
            self.bounds.push((-lower).max(0.0));
        }
    }
}

/// Minimizer of d^T H d / 2 + g^T d under `constraints`, for symmetric positive definite H,
/// by the primal active-set method (Nocedal & Wright, "Numerical Optimization",
/// algorithm 16.3): from the feasible d = 0, minimize over the working set's equalities
/// (a KKT system of at most n + m unknowns); if the step leaves the feasible set, go to the
/// first constraint it meets and add it; otherwise drop the working constraint with the most
/// negative multiplier, or stop when none is negative. The objective never increases and
/// every iterate is feasible, so the guard on the passes (and a singular KKT system, from
/// degenerate constraints) returns a feasible, improved d.
pub(super) fn solve_qp(H: &DMatrix<f64>, g: &DVector<f64>, constraints: &Constraints) -> DVector<f64> {
    let n = g.len();
    let (rows, bounds) = (&constraints.rows, &constraints.bounds);
    let mut d = DVector::zeros(n);
    let mut working: Vec<usize> = Vec::new();
    // Scale of the steps: the unconstrained minimizer's size; a step below 1e-12 of it (or
    // of d) is zero to rounding.
    let scale = H
        .clone()
        .cholesky()
        .map_or(1.0, |c| c.solve(g).amax())
        .max(f64::MIN_POSITIVE);
    // Each pass adds or drops one constraint; 10 (n + m + 1) passes are far beyond what a
    // handful of tendons needs (a guard against cycling at degenerate vertices).
    for _ in 0..10 * (n + rows.len() + 1) {
        let m = working.len();
        let mut K = DMatrix::zeros(n + m, n + m);
        K.view_mut((0, 0), (n, n)).copy_from(H);
        let mut rhs = DVector::zeros(n + m);
        rhs.rows_mut(0, n).copy_from(&(-(H * &d + g)));
        for (w, &i) in working.iter().enumerate() {
            for j in 0..n {
                K[(n + w, j)] = rows[i][j];
                K[(j, n + w)] = rows[i][j];
            }
        }
        let Some(solution) = K.lu().solve(&rhs) else {
            return d;
        };
        let p = solution.rows(0, n).into_owned();
        if p.amax() <= 1e-12 * scale.max(d.amax()) {
            // At the minimizer over the working set: drop a constraint whose multiplier says
            // the objective decreases by leaving it, or stop.
            let worst = (0..m)
                .filter(|&w| solution[n + w] < 0.0)
                .min_by(|&a, &b| solution[n + a].total_cmp(&solution[n + b]));
            match worst {
                Some(w) => {
                    working.remove(w);
                    continue;
                }
                None => return d,
            }
        }
        // The longest fraction of p that stays feasible, and the constraint that stops it.
        let mut alpha = 1.0;
        let mut blocking = None;
        for i in (0..rows.len()).filter(|i| !working.contains(i)) {
            let rate = rows[i].dot(&p);
            // A constraint p runs parallel to (rounding: 1e-14 of |a| |p|) does not block.
            if rate > 1e-14 * rows[i].norm() * p.norm() {
                let t = ((bounds[i] - rows[i].dot(&d)) / rate).max(0.0);
                if t < alpha {
                    alpha = t;
                    blocking = Some(i);
                }
            }
        }
        d += alpha * &p;
        if let Some(i) = blocking {
            working.push(i);
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over a fine grid of a 2-D box, with and without a tilted constraint: the
    /// active-set minimizer is feasible and no worse, and satisfies the KKT conditions.
    #[test]
    fn qp_matches_grid_search() {
        let H = DMatrix::from_row_slice(2, 2, &[2.0, 0.9, 0.9, 1.0]);
        let q = |d: &DVector<f64>, g: &DVector<f64>| 0.5 * d.dot(&(&H * d)) + g.dot(d);
        let (lo, hi) = (
            DVector::from_row_slice(&[-1.0, 0.0]),
            DVector::from_row_slice(&[0.5, 1.5]),
        );
        // -0.3 <= d0 + d1 <= 0.8, on top of the box.
        let tilt = DVector::from_row_slice(&[1.0, 1.0]);
        for tilted in [false, true] {
            let mut constraints = Constraints::bounds(&lo, &hi);
            if tilted {
                constraints.between(&tilt, -0.3, 0.8);
            }
            let feasible = |d: &DVector<f64>| {
                // 1e-12: rounding of the steps onto a constraint
                (0..2).all(|i| d[i] >= lo[i] - 1e-12 && d[i] <= hi[i] + 1e-12)
                    && (!tilted || (tilt.dot(d) >= -0.3 - 1e-12 && tilt.dot(d) <= 0.8 + 1e-12))
            };
            for g in [
                [3.0, -1.0],
                [-4.0, -4.0],
                [0.1, 0.2],
                [-0.5, 2.0],
                [5.0, 5.0],
                [-2.0, 1.0],
            ] {
                let g = DVector::from_row_slice(&g);
                let d = solve_qp(&H, &g, &constraints);
                assert!(feasible(&d), "g = {g:?}: d = {d:?} infeasible");
                let mut best = f64::INFINITY;
                for a in 0..=300 {
                    for b in 0..=300 {
                        let x = DVector::from_row_slice(&[-1.0 + 1.5 * a as f64 / 300.0, 1.5 * b as f64 / 300.0]);
                        if feasible(&x) {
                            best = best.min(q(&x, &g));
                        }
                    }
                }
                // The grid minimum is above the true one (by up to about 1e-4 at this
                // spacing), never below: 1e-12 is rounding.
                assert!(q(&d, &g) <= best + 1e-12, "g = {g:?}: {} vs grid {best}", q(&d, &g));
            }
        }
    }

    /// A start past a constraint (b < 0) keeps d = 0 feasible: the step may not make it worse.
    #[test]
    fn a_violated_side_only_stops_it_getting_worse() {
        let H = DMatrix::identity(1, 1);
        let mut constraints = Constraints::bounds(&DVector::from_element(1, -1.0), &DVector::from_element(1, 1.0));
        // d >= 0.5 cannot hold at d = 0; it becomes d >= 0.
        constraints.between(&DVector::from_element(1, 1.0), 0.5, f64::INFINITY);
        let d = solve_qp(&H, &DVector::from_element(1, 2.0), &constraints);
        assert_eq!(d[0], 0.0);
        let d = solve_qp(&H, &DVector::from_element(1, -2.0), &constraints);
        // 1e-12: rounding of the step onto the bound 1.
        assert!((d[0] - 1.0).abs() <= 1e-12, "{d:?}");
    }
}
