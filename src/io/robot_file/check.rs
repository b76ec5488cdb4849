//! The field-by-field rules of a robot file: every value checked against its rule (finite,
//! positive, on the rod, a rotation, the solver library's own option rules), each broken
//! rule one problem at its field path.

use super::build::rotation_from_rows;
use super::tables::{BaseTable, DisksTable, LoadsTable, RodTable, RoutingTable, SolverTable, TendonTable, Vec3};
use crate::io::Problem;
use crate::io::locate::LazyLocator;
use crate::{Error, Readable, collocation, shooting, so3};

/// Largest |R^T R - I|, |det R - 1| accepted for a base rotation (the 1e-6: loose
/// enough for matrices typed with 7 digits).
const ROTATION_TOLERANCE: f64 = 1e-6;

/// The most spacer disks a `[disks]` table may give: each is a point load and a breakpoint
/// of the mesh, and a robot with more is better modelled by a distributed weight.
pub(super) const MAX_DISKS: usize = 10_000;

/// A number as TOML spells it (`nan`, `inf`, `-inf` for the non-finite ones).
fn toml_number(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf".into() } else { "-inf".into() }
    } else {
        Readable(x).to_string()
    }
}

/// Field-by-field rules; every broken rule is one problem.
pub(super) struct Checker<'a> {
    /// Where each field is in the file.
    pub(super) locator: &'a LazyLocator<'a>,
    /// The broken rules found so far, in the order checked.
    pub(super) problems: Vec<Problem>,
}

