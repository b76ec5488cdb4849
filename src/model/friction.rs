//! Friction between tendons and their channels in full slip (the capstan law along the
//! tendon, docs/friction.md): eq. 13 with the tangential part of the tendon's load on the
//! backbone, and the rate of the tension along the tendon.
//!
//! With friction the tension tau_i(s) varies along the tendon. The channels' force on the
//! backbone per unit s is then `-f_i = (tau_i t_i)' = tau_i t_i' + tau_i' t_i` (world
//! frame): the normal part `q_i = tau_i t_i'`, which eq. 13 already has (its body-frame form
//! is `A_i p_i^b''`), and the new tangential part `tau_i' t_i`. Coulomb's law in full slip
//! makes the tangential part mu_i times the normal part's magnitude, signed by the motion:
//!
//! ```text
//! tau_i' = w_i mu_i |q_i| = w_i mu_i tau_i kappa_i,   kappa_i = |t_i'|,   w_i = -1 (pull), +1 (release)
//! ```
//!
//! kappa_i is the turning rate of the tendon's path per unit s: the backbone's bending and
//! the routing's own turning (a helix) together. It depends on the rates (v', u') through
//! p_i^b'', and the rates depend on tau_i' through the tangential load, so eq. 13 is no
//! longer explicit. Here the rates with friction are
//!
//! ```text
//! x = x0 - sum_j g_j y_j,   y_j = M^-1 (t_j, r_j x t_j),   g_j = w_j mu_j |q_j(x)|
//! ```
//!
//! (x0 the rates without the tangential loads, M the matrix of eq. 13, t_j the body-frame
//! unit tangent), solved for the tangential loads g_j (N/m) in `model/tangential.rs`: in
//! closed form where one tendon with friction loads the point (a quadratic in g), else by
//! Newton on these k scalars. The tangential loads change the normal forces only through
//! the small moment r_j x t_j, so the iteration contracts by about mu tau r^2 / (E I) per
//! step (1e-3 for the prototype).
#![allow(non_snake_case)]

mod lanes;
mod response;
#[cfg(test)]
pub(crate) use lanes::friction_robots;
pub(crate) use lanes::linearize_lanes_into;
use response::LaneResponse;

use crate::error::{Result, invalid};
use crate::model::equations::{Model, Site};
use crate::model::linearize::{Linearization, Point};
use crate::model::robot::{Robot, TendonModel};
use crate::model::tangential::{Slip, solve};
use crate::model::tendon::Tendon;
use crate::simd::avx2_fma;
use crate::{Error, Readable};
use nalgebra::{Matrix3, Matrix6, Matrix6x3, SMatrix, Vector3, Vector6};

/// Checks the friction of tendon `i`: a finite coefficient >= 0, and for a coefficient > 0
/// what the full-slip model needs: the coupled tendon model, and no breakpoint (point load or another tendon's termination)
/// inside the tendon's span, where its path would have a corner.
///
/// # Errors
/// [`Error::InvalidInput`] naming `tendons[i].friction`.
pub(crate) fn validate(robot: &Robot, i: usize, t: &Tendon) -> Result<()> {
    let Some(friction) = t.friction else {
        return Ok(());
    };
    let field = format!("tendons[{i}].friction");
    let mu = friction.coefficient;
    if !(mu.is_finite() && mu >= 0.0) {
        return Err(invalid(
            field,
            format!("is {}", Readable(mu)),
            "give the friction coefficient as a finite number >= 0 (0.1 for steel in steel, 0 for none)",
        ));
    }
    if mu == 0.0 {
        return Ok(());
    }
    if robot.tendon_model != TendonModel::Coupled {
        return Err(invalid(
            field,
            format!("is {} with the point-moment tendon model", Readable(mu)),
            "friction needs the coupled tendon model (distributed tendon loads): use it, or set the friction to 0",
        ));
    }
    let end = t.end(robot.length());
    if let Some(s) = robot.breakpoints().into_iter().find(|&s| s > 0.0 && s < end) {
        return Err(invalid(
            field,
            format!(
                "is {} on a tendon that passes a point load or another tendon's termination at s = {} m",
                Readable(mu),
                Readable(s)
            ),
            "friction is supported on tendons whose span holds no breakpoint for now: move the point load or \
             termination past the tendon's end, or set its friction to 0",
        ));
    }
    Ok(())
}

