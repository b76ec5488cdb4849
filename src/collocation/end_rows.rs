//! The base and tip rows of the collocation Jacobian in closed form (docs/numerics.md, "The
//! base and tip rows' derivatives"): their values are the f64 residual's
//! ([`residual::base`], [`residual::tip`]) and their derivatives the chain rule written out,
//! where dual numbers carried 6 and 9 derivative lanes through the same code (a ninth of a
//! prototype Jacobian's instructions, 67 k of 0.61 M, for 12 of its 396 rows).
//!
//! Base rows b = ((p - p_0) / L, log(R_0^T R)) with p -> p + L dp, R -> R exp(dtheta):
//! db/d(dp) = I, db/d(dtheta) = J_r^-1(log(R_0^T R)).
//!
//! Tip rows (the free end's wrench balance, [`Model::wrench_balance`] with no right side)
//! in the tip's body frame: with the tendons i that end at the tip, their body-frame pulls
//! f_i = tau_i p_i' / |p_i'|, p_i' = u x r_i + r_i' + v (the strain of the node's
//! coordinate, [`crate::model::equations::Site::strain`]), the external point wrench
//! (F, M) in the world frame and the follower wrench (F_b, M_b) in the body frame,
//!
//! ```text
//! R^T dn = D (v - v*) - R^T F + sum_i f_i - F_b          (force: sum only when coupled)
//! R^T dm = C (u - u*) - R^T M + sum_i r_i x f_i - M_b
//! rows   = (D^-1 R^T dn, C^-1 R^T dm L)
//! ```
//!
//! With R -> R exp(dtheta), R^T a -> R^T a + (R^T a) x dtheta, so d(-R^T F)/d(dtheta) =
//! -hat(R^T F) (and -hat(R^T M)); df_i/dp_i' = tau_i (I - t_i t_i^T) / |p_i'| =: G_i
//! (t_i = p_i' / |p_i'|), dp_i'/dv = I on a Cosserat rod (0 on a Kirchhoff rod, whose strain
//! is v*), dp_i'/du = -hat(r_i); the unknowns move u by du L / L, so the u columns carry
//! 1 / L.

use super::residual::{self, Delta};
use super::unknowns::{BASE_COLUMNS, BASE_ROWS, TIP_COLUMNS, TIP_ROWS};
use crate::error::Result;
use crate::model::equations::{Model, Site, Which};
use crate::model::robot::TendonModel;
use crate::so3;
use crate::solution::State;
use nalgebra::{Matrix3, Vector3};

/// The base rows at node 0's state `x` into `out` (6 values) and their derivatives in
/// node 0's (dp / L, dtheta) into `values` (6 x 6, row major, as
/// [`super::unknowns::pattern`] lists them).
pub(super) fn base_rows(model: &Model, x: &State, out: &mut [f64], values: &mut [f64]) {
    let rows = residual::base(model, x, &Delta::<f64>::zeros());
    out[..BASE_ROWS].copy_from_slice(rows.as_slice());
    let phi: Vector3<f64> = rows.fixed_rows::<3>(3).into();
    let jri = so3::right_jacobian_inv(&phi);
    for r in 0..3 {
        let position = &mut values[r * BASE_COLUMNS..(r + 1) * BASE_COLUMNS];
        position.fill(0.0);
        position[r] = 1.0;
        let rotation = &mut values[(3 + r) * BASE_COLUMNS..(4 + r) * BASE_COLUMNS];
        rotation[..3].fill(0.0);
        for c in 0..3 {
            rotation[3 + c] = jri[(r, c)];
        }
    }
}

