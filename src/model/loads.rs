//! External loads: distributed force and moment per unit length, tip and interior point
//! wrenches, all in the world frame (dead loads); and follower loads, fixed in the body
//! frame, which turn with the rod (a tip force that follows the tip, a pressure-like force
//! per length), which are not conservative (docs/stability.md).

use nalgebra::Vector3;
use std::fmt;
use std::sync::Arc;

/// A vector quantity along the backbone: constant or a function of s (m).
#[derive(Clone)]
pub enum Field {
    /// The same value everywhere.
    Constant(Vector3<f64>),
    /// A function of arc length.
    Varying(Arc<dyn Fn(f64) -> Vector3<f64> + Send + Sync>),
}

impl Field {
    /// Value at s.
    pub fn at(&self, s: f64) -> Vector3<f64> {
        match self {
            Field::Constant(v) => *v,
            Field::Varying(f) => f(s),
        }
    }

    /// Whether the field is taken as absent on [0, `length`]: a constant one when it is
    /// zero, a varying one when it vanishes at the ends and midpoints of every interval of a
    /// 64-interval grid (129 samples).
    pub(crate) fn vanishes_on(&self, length: f64) -> bool {
        match self {
            Field::Constant(v) => *v == Vector3::zeros(),
            Field::Varying(_) => (0..=128).all(|i| self.at(length * i as f64 / 128.0) == Vector3::zeros()),
        }
    }
}

impl fmt::Debug for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Field::Constant(v) => write!(f, "Constant({}, {}, {})", v[0], v[1], v[2]),
            Field::Varying(_) => f.write_str("Varying(<fn>)"),
        }
    }
}

/// A point force and moment applied at an interior arc length (world frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad {
    /// Arc length where it acts (m), in (0, L).
    pub s: f64,
    /// Force (N), world frame.
    pub force: Vector3<f64>,
    /// Moment (N m), world frame.
    pub moment: Vector3<f64>,
}

/// All external loads on the backbone.
#[derive(Clone, Debug)]
pub struct Loads {
    /// f_e: distributed force per unit length (N/m), world frame.
    pub distributed_force: Field,
    /// l_e: distributed moment per unit length (N m/m), world frame.
    pub distributed_moment: Field,
    /// Force at the tip (N), world frame.
    pub tip_force: Vector3<f64>,
    /// Moment at the tip (N m), world frame.
    pub tip_moment: Vector3<f64>,
    /// Point wrenches at interior arc lengths.
    pub point: Vec<PointLoad>,
    /// Follower force at the tip (N), tip body frame: n(L) gains R(L) times it.
    pub follower_tip_force: Vector3<f64>,
    /// Follower moment at the tip (N m), tip body frame: m(L) gains R(L) times it.
    pub follower_tip_moment: Vector3<f64>,
    /// Follower force per unit length (N/m), body frame at s: the distributed force
    /// R(s) times it (a pressure-like load that turns with the cross-section).
    pub follower_distributed_force: Field,
}

impl Default for Loads {
    fn default() -> Self {
        Self::none()
    }
}

impl Loads {
    /// No external load.
    pub fn none() -> Self {
        Loads {
            distributed_force: Field::Constant(Vector3::zeros()),
            distributed_moment: Field::Constant(Vector3::zeros()),
            tip_force: Vector3::zeros(),
            tip_moment: Vector3::zeros(),
            point: Vec::new(),
            follower_tip_force: Vector3::zeros(),
            follower_tip_moment: Vector3::zeros(),
            follower_distributed_force: Field::Constant(Vector3::zeros()),
        }
    }

    /// Self weight: `weight_per_length` (N/m) along the world direction `down` (normalized here).
    pub fn self_weight(weight_per_length: f64, down: Vector3<f64>) -> Self {
        Loads {
            distributed_force: Field::Constant(down.normalize() * weight_per_length),
            ..Self::none()
        }
    }

    /// The same loads plus a tip force (N, world frame).
    pub fn with_tip_force(mut self, force: Vector3<f64>) -> Self {
        self.tip_force = force;
        self
    }

    /// The same loads plus a follower tip force (N, tip body frame).
    pub fn with_follower_tip_force(mut self, force: Vector3<f64>) -> Self {
        self.follower_tip_force = force;
        self
    }

    /// The same loads plus a follower tip moment (N m, tip body frame).
    pub fn with_follower_tip_moment(mut self, moment: Vector3<f64>) -> Self {
        self.follower_tip_moment = moment;
        self
    }

    /// Whether any follower load is present (the distributed one sampled at the ends and
    /// midpoints of every interval of a 64-interval grid over `length`).
    pub fn has_follower(&self, length: f64) -> bool {
        self.follower_tip_force != Vector3::zeros()
            || self.follower_tip_moment != Vector3::zeros()
            || !self.follower_distributed_force.vanishes_on(length)
    }

    /// The same loads plus a tip moment (N m, world frame).
    pub fn with_tip_moment(mut self, moment: Vector3<f64>) -> Self {
        self.tip_moment = moment;
        self
    }
}
