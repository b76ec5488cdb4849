//! The collocation of an interval with friction (the log tensions on the mesh are the
//! [`Profile`]): the 12 rows of the backbone and one capstan row
//! per tendon with friction, with their exact Jacobian (docs/friction.md, "Collocation").
//!
//! Each tendon j with friction carries the log tension z_j = ln(tau_j / tau_j(0)) at the
//! nodes of its span, z_j = 0 at the base. On an interval, z_j obeys
//! z_j' = kappa~_j(y) = w_j mu_j kappa_j, collocated by the same Hermite-Simpson formula as
//! the backbone state y:
//!
//! ```text
//! z_m = (z_a + z_b) / 2 + h/8 (kappa~_a - kappa~_b),  psi = z_b - z_a - h/6 (kappa~_a + 4 kappa~_m + kappa~_b)
//! ```
//!
//! where kappa~ at the midpoint is evaluated at (y_m, z_m): y and z are one collocation
//! state, so the scheme keeps order 4. The backbone rows see z through the tensions of eq.
//! 13 with friction at the nodes and the midpoint ([`crate::model::friction::linearize`]).
#![allow(non_snake_case)]

use super::super::residual::{
    Block, EndColumns, IntervalSites, PointFrame, PointLinearization, end_points, midpoint_product, rhs_from_rates,
    rhs_linearized_inline, scale_rows,
};
use super::super::unknowns::THETA;
use super::profile::LinkScratch;
pub(crate) use super::profile::Profile;
use super::stuck_links::{MULTIPLIER_STEP, add_multiplier_columns, pointwise, slices, stuck_slips};
use crate::error::Result;
use crate::model::equations::Site;
use crate::model::friction::FrictionLinearization;
use crate::simd::{avx2_fma, product, refill};
use crate::so3;
use crate::solution::State;
use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};

/// The linearization of an interval with friction: its backbone rows, capstan rows and
/// their derivatives.
#[derive(Debug)]
pub(crate) struct IntervalLinearization {
    /// The 12 backbone rows (scaled).
    pub(crate) residual: Block<f64>,
    /// psi_j, one per slip (0 for slips not on this link): the capstan row, or in a
    /// history the stick row where the slip sticks.
    pub(crate) psi: Vec<f64>,
    /// C_j = h/6 mu_j (kappa_a + 4 kappa_m + kappa_b): the most the log tension of slip j
    /// can change across the link (the capstan row's increment at |w| = 1).
    pub(crate) capacity: Vec<f64>,
    /// Per slip stuck on the link with the material's interpolant given ([`Grip::points`]),
    /// its per-point multipliers' shares (sigma_a, sigma_m, sigma_b) and their capacity
    /// C_sigma = h/6 mu (sigma_a kappa_a + 4 sigma_m kappa_m + sigma_b kappa_b), which the
    /// link's next evaluation takes ([`pointwise`]); None elsewhere.
    pub(crate) pointwise: Vec<Option<[f64; 4]>>,
    /// In a history, slip j's tension at node b if its material there had not moved
    /// ([`Profile::stuck_tension`]); NaN in full slip.
    pub(crate) stuck_tension: Vec<f64>,
    /// d(backbone rows)/dz: 12 x 2k, columns z_a of every slip, then z_b.
    pub(crate) rows_z: DMatrix<f64>,
    /// d psi / d(node unknowns): k x 24, the block's column layout.
    pub(crate) psi_x: DMatrix<f64>,
    /// d psi / dz: k x 2k, columns as `rows_z`.
    pub(crate) psi_z: DMatrix<f64>,
    /// Whether the derivatives were evaluated (else the three blocks above hold no values of
    /// this evaluation: they keep their shape, and nothing reads them).
    pub(crate) derivatives: bool,
}

impl IntervalLinearization {
    /// An evaluation with no rows yet, whose buffers a link's evaluation fills.
    pub(super) fn empty() -> Self {
        IntervalLinearization {
            residual: Block::zeros(),
            psi: Vec::new(),
            capacity: Vec::new(),
            pointwise: Vec::new(),
            stuck_tension: Vec::new(),
            rows_z: DMatrix::zeros(0, 0),
            psi_x: DMatrix::zeros(0, 0),
            psi_z: DMatrix::zeros(0, 0),
            derivatives: false,
        }
    }
}

