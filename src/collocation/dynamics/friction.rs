//! The linearized dynamics of an equilibrium with tendons with friction (docs/stability.md,
//! "Tendons with friction"): the collocation system bordered by the log tensions z and
//! their capstan rows (`collocation/friction`), each link's slip pattern held as the solve
//! used it (full slip: w = -1 or +1; in a history, stuck links keep their stick rows).
//!
//! The tendons are massless, so the log tensions are algebraic unknowns like the tensions of
//! displacement-controlled tendons, and the modes solve
//!
//! ```text
//! [ J      F_z   ] [phi]        [ M_x ] [phi]
//! [ psi_x  psi_z ] [ zeta ] = mu [ M_psi ]
//! ```
//!
//! M_x is the backbone's mass of [`Mass`] with each collocation point's response to the
//! inertia load taken from eq. 13 with friction (the tangential loads follow the normal loads
//! the accelerated rates press: [`FrictionLinearization::load_response`]); M_psi is the same
//! quadrature of the capstan rows' turning rates, which depend on the rates (0 on a stick
//! row, which depends on node states alone). Shift-invert at 0 with the factors of the
//! bordered Jacobian at the answer (the staircase: Newton's last, when it was evaluated
//! there) gives the lowest modes, classified as [`super::classify`] classifies the
//! frictionless ones.

#![allow(non_snake_case)]

use super::{KRYLOV, MOVING, Mass, Vibration, inertia_load_transposed, quadrature, restricted, spectrum};
use crate::collocation::friction::Capstan;
use crate::collocation::residual::end_values;
use crate::collocation::unknowns::{THETA, U, V, unknowns};
use crate::model::equations::{Model, Site};
use crate::model::friction::{FrictionLinearization, linearize_into};
use crate::report::{SolveReport, Stability};
use crate::simd::{all_finite, avx2_fma};
use crate::so3;
use crate::solution::State;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// The mass of the bordered system: the backbone's blocks and, per capstan row that has
/// mass, its border row and its 1 x 12 block over the (p, theta) of its link's two nodes.
struct CapstanMass {
    backbone: Mass,
    rows: Vec<(usize, usize, SMatrix<f64, 1, 12>)>,
}

