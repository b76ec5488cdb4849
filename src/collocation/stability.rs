//! Stability of a converged equilibrium: Jacobi's conjugate-point test on the linearized
//! collocation system (docs/stability.md).
//!
//! For conservative loading the equilibria are the critical points of the potential energy
//! (strain energy, plus tension x path length for every tendon, minus the work of the dead
//! forces), and an equilibrium is stable when the second variation is positive definite.
//! By the Morse index theorem the number of its negative eigenvalues equals the number of
//! conjugate points: the arc lengths sigma in [0, L) at which the linearized equations
//! (Jacobi's equations) have a non-zero solution that is clamped at sigma (dp = dtheta = 0)
//! and meets the linearized tip conditions at L.
//!
//! The test runs on the collocation Jacobian J that Newton already assembles: six Jacobi
//! fields start at the tip with the identity in (dp, dtheta) and the (dv, du) the linearized
//! tip rows demand; each link's rows carry them from node k + 1 to node k. A conjugate point
//! is where the 6 x 6 block of their (dp, dtheta) parts, Q(s), is singular. Crossings are
//! counted with their multiplicity (a round rod under axial load buckles in two planes at
//! once, so det Q only touches zero there): between two nodes Q is interpolated linearly,
//! Q(t) = Q0 + t (Q1 - Q0), and each real root t in (0, 1] of det Q(t) = 0 is an eigenvalue
//! -1/t of Q0^-1 (Q1 - Q0), found with a 6 x 6 eigenvalue solve in the few links where a
//! root is possible at all (norm of Q0^-1 (Q1 - Q0) at least 1).

use super::unknowns::{BASE_COLUMNS, BASE_ROWS, NODE, P, THETA, TIP_COLUMNS, TIP_ROWS, U, V};
use crate::model::equations::Model;
use crate::model::parameter::Parameter;
use crate::report::Stability;
use nalgebra::{Complex, DMatrix, Matrix6, SMatrix};

mod link;

use link::{Fields, NEAR_IDENTITY, advance};

// The fields' rows 0..6 are (dp, dtheta) and 6..12 (dv, du): the sweep's blocks Q and the
// tip rows' columns are taken by these offsets.
const _: () = assert!(P == 0 && THETA == 3 && V == 6 && U == 9);

/// A root of det Q within this fraction of the rod length from the base counts as at the
/// base (a singular second variation, not an unstable direction): in a converged state,
/// rounding moves an exact zero (the neutral direction of a perfectly round buckled
/// column) by up to 5e-8 L (measured: 2e-8 to 5e-8 L). Such a root is reported with the
/// verdict ([`count`]) and decided by module `neutral`.
const NEUTRAL: f64 = 1e-6;

/// Why the conjugate-point test cannot decide stability for the loads of `model` (its
/// robot's, with a traced parameter's value), if it cannot: the test needs conservative
/// loading. Constant tensions and dead forces are conservative; a dead moment (tip, point or
/// distributed) is not in 3D in general (its work depends on the path of the rotation), nor
/// is a follower load (its work depends on the path of the rod). Their verdict comes from
/// the linearized dynamics instead (collocation/dynamics.rs).
pub fn non_conservative(model: &Model) -> Option<String> {
    let robot = model.robot;
    let loads = &robot.loads;
    if loads.has_follower(robot.length()) {
        return Some("a follower load is not conservative".into());
    }
    let mut tip_moment = loads.tip_moment;
    if let Some((Parameter::TipMoment(c), value)) = model.parameter {
        tip_moment[c] = value;
    }
    if tip_moment != nalgebra::Vector3::zeros() {
        return Some("the tip moment is a dead moment, which is not conservative in 3D".into());
    }
    if loads.point.iter().any(|p| p.moment != nalgebra::Vector3::zeros()) {
        return Some("a point load carries a dead moment, which is not conservative in 3D".into());
    }
    // The distributed moment is sampled: a field that vanishes at the ends and midpoints of
    // every interval of a 64-interval grid is taken as absent.
    if !loads.distributed_moment.vanishes_on(robot.length()) {
        return Some("the distributed moment is a dead moment, which is not conservative in 3D".into());
    }
    None
}

/// The verdict for the Jacobian `values` (in [`pattern`](super::unknowns::pattern) order)
/// at an equilibrium on a mesh with node arc lengths `s` (m): the conjugate points alone, a
/// root within [`NEUTRAL`] of the base not counted ([`count`] says whether there was one).
pub fn assess(values: &[f64], s: &[f64]) -> Stability {
    count(values, s).0
}

/// The conjugate points [`count`] left out as within [`NEUTRAL`] of the base: how many
/// (counted with multiplicity) and the arc length of the first (m).
pub(crate) type NeutralRoots = (usize, f64);

