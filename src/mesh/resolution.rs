//! How fine a mesh must be to resolve a robot at all: the resolution rule.
//!
//! Whatever decides the mesh (a user's fixed `intervals`, a starting mesh for refinement), an
//! interval must not span more than [`MAX_ANGLE`] of any rotation the robot prescribes along
//! its backbone: a tendon routing turning about the backbone (a helix of `turns` turns turns
//! at 2 pi turns / L rad/m) and the reference precurvature |u*| (rad/m). On a coarser mesh
//! the scheme samples the routing too sparsely and converges, without complaint, to a shape
//! that can be most of a rod length away from the true one (aliasing).
//!
//! The bound comes from a convergence study (docs/numerics.md, "Resolution"): case H's helical
//! tendon with 1, 4, 16 and 100 turns on uniform meshes of 1 to 32 intervals per turn, tip
//! error against a refined solution (1e-10 m, agreeing with shooting to 2e-10 m):
//!
//! | angle per interval | 2 pi | pi | 2 pi / 3 | pi / 2 | pi / 4 | pi / 8 |
//! | --- | --- | --- | --- | --- | --- | --- |
//! | tip error / L, 1 turn | no convergence | 0.19 | 1.6e-2 | 5.2e-3 | 3.0e-4 | 1.8e-5 |
//! | tip error / L, 100 turns | 0.84 | 0.55 | 9.6e-2 | 2.9e-2 | 1.7e-3 | 1.0e-4 |
//!
//! At pi and beyond (two intervals or fewer per turn, the Nyquist limit) the answer is off by
//! half a rod length or more; from 2 pi / 3 on the error falls at the scheme's order 4 (16-fold
//! per halving of the angle); [`MAX_ANGLE`] = pi / 2 keeps a factor of
//! two from the Nyquist limit and is inside the order-4 regime for every helix of the study.

use crate::model::robot::Robot;
use crate::model::rod::ReferenceStrains;
use crate::model::routing::Routing;
use std::f64::consts::{FRAC_PI_2, PI};

/// The largest angle (rad) of a routing's turn about the backbone or of the reference
/// precurvature that one mesh interval may span: pi / 2, four intervals per helix turn
/// (twice the Nyquist limit of two; the study in this module's doc).
pub const MAX_ANGLE: f64 = FRAC_PI_2;

/// Points at which a custom routing or a varying reference is sampled for its rate: as
/// many as `Robot::validate` samples a routing, so a feature that validation sees is seen.
const SAMPLES: usize = 128;

/// What turns fastest along the backbone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// The routing of the tendon with this index (from 0) turning about the backbone.
    Routing(usize),
    /// The reference precurvature u* of the rod.
    Precurvature,
}

/// The resolution a robot needs: see [`required`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolution {
    /// The fastest rotation rate (rad/m) anywhere on the rod: of a routing about the
    /// backbone or of the reference precurvature |u*|; 0 for straight routings on a straight
    /// rod.
    pub rate: f64,
    /// What turns at `rate`; `None` when nothing turns.
    pub feature: Option<Feature>,
    /// The fewest intervals of a uniform mesh that resolve it: ceil(L rate / [`MAX_ANGLE`]),
    /// at least 1.
    pub intervals: usize,
}

impl Resolution {
    /// The longest interval (m) that resolves the robot: [`MAX_ANGLE`] / rate (infinite when
    /// nothing turns).
    pub fn longest_interval(&self) -> f64 {
        MAX_ANGLE / self.rate
    }
}

