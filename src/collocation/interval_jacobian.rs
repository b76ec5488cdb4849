//! The interval block's Jacobian ([`interval_jacobian`], re-exported by `residual`): the
//! interval rows of the Hermite-Simpson scheme (`residual` module docs) and their exact
//! 12 x 24 Jacobian by the chain rule through the scheme, from eq. 13's analytic
//! linearization at the interval's end node and midpoint ([`crate::model::linearize`]),
//! the points' F and dF ([`super::point`]) and the end columns ([`super::ends`]). Compiled a
//! second time for AVX2 and FMA, chosen at run time (the same operations in the same order).
#![allow(non_snake_case)]

use super::residual::{
    Block, EndColumns, IntervalFactors, IntervalSites, IntervalTensions, PointFrame, PointLinearization,
    derivative_rows, end_points, rhs_linearized_inline, scale_rows,
};
use super::unknowns::{P, THETA, U, V};
use crate::error::Result;
use crate::model::equations::Model;
use crate::model::linearize::{self, Linearization, linearize_keeping};
use crate::simd::avx2_fma;
use crate::simd::lanes::F4;
use crate::solution::State;
use nalgebra::{SMatrix, Vector3, Vector6};

/// Interval rows, their exact Jacobian with respect to the scaled unknowns of both nodes
/// (12 x 24, written row by row into `jac`), and the linearization of eq. 13 at node b (the
/// next interval's `start`, shared as in [`interval`](super::residual::interval)), by the chain rule through the
/// Hermite-Simpson formula: pointwise linearizations instead of differentiating the whole
/// block.
///
/// The p columns are constant (F does not depend on p), so the chain rule runs on the other
/// 18 columns, ordered (theta, v, u) of node a then of node b; of those, y_0 depends on
/// v_a, u_a only and y_1 on theta_a, theta_b, v_b, u_b, so F_0 and F_1 need no products
/// and only the midpoint needs a 12 x 9 by 9 x 18 one.
///
/// On x86-64 with AVX2 and FMA (checked at run time) the block's own arithmetic (the chain
/// rule, its 12 x 9 by 9 x 18 product and the writes) is compiled for them: the same
/// operations in the same order (Rust does not fuse a product and a sum into an FMA), so the
/// same bits in wider registers (docs/benchmarks.md, "A batch row").
///
/// # Errors
/// A model breakdown at a node or at the midpoint.
#[allow(clippy::too_many_arguments)]
pub fn interval_jacobian(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start: Option<&Linearization>,
    jac: &mut [f64],
    tensions: Option<IntervalTensions>,
) -> Result<(Block<f64>, Linearization)> {
    let mut end = Linearization::zeros();
    interval_jacobian_into(model, sites, segment_end, (a, b), start, jac, tensions, &mut end).map(|r| (r, end))
}

/// [`interval_jacobian`] with the end node's linearization written into `end` instead of
/// returned, so that the system's assembly keeps it where the next interval reads it (no
/// copies of it per interval).
///
/// # Errors
/// As [`interval_jacobian`].
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_jacobian_into(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    start: Option<&Linearization>,
    jac: &mut [f64],
    tensions: Option<IntervalTensions>,
    end: &mut Linearization,
) -> Result<Block<f64>> {
    interval_jacobian_tensions(model, sites, segment_end, (a, b), start, jac, tensions, false, end).map(|(r, _)| r)
}

/// [`interval_jacobian`] whose residual is bit for bit [`interval`](super::residual::interval)'s, with the rates at
/// node a: F_1's position row is R_b v_b, as [`interval`](super::residual::interval) forms it, not R_a exp(theta_1) v_b
/// (which differ by rounding; no derivative reads that row). For a Jacobian evaluated in
/// place of a residual evaluation (Newton's trial point, `System::jacobian_rates`);
/// `tensions` as in [`interval_jacobian`], `end` as in [`interval_jacobian_into`].
///
/// # Errors
/// As [`interval_jacobian`].
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_jacobian_as_residual(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    start: Option<&Linearization>,
    jac: &mut [f64],
    tensions: Option<IntervalTensions>,
    end: &mut Linearization,
) -> Result<(Block<f64>, Vector6<f64>)> {
    interval_jacobian_tensions(model, sites, segment_end, (a, b), start, jac, tensions, true, end)
}

