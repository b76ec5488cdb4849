//! Stuck links in a load history (docs/friction.md section 8): which slips stick on a
//! link and what their multipliers divide by, the central difference of the rows in a
//! stuck multiplier, and the per-point multipliers' shares of a stuck link ("ord23").

use super::interval::{IntervalLinearization, Link};
use super::profile::Profile;
use crate::collocation::residual::Block;
use crate::model::equations::Site;
use crate::model::friction::FrictionLinearization;
use nalgebra::Vector3;

/// The step of the central difference in a stuck slip's multiplier: the rows are smooth in
/// w, and a step of 1e-6 leaves a truncation of 1e-12 and rounding of 1e-10 of the rows'
/// scale.
pub(super) const MULTIPLIER_STEP: f64 = 1e-6;

/// The slips that stick on link k of `profile` (their rows the stick rows, their
/// multipliers w = (z_b - z_a) / C), with the capacities C > 0 their multipliers divide by
/// ([`Profile::stuck_scale`]; a slip without one has w = 0 whatever its log tensions).
pub(super) fn stuck_slips<'p>(profile: &'p Profile, k: usize) -> impl Iterator<Item = (usize, f64)> + 'p {
    (0..profile.count())
        .filter(move |&j| profile.on_link(j, k) && profile.sticks(j, k))
        .filter_map(move |j| profile.stuck_scale(j, k).filter(|c| *c > 0.0).map(|c| (j, c)))
}

/// Adds to a stuck link's backbone rows' derivatives in the log tensions (`out`, `count`
/// slips) their change through slip j's multiplier w = (z_b - z_a) / C (`(j, C)`): the
/// rows' derivative in w by a central difference of the rows `plus` and `minus` at
/// w_j +- [`MULTIPLIER_STEP`], divided by -C in z_a's column and +C in z_b's.
pub(super) fn add_multiplier_columns(
    out: &mut IntervalLinearization,
    count: usize,
    (j, capacity): (usize, f64),
    plus: &Block<f64>,
    minus: &Block<f64>,
) {
    let d_rows = (plus - minus) / (2.0 * MULTIPLIER_STEP);
    for r in 0..12 {
        out.rows_z[(r, j)] -= d_rows[r] / capacity;
        out.rows_z[(r, count + j)] += d_rows[r] / capacity;
    }
}

/// The per-point multipliers' shares of stuck slip j on `link` from eq. 13 with friction
/// at its start, midpoint and end (each its site, strains, linearization and log tension):
/// at each point w*_P = zeta'(P) / (mu kappa_P), the stuck material's log-tension slope
/// ([`Profile::stuck_slope`]) over the slip's turning, and sigma_P = w*_P / their Simpson
/// mean, with C_sigma = h/6 mu (sigma_a kappa_a + 4 sigma_m kappa_m + sigma_b kappa_b). A
/// stuck link's multiplier at P is then W sigma_P with W = (z_b - z_a) / C_sigma, so the
/// scheme's log-tension slope at P is the stuck profile's to O(h^4) once the shares settle
/// (docs/friction.md section 8, "ord23"). None where the link has no material interpolant
/// ([`super::grip::Grip::points`]: the history's own mesh) or a share is not finite (a
/// mean of 0, a point without turning): the link keeps the constant multiplier.
#[allow(clippy::type_complexity)]
pub(super) fn pointwise(
    link: &Link,
    j: usize,
    points: [(&Site, (&Vector3<f64>, &Vector3<f64>), &FrictionLinearization, f64); 3],
) -> Option<[f64; 4]> {
    let Link {
        profile,
        length,
        k,
        sites,
        ..
    } = *link;
    // With two or more tendons with friction each stuck slope moves with the others'
    // tangential loads too (cross gains of the own one's size, docs/friction.md section 8,
    // "Opposite tendons"), which the lag does not correct: not done (ord23).
    if profile.count() > 1 {
        return None;
    }
    let grip = profile.grips.as_ref()?.get(j)?;
    let &[d_a, lambda_m, d_m, d_b] = grip.points.get(k)?;
    let material = [(grip.reference[k], d_a), (lambda_m, d_m), (grip.reference[k + 1], d_b)];
    let mu = profile.coefficient(j);
    let mut star = [0.0; 3];
    for (w, ((site, strains, lin, z), material)) in star.iter_mut().zip(points.into_iter().zip(material)) {
        let load = profile.tension(j, z) * lin.turning[j];
        let slope = profile.stuck_slope(j, site, strains, &lin.lin.rates, load, material, length);
        *w = slope / (mu * lin.kappa[j]);
    }
    let mean = (star[0] + 4.0 * star[1] + star[2]) / 6.0;
    let sigma = star.map(|w| w / mean);
    let kappa = points.map(|p| p.2.kappa[j]);
    let h = sites.end.s - sites.start.s;
    let capacity = h / 6.0 * mu * (sigma[0] * kappa[0] + 4.0 * sigma[1] * kappa[1] + sigma[2] * kappa[2]);
    (sigma.iter().all(|s| s.is_finite()) && capacity > 0.0).then_some([sigma[0], sigma[1], sigma[2], capacity])
}

/// Per-point multipliers as slices.
pub(super) fn slices(p: &[Vec<f64>; 3]) -> [&[f64]; 3] {
    [&p[0], &p[1], &p[2]]
}
