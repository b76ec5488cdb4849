//! Spacer disks: rigid disks on the backbone that guide the tendons. Their weight loads the
//! rod as point forces at their positions ([`Disks::point_loads`], added to
//! [`Loads::point`](crate::Loads)), which the solvers treat like any point load: a jump in
//! n at an interior mesh point, part of the tip condition for a disk at the tip.

use crate::model::loads::PointLoad;
use nalgebra::Vector3;

/// A set of equal spacer disks.
#[derive(Clone, Debug, PartialEq)]
pub struct Disks {
    /// Arc lengths of the disks (m), each in (0, L].
    pub positions: Vec<f64>,
    /// The weight of each disk (N, world frame): its mass times the gravity vector.
    pub weight: Vector3<f64>,
    /// The radius the pictures draw them with (m); `None`: the pictures' own default.
    /// No effect on the model.
    pub radius: Option<f64>,
}

impl Disks {
    /// `count` disks evenly spaced on a rod of `length` L (m), the last at the tip:
    /// s_k = k L / count for k = 1..count (the last exactly L), each of `weight` (N, world).
    ///
    /// # Examples
    /// ```
    /// use tdcr::Disks;
    /// use tdcr::nalgebra::Vector3;
    /// let disks = Disks::evenly(12, 0.242, Vector3::new(0.0, 0.0, -0.001 * 9.81));
    /// assert_eq!((disks.positions[0], disks.positions[11]), (0.242 / 12.0, 0.242));
    /// ```
    pub fn evenly(count: usize, length: f64, weight: Vector3<f64>) -> Self {
        let positions = (1..=count)
            .map(|k| {
                if k == count {
                    length
                } else {
                    length * k as f64 / count as f64
                }
            })
            .collect();
        Disks {
            positions,
            weight,
            radius: None,
        }
    }

    /// The disks' weights as point loads, one per disk, in the order of `positions`: the
    /// weight as force, no moment (the weight acts through the disk's centre, on the
    /// backbone).
    pub fn point_loads(&self) -> Vec<PointLoad> {
        self.positions
            .iter()
            .map(|&s| PointLoad {
                s,
                force: self.weight,
                moment: Vector3::zeros(),
            })
            .collect()
    }

    /// The point loads of `points` other than these disks' weights, if `points` ends with
    /// exactly [`Disks::point_loads`] (as a robot file's point loads do); `None` if the
    /// weights were changed since (by a load scale, say) or are not there.
    pub fn others<'a>(&self, points: &'a [PointLoad]) -> Option<&'a [PointLoad]> {
        let weights = self.point_loads();
        let rest = points.len().checked_sub(weights.len())?;
        (points[rest..] == weights[..]).then_some(&points[..rest])
    }
}
