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

type M12x6 = SMatrix<f64, 12, 6>;

/// A root of det Q within this fraction of the rod length from the base counts as at the
/// base (a singular second variation, not an unstable direction): in a converged state,
/// rounding moves an exact zero (the neutral direction of a perfectly round buckled
/// column) by up to 5e-8 L (measured: 2e-8 to 5e-8 L).
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
    let l = robot.length();
    if (0..=128).any(|i| loads.distributed_moment.at(l * i as f64 / 128.0) != nalgebra::Vector3::zeros()) {
        return Some("the distributed moment is a dead moment, which is not conservative in 3D".into());
    }
    None
}

/// The verdict for the Jacobian `values` (in [`pattern`](super::unknowns::pattern) order)
/// at an equilibrium on a mesh with node arc lengths `s` (m).
pub fn assess(values: &[f64], s: &[f64]) -> Stability {
    let nodes = s.len();
    let links = nodes - 1;
    let link_block = NODE * 2 * NODE;
    let tip_at = BASE_ROWS * BASE_COLUMNS + links * link_block;
    // The tip rows act on (dtheta, dv, du) of the last node.
    let tip = SMatrix::<f64, TIP_ROWS, TIP_COLUMNS>::from_row_slice(&values[tip_at..tip_at + TIP_ROWS * TIP_COLUMNS]);
    let t_theta = tip.fixed_view::<6, 3>(0, 0).into_owned();
    let t_vu: Matrix6<f64> = tip.fixed_view::<6, 6>(0, 3).into_owned();
    let Some(t_vu_lu) = t_vu.try_inverse() else {
        return Stability::Unknown {
            reason: "the linearized tip conditions do not fix the tip strains (singular tip block)".into(),
        };
    };
    let mut y = M12x6::zeros();
    for j in 0..6 {
        y[(P + j, j)] = 1.0;
    }
    let vu = -t_vu_lu * t_theta * y.fixed_view::<3, 6>(THETA, 0);
    y.fixed_view_mut::<3, 6>(V, 0).copy_from(&vu.fixed_view::<3, 6>(0, 0));
    y.fixed_view_mut::<3, 6>(U, 0).copy_from(&vu.fixed_view::<3, 6>(3, 0));

    let mut count = 0;
    let mut first = None;
    // The fields are kept normalized so that their (dp, dtheta) block is the identity (a
    // change of basis, which moves no root): then Q0 = I, and most links need only the
    // bound on Q1 - I to exclude a root. Near a conjugate point, where Q1 is nearly
    // singular, they are orthonormalized instead, and the next link takes the general path.
    let mut identity = true;
    for k in (0..links).rev() {
        let at = BASE_ROWS * BASE_COLUMNS + k * link_block;
        let block = &values[at..at + link_block];
        let Some(next) = carry(block, &y, identity) else {
            return Stability::Unknown {
                reason: format!(
                    "the linearized equations of the link at s = {:.4} m cannot be carried across it",
                    s[k]
                ),
            };
        };
        if !next.iter().all(|v| v.is_finite()) {
            return Stability::Unknown {
                reason: format!("the Jacobi fields became non-finite at s = {:.4} m", s[k]),
            };
        }
        let q0: Matrix6<f64> = y.fixed_view::<6, 6>(0, 0).into_owned();
        let q1: Matrix6<f64> = next.fixed_view::<6, 6>(0, 0).into_owned();
        let mut roots = if identity {
            crossings_from_identity(&q1)
        } else {
            crossings(&q0, &q1)
        };
        if k == 0 {
            // A root at the base itself is a zero eigenvalue of the second variation, not a
            // negative one: the state is on the verge (exactly at a fold or bifurcation), or
            // it has a neutral direction along a continuous symmetry (a perfectly round
            // column buckles in any plane, and turning the plane costs no energy).
            roots.retain(|&t| (1.0 - t) * s[1] >= NEUTRAL * s[links]);
        }
        if let Some(&t) = roots.first() {
            first.get_or_insert(s[k + 1] + t * (s[k] - s[k + 1]));
        }
        count += roots.len();
        // 1e-6: Q1 is then far enough from singular that its inverse is accurate to about
        // 1e-10 relative.
        let inverse = q1.try_inverse().filter(|inv| {
            let norm = |m: &Matrix6<f64>| m.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            norm(&q1) * norm(inv) < 1e6
        });
        match inverse {
            Some(inv) => {
                // next Q1^-1: its (dp, dtheta) block is the identity, set exactly.
                y.fixed_view_mut::<6, 6>(0, 0).copy_from(&Matrix6::identity());
                let lower: Matrix6<f64> = next.fixed_view::<6, 6>(6, 0) * inv;
                y.fixed_view_mut::<6, 6>(6, 0).copy_from(&lower);
                identity = true;
            }
            None => {
                y = next.qr().q();
                identity = false;
            }
        }
    }
    match first {
        None => Stability::Stable,
        Some(s) => Stability::Unstable {
            directions: count,
            conjugate_point: s,
        },
    }
}

