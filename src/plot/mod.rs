//! Pictures of solved shapes as hand-written SVG: three orthographic views (top XY, side
//! XZ, front YZ, all at one scale) and a perspective view, with a legend and a scale bar.
//!
//! ```
//! use tdcr::plot::{Figure, Style};
//! let robot = tdcr::cases::case_s();
//! let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
//! let mut figure = Figure::new("case S");
//! figure.add_shape(&robot, &solution, &Style::new("#1f77b4"));
//! let svg = figure.to_svg();
//! assert!(svg.starts_with("<svg") && svg.contains("perspective"));
//! ```

use crate::{Robot, Solution};
use nalgebra::{Vector2, Vector3};
use std::fmt::Write;

/// Points per metre of backbone drawn, at least [`MIN_SAMPLES`]: 1 mm spacing on the
/// prototype, far below a pixel's worth of Hermite interpolation error.
const SAMPLES_PER_METRE: f64 = 1000.0;
/// Fewest backbone points drawn per shape.
const MIN_SAMPLES: usize = 200;

/// Colours for tendon numbers 1, 2, ... (cycled), from the Tableau 10 palette.
pub const PALETTE: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
];

/// A polyline in world coordinates (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// Points (m), world frame.
    pub points: Vec<Vector3<f64>>,
    /// SVG colour.
    pub color: String,
    /// Stroke width (px).
    pub width: f64,
    /// SVG dash pattern (`"6 3"`), `None` for solid.
    pub dash: Option<String>,
    /// Opacity in [0, 1].
    pub opacity: f64,
}

/// A dot at a world point (m).
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// Position (m), world frame.
    pub point: Vector3<f64>,
    /// SVG colour.
    pub color: String,
    /// Radius (px).
    pub radius: f64,
}

/// One legend line: a stroke sample and its label.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// Text.
    pub label: String,
    /// SVG colour.
    pub color: String,
    /// SVG dash pattern, `None` for solid.
    pub dash: Option<String>,
}

/// How [`Figure::add_shape`] draws one solution.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    /// Backbone colour.
    pub color: String,
    /// Backbone dash pattern, `None` for solid.
    pub dash: Option<String>,
    /// Draw tendons with zero tension too (dotted and faint). Default false.
    pub slack_tendons: bool,
    /// Colour tendons by their number from [`PALETTE`] rather than with the backbone's
    /// colour. Default false.
    pub tendon_colors: bool,
    /// Backbone opacity. Default 1.
    pub opacity: f64,
}

impl Style {
    /// A solid backbone in `color` with its pulled tendons drawn along.
    pub fn new(color: &str) -> Self {
        Style {
            color: color.to_string(),
            dash: None,
            slack_tendons: false,
            tendon_colors: false,
            opacity: 1.0,
        }
    }
}

/// A picture of shapes and curves in four views.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Figure {
    /// Title line.
    pub title: String,
    /// Lines under the title (e.g. the solver used).
    pub subtitle: Vec<String>,
    /// Curves, drawn in order.
    pub curves: Vec<Curve>,
    /// Markers, drawn over the curves.
    pub markers: Vec<Marker>,
    /// Legend entries, under the views.
    pub legend: Vec<LegendEntry>,
    /// Where the world axes are drawn in the perspective view (m); the first base drawn if
    /// `None`.
    pub origin: Option<Vector3<f64>>,
}

/// The four views, in panel order.
#[derive(Clone, Copy, PartialEq)]
enum View {
    Top,
    Side,
    Front,
    Perspective,
}

impl View {
    fn title(self) -> &'static str {
        match self {
            View::Top => "top view (XY)",
            View::Side => "side view (XZ)",
            View::Front => "front view (YZ)",
            View::Perspective => "perspective",
        }
    }

    /// Axis names (horizontal, vertical) of an orthographic view.
    fn axes(self) -> (&'static str, &'static str) {
        match self {
            View::Top => ("x", "y"),
            View::Side => ("x", "z"),
            View::Front => ("y", "z"),
            View::Perspective => ("", ""),
        }
    }
}

