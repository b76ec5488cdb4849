//! Error control of a history step with a stuck stretch (docs/friction.md section 8, "Error
//! control of stuck steps"): the step is solved again on its mesh with its links split in
//! two, four, ... parts (with a tolerance only the links where a tendon sticks, [`parts`];
//! the others at half that rate), from the same carried material, until two successive
//! answers agree to the tolerance; the finer one is returned, with their difference (over 7
//! from the second level on) as its error estimate plus the error the carried material's
//! interpolation leaves ([`material_error`]), which every level shares. On each level the
//! split node nearest each tendon's stick/slip boundary is moved onto it, the boundary
//! estimated again from the level's own answer ([`boundaries`]) and the level solved again
//! until it stays, so the kink of the tension lies at a node; the stuck links take the
//! stuck tension point by point (`collocation/friction/stuck.rs`), order 4
//! (docs/friction.md section 8, "Order 4 on stuck links", "ord18"). The history's own mesh
//! is a subset of every split mesh, so the material the step leaves is handed back to it at
//! its nodes exactly.

use super::{Carried, Contact, Grip, Kink, Options, Profile, Result, Robot, StepAnswer, solve_on};
use crate::collocation::refine;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate;
use crate::model::equations::Model;
use crate::report::ErrorEstimate;
use crate::solution::Solution;
use nalgebra::Vector3;

/// Most splits of a stuck step's links: 2^6 = 64 parts per link. With a node at the
/// stick/slip boundary, placed again on each level, and the pointwise load on stuck links
/// a stuck step's split differences fall about 16 times per level (order 4,
/// docs/friction.md section 8, "ord18"); a step that still misses its tolerance (or would
/// need more than `max_intervals`) reports so.
const LEVELS: u32 = 6;

/// The first graded level whose difference to the one before sees the sliding links'
/// error: they are cut in 2^(level - 1) parts, so first again from level 1 to 2; the first
/// whose difference is of two pointwise levels (order 4) too.
const SLIDING_SEEN: u32 = 2;

/// Placings of a level's boundary node at most: each re-estimates the boundary from the
/// level's answer and solves the level again.
const PLACINGS: usize = 6;

/// A boundary that moved by less than this (m) since the level was solved stays: the
/// tension's kink then lies within it of a node, a tip error of about this times the
/// jump of the slope of the log tension (1/m) times the link's length, far below any
/// tolerance.
const PLACED: f64 = 1e-9;

/// Whether the boundaries `again` differ from `placed`: another tendon, or one moved by
/// more than [`PLACED`].
fn moved(placed: &[(usize, f64)], again: &[(usize, f64)]) -> bool {
    placed.len() != again.len()
        || placed
            .iter()
            .zip(again)
            .any(|(&(i, e), &(l, f))| i != l || (e - f).abs() > PLACED)
}

/// How many parts each link of `before`'s mesh is cut into on split level `level` after
/// the answer `last` (the last level's, or the step's on the history's mesh) with its
/// stick/slip `boundaries`. Uniform (`graded` false): 2^level. Graded: 2^level where a
/// tendon sticks on the link in `last` or a boundary lies on it, and on the link before
/// such a one; 2^(level - 1) on the other links, where every tendon slides: from level 2
/// on every link is halved between levels, so their difference is of order 4 on the stuck
/// links (the pointwise load) and the sliding ones alike (docs/friction.md section 8,
/// "Graded levels", "ord18").
fn parts(before: &Carried, level: u32, graded: bool, last: &StepAnswer, boundaries: &[(usize, f64)]) -> Vec<usize> {
    let full = 1 << level;
    let nodes = &before.mesh.nodes;
    if !graded {
        return vec![full; nodes.len() - 1];
    }
    let sliding = 1 << level.saturating_sub(SLIDING_SEEN - 1);
    let fine: Vec<bool> = nodes
        .windows(2)
        .map(|pair| {
            let (a, b) = (pair[0].s, pair[1].s);
            let stuck = last.1.iter().any(|(_, list)| {
                list.iter()
                    .any(|&(start, end, c)| c == Contact::Stick && start < b && end > a)
            });
            stuck || boundaries.iter().any(|&(_, e)| e >= a && e <= b)
        })
        .collect();
    // The link before a fine one is fine too: the boundary's estimate ([`boundaries`])
    // reads three nodes on each side of it, at the fine spacing.
    (0..fine.len())
        .map(|k| {
            if fine[k] || fine.get(k + 1) == Some(&true) {
                full
            } else {
                sliding
            }
        })
        .collect()
}