/// Collocation of link k with friction: residual rows and capstan rows, and when `jac` is
/// given, the backbone rows' Jacobian in the scaled node unknowns there (12 x 24, row major)
/// and the border's derivatives in the return value.
///
/// # Errors
/// A model breakdown at a node or the midpoint.
#[allow(clippy::too_many_arguments)]
pub(crate) fn interval(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    jac: Option<&mut [f64]>,
) -> Result<IntervalLinearization> {
    let w = profile.multipliers(k);
    let points = w.as_deref().map(|w| profile.point_multipliers(k, w));
    let derivatives = jac.is_some();
    let (Some(w), true) = (points.as_ref(), derivatives) else {
        return interval_at(
            profile,
            length,
            k,
            sites,
            segment_end,
            a,
            b,
            points.as_ref().map(slices),
            jac,
        );
    };
    // A stuck link's multiplier w = (z_b - z_a) / C moves its backbone rows with its log
    // tensions ([`add_multiplier_columns`]). The moved rows are evaluated first, so that the
    // link's own evaluation is the one the profile keeps at its nodes (for the next link's
    // start and the order-6 rows).
    let count = profile.count();
    let mut moved_rows = Vec::new();
    for (j, capacity) in stuck_slips(profile, k) {
        let sigma = profile.sigma(j, k);
        let moved = |d: f64| -> Result<Block<f64>> {
            let mut w = w.clone();
            for (p, w) in w.iter_mut().enumerate() {
                w[j] += sigma.map_or(d, |sigma| d * sigma[p]);
            }
            let lin = interval_at(profile, length, k, sites, segment_end, a, b, Some(slices(&w)), None)?;
            let rows = lin.residual;
            profile.give_link(lin);
            Ok(rows)
        };
        moved_rows.push((j, capacity, moved(MULTIPLIER_STEP)?, moved(-MULTIPLIER_STEP)?));
    }
    let mut out = interval_at(profile, length, k, sites, segment_end, a, b, Some(slices(w)), jac)?;
    for (j, capacity, plus, minus) in &moved_rows {
        add_multiplier_columns(&mut out, count, (*j, *capacity), plus, minus);
    }
    Ok(out)
}

/// [`interval`] with the slips' multipliers `w` at the link's start, midpoint and end (None
/// in full slip: the motions' signs), the backbone rows' derivatives at fixed `w`.
///
/// On x86-64 with AVX2 and FMA (checked at run time) the link's own arithmetic (the chain
/// rule with the log tensions' columns, the capstan rows and the writes) is compiled for
/// them, as [`super::super::residual::interval_jacobian`] is: the same operations in the
/// same order (Rust does not fuse a product and a sum into an FMA), so the same bits in
/// wider registers.
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_at(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    w: Option<[&[f64]; 3]>,
    jac: Option<&mut [f64]>,
) -> Result<IntervalLinearization> {
    avx2_fma!(interval_at_kernel(profile, length, k, sites, segment_end, a, b, w, jac))
}

/// [`interval_at`]'s operations: the link's nodes, [`front`], its midpoint and [`back`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn interval_at_kernel(
    profile: &Profile,
    length: f64,
    k: usize,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    w: Option<[&[f64]; 3]>,
    jac: Option<&mut [f64]>,
) -> Result<IntervalLinearization> {
    // The link's buffers, the profile's spare ones (given back at the end).
    let mut scratch = profile.take_scratch();
    node_tensions(profile, k, &mut scratch);
    let derivatives = jac.is_some();
    let [wa, wm, wb] = w.map_or([None; 3], |w| w.map(Some));
    let la = profile.start_point(k, &sites.start, segment_end, a, &scratch.za, wa, derivatives)?;
    let lb = profile.point(
        &sites.end,
        segment_end,
        &b.R,
        (&b.v, &b.u),
        &scratch.zb,
        wb,
        derivatives,
    )?;
    let link = Link {
        profile,
        length,
        k,
        sites,
        segment_end,
        a,
        b,
        w,
    };
    let mut ends = None;
    let front = front(&link, (&la, &lb), (derivatives, true), &mut scratch, &mut ends);
    let lm = profile.point(
        &sites.mid,
        segment_end,
        &front.Rm,
        (&front.vm, &front.um),
        &scratch.zm,
        wm,
        derivatives,
    )?;
    let out = back(&link, &front, [&la, &lm, &lb], jac, &mut scratch);
    profile.keep_point(k + 1, segment_end, b, &scratch.zb, wb, derivatives, lb);
    profile.give(la);
    profile.give(lm);
    profile.give_scratch(scratch);
    Ok(out)
}