/// An error naming the first tendon of `robot` with friction, and the others' coefficients,
/// when `what` (an analysis that does not model friction yet) is asked of it.
///
/// # Errors
/// [`Error::ModelLimit`] naming `tendons[i].friction`.
pub(crate) fn unsupported(robot: &Robot, what: &str) -> Result<()> {
    let with = slipping(robot);
    let Some(&first) = with.first() else {
        return Ok(());
    };
    let mu = |i: usize| Readable(robot.tendons[i].friction.map_or(0.0, |f| f.coefficient));
    let others: Vec<String> = with[1..]
        .iter()
        .map(|&i| format!(", tendon {}'s {}", i + 1, mu(i)))
        .collect();
    Err(crate::error::limit(
        format!("tendons[{first}].friction"),
        format!(
            "is {}{}, and {what} does not model friction yet",
            mu(first),
            others.concat()
        ),
        format!(
            "set the friction of {} to 0 (robot file `friction = 0` in its [[tendon]]); a solve, sweep or load \
             history models friction",
            if others.is_empty() {
                "this tendon"
            } else {
                "every tendon with friction"
            }
        ),
    ))
}

/// Whether any tendon of `robot` has friction (a coefficient > 0).
pub fn any(robot: &Robot) -> bool {
    robot.tendons.iter().any(|t| t.active_friction().is_some())
}

/// The indices of the tendons of `robot` with friction (a coefficient > 0), in order: the
/// order of every per-tendon friction quantity below.
pub(crate) fn slipping(robot: &Robot) -> Vec<usize> {
    (0..robot.tendons.len())
        .filter(|&i| robot.tendons[i].active_friction().is_some())
        .collect()
}

/// The error of eq. 13 with friction singular at arc length `s`.
fn breakdown(s: f64) -> Error {
    Error::Breakdown {
        s,
        what: "eq. 13 with friction is singular".into(),
    }
}

/// Eq. 13 with friction at a site: the rates (v', u') for the state (R, v, u), with every
/// tendon at the tension the model holds for it here ([`Model::tensions`]: for a tendon
/// with friction its tension at this s), and in `turning` (one entry per tendon) the
/// relative rate of each tension, tau_i' / tau_i = w_i mu_i kappa_i (1/m; 0 for tendons
/// without friction, at zero tension or not loading this segment). The multiplier w_i is
/// the motion's sign, or `multipliers[j]` for the j-th tendon of [`slipping`] when given.
///
/// # Errors
/// As [`crate::model::linearize::rates`], and [`Error::Breakdown`] when the tangential
/// loads do not converge.
pub(crate) fn rates(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    multipliers: Option<&[f64]>,
    turning: &mut [f64],
) -> Result<Vector6<f64>> {
    turning.fill(0.0);
    let slipping = slipping(model.robot);
    let (R, v, u) = state;
    let point = Point::new(model, site, segment_end, (R, v, u))?;
    let mut slips = Vec::with_capacity(slipping.len());
    let x = solve(
        model,
        &point,
        site,
        segment_end,
        (v, u),
        &slipping,
        multipliers,
        &mut slips,
    )?;
    for sl in &slips {
        turning[slipping[sl.slot]] = relative(sl);
    }
    Ok(x)
}

/// kappa_i = |q_i| / tau_i = |t_i'| (1/m), whatever the multiplier.
fn path_turning(sl: &Slip) -> f64 {
    // k_i = tau_i / |p_i^b'| > 0 for a loading tendon
    sl.q.norm() * sl.tp.inv_speed / sl.tp.k
}

/// tau_i' / tau_i = w_i mu_i |q_i| / tau_i (1/m).
fn relative(sl: &Slip) -> f64 {
    // k_i = tau_i / |p_i^b'| > 0 for a loading tendon
    sl.g * sl.tp.inv_speed / sl.tp.k
}