/// Solves the step again on split meshes (module docs) after `answer`, its solution on
/// the history's mesh from the material `before`, within `options.max_intervals` (one split
/// at least), and adds the material's error to the finest answer's estimate; leaves in
/// `carried` (which holds that solve's end state and factors) the finest answer's material
/// at the history's nodes.
///
/// # Errors
/// As [`super::step`], on a split mesh.
pub(super) fn refine(
    robot: &Robot,
    options: &Options,
    carried: &mut Carried,
    before: &Carried,
    answer: StepAnswer,
) -> Result<StepAnswer> {
    let length = robot.length();
    let mut best = answer;
    let mut finest: Option<Carried> = None;
    // The material's error, measured once (on the first level whose split difference meets
    // the tolerance, or the last): every level reads the same material.
    let mut material = None;
    let intervals = before.mesh.intervals();
    // With a tolerance the levels are graded (only the links that stick are cut at the
    // full rate); without one the step is solved once more on its links cut in two.
    let graded = options.tolerance.is_some();
    // The last level solved: a graded refine that the interval cap ends before
    // [`SLIDING_SEEN`] has an estimate without the sliding links' error.
    let mut reached = 0;
    // The boundaries the last level's nodes settled on (none before the first level:
    // estimated from the answer on the history's mesh).
    let mut settled: Option<Vec<(usize, f64)>> = None;
    for level in 1..=LEVELS {
        let mut placed = settled.take().unwrap_or_else(|| boundaries(&best));
        let parts = parts(before, level, graded, &best, &placed);
        if parts.iter().sum::<usize>() > options.max_intervals.max(2 * intervals) {
            break;
        }
        let mut fine = split(robot, before, &parts, &best.0, &placed)?;
        let (mut next, _) = solve_on(robot, options, &mut fine, None)?;
        // The boundary estimated again from this level's answer, and the level solved
        // again with its node there, until it stays (docs/friction.md section 8: a node a
        // fixed distance off the boundary leaves a kink inside a link, order 1).
        let mut earlier: Option<Vec<(usize, f64)>> = None;
        for _ in 0..PLACINGS {
            let again = boundaries(&next);
            // Settled, or back where it was two placings ago: the tie at the node decides
            // the side by the last 1e-8 of log tension, which can alternate by that much
            // over 1/m (1e-8 m).
            if !moved(&placed, &again) || earlier.as_ref().is_some_and(|e| !moved(e, &again)) {
                break;
            }
            let parts = self::parts(before, level, graded, &next, &again);
            fine = split(robot, before, &parts, &next.0, &again)?;
            next = solve_on(robot, options, &mut fine, None)?.0;
            earlier = Some(std::mem::replace(&mut placed, again));
        }
        settled = Some(placed);
        reached = level;
        // Two pointwise levels differ at order 4: the finer one's error is their
        // difference / 15; the first level's difference to the answer on the history's mesh
        // (the constant multiplier, order 2) is taken whole.
        let estimate = difference(&best.0, &next.0, if level > 1 { 3 } else { 1 });
        best = next;
        best.0.report.error_estimate = Some(estimate);
        let fine = finest.insert(fine);
        let Some(tol) = options.tolerance else {
            break;
        };
        // The sliding links are cut again from level 2 on: only then does the difference
        // see their error too.
        if level < SLIDING_SEEN || !refine::meets(&estimate, tol, length) {
            continue;
        }
        let material = match material {
            Some(m) => m,
            None => *material.insert(material_error(robot, options, before, fine, &best.0)?),
        };
        // Met with the material's error, or never: the levels do not change it.
        if refine::meets(&sum(&estimate, &material), tol, length) || !refine::meets(&material, tol, length) {
            break;
        }
    }
    if let Some(mut fine) = finest {
        let material = match material {
            Some(m) => m,
            None => material_error(robot, options, before, &mut fine, &best.0)?,
        };
        let report = &mut best.0.report;
        report.error_estimate = report.error_estimate.map(|e| sum(&e, &material));
        report.tolerance = options.tolerance;
        // Cut short before the sliding links are cut again, the estimate cannot vouch for
        // them: the step says it misses its tolerance (docs/friction.md section 8).
        let seen = !graded || reached >= SLIDING_SEEN;
        report.tolerance_met = options
            .tolerance
            .zip(report.error_estimate)
            .map(|(tol, estimate)| seen && refine::meets(&estimate, tol, length));
        hand_back(carried, &fine, before);
    }
    Ok(best)
}

