//! The carried material between the nodes of the history's mesh (docs/friction.md section
//! 8, "The material's kinks", "ord23"): per smooth piece, the polynomial through the
//! nearest points and its slope.

use super::Kink;

/// The carried material at `at` (docs/friction.md section 8, "The material's kinks"): the
/// polynomial through the `points` points nearest to `at` of the smooth piece that holds
/// it, evaluated there. A piece runs between two successive `kinks` (or a kink and an end
/// of the span); its points are the nodes of `s` (increasing, within a tendon's span, with
/// the material `values`) inside it and the kinks that bound it, with the piece's own
/// lambda there, so no stencil straddles a kink and `at` always lies between a stencil's
/// first and last point. `points` is 6 for the quintic the step is solved with (O(h^6) where
/// the material is smooth), 8 for the degree-7 polynomial that estimates its error (at most
/// 8 are read); a piece with fewer points gives the polynomial through all of them. At a node it is the value
/// there exactly, so the material handed back at the history's nodes is the last step's;
/// at a kink that is not a node, the value after it.
pub(super) fn lagrange(s: &[f64], values: &[f64], kinks: &[Kink], at: f64, points: usize) -> f64 {
    if let Some(k) = s.iter().position(|&x| x == at) {
        return values[k];
    }
    let (stencil, points) = stencil(s, values, kinks, at, points);
    let stencil = &stencil[..points];
    stencil
        .iter()
        .enumerate()
        .map(|(a, &(sa, value))| {
            let weight: f64 = stencil
                .iter()
                .enumerate()
                .filter(|&(b, _)| b != a)
                .map(|(_, &(sb, _))| (at - sb) / (sa - sb))
                .product();
            weight * value
        })
        .sum()
}

/// The stencil [`lagrange`] and [`lagrange_slopes`] read: the (up to) `points` (at most 8)
/// points (s, lambda) of the smooth piece of the carried material that holds `within`
/// nearest to it (half of them at or before `within` where the piece allows), in order,
/// found by bisection and copied once; with their count. A piece runs between two
/// successive kinks (or a kink and an end of the span): its points are the nodes strictly
/// between them and the kinks, the one below with the lambda after it, the one above with
/// the lambda before it.
fn stencil(s: &[f64], values: &[f64], kinks: &[Kink], within: f64, points: usize) -> ([(f64, f64); 8], usize) {
    let below = kinks.iter().rfind(|k| k.0 <= within);
    let above = kinks.iter().find(|k| k.0 > within);
    let (lo, hi) = (
        below.map_or(f64::NEG_INFINITY, |k| k.0),
        above.map_or(f64::INFINITY, |k| k.0),
    );
    let nodes = s.len().min(values.len());
    let start = s[..nodes].partition_point(|&x| x <= lo);
    let count = s[..nodes].partition_point(|&x| x < hi).saturating_sub(start);
    let head = usize::from(below.is_some());
    let first_point = below.map_or((lo, 0.0), |&(e, _, after)| (e, after));
    let last_point = above.map_or((hi, 0.0), |&(e, before, _)| (e, before));
    let point = |p: usize| -> (f64, f64) {
        if p < head {
            first_point
        } else if p - head < count {
            (s[start + p - head], values[start + p - head])
        } else {
            last_point
        }
    };
    let n = head + count + usize::from(above.is_some());
    let points = points.min(n).min(8);
    let mut out = [(0.0, 0.0); 8];
    if points == 0 {
        return (out, 0);
    }
    let k = (0..n).rposition(|p| point(p).0 <= within).unwrap_or(0);
    let first = (k + 1).saturating_sub(points / 2).min(n - points);
    for (q, slot) in out.iter_mut().take(points).enumerate() {
        *slot = point(first + q);
    }
    (out, points)
}