/// [`interval_jacobian_as_residual`] or, with `as_residual` false, [`interval_jacobian_into`]
/// (returning the rates at node a too): one AVX2 copy of the kernel for both.
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_jacobian_tensions(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    start: Option<&Linearization>,
    jac: &mut [f64],
    tensions: Option<IntervalTensions>,
    as_residual: bool,
    end: &mut Linearization,
) -> Result<(Block<f64>, Vector6<f64>)> {
    avx2_fma!(interval_jacobian_kernel(
        model,
        sites,
        segment_end,
        a,
        b,
        start,
        jac,
        None,
        tensions,
        as_residual,
        end
    ))
}

/// [`interval_jacobian`] that keeps eq. 13's factored matrix at its points in `kept` (the
/// start's only when it evaluates it, not given `start`): the Jacobian at an answer whose
/// verdict comes from the linearized dynamics, whose mass solves with them
/// (`collocation/dynamics.rs`); `as_residual` as in [`interval_jacobian_as_residual`] (that
/// Jacobian evaluated by Newton in place of its last residual), with the rates at node a;
/// `end` as in [`interval_jacobian_into`].
///
/// # Errors
/// As [`interval_jacobian`].
#[allow(clippy::too_many_arguments)]
pub(super) fn interval_jacobian_keeping(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    (a, b): (&State, &State),
    start: Option<&Linearization>,
    jac: &mut [f64],
    kept: &mut IntervalFactors,
    as_residual: bool,
    end: &mut Linearization,
) -> Result<(Block<f64>, Vector6<f64>)> {
    avx2_fma!(interval_jacobian_kernel(
        model,
        sites,
        segment_end,
        a,
        b,
        start,
        jac,
        Some(kept),
        None,
        as_residual,
        end,
    ))
}