/// Panel size and margins (px).
const PANEL: f64 = 460.0;
const MARGIN: f64 = 30.0;
const HEADER: f64 = 70.0;

/// A projection of world points to panel pixels.
struct Projection {
    view: View,
    camera: Camera,
    scale: f64,
    offset: Vector2<f64>,
}

/// The perspective camera: eye position and orthonormal right, up, forward axes.
#[derive(Clone, Copy)]
struct Camera {
    eye: Vector3<f64>,
    right: Vector3<f64>,
    up: Vector3<f64>,
    forward: Vector3<f64>,
}

impl Camera {
    /// A camera looking at `center` from azimuth -60 deg and elevation 25 deg (the x-z plane
    /// seen obliquely, z up), at 4 times the scene radius so the distortion stays mild.
    fn new(center: Vector3<f64>, radius: f64) -> Self {
        let (az, el) = ((-60.0f64).to_radians(), 25.0f64.to_radians());
        let dir = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        let eye = center + dir * (4.0 * radius.max(1e-9));
        let forward = -dir;
        let right = forward.cross(&Vector3::z()).normalize();
        let up = right.cross(&forward);
        Camera {
            eye,
            right,
            up,
            forward,
        }
    }

    fn project(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let q = p - self.eye;
        // Points behind the eye cannot occur (the eye is 4 radii out); guard the division.
        let depth = q.dot(&self.forward).max(1e-12);
        Vector2::new(q.dot(&self.right), q.dot(&self.up)) / depth
    }
}

impl Projection {
    /// Unscaled 2-D coordinates, vertical up.
    fn raw(&self, p: &Vector3<f64>) -> Vector2<f64> {
        match self.view {
            View::Top => Vector2::new(p.x, p.y),
            View::Side => Vector2::new(p.x, p.z),
            View::Front => Vector2::new(p.y, p.z),
            View::Perspective => self.camera.project(p),
        }
    }

    /// Pixel coordinates inside the panel, y down.
    fn px(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let r = self.raw(p) * self.scale + self.offset;
        Vector2::new(r.x, PANEL - r.y)
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A round length (m) close to `target`: 1, 2 or 5 times a power of ten.
fn round_length(target: f64) -> f64 {
    let power = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * power)
        .find(|&l| l <= target)
        .unwrap_or(power)
}

impl Figure {
    /// An empty figure with a title.
    pub fn new(title: &str) -> Self {
        Figure {
            title: title.to_string(),
            ..Default::default()
        }
    }

    /// Adds a solved shape: the backbone sampled densely with [`Solution::at`], the paths of
    /// the pulled tendons ([`Solution::tendon_paths`]) thin alongside, a square at the base
    /// and a dot at the tip.
    pub fn add_shape(&mut self, robot: &Robot, solution: &Solution, style: &Style) {
        let length = solution.length();
        let count = ((length * SAMPLES_PER_METRE) as usize).max(MIN_SAMPLES);
        let backbone = (0..=count)
            .map(|k| solution.at(length * k as f64 / count as f64).p)
            .collect();
        for (i, (tendon, path)) in robot.tendons.iter().zip(&solution.tendon_paths).enumerate() {
            let pulled = tendon.tension > 0.0;
            if !pulled && !style.slack_tendons {
                continue;
            }
            let color = if style.tendon_colors {
                PALETTE[i % PALETTE.len()]
            } else {
                &style.color
            };
            self.curves.push(Curve {
                points: path.clone(),
                color: color.to_string(),
                width: if pulled { 1.0 } else { 0.7 },
                dash: if pulled { None } else { Some("1 2".into()) },
                opacity: if pulled { 0.6 } else { 0.4 } * style.opacity,
            });
        }
        self.curves.push(Curve {
            points: backbone,
            color: style.color.clone(),
            width: 1.8,
            dash: style.dash.clone(),
            opacity: style.opacity,
        });
        self.origin.get_or_insert(solution.base().p);
        self.markers.push(Marker {
            point: solution.tip().p,
            color: style.color.clone(),
            radius: 2.5,
        });
    }