/// The log tensions at link k's nodes into `scratch`.
#[inline(always)]
pub(super) fn node_tensions(profile: &Profile, k: usize, scratch: &mut LinkScratch) {
    refill(&mut scratch.za, profile.z.len(), |j| profile.z[j][k]);
    refill(&mut scratch.zb, profile.z.len(), |j| profile.z[j][k + 1]);
}

/// One link's inputs: link k of `profile` between the states `a` and `b`, the slips at
/// multipliers `w` (at its start, midpoint and end).
pub(super) struct Link<'l, 'p> {
    pub(super) profile: &'l Profile<'p>,
    pub(super) length: f64,
    pub(super) k: usize,
    pub(super) sites: &'l IntervalSites,
    pub(super) segment_end: f64,
    pub(super) a: &'l State,
    pub(super) b: &'l State,
    pub(super) w: Option<[&'l [f64]; 3]>,
}

/// The linearizations of F at a link's two nodes (with derivatives only): [`front`] writes
/// them into a slot of its caller's, so that they are not moved with the [`Front`].
pub(super) type Ends = Option<(PointLinearization, PointLinearization)>;

/// A link's evaluation up to its midpoint's state (its log tensions in the scratch's
/// `zm`): what [`back`] takes with the midpoint's linearization.
pub(super) struct Front<'e> {
    y0: Block<f64>,
    y1: Block<f64>,
    ends: Option<&'e (PointLinearization, PointLinearization)>,
    frame1: Option<PointFrame>,
    frame_m: Option<PointFrame>,
    f0: Block<f64>,
    f1: Block<f64>,
    ym: Block<f64>,
    Em: Matrix3<f64>,
    /// The midpoint's rotation and strains, where eq. 13 with friction is evaluated next.
    pub(super) Rm: Matrix3<f64>,
    pub(super) vm: Vector3<f64>,
    pub(super) um: Vector3<f64>,
}