/// [`assess`], with the roots it left out as within [`NEUTRAL`] of the base, if there were
/// any. A root there is either a neutral direction (rounding of an exact zero) or an unstable
/// direction that has just appeared, which the position alone cannot tell apart; module
/// `neutral` decides it by the lowest vibration mode (docs/stability.md, "A root at the
/// base").
pub(crate) fn count(values: &[f64], s: &[f64]) -> (Stability, Option<NeutralRoots>) {
    count_with(values, s, NEAR_IDENTITY)
}

/// [`count`], the fields normalized by an LU solve on the links where the bound on Q1 - I
/// is below `near_identity` ([`link::NEAR_IDENTITY`] in a verdict; 0: by Q1's inverse on
/// every link, the tests' reference).
fn count_with(values: &[f64], s: &[f64], near_identity: f64) -> (Stability, Option<NeutralRoots>) {
    let nodes = s.len();
    let links = nodes - 1;
    let link_block = NODE * 2 * NODE;
    let tip_at = BASE_ROWS * BASE_COLUMNS + links * link_block;
    // The tip rows act on (dtheta, dv, du) of the last node.
    let tip = SMatrix::<f64, TIP_ROWS, TIP_COLUMNS>::from_row_slice(&values[tip_at..tip_at + TIP_ROWS * TIP_COLUMNS]);
    let t_theta = tip.fixed_view::<6, 3>(0, 0).into_owned();
    let t_vu: Matrix6<f64> = tip.fixed_view::<6, 6>(0, 3).into_owned();
    let Some(t_vu_lu) = t_vu.try_inverse() else {
        return (
            Stability::Unknown {
                reason: "the linearized tip conditions do not fix the tip strains (singular tip block)".into(),
            },
            None,
        );
    };
    // Identity in (dp, dtheta); (dv, du) = -T_vu^-1 T_theta dtheta.
    let vu = -t_vu_lu * t_theta;
    // The fields at node k + 1 and the buffer the link writes the next ones into, in turn:
    // `fields[at]` holds them; `next` the fields at node k before normalization.
    let mut fields: [Fields; 2] = [[[0.0; 6]; NODE]; 2];
    let mut at = 0;
    let mut next: Fields = [[0.0; 6]; NODE];
    for (j, row) in fields[0].iter_mut().take(6).enumerate() {
        row[j] = 1.0;
    }
    for (r, row) in fields[0].iter_mut().skip(V).take(6).enumerate() {
        for (j, value) in row.iter_mut().skip(THETA).take(3).enumerate() {
            *value = vu[(r, j)];
        }
    }

    let mut count = 0;
    let mut first = None;
    let mut neutral = None;
    // The fields are kept normalized so that their (dp, dtheta) block is the identity (a
    // change of basis, which moves no root): then Q0 = I, and most links need only the
    // bound on Q1 - I to exclude a root. Near a conjugate point, where Q1 is nearly
    // singular, they are orthonormalized instead, and the next link takes the general path.
    let mut identity = true;
    for k in (0..links).rev() {
        let from = BASE_ROWS * BASE_COLUMNS + k * link_block;
        let [first_buffer, second_buffer] = &mut fields;
        let (y, spare) = if at == 0 {
            (&*first_buffer, second_buffer)
        } else {
            (&*second_buffer, first_buffer)
        };
        let Some(link) = values[from..from + link_block]
            .try_into()
            .ok()
            .and_then(|b| advance(b, y, identity, near_identity, &mut next, spare))
        else {
            return (
                Stability::Unknown {
                    reason: format!(
                        "the linearized equations of the link at s = {:.4} m cannot be carried across it",
                        s[k]
                    ),
                },
                None,
            );
        };
        if !link.finite {
            return (
                Stability::Unknown {
                    reason: format!("the Jacobi fields became non-finite at s = {:.4} m", s[k]),
                },
                None,
            );
        }
        // Every eigenvalue mu of Q1 - I has |mu| <= its max row sum; a root needs mu <= -1.
        let mut roots = match identity {
            true if link.bound < 1.0 => Vec::new(),
            true => {
                let q1 = block6(&next);
                roots(&(q1 - Matrix6::identity()), q1.determinant() < 0.0, false)
            }
            false => crossings(&block6(y), &block6(&next)),
        };
        if k == 0 {
            // A root at the base itself is a zero eigenvalue of the second variation, not a
            // negative one: the state is on the verge (exactly at a fold or bifurcation), or
            // it has a neutral direction along a continuous symmetry (a perfectly round
            // column buckles in any plane, and turning the plane costs no energy).
            // A root there may also be an unstable direction that has just appeared: the
            // roots left out are kept for module `neutral` to decide.
            let (kept, dropped): (Vec<f64>, Vec<f64>) =
                roots.iter().partition(|&&t| (1.0 - t) * s[1] >= NEUTRAL * s[links]);
            if let Some(&t) = dropped.first() {
                neutral = Some((dropped.len(), s[1] + t * (s[0] - s[1])));
            }
            roots = kept;
        }
        if let Some(&t) = roots.first() {
            first.get_or_insert(s[k + 1] + t * (s[k] - s[k + 1]));
        }
        count += roots.len();
        // The next link's fields: the normalized ones the link wrote into `spare`, or the
        // orthonormalized ones written there now.
        identity = link.normalized;
        if !identity {
            let q = SMatrix::<f64, NODE, 6>::from_fn(|r, c| next[r][c]).qr().q();
            *spare = std::array::from_fn(|r| std::array::from_fn(|c| q[(r, c)]));
        }
        at = 1 - at;
    }
    let verdict = match first {
        None => Stability::Stable,
        Some(s) => Stability::Unstable {
            directions: count,
            conjugate_point: s,
        },
    };
    (verdict, neutral)
}