/// A split difference with the material's error added: the estimate of a stuck step.
fn sum(split: &ErrorEstimate, material: &ErrorEstimate) -> ErrorEstimate {
    ErrorEstimate {
        tip_position: split.tip_position + material.tip_position,
        tip_rotation: split.tip_rotation + material.tip_rotation,
        backbone_max: split.backbone_max + material.backbone_max,
        ..*split
    }
}

/// The error of `answer` (solved on `fine`'s mesh from `before`'s order-4 node
/// material interpolated by [`lagrange`] through six points, `fine` holding its end state)
/// that the carried material leaves, which every split level shares and so no difference
/// of levels sees (docs/friction.md section 8, "Error control of stuck steps"): the change
/// of the answer when the step is solved again on the same mesh from the material at its
/// best (`before.corrected`: the deferred-corrected nodes, order 6, of the step that last
/// slid there) and the polynomial through eight points of its smooth piece, started from
/// `answer`'s state and factors. Both the node values' error (the discretization error of
/// the step that left them, inherited) and the interpolation's are of higher order there,
/// so this is the material error of the answer to leading order.
///
/// The solve holds `answer`'s pattern; a slip against the friction larger than the
/// material's change can move it (integrated over the rod: the held solve's slip error)
/// is a real flip, and the step's full loop is run instead.
///
/// # Errors
/// As [`super::step`], on `fine`'s mesh.
fn material_error(
    robot: &Robot,
    options: &Options,
    before: &Carried,
    fine: &mut Carried,
    answer: &Solution,
) -> Result<ErrorEstimate> {
    let coarse: Vec<f64> = before.mesh.nodes.iter().map(|n| n.s).collect();
    let start = |factors| {
        let mut better = Carried {
            mesh: fine.mesh.clone(),
            x: fine.x.clone(),
            z: fine.z.clone(),
            grips: fine.grips.clone(),
            corrected: Vec::new(),
            solved: false,
            report: fine.report.clone(),
            factors,
            settled: None,
            rest: false,
            tensions: fine.tensions.clone(),
        };
        for ((grip, old), corrected) in better.grips.iter_mut().zip(&before.grips).zip(&before.corrected) {
            let span = old.contacts.len();
            for (value, node) in grip.reference.iter_mut().zip(&fine.mesh.nodes) {
                *value = lagrange(
                    &coarse[..=span],
                    &corrected.values[..=span],
                    &corrected.kinks,
                    node.s,
                    8,
                );
            }
            let nodes = &fine.mesh.nodes;
            for (l, value) in grip.midpoints.iter_mut().enumerate() {
                let mid = 0.5 * (nodes[l].s + nodes[l + 1].s);
                *value = lagrange(&coarse[..=span], &corrected.values[..=span], &corrected.kinks, mid, 8);
            }
        }
        better
    };
    let factors = fine.factors.take();
    let mut better = start(factors);
    // The largest change of the material from the one the answer was solved from, times
    // the rod's length: the most it moves the slip (its integral), so the held pattern's
    // slip may cross zero by that much.
    let solved_from = fine.settled.as_ref().map_or(&fine.grips, |s| &s.grips);
    let change = better
        .grips
        .iter()
        .zip(solved_from)
        .flat_map(|(b, f)| b.reference.iter().zip(&f.reference).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
        * robot.length();
    let again = match solve_on(robot, options, &mut better, Some(change)) {
        Ok(((again, _), _)) => again,
        // A real flip (or a held Newton that fails): the step's full loop sets the pattern.
        Err(_) => solve_on(robot, options, &mut start(None), None)?.0.0,
    };
    Ok(difference(answer, &again, 1))
}

/// The error estimate of the finer of two answers of a step: their difference over
/// 2^order - 1, the finer one's error where the two are of that order and the finer has
/// half the link length (`order` 1: the difference whole). The split levels take order 3
/// for two pointwise levels of order 4 (with 15 the estimates were below the error on
/// some of the prototype's stuck steps, docs/friction.md section 8, "ord18"), 1 for the
/// first level against the answer on the history's mesh; [`material_error`] measures the
/// material's error with order 1.
fn difference(coarse: &Solution, fine: &Solution, order: u32) -> ErrorEstimate {
    // The finer one's error at `order` (1: the difference whole).
    let factor = 1.0 / f64::from((1_u32 << order) - 1);
    let (a, b) = (coarse.tip(), fine.tip());
    // The angle of R_a^T R_b from its cosine and sine together: the cosine alone resolves
    // no angle below sqrt(2 eps) = 1.5e-8 rad, which would read differences of 1e-9 rad as
    // 0 or 1.5e-8 rad and miss a tolerance of 1e-8 rad.
    let relative = a.R.transpose() * b.R;
    let skew = relative - relative.transpose();
    let sin = 0.5 * Vector3::new(skew[(2, 1)], skew[(0, 2)], skew[(1, 0)]).norm();
    let cos = (relative.trace() - 1.0) / 2.0;
    let backbone_max = fine
        .nodes
        .iter()
        .map(|n| (coarse.at(n.s).p - n.p).norm())
        .fold(0.0, f64::max);
    ErrorEstimate {
        tip_position: (a.p - b.p).norm() * factor,
        tip_rotation: sin.atan2(cos) * factor,
        backbone_max: backbone_max * factor,
        order,
    }
}

/// The start of a step on `before`'s mesh with each link cut into its `parts` equal links,
/// the one of them nearest each point of `boundaries` inside a link moved onto it (the
/// mesh keeps its intervals): the carried material (lambda) interpolated at the new nodes
/// by the quintic through the six nearest points of their smooth piece ([`lagrange`]:
/// O(h^6), below the step's own error; the cubic's O(h^4) was what the 101-step history's
/// first stuck steps missed their tolerance by, docs/friction.md section 8), each new link with its parent's
/// contact and multiplier, and the states and log tensions of `guess`.
///
/// # Errors
/// An invalid mesh (none: the points lie on the rod).
fn split(
    robot: &Robot,
    before: &Carried,
    parts: &[usize],
    guess: &Solution,
    boundaries: &[(usize, f64)],
) -> Result<Carried> {
    let nodes = &before.mesh.nodes;
    let mut points = Vec::with_capacity(parts.iter().sum::<usize>() + 1);
    // Each tendon's boundary node: the point placed on it, or the link's end it is left to.
    let mut placed: Vec<(usize, f64)> = Vec::new();
    for (pair, &parts) in nodes.windows(2).zip(parts) {
        let (a, b) = (pair[0].s, pair[1].s);
        points.push(a);
        if b > a {
            let mut inner: Vec<f64> = (1..parts).map(|q| a + (b - a) * q as f64 / parts as f64).collect();
            // A boundary within 1e-3 of the link from one of its ends is left to that node.
            let margin = 1e-3 * (b - a);
            for &(i, e) in boundaries.iter().filter(|&&(_, e)| e >= a && e <= b) {
                if e <= a + margin || e >= b - margin {
                    placed.push((i, if e - a < b - e { a } else { b }));
                    continue;
                }
                let nearest = (0..inner.len()).min_by(|&p, &q| (inner[p] - e).abs().total_cmp(&(inner[q] - e).abs()));
                if let Some(q) = nearest {
                    inner[q] = e;
                    placed.push((i, e));
                }
            }
            inner.sort_by(f64::total_cmp);
            points.extend(inner);
        }
    }
    points.push(robot.length());
    let mesh = Mesh::from_points(robot, &points)?;
    let model = Model::new(robot);
    let x = interpolate(&model, guess, &mesh);
    let profile = Profile::new(&model, &mesh);
    let coarse: Vec<f64> = nodes.iter().map(|n| n.s).collect();
    let mut z = profile.z.clone();
    let mut grips = Vec::with_capacity(before.grips.len());
    for (j, old) in before.grips.iter().enumerate() {
        let (i, span, base) = (profile.slipping[j], profile.spans[j], profile.base[j]);
        for (n, value) in z[j].iter_mut().enumerate() {
            let tension = guess.tension_at(i, mesh.nodes[n.min(span)].s).unwrap_or(0.0);
            *value = if base > 0.0 && tension > 0.0 {
                (tension / base).ln()
            } else {
                0.0
            };
        }
        let links = old.contacts.len();
        // The history's link that holds new link l, and l's share of its length.
        let parent = |l: usize| {
            let mid = 0.5 * (mesh.nodes[l].s + mesh.nodes[l + 1].s);
            coarse
                .iter()
                .rposition(|&c| c <= mid)
                .unwrap_or(0)
                .min(links.saturating_sub(1))
        };
        let share = |l: usize| {
            let p = parent(l);
            let whole = coarse[p + 1] - coarse[p];
            if whole > 0.0 {
                (mesh.nodes[l + 1].s - mesh.nodes[l].s) / whole
            } else {
                0.0
            }
        };
        grips.push(Grip {
            contacts: (0..span).map(|l| old.contacts[parent(l)]).collect(),
            multipliers: (0..span).map(|l| old.multipliers[parent(l)]).collect(),
            capacities: (0..span).map(|l| old.capacities[parent(l)] * share(l)).collect(),
            reference: mesh
                .nodes
                .iter()
                .map(|node| lagrange(&coarse[..=links], &old.reference[..=links], &old.kinks, node.s, 6))
                .collect(),
            kinks: old.kinks.clone(),
            midpoints: (0..span)
                .map(|l| {
                    let mid = 0.5 * (mesh.nodes[l].s + mesh.nodes[l + 1].s);
                    lagrange(&coarse[..=links], &old.reference[..=links], &old.kinks, mid, 6)
                })
                .collect(),
            boundary: placed.iter().find(|&&(t, _)| t == i).map(|&(_, e)| e),
        });
    }
    Ok(Carried {
        mesh,
        x,
        z,
        grips,
        corrected: Vec::new(),
        solved: false,
        report: before.report.clone(),
        factors: None,
        settled: None,
        rest: before.rest,
        tensions: robot.tendons.iter().map(|t| t.tension()).collect(),
    })
}

/// Where each tendon of `answer` with a stuck stretch meets it: the root, between the
/// neighbours of the first stuck link's start node, of the difference of the quadratic
/// through the last three sliding nodes' tensions and the one through the first three
/// stuck nodes' (beyond that start node), each extrapolated into the link
/// (docs/friction.md section 8, "A node at the boundary"). A tendon whose stuck stretch
/// starts within two nodes of its base or three of its termination, or whose two profiles
/// do not cross there, gives none.
fn boundaries(answer: &StepAnswer) -> Vec<(usize, f64)> {
    let (solution, zones) = answer;
    let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mut out = Vec::new();
    for (i, list) in zones {
        let Some(pair) = list
            .windows(2)
            .find(|w| w[0].2 != Contact::Stick && w[1].2 == Contact::Stick)
        else {
            continue;
        };
        let Some(a) = s.iter().position(|&x| x == pair[1].0) else {
            continue;
        };
        if a < 2 || a + 3 >= s.len() {
            continue;
        }
        let tension = &solution.tendon_tensions[*i];
        let quadratic = |n: [usize; 3], at: f64| -> f64 {
            (0..3)
                .map(|p| {
                    let weight: f64 = (0..3)
                        .filter(|&q| q != p)
                        .map(|q| (at - s[n[q]]) / (s[n[p]] - s[n[q]]))
                        .product();
                    weight * tension[n[p]]
                })
                .sum()
        };
        let gap = |at: f64| quadratic([a - 2, a - 1, a], at) - quadratic([a + 1, a + 2, a + 3], at);
        let (mut lo, mut hi) = (s[a - 1], s[a + 1]);
        // A root at the start node itself (the boundary node of the last placing, whose tie
        // the march left stuck) may show as none: look one link further back.
        if gap(lo) * gap(hi) > 0.0 {
            lo = s[a - 2];
        }
        if gap(lo) * gap(hi) > 0.0 {
            continue;
        }
        // Bisection to the resolution of s.
        while hi - lo > 4.0 * f64::EPSILON * hi {
            let mid = 0.5 * (lo + hi);
            if gap(lo) * gap(mid) <= 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        out.push((*i, 0.5 * (lo + hi)));
    }
    out
}

/// The carried material at `at` (docs/friction.md section 8, "The material's kinks"): the
/// polynomial through the `points` points nearest to `at` of the smooth piece that holds
/// it, evaluated there. A piece runs between two successive `kinks` (or a kink and an end
/// of the span); its points are the nodes of `s` (increasing, within a tendon's span, with
/// the material `values`) inside it and the kinks that bound it, with the piece's own
/// lambda there, so no stencil straddles a kink and `at` always lies between a stencil's
/// first and last point. `points` is 6 for the quintic the step is solved with (O(h^6) where
/// the material is smooth), 8 for the degree-7 polynomial that estimates its error; a piece
/// with fewer points gives the polynomial through all of them. At a node it is the value
/// there exactly, so the material handed back at the history's nodes is the last step's;
/// at a kink that is not a node, the value after it.
fn lagrange(s: &[f64], values: &[f64], kinks: &[Kink], at: f64, points: usize) -> f64 {
    if let Some(k) = s.iter().position(|&x| x == at) {
        return values[k];
    }
    let below = kinks.iter().rfind(|k| k.0 <= at);
    let above = kinks.iter().find(|k| k.0 > at);
    let (lo, hi) = (
        below.map_or(f64::NEG_INFINITY, |k| k.0),
        above.map_or(f64::INFINITY, |k| k.0),
    );
    let piece: Vec<(f64, f64)> = below
        .map(|&(e, _, after)| (e, after))
        .into_iter()
        .chain(
            s.iter()
                .copied()
                .zip(values.iter().copied())
                .filter(|&(x, _)| x > lo && x < hi),
        )
        .chain(above.map(|&(e, before, _)| (e, before)))
        .collect();
    let n = piece.len();
    let points = points.min(n);
    let k = piece.iter().rposition(|p| p.0 <= at).unwrap_or(0);
    let first = (k + 1).saturating_sub(points / 2).min(n - points);
    let stencil = &piece[first..first + points];
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

/// Hands the material `fine` holds after its step back to the history's mesh in
/// `carried`: the node states, log tensions and carried material at the history's nodes,
/// which are nodes of the split mesh (matched by arc length and segment), so exactly. The
/// material at its best (`corrected`) is the one `before` the step where the step stuck
/// (its material has not moved), and the step's own where it slid, with the kink at the
/// boundary between them (docs/friction.md section 8, "The material's kinks").
fn hand_back(carried: &mut Carried, fine: &Carried, before: &Carried) {
    let index: Vec<usize> = carried
        .mesh
        .nodes
        .iter()
        .map(|node| {
            fine.mesh
                .nodes
                .iter()
                .position(|f| f.s == node.s && f.segment_end == node.segment_end)
                .expect("the history's nodes are nodes of every split mesh")
        })
        .collect();
    carried.settled.clone_from(&fine.settled);
    carried.x = index.iter().map(|&n| fine.x[n]).collect();
    for (j, z) in carried.z.iter_mut().enumerate() {
        *z = index.iter().map(|&n| fine.z[j][n]).collect();
    }
    let coarse: Vec<f64> = carried.mesh.nodes.iter().map(|n| n.s).collect();
    for (((grip, corrected), f), (old, was)) in carried
        .grips
        .iter_mut()
        .zip(&mut carried.corrected)
        .zip(&fine.grips)
        .zip(before.corrected.iter().zip(&before.grips))
    {
        grip.reference = index.iter().map(|&n| f.reference[n]).collect();
        grip.kinks.clone_from(&f.kinks);
        // The step's stick/slip boundary, where its first stuck link starts (none: it slid
        // all along).
        let first = f.contacts.iter().position(|&c| c == Contact::Stick);
        let boundary = first.map_or(f64::INFINITY, |k| fine.mesh.nodes[k].s);
        corrected.values = coarse
            .iter()
            .zip(&grip.reference)
            .zip(&old.values)
            .map(|((&s, &slid), &kept)| if s > boundary { kept } else { slid })
            .collect();
        let span = was.contacts.len();
        corrected.kinks = match first {
            None => Vec::new(),
            Some(k) => {
                let stuck = lagrange(&coarse[..=span], &old.values[..=span], &old.kinks, boundary, 8);
                let new = (k > 0).then_some((boundary, f.reference[k], stuck));
                new.into_iter()
                    .chain(old.kinks.iter().copied().filter(|&(e, _, _)| e > boundary))
                    .collect()
            }
        };
    }
}