/// Eq. 13 with friction and its exact first derivatives at one point, for the collocation
/// solve: at fixed tensions, the rates' [`Linearization`]; the rates' change with the log
/// tension z_j = ln(tau_j / tau_j(0)) of each tendon with friction; the relative tension
/// rates (turning) and their derivatives. Refilled in place by [`linearize_into`], which
/// keeps every buffer's capacity (with the scratch of its last evaluation), so that a
/// linearization used again allocates nothing.
#[derive(Debug)]
pub(crate) struct FrictionLinearization {
    /// The rates and their derivatives in the strains and the rotation, tensions fixed.
    pub lin: Linearization,
    /// d(v', u')/dz_j, one per tendon of [`slipping`] (0 for those not loading here).
    pub d_log_tension: Vec<Vector6<f64>>,
    /// tau_j' / tau_j = w_j mu_j kappa_j (1/m), one per tendon of [`slipping`].
    pub turning: Vec<f64>,
    /// kappa_j = |t_j'|, the turning rate of the path (1/m), one per tendon of
    /// [`slipping`] (0 for those not loading here).
    pub kappa: Vec<f64>,
    /// d(turning_j)/d(v, u, phi), as a row of 9.
    pub d_turning: Vec<SMatrix<f64, 1, 9>>,
    /// d(turning_j)/dz_l, row-major k x k.
    pub d_turning_log_tension: Vec<f64>,
    /// Scratch of the evaluation: eq. 13 assembled at the point, the slips loading it, their
    /// gradients dg_i/dx and their columns dPhi/dz_i.
    point: Option<Point>,
    slips: Vec<Slip>,
    gradients: Vec<Vector6<f64>>,
    columns: Vec<Vector6<f64>>,
    /// Each slip's q^_i^T dq_i/d(v, u) at fixed rates, for dg_i and d(turning_i).
    explicit: Vec<SMatrix<f64, 1, 6>>,
    /// The lanes' response to one set of loads ([`linearize_lanes_into`] evaluates no
    /// scalar scratch), which [`FrictionLinearization::load_response`] returns for the same
    /// loads while it is `current` (not after another evaluation).
    lane_response: Option<LaneResponse>,
}

impl Default for FrictionLinearization {
    /// An empty linearization (zero rates, no tendons), to be filled by [`linearize_into`].
    fn default() -> Self {
        FrictionLinearization {
            lin: Linearization {
                rates: Vector6::zeros(),
                d_strains: Matrix6::zeros(),
                d_rotation: Matrix6x3::zeros(),
            },
            d_log_tension: Vec::new(),
            turning: Vec::new(),
            kappa: Vec::new(),
            d_turning: Vec::new(),
            d_turning_log_tension: Vec::new(),
            point: None,
            slips: Vec::new(),
            gradients: Vec::new(),
            columns: Vec::new(),
            explicit: Vec::new(),
            lane_response: None,
        }
    }
}

/// [`FrictionLinearization`] at a site for the state (R, v, u), the tendons of `slipping`
/// at the tensions the model holds for them here (module docs, "Linearization" in
/// docs/friction.md), each with its friction multiplier from `multipliers` if given (else
/// its motion's sign); without `derivatives` only the rates and the turning rates (the
/// derivative fields zero or empty), for residuals.
///
/// # Errors
/// As [`rates`].
#[cfg(test)]
pub(crate) fn linearize(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    slipping: &[usize],
    multipliers: Option<&[f64]>,
    derivatives: bool,
) -> Result<FrictionLinearization> {
    let mut out = FrictionLinearization::default();
    linearize_into(
        model,
        site,
        segment_end,
        state,
        slipping,
        multipliers,
        derivatives,
        &mut out,
    )?;
    Ok(out)
}

