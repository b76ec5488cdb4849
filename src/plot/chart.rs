//! A 2D line chart (a traced branch: the parameter against a tip coordinate): ticks with
//! numbers on both axes, segments solid or dashed, point markers, a legend.

use super::axes::{significant, tick_step, ticks};
use super::png::{self, Png};
use super::text::escape;
use crate::error::Result;
use std::fmt::Write as _;

/// One drawn segment between two points (x, y) in the chart's units.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Start and end.
    pub ends: [(f64, f64); 2],
    /// Dashed (for example: unstable) or solid.
    pub dashed: bool,
    /// CSS colour.
    pub color: String,
}

/// A marked point with a label.
#[derive(Clone, Debug, PartialEq)]
pub struct Mark {
    /// Position (x, y) in the chart's units.
    pub at: (f64, f64),
    /// Text next to it.
    pub label: String,
    /// CSS colour.
    pub color: String,
}

/// A line chart.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Chart {
    /// Title, top left.
    pub title: String,
    /// Lines under the title.
    pub subtitle: Vec<String>,
    /// Axis labels (with units).
    pub x_label: String,
    /// Axis labels (with units).
    pub y_label: String,
    /// The segments.
    pub segments: Vec<Segment>,
    /// Marked points.
    pub marks: Vec<Mark>,
    /// Legend lines: (label, colour, dashed; `None` for a mark).
    pub legend: Vec<(String, String, Option<bool>)>,
}

const WIDTH: f64 = 760.0;
const HEIGHT: f64 = 520.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 30.0;
const TOP: f64 = 80.0;
const BOTTOM: f64 = 130.0;

