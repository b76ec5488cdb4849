//! Nodes where the tendons stop turning in a full-slip solve's error control
//! (docs/friction.md section 8, "honest19"): where the backbone's bending reverses inside
//! a link, each tendon with friction's turning rate has a kink and its sliding tension a
//! jump in its second derivative ([`super::turning`]); the link loses its order and the
//! deferred correction misjudges it (estimates up to 2 times below the true error, meshes
//! refined 1.4 to 3.2 times past a smooth solve's). Each mesh of the refinement gets a node
//! at each such point, located on the last answer and moved to where the next one puts it
//! until it settles; the estimate then sees a smooth answer on every link and chooses the
//! next mesh as for a smooth solve. Points that cannot move the answer by more than a small
//! share of the tolerance (a vanishing mu) get no node: the estimate is widened by their
//! bound instead ("kinks20"), so the solve is mu = 0's to within friction's own effect.

use super::Options;
use super::turning::{Effect, NEAR, SETTLED, kinks, relocate, reversed};
use crate::Robot;
use crate::collocation::refine;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::report::{ErrorEstimate, SolveReport};
use crate::solution::{Solution, State};

/// Most solves of one mesh level while its points move (as a history's sliding step,
/// `history/inflection.rs`); the last placing's answer stands.
const RELOCATE: usize = 4;

/// A node of the refinement's own mesh closer to a point than this share of its link gives
/// way to the point (a link that short only adds an interval).
const CROWDED: f64 = 1e-3;

/// No point is placed while the bound on what all of them together can do to the answer
/// ([`Effect`]) is within this share of the tolerance (on the tip position, the tip
/// rotation and the tensions): the answer's estimate is widened by the bound instead, by
/// at most this share of the tolerance, so a vanishing mu solves on mu = 0's meshes
/// (docs/friction.md section 8, "kinks20").
const NEGLIGIBLE: f64 = 1e-3;

/// The points placed as nodes of the refinement's meshes, and how often the points of the
/// current level have been placed.
#[derive(Default)]
pub(super) struct Kinks {
    /// The points in the mesh solved last (sorted).
    points: Vec<f64>,
    /// Solves of this level with its points moved.
    placings: usize,
    /// The bound on the effect of the points of the answer looked at last, where they were
    /// left inside their links as negligible ([`NEGLIGIBLE`]); zero where there were none
    /// or they were placed.
    unplaced: Effect,
}

impl Kinks {
    /// The mesh to solve on after a converged solve on `mesh` with node states `x`, given
    /// `next`, the mesh the estimate asks for (None when it meets the tolerance): None when
    /// the solve is done. Without a tolerance in `options`, or where the rod's bending does
    /// not reverse between two nodes and no point was placed, `next` itself, so a smooth
    /// solve is unchanged. Else the points are located on the answer (`solution`, built
    /// only then): while one moves by more than 1e-8 L or a new one is found (at most
    /// [`RELOCATE`] times per level), `mesh` with the points moved, whatever `next`; once
    /// they settle, `next` with the points, or None. A mesh with the points that would exceed
    /// `options.max_intervals` is not tried: `next` stands as it is. While none has been
    /// placed, points whose effect is negligible ([`NEGLIGIBLE`]) are not placed either
    /// (`next` stands), unless the answer is done (`next` None) and its `estimate` widened
    /// by their effect would no longer meet the tolerance.
    ///
    /// # Errors
    /// Those of `solution`, or of a mesh through the points.
    pub(super) fn next(
        &mut self,
        robot: &Robot,
        options: &Options,
        (mesh, x, estimate): (&Mesh, &[State], &ErrorEstimate),
        solution: impl FnOnce() -> Result<Solution>,
        next: Option<Mesh>,
    ) -> Result<Option<Mesh>> {
        let length = robot.length();
        self.unplaced = Effect::default();
        let bending: Vec<_> = x.iter().map(|state| state.u).collect();
        let Some(tol) = options.tolerance else {
            return Ok(next);
        };
        if self.points.is_empty() && !reversed(&bending, length).contains(&true) {
            return Ok(next);
        }
        let kinks = kinks(robot, &solution()?);
        let effect = kinks.iter().fold(Effect::default(), |sum, kink| sum.plus(kink.effect));
        let negligible = effect.tip <= NEGLIGIBLE * tol * length
            && effect.rotation <= NEGLIGIBLE * tol
            && effect.tension <= NEGLIGIBLE * tol;
        if self.points.is_empty()
            && negligible
            && (next.is_some() || refine::meets(&widened(estimate, effect), tol, length))
        {
            self.unplaced = effect;
            return Ok(next);
        }
        let found: Vec<f64> = kinks.iter().map(|kink| kink.at).collect();
        let placed = self.points.clone();
        let (moved, fresh) = relocate(&mut self.points, &found, NEAR * length);
        let settled = moved <= SETTLED * length && !fresh;
        let placed_mesh = if !settled && self.placings < RELOCATE {
            // The same mesh with the points moved: the estimate on a mesh without a node at
            // a kink overstates the error there (4.6e-7 m for 1e-10 m), so it chooses no
            // mesh until they have settled.
            self.placings += 1;
            self.through(robot, mesh, &placed)?
        } else if let Some(fine) = &next {
            // Refined as the estimate asks, with the points where this level's answer puts
            // them.
            self.placings = 0;
            self.through(robot, fine, &[])?
        } else {
            return Ok(None);
        };
        if placed_mesh.intervals() > options.max_intervals {
            return Ok(next);
        }
        Ok(Some(placed_mesh))
    }

    /// Widens the estimate in `report` (recorded from the last answer looked at) by the
    /// bound on the effect of the points left inside their links ([`NEGLIGIBLE`]), and
    /// whether it meets the tolerance with it; nothing where there were none.
    pub(super) fn widen(&self, report: &mut SolveReport, length: f64) {
        if self.unplaced == Effect::default() {
            return;
        }
        if let Some(estimate) = report.error_estimate.as_mut() {
            *estimate = widened(estimate, self.unplaced);
        }
        report.tolerance_met = report
            .tolerance
            .zip(report.error_estimate)
            .map(|(tol, e)| refine::meets(&e, tol, length));
    }

    /// `mesh` without its nodes at `placed` (the points it was built with), with a node at
    /// each point; a node of its own within [`CROWDED`] of its link of a point gives way.
    fn through(&self, robot: &Robot, mesh: &Mesh, placed: &[f64]) -> Result<Mesh> {
        let nodes = &mesh.nodes;
        let crowded = |k: usize| {
            let s = nodes[k].s;
            // The longer of the node's two links.
            let left = k.checked_sub(1).map_or(0.0, |j| s - nodes[j].s);
            let right = nodes.get(k + 1).map_or(0.0, |n| n.s - s);
            let link = left.max(right);
            self.points.iter().any(|&p| (p - s).abs() < CROWDED * link)
        };
        let points: Vec<f64> = (0..nodes.len())
            .filter(|&k| !placed.contains(&nodes[k].s) && !crowded(k))
            .map(|k| nodes[k].s)
            .chain(self.points.iter().copied())
            .collect();
        // Breakpoints, 0 and L come back in `from_points` whatever gave way.
        Mesh::from_points(robot, &points)
    }
}

/// `estimate` with the bound `effect` added to its tip position and rotation.
fn widened(estimate: &ErrorEstimate, effect: Effect) -> ErrorEstimate {
    ErrorEstimate {
        tip_position: estimate.tip_position + effect.tip,
        tip_rotation: estimate.tip_rotation + effect.rotation,
        ..*estimate
    }
}