/// [`linearize`] into `out`, whose buffers are cleared and refilled (their capacity kept):
/// the same arithmetic, without allocating once `out` has held an evaluation of as many
/// tendons. On an error `out` holds no valid linearization.
///
/// # Errors
/// As [`rates`].
///
/// On x86-64 with AVX2 and FMA (checked at run time) compiled for them, eq. 13's assembly,
/// the tangential loads and the derivative columns inlined: the same operations in the same
/// order (Rust does not fuse a product and a sum into an FMA), so the same bits.
#[allow(clippy::too_many_arguments)]
pub(crate) fn linearize_into(
    model: &Model,
    site: &Site,
    segment_end: f64,
    state: (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    slipping: &[usize],
    multipliers: Option<&[f64]>,
    derivatives: bool,
    out: &mut FrictionLinearization,
) -> Result<()> {
    avx2_fma!(linearize_into_kernel(
        model,
        site,
        segment_end,
        state,
        slipping,
        multipliers,
        derivatives,
        out
    ))
}

/// [`linearize_into`]'s operations.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn linearize_into_kernel(
    model: &Model,
    site: &Site,
    segment_end: f64,
    (R, v, u): (&Matrix3<f64>, &Vector3<f64>, &Vector3<f64>),
    slipping: &[usize],
    multipliers: Option<&[f64]>,
    derivatives: bool,
    out: &mut FrictionLinearization,
) -> Result<()> {
    if let Some(kept) = &mut out.lane_response {
        kept.current = false;
    }
    // Eq. 13 assembled in the point this linearization kept (in place, not moved).
    let point = match &mut out.point {
        Some(point) => {
            point.refill(model, site, segment_end, (R, v, u))?;
            point
        }
        None => out.point.insert(Point::new(model, site, segment_end, (R, v, u))?),
    };
    let point = &*point;
    let x = solve(
        model,
        point,
        site,
        segment_end,
        (v, u),
        slipping,
        multipliers,
        &mut out.slips,
    )?;
    let slips = &out.slips;
    let k = slipping.len();
    let kappa = &mut out.kappa;
    kappa.clear();
    kappa.resize(k, 0.0);
    for sl in slips {
        kappa[sl.slot] = path_turning(sl);
    }
    let turning = &mut out.turning;
    turning.clear();
    turning.resize(k, 0.0);
    for sl in slips {
        turning[sl.slot] = relative(sl);
    }
    out.d_log_tension.clear();
    out.d_turning.clear();
    out.d_turning_log_tension.clear();
    if !derivatives {
        out.lin = Linearization {
            rates: x,
            d_strains: Matrix6::zeros(),
            d_rotation: Matrix6x3::zeros(),
        };
        return Ok(());
    }
    // dPhi/d(v, u, phi) at fixed x: eq. 13's dF plus the tangential loads' change,
    // sum_i (g_i de_i + e_i dg_i|x); then the columns dPhi/dz_i = (q_i, r_i x q_i) + e_i g_i.
    let dFt = point.derivative(model, site, segment_end, (v, u), &x.transpose())?;
    // Kept as rows (direction c of (v, u, phi) in row c), the layout M^-1 is applied in.
    let mut rows = dFt;
    let columns = &mut out.columns;
    columns.clear();
    columns.resize(slips.len(), Vector6::<f64>::zeros());
    let explicits = &mut out.explicit;
    explicits.clear();
    explicits.resize(slips.len(), SMatrix::<f64, 1, 6>::zeros());
    for ((sl, column), kept) in slips.iter().zip(columns.iter_mut()).zip(explicits.iter_mut()) {
        let tp = &sl.tp;
        let P = Matrix3::identity() - tp.t * tp.t.transpose();
        // dt/dv = P / |p| (0 on a Kirchhoff rod: t sees the strain v*), dt/du = -P r^ / |p|
        let dt_du = -P * tp.inv_speed * crate::so3::hat(&tp.r);
        let dt_dv = if tp.inextensible {
            Matrix3::zeros()
        } else {
            P * tp.inv_speed
        };
        let QQ = tp.normal_derivative(&Vector3::new(x[0], x[1], x[2]), &Vector3::new(x[3], x[4], x[5]), u);
        let explicit = sl.q_hat.transpose() * QQ; // 1 x 6
        *kept = explicit;
        let dg = explicit * sl.signed_mu;
        for c in 0..6 {
            let dt = if c < 3 {
                dt_dv.column(c).into_owned()
            } else {
                dt_du.column(c - 3).into_owned()
            };
            let de_top = dt * sl.g;
            let de_bottom = tp.r.cross(&dt) * sl.g;
            for r in 0..3 {
                rows[(c, r)] += de_top[r] + sl.e[r] * dg[c];
                rows[(c, r + 3)] += de_bottom[r] + sl.e[r + 3] * dg[c];
            }
        }
        let m = tp.r.cross(&sl.q);
        *column = Vector6::new(sl.q[0], sl.q[1], sl.q[2], m[0], m[1], m[2]) + sl.e * sl.g;
    }
    // dx = -J^-1 dPhi with J = M + sum_i e_i (dg_i/dx)^T, by Woodbury on M's factor:
    // J^-1 B = M^-1 B - Y S^-1 G^T M^-1 B, Y = [y_i], G = [dg_i/dx], S = I + G^T Y.
    let m_count = slips.len();
    let gradients = &mut out.gradients;
    gradients.clear();
    gradients.extend(slips.iter().map(Slip::gradient));
    // S, S^-1, a copy of S to factor and a column: on the stack for up to 3 tendons here.
    let square = m_count * m_count;
    let mut stack = [0.0; 30];
    let mut heap = Vec::new();
    let buffer: &mut [f64] = if 3 * square + m_count <= stack.len() {
        &mut stack[..3 * square + m_count]
    } else {
        heap.resize(3 * square + m_count, 0.0);
        &mut heap
    };
    let (schur, rest) = buffer.split_at_mut(square);
    let (inverse, rest) = rest.split_at_mut(square);
    let (a, column) = rest.split_at_mut(square);
    for (j, gj) in gradients.iter().enumerate() {
        for (l, sl) in slips.iter().enumerate() {
            schur[j * m_count + l] = f64::from(u8::from(j == l)) + gj.dot(&sl.y);
        }
    }
    // S^-1 once, column by column (S is m x m for the m tendons with friction here).
    for l in 0..m_count {
        a.copy_from_slice(schur);
        column.fill(0.0);
        column[l] = 1.0;
        if !crate::dense::solve_dense(a, column, m_count) {
            return Err(breakdown(site.s));
        }
        for (j, c) in column.iter().enumerate() {
            inverse[j * m_count + l] = *c;
        }
    }
    let solve_j = |b: &Vector6<f64>| -> Option<Vector6<f64>> {
        let mut row = b.transpose();
        point.solve_rows(&mut row).then(|| {
            let mut column = row.transpose();
            woodbury(slips, gradients, inverse, &mut column);
            column
        })
    };
    // The 9 columns of dPhi/d(v, u, phi) through M^-1 at once.
    if !point.solve_rows(&mut rows) {
        return Err(breakdown(site.s));
    }
    let mut dx = SMatrix::<f64, 6, 9>::zeros();
    for c in 0..9 {
        let mut column = rows.row(c).transpose();
        woodbury(slips, gradients, inverse, &mut column);
        dx.set_column(c, &-column);
    }
    let d_log_tension = &mut out.d_log_tension;
    d_log_tension.resize(k, Vector6::zeros());
    for (sl, column) in slips.iter().zip(columns.iter()) {
        d_log_tension[sl.slot] = -solve_j(column).ok_or_else(|| breakdown(site.s))?;
    }
    // turning_j = w_j mu_j |q_j| / tau_j: d = (w_j mu_j / tau_j) q^_j . (dq_j|x + k P W dx).
    let d_turning = &mut out.d_turning;
    d_turning.resize(k, SMatrix::<f64, 1, 9>::zeros());
    let d_turning_log_tension = &mut out.d_turning_log_tension;
    d_turning_log_tension.resize(k * k, 0.0);
    for (sl, explicit) in slips.iter().zip(out.explicit.iter()) {
        let tp = &sl.tp;
        // w mu / tau = w mu inv_speed / k
        let factor = sl.signed_mu * tp.inv_speed / tp.k;
        let mut row = SMatrix::<f64, 1, 9>::zeros();
        for c in 0..9 {
            let through_rates = sl.q_hat.dot(&sl.normal_change(&dx.column(c).into_owned()));
            let direct = if c < 6 { explicit[c] } else { 0.0 };
            row[c] = factor * (direct + through_rates);
        }
        d_turning[sl.slot] = row;
        for l in 0..k {
            d_turning_log_tension[sl.slot * k + l] = factor * sl.q_hat.dot(&sl.normal_change(&d_log_tension[l]));
        }
    }
    out.lin = Linearization {
        rates: x,
        d_strains: Matrix6::from_fn(|i, c| dx[(i, c)]),
        d_rotation: Matrix6x3::from_fn(|i, c| dx[(i, 6 + c)]),
    };
    Ok(())
}

