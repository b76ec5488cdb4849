//! Force and distributed-load arrows in one cell: shaft and head, the symbol of a force along
//! the line of sight, and labels placed clear of the labels already placed, the markers and
//! the curves, inside the cell.

use super::scene::{Scene, finite};
use super::text::{FONT, halo_text, text_width};
use super::view::{Projection, View};
use super::{Arrow, ArrowKind};
use nalgebra::Vector2;
use std::fmt::Write;

/// One arrow: shaft and head in pixels from the projected tail and head; for a force along
/// the line of sight of an orthographic view, a circle with a dot (towards the viewer) or a
/// cross (away).
pub(super) fn arrow_svg(svg: &mut String, pr: &Projection, a: &Arrow, scene: &Scene, room: &mut Room) {
    if !finite(&a.point) || !finite(&a.vector) {
        return;
    }
    let (q0, q1) = (pr.px(&a.point), pr.px(&scene.arrow_head(a)));
    let d = q1 - q0;
    let length = d.norm();
    let (width, head, class) = match a.kind {
        ArrowKind::Force => (1.8, 9.0, "arrow"),
        ArrowKind::Distributed => (1.0, 5.0, "load-hint"),
    };
    let color = &a.color;
    let _ = writeln!(svg, r#"<g class="{class}">"#);
    // A force mostly along the line of sight (less than a third of it in the view's plane)
    // is a circle with a dot or a cross; any other arrow at least a head and a bit long.
    let along_sight =
        pr.view != View::Perspective && a.vector.dot(&pr.view.toward_viewer()).abs() > 0.94 * a.vector.norm();
    let (q1, d, length) = if !along_sight && length > 0.0 && length < head + 4.0 {
        let q1 = q0 + d * ((head + 4.0) / length);
        (q1, q1 - q0, head + 4.0)
    } else {
        (q1, d, length)
    };
    let label_at = if length < head || along_sight {
        if a.kind == ArrowKind::Force && pr.view != View::Perspective && along_sight {
            let toward = a.vector.dot(&pr.view.toward_viewer()) > 0.0;
            let _ = writeln!(
                svg,
                r#"<circle cx="{:.2}" cy="{:.2}" r="6" fill="white" stroke="{color}" stroke-width="1.5"/>"#,
                q0.x, q0.y
            );
            if toward {
                let _ = writeln!(
                    svg,
                    r#"<circle cx="{:.2}" cy="{:.2}" r="2" fill="{color}"/>"#,
                    q0.x, q0.y
                );
            } else {
                let k = 4.2;
                let _ = writeln!(
                    svg,
                    r#"<path d="M{:.2},{:.2}L{:.2},{:.2}M{:.2},{:.2}L{:.2},{:.2}" stroke="{color}" stroke-width="1.5"/>"#,
                    q0.x - k,
                    q0.y - k,
                    q0.x + k,
                    q0.y + k,
                    q0.x - k,
                    q0.y + k,
                    q0.x + k,
                    q0.y - k
                );
            }
            Some((q0 + Vector2::new(9.0, -9.0), Vector2::new(1.0, -1.0)))
        } else {
            None
        }
    } else {
        let u = d / length;
        let n = Vector2::new(-u.y, u.x);
        let shaft = q1 - u * (head * 0.8);
        let (b1, b2) = (q1 - u * head + n * (head * 0.42), q1 - u * head - n * (head * 0.42));
        let _ = writeln!(
            svg,
            r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{color}" stroke-width="{width}"/><polygon fill="{color}" points="{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}"/>"#,
            q0.x, q0.y, shaft.x, shaft.y, q1.x, q1.y, b1.x, b1.y, b2.x, b2.y
        );
        Some((q1 + u * 8.0, u))
    };
    if let (Some((at, u)), Some(label)) = (label_at, &a.label) {
        let anchor = if u.x > 0.35 {
            "start"
        } else if u.x < -0.35 {
            "end"
        } else {
            "middle"
        };
        let dy = if u.y > 0.35 {
            10.0
        } else if u.y < -0.35 {
            -2.0
        } else {
            4.0
        };
        let size = if a.kind == ArrowKind::Force { FONT } else { FONT - 1.0 };
        let w = text_width(label, size);
        let x0 = match anchor {
            "start" => at.x,
            "end" => at.x - w,
            _ => at.x - w / 2.0,
        };
        let (dx, y) = room.place(x0, at.y + dy, w, size, pr.size);
        halo_text(
            svg,
            at.x + dx,
            y,
            anchor,
            &format!(r#" fill="{color}" font-size="{size}""#),
            label,
        );
    }
    svg.push_str("</g>\n");
}

/// What labels of one cell must keep clear of: the boxes of the labels placed so far and the
/// pixel points of the curves and markers drawn.
pub(super) struct Room {
    /// Placed label boxes: [left, top, right, bottom] (px).
    boxes: Vec<[f64; 4]>,
    /// Points of curves (px); a label covering them hides a line.
    points: Vec<Vector2<f64>>,
    /// Marker centres (px); covering one hides it.
    markers: Vec<Vector2<f64>>,
}

impl Room {
    /// Room in a cell with curve points `points` and marker centres `markers` (px).
    pub(super) fn new(points: Vec<Vector2<f64>>, markers: Vec<Vector2<f64>>) -> Self {
        Room {
            boxes: Vec::new(),
            points,
            markers,
        }
    }

    /// Where a label of width `w` and font size `size` goes whose preferred box starts at
    /// `x0` with its baseline at `y`, in a cell `cell` px wide: of candidate shifts (up and
    /// down by up to four lines, sideways by up to one and a half label widths), nearest
    /// first, the first that keeps inside the cell and clear of every placed label, marker
    /// and curve point; failing that, the one covering least. Returns the horizontal shift
    /// and the baseline, and records the box.
    pub(super) fn place(&mut self, x0: f64, y: f64, w: f64, size: f64, cell: f64) -> (f64, f64) {
        let line = size + 2.0;
        let mut shifts = Vec::new();
        for i in -3..=3 {
            for j in -4..=4 {
                shifts.push((f64::from(i) * (w / 2.0 + 6.0), f64::from(j) * line));
            }
        }
        shifts.sort_by(|a: &(f64, f64), b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
        let mut best = (f64::INFINITY, 0.0, y);
        for (dx, dy) in shifts {
            let b = [x0 + dx, y + dy - size, x0 + dx + w, y + dy + 2.0];
            let cost = self.cost(&b, cell);
            if cost < best.0 {
                best = (cost, dx, y + dy);
            }
            if cost == 0.0 {
                break;
            }
        }
        let (_, dx, y) = best;
        self.boxes.push([x0 + dx, y - size, x0 + dx + w, y + 2.0]);
        (dx, y)
    }

    /// How badly the box `b` sits: past the cell's edge (heaviest), over a placed label, a
    /// marker or curve points (lightest); 0 when clear.
    fn cost(&self, b: &[f64; 4], cell: f64) -> f64 {
        let inside = |p: &Vector2<f64>| p.x > b[0] - 2.0 && p.x < b[2] + 2.0 && p.y > b[1] - 2.0 && p.y < b[3] + 2.0;
        let outside = (-b[0]).max(0.0) + (b[2] - cell).max(0.0) + (-b[1]).max(0.0) + (b[3] - cell).max(0.0);
        let labels = self
            .boxes
            .iter()
            .filter(|o| b[0] < o[2] && b[2] > o[0] && b[1] < o[3] && b[3] > o[1])
            .count();
        let markers = self.markers.iter().filter(|p| inside(p)).count();
        let points = self.points.iter().filter(|p| inside(p)).count();
        1e4 * outside + 1e3 * labels as f64 + 1e2 * markers as f64 + points as f64
    }
}
