//! Force and distributed-load arrows in one cell: shaft and head, the symbol of a force along
//! the line of sight, and labels moved clear of the ones already placed.

use super::scene::{Scene, finite};
use super::text::{FONT, halo_text, text_width};
use super::view::{Projection, View};
use super::{Arrow, ArrowKind};
use nalgebra::Vector2;
use std::fmt::Write;

/// One arrow: shaft and head in pixels from the projected tail and head; for a force along
/// the line of sight of an orthographic view, a circle with a dot (towards the viewer) or a
/// cross (away).
pub(super) fn arrow_svg(svg: &mut String, pr: &Projection, a: &Arrow, scene: &Scene, placed: &mut Vec<[f64; 4]>) {
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
    let label_at = if length < head {
        if a.kind == ArrowKind::Force && pr.view != View::Perspective {
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
        // Move the label down past the labels already placed in this cell that it would cover.
        let w = text_width(label, size);
        let x0 = match anchor {
            "start" => at.x,
            "end" => at.x - w,
            _ => at.x - w / 2.0,
        };
        let mut y = at.y + dy;
        while let Some(b) = placed
            .iter()
            .find(|b| x0 < b[2] && x0 + w > b[0] && y - size < b[3] && y > b[1])
        {
            y = b[3] + size + 1.0;
        }
        placed.push([x0, y - size, x0 + w, y + 2.0]);
        halo_text(
            svg,
            at.x,
            y,
            anchor,
            &format!(r#" fill="{color}" font-size="{size}""#),
            label,
        );
    }
    svg.push_str("</g>\n");
}
