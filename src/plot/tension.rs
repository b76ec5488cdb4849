//! Tendons with friction drawn by their tension (when tendons have their own colours): the path in pieces whose width follows
//! tau(s) / tau_max and whose colour lightens from the tendon's own colour (highest tension)
//! toward white (lowest), one hue, so it reads in greyscale and for colour-blind readers;
//! and the legend words that give the tension at the base entry and the delivered one
//! (docs/cli.md, "Pictures"; docs/friction.md).

use super::axes::significant;
use super::{Curve, LegendEntry, Style, Symbol};
use crate::model::tendon::Motion;
use crate::{Robot, Solution};
use nalgebra::Vector3;

/// Pieces a tendon with friction is drawn in: each has one width and one shade.
const PIECES: usize = 40;
/// Stroke width (px) of a tendon with friction where its tension is highest.
pub(super) const FRICTION_WIDTH: f64 = 2.0;
/// Share of white mixed into the tendon's colour where its tension is lowest.
pub(super) const LIGHTEST: f64 = 0.55;
/// A tension range of at least this share of the highest tension spans the whole shading
/// ramp; a smaller one spans that share of it, so a tiny variation stays a tiny change.
const FULL_RAMP: f64 = 0.1;

/// The tension of one tendon with friction along its path, as drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Profile {
    /// Tension at the base entry (N): the actuator's side.
    pub(super) entry: f64,
    /// Tension at the termination (N): what the tendon delivers.
    pub(super) delivered: f64,
    /// Lowest and highest tension along the path (N).
    pub(super) low: f64,
    pub(super) high: f64,
}

impl Profile {
    /// Share of white mixed into the colour at tension `tau`: 0 at the highest tension,
    /// [`LIGHTEST`] at the lowest when they differ by [`FULL_RAMP`] of the highest or more.
    pub(super) fn shade(&self, tau: f64) -> f64 {
        let range = (self.high - self.low).max(FULL_RAMP * self.high);
        (LIGHTEST * (self.high - tau) / range).clamp(0.0, LIGHTEST)
    }

    /// Stroke width (px) at tension `tau`: [`FRICTION_WIDTH`] times tau / tau_max.
    pub(super) fn width(&self, tau: f64) -> f64 {
        FRICTION_WIDTH * (tau / self.high).clamp(0.0, 1.0)
    }
}

/// The tension profile of tendon `index` when `style` draws it by its tension: tendons have
/// their own colours ([`Style::tendon_colors`]; a picture of many shapes in one colour, a
/// sweep's, draws them as lines) and this one is `pulled` and has a [`profile`].
pub(super) fn shaded(robot: &Robot, solution: &Solution, index: usize, style: &Style, pulled: bool) -> Option<Profile> {
    if style.tendon_colors && pulled {
        profile(robot, solution, index)
    } else {
        None
    }
}

/// The tension profile of tendon `index` when it is drawn by its tension: it has friction
/// ([`crate::Tendon::active_friction`]), is taut and its solved tensions are finite; `None`
/// otherwise (a frictionless tendon is drawn as one line).
pub(super) fn profile(robot: &Robot, solution: &Solution, index: usize) -> Option<Profile> {
    robot.tendons.get(index)?.active_friction()?;
    let tensions = solution.tendon_tensions.get(index)?;
    let state = solution.tendons.get(index)?;
    if tensions.is_empty() || tensions.iter().any(|t| !t.is_finite()) {
        return None;
    }
    let low = tensions.iter().copied().fold(f64::INFINITY, f64::min);
    let high = tensions.iter().copied().fold(0.0, f64::max);
    (high > 0.0).then_some(Profile {
        entry: state.tension,
        delivered: state.delivered_tension,
        low,
        high,
    })
}

