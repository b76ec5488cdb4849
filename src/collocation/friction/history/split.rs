//! Error control of a history step with a stuck stretch (docs/friction.md section 8, "Error
//! control of stuck steps"): the step is solved again on its mesh with its links split in
//! two, four, ... parts (with a tolerance only the links where a tendon sticks, [`parts`];
//! the others four times more slowly), from the same carried material, until two
//! successive answers agree to the tolerance; the finer one is returned, with their difference as its error estimate
//! plus the error the carried material's interpolation leaves ([`material_error`]), which
//! every level shares. On each level the split node nearest each tendon's stick/slip
//! boundary (estimated from the last level's tensions, [`boundaries`]) is moved onto it, so
//! the kink of the tension lies at a node and the step is of order 4 over the levels with
//! the stuck links' per-point multipliers (one tendon with friction; order 2 with the
//! constant multiplier of two or more, docs/friction.md section 8, "ord23"). The
//! history's own mesh is a subset of every split mesh, so the material the step leaves is
//! handed back to it at its nodes exactly.

use super::interpolant::{lagrange, lagrange_slopes};
use super::{Carried, Contact, Grip, Options, Profile, Result, Robot, StepAnswer, solve_on};
use crate::collocation::refine;
use crate::mesh::Mesh;
use crate::mesh::guess::interpolate;
use crate::model::equations::Model;
use crate::report::ErrorEstimate;
use crate::solution::Solution;
use nalgebra::Vector3;

/// Most splits of a stuck step's links: 2^6 = 64 parts per link. With a node at the
/// stick/slip boundary a stuck step's split differences fall about 4 times per level with
/// the constant multiplier (order 2, docs/friction.md section 8; 16 to 25 times with the
/// per-point ones), so 64 parts cut a step's error at least about 4 000
/// times; a step that still misses its tolerance (or would need more than
/// `max_intervals`) reports so.
const LEVELS: u32 = 6;

/// The first graded level whose difference to the one before sees the sliding links'
/// error: they are cut in 2^(level - 2) parts, so first again from level 2 to 3.
const SLIDING_SEEN: u32 = 3;