impl CapstanMass {
    /// The mass of `border`'s system (its profile at the current log tensions) at the
    /// equilibrium `x`, with each link's multipliers `held` when given ([`Multipliers`]),
    /// else the profile's now; None when eq. 13 with friction or its load response breaks
    /// down.
    fn new(border: &Capstan, x: &[State], held: Option<&Multipliers>) -> Option<Self> {
        let system = border.system();
        let profile = system.friction.as_ref()?;
        let (ratio, length) = mass_scale(system.model.robot);
        let count = profile.count();
        let mut model: Model = system.model.clone();
        let mut lin = FrictionLinearization::default();
        let mut turning_at = vec![SMatrix::<f64, 1, 6>::zeros(); count];
        // Eq. 13 with friction at point `index` (link k's start node 2k, its midpoint
        // 2k + 1, the last node 2 links) with the slips at log tensions `z`: its rates,
        // turning rates, response to a unit acceleration (`z6`) and the turning rates'
        // response (`turn`, one per slip). Taken from the Jacobian at the same inputs when it
        // kept them (`Profile::kept_response`: the same evaluation, bit for bit), else
        // evaluated.
        let mut point = |index: usize,
                         site: &Site,
                         seg: f64,
                         (Rc, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
                         z: &[f64],
                         w: Option<&[f64]>,
                         z6: &mut SMatrix<f64, 6, 6>,
                         turn: &mut Vec<SMatrix<f64, 1, 6>>|
         -> Option<(nalgebra::Vector6<f64>, Vec<f64>)> {
            let mut t = SMatrix::<f64, 6, 6>::zeros();
            if let Some(kept) = profile.kept_response(index, seg, (Rc, v, u), (z, w), (&mut t, turn)) {
                *z6 = t.transpose();
                return Some(kept);
            }
            for (j, &i) in profile.slipping.iter().enumerate() {
                model.tensions[i] = profile.tension(j, z[j]);
            }
            linearize_into(&model, site, seg, (Rc, v, u), &profile.slipping, w, false, &mut lin).ok()?;
            t = inertia_load_transposed(site, Rc, ratio, length);
            if !lin.load_response(&mut t, &mut turning_at) {
                return None;
            }
            *z6 = t.transpose();
            turn.clone_from(&turning_at);
            Some((lin.lin.rates, lin.turning.clone()))
        };
        let links = x.len() - 1;
        let mut blocks = Vec::with_capacity(links);
        let mut rows = Vec::new();
        let (mut za, mut zm, mut zb) = (SMatrix::<f64, 6, 6>::zeros(), SMatrix::zeros(), SMatrix::zeros());
        let (mut ta, mut tm, mut tb) = (Vec::new(), Vec::new(), Vec::new());
        // The log tensions at the link's nodes and midpoint, refilled per link.
        let (mut z_a, mut z_b, mut z_m) = (
            Vec::with_capacity(count),
            Vec::with_capacity(count),
            Vec::with_capacity(count),
        );
        // The node whose evaluation the last interval left in (zb, tb, end), with its
        // segment and multipliers: the next interval's start when it has the same inputs.
        let mut carried: Option<(usize, f64, Option<Vec<f64>>)> = None;
        let mut end = None;
        for k in 0..links {
            let Some(sites) = system.interval_sites(k) else {
                carried = None;
                blocks.push(None);
                continue;
            };
            let seg = system.mesh.nodes[k].segment_end;
            let (a, b) = (&x[k], &x[k + 1]);
            let h = sites.end.s - sites.start.s;
            // The multipliers at the link's start, midpoint and end (a stuck link's
            // per-point ones, W sigma_P, where it has them).
            let multipliers = match held {
                Some(held) => held.0.get(k).cloned().flatten(),
                None => profile.multipliers(k).map(|w| profile.point_multipliers(k, &w)),
            };
            let [w_a, w_m, w_b] = match &multipliers {
                Some([a, m, b]) => [Some(a.as_slice()), Some(m.as_slice()), Some(b.as_slice())],
                None => [None; 3],
            };
            z_a.clear();
            z_a.extend(profile.z.iter().map(|z| z[k]));
            z_b.clear();
            z_b.extend(profile.z.iter().map(|z| z[k + 1]));
            let (ra, kappa_a) = match (carried.take(), end.take()) {
                (Some((node, s, kept)), Some(start)) if node == k && s == seg && kept.as_deref() == w_a => {
                    std::mem::swap(&mut za, &mut zb);
                    std::mem::swap(&mut ta, &mut tb);
                    start
                }
                _ => point(
                    2 * k,
                    &sites.start,
                    seg,
                    (&a.R, &a.v, &a.u),
                    &z_a,
                    w_a,
                    &mut za,
                    &mut ta,
                )?,
            };
            // Node k + 1 as the next link's start, where a Jacobian keeps it, or on a link
            // with a stuck slip as its own end (with its own multipliers).
            let stuck = (0..count).any(|j| profile.sticks(j, k));
            let (rb, kappa_b) = point(
                if stuck { profile.end_point(k) } else { 2 * k + 2 },
                &sites.end,
                seg,
                (&b.R, &b.v, &b.u),
                &z_b,
                w_b,
                &mut zb,
                &mut tb,
            )?;
            // The Hermite-Simpson midpoint of (y, z), as the interval's rows take it.
            let [y0, y1, f0, f1] = end_values(sites, a, b, &ra, &rb);
            let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
            z_m.clear();
            z_m.extend((0..count).map(|j| 0.5 * (z_a[j] + z_b[j]) + h / 8.0 * (kappa_a[j] - kappa_b[j])));
            let part = |at: usize| Vector3::new(ym[at], ym[at + 1], ym[at + 2]);
            let Rm = a.R * so3::exp(&part(THETA));
            let (vm, um) = (part(V), part(U));
            point(2 * k + 1, &sites.mid, seg, (&Rm, &vm, &um), &z_m, w_m, &mut zm, &mut tm)?;
            let mut block = quadrature(h, (&a.R, &b.R), [&za, &zm, &zb]);
            for r in 3..6 {
                for c in 0..12 {
                    block[(r, c)] *= length;
                }
            }
            blocks.push(Some(block));
            end = Some((rb, kappa_b));
            carried = Some((k + 1, seg, w_b.map(<[f64]>::to_vec)));
            // The capstan row psi = z_b - z_a - h/6 (kappa~_a + 4 kappa~_m + kappa~_b)
            // gains the same quadrature of the turning rates' response, with the sign the
            // backbone rows' rates have in theirs (module docs of `dynamics`).
            for j in (0..count).filter(|&j| profile.on_link(j, k) && !profile.sticks(j, k)) {
                let row = quadrature(h, (&a.R, &b.R), [&ta[j], &tm[j], &tb[j]]);
                rows.push((border.capstan_row(j, k), k, row));
            }
        }
        Some(CapstanMass {
            backbone: Mass { blocks },
            rows,
        })
    }

    /// (y_x, y_psi) = M z for the (p, theta) parts `z` ([`restrict`]'s layout); `y_x` must be
    /// zero outside the rows [`Mass::apply`] writes, `y_psi` is written whole. On x86-64 with
    /// AVX2 and FMA (checked at run time) compiled for them: the same operations in the same
    /// order (no product and sum fused), so the same bits.
    fn apply(&self, z: &[f64], y_x: &mut [f64], y_psi: &mut [f64]) {
        avx2_fma!(self.apply_kernel(z, y_x, y_psi));
    }

    /// [`CapstanMass::apply`]'s operations.
    #[inline(always)]
    fn apply_kernel(&self, z: &[f64], y_x: &mut [f64], y_psi: &mut [f64]) {
        self.backbone.apply(z, y_x);
        y_psi.fill(0.0);
        for (row, k, block) in &self.rows {
            let z = &z[k * MOVING..(k + 2) * MOVING];
            y_psi[*row] = block.iter().zip(z).map(|(m, z)| m * z).sum();
        }
    }
}

/// The rod's density over its Young's modulus and its length, the scale of the inertia
/// loads of the mass ([`inertia_load_transposed`]).
pub(crate) fn mass_scale(robot: &crate::Robot) -> (f64, f64) {
    let ratio = super::DENSITY / robot.rod.geometry.map_or(super::MODULUS, |g| g.youngs_modulus);
    (ratio, robot.length())
}

/// The scope of a verdict with friction, noted on every full-slip solve that has one
/// (docs/stability.md, "Tendons with friction"): the linearized dynamics holds each
/// stretch's slip direction, and a disturbance that reverses it meets the stuck system.
pub(crate) const SLIP_HELD: &str = "with friction the stability verdict is that of the linearized dynamics with each \
     stretch's slip direction held (the tendon keeps sliding the way the solve assumed, as while its actuator \
     moves); a disturbance that reverses the slip somewhere makes that stretch stick, which the verdict does not cover";

/// The verdict of an inner solve of the pull-in loop with friction (at given base-entry
/// tensions): none, since the loop's answer gets the verdict with its pull-ins held
/// ([`super::pulled`]).
pub(crate) fn held_unknown() -> Stability {
    Stability::Unknown {
        reason: "tendons with friction and displacement control: an inner solve at given tensions of the pull-in \
                 loop, whose answer gets the verdict with the pull-ins held"
            .into(),
    }
}

/// Each link's multipliers at its start, midpoint and end (`Profile::multipliers` and
/// `Profile::point_multipliers`: None in full slip; on a stuck link of a history step
/// w = (z_b - z_a) / C, C the link's capacity from its last evaluation, or with per-point
/// multipliers W sigma_P at each point) as the bordered Jacobian at the answer takes them:
/// read before [`factor_at`] evaluates it, since that evaluation leaves each stuck link's
/// own capacity and shares at the answer in the profile, which may differ from the ones it
/// was evaluated with in the last bits (docs/stability.md, "Load-history steps"). The mass
/// takes the same, so that it is the Jacobian's linearization and reads the responses that
/// Jacobian kept at its points.
pub(super) struct Multipliers(Vec<Option<[Vec<f64>; 3]>>);

/// The bordered Jacobian of `border` evaluated and factored at `x` for a verdict (counted
/// in `report`), with the multipliers it took; Err with the verdict when it is singular or
/// cannot be evaluated.
pub(super) fn factor_at(border: &mut Capstan, x: &[State], report: &mut SolveReport) -> Result<Multipliers, Stability> {
    let multipliers = border.system().friction.as_ref().map_or_else(Vec::new, |p| {
        (0..x.len() - 1)
            .map(|k| p.multipliers(k).map(|w| p.point_multipliers(k, &w)))
            .collect()
    });
    match border.factor_at(x, report) {
        Ok(true) => Ok(Multipliers(multipliers)),
        Ok(false) => Err(Stability::Unknown {
            reason: "the bordered Jacobian at the solution is singular".into(),
        }),
        Err(e) => Err(Stability::Unknown {
            reason: format!("the bordered Jacobian at the solution could not be evaluated: {e}"),
        }),
    }
}

/// The verdict of the linearized dynamics at the equilibrium `x` of `border`'s system (its
/// profile loaded at the solved log tensions), with the factors of Newton's last bordered
/// Jacobian held in its staircase when `fresh` (that Jacobian belongs to `x`: evaluated
/// within Newton's stopping distance of it, docs/stability.md "Which Jacobian"), else with
/// the bordered Jacobian evaluated and factored at `x` for it (counted in `report`).
pub(crate) fn assess(border: &mut Capstan, x: &[State], fresh: bool, report: &mut SolveReport) -> Stability {
    let multipliers = if fresh {
        None
    } else {
        match factor_at(border, x, report) {
            Ok(m) => Some(m),
            Err(verdict) => return verdict,
        }
    };
    modes_held(border, x, KRYLOV, false, multipliers.as_ref(), &mut |_, _| true).stability
}

/// [`assess`] with the eigenvalues, from `krylov` Arnoldi steps as [`super::modes`] takes
/// them, with the factors `border` holds (the mass with the profile's multipliers now).
pub(super) fn modes(border: &mut Capstan, x: &[State], krylov: usize, all: bool) -> Vibration {
    modes_held(border, x, krylov, all, None, &mut |_, _| true)
}

/// [`modes`] with the mass taking `multipliers` when given (those of the Jacobian
/// factored by [`factor_at`]), and `held` applied to each bordered solve's backbone part
/// (scaled node unknowns, the border's log tensions still its last solve's) before the
/// restriction: the held pull-ins' projection of `pulled.rs` (false when it cannot be
/// applied).
pub(super) fn modes_held(
    border: &mut Capstan,
    x: &[State],
    krylov: usize,
    all: bool,
    multipliers: Option<&Multipliers>,
    held: &mut dyn FnMut(&Capstan, &mut [f64]) -> bool,
) -> Vibration {
    let Some(mass) = CapstanMass::new(border, x, multipliers) else {
        return Vibration {
            stability: Stability::Unknown {
                reason: "the mass matrix with friction could not be formed (eq. 13 with friction singular at a point)"
                    .into(),
            },
            eigenvalues: Vec::new(),
        };
    };
    let n = unknowns(x.len());
    let mut y_x = vec![0.0; n];
    let mut y_psi = vec![0.0; border.border_rows()];
    let mut dx = vec![0.0; n];
    let mut operator = |z: &[f64], out: &mut Vec<f64>| -> bool {
        mass.apply(z, &mut y_x, &mut y_psi);
        if !border.solve_with_factors(&y_x, &y_psi, &mut dx) || !held(border, &mut dx) || !all_finite(&dx) {
            return false;
        }
        restricted(&dx, out);
        true
    };
    spectrum(&mut operator, x.len(), krylov, all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::sensitivity::Sensitivity;
    use crate::report::Method;
    use crate::{Friction, Motion, cases};

    /// The mass with friction from the responses that the Jacobian at the answer keeps
    /// (`Profile::kept_response`) is the mass evaluated afresh, bit for bit, on every block
    /// and capstan row: case H with friction on its helix (pull) and case S released, at
    /// their answers.
    #[test]
    fn kept_responses_give_the_mass_bit_for_bit() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut h = cases::case_h();
        h.tendons[4].friction = Some(Friction::pull(0.1));
        let mut s = cases::case_s();
        s.tendons[0].friction = Some(Friction {
            coefficient: 0.1,
            motion: Motion::Release,
        });
        for robot in [h, s] {
            let solution = crate::collocation::solve(&robot, &Default::default()).unwrap();
            let (mut border, x, _) = Sensitivity::new(&robot, &solution).unwrap().into_border();
            // Nothing kept yet: every point evaluated.
            let fresh = CapstanMass::new(&border, &x, None).unwrap();
            let mut report = SolveReport::new(Method::Collocation);
            assert!(border.factor_at(&x, &mut report).unwrap());
            // The Jacobian at x kept node 0's response (the mass reads it below).
            let system = border.system();
            let profile = system.friction.as_ref().unwrap();
            let z: Vec<f64> = profile.z.iter().map(|z| z[0]).collect();
            let w = profile.multipliers(0);
            let (mut loads, mut turns) = (SMatrix::zeros(), Vec::new());
            let seg = system.mesh.nodes[0].segment_end;
            let state = (&x[0].R, &x[0].v, &x[0].u);
            assert!(
                profile
                    .kept_response(0, seg, state, (&z, w.as_deref()), (&mut loads, &mut turns))
                    .is_some()
            );
            let hits = border.system().friction.as_ref().unwrap().kept_hits();
            let kept = CapstanMass::new(&border, &x, None).unwrap();
            // Each link's start node and midpoint reads a kept response (measured: exactly
            // 2 per link on H; a cache that never hits would read none).
            let links = x.len() - 1;
            let read = border.system().friction.as_ref().unwrap().kept_hits() - hits;
            assert!(read >= 2 * links, "{read} kept responses read for {links} links");
            let mut compared = 0;
            for (a, b) in fresh.backbone.blocks.iter().zip(&kept.backbone.blocks) {
                match (a, b) {
                    (Some(a), Some(b)) => {
                        assert_eq!(bits(a.as_slice()), bits(b.as_slice()));
                        compared += 1;
                    }
                    (None, None) => {}
                    _ => panic!("a jump in one mass only"),
                }
            }
            assert!(compared >= 16, "{compared} intervals");
            assert_eq!(fresh.rows.len(), kept.rows.len());
            for ((ra, ka, a), (rb, kb, b)) in fresh.rows.iter().zip(&kept.rows) {
                assert_eq!((ra, ka), (rb, kb));
                assert_eq!(bits(a.as_slice()), bits(b.as_slice()));
            }
        }
    }

    /// On a history step with a stuck stretch (the prototype's pull-release loop, tendon 1
    /// at mu 0.1 and E_t A_t 2000 N, the first step back: stuck from 0.049 m to the tip), the
    /// Jacobian at the answer takes each link's multipliers as they were before it (each
    /// stuck link's W sigma_P at its three points, with the answer's shares); with those,
    /// the mass reads every link's midpoint,
    /// each stuck link's start and end node and the sliding links' ends from that Jacobian's
    /// kept responses, and is the mass evaluated afresh with the same multipliers, bit for bit.
    #[test]
    fn a_stuck_steps_mass_reads_the_jacobians_responses_bit_for_bit() {
        use crate::analysis::sweep::{Input, Ranges};
        use crate::collocation::friction::history::{start, step};
        use crate::model::parameter::Parameter;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut robot = cases::prototype();
        robot.tendons[0].friction = Some(Friction::pull(0.1));
        robot.tendons[0].stiffness = Some(2000.0);
        let values: Vec<f64> = (0..=10).map(|k| 4.91 * k as f64 / 10.0).collect();
        let ranges = Ranges::new(robot, vec![(Input::Parameter(Parameter::Tension(0)), values)])
            .unwrap()
            .up_down();
        let robots: Vec<crate::Robot> = (0..12).map(|k| ranges.robot(k as f64).unwrap()).collect();
        let options = Default::default();
        let mut carried = start(&robots, &options).unwrap();
        for robot in &robots {
            step(robot, &options, &mut carried).unwrap();
        }
        let settled = carried.settled.as_ref().unwrap();
        let x = &settled.x;
        let links = x.len() - 1;
        let mut border = super::super::stuck::border(&robots[11], settled);
        let profile = border.system().friction.as_ref().unwrap();
        let stuck = (0..links).filter(|&k| profile.sticks(0, k)).count();
        assert!(stuck > links / 2 && stuck < links, "{stuck} of {links} links stuck");
        let before = Multipliers(
            (0..links)
                .map(|k| profile.multipliers(k).map(|w| profile.point_multipliers(k, &w)))
                .collect(),
        );
        // Nothing kept yet: every point evaluated.
        let fresh = CapstanMass::new(&border, x, Some(&before)).unwrap();
        let mut report = SolveReport::new(Method::Collocation);
        let held = factor_at(&mut border, x, &mut report).ok().unwrap();
        assert_eq!(held.0, before.0);
        let hits = border.system().friction.as_ref().unwrap().kept_hits();
        let kept = CapstanMass::new(&border, x, Some(&held)).unwrap();
        // Per link its midpoint and end node, and a stuck link's start (its multipliers are
        // not the link before's, so its start is not carried from that link's end; the
        // bound leaves one such start to be carried where two links' multipliers happen
        // to agree, and leaves out the first link's start). Measured: 656 = 2 x 226 + 204
        // read on 226 links, 204 of them stuck; without the stuck links' ends kept each of
        // them is evaluated afresh (204 fewer reads), and with the multipliers taken after
        // the Jacobian a stuck link's start and midpoint miss wherever its capacity's last
        // bits moved.
        let read = border.system().friction.as_ref().unwrap().kept_hits() - hits;
        assert!(
            read >= 2 * links + stuck - 1,
            "{read} kept responses read for {links} links, {stuck} stuck"
        );
        for (a, b) in fresh.backbone.blocks.iter().zip(&kept.backbone.blocks) {
            assert_eq!(a.map(|a| bits(a.as_slice())), b.map(|b| bits(b.as_slice())));
        }
        assert_eq!(fresh.rows.len(), kept.rows.len());
        for ((ra, ka, a), (rb, kb, b)) in fresh.rows.iter().zip(&kept.rows) {
            assert_eq!((ra, ka), (rb, kb));
            assert_eq!(bits(a.as_slice()), bits(b.as_slice()));
        }
        // The Jacobian and the mass took the answer's per-point multipliers W sigma_P
        // (docs/friction.md section 8, "ord23"): on the stuck links their three differ (the
        // constant multiplier, as the verdict took before, has them equal).
        let pointwise = held
            .0
            .iter()
            .filter(|m| m.as_ref().is_some_and(|[a, m, b]| a != m || m != b))
            .count();
        assert!(
            pointwise + 1 >= stuck,
            "{pointwise} of {stuck} stuck links with per-point multipliers"
        );
        // So the verdict's rows are the answer's: its backbone residual at the answer is
        // Newton's (the answer is an equilibrium of the system assessed), where the
        // constant multiplier leaves the per-point multipliers' O(h^2) spread of the
        // tangential loads.
        let residual = |settled: &crate::collocation::friction::history::Settled| -> f64 {
            let border = super::super::stuck::border(&robots[11], settled);
            let mut r = vec![0.0; border.system().unknowns()];
            border.system().residual(x, &mut r).unwrap();
            // The links' rows: all but the tip's six end rows (which the border's tendon
            // terms complete, as Newton's bordered residual does).
            r[..r.len() - 6].iter().fold(0.0, |m: f64, v| m.max(v.abs()))
        };
        let mut constant = settled.clone();
        constant.shares.clear();
        let (own, other) = (residual(settled), residual(&constant));
        // Measured: 8.9e-12 (Newton's residual tolerance is 1e-11) against 1.3e-8.
        assert!(own < 1e-10 && other > 100.0 * own, "{own:e} {other:e}");
    }
}
