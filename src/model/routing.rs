//! Tendon routings: where a tendon crosses each cross-section, r(s) = (x(s), y(s), 0) in the
//! body frame (eq. 6), with exact first and second derivatives.

use crate::Readable;
use nalgebra::Vector3;
use num_dual::{Dual2_64, second_derivative};
use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;

/// r, r' and r'' at one arc length (body frame; m, dimensionless, 1/m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoutingPoint {
    /// r(s), m.
    pub r: Vector3<f64>,
    /// dr/ds.
    pub r_s: Vector3<f64>,
    /// d2r/ds2, 1/m.
    pub r_ss: Vector3<f64>,
}

/// A user routing: maps (s, L) to r, r', r'' with exact derivatives.
pub type RoutingFn = dyn Fn(f64, f64) -> RoutingPoint + Send + Sync;

/// Where a tendon runs in the cross-section along the backbone.
#[derive(Clone)]
pub enum Routing {
    /// Parallel to the backbone at the fixed offset (x, y) (m).
    Straight {
        /// x offset, m.
        x: f64,
        /// y offset, m.
        y: f64,
    },
    /// A helix: x = radius cos(2 pi turns s / L + phase), y = radius sin(...).
    Helical {
        /// Radius, m.
        radius: f64,
        /// Turns over the rod length (negative: left-handed).
        turns: f64,
        /// Angle at s = 0, rad.
        phase: f64,
    },
    /// Any curve with exact derivatives.
    Custom(Arc<RoutingFn>),
}

impl Routing {
    /// A straight routing at body offset (x, y) (m).
    pub fn straight(x: f64, y: f64) -> Self {
        Routing::Straight { x, y }
    }

    /// A helical routing of `radius` (m) making `turns` turns over the rod length, starting
    /// at angle `phase` (rad); turns < 0 is left-handed.
    pub fn helical(radius: f64, turns: f64, phase: f64) -> Self {
        Routing::Helical { radius, turns, phase }
    }

    /// A routing with analytic derivatives supplied by the caller: `f(s, L)` returns r, r', r''.
    pub fn custom(f: impl Fn(f64, f64) -> RoutingPoint + Send + Sync + 'static) -> Self {
        Routing::Custom(Arc::new(f))
    }

    /// A routing written once as `(x(s), y(s))` over second-order dual numbers; r' and r''
    /// come out exact by automatic differentiation. `f(s, L)` gets the rod length L (m).
    pub fn from_dual(f: impl Fn(Dual2_64, f64) -> [Dual2_64; 2] + Send + Sync + 'static) -> Self {
        Routing::custom(move |s, length| {
            let (x, x_s, x_ss) = second_derivative(|t| f(t, length)[0], s);
            let (y, y_s, y_ss) = second_derivative(|t| f(t, length)[1], s);
            RoutingPoint {
                r: Vector3::new(x, y, 0.0),
                r_s: Vector3::new(x_s, y_s, 0.0),
                r_ss: Vector3::new(x_ss, y_ss, 0.0),
            }
        })
    }

    /// r, r', r'' at arc length `s` of a rod of `length` L (m).
    pub fn at(&self, s: f64, length: f64) -> RoutingPoint {
        match self {
            Routing::Straight { x, y } => RoutingPoint {
                r: Vector3::new(*x, *y, 0.0),
                r_s: Vector3::zeros(),
                r_ss: Vector3::zeros(),
            },
            Routing::Helical { radius, turns, phase } => {
                let w = 2.0 * PI * turns / length;
                let (sin, cos) = (w * s + phase).sin_cos();
                RoutingPoint {
                    r: Vector3::new(radius * cos, radius * sin, 0.0),
                    r_s: Vector3::new(-radius * w * sin, radius * w * cos, 0.0),
                    r_ss: Vector3::new(-radius * w * w * cos, -radius * w * w * sin, 0.0),
                }
            }
            Routing::Custom(f) => f(s, length),
        }
    }
}

impl fmt::Debug for Routing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Routing::Straight { x, y } => write!(f, "Straight {{ x: {}, y: {} }}", Readable(*x), Readable(*y)),
            Routing::Helical { radius, turns, phase } => write!(
                f,
                "Helical {{ radius: {}, turns: {}, phase: {} }}",
                Readable(*radius),
                Readable(*turns),
                Readable(*phase)
            ),
            Routing::Custom(_) => f.write_str("Custom(<fn>)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use num_dual::DualNum;

    #[test]
    fn helix_derivatives_match_dual_version() {
        let (radius, turns, phase, length) = (0.008, -1.5, 0.3, 0.242);
        let helix = Routing::helical(radius, turns, phase);
        let dual = Routing::from_dual(move |s, l| {
            let a = s * (2.0 * PI * turns / l) + phase;
            [a.cos() * radius, a.sin() * radius]
        });
        for &s in &[0.0, 0.05, 0.2] {
            let (a, b) = (helix.at(s, length), dual.at(s, length));
            // 1e-14: both are exact; only rounding differs
            assert_relative_eq!(a.r, b.r, epsilon = 1e-14);
            assert_relative_eq!(a.r_s, b.r_s, epsilon = 1e-14);
            assert_relative_eq!(a.r_ss, b.r_ss, epsilon = 1e-12);
        }
    }
}