/// J^-1 applied to `mb` = M^-1 b in place: `mb` minus Y S^-1 G^T `mb` (Woodbury, module docs
/// and [`linearize_into`]), Y the slips' y_i, G their gradients dg_i/dx, `inverse` S^-1 row
/// major. Each w_j = sum_l (S^-1)_jl (g_l . mb) is summed from -0.0 in ascending l, as
/// `Iterator::sum` sums (so with one slip it is the one term, which is computed alone); the
/// products g_l . mb of the unchanged `mb`, once per slip.
#[inline(always)]
fn woodbury(slips: &[Slip], gradients: &[Vector6<f64>], inverse: &[f64], mb: &mut Vector6<f64>) {
    if let ([sl], [g], [s]) = (slips, gradients, inverse) {
        let w = s * g.dot(mb);
        *mb -= sl.y * w;
        return;
    }
    let b = *mb;
    let count = slips.len();
    for (j, sl) in slips.iter().enumerate() {
        let mut w = -0.0;
        for (l, g) in gradients.iter().enumerate() {
            w += inverse[j * count + l] * g.dot(&b);
        }
        *mb -= sl.y * w;
    }
}

#[cfg(test)]
mod tests {
    use super::response::{woodbury_one, woodbury_rows};
    use super::*;
    use crate::cases;
    use crate::model::tendon::Friction;
    use crate::so3;
    use nalgebra::U1;