/// How many parts each link of `before`'s mesh is cut into on split level `level` after
/// the answer `last` (the last level's, or the step's on the history's mesh) with its
/// stick/slip `boundaries`. Uniform (`graded` false): 2^level. Graded: 2^level on the
/// fine links, 2^(level - 2) (at least one) on the others. With one tendon with friction
/// the stuck links take per-point multipliers and are of order 4 like the sliding ones,
/// whose error on the history's mesh is already that of a step that slides all along: the
/// fine links are those where a stuck stretch of `last` starts or a boundary lies, and
/// their neighbours (docs/friction.md section 8, "ord23"). With two or more a stuck
/// link's multiplier is constant across it (order 2): the fine links are those where a
/// tendon sticks in `last` or a boundary lies, and the link before such a one
/// ("Graded levels").
fn parts(before: &Carried, level: u32, graded: bool, last: &StepAnswer, boundaries: &[f64]) -> Vec<usize> {
    let full = 1 << level;
    let nodes = &before.mesh.nodes;
    if !graded {
        return vec![full; nodes.len() - 1];
    }
    let sliding = 1 << level.saturating_sub(2);
    let pointwise = before.grips.len() == 1;
    let fine: Vec<bool> = nodes
        .windows(2)
        .map(|pair| {
            let (a, b) = (pair[0].s, pair[1].s);
            // With per-point multipliers (one tendon with friction) a stuck link is of
            // order 4 as a sliding one: only the links at the boundary, where the
            // stretches meet, are cut at the full rate (docs/friction.md section 8, "ord23").
            let stuck = last.1.iter().any(|(_, list)| {
                list.iter().any(|&(start, end, c)| {
                    c == Contact::Stick
                        && if pointwise {
                            start >= a && start <= b
                        } else {
                            start < b && end > a
                        }
                })
            });
            // A slip zone inside the stuck stretch starts inside a link (docs/friction.md
            // section 8, "Slip zones inside a stuck stretch"): its tension kinks there.
            let zone = last.1.iter().any(|(_, list)| {
                list.iter()
                    .skip(1)
                    .any(|&(start, _, c)| c != Contact::Stick && start >= a && start <= b)
            });
            stuck || zone || boundaries.iter().any(|&e| e >= a && e <= b)
        })
        .collect();
    // The link before a fine one is fine too: the boundary's estimate ([`boundaries`])
    // reads three nodes on each side of it, at the fine spacing.
    (0..fine.len())
        .map(|k| {
            if fine[k] || fine.get(k + 1) == Some(&true) || (pointwise && k > 0 && fine[k - 1]) {
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
    // The work of every solve of the step, which its answer reports.
    let mut spent = answer.0.report.clone();
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
    for level in 1..=LEVELS {
        let boundaries = boundaries(&best);
        let parts = parts(before, level, graded, &best, &boundaries);
        if parts.iter().sum::<usize>() > options.max_intervals.max(2 * intervals) {
            break;
        }
        let mut fine = split(robot, before, &parts, &best.0, &boundaries)?;
        let next = match solve_on(robot, options, &mut fine, None) {
            Ok((next, _)) => next,
            // The per-point multipliers can leave a near tie at the placed boundary node
            // that the march does not settle (docs/friction.md section 8, "ord23"): the
            // level is solved again with the constant multiplier.
            Err(_) if fine.grips.iter().any(|g| !g.points.is_empty()) => {
                fine = split(robot, before, &parts, &best.0, &boundaries)?;
                for grip in &mut fine.grips {
                    grip.points.clear();
                }
                solve_on(robot, options, &mut fine, None)?.0
            }
            Err(e) => return Err(e),
        };
        spent.add_mesh_work(&next.0.report);
        reached = level;
        let estimate = difference(&best.0, &next.0);
        best = next;
        best.0.report.error_estimate = Some(estimate);
        let fine = finest.insert(fine);
        let Some(tol) = options.tolerance else {
            break;
        };
        // The sliding links are cut again from level 3 on: only then does the difference
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
        // The answer's order: 4 where its stuck links took per-point multipliers (one
        // tendon with friction, a level that settled with them), else 2.
        let order = if fine.grips.iter().all(|g| !g.points.is_empty()) && fine.grips.len() == 1 {
            4
        } else {
            2
        };
        let report = &mut best.0.report;
        report.error_estimate = report.error_estimate.map(|e| ErrorEstimate {
            order,
            ..sum(&e, &material)
        });
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
    best.0.report.set_work(&spent);
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
        }
        better
    };
    let factors = fine.factors.take();
    let mut better = start(factors);
    // The answer's pattern with its per-point shares, which the held solve starts from.
    better.settled.clone_from(&fine.settled);
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
    Ok(difference(answer, &again))
}

/// The error estimate of the finer of two answers of a step: their difference. With an
/// order p >= 1 the finer one's error is the difference / (2^p - 1), so this bounds it
/// (at the order 2 the boundary node gives with constant multipliers, by about 3 times,
/// at order 4 by about 15; where the boundary moves
/// between levels the order is irregular, and at order 1 the difference about equals it).
/// [`material_error`] measures the material's error with it too.
fn difference(coarse: &Solution, fine: &Solution) -> ErrorEstimate {
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
        tip_position: (a.p - b.p).norm(),
        tip_rotation: sin.atan2(cos),
        backbone_max,
        order: 2,
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
pub(super) fn split(
    robot: &Robot,
    before: &Carried,
    parts: &[usize],
    guess: &Solution,
    boundaries: &[f64],
) -> Result<Carried> {
    let nodes = &before.mesh.nodes;
    let mut points = Vec::with_capacity(parts.iter().sum::<usize>() + 1);
    for (pair, &parts) in nodes.windows(2).zip(parts) {
        let (a, b) = (pair[0].s, pair[1].s);
        points.push(a);
        if b > a {
            let mut inner: Vec<f64> = (1..parts).map(|q| a + (b - a) * q as f64 / parts as f64).collect();
            // A boundary within 1e-3 of the link from one of its ends is left to that node.
            // Each boundary takes a point of its own (a second one in the link the next
            // nearest).
            let margin = 1e-3 * (b - a);
            let mut taken = vec![false; inner.len()];
            for &e in boundaries.iter().filter(|&&e| e > a + margin && e < b - margin) {
                let nearest = (0..inner.len())
                    .filter(|&q| !taken[q])
                    .min_by(|&p, &q| (inner[p] - e).abs().total_cmp(&(inner[q] - e).abs()));
                if let Some(q) = nearest {
                    inner[q] = e;
                    taken[q] = true;
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
        let along = guess.tensions_at(i, (0..z[j].len()).map(|n| mesh.nodes[n.min(span)].s));
        for (value, tension) in z[j].iter_mut().zip(along) {
            let tension = tension.unwrap_or(0.0);
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
            points: (0..span)
                .map(|l| {
                    let (a, b) = (mesh.nodes[l].s, mesh.nodes[l + 1].s);
                    let m = 0.5 * (a + b);
                    let (s, v) = (&coarse[..=links], &old.reference[..=links]);
                    let [sa, sm, sb] = lagrange_slopes(s, v, &old.kinks, [a, m, b], m);
                    [sa, lagrange(s, v, &old.kinks, m, 6), sm, sb]
                })
                .collect(),
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
/// do not cross there, gives none. The same for each end of every slip zone inside the
/// stuck stretch (section 8, "Slip zones inside a stuck stretch"): the stretches before
/// and after the link where its zone list changes.
fn boundaries(answer: &StepAnswer) -> Vec<f64> {
    let (solution, zones) = answer;
    let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
    let mut out = Vec::new();
    for (i, list) in zones {
        let base = list
            .windows(2)
            .position(|w| w[0].2 != Contact::Stick && w[1].2 == Contact::Stick);
        // Every other change of the list: zones inside the stuck stretch.
        let inner = (0..list.len().saturating_sub(1))
            .filter(|&p| Some(p) != base && list[p].2 != Contact::Slack && list[p + 1].2 != Contact::Slack);
        for p in base.into_iter().chain(inner) {
            if let Some(e) = meeting(&s, &solution.tendon_tensions[*i], list[p + 1].0) {
                out.push(e);
            }
        }
    }
    out
}

/// The root, around the node at `start`, of the difference of the quadratics through the
/// three nodes' `tension` up to it and the three after the next ([`boundaries`]).
fn meeting(s: &[f64], tension: &[f64], start: f64) -> Option<f64> {
    {
        let a = s.iter().position(|&x| x == start)?;
        if a < 2 || a + 3 >= s.len() {
            return None;
        }
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
        if gap(lo) * gap(hi) > 0.0 {
            return None;
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
        Some(0.5 * (lo + hi))
    }
}

/// Hands the material `fine` holds after its step back to the history's mesh in
/// `carried`: the node states, log tensions and carried material at the history's nodes,
/// which are nodes of the split mesh (matched by arc length and segment), so exactly. The
/// material at its best (`corrected`) is the one `before` the step where the step stuck
/// (its material has not moved), and the step's own where it slid, with the kink at the
/// boundary between them and the kinks the sliding stretch laid where other tendons'
/// boundaries lay (docs/friction.md section 8, "The material's kinks", "hist20"). Returns
/// the index in `fine`'s mesh of each of the history's nodes.
pub(super) fn hand_back(carried: &mut Carried, fine: &Carried, before: &Carried) -> Vec<usize> {
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
        let span = was.contacts.len();
        if !f.zone_starts().is_empty() {
            // Slip zones inside the stuck stretch: a node's material moved unless the
            // fine link before it sticks ([`super::zone::kinks`]).
            corrected.values = index
                .iter()
                .zip(&grip.reference)
                .zip(&old.values)
                .map(|((&n, &slid), &kept)| {
                    if n > 0 && f.contacts.get(n - 1) == Some(&Contact::Stick) {
                        kept
                    } else {
                        slid
                    }
                })
                .collect();
            let s: Vec<f64> = fine.mesh.nodes.iter().map(|n| n.s).collect();
            let stuck = |n: usize| lagrange(&coarse[..=span], &old.values[..=span], &old.kinks, s[n], 8);
            let others: Vec<f64> = f.kinks.iter().filter(|k| k.1 == k.2).map(|k| k.0).collect();
            corrected.kinks = super::zone::kinks(&f.contacts, &s, &f.reference, &stuck, &old.kinks, &others);
            continue;
        }
        corrected.values = coarse
            .iter()
            .zip(&grip.reference)
            .zip(&old.values)
            .map(|((&s, &slid), &kept)| if s > boundary { kept } else { slid })
            .collect();
        // The kinks its sliding stretch laid at other tendons' boundaries, with the
        // order-4 material there (as the boundary's own kink has before it).
        let laid = f.kinks.iter().copied().filter(|&(e, _, _)| e < boundary);
        corrected.kinks = match first {
            None => laid.collect(),
            Some(k) => {
                let stuck = lagrange(&coarse[..=span], &old.values[..=span], &old.kinks, boundary, 8);
                let new = (k > 0).then_some((boundary, f.reference[k], stuck));
                laid.chain(new)
                    .chain(old.kinks.iter().copied().filter(|&(e, _, _)| e > boundary))
                    .collect()
            }
        };
    }
    index
}