    /// Every point drawn.
    fn points(&self) -> impl Iterator<Item = &Vector3<f64>> {
        self.curves
            .iter()
            .flat_map(|c| c.points.iter())
            .chain(self.markers.iter().map(|m| &m.point))
            .chain(self.origin.iter())
            .filter(|p| p.iter().all(|x| x.is_finite()))
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
        for p in self.points() {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo.x > hi.x {
            (lo, hi) = (Vector3::zeros(), Vector3::zeros());
        }
        let extent = (hi - lo).amax().max(1e-6);
        let center = (lo + hi) / 2.0;
        let camera = Camera::new(center, (hi - lo).norm() / 2.0);
        let axis_length = round_length(extent / 4.0);
        let origin = self.origin.unwrap_or(lo);
        let inner = PANEL - 2.0 * MARGIN;

        let legend_rows = self.legend.len().div_ceil(3);
        let width = 2.0 * PANEL + 3.0 * MARGIN;
        let height = HEADER + 2.0 * PANEL + MARGIN + 22.0 * legend_rows as f64 + 20.0;
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="Helvetica, Arial, sans-serif" font-size="12">"#
        );
        let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{MARGIN}" y="26" font-size="17" font-weight="bold">{}</text>"#,
            escape(&self.title)
        );
        for (k, line) in self.subtitle.iter().enumerate() {
            let _ = writeln!(
                svg,
                r##"<text x="{MARGIN}" y="{}" fill="#444">{}</text>"##,
                46 + 16 * k,
                escape(line)
            );
        }
        for (k, view) in [View::Top, View::Side, View::Front, View::Perspective]
            .into_iter()
            .enumerate()
        {
            let x0 = MARGIN + (k % 2) as f64 * (PANEL + MARGIN);
            let y0 = HEADER + (k / 2) as f64 * PANEL;
            let mut projection = Projection {
                view,
                camera,
                scale: 1.0,
                offset: Vector2::zeros(),
            };
            // Orthographic views share one scale (mm per px) so they can be compared; the
            // perspective view is fitted on its own.
            let extras: Vec<Vector3<f64>> = if view == View::Perspective {
                (0..3).map(|a| origin + Vector3::ith(a, axis_length * 1.2)).collect()
            } else {
                Vec::new()
            };
            let all: Vec<Vector2<f64>> = self.points().chain(extras.iter()).map(|p| projection.raw(p)).collect();
            let (mut a, mut b) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
            for q in &all {
                a = a.inf(q);
                b = b.sup(q);
            }
            if a.x > b.x {
                (a, b) = (Vector2::zeros(), Vector2::zeros());
            }
            projection.scale = if view == View::Perspective {
                inner / (b - a).amax().max(1e-12)
            } else {
                inner / extent
            };
            projection.offset = Vector2::repeat(PANEL / 2.0) - (a + b) / 2.0 * projection.scale;
            self.panel(&mut svg, &projection, x0, y0, axis_length, &origin);
        }
        let top = HEADER + 2.0 * PANEL + MARGIN;
        for (k, entry) in self.legend.iter().enumerate() {
            let x = MARGIN + (k % 3) as f64 * (width - 2.0 * MARGIN) / 3.0;
            let y = top + 22.0 * (k / 3) as f64;
            let dash = entry
                .dash
                .as_ref()
                .map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#));
            let _ = writeln!(
                svg,
                r#"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="{}" stroke-width="2.5"{dash}/><text x="{}" y="{}">{}</text>"#,
                x + 28.0,
                entry.color,
                x + 36.0,
                y + 4.0,
                escape(&entry.label)
            );
        }
        svg.push_str("</svg>\n");
        svg
    }