/// The fields at node k from those at node k + 1 through one link's rows
/// [A | B] (12 x 24, row major in `block`): A next = -B y, by Gaussian elimination with
/// partial pivoting on the 12 x 18 augmented matrix (a hand-written kernel: the verdict
/// runs it once per link, and a generic LU costs twice as much). When `identity`, the
/// (dp, dtheta) block of y is exactly the identity, and B y = B_(p, theta) + B_(v, u) y_(v, u)
/// takes half the products. None for a zero pivot.
fn carry(block: &[f64], y: &M12x6, identity: bool) -> Option<M12x6> {
    const W: usize = 2 * NODE;
    let mut m = [[0.0f64; NODE + 6]; NODE];
    for (r, row) in m.iter_mut().enumerate() {
        let line = &block[r * W..(r + 1) * W];
        row[..NODE].copy_from_slice(&line[..NODE]);
        let b: &[f64; NODE] = line[NODE..].try_into().ok()?;
        let product = &mut row[NODE..];
        if identity {
            product.copy_from_slice(&b[..6]);
            for (c, bc) in b.iter().enumerate().skip(6) {
                for (p, yc) in product.iter_mut().zip(y.fixed_view::<1, 6>(c, 0).iter()) {
                    *p += bc * yc;
                }
            }
        } else {
            product.fill(0.0);
            for (c, bc) in b.iter().enumerate() {
                for (p, yc) in product.iter_mut().zip(y.fixed_view::<1, 6>(c, 0).iter()) {
                    *p += bc * yc;
                }
            }
        }
        for p in product.iter_mut() {
            *p = -*p;
        }
    }
    for c in 0..NODE {
        let pivot = (c..NODE).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[pivot][c] == 0.0 {
            return None;
        }
        m.swap(c, pivot);
        let inv = 1.0 / m[c][c];
        let (upper, lower) = m.split_at_mut(c + 1);
        let pivot_row = &upper[c];
        for row in lower.iter_mut() {
            let f = row[c] * inv;
            if f != 0.0 {
                for (x, p) in row[c..].iter_mut().zip(&pivot_row[c..]) {
                    *x -= f * p;
                }
            }
        }
    }
    let mut out = M12x6::zeros();
    for r in (0..NODE).rev() {
        for j in 0..6 {
            let mut v = m[r][NODE + j];
            for k in r + 1..NODE {
                v -= m[r][k] * out[(k, j)];
            }
            out[(r, j)] = v / m[r][r];
        }
    }
    Some(out)
}

/// [`crossings`] from q0 = I: the roots of det(I + t (q1 - I)).
fn crossings_from_identity(q1: &Matrix6<f64>) -> Vec<f64> {
    let m = q1 - Matrix6::identity();
    // Every eigenvalue mu of m has |mu| <= its max row sum; a root needs mu <= -1.
    let bound = (0..6)
        .map(|r| m.row(r).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    if bound < 1.0 {
        return Vec::new();
    }
    roots(&m, q1.determinant() < 0.0, false)
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