/// The mesh resolution `robot` (validated) needs: each interval may span at most
/// [`MAX_ANGLE`] of every tendon routing's rotation about the backbone (a helix: 2 pi turns /
/// L rad/m; a custom routing: the largest |x y' - y x'| / (x^2 + y^2) of 129 points
/// on the tendon, points on the axis skipped) and of the reference precurvature |u*|
/// (sampled likewise when it varies). The rate is the largest on the whole rod, also for a
/// tendon that ends early: a uniform mesh is as fine everywhere.
///
/// Used to refuse a fixed mesh that cannot resolve the robot; a starting mesh for refinement
/// should have at least [`Resolution::intervals`] intervals too.
pub fn required(robot: &Robot) -> Resolution {
    let length = robot.length();
    let mut best = (0.0, None);
    let mut consider = |rate: f64, feature: Feature| {
        if rate.is_finite() && rate > best.0 {
            best = (rate, Some(feature));
        }
    };
    for (i, tendon) in robot.tendons.iter().enumerate() {
        let rate = match &tendon.routing {
            Routing::Straight { .. } => 0.0,
            Routing::Helical { turns, .. } => 2.0 * PI * turns.abs() / length,
            Routing::Custom(_) => {
                let end = tendon.end(length);
                (0..=SAMPLES)
                    .map(|k| {
                        let p = tendon.routing.at(end * k as f64 / SAMPLES as f64, length);
                        let r2 = p.r.x * p.r.x + p.r.y * p.r.y;
                        if r2 > 0.0 {
                            (p.r.x * p.r_s.y - p.r.y * p.r_s.x).abs() / r2
                        } else {
                            0.0
                        }
                    })
                    .fold(0.0, f64::max)
            }
        };
        consider(rate, Feature::Routing(i));
    }
    let curvature = match &robot.rod.reference {
        ReferenceStrains::Straight => 0.0,
        ReferenceStrains::Constant { u_star, .. } => u_star.norm(),
        ReferenceStrains::Segments { u_star, .. } => u_star.iter().map(|u| u.norm()).fold(0.0, f64::max),
        ReferenceStrains::Varying(_) => (0..=SAMPLES)
            .map(|k| robot.rod.reference_at(length * k as f64 / SAMPLES as f64).u_star.norm())
            .fold(0.0, f64::max),
    };
    consider(curvature, Feature::Precurvature);
    let (rate, feature) = best;
    // 1e-9: the rounding of 2 pi turns / L * L / (pi / 2) must not add an interval (one
    // turn needs 4, not 5).
    let intervals = (length * rate / MAX_ANGLE - 1e-9).ceil().max(1.0);
    Resolution {
        rate,
        feature,
        // At most usize::MAX (saturating): a validated robot has finite turns and u*.
        intervals: intervals as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Rod, Tendon};
    use nalgebra::Vector3;
    use num_dual::DualNum;

    fn rod() -> Rod {
        Rod::solid_circle(0.2, 0.001, 2e11, 0.3)
    }

    #[test]
    fn a_helix_needs_four_intervals_per_turn() {
        let robot = Robot::new(rod())
            .with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 1.0))
            .with_tendon(Tendon::new(Routing::helical(0.008, -100.0, 0.3), 1.0));
        let r = required(&robot);
        assert_eq!(r.feature, Some(Feature::Routing(1)));
        assert_eq!(r.intervals, 400);
        // 1e-12: 2 pi 100 / 0.2 computed two ways
        assert!((r.rate - 2.0 * PI * 100.0 / 0.2).abs() < 1e-12 * r.rate);
        let one = Robot::new(rod()).with_tendon(Tendon::new(Routing::helical(0.008, 1.0, 0.0), 1.0));
        assert_eq!(required(&one).intervals, 4);
    }

    #[test]
    fn a_custom_helix_needs_what_the_built_in_one_needs() {
        let w = 2.0 * PI * 10.0 / 0.2;
        let custom = Routing::from_dual(move |s, _| [(s * w).cos() * 0.008, (s * w).sin() * 0.008]);
        let robot = Robot::new(rod()).with_tendon(Tendon::new(custom, 1.0));
        let r = required(&robot);
        assert_eq!(r.intervals, 40);
        assert_eq!(r.feature, Some(Feature::Routing(0)));
    }

    #[test]
    fn precurvature_counts_and_straight_robots_need_one_interval() {
        let bent = Robot::new(rod().with_precurvature(Vector3::new(0.0, 20.0 * PI, 0.0)));
        let r = required(&bent);
        // 4 pi rad over the rod in quarter turns: 8 intervals
        assert_eq!((r.intervals, r.feature), (8, Some(Feature::Precurvature)));
        let straight = Robot::new(rod()).with_tendon(Tendon::new(Routing::straight(0.008, 0.0), 1.0));
        let r = required(&straight);
        assert_eq!((r.intervals, r.feature, r.rate), (1, None, 0.0));
        assert!(r.longest_interval().is_infinite());
    }
}