/// The (dp, dtheta) block Q of `fields`, as a matrix.
fn block6(fields: &Fields) -> Matrix6<f64> {
    Matrix6::from_fn(|r, c| fields[r][c])
}

/// Roots t in (0, 1] of det(q0 + t (q1 - q0)) = 0, in increasing t, counted with
/// multiplicity.
fn crossings(q0: &Matrix6<f64>, q1: &Matrix6<f64>) -> Vec<f64> {
    let dq = q1 - q0;
    // Solve from the better-conditioned end: a conjugate point exactly at a node makes that
    // end's block singular.
    let (from, to_dq, flip) = if q0.determinant().abs() >= q1.determinant().abs() {
        (q0, dq, false)
    } else {
        (q1, -dq, true)
    };
    let Some(inv) = from.try_inverse() else {
        return Vec::new();
    };
    let m = inv * to_dq;
    // Every eigenvalue mu of m has |mu| <= its max row sum; a root needs mu <= -1.
    let bound = (0..6)
        .map(|r| m.row(r).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if bound < 1.0 {
        return Vec::new();
    }
    let parity_changes = (q0.determinant() < 0.0) != (q1.determinant() < 0.0);
    roots(&m, parity_changes, flip)
}

/// The roots t in (0, 1] of det(I + t m) (of det(I + (1 - t) m) when `flip`), in
/// increasing t: eigenvalues mu of m give t = -1/mu; `parity_changes` says whether the
/// determinant changes sign over the link.
fn roots(m: &Matrix6<f64>, parity_changes: bool, flip: bool) -> Vec<f64> {
    let eig: Vec<Complex<f64>> = DMatrix::from_column_slice(6, 6, m.as_slice())
        .complex_eigenvalues()
        .iter()
        .copied()
        .collect();
    let mut roots: Vec<f64> = eig
        .iter()
        .filter_map(|mu| {
            if mu.norm() < 1e-300 {
                return None;
            }
            let t = -mu.inv();
            // A double crossing interpolated linearly can come out as a complex pair with a
            // small imaginary part: count it (a quarter of the link is the allowance).
            let real = t.im.abs() <= 0.25;
            let inside = if flip {
                t.re >= 0.0 && t.re < 1.0
            } else {
                t.re > 0.0 && t.re <= 1.0
            };
            (real && inside).then_some(if flip { 1.0 - t.re } else { t.re })
        })
        .collect();
    // The determinant's sign is exact about the parity of the count: where the eigenvalues
    // disagree (a root at the allowance's edge), it decides.
    if (roots.len() % 2 == 1) != parity_changes {
        if parity_changes {
            roots.push(1.0);
        } else {
            roots.pop();
        }
    }
    roots.sort_by(f64::total_cmp);
    roots
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collocation::options::{Equilibrium, Options};
    use crate::collocation::test_support::linearized_at;
    use crate::model::loads::Loads;
    use crate::model::rod::Rod;
    use crate::model::routing::Routing;
    use crate::model::tendon::Tendon;
    use crate::{Robot, cases};
    use std::f64::consts::PI;

    /// Deterministic numbers in [0, 1) (a linear congruential sequence).
    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A random robot in the ranges of tests/properties.rs (length 0.05..1 m, radius
    /// 0.2..2 mm, E 1..300 GPa, 1..8 straight or helical tendons at 1..10 mm ending in
    /// (0.3 L, L], tensions up to the one that bends the rod through 2 pi, self weight 1..3
    /// times the rod's own, a tip force up to 2 E I / L^2), in random directions.
    fn random_robot(state: &mut u64) -> Robot {
        let mut u = || uniform(state);
        let (length, radius) = (0.05 + 0.95 * u(), 0.2e-3 + 1.8e-3 * u());
        let rod = Rod::solid_circle(length, radius, 1e9 + 299e9 * u(), 0.25 + 0.2 * u());
        let ei = rod.section_at(0.0).section.kbt[0];
        let weight = (1.0 + 2.0 * u()) * 8000.0 * 9.81 * PI * radius * radius;
        let down = nalgebra::Vector3::new(2.0 * u() - 1.0, 2.0 * u() - 1.0, 2.0 * u() - 2.5);
        let tip = nalgebra::Vector3::new(2.0 * u() - 1.0, 2.0 * u() - 1.0, 2.0 * u() - 1.0 + 1e-3);
        let tip = tip.normalize() * 2.0 * u() * ei / (length * length);
        let mut robot = Robot::new(rod).with_loads(Loads::self_weight(weight, down).with_tip_force(tip));
        let count = 1 + (8.0 * u()) as usize;
        for _ in 0..count {
            let (offset, angle) = (0.001 + 0.009 * u(), 2.0 * PI * u());
            let routing = if u() < 0.5 {
                Routing::helical(offset, 4.0 * u() - 2.0, angle)
            } else {
                Routing::straight(offset * angle.cos(), offset * angle.sin())
            };
            let tension = u() * 2.0 * PI * ei / (offset * length) / count as f64;
            let mut tendon = Tendon::new(routing, tension);
            if u() < 0.5 {
                tendon = tendon.ending_at((0.3 + 0.7 * u()) * length);
            }
            robot = robot.with_tendon(tendon);
        }
        robot
    }

    /// The fields normalized by the LU solve where Q1 is near the identity give the verdict
    /// of the inverse on every link (the earlier sweep): the same count and roots left at the
    /// base, conjugate points within 1e-9 of the rod length (the normalized fields differ by
    /// rounding, about 1e-15 relative a link; a root moves with them by as little), on the
    /// default solves of 60 random robots and, to count unstable directions, their nearest
    /// equilibria from the guess, the prototype, and the straight column past one to five
    /// times Euler's load (unstable in 2 to 4 directions).
    #[test]
    fn the_near_identity_normalization_keeps_every_verdict() {
        let mut robots: Vec<Robot> = vec![cases::prototype()];
        let column_rod = Rod::solid_circle(1.0, 0.001, 200e9, 0.3);
        let euler = PI * PI * column_rod.section_at(0.0).section.kbt[0] / 4.0;
        for factor in [0.5, 1.5, 3.0, 5.0, 12.0] {
            let load = nalgebra::Vector3::new(0.0, 0.0, -factor * euler);
            robots.push(Robot::new(column_rod.clone()).with_loads(Loads::none().with_tip_force(load)));
        }
        let mut state = 29;
        robots.extend((0..60).map(|_| random_robot(&mut state)));
        let nearest = Options {
            equilibrium: Equilibrium::Nearest,
            ..Options::default()
        };
        let (mut compared, mut unstable, mut neutral) = (0, 0, 0);
        for (i, robot) in robots.iter().enumerate() {
            for options in [&Options::default(), &nearest] {
                let Ok(solution) = crate::collocation::solve(robot, options) else {
                    continue;
                };
                let (_, _, mut ws, _) = linearized_at(robot, &solution);
                let s: Vec<f64> = solution.nodes.iter().map(|n| n.s).collect();
                let length = robot.length();
                ws.verdict_counted(|values| {
                    let (new, new_neutral) = count(values, &s);
                    let (old, old_neutral) = count_with(values, &s, 0.0);
                    match (&new, &old) {
                        (Stability::Stable, Stability::Stable) => {}
                        (
                            Stability::Unstable {
                                directions: a,
                                conjugate_point: x,
                            },
                            Stability::Unstable {
                                directions: b,
                                conjugate_point: y,
                            },
                        ) => {
                            assert_eq!(a, b, "robot {i}");
                            assert!((x - y).abs() <= 1e-9 * length, "robot {i}: {x} {y}");
                            unstable += 1;
                        }
                        _ => panic!("robot {i}: {new:?} against {old:?}"),
                    }
                    match (new_neutral, old_neutral) {
                        (None, None) => {}
                        (Some((a, x)), Some((b, y))) => {
                            assert_eq!(a, b, "robot {i}");
                            assert!((x - y).abs() <= 1e-9 * length, "robot {i}");
                            neutral += 1;
                        }
                        other => panic!("robot {i}: neutral roots {other:?}"),
                    }
                    compared += 1;
                    (new, new_neutral)
                });
            }
        }
        // Most solves compared, and unstable verdicts among them (the columns past Euler's
        // load at least), so that the count itself was compared.
        assert!(
            compared >= 100 && unstable >= 4,
            "{compared} compared, {unstable} unstable, {neutral} neutral"
        );
    }
}
