//! Collocation meshes: nodes on [0, L] with a node on each side of every breakpoint
//! (tendon termination or interior point load), joined there by the jump conditions.

pub mod guess;
pub mod nodes;
pub(crate) mod points;
pub mod resolution;
pub(crate) mod spare;

use crate::Readable;
use crate::error::{Result, invalid};
use crate::model::robot::Robot;

/// A mesh node: where it is and which segment (stretch between breakpoints) it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshNode {
    /// Arc length (m).
    pub s: f64,
    /// End of the node's segment (m): tendons ending at or after it load the segment.
    pub segment_end: f64,
}

/// Nodes in increasing s. Two consecutive nodes with the same s are the left and right
/// limits at a breakpoint; every other pair of neighbours bounds an interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// The nodes, from s = 0 to s = L.
    pub nodes: Vec<MeshNode>,
}

impl Mesh {
    /// About `intervals` intervals of equal length, distributed over the segments between
    /// breakpoints in proportion to their length (at least one per segment).
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] when `intervals` is 0.
    pub fn uniform(robot: &Robot, intervals: usize) -> Result<Self> {
        if intervals == 0 {
            return Err(invalid(
                "options.intervals",
                "is 0",
                "use at least 1 interval (16 or more for accuracy)",
            ));
        }
        let length = robot.length();
        let mut points = spare::take(intervals + 1);
        let mut breaks = spare::take(robot.tendons.len());
        robot.breakpoints_into(&mut breaks);
        let mut start = 0.0;
        for &end in breaks.iter().chain(std::iter::once(&length)) {
            // The share of the intervals between two breakpoints; on a rod so long that
            // `intervals * length` overflows, the same share computed the other way round
            // (which would change the last bit of ordinary meshes, so only then).
            let share = (intervals as f64) * (end - start) / length;
            let share = if share.is_finite() {
                share
            } else {
                (intervals as f64) * ((end - start) / length)
            };
            let count = share.round().max(1.0) as usize;
            points.extend((0..count).map(|k| start + (end - start) * k as f64 / count as f64));
            start = end;
        }
        points.push(length);
        let mesh = Self::from_points(robot, &points);
        spare::give(points);
        spare::give(breaks);
        mesh
    }

    /// A mesh through the given arc lengths (m), plus 0, L and every breakpoint.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for a point outside [0, L] or not finite.
    pub fn from_points(robot: &Robot, points: &[f64]) -> Result<Self> {
        let length = robot.length();
        if let Some((i, &s)) = points
            .iter()
            .enumerate()
            .find(|(_, s)| !(s.is_finite() && (0.0..=length).contains(*s)))
        {
            return Err(invalid(
                format!("mesh[{i}]"),
                format!("is {} m, outside [0, {}]", Readable(s), Readable(length)),
                "give mesh points on the rod",
            ));
        }
        let mut breaks = spare::take(robot.tendons.len());
        robot.breakpoints_into(&mut breaks);
        let mut s = spare::take(points.len() + 2 + breaks.len());
        s.extend(
            points
                .iter()
                .copied()
                .chain([0.0, length])
                .chain(breaks.iter().copied()),
        );
        s.sort_by(f64::total_cmp);
        s.dedup();
        let mut nodes = spare::take(s.len() + breaks.len());
        let mut seg = 0;
        for &x in &s {
            let end = breaks.get(seg).copied().unwrap_or(length);
            nodes.push(MeshNode { s: x, segment_end: end });
            if x == end && seg < breaks.len() {
                seg += 1;
                nodes.push(MeshNode {
                    s: x,
                    segment_end: breaks.get(seg).copied().unwrap_or(length),
                });
            }
        }
        spare::give(s);
        spare::give(breaks);
        Ok(Mesh { nodes })
    }

    /// Gives the node buffer back to this thread's kept buffers ([`spare`]), for the next
    /// mesh built: what a solve does with a mesh it is done with.
    pub(crate) fn release(self) {
        spare::give(self.nodes);
    }

    /// Number of intervals (neighbour pairs of positive length).
    pub fn intervals(&self) -> usize {
        self.nodes.windows(2).filter(|w| w[1].s > w[0].s).count()
    }

    /// Whether link k (between nodes k and k + 1) is a jump (zero length).
    pub fn is_jump(&self, k: usize) -> bool {
        self.nodes[k + 1].s == self.nodes[k].s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Rod, Routing, Tendon};

    #[test]
    fn breakpoints_get_two_nodes_and_segments() {
        let robot = Robot::new(Rod::solid_circle(1.0, 0.001, 1e9, 0.3))
            .with_tendon(Tendon::new(Routing::straight(0.01, 0.0), 1.0).ending_at(0.5))
            .with_tendon(Tendon::new(Routing::straight(-0.01, 0.0), 1.0));
        let mesh = Mesh::uniform(&robot, 4).unwrap();
        let s: Vec<f64> = mesh.nodes.iter().map(|n| n.s).collect();
        assert_eq!(s, vec![0.0, 0.25, 0.5, 0.5, 0.75, 1.0]);
        let ends: Vec<f64> = mesh.nodes.iter().map(|n| n.segment_end).collect();
        assert_eq!(ends, vec![0.5, 0.5, 0.5, 1.0, 1.0, 1.0]);
        assert_eq!(mesh.intervals(), 4);
        assert!(mesh.is_jump(2) && !mesh.is_jump(1));
    }
}
