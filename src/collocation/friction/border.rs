//! The border rows of tendons with friction in Newton's loop ([`Border`] for [`Capstan`]):
//! the capstan rows and their linearization at the current and trial points, and the
//! bordered step through the Schur complement (module docs of [`super`]).

use super::*;

impl Capstan<'_> {
    /// Reads psi_x, psi_z and F_z from the links' evaluations by the system's Jacobian at
    /// `x` (its last evaluation), and the termination rows' columns.
    pub(super) fn read_border(&mut self, x: &[State]) -> Result<(), Termination> {
        self.load(Point::Current);
        let m = self.z.len();
        let count = self.offsets.len();
        self.psi_z.fill(0.0);
        self.columns_ready = false;
        let Some(profile) = self.system.friction.as_ref() else {
            return Ok(());
        };
        let last = profile.spans.iter().copied().max().unwrap_or(0);
        for k in 0..last {
            let done = profile.cached(k, |lin| {
                let Some(lin) = lin.filter(|l| l.derivatives) else {
                    return self.system.interval_sites(k).is_none();
                };
                for j in (0..count).filter(|&j| profile.on_link(j, k)) {
                    let row = self.offsets[j] + k;
                    for c in 0..2 * NODE {
                        self.psi_x[row][c] = lin.psi_x[(j, c)];
                    }
                    for l in 0..count {
                        for (side, node) in [(0, k), (1, k + 1)] {
                            if let Some(u) = unknown(&self.offsets, &profile.spans, l, node) {
                                self.psi_z[row * m + u] += lin.psi_z[(j, side * count + l)];
                            }
                        }
                    }
                }
                self.link_z[k] = Some(lin.rows_z.clone());
                true
            });
            if !done {
                return Err(Termination::NonFinite);
            }
        }
        for j in 0..count {
            self.terminations[j] = self.termination_column(j, x).map_err(|_| Termination::NonFinite)?;
        }
        Ok(())
    }
}

impl Border for Capstan<'_> {
    fn on<R>(&mut self, point: Point, f: impl FnOnce(&System) -> R) -> R {
        self.load(point);
        f(&self.system)
    }

    fn rows(&mut self, point: Point, x: &[State]) {
        self.load(point);
        let psi = match point {
            Point::Current => &mut self.psi,
            Point::Trial => &mut self.trial_psi,
        };
        // The system's residual at this point and x has just evaluated every link.
        let _ = x;
        if let Some(profile) = self.system.friction.as_ref() {
            capstan_rows(profile, &self.offsets, psi);
        }
    }

    fn residual(&self, point: Point) -> &[f64] {
        match point {
            Point::Current => &self.psi,
            Point::Trial => &self.trial_psi,
        }
    }

    /// Reads the border's blocks ([`Capstan::read_border`]) at `x`, which Newton has just
    /// factored.
    fn factored(&mut self, x: &[State], _: &mut Linearization, _: &mut SolveReport) -> Result<(), Termination> {
        self.read_border(x)
    }

    fn step(
        &mut self,
        point: Point,
        _x: &[State],
        a: &mut [f64],
        at: &mut Linearization,
        report: &mut SolveReport,
    ) -> Option<f64> {
        let psi = match point {
            Point::Current => &self.psi,
            Point::Trial => &self.trial_psi,
        };
        self.rows_in.copy_from_slice(psi);
        let norm = self.bordered(a, &mut |rhs, out| at.solve(rhs, out, report))?;
        match point {
            Point::Current => self.dz.copy_from_slice(&self.border_step),
            Point::Trial => self.simplified.copy_from_slice(&self.border_step),
        }
        Some(norm)
    }

    fn trial(&mut self, alpha: f64) {
        for ((t, &z), &d) in self.trial_z.iter_mut().zip(&self.z).zip(&self.dz) {
            *t = z + alpha * d;
        }
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.psi, &mut self.trial_psi);
        self.z.copy_from_slice(&self.trial_z);
    }
}