/// A link's evaluation from eq. 13 with friction at its nodes (`la`, `lb`, at the log
/// tensions in `scratch`) to its midpoint's state, the ends' linearizations into `slot`
/// (None, as given, without derivatives); with `keep`, keeps the nodes' rates in the
/// profile ([`Profile::keep_node`]).
#[inline(always)]
pub(super) fn front<'e>(
    link: &Link,
    (la, lb): (&FrictionLinearization, &FrictionLinearization),
    (derivatives, keep): (bool, bool),
    scratch: &mut LinkScratch,
    slot: &'e mut Ends,
) -> Front<'e> {
    let Link {
        profile,
        k,
        sites,
        segment_end,
        a,
        b,
        w,
        ..
    } = *link;
    let count = profile.count();
    let h = sites.end.s - sites.start.s;
    let LinkScratch { za, zb, zm, .. } = scratch;
    let [wa, _, wb] = w.map_or([None; 3], |w| w.map(Some));
    if keep {
        profile.keep_node(k, segment_end, a, (za, wa), la);
        profile.keep_node(k + 1, segment_end, b, (zb, wb), lb);
    }
    let (y0, y1) = end_points(a, b);
    let theta1: Vector3<f64> = y1.fixed_rows::<3>(THETA).into();
    // F at a point from its rates; with derivatives also its linearization (a residual
    // needs only the value, the same arithmetic as the linearization's).
    let value = |site: &Site, lin: &FrictionLinearization, y: &Block<f64>| {
        let theta: Vector3<f64> = y.fixed_rows::<3>(THETA).into();
        rhs_from_rates(site, &(a.R * so3::exp(&theta)), y, &lin.lin.rates)
    };
    // The slot written only with derivatives (an assignment of None would copy it whole).
    // Here and below `if` and `match`, not `bool::then` or `Option::map` with a closure,
    // which stayed calls compiled apart from the AVX2 kernels this is inlined into.
    let frame1 = if derivatives {
        let frame1 = PointFrame::new(&a.R, &theta1);
        *slot = Some((
            rhs_linearized_inline(&sites.start, &la.lin, &a.R, &y0, &PointFrame::start(&a.R)),
            rhs_linearized_inline(&sites.end, &lb.lin, &a.R, &y1, &frame1),
        ));
        Some(frame1)
    } else {
        None
    };
    let ends = slot.as_ref();
    let (f0, f1) = match ends {
        Some((p0, p1)) => (p0.f, p1.f),
        None => (value(&sites.start, la, &y0), value(&sites.end, lb, &y1)),
    };
    let ym = (y0 + y1) * 0.5 + (f0 - f1) * (h / 8.0);
    refill(zm, count, |j| {
        0.5 * (za[j] + zb[j]) + h / 8.0 * (la.turning[j] - lb.turning[j])
    });
    let theta_m: Vector3<f64> = ym.fixed_rows::<3>(THETA).into();
    let (vm, um): (Vector3<f64>, Vector3<f64>) = (ym.fixed_rows::<3>(6).into(), ym.fixed_rows::<3>(9).into());
    // exp(theta_m) and R_m once; with derivatives the midpoint's whole frame (exp, J_r and
    // J_r^-1 from one evaluation, the same bits as `so3::exp`), which the chain rule below
    // takes too.
    let (Em, Rm, frame_m) = if derivatives {
        let frame = PointFrame::new(&a.R, &theta_m);
        (frame.E, frame.R, Some(frame))
    } else {
        let Em = so3::exp(&theta_m);
        (Em, a.R * Em, None)
    };
    Front {
        y0,
        y1,
        ends,
        frame1,
        frame_m,
        f0,
        f1,
        ym,
        Em,
        Rm,
        vm,
        um,
    }
}

/// A link's 12 backbone rows (scaled) from its [`Front`] and F at its midpoint `fm`
/// (`h` its length, `length` the rod's).
#[inline(always)]
fn rows_with(front: &Front, fm: &Block<f64>, h: f64, length: f64) -> Block<f64> {
    scale_rows(
        front.y1 - front.y0 - (front.f0 + fm * 4.0 + front.f1) * (h / 6.0),
        length,
    )
}

/// A link's 12 backbone rows (scaled) from its [`Front`] and eq. 13 with friction at its
/// midpoint `lm` evaluated without derivatives: the rows [`back`] gives then.
#[inline(always)]
pub(super) fn value_rows(link: &Link, front: &Front, lm: &FrictionLinearization) -> Block<f64> {
    let sites = link.sites;
    let fm = rhs_from_rates(&sites.mid, &front.Rm, &front.ym, &lm.lin.rates);
    rows_with(front, &fm, sites.end.s - sites.start.s, link.length)
}

