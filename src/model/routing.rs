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
    /// A helix: x = radius cos(2 pi turns s / L + phase), y = radius sin(...), with L the
    /// rod length.
    ///
    /// `turns` is a rate: turns per rod length L, not the turns of any one tendon. A tendon
    /// on this routing that ends at l <= L makes `turns * l / L` turns ([`Tendon::turns`]
    /// gives that number): `turns = 1` on a tendon ending at L/2 is half a turn. The rate
    /// does not depend on where a tendon ends, so moving an end keeps the helix's pitch.
    ///
    /// [`Tendon::turns`]: crate::model::tendon::Tendon::turns
    Helical {
        /// Radius, m.
        radius: f64,
        /// Turns per rod length L (the helix turns by 2 pi `turns` over s in [0, L]);
        /// negative: left-handed. Not the turns of a tendon that ends before the tip.
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

    /// A straight routing at `radius` (m) from the backbone, at `angle_deg` (degrees) from
    /// body x toward body y: (x, y) = radius (cos, sin) of the angle. The cosine and sine are
    /// exact where they are simple numbers: at multiples of 90 degrees one of them is exactly
    /// 0 (not the 6.1e-17 of `cos(pi / 2)`), at 30 degrees off an axis the sine is exactly
    /// 1/2, so a tendon at 120 degrees has x = -radius / 2 exactly.
    ///
    /// # Examples
    /// ```
    /// use tdcr::Routing;
    /// let r = Routing::polar(0.008, 90.0).at(0.0, 0.2).r;
    /// assert_eq!((r.x, r.y), (0.0, 0.008));
    /// let r = Routing::polar(0.008, 240.0).at(0.0, 0.2).r;
    /// assert_eq!(r.x, -0.004);
    /// ```
    pub fn polar(radius: f64, angle_deg: f64) -> Self {
        let (cos, sin) = cos_sin_degrees(angle_deg);
        Routing::Straight {
            x: radius * cos,
            y: radius * sin,
        }
    }

    /// A helical routing of `radius` (m) at `turns` turns per rod length L (the angle
    /// advances by 2 pi `turns` over s in [0, L], whatever the tendon's end), starting at
    /// angle `phase` (rad); turns < 0 is left-handed. A tendon ending at l makes
    /// `turns * l / L` turns: for one full turn on a tendon that ends at L/2, give
    /// `turns = 2`.
    ///
    /// # Examples
    /// ```
    /// use tdcr::{Routing, Tendon};
    /// // 1 turn per rod length on a tendon that ends half-way: half a turn.
    /// let tendon = Tendon::new(Routing::helical(0.008, 1.0, 0.0), 1.0).ending_at(0.121);
    /// assert_eq!(tendon.turns(0.242), 0.5);
    /// ```
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

    /// The signed turns this routing makes about the backbone between arc lengths `from` and
    /// `to` (m) on a rod of `length` L (m): the winding angle of r(s) in the cross-section
    /// divided by 2 pi (negative: left-handed). 0 for a straight routing, `turns (to - from) / L`
    /// for a helix; for a custom routing the angle unwrapped on a grid fine enough that no
    /// step exceeds pi/4 (then every unwrapped step is the true one), exact to rounding for a
    /// routing that does not pass through the backbone.
    pub fn turns_between(&self, from: f64, to: f64, length: f64) -> f64 {
        match self {
            Routing::Straight { .. } => 0.0,
            Routing::Helical { turns, .. } => turns * (to - from) / length,
            Routing::Custom(_) => self.winding(from, to, length),
        }
    }

    /// The winding of r(s) for s from `from` to `to` (m), in turns, unwrapped numerically: 4096 steps,
    /// doubled until no step turns by more than pi/4 (at most 2^22 steps). Points on the
    /// backbone (r = 0) have no angle and are skipped.
    fn winding(&self, from: f64, to: f64, length: f64) -> f64 {
        let angle = |s: f64| {
            let r = self.at(s, length).r;
            (r.norm() > 0.0).then(|| r.y.atan2(r.x))
        };
        let mut count = 4096;
        loop {
            let (mut total, mut largest) = (0.0, 0.0f64);
            let mut previous = angle(from);
            for k in 1..=count {
                let current = angle(from + (to - from) * k as f64 / count as f64);
                if let (Some(a), Some(b)) = (previous, current) {
                    let step = (b - a + PI).rem_euclid(2.0 * PI) - PI;
                    total += step;
                    largest = largest.max(step.abs());
                }
                previous = current.or(previous);
            }
            if largest <= PI / 4.0 || count >= 1 << 22 {
                return total / (2.0 * PI);
            }
            count *= 2;
        }
    }

    /// The largest offset |r(s)| (m) of the routing from the backbone over s in [0, `end`]
    /// on a rod of `length` L (m): exact for straight and helical routings, the largest of
    /// 65 samples for a custom one.
    pub fn max_offset(&self, end: f64, length: f64) -> f64 {
        match self {
            Routing::Straight { x, y } => x.hypot(*y),
            Routing::Helical { radius, .. } => radius.abs(),
            Routing::Custom(_) => (0..=64)
                .map(|k| self.at(end * f64::from(k) / 64.0, length).r.norm())
                .fold(0.0, f64::max),
        }
    }

    /// r, r', r'' at arc length `s` of a rod of `length` L (m).
    ///
    /// Inlined for a straight routing (a constant point: its call cost more than its
    /// copies, and eq. 13 evaluates it for every taut tendon at every point); the other
    /// routings are evaluated by a call (`curved_at`), so that their sines and
    /// cosines are not inlined where they are rare.
    #[inline(always)]
    pub fn at(&self, s: f64, length: f64) -> RoutingPoint {
        match self {
            Routing::Straight { x, y } => RoutingPoint {
                r: Vector3::new(*x, *y, 0.0),
                r_s: Vector3::zeros(),
                r_ss: Vector3::zeros(),
            },
            _ => self.curved_at(s, length),
        }
    }

    /// [`Routing::at`] of a routing that is not straight.
    #[inline(never)]
    fn curved_at(&self, s: f64, length: f64) -> RoutingPoint {
        match self {
            Routing::Straight { .. } => self.at(s, length),
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

/// cos and sin of `angle` in degrees, reduced to within 45 degrees of an axis first so that
/// multiples of 90 degrees give exact zeros and ones, and 30 degrees off an axis an exact 1/2
/// for the sine (the cosine is then sqrt(3)/2 rounded once). Within rounding of
/// `angle.to_radians().sin_cos()` everywhere else.
fn cos_sin_degrees(angle: f64) -> (f64, f64) {
    let turned = angle.rem_euclid(360.0);
    let quadrant = (turned / 90.0).round();
    let rest = turned - 90.0 * quadrant;
    let (cos, sin) = if rest.abs() == 30.0 {
        (0.75f64.sqrt(), 0.5f64.copysign(rest))
    } else {
        let (sin, cos) = rest.to_radians().sin_cos();
        (cos, sin)
    };
    // Turn by `quadrant` right angles exactly: (c, s) -> (-s, c) per quarter turn.
    let (cos, sin) = match quadrant as i64 {
        1 => (-sin, cos),
        2 => (-cos, -sin),
        3 => (sin, -cos),
        _ => (cos, sin),
    };
    // + 0.0 makes a negated exact zero +0, which prints as `0`, not `-0`.
    (cos + 0.0, sin + 0.0)
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

    /// Issue 17: `turns` counts per rod length; a tendon ending at L/2 on `turns = 1` makes
    /// half a turn, and the routing's angle at its end says so.
    #[test]
    fn helix_turns_count_per_rod_length() {
        use crate::model::tendon::Tendon;
        let length = 0.242;
        let helix = Routing::helical(0.008, 1.0, 0.0);
        let half = Tendon::new(helix.clone(), 1.0).ending_at(length / 2.0);
        assert_eq!(half.turns(length), 0.5);
        assert_eq!(Tendon::new(helix.clone(), 1.0).turns(length), 1.0);
        // The path itself: at L/2 the offset points the opposite way from the base (pi rad).
        let (base, end) = (helix.at(0.0, length).r, helix.at(length / 2.0, length).r);
        // 1e-15: cos(pi) rounds to -1 within an ulp of the 8 mm radius
        assert_relative_eq!(end, -base, epsilon = 1e-15);
        assert_eq!(Tendon::new(Routing::straight(0.008, 0.0), 1.0).turns(length), 0.0);
        assert_eq!(
            Routing::helical(0.008, -3.0, 0.0).turns_between(0.0, length / 3.0, length),
            -1.0
        );
    }

    /// Issue 27: polar placements give exact zeros on the axes and exact halves at 30
    /// degrees off them, and agree with the radian formula everywhere.
    #[test]
    fn polar_offsets_are_exact_where_simple() {
        let offset = |deg: f64| {
            let r = Routing::polar(0.01, deg).at(0.0, 0.4).r;
            (r.x, r.y)
        };
        assert_eq!(offset(0.0), (0.01, 0.0));
        assert_eq!(offset(90.0), (0.0, 0.01));
        assert!(offset(90.0).0.is_sign_positive() && offset(180.0).1.is_sign_positive());
        assert_eq!(offset(180.0), (-0.01, 0.0));
        assert_eq!(offset(-90.0), (0.0, -0.01));
        assert_eq!(offset(450.0), (0.0, 0.01));
        assert_eq!(offset(120.0).0, -0.005);
        assert_eq!(offset(240.0).0, -0.005);
        assert_eq!(offset(30.0).1, 0.005);
        assert_eq!(offset(330.0).1, -0.005);
        for deg in (-720..=720).map(|k| f64::from(k) * 0.7) {
            let (x, y) = offset(deg);
            let (sin, cos) = deg.to_radians().sin_cos();
            // 2e-17 m: the radian formula's own rounding of deg * pi / 180 (up to ~1e-15 rad
            // at 504 degrees) on the 1 cm radius, plus a few ulps
            assert!(
                (x - 0.01 * cos).abs() < 2e-17 && (y - 0.01 * sin).abs() < 2e-17,
                "{deg}"
            );
        }
    }

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