/// [`interval_jacobian`]'s operations; `kept` as in [`interval_jacobian_keeping`], `tensions`
/// as in [`interval_jacobian`] (one of the two at most: a point keeps its factors or forms
/// its tension rows), `as_residual` as in [`interval_jacobian_as_residual`]; writes the end
/// node's linearization into `end` and returns the residual and the rates at node a.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn interval_jacobian_kernel(
    model: &Model,
    sites: &IntervalSites,
    segment_end: f64,
    a: &State,
    b: &State,
    start: Option<&Linearization>,
    jac: &mut [f64],
    mut kept: Option<&mut IntervalFactors>,
    mut tensions: Option<IntervalTensions>,
    as_residual: bool,
    end: &mut Linearization,
) -> Result<(Block<f64>, Vector6<f64>)> {
    let length = model.robot.length();
    let h = sites.end.s - sites.start.s;
    let (y0, y1) = end_points(a, b);
    let theta1: Vector3<f64> = y1.fixed_rows::<3>(THETA).into();
    let computed;
    let lin0 = match start {
        Some(l) => l,
        None => {
            let keep = kept.as_deref_mut().map(|k| &mut k.start);
            computed = match tensions.as_mut() {
                Some(t) => {
                    linearize::linearize_tensions(model, &sites.start, segment_end, (&a.R, &a.v, &a.u), t.start)?
                }
                None => linearize_keeping(model, &sites.start, segment_end, &a.R, &a.v, &a.u, keep)?,
            };
            &computed
        }
    };
    *end = match tensions.as_mut() {
        Some(t) => linearize::linearize_tensions_inline(
            model,
            &sites.end,
            segment_end,
            (&b.R, &b.v, &b.u),
            t.end,
            t.routing.map(|[end, _]| end),
        )?,
        None => {
            let keep = kept.as_deref_mut().map(|k| &mut k.end);
            linearize_keeping(model, &sites.end, segment_end, &b.R, &b.v, &b.u, keep)?
        }
    };
    let lin1: &Linearization = end;
    let frame1 = PointFrame::new(&a.R, &theta1);
    let p0 = rhs_linearized_inline(&sites.start, lin0, &a.R, &y0, &PointFrame::start(&a.R));
    let mut p1 = rhs_linearized_inline(&sites.end, lin1, &a.R, &y1, &frame1);
    if as_residual {
        // `end_rhs`'s position row (the midpoint reads only the theta, v and u rows).
        p1.f.fixed_rows_mut::<3>(P).copy_from(&(b.R * sites.end.strain(&b.v)));
    }
    let ym = (y0 + y1) * 0.5 + (p0.f - p1.f) * (h / 8.0);
    let frame_m = PointFrame::new(&a.R, &ym.fixed_rows::<3>(THETA).into());
    let (v_m, u_m): (Vector3<f64>, Vector3<f64>) = (ym.fixed_rows::<3>(V).into(), ym.fixed_rows::<3>(U).into());
    let lin_m = match tensions.as_mut() {
        Some(t) => {
            let routing = t.routing.map(|[_, mid]| mid);
            linearize::linearize_tensions_inline(
                model,
                &sites.mid,
                segment_end,
                (&frame_m.R, &v_m, &u_m),
                t.mid,
                routing,
            )?
        }
        None => {
            let keep = kept.map(|k| {
                k.mid_R = frame_m.R;
                &mut k.mid
            });
            linearize_keeping(model, &sites.mid, segment_end, &frame_m.R, &v_m, &u_m, keep)?
        }
    };
    let pm = rhs_linearized_inline(&sites.mid, &lin_m, &a.R, &ym, &frame_m);
    let residual = scale_rows(y1 - y0 - (p0.f + pm.f * 4.0 + p1.f) * (h / 6.0), length);

    let ends = EndColumns::new(&p0, &p1, &frame1, length);
    let dFm = midpoint_product(&pm, &ends.midpoint(h));
    ends.write(&dFm, h, length, jac);
    if let Some(t) = tensions {
        tension_rows(t, h, length, &lin_m, (sites.mid.inextensible, &frame_m));
    }
    Ok((residual, lin0.rates))
}

/// An interval's rows of the tension columns' right-hand sides into `t.columns`, from the
/// rates' derivatives at its fixed states in `t` (start node, end node, midpoint), its
/// length `h`, the midpoint's linearization `lin_m` and frame (with whether its rod is
/// inextensible): the tail of the interval kernel with `tensions`, shared with the lane
/// kernel of `interval_lanes` (the same operations, so the same bits).
#[inline(always)]
pub(super) fn tension_rows(
    t: IntervalTensions,
    h: f64,
    length: f64,
    lin_m: &Linearization,
    (inextensible, frame_m): (bool, &PointFrame),
) {
    // The chain rule of `interval_derivatives`: the midpoint's strains move by
    // dy_m = h/8 (dF_0 - dF_1) with each tension, which adds d(v', u')/d(v, u) dy_m
    // to its derivative at the fixed state.
    for ((dy, s), e) in t.dy_mid.iter_mut().zip(t.start.iter()).zip(t.end.iter()) {
        *dy = (s - e) * (h / 8.0);
    }
    for (d, dy) in t.mid.iter_mut().zip(t.dy_mid.iter()) {
        *d += lin_m.d_strains * dy;
    }
    let mid = (inextensible, &frame_m.R, &frame_m.Jri);
    // The right-hand sides' rows, weight h/6: the rows' derivatives (weight -h/6)
    // negated, bit for bit, written straight into the columns.
    let (columns, n, row) = (t.columns, t.n, t.row);
    derivative_rows(mid, h / 6.0, length, [t.start, t.end, t.mid, t.dy_mid], |i, b| {
        columns[i * n + row..i * n + row + b.len()].copy_from_slice(b.as_slice());
    });
}