    /// Case H with friction on its helical tendon and a straight one, at a bent, twisted
    /// state with a generic rotation.
    fn setup() -> (Robot, Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
        let mut robot = cases::case_h();
        robot.tendons[4].friction = Some(Friction::pull(0.3));
        robot.tendons[0].set_tension(1.5);
        robot.tendons[0].friction = Some(Friction {
            coefficient: 0.2,
            motion: crate::model::tendon::Motion::Release,
        });
        let R = so3::exp(&Vector3::new(0.3, -0.7, 0.4));
        (robot, R, Vector3::new(0.01, -0.02, 0.98), Vector3::new(4.0, 9.0, -3.0))
    }

    /// The one-slip Woodbury rows of the load response ([`woodbury_one`]) are nalgebra's
    /// 1 x 1 LU solve ([`woodbury_rows`]) bit for bit: case H with friction on its helix
    /// alone, at the bent state of [`setup`], on six loads made from its rotation.
    #[test]
    fn one_slip_load_response_is_the_lu_solve_bit_for_bit() {
        let (mut robot, R, v, u) = setup();
        robot.tendons[0].friction = None;
        let model = Model::new(&robot);
        let slipping = slipping(&robot);
        let site = model.site(0.07);
        let lin = linearize(&model, &site, robot.length(), (&R, &v, &u), &slipping, None, true).unwrap();
        assert_eq!(lin.slips.len(), 1);
        let loads = SMatrix::<f64, 6, 6>::from_fn(|i, j| (R[(i % 3, j % 3)] + 0.1 * (i + 2 * j) as f64) * 1e-3);
        let (mut one, mut lu) = (loads, loads);
        assert!(woodbury_one(&lin.slips[0], &mut one));
        assert!(woodbury_rows(U1, &lin.slips, &mut lu));
        let bits = |m: &SMatrix<f64, 6, 6>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&lu));
        // The correction is there (not a copy of the loads).
        assert_ne!(bits(&one), bits(&loads));
    }

    #[test]
    fn linearization_matches_central_differences() {
        let (robot, R, v, u) = setup();
        check(&robot, &R, &v, &u);
    }

    /// One tendon with friction at the point: its tangential load in closed form
    /// (`model/tangential.rs`), the linearization the same implicit-function one.
    #[test]
    fn linearization_with_one_tendon_matches_central_differences() {
        let (mut robot, R, v, u) = setup();
        robot.tendons[0].friction = None;
        check(&robot, &R, &v, &u);
    }

    #[test]
    fn linearization_on_a_kirchhoff_rod_matches_central_differences() {
        let (mut robot, R, v, u) = setup();
        robot.rod_model = crate::model::robot::RodModel::Kirchhoff;
        // v is the force coordinate v* + D^-1 n_b here: a compressive 2e-2 EA of force
        check(&robot, &R, &v, &u);
    }

    /// The friction linearization at (R, v, u) against Richardson-extrapolated central
    /// differences of the rates and turning rates.
    fn check(robot: &Robot, R: &Matrix3<f64>, v: &Vector3<f64>, u: &Vector3<f64>) {
        let (R, v, u) = (*R, *v, *u);
        let model = Model::new(robot);
        let slipping = slipping(robot);
        let site = model.site(0.07);
        let end = robot.length();
        let lin = linearize(&model, &site, end, (&R, &v, &u), &slipping, None, true).unwrap();
        let eval = |model: &Model, R: &Matrix3<f64>, v: &Vector3<f64>, u: &Vector3<f64>| {
            let mut turning = vec![0.0; robot.tendons.len()];
            let x = rates(model, &site, end, (R, v, u), None, &mut turning).unwrap();
            let t: Vec<f64> = slipping.iter().map(|&i| turning[i]).collect();
            (x, t)
        };
        let (x, t) = eval(&model, &R, &v, &u);
        // The same solve: bitwise
        assert_eq!(x, lin.lin.rates);
        assert_eq!(t, lin.turning);
        // 3e-5: the rates carry rounding of about 1e-16 E A |v - v*| / (E I) ~ 5e-11 (u'), so
        // a central difference has ~1e-6 of noise there; truncation h^2 is below it.
        let h = 3e-5;
        // Richardson-extrapolated central differences (error O(h^4)) of (rates, turning)
        // along a step `at(t)` of the inputs.
        let difference = |at: &dyn Fn(f64) -> (Vector6<f64>, Vec<f64>)| {
            let central = |h: f64| {
                let ((xp, tp), (xm, tm)) = (at(h), at(-h));
                let t: Vec<f64> = tp.iter().zip(&tm).map(|(a, b)| (a - b) / (2.0 * h)).collect();
                ((xp - xm) / (2.0 * h), t)
            };
            let ((x1, t1), (x2, t2)) = (central(h), central(h / 2.0));
            let t: Vec<f64> = t1.iter().zip(&t2).map(|(a, b)| (4.0 * b - a) / 3.0).collect();
            ((x2 * 4.0 - x1) / 3.0, t)
        };
        for c in 0..9 {
            let at = |step: f64| {
                let mut d = [0.0; 9];
                d[c] = step;
                let dv = Vector3::new(d[0], d[1], d[2]);
                let du = Vector3::new(d[3], d[4], d[5]);
                let dphi = Vector3::new(d[6], d[7], d[8]);
                eval(&model, &(R * so3::exp(&dphi)), &(v + dv), &(u + du))
            };
            let (fd, fd_turning) = difference(&at);
            let exact = if c < 6 {
                lin.lin.d_strains.column(c).into_owned()
            } else {
                lin.lin.d_rotation.column(c - 6).into_owned()
            };
            // 1e-6 relative (to at least 10 for the rates, whose strain derivatives are 10..1e3,
            // and 1 for the turning rates, ~1e3 per unit strain):
            // the rounding noise of the differences above
            assert!(
                (fd - exact).norm() <= 1e-6 * exact.norm().max(10.0),
                "column {c}: {fd} vs {exact}"
            );
            for (j, fd) in fd_turning.iter().enumerate() {
                let exact = lin.d_turning[j][c];
                assert!(
                    (fd - exact).abs() <= 1e-6 * fd.abs().max(1.0),
                    "turning {j} column {c}: {fd} vs {exact}"
                );
            }
        }
        for (l, &i) in slipping.iter().enumerate() {
            let at = |step: f64| {
                let mut m = model.clone();
                m.tensions[i] *= step.exp();
                eval(&m, &R, &v, &u)
            };
            let (fd, fd_turning) = difference(&at);
            // 1e-6 relative: as above
            assert!((fd - lin.d_log_tension[l]).norm() <= 1e-6 * fd.norm().max(1.0), "z {l}");
            for (j, fd) in fd_turning.iter().enumerate() {
                let exact = lin.d_turning_log_tension[j * slipping.len() + l];
                assert!(
                    (fd - exact).abs() <= 1e-6 * fd.abs().max(1.0),
                    "turning {j} z {l}: {fd} vs {exact}"
                );
            }
        }
    }

    /// The response to body loads (the mass of the linearized dynamics with friction)
    /// against Richardson-extrapolated central differences of the rates and turning rates
    /// in a distributed force and moment added at the point: eq. 13's right-hand side gains
    /// -R^T f_e and -R^T l_e, so the rows (-R^T e_k, 0) and (0, -R^T e_k) are the loads whose
    /// responses are the rates' and turning rates' derivatives in f_e and l_e.
    #[test]
    fn load_response_matches_central_differences_in_a_distributed_load() {
        let (robot, R, v, u) = setup();
        let model = Model::new(&robot);
        let slipping = slipping(&robot);
        let site = model.site(0.07);
        let end = robot.length();
        let lin = linearize(&model, &site, end, (&R, &v, &u), &slipping, None, false).unwrap();
        let mut loads = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..3 {
            let row: Vector3<f64> = -R.transpose().column(k);
            for (j, value) in row.iter().enumerate() {
                loads[(k, j)] = *value;
                loads[(3 + k, 3 + j)] = *value;
            }
        }
        let mut turning = vec![SMatrix::<f64, 1, 6>::zeros(); slipping.len()];
        assert!(lin.load_response(&mut loads, &mut turning));
        let eval = |site: &Site| {
            let mut t = vec![0.0; robot.tendons.len()];
            let x = rates(&model, site, end, (&R, &v, &u), None, &mut t).unwrap();
            (x, slipping.iter().map(|&i| t[i]).collect::<Vec<f64>>())
        };
        // 0.05 N/m and N m/m: the rates are linear in the loads but for the tangential loads'
        // dependence on them (Richardson's O(h^4) takes care of that), and a longer step
        // keeps the rates' rounding (about 5e-11 in u') from dominating the small responses.
        let h = 0.05;
        for c in 0..6 {
            let at = |step: f64| {
                let mut moved = site;
                let mut d = Vector3::zeros();
                d[c % 3] = step;
                if c < 3 {
                    moved.f_e += d;
                } else {
                    moved.l_e += d;
                }
                eval(&moved)
            };
            let central = |h: f64| {
                let ((xp, tp), (xm, tm)) = (at(h), at(-h));
                let t: Vec<f64> = tp.iter().zip(&tm).map(|(a, b)| (a - b) / (2.0 * h)).collect();
                ((xp - xm) / (2.0 * h), t)
            };
            let ((x1, t1), (x2, t2)) = (central(h), central(h / 2.0));
            let fd = (x2 * 4.0 - x1) / 3.0;
            let exact: Vector6<f64> = loads.row(c).transpose();
            // 1e-7 relative and 5e-9 absolute: the rates' rounding (about 5e-11 in u') over the
            // step leaves about 1e-9 of noise in the differences (measured 1e-10 to 1e-9), and a
            // force's u' response is only about 1e-4.
            assert!(
                (fd - exact).norm() <= 1e-7 * exact.norm() + 5e-9,
                "load {c}: {fd} vs {exact}"
            );
            for (j, (a, b)) in t1.iter().zip(&t2).enumerate() {
                let fd = (4.0 * b - a) / 3.0;
                let exact = turning[j][c];
                // 1e-7 of the largest turning response of that tendon (measured 1e-12 absolute).
                let scale = turning[j].iter().fold(0.0f64, |m, t| m.max(t.abs()));
                assert!(
                    (fd - exact).abs() <= 1e-7 * scale,
                    "turning {j} load {c}: {fd} vs {exact}"
                );
            }
        }
    }
}