/// The tip rows at the last node's state `x` (site `site`) into `out` (6 values) and their
/// derivatives in its (dtheta, dv, du L) into `values` (6 x 9, row major, as
/// [`super::unknowns::pattern`] lists them).
///
/// # Errors
/// [`crate::Error::SingularRouting`] where a tendon ending at the tip has no tangent.
pub(super) fn tip_rows(model: &Model, site: &Site, x: &State, out: &mut [f64], values: &mut [f64]) -> Result<()> {
    let rows = residual::tip(model, site, x, &Delta::<f64>::zeros())?;
    out[..TIP_ROWS].copy_from_slice(rows.as_slice());
    let length = model.robot.length();
    let inv_length = 1.0 / length;
    // Derivatives of R^T dn (force) and R^T dm (moment) in dtheta, dv and du, before the
    // rows' scaling; du is the curvature's own change here (1 / L applied at the end).
    let (f_ext, l_ext) = model.point_wrench(site.s);
    let rt = x.R.transpose();
    let section = &site.section.section;
    let mut force = [
        -so3::hat(&(rt * f_ext)),
        Matrix3::from_diagonal(&section.kse),
        Matrix3::zeros(),
    ];
    let mut moment = [
        -so3::hat(&(rt * l_ext)),
        Matrix3::zeros(),
        Matrix3::from_diagonal(&section.kbt),
    ];
    let coupled = model.robot.tendon_model == TendonModel::Coupled;
    let strain = site.strain(&x.v);
    for (_, tension, rp) in model.tendons(site.s, Which::EndingAt(site.s)) {
        let pb_s = x.u.cross(&rp.r) + rp.r_s + strain;
        let speed = pb_s.norm();
        let t = pb_s / speed;
        let g = (Matrix3::identity() - t * t.transpose()) * (tension / speed);
        let arm = so3::hat(&rp.r);
        let g_u = -(g * arm);
        if coupled {
            if !site.inextensible {
                force[1] += g;
            }
            force[2] += g_u;
        }
        if !site.inextensible {
            moment[1] += arm * g;
        }
        moment[2] += arm * g_u;
    }
    for r in 0..3 {
        for (block, scale) in [1.0, 1.0, inv_length].into_iter().enumerate() {
            for c in 0..3 {
                values[r * TIP_COLUMNS + 3 * block + c] = force[block][(r, c)] * scale / section.kse[r];
                values[(3 + r) * TIP_COLUMNS + 3 * block + c] = moment[block][(r, c)] * scale / section.kbt[r] * length;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Robot;
    use crate::collocation::unknowns::THETA;
    use crate::mesh::{Mesh, guess};
    use crate::model::robot::RodModel;
    use num_dual::DualSVec64;

    /// A node's unknowns as dual numbers carrying the derivatives in the `N` of them from
    /// `first` on (as the Jacobian's assembly seeded them before).
    fn seeded<const N: usize>(first: usize) -> Delta<DualSVec64<N>> {
        Delta::<DualSVec64<N>>::from_fn(|i, _| {
            let x = DualSVec64::<N>::from(0.0);
            if (first..first + N).contains(&i) {
                x.derivative(i - first)
            } else {
                x
            }
        })
    }

    /// The largest difference between the closed-form blocks and forward-mode derivatives
    /// of the same rows (relative to 1 + the entry), and between their values, at the base
    /// and tip of `robot`'s rigid-equilibrium guess turned and bent off it.
    fn worst_difference(robot: &Robot) -> f64 {
        let mut model = Model::new(robot);
        model.tension_factor = 0.8;
        let mesh = Mesh::uniform(robot, 4).unwrap();
        let mut x = guess::rigid_estimate(&model, &mesh.nodes);
        // Off the base rotation (J_r^-1 of a non-zero angle), with strains off the guess.
        x[0].R *= so3::exp(&Vector3::new(0.3, -0.2, 0.4));
        let last = x.len() - 1;
        x[last].R *= so3::exp(&Vector3::new(-0.5, 0.1, 0.7));
        x[last].v += Vector3::new(2e-4, -1e-4, 3e-4);
        x[last].u += Vector3::new(1.5, -2.0, 0.5);
        let mut worst: f64 = 0.0;
        let mut compare = |values: &[f64], out: &[f64], duals: &[(f64, Vec<f64>)]| {
            for (r, (re, eps)) in duals.iter().enumerate() {
                worst = worst.max((out[r] - re).abs() / (1.0 + re.abs()));
                for (c, e) in eps.iter().enumerate() {
                    let v = values[r * eps.len() + c];
                    worst = worst.max((v - e).abs() / (1.0 + e.abs()));
                }
            }
        };
        let (mut out, mut values) = ([0.0; 6], [0.0; 6 * TIP_COLUMNS]);
        base_rows(&model, &x[0], &mut out, &mut values);
        let base = residual::base(&model, &x[0], &seeded::<BASE_COLUMNS>(0));
        let duals: Vec<_> = base
            .iter()
            .map(|d| (d.re, d.eps.0.map_or(vec![0.0; BASE_COLUMNS], |e| e.as_slice().to_vec())))
            .collect();
        compare(&values, &out, &duals);
        let site = model.site(robot.length());
        tip_rows(&model, &site, &x[last], &mut out, &mut values).unwrap();
        let tip = residual::tip(&model, &site, &x[last], &seeded::<TIP_COLUMNS>(THETA)).unwrap();
        let duals: Vec<_> = tip
            .iter()
            .map(|d| (d.re, d.eps.0.map_or(vec![0.0; TIP_COLUMNS], |e| e.as_slice().to_vec())))
            .collect();
        compare(&values, &out, &duals);
        worst
    }

    /// The closed-form base and tip blocks are forward-mode AD's to rounding on robots that
    /// use every term: case H (a helical tendon and a tip force), the prototype with four
    /// tendons pulled, a tip moment, follower tip loads and a tension factor, the same on a
    /// Kirchhoff rod and with the point-moment tendon model. 1e-12: the two evaluations
    /// differ by the order of their roundings, about 1e-15 of the entries, while a wrong
    /// term or scale differs by O(1) (a tendon's G is tau / |p'| ~ 1e2 before scaling).
    #[test]
    fn the_closed_form_end_rows_are_the_dual_numbers_derivatives() {
        let mut loaded = crate::collocation::test_support::pulled_prototype();
        loaded.loads.tip_force = Vector3::new(0.3, -0.2, -0.5);
        loaded.loads.tip_moment = Vector3::new(0.01, 0.02, -0.015);
        loaded.loads.follower_tip_force = Vector3::new(-0.1, 0.2, 0.4);
        loaded.loads.follower_tip_moment = Vector3::new(0.005, -0.01, 0.002);
        let mut kirchhoff = loaded.clone();
        kirchhoff.rod_model = RodModel::Kirchhoff;
        let mut point_moment = loaded.clone();
        point_moment.tendon_model = TendonModel::PointMoment;
        for (name, robot) in [
            ("case H", crate::cases::case_h()),
            ("loaded prototype", loaded),
            ("Kirchhoff", kirchhoff),
            ("point-moment", point_moment),
        ] {
            robot.validate().unwrap();
            let worst = worst_difference(&robot);
            eprintln!("{name}: worst relative difference {worst:.2e}");
            assert!(
                worst < 1e-12,
                "{name}: closed form and dual numbers differ by {worst:.3e}"
            );
        }
    }
}