/// The midpoint's F on the 18 columns: its (theta, v, u) columns of dF/dy times the
/// midpoint's columns `dYm`, plus dF/dphi on the theta_a columns. Each column's 12 rows are
/// three [`F4`]s, so the loops are wide in every build (the one-interval kernel's, the lane
/// kernel's and friction's AVX2 copies: written on scalars the lane kernel's build left them
/// scalar, 3.5 k instructions an interval against 1.4 k), with each entry's sum in the order
/// of nalgebra's product (the k = 0 term, then each further term added to it), so the same
/// bits.
#[inline(always)]
pub(super) fn midpoint_product(pm: &PointLinearization, dYm: &SMatrix<f64, 9, 18>) -> SMatrix<f64, 12, 18> {
    let load = |s: &[f64], i: usize| F4([s[i], s[i + 1], s[i + 2], s[i + 3]]);
    let (f_y, f_frame) = (pm.f_y.as_slice(), pm.f_frame.as_slice()); // column-major
    let mut dFm = SMatrix::<f64, 12, 18>::zeros();
    for (j, (col, dy)) in dFm
        .as_mut_slice()
        .chunks_exact_mut(12)
        .zip(dYm.as_slice().chunks_exact(9))
        .enumerate()
    {
        let mut c = [load(f_y, 36) * dy[0], load(f_y, 40) * dy[0], load(f_y, 44) * dy[0]];
        for (k, &dy_k) in dy.iter().enumerate().skip(1) {
            for (r, c) in c.iter_mut().enumerate() {
                *c += load(f_y, 12 * (3 + k) + 4 * r) * dy_k;
            }
        }
        if j < 3 {
            for (r, c) in c.iter_mut().enumerate() {
                *c += load(f_frame, 12 * j + 4 * r);
            }
        }
        for (r, c) in c.iter().enumerate() {
            col[4 * r..4 * r + 4].copy_from_slice(&c.0);
        }
    }
    dFm
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Mesh, guess::rigid_estimate};

    /// The AVX2 build of `interval_jacobian` gives the baseline build's bits (residual,
    /// 12 x 24 block and the end node's linearization) on every interval of the prototype
    /// with four tendons pulled: the same operations in the same order (on a processor
    /// without AVX2 both are the baseline).
    #[test]
    fn interval_jacobian_gives_the_baseline_bits() {
        let robot = crate::collocation::test_support::pulled_prototype();
        let model = Model::new(&robot);
        let mesh = Mesh::uniform(&robot, 16).unwrap();
        let x = rigid_estimate(&model, &mesh.nodes);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut compared = 0;
        for k in 0..mesh.nodes.len() - 1 {
            if mesh.is_jump(k) {
                continue;
            }
            let (s0, s1) = (x[k].s, x[k + 1].s);
            let sites = IntervalSites {
                start: model.site(s0),
                mid: model.site(0.5 * (s0 + s1)),
                end: model.site(s1),
            };
            let seg = mesh.nodes[k].segment_end;
            let (mut fast, mut baseline) = ([0.0; 12 * 24], [0.0; 12 * 24]);
            let (r_fast, l_fast) =
                interval_jacobian(&model, &sites, seg, &x[k], &x[k + 1], None, &mut fast, None).unwrap();
            let mut l_base = Linearization::zeros();
            let (r_base, _) = interval_jacobian_kernel(
                &model,
                &sites,
                seg,
                &x[k],
                &x[k + 1],
                None,
                &mut baseline,
                None,
                None,
                false,
                &mut l_base,
            )
            .unwrap();
            assert!(fast.iter().all(|v| v.is_finite()));
            assert_eq!(bits(&fast), bits(&baseline), "interval {k}");
            assert_eq!(bits(r_fast.as_slice()), bits(r_base.as_slice()), "interval {k}");
            assert_eq!(bits(l_fast.d_strains.as_slice()), bits(l_base.d_strains.as_slice()));
            assert_eq!(bits(l_fast.d_rotation.as_slice()), bits(l_base.d_rotation.as_slice()));
            assert_eq!(bits(l_fast.rates.as_slice()), bits(l_base.rates.as_slice()));
            compared += 1;
        }
        assert_eq!(compared, 16);
    }
}