impl Checker<'_> {
    /// One problem at `field`, placed where the file has it.
    pub(super) fn report(&mut self, field: &str, message: String) {
        self.problems.push(Problem {
            position: self.locator.get().find(field),
            field: field.to_string(),
            message,
        });
    }

    /// Whether `x` is finite; if not, reports it (`unit` follows the value in the message).
    pub(super) fn finite(&mut self, field: &str, x: f64, unit: &str) -> bool {
        if x.is_finite() {
            return true;
        }
        self.report(
            field,
            format!("is {}{unit}, but every number must be finite", toml_number(x)),
        );
        false
    }

    /// Reports `x` unless it is finite and above 0.
    pub(super) fn positive(&mut self, field: &str, x: f64, unit: &str) {
        if self.finite(field, x, unit) && x <= 0.0 {
            self.report(field, format!("is {}{unit}, but must be positive", Readable(x)));
        }
    }

    /// Reports each non-finite component of `v`, if given.
    pub(super) fn vector(&mut self, field: &str, v: &Option<Vec3>, unit: &str) {
        if let Some(v) = v {
            for (k, x) in v.iter().enumerate() {
                if !x.is_finite() {
                    let axis = ["x", "y", "z"][k];
                    self.report(
                        field,
                        format!(
                            "has {axis} = {}{unit}, but every number must be finite",
                            toml_number(*x)
                        ),
                    );
                }
            }
        }
    }

    /// The `[rod]` rules.
    pub(super) fn rod(&mut self, rod: &RodTable) {
        self.positive("rod.length", rod.length, " m");
        self.tube(
            "rod",
            rod.outer_radius,
            rod.inner_radius,
            rod.youngs_modulus,
            (rod.poisson_ratio, rod.shear_modulus),
        );
        self.vector("rod.precurvature", &rod.precurvature, " rad/m");
    }

    /// The rules of a tube's section in table `path` (`rod`, `segment[2]`): positive outer
    /// radius and Young's modulus, an inner radius in [0, outer), and one of Poisson's ratio
    /// (in (-1, 0.5]) and the shear modulus (positive), given as `torsion`.
    pub(super) fn tube(&mut self, path: &str, outer: f64, inner: f64, e: f64, torsion: (Option<f64>, Option<f64>)) {
        let field = |key: &str| format!("{path}.{key}");
        self.positive(&field("outer_radius"), outer, " m");
        if self.finite(&field("inner_radius"), inner, " m") {
            if inner < 0.0 {
                self.report(
                    &field("inner_radius"),
                    format!("is {} m, but must be >= 0 (0 for a solid rod)", Readable(inner)),
                );
            } else if outer.is_finite() && inner >= outer {
                self.report(
                    &field("inner_radius"),
                    format!(
                        "is {} m, but must be below the outer radius {} m",
                        Readable(inner),
                        Readable(outer)
                    ),
                );
            }
        }
        self.positive(&field("youngs_modulus"), e, " Pa");
        match torsion {
            (Some(_), Some(_)) => self.report(
                &field("shear_modulus"),
                "is given together with `poisson_ratio`: give one of them".into(),
            ),
            (None, None) => self.report(
                path,
                "needs `poisson_ratio` or `shear_modulus` (Pa) for the torsion stiffness G J".into(),
            ),
            (Some(nu), None) => {
                if self.finite(&field("poisson_ratio"), nu, "") && !(nu > -1.0 && nu <= 0.5) {
                    self.report(
                        &field("poisson_ratio"),
                        format!("is {}, but must lie in (-1, 0.5]", Readable(nu)),
                    );
                }
            }
            (None, Some(g)) => self.positive(&field("shear_modulus"), g, " Pa"),
        }
    }

    /// The `[base]` rules: a finite position, one rotation that is a rotation.
    pub(super) fn base(&mut self, base: &BaseTable) {
        self.vector("base.position", &base.position, " m");
        if base.rotation.is_some() && base.euler_xyz_deg.is_some() {
            self.report(
                "base.euler_xyz_deg",
                "is given together with `rotation`: give one of them".into(),
            );
            return;
        }
        self.vector("base.euler_xyz_deg", &base.euler_xyz_deg, " deg");
        if let Some(rows) = &base.rotation {
            if rows.iter().flatten().any(|x| !x.is_finite()) {
                self.report(
                    "base.rotation",
                    "has a non-finite entry, but every number must be finite".into(),
                );
                return;
            }
            let error = so3::orthonormality_error(&rotation_from_rows(rows));
            if error > ROTATION_TOLERANCE {
                self.report(
                    "base.rotation",
                    format!(
                        "is not a rotation: |R^T R - I|, |det R - 1| = {error:.2e} > {ROTATION_TOLERANCE:.0e}; \
                         its rows must be orthonormal with determinant +1"
                    ),
                );
            }
        }
    }

    /// The `[loads]` rules: finite loads, point loads on the rod of `length` (NaN if unknown).
    pub(super) fn loads(&mut self, loads: &LoadsTable, length: f64) {
        self.vector("loads.distributed_force", &loads.distributed_force, " N/m");
        self.vector("loads.distributed_moment", &loads.distributed_moment, " N m/m");
        self.vector("loads.tip_force", &loads.tip_force, " N");
        self.vector("loads.tip_moment", &loads.tip_moment, " N m");
        self.vector("loads.follower_tip_force", &loads.follower_tip_force, " N");
        self.vector("loads.follower_tip_moment", &loads.follower_tip_moment, " N m");
        self.vector(
            "loads.follower_distributed_force",
            &loads.follower_distributed_force,
            " N/m",
        );
        for (i, p) in loads.point.iter().enumerate() {
            let path = format!("loads.point[{}]", i + 1);
            let s = format!("{path}.s");
            if self.finite(&s, p.s, " m") && length.is_finite() && !(p.s > 0.0 && p.s <= length) {
                self.report(
                    &s,
                    format!(
                        "is {} m, but must lie on the rod, in (0, {}] m",
                        Readable(p.s),
                        Readable(length)
                    ),
                );
            }
            self.vector(&format!("{path}.force"), &p.force, " N");
            self.vector(&format!("{path}.moment"), &p.moment, " N m");
        }
    }

    /// The rules of `[[tendon]]` number `i` (from 0) on a rod of `length` (NaN if unknown).
    pub(super) fn tendon(&mut self, i: usize, t: &TendonTable, length: f64) {
        let path = format!("tendon[{}]", i + 1);
        let tension = format!("{path}.tension");
        match (t.tension, t.displacement) {
            (Some(tau), None) => {
                if self.finite(&tension, tau, " N") && tau < 0.0 {
                    self.report(
                        &tension,
                        format!("is {} N, but a tendon can only pull: must be >= 0", Readable(tau)),
                    );
                }
            }
            (None, Some(q)) => {
                self.finite(&format!("{path}.displacement"), q, " m");
            }
            (Some(_), Some(_)) => self.report(
                &format!("{path}.displacement"),
                "is given together with `tension`: a tendon is driven by its tension (N) or by its \
                 actuator's displacement (m), so give one of them"
                    .to_string(),
            ),
            // Reported when the table was read, with the table's missing fields.
            (None, None) => {}
        }
        if let Some(end) = t.end {
            let field = format!("{path}.end");
            if self.finite(&field, end, " m") && length.is_finite() {
                if end > length {
                    self.report(
                        &field,
                        format!(
                            "is {} m, past the tip at {} m: must be at most rod.length",
                            Readable(end),
                            Readable(length)
                        ),
                    );
                } else if end <= 0.0 {
                    self.report(
                        &field,
                        format!("is {} m, but must be above 0 (the base)", Readable(end)),
                    );
                }
            }
        }
        let routing = format!("{path}.routing");
        match t.routing {
            RoutingTable::Straight {
                x,
                y,
                radius,
                angle_deg,
            } => {
                // The missing half of a pair was reported when the table was read.
                let cartesian = x.is_some() || y.is_some();
                if cartesian && (radius.is_some() || angle_deg.is_some()) {
                    let given = if radius.is_some() { "radius" } else { "angle_deg" };
                    self.report(
                        &format!("{routing}.{given}"),
                        "is given together with `x` or `y`: place the tendon by `x` and `y` (m) or by \
                         `radius` (m) and `angle_deg` (degrees from body x toward body y), not both"
                            .to_string(),
                    );
                }
                for (key, value, unit) in [("x", x, " m"), ("y", y, " m"), ("angle_deg", angle_deg, " deg")] {
                    if let Some(v) = value {
                        self.finite(&format!("{routing}.{key}"), v, unit);
                    }
                }
                if let Some(r) = radius {
                    let field = format!("{routing}.radius");
                    if self.finite(&field, r, " m") && r < 0.0 {
                        self.report(
                            &field,
                            format!(
                                "is {} m, but a distance from the backbone must be >= 0 (turn `angle_deg` \
                                 by 180 to place the tendon on the other side)",
                                Readable(r)
                            ),
                        );
                    }
                }
            }
            RoutingTable::Helical {
                radius,
                turns_per_rod_length,
                turns,
                phase,
                angle_deg,
            } => {
                self.positive(&format!("{routing}.radius"), radius, " m");
                // `turns` is the old name of `turns_per_rod_length`, with the same meaning.
                match (turns_per_rod_length, turns) {
                    (Some(_), Some(_)) => self.report(
                        &format!("{routing}.turns"),
                        "is given together with `turns_per_rod_length`: `turns` is its old name \
                         (the same meaning, turns per rod length); give one of them"
                            .into(),
                    ),
                    (Some(n), None) => {
                        self.finite(&format!("{routing}.turns_per_rod_length"), n, "");
                    }
                    (None, Some(n)) => {
                        self.finite(&format!("{routing}.turns"), n, "");
                    }
                    (None, None) => self.report(
                        &format!("{routing}.turns_per_rod_length"),
                        format!(
                            "is required but missing in [[tendon]] #{}: the helix's turns per rod \
                             length L (a tendon ending at l makes turns_per_rod_length * l / L turns)",
                            i + 1
                        ),
                    ),
                }
                match (phase, angle_deg) {
                    (Some(_), Some(_)) => self.report(
                        &format!("{routing}.angle_deg"),
                        "is given together with `phase`: give the helix's starting angle as `phase` \
                         (rad) or as `angle_deg` (degrees), not both"
                            .into(),
                    ),
                    (Some(p), None) => {
                        self.finite(&format!("{routing}.phase"), p, " rad");
                    }
                    (None, Some(a)) => {
                        self.finite(&format!("{routing}.angle_deg"), a, " deg");
                    }
                    (None, None) => {}
                }
            }
        }
    }

    /// The `[disks]` rules on a rod of `length` (m; NaN if unknown): `count` or `positions`
    /// (on the rod, increasing), `mass` (>= 0, with `gravity`) or `weight`, finite vectors,
    /// a positive `radius`.
    pub(super) fn disks(&mut self, d: &DisksTable, length: f64) {
        match (d.count, &d.positions) {
            (Some(_), Some(_)) => self.report(
                "disks.positions",
                "is given together with `count`: give `count` (evenly spaced, the last at the tip) or \
                 `positions` (m), not both"
                    .into(),
            ),
            (None, None) => self.report(
                "disks",
                "needs `count` (evenly spaced, the last at the tip) or `positions` (arc lengths in m)".into(),
            ),
            (Some(n), None) if !(1..=MAX_DISKS).contains(&n) => {
                self.report("disks.count", format!("is {n}, but must be from 1 to {MAX_DISKS}"))
            }
            (None, Some(positions)) => self.disk_positions(positions, length),
            (Some(_), None) => {}
        }
        match (d.mass, d.weight, d.gravity) {
            (Some(_), Some(_), _) => self.report(
                "disks.weight",
                "is given together with `mass`: give each disk's `mass` (kg, with `gravity`) or its \
                 `weight` (N, world frame), not both"
                    .into(),
            ),
            (None, None, _) => self.report(
                "disks",
                "needs each disk's `mass` (kg, with `gravity`) or `weight` (N, world frame, e.g. \
                 [0.0, 0.0, -0.0098] for 1 g); `mass = 0.0` for disks that are only drawn"
                    .into(),
            ),
            (Some(_), None, None) => self.report(
                "disks.gravity",
                "is required with `mass`: give the gravity vector in m/s^2, world frame, e.g. \
                 [0.0, 0.0, -9.81]"
                    .into(),
            ),
            (None, Some(_), Some(_)) => self.report(
                "disks.gravity",
                "is given with `weight`, which is already a force (N, world frame): give `mass` \
                 with `gravity`, or `weight` alone"
                    .into(),
            ),
            (Some(m), None, Some(_)) => {
                if self.finite("disks.mass", m, " kg") && m < 0.0 {
                    self.report("disks.mass", format!("is {} kg, but must be >= 0", Readable(m)));
                }
            }
            (None, Some(_), None) => {}
        }
        self.vector("disks.gravity", &d.gravity, " m/s^2");
        self.vector("disks.weight", &d.weight, " N");
        if let Some(r) = d.radius {
            self.positive("disks.radius", r, " m");
        }
    }

    /// The rules of `[disks] positions` on a rod of `length` (m; NaN if unknown).
    fn disk_positions(&mut self, positions: &[f64], length: f64) {
        let field = "disks.positions";
        if positions.is_empty() || positions.len() > MAX_DISKS {
            let n = positions.len();
            self.report(field, format!("has {n} entries, but must have 1 to {MAX_DISKS}"));
            return;
        }
        for (k, &s) in positions.iter().enumerate() {
            if !self.finite(field, s, " m") {
                continue;
            }
            if length.is_finite() && !(s > 0.0 && s <= length) {
                self.report(
                    field,
                    format!(
                        "has {} m (entry {}), but every disk must lie on the rod, in (0, {}] m",
                        Readable(s),
                        k + 1,
                        Readable(length)
                    ),
                );
            }
            if k > 0 && s <= positions[k - 1] {
                self.report(
                    field,
                    format!(
                        "has {} m after {} m (entry {}): give the positions increasing, each once",
                        Readable(s),
                        Readable(positions[k - 1]),
                        k + 1
                    ),
                );
            }
        }
    }

    /// A key given under its name or its old name (an alias): the field path and value of
    /// the one given (the new name if both, which is a problem naming both).
    fn renamed(
        &mut self,
        name: &str,
        alias: &str,
        value: Option<usize>,
        old: Option<usize>,
    ) -> Option<(String, usize)> {
        match (value, old) {
            (Some(n), Some(_)) => {
                self.report(
                    &format!("solver.{alias}"),
                    format!("is given together with `{name}`: `{alias}` is its old name; give one of them"),
                );
                Some((format!("solver.{name}"), n))
            }
            (Some(n), None) => Some((format!("solver.{name}"), n)),
            (None, Some(n)) => Some((format!("solver.{alias}"), n)),
            (None, None) => None,
        }
    }

    /// Reports the first rule of the library that `checks` (each the options' `validate()`
    /// with only `field` changed from the defaults) says `field` = `shown` breaks.
    fn library_rule(&mut self, field: &str, shown: &str, checks: &[Result<(), Error>]) -> bool {
        let Some(Err(e)) = checks.iter().find(|c| c.is_err()) else {
            return true;
        };
        let message = match e {
            // A rule about the options as a whole: its hint speaks of the Rust API.
            Error::InvalidInput { field: f, problem, .. } if !f.contains('.') => format!("is {shown}, but {problem}"),
            Error::InvalidInput { problem, hint, .. } => format!("{problem}; {hint}"),
            other => other.to_string(),
        };
        self.report(field, message);
        false
    }

    /// The `[solver]` rules: the library's own (`collocation::Options::validate`,
    /// `shooting::Options::validate`), checked one field at a time from the defaults so
    /// that every broken rule is reported at its key, plus the file's: numbers finite, a
    /// mesh of at least one interval, a key and its old name not both given.
    pub(super) fn solver(&mut self, solver: &SolverTable) {
        let intervals = self.renamed("intervals", "nodes", solver.intervals, solver.nodes);
        let cap = self.renamed("max_intervals", "max_nodes", solver.max_intervals, solver.max_nodes);
        if let Some((field, 0)) = &intervals {
            self.report(field, "is 0, but the mesh needs at least 1 interval".into());
        }
        let mut finite = |field: &str, x: Option<f64>, unit: &str| x.filter(|&x| self.finite(field, x, unit));
        let tolerance = finite("solver.tolerance", solver.tolerance, " (relative to the rod length)");
        let residual = finite("solver.residual_tolerance", solver.residual_tolerance, "");
        let integration = finite("solver.integration_tolerance", solver.integration_tolerance, "");
        let c = collocation::Options::default;
        let s = shooting::Options::default;
        if let Some(x) = residual {
            let checks = [
                collocation::Options {
                    residual_tolerance: x,
                    ..c()
                }
                .validate(),
                shooting::Options {
                    residual_tolerance: x,
                    ..s()
                }
                .validate(),
            ];
            self.library_rule("solver.residual_tolerance", &Readable(x).to_string(), &checks);
        }
        if let Some(n) = solver.max_iterations {
            let checks = [
                collocation::Options {
                    max_iterations: n,
                    ..c()
                }
                .validate(),
                shooting::Options {
                    max_iterations: n,
                    ..s()
                }
                .validate(),
            ];
            self.library_rule("solver.max_iterations", &n.to_string(), &checks);
        }
        if let Some(t) = tolerance {
            let checks = [collocation::Options {
                tolerance: Some(t),
                ..c()
            }
            .validate()];
            self.library_rule(
                "solver.tolerance",
                &format!("{} (relative to the rod length)", Readable(t)),
                &checks,
            );
        }
        if let Some(x) = integration {
            let checks = [shooting::Options {
                integration_tolerance: x,
                ..s()
            }
            .validate()];
            self.library_rule("solver.integration_tolerance", &Readable(x).to_string(), &checks);
        }
        // The cap on its own (with a starting mesh within it), then the starting mesh
        // against the cap: at `intervals` if given, else at the cap that the default breaks.
        let cap_ok = match &cap {
            Some((field, n)) => {
                let checks = [collocation::Options {
                    max_intervals: *n,
                    intervals: c().intervals.min(*n),
                    ..c()
                }
                .validate()];
                self.library_rule(field, &n.to_string(), &checks)
            }
            None => true,
        };
        if cap_ok && !matches!(intervals, Some((_, 0))) {
            let options = collocation::Options {
                intervals: intervals.as_ref().map_or(c().intervals, |i| i.1),
                max_intervals: cap.as_ref().map_or(c().max_intervals, |m| m.1),
                ..c()
            };
            if let Err(Error::InvalidInput { problem, hint, .. }) = options.validate() {
                match (&intervals, &cap) {
                    (Some((field, _)), _) => self.report(field, format!("{problem}; {hint}")),
                    (None, Some((field, n))) => {
                        self.report(field, format!("is {n}: the default `intervals` {problem}; {hint}"));
                    }
                    (None, None) => {}
                }
            }
        }
    }
}