/// The rest of a link's evaluation ([`interval_at`]) from its [`Front`] and eq. 13 with
/// friction at its start, midpoint and end (`l`); the profile keeps the start's and the
/// midpoint's responses when it keeps them (not the end's linearization: the caller does).
#[inline(always)]
pub(super) fn back(
    link: &Link,
    front: &Front,
    l: [&FrictionLinearization; 3],
    jac: Option<&mut [f64]>,
    scratch: &mut LinkScratch,
) -> IntervalLinearization {
    let Link {
        profile,
        length,
        k,
        sites,
        segment_end,
        a,
        b,
        w,
    } = *link;
    let [la, lm, lb] = l;
    // The small values copied, the ends' linearizations and the frames read in place.
    let ym = front.ym;
    let (Em, Rm, vm, um) = (front.Em, front.Rm, front.vm, front.um);
    let (ends, frame1, frame_m) = (front.ends, front.frame1.as_ref(), front.frame_m.as_ref());
    let count = profile.count();
    let h = sites.end.s - sites.start.s;
    let derivatives = jac.is_some();
    let LinkScratch {
        za,
        zb,
        zm,
        on,
        stuck,
        dzm,
        dturn_m,
        dzm_l,
        ..
    } = scratch;
    let (pm, residual) = match frame_m {
        Some(frame) => {
            let pm = rhs_linearized_inline(&sites.mid, &lm.lin, &a.R, &ym, frame);
            let residual = rows_with(front, &pm.f, h, length);
            (Some(pm), residual)
        }
        None => (None, value_rows(link, front, lm)),
    };
    refill(on, count, |j| profile.on_link(j, k));
    // In a history, the stuck material's tension at node b, for the stick/slip choice.
    refill(stuck, count, |j| {
        (profile.grips.is_some() && on[j]).then(|| profile.stuck_tension(j, k + 1, &sites.end, b, length))
    });
    // The link's evaluation in the buffers of one the profile no longer keeps.
    let mut out = profile.take_link();
    out.residual = residual;
    refill(&mut out.capacity, count, |j| {
        h / 6.0 * profile.coefficient(j) * (la.kappa[j] + 4.0 * lm.kappa[j] + lb.kappa[j])
    });
    refill(&mut out.pointwise, count, |j| {
        (on[j] && profile.sticks(j, k))
            .then(|| {
                let points = [
                    (&sites.start, (&a.v, &a.u), la, za[j]),
                    (&sites.mid, (&vm, &um), lm, zm[j]),
                    (&sites.end, (&b.v, &b.u), lb, zb[j]),
                ];
                pointwise(link, j, points)
            })
            .flatten()
    });
    refill(&mut out.psi, count, |j| {
        if on[j] {
            zb[j] - za[j] - h / 6.0 * (la.turning[j] + 4.0 * lm.turning[j] + lb.turning[j])
        } else {
            0.0
        }
    });
    // In a history, a stuck link's row is its stick row z_b - zeta_b, zeta_b the stuck
    // material's log tension (section 8); a sliding link keeps its capstan row at w = -1
    // or +1.
    for j in 0..count {
        if let (Some((tension, _, _)), true) = (stuck[j], profile.sticks(j, k)) {
            out.psi[j] = zb[j] - (tension / profile.base[j]).ln();
        }
    }
    refill(&mut out.stuck_tension, count, |j| stuck[j].map_or(f64::NAN, |t| t.0));
    // The blocks keep their shape (sized once per recycled evaluation); without
    // derivatives they are not written, and nothing reads them then.
    for (block, shape) in [
        (&mut out.rows_z, (12, 2 * count)),
        (&mut out.psi_x, (count, 24)),
        (&mut out.psi_z, (count, 2 * count)),
    ] {
        if block.shape() != shape {
            *block = DMatrix::zeros(shape.0, shape.1);
        } else if derivatives {
            block.fill(0.0);
        }
    }
    out.derivatives = derivatives;
    let (Some(jac), Some((p0, p1)), Some(pm), Some(frame1), Some(frame_m)) = (jac, ends, pm, frame1, frame_m) else {
        return out;
    };

    // The backbone rows: the chain rule of residual::interval_jacobian, with the midpoint's
    // log tensions z_m depending on the node states through kappa~_a, kappa~_b.
    let ends = EndColumns::new(p0, p1, frame1, length);
    let dYm = ends.midpoint(h);
    // d kappa~ / d(18 columns) at the nodes: (theta, v, u / L) of their own node.
    let node_turning = |l: &FrictionLinearization, j: usize, first: usize| {
        let mut row = SMatrix::<f64, 1, 18>::zeros();
        for c in 0..3 {
            row[first + c] = l.d_turning[j][6 + c];
            row[first + 3 + c] = l.d_turning[j][c];
            row[first + 6 + c] = l.d_turning[j][3 + c] / length;
        }
        row
    };
    refill(dzm, count, |j| {
        (node_turning(la, j, 0) - node_turning(lb, j, 9)) * (h / 8.0)
    });
    // F_m and kappa~_m in the midpoint's local coordinates (theta, v, u) and the frame.
    let Jr_m = frame_m.Jr;
    let turning_y = |j: usize| {
        let mut row = SMatrix::<f64, 1, 12>::zeros();
        let d_phi = lm.d_turning[j].fixed_columns::<3>(6).into_owned();
        row.fixed_columns_mut::<3>(3).copy_from(&product(&d_phi, &Jr_m));
        row.fixed_columns_mut::<3>(6)
            .copy_from(&lm.d_turning[j].fixed_columns::<3>(0));
        row.fixed_columns_mut::<3>(9)
            .copy_from(&lm.d_turning[j].fixed_columns::<3>(3));
        (row, product(&d_phi, &Em.transpose()))
    };
    // The frictionless midpoint's product (the same sums in the same order as nalgebra's).
    let mut dFm = midpoint_product(&pm, &dYm);
    let rates_z = |l: &FrictionLinearization, j: usize| {
        let mut col = Block::<f64>::zeros();
        col.fixed_rows_mut::<6>(6).copy_from(&l.d_log_tension[j]);
        col
    };
    for (j, dz) in dzm.iter().enumerate() {
        dFm += product(&rates_z(lm, j), dz);
    }
    ends.write(&dFm, h, length, jac);

    // d kappa~_m / d(18 columns), including z_m's dependence.
    dturn_m.clear();
    for j in 0..count {
        let (row_y, row_frame) = turning_y(j);
        let mut row = product(&row_y.fixed_columns::<9>(3), &dYm);
        for c in 0..3 {
            row[c] += row_frame[c];
        }
        for (l, dz) in dzm.iter().enumerate() {
            row += dz * lm.d_turning_log_tension[j * count + l];
        }
        dturn_m.push(row);
    }
    // The capstan rows in the block's columns (p columns are 0).
    for j in (0..count).filter(|&j| on[j]) {
        let row = (node_turning(la, j, 0) + dturn_m[j] * 4.0 + node_turning(lb, j, 9)) * (-h / 6.0);
        for c in 0..18 {
            let column = if c < 9 { 3 + c } else { 6 + c };
            out.psi_x[(j, column)] = row[c];
        }
    }

    // The log-tension columns: z_a of slip l (column l), z_b (column count + l).
    for l in 0..count {
        for (side, sign, lin) in [(0, 1.0, &la), (1, -1.0, &lb)] {
            let dF_end = rates_z(lin, l); // dF_a or dF_b / dz
            // y_m moves by +-h/8 dF_end; z_m by delta/2 +- h/8 d kappa~_end / dz.
            let dym = dF_end * (sign * h / 8.0);
            refill(dzm_l, count, |j| {
                let own = if j == l { 0.5 } else { 0.0 };
                own + sign * h / 8.0 * lin.d_turning_log_tension[j * count + l]
            });
            let mut dFm_z = product(&pm.f_y, &dym);
            for (j, d) in dzm_l.iter().enumerate() {
                dFm_z += rates_z(lm, j) * *d;
            }
            let column = scale_rows(-(dF_end + dFm_z * 4.0) * (h / 6.0), length);
            out.rows_z.set_column(side * count + l, &column);
            for j in (0..count).filter(|&j| on[j]) {
                let (row_y, _) = turning_y(j);
                let mut dturn = product(&row_y, &dym)[0];
                for (m, d) in dzm_l.iter().enumerate() {
                    dturn += lm.d_turning_log_tension[j * count + m] * d;
                }
                let own_end = lin.d_turning_log_tension[j * count + l];
                let delta = if j == l { -sign } else { 0.0 };
                out.psi_z[(j, side * count + l)] = delta - h / 6.0 * (own_end + 4.0 * dturn);
            }
        }
    }
    // Stick rows: d(z_b - zeta_b) in z_b and in node b's v and (scaled) u.
    for j in (0..count).filter(|&j| profile.sticks(j, k)) {
        let Some((tension, d_v, d_u)) = stuck[j] else {
            continue;
        };
        out.psi_x.row_mut(j).fill(0.0);
        out.psi_z.row_mut(j).fill(0.0);
        for i in 0..3 {
            out.psi_x[(j, 18 + i)] = -d_v[i] / tension;
            out.psi_x[(j, 21 + i)] = -d_u[i] / (tension * length);
        }
        out.psi_z[(j, count + j)] = 1.0;
    }
    // For the verdict's mass at the same state, when the profile keeps it (the Jacobian at
    // the answer).
    let [wa, wm, wb] = w.map_or([None; 3], |w| w.map(Some));
    profile.keep_response(2 * k, &sites.start, segment_end, (&a.R, &a.v, &a.u), (za, wa), la);
    profile.keep_response(2 * k + 1, &sites.mid, segment_end, (&Rm, &vm, &um), (zm, wm), lm);
    profile.keep_end_response(k, &sites.end, segment_end, (&b.R, &b.v, &b.u), (zb, wb), lb);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases;
    use crate::collocation::friction::interval_order6;
    use crate::collocation::residual::IntervalSites;
    use crate::collocation::residual::QuarterSites;
    use crate::mesh::Mesh;
    use crate::model::equations::Model;
    use crate::model::tendon::{Friction, Motion};

    /// The interval's backbone rows and capstan rows against central differences in the
    /// scaled node unknowns and the log tensions, on case H with friction on its helix and
    /// (released) on tendon 1, at a bent state.
    #[test]
    fn interval_blocks_match_central_differences() {
        let mut robot = cases::case_h();
        robot.tendons[4].friction = Some(Friction::pull(0.3));
        robot.tendons[0].set_tension(1.0);
        robot.tendons[0].friction = Some(Friction {
            coefficient: 0.2,
            motion: Motion::Release,
        });
        let solution = crate::solve(&robot, &crate::collocation::Options::fixed(8)).unwrap();
        let model = Model::new(&robot);
        let mesh = Mesh::from_points(&robot, &solution.nodes.iter().map(|n| n.s).collect::<Vec<_>>()).unwrap();
        let mut profile = Profile::new(&model, &mesh);
        let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
        let k = 3;
        for (j, z) in profile.z.iter_mut().enumerate() {
            for (n, value) in z.iter_mut().enumerate() {
                *value = -0.03 * n as f64 * (j as f64 + 1.0);
            }
        }
        let site = |s: f64| model.site(s);
        let (s0, s1) = (x[k].s, x[k + 1].s);
        let sites = IntervalSites {
            start: site(s0),
            mid: site(0.5 * (s0 + s1)),
            end: site(s1),
        };
        let length = robot.length();
        let seg = mesh.nodes[k].segment_end;
        let mut jac = [0.0; 12 * 24];
        let lin = interval(&profile, length, k, &sites, seg, &x[k], &x[k + 1], Some(&mut jac)).unwrap();
        let count = profile.count();
        // One scaled unknown of node a (column < 12) or b moved by h.
        let moved = |column: usize, h: f64| {
            let (mut a, mut b) = (x[k], x[k + 1]);
            let node = if column < 12 { &mut a } else { &mut b };
            let (part, i) = ((column % 12) / 3, column % 3);
            let mut d = Vector3::zeros();
            d[i] = h;
            match part {
                0 => node.p += d * length,
                1 => node.R *= so3::exp(&d),
                2 => node.v += d,
                _ => node.u += d / length,
            }
            interval(&profile, length, k, &sites, seg, &a, &b, None).unwrap()
        };
        // Richardson-extrapolated central differences (error O(h^4)): the strains enter the
        // rates through E A / (E I) ~ 1e7, so plain differences are too coarse at any h.
        let h = 1e-5;
        let extrapolate = |f: &dyn Fn(f64) -> IntervalLinearization, h: f64| -> (Vec<f64>, Vec<f64>) {
            let central = |h: f64| {
                let (p, m) = (f(h), f(-h));
                let rows: Vec<f64> = (0..12).map(|r| (p.residual[r] - m.residual[r]) / (2.0 * h)).collect();
                let psi: Vec<f64> = (0..p.psi.len()).map(|j| (p.psi[j] - m.psi[j]) / (2.0 * h)).collect();
                (rows, psi)
            };
            let ((r1, p1), (r2, p2)) = (central(h), central(h / 2.0));
            let mix = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (4.0 * y - x) / 3.0).collect();
            (mix(&r1, &r2), mix(&p1, &p2))
        };
        for column in 0..24 {
            // The shear/extension strains v move the internal force by E A dv (1e5 N per
            // unit): a step of 1e-8 keeps that below 1e-3 N.
            let step = if (6..9).contains(&(column % 12)) { 1e-8 } else { h };
            let (rows, psi) = extrapolate(&|h| moved(column, h), step);
            for (row, &fd) in rows.iter().enumerate() {
                let exact = jac[row * 24 + column];
                // 1e-6 relative to at least 1: rows are O(1) scaled; the extrapolated
                // difference carries ~1e-9 of rounding and h^4 of truncation
                assert!(
                    (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                    "row {row}, column {column}: {fd} vs {exact}"
                );
            }
            for (j, &fd) in psi.iter().enumerate() {
                let exact = lin.psi_x[(j, column)];
                assert!(
                    (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                    "psi {j}, column {column}: {fd} vs {exact}"
                );
            }
        }
        for side in 0..2 {
            for l in 0..count {
                let at = |h: f64| {
                    let mut p = profile.clone_z();
                    p.z[l][k + side] += h;
                    interval(&p, length, k, &sites, seg, &x[k], &x[k + 1], None).unwrap()
                };
                let (rows, psi) = extrapolate(&at, h);
                for (row, &fd) in rows.iter().enumerate() {
                    let exact = lin.rows_z[(row, side * count + l)];
                    assert!(
                        (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                        "row {row}, z {side} {l}: {fd} vs {exact}"
                    );
                }
                for (j, &fd) in psi.iter().enumerate() {
                    let exact = lin.psi_z[(j, side * count + l)];
                    assert!(
                        (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                        "psi {j}, z {side} {l}: {fd} vs {exact}"
                    );
                }
            }
        }
    }

    /// The order-6 rows at a node take eq. 13 with friction from the last link evaluation
    /// there only when its inputs are the same: after a residual pass they are bitwise the
    /// rows of a profile that kept nothing, and after the log tensions moved they are those
    /// of the moved profile, not the kept values (case H with friction on its helix).
    #[test]
    fn order6_rows_reuse_node_evaluations_only_at_the_same_inputs() {
        let mut robot = cases::case_h();
        robot.tendons[4].friction = Some(Friction::pull(0.3));
        let solution = crate::solve(&robot, &crate::collocation::Options::fixed(8)).unwrap();
        let model = Model::new(&robot);
        let mesh = Mesh::from_points(&robot, &solution.nodes.iter().map(|n| n.s).collect::<Vec<_>>()).unwrap();
        let mut profile = Profile::new(&model, &mesh);
        let x: Vec<State> = solution.nodes.iter().map(|n| n.state()).collect();
        for z in &mut profile.z {
            for (n, value) in z.iter_mut().enumerate() {
                *value = -0.02 * n as f64;
            }
        }
        let length = robot.length();
        let k = 3;
        let (s0, s1) = (x[k].s, x[k + 1].s);
        let h = s1 - s0;
        let sites = IntervalSites {
            start: model.site(s0),
            mid: model.site(0.5 * (s0 + s1)),
            end: model.site(s1),
        };
        let quarters = QuarterSites {
            quarter: model.site(s0 + 0.25 * h),
            three_quarters: model.site(s0 + 0.75 * h),
        };
        let seg = mesh.nodes[k].segment_end;
        let order6 = |p: &Profile| interval_order6(p, length, k, &sites, &quarters, seg, &x[k], &x[k + 1]).unwrap();
        // The residual pass keeps both nodes' evaluations.
        interval(&profile, length, k, &sites, seg, &x[k], &x[k + 1], None).unwrap();
        let (kept, kept_psi, kept_a, kept_b) = order6(&profile);
        let (fresh, fresh_psi, fresh_a, fresh_b) = order6(&profile.clone_z());
        // Bit for bit: the kept values are the evaluation at the same inputs.
        assert_eq!((kept, kept_psi, kept_a, kept_b), (fresh, fresh_psi, fresh_a, fresh_b));
        // Moved log tensions at node b: its kept evaluation no longer applies.
        for z in &mut profile.z {
            z[k + 1] -= 0.05;
        }
        let (moved, moved_psi, _, moved_b) = order6(&profile);
        let (exact, exact_psi, _, exact_b) = order6(&profile.clone_z());
        assert_eq!((moved, moved_psi, moved_b), (exact, exact_psi, exact_b));
        // And the move matters: the kept node-b rates would have given other rows.
        assert_ne!(moved_b, kept_b);
    }
}
