//! The optional outputs of a dataset row, one meaning for `tdcr batch` (its columns) and
//! Python's `tdcr.solve_parameters` and `tdcr.dataset` (their keys): the tip orientation as
//! a unit quaternion, the stability verdict, the estimated tip error and K backbone points
//! evenly spaced from base to tip (docs/cli.md, "batch"); and, for each tendon with
//! friction, the tension it delivers at its termination (docs/friction.md).

use crate::error::{Result, invalid};
use crate::model::{parameter::Parameter, robot::Robot};
use crate::solution::Solution;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// Which optional outputs a row carries.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RowOutputs {
    /// The tip orientation R(L) (body to world) as a unit quaternion (w, x, y, z), w >= 0.
    pub orientation: bool,
    /// The stability verdict: "stable", "unstable" or "unknown" (docs/stability.md).
    pub stability: bool,
    /// The solver's estimate of the tip position error (m); empty/NaN without one.
    pub error_estimate: bool,
    /// K backbone points p(s_j) (m, world frame) at s_j = j L / (K - 1), j = 0..K-1 (base
    /// to tip); 0 for none, else at least 2.
    pub points: usize,
    /// The tendons (numbered from 0, ascending) whose delivered tension (N, at the
    /// termination; [`crate::TendonState::delivered_tension`]) a row carries: the tendons
    /// with friction in some row ([`RowOutputs::tendons_with_friction`]); empty for none.
    pub delivered: Vec<usize>,
}

impl RowOutputs {
    /// Checks the point count: 0 or at least 2.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] for 1 point.
    pub fn check(&self) -> Result<()> {
        if self.points == 1 {
            return Err(invalid(
                "points",
                "is 1; the points run from base to tip",
                "give 0 (none) or at least 2 points",
            ));
        }
        Ok(())
    }

    /// The arc lengths of the backbone points for a rod of `length` (m).
    pub fn arc_lengths(&self, length: f64) -> Vec<f64> {
        let k = self.points;
        (0..k).map(|j| length * j as f64 / (k - 1) as f64).collect()
    }

    /// The tendons of a table of rows on `robot` that have friction in some row (numbered
    /// from 0, ascending): those with friction in `robot` (a coefficient > 0) and those whose
    /// coefficient a column of `parameters` sets (`friction.I`; a row may set it to 0, and
    /// such a row delivers the tendon's tension). A table without friction gets none, so its
    /// rows are those of a run without friction.
    pub fn tendons_with_friction(robot: &Robot, parameters: &[Parameter]) -> Vec<usize> {
        (0..robot.tendons.len())
            .filter(|&i| robot.tendons[i].active_friction().is_some() || parameters.contains(&Parameter::Friction(i)))
            .collect()
    }

    /// The column names these outputs add to a `tdcr batch` row: `q_w q_x q_y q_z`,
    /// `stability`, `error_estimate`, `p1_x p1_y p1_z ... pK_z` (points numbered from 1),
    /// `delivered_I ...` (tendons numbered from 1), as `tdcr sweep` names the delivered
    /// tension.
    pub fn header(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.orientation {
            out.extend(["q_w", "q_x", "q_y", "q_z"].map(String::from));
        }
        if self.stability {
            out.push("stability".into());
        }
        if self.error_estimate {
            out.push("error_estimate".into());
        }
        for j in 1..=self.points {
            out.extend(["x", "y", "z"].map(|a| format!("p{j}_{a}")));
        }
        out.extend(self.delivered.iter().map(|i| format!("delivered_{}", i + 1)));
        out
    }

    /// The delivered tensions (N) of [`RowOutputs::delivered`]'s tendons in `solution`.
    pub fn delivered_of(&self, solution: &Solution) -> Vec<f64> {
        self.delivered
            .iter()
            .map(|&i| solution.tendons[i].delivered_tension)
            .collect()
    }

    /// The backbone points of `solution` ([`RowOutputs::arc_lengths`]).
    pub fn points_of(&self, solution: &Solution) -> Vec<Vector3<f64>> {
        self.arc_lengths(solution.length())
            .iter()
            .map(|&s| solution.at(s).p)
            .collect()
    }
}

/// The unit quaternion (w, x, y, z) of the rotation `R`, with w >= 0 (of q and -q, which
/// give the same rotation, the one with the non-negative scalar part).
#[allow(non_snake_case)]
pub fn quaternion(R: &Matrix3<f64>) -> [f64; 4] {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*R));
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    [q.w * sign, q.i * sign, q.j * sign, q.k * sign]
}

/// The estimated tip position error of `solution` (m); NaN without an estimate.
pub fn tip_error_estimate(solution: &Solution) -> f64 {
    solution
        .report
        .error_estimate
        .as_ref()
        .map_or(f64::NAN, |e| e.tip_position)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3;

    #[test]
    fn quaternion_rotates_like_the_matrix_and_has_nonnegative_w() {
        for axis in [
            Vector3::new(0.3, -2.9, 0.4),
            Vector3::new(0.0, 0.0, 3.1),
            Vector3::zeros(),
        ] {
            let r = so3::exp(&axis);
            let [w, x, y, z] = quaternion(&r);
            assert!(w >= 0.0);
            let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
            // 1e-14: a rotation matrix from its quaternion, to rounding
            assert!((q.to_rotation_matrix().matrix() - r).amax() < 1e-14);
        }
    }

    #[test]
    fn points_run_from_base_to_tip_and_one_is_refused() {
        let outputs = RowOutputs {
            points: 3,
            ..Default::default()
        };
        assert_eq!(outputs.arc_lengths(0.2), vec![0.0, 0.1, 0.2]);
        assert_eq!(outputs.header().len(), 9);
        let one = RowOutputs {
            points: 1,
            ..Default::default()
        };
        assert!(one.check().unwrap_err().to_string().contains("at least 2"));
    }

    #[test]
    fn delivered_columns_are_the_tendons_with_friction_in_some_row() {
        let mut robot = crate::cases::prototype();
        assert!(RowOutputs::tendons_with_friction(&robot, &[Parameter::Tension(0)]).is_empty());
        robot.tendons[2].friction = Some(crate::Friction {
            coefficient: 0.1,
            motion: crate::Motion::Pull,
        });
        let parameters = [Parameter::Friction(0), Parameter::Tension(1)];
        let outputs = RowOutputs {
            delivered: RowOutputs::tendons_with_friction(&robot, &parameters),
            ..Default::default()
        };
        assert_eq!(outputs.delivered, vec![0, 2]);
        assert_eq!(outputs.header(), vec!["delivered_1", "delivered_3"]);
    }
}