/// The path `points` of tendon `index` (evenly spaced in s from 0 to its end, as
/// [`super::tendon_path`] samples it) cut into pieces, each drawn at the tension of its
/// middle ([`Solution::tension_at`]); consecutive pieces share their end points.
pub(super) fn pieces(
    points: &[Vector3<f64>],
    end: f64,
    solution: &Solution,
    index: usize,
    profile: &Profile,
    color: &str,
    opacity: f64,
) -> Vec<Curve> {
    let intervals = points.len().saturating_sub(1);
    if intervals == 0 {
        return Vec::new();
    }
    let pieces = PIECES.min(intervals);
    (0..pieces)
        .map(|k| {
            let (a, b) = (k * intervals / pieces, (k + 1) * intervals / pieces);
            let s = end * (a + b) as f64 / (2 * intervals) as f64;
            let tau = solution.tension_at(index, s).unwrap_or(profile.high);
            Curve {
                points: points[a..=b].to_vec(),
                color: lighter(color, profile.shade(tau)),
                width: profile.width(tau),
                dash: None,
                opacity,
            }
        })
        .collect()
}

/// The legend entry of a tendon with friction: `description` is its routing, and the label
/// gives the friction, the motion and the tension at both ends, e.g. `tendon 1 (line darker
/// and wider where the tension is higher): straight at (8, 0) mm; friction 0.1, pulled in:
/// 2.94 N at the base -> 2.55 N delivered`.
pub(super) fn legend_entry(
    robot: &Robot,
    index: usize,
    profile: &Profile,
    description: &str,
    color: &str,
) -> LegendEntry {
    let friction = robot.tendons[index].active_friction();
    let (mu, motion) = friction.map_or((0.0, Motion::Pull), |f| (f.coefficient, f.motion));
    let motion = match motion {
        Motion::Pull => "pulled in",
        Motion::Release => "let out",
    };
    LegendEntry::new(
        Symbol::Ramp,
        &format!(
            "tendon {} (line darker and wider where the tension is higher): {description}; friction {}, {motion}: {} N at the base -> {} N delivered",
            index + 1,
            significant(mu),
            significant(profile.entry),
            significant(profile.delivered),
        ),
        color,
    )
    .width(FRICTION_WIDTH)
}

/// `color` with a share `white` of white mixed in, for `#rrggbb` and `#rgb` colours; any
/// other colour (a name) is returned as it is.
pub(super) fn lighter(color: &str, white: f64) -> String {
    let hex = color.strip_prefix('#').unwrap_or("");
    let digits: Vec<u32> = hex.chars().filter_map(|c| c.to_digit(16)).collect();
    let rgb = match (hex.len(), digits.len()) {
        (6, 6) => [0, 2, 4].map(|k| digits[k] * 16 + digits[k + 1]),
        (3, 3) => [0, 1, 2].map(|k| digits[k] * 17),
        _ => return color.to_string(),
    };
    let [r, g, b] = rgb.map(|c| (c as f64 + (255.0 - c as f64) * white.clamp(0.0, 1.0)).round() as u32);
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lighter_mixes_in_white_and_leaves_names_alone() {
        assert_eq!(lighter("#0072B2", 0.0), "#0072b2");
        assert_eq!(lighter("#000000", 0.5), "#808080");
        assert_eq!(lighter("#fff", 0.3), "#ffffff");
        assert_eq!(lighter("black", 0.5), "black");
    }

    #[test]
    fn the_ramp_spans_the_profile_and_a_small_range_only_a_little() {
        let wide = Profile {
            entry: 2.94,
            delivered: 2.55,
            low: 2.55,
            high: 2.94,
        };
        assert_eq!(wide.shade(2.94), 0.0);
        // 1e-12: (high - low) / (high - low) rounds to 1 within a few ulps
        assert!((wide.shade(2.55) - LIGHTEST).abs() < 1e-12);
        assert_eq!(wide.width(2.94), FRICTION_WIDTH);
        let narrow = Profile { low: 2.9106, ..wide };
        // 1 % of the highest tension is a tenth of FULL_RAMP: a tenth of the ramp (1e-12: rounding)
        assert!((narrow.shade(2.9106) - 0.1 * LIGHTEST).abs() < 1e-12);
    }
}