impl Chart {
    /// The range of the data along one axis, padded by 5 % (a flat range gets +-1).
    fn range(&self, axis: usize) -> (f64, f64) {
        let values = self
            .segments
            .iter()
            .flat_map(|s| s.ends)
            .chain(self.marks.iter().map(|m| m.at))
            .map(|p| if axis == 0 { p.0 } else { p.1 });
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        if !lo.is_finite() || !hi.is_finite() {
            return (0.0, 1.0);
        }
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            1.0f64.max(lo.abs() * 0.05)
        };
        (lo - pad, hi + pad)
    }

    /// The chart as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let (x0, x1) = self.range(0);
        let (y0, y1) = self.range(1);
        let (w, h) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
        let px = |x: f64| LEFT + (x - x0) / (x1 - x0) * w;
        let py = |y: f64| TOP + (y1 - y) / (y1 - y0) * h;
        let mut out = String::new();
        let _ = writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
        );
        let _ = writeln!(out, r##"<rect width="100%" height="100%" fill="#ffffff"/>"##);
        let _ = writeln!(
            out,
            r#"<text x="16" y="26" font-size="17" font-weight="bold">{}</text>"#,
            escape(&self.title)
        );
        for (i, line) in self.subtitle.iter().enumerate() {
            let _ = writeln!(
                out,
                r##"<text x="16" y="{}" font-size="12" fill="#444444">{}</text>"##,
                46.0 + 16.0 * i as f64,
                escape(line)
            );
        }
        let _ = writeln!(
            out,
            r##"<rect x="{LEFT}" y="{TOP}" width="{w}" height="{h}" fill="none" stroke="#888888"/>"##
        );
        for (axis, (lo, hi)) in [(0, (x0, x1)), (1, (y0, y1))] {
            let step = tick_step(hi - lo, 6.0, 0.0);
            for t in ticks(lo, hi, step) {
                let label = escape(&significant(t));
                if axis == 0 {
                    let x = px(t);
                    let _ = writeln!(
                        out,
                        r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#eeeeee"/><text x="{x:.1}" y="{:.1}" font-size="11" text-anchor="middle">{label}</text>"##,
                        TOP + h,
                        TOP + h + 16.0
                    );
                } else {
                    let y = py(t);
                    let _ = writeln!(
                        out,
                        r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eeeeee"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{label}</text>"##,
                        LEFT + w,
                        LEFT - 6.0,
                        y + 4.0
                    );
                }
            }
        }
        let _ = writeln!(
            out,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle">{}</text>"#,
            LEFT + w / 2.0,
            TOP + h + 36.0,
            escape(&self.x_label)
        );
        let _ = writeln!(
            out,
            r#"<text x="20" y="{:.1}" font-size="13" text-anchor="middle" transform="rotate(-90 20 {:.1})">{}</text>"#,
            TOP + h / 2.0,
            TOP + h / 2.0,
            escape(&self.y_label)
        );
        for s in &self.segments {
            let [(a, b), (c, d)] = s.ends;
            let dash = if s.dashed { r#" stroke-dasharray="6 4""# } else { "" };
            let _ = writeln!(
                out,
                r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{}" stroke-width="2.2"{dash}/>"#,
                px(a),
                py(b),
                px(c),
                py(d),
                s.color
            );
        }
        for m in &self.marks {
            let (x, y) = (px(m.at.0), py(m.at.1));
            // Labels in the right half go to the left of their mark, so they stay inside.
            let (dx, anchor) = if x > LEFT + 0.5 * w {
                (-8.0, "end")
            } else {
                (8.0, "start")
            };
            let _ = writeln!(
                out,
                r#"<circle cx="{x:.2}" cy="{y:.2}" r="5" fill="none" stroke="{}" stroke-width="2"/><text x="{:.2}" y="{:.2}" font-size="11" fill="{}" text-anchor="{anchor}">{}</text>"#,
                m.color,
                x + dx,
                y - 6.0,
                m.color,
                escape(&m.label)
            );
        }
        for (i, (label, color, dashed)) in self.legend.iter().enumerate() {
            let y = TOP + h + 62.0 + 18.0 * i as f64;
            match dashed {
                Some(d) => {
                    let dash = if *d { r#" stroke-dasharray="6 4""# } else { "" };
                    let _ = writeln!(
                        out,
                        r#"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{color}" stroke-width="2.2"{dash}/>"#,
                        LEFT + 36.0
                    );
                }
                None => {
                    let _ = writeln!(
                        out,
                        r#"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="none" stroke="{color}" stroke-width="2"/>"#,
                        LEFT + 18.0
                    );
                }
            }
            let _ = writeln!(
                out,
                r#"<text x="{:.1}" y="{:.1}" font-size="12">{}</text>"#,
                LEFT + 46.0,
                y + 4.0,
                escape(label)
            );
        }
        out.push_str("</svg>\n");
        out
    }

    /// The chart as a PNG at `scale` pixels per SVG pixel.
    pub fn to_png(&self, scale: f64) -> Result<Png> {
        png::render(&self.to_svg(), scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_ticks_segments_marks_and_legend() {
        let chart = Chart {
            title: "branch".into(),
            x_label: "tension (N)".into(),
            y_label: "tip x (mm)".into(),
            segments: vec![
                Segment {
                    ends: [(0.0, 0.0), (1.0, 2.0)],
                    dashed: false,
                    color: "#1f77b4".into(),
                },
                Segment {
                    ends: [(1.0, 2.0), (0.5, 3.0)],
                    dashed: true,
                    color: "#1f77b4".into(),
                },
            ],
            marks: vec![Mark {
                at: (1.0, 2.0),
                label: "fold".into(),
                color: "#d62728".into(),
            }],
            legend: vec![("stable".into(), "#1f77b4".into(), Some(false))],
            ..Default::default()
        };
        let svg = chart.to_svg();
        assert_eq!(
            svg.matches("<line x1=").count() - svg.matches("stroke=\"#eeeeee\"").count(),
            3
        );
        assert_eq!(svg.matches("stroke-dasharray").count(), 1);
        assert!(svg.contains(">fold</text>") && svg.contains(">stable</text>") && svg.contains(">tension (N)</text>"));
        // Tick numbers on both axes: 0.5 on x, 2 on y.
        assert!(svg.contains(">0.5</text>") && svg.contains(">2</text>"), "{svg}");
    }
}