    fn panel(&self, svg: &mut String, pr: &Projection, x0: f64, y0: f64, axis_length: f64, origin: &Vector3<f64>) {
        let _ = writeln!(svg, r#"<g transform="translate({x0:.1},{y0:.1})">"#);
        let _ = writeln!(
            svg,
            r##"<rect x="0" y="0" width="{PANEL}" height="{PANEL}" fill="none" stroke="#bbb"/><text x="8" y="18" font-weight="bold">{}</text>"##,
            pr.view.title()
        );
        for c in &self.curves {
            let points: Vec<String> = c
                .points
                .iter()
                .filter(|p| p.iter().all(|x| x.is_finite()))
                .map(|p| {
                    let q = pr.px(p);
                    format!("{:.2},{:.2}", q.x, q.y)
                })
                .collect();
            if points.len() < 2 {
                continue;
            }
            let dash = c
                .dash
                .as_ref()
                .map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#));
            let _ = writeln!(
                svg,
                r#"<polyline fill="none" stroke="{}" stroke-width="{}" stroke-opacity="{}" stroke-linejoin="round"{dash} points="{}"/>"#,
                c.color,
                c.width,
                c.opacity,
                points.join(" ")
            );
        }
        for m in &self.markers {
            if m.point.iter().all(|x| x.is_finite()) {
                let q = pr.px(&m.point);
                let _ = writeln!(
                    svg,
                    r#"<circle cx="{:.2}" cy="{:.2}" r="{}" fill="{}"/>"#,
                    q.x, q.y, m.radius, m.color
                );
            }
        }
        let b = pr.px(origin);
        let _ = writeln!(
            svg,
            r#"<rect x="{:.2}" y="{:.2}" width="7" height="7" fill="black"/>"#,
            b.x - 3.5,
            b.y - 3.5
        );
        if pr.view == View::Perspective {
            for (a, name) in ["x", "y", "z"].iter().enumerate() {
                let tip = origin + Vector3::ith(a, axis_length);
                let label = origin + Vector3::ith(a, axis_length * 1.15);
                let (q, l) = (pr.px(&tip), pr.px(&label));
                let _ = writeln!(
                    svg,
                    r##"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="black" stroke-width="1.5"/><text x="{:.2}" y="{:.2}" text-anchor="middle" font-weight="bold" stroke="white" stroke-width="3" paint-order="stroke">{name}</text>"##,
                    b.x,
                    b.y,
                    q.x,
                    q.y,
                    l.x,
                    l.y + 4.0
                );
            }
            let _ = writeln!(
                svg,
                r##"<text x="8" y="{}" fill="#555">world axes at the base, {} mm long</text>"##,
                PANEL - 10.0,
                axis_length * 1e3
            );
        } else {
            let (h, v) = pr.view.axes();
            let bar = axis_length * pr.scale;
            let y = PANEL - 14.0;
            let _ = writeln!(
                svg,
                r##"<line x1="12" y1="{y}" x2="{:.2}" y2="{y}" stroke="black" stroke-width="2"/><text x="{:.2}" y="{}">{} mm</text>"##,
                12.0 + bar,
                18.0 + bar,
                y + 4.0,
                axis_length * 1e3
            );
            let _ = writeln!(
                svg,
                r##"<text x="{}" y="{}" text-anchor="end" fill="#555">{h} &#8594;</text><text x="{}" y="34" text-anchor="end" fill="#555">{v} &#8593;</text>"##,
                PANEL - 8.0,
                PANEL - 10.0,
                PANEL - 8.0
            );
        }
        svg.push_str("</g>\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_lengths_are_one_two_five() {
        for (target, round) in [(0.06, 0.05), (0.025, 0.02), (0.0013, 0.001), (7.0, 5.0)] {
            // 1e-12: powers of ten are not exact in binary
            assert!((round_length(target) / round - 1.0).abs() < 1e-12, "{target}");
        }
    }

    #[test]
    fn perspective_keeps_the_centre_on_the_axis() {
        let c = Camera::new(Vector3::new(0.1, 0.0, -0.1), 0.2);
        let q = c.project(&Vector3::new(0.1, 0.0, -0.1));
        // 1e-12: the centre lies on the optical axis up to rounding
        assert!(q.norm() < 1e-12);
    }
}