/// The slopes (1/m) at each of `ats` of the quintic [`lagrange`] reads the carried
/// material with, on the smooth piece that holds `within` (a point of the same link: at a
/// kink the link's own side), through the six points of that piece nearest to `within`:
/// lambda' for the stuck links' per-point multipliers (docs/friction.md section 8,
/// "ord23"). The stencil is found once for all of `ats`, and each factor
/// `(at - s_b) / (s_a - s_b)` computed once per pair (a, b); each slope is the products
/// and sums of the formula below in its order, so the bits of the derivative evaluated
/// per point with the stencil found each time.
pub(super) fn lagrange_slopes<const N: usize>(
    s: &[f64],
    values: &[f64],
    kinks: &[Kink],
    ats: [f64; N],
    within: f64,
) -> [f64; N] {
    let (stencil, points) = stencil(s, values, kinks, within, 6);
    if points < 2 {
        return [0.0; N];
    }
    let stencil = &stencil[..points];
    ats.map(|at| {
        // factor[a][b] = (at - s_b) / (s_a - s_b).
        let mut factor = [[0.0; 6]; 6];
        for (a, row) in factor.iter_mut().enumerate().take(points) {
            for (b, f) in row.iter_mut().enumerate().take(points) {
                if b != a {
                    *f = (at - stencil[b].0) / (stencil[a].0 - stencil[b].0);
                }
            }
        }
        // d/dx of sum_a v_a prod_{b != a} (x - s_b) / (s_a - s_b).
        stencil
            .iter()
            .enumerate()
            .map(|(a, &(sa, value))| {
                let slope: f64 = (0..points)
                    .filter(|&c| c != a)
                    .map(|c| {
                        let rest: f64 = (0..points)
                            .filter(|&b| b != a && b != c)
                            .map(|b| factor[a][b])
                            .product();
                        rest / (sa - stencil[c].0)
                    })
                    .sum();
                slope * value
            })
            .sum()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The points (s, lambda) of the smooth piece of the carried material that holds `at`:
    /// the kink below it with the lambda after it, the nodes of `s` strictly between the
    /// kinks, and the kink above it with the lambda before it ([`lagrange`]'s piece, listed).
    fn piece(s: &[f64], values: &[f64], kinks: &[Kink], at: f64) -> Vec<(f64, f64)> {
        let below = kinks.iter().rfind(|k| k.0 <= at);
        let above = kinks.iter().find(|k| k.0 > at);
        let (lo, hi) = (
            below.map_or(f64::NEG_INFINITY, |k| k.0),
            above.map_or(f64::INFINITY, |k| k.0),
        );
        below
            .map(|&(e, _, after)| (e, after))
            .into_iter()
            .chain(
                s.iter()
                    .copied()
                    .zip(values.iter().copied())
                    .filter(|&(x, _)| x > lo && x < hi),
            )
            .chain(above.map(|&(e, before, _)| (e, before)))
            .collect()
    }

    /// The `points` points of a listed `piece` ([`piece`]) nearest to `at`, as [`lagrange`]
    /// picks its stencil: half of them at or before `at` where the piece allows; all of
    /// them in a piece with fewer.
    fn nearest(piece: &[(f64, f64)], at: f64, points: usize) -> &[(f64, f64)] {
        let n = piece.len();
        let points = points.min(n);
        let k = piece.iter().rposition(|p| p.0 <= at).unwrap_or(0);
        let first = (k + 1).saturating_sub(points / 2).min(n - points);
        &piece[first..first + points]
    }

    /// [`lagrange_slopes`] at one point as it was before (d97d819): the piece listed per
    /// call, the stencil taken from the list, each factor computed where the product takes it.
    fn slope_listed(s: &[f64], values: &[f64], kinks: &[Kink], at: f64, within: f64) -> f64 {
        let piece = piece(s, values, kinks, within);
        let stencil = nearest(&piece, within, 6);
        let points = stencil.len();
        if points < 2 {
            return 0.0;
        }
        stencil
            .iter()
            .enumerate()
            .map(|(a, &(sa, value))| {
                let slope: f64 = (0..points)
                    .filter(|&c| c != a)
                    .map(|c| {
                        let rest: f64 = (0..points)
                            .filter(|&b| b != a && b != c)
                            .map(|b| (at - stencil[b].0) / (sa - stencil[b].0))
                            .product();
                        rest / (sa - stencil[c].0)
                    })
                    .sum();
                slope * value
            })
            .sum()
    }

    /// [`lagrange`] as it was before it found the piece's nodes by bisection: the piece
    /// listed, then the stencil taken from the list.
    fn listed(s: &[f64], values: &[f64], kinks: &[Kink], at: f64, points: usize) -> f64 {
        if let Some(k) = s.iter().position(|&x| x == at) {
            return values[k];
        }
        let piece = piece(s, values, kinks, at);
        let stencil = nearest(&piece, at, points);
        stencil
            .iter()
            .enumerate()
            .map(|(a, &(sa, value))| {
                let weight: f64 = stencil
                    .iter()
                    .enumerate()
                    .filter(|&(b, _)| b != a)
                    .map(|(_, &(sb, _))| (at - sb) / (sa - sb))
                    .product();
                weight * value
            })
            .sum()
    }

    /// The material between the nodes is the listed piece's polynomial bit for bit: on a
    /// span of 33 nodes (a jump, i.e. a repeated node, among them) with no kink, one, two,
    /// a kink at a node and kinks near the ends, at points between and at the nodes and
    /// the kinks, through 6 and 8 points, more than a short piece has.
    #[test]
    fn the_material_is_the_listed_pieces_polynomial() {
        let mut s: Vec<f64> = (0..32).map(|k| 0.242 * (k as f64 / 31.0).powf(1.1)).collect();
        s.insert(12, s[12]);
        let values: Vec<f64> = s.iter().map(|x| 1.0 + 0.01 * (7.0 * x).sin() + 0.002 * x).collect();
        let kinks: [&[Kink]; 5] = [
            &[],
            &[(0.1003, 1.0011, 1.0013)],
            &[(0.05, 1.0, 1.001), (0.1703, 1.002, 1.0025)],
            &[(s[20], 1.0, 1.001)],
            &[(0.001, 1.0, 1.001), (0.2415, 1.002, 1.0025)],
        ];
        let mut at: Vec<f64> = s.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        at.extend(s.windows(2).map(|w| w[0] + 0.01 * (w[1] - w[0])));
        at.extend(&s);
        let mut compared = 0;
        for kinks in kinks {
            let mut at = at.clone();
            at.extend(kinks.iter().flat_map(|k| [k.0, k.0 - 1e-9, k.0 + 1e-9]));
            for &x in &at {
                for points in [6, 8] {
                    let (got, want) = (
                        lagrange(&s, &values, kinks, x, points),
                        listed(&s, &values, kinks, x, points),
                    );
                    assert_eq!(got.to_bits(), want.to_bits(), "{x} through {points} with {kinks:?}");
                    compared += 1;
                }
            }
        }
        // Values that are not the nodes' own (an interpolation, not a copy) are among them.
        let between = lagrange(&s, &values, &[], at[3], 6);
        assert!(values.iter().all(|v| *v != between));
        assert!(compared > 1000, "{compared}");
    }

    /// The slopes with the stencil found once per link are the per-call ones bit for bit:
    /// each link of the span of 33 nodes above (a jump among them) split in one to five
    /// parts, at each part's start, midpoint and end within its midpoint, with no kink, one,
    /// two, a kink at a node and kinks near the ends (so pieces of one to five points, which
    /// give 0 or the polynomial through all of them, as well as full stencils); the slopes
    /// are the material's own to the quintic's accuracy where the piece is long.
    #[test]
    fn the_slopes_are_the_per_call_ones_bit_for_bit() {
        let mut s: Vec<f64> = (0..32).map(|k| 0.242 * (k as f64 / 31.0).powf(1.1)).collect();
        s.insert(12, s[12]);
        let values: Vec<f64> = s.iter().map(|x| 1.0 + 0.01 * (7.0 * x).sin() + 0.002 * x).collect();
        let kinks: [&[Kink]; 6] = [
            &[],
            &[(0.1003, 1.0011, 1.0013)],
            &[(0.05, 1.0, 1.001), (0.1703, 1.002, 1.0025)],
            &[(s[20], 1.0, 1.001)],
            &[(0.001, 1.0, 1.001), (0.2415, 1.002, 1.0025)],
            &[(s[10], 1.0, 1.001), (s[13], 1.002, 1.0025), (s[15], 1.003, 1.0035)],
        ];
        let mut compared = 0;
        let mut largest: f64 = 0.0;
        for kinks in kinks {
            for (i, pair) in s.windows(2).enumerate() {
                for parts in 1..=5 {
                    for q in 0..parts {
                        let a = pair[0] + (pair[1] - pair[0]) * q as f64 / parts as f64;
                        let b = pair[0] + (pair[1] - pair[0]) * (q + 1) as f64 / parts as f64;
                        let m = 0.5 * (a + b);
                        let got = lagrange_slopes(&s, &values, kinks, [a, m, b], m);
                        for (at, got) in [a, m, b].into_iter().zip(got) {
                            let want = slope_listed(&s, &values, kinks, at, m);
                            assert_eq!(got.to_bits(), want.to_bits(), "{at} within {m} with {kinks:?}");
                            compared += 1;
                            // Away from the repeated node (a stencil through both is not a
                            // polynomial's).
                            if kinks.is_empty() && i.abs_diff(12) > 4 {
                                let exact = 0.07 * (7.0 * at).cos() + 0.002;
                                largest = largest.max((got - exact).abs());
                            }
                        }
                    }
                }
            }
        }
        assert!(compared > 2000, "{compared}");
        // The quintic's slope error on links of about 8 mm, lambda'' ~ 0.5 /m^2 with
        // lambda^(6) ~ 1e3: far below 1e-6 /m, against slopes of 0.07.
        assert!(largest < 1e-6, "{largest}");
    }
}
