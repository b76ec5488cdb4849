//! The SVG document of a [`Figure`]: the header, every cell (frame, ticks, disks, curves,
//! markers, the base square, the perspective's world axes, arrows) and the legend, placed by
//! [`layout`](super::layout) and projected by [`view`](super::view).

use super::arrow::{Room, arrow_svg};
use super::axes::{round_length, tick_label, tick_step, ticks};
use super::layout::{Cell, GAP, MARGIN, PAD, TOP_PAD, layout};
use super::legend::{legend_entry, legend_layout};
use super::scene::{Scene, finite, points, rim, scene};
use super::shape::DISK_COLOR;
use super::text::{FONT, FONT_FAMILY, TITLE_FONT, escape, halo_text, wrap};
use super::view::{Camera, Projection, VIEWS, View};
use super::{Figure, Panel};
use nalgebra::{Vector2, Vector3};
use std::fmt::Write;

/// The figure as a standalone SVG document.
pub(super) fn document(figure: &Figure) -> String {
    let empty = [Panel::default()];
    let panels: &[Panel] = if figure.panels.is_empty() {
        &empty
    } else {
        &figure.panels
    };
    let scene = scene(panels);
    let views = figure.views.clone().unwrap_or_else(|| shown_views(panels));
    // The layout is made at the body font size FONT and then zoomed to the asked size.
    let zoom = figure.font_size.map_or(1.0, |f| f / FONT);
    let layout = layout(figure, panels.len(), &views, figure.width.map(|w| w / zoom));
    let legend = legend_layout(&figure.legend, layout.width, layout.legend_top);
    let width = layout.width;
    let height = (layout.legend_top + legend.height + MARGIN).ceil();
    let cell = layout.cell;

    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {width} {height}" font-family="{FONT_FAMILY}" font-size="{FONT}">"#,
        width * zoom,
        height * zoom
    );
    let _ = writeln!(
        svg,
        r#"<defs><clipPath id="cell"><rect width="{cell}" height="{cell}"/></clipPath></defs>"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let mut y = MARGIN;
    for line in &layout.title {
        y += 19.0;
        let _ = writeln!(
            svg,
            r#"<text x="{MARGIN}" y="{y}" font-size="{TITLE_FONT}" font-weight="bold">{}</text>"#,
            escape(line)
        );
        y += 2.0;
    }
    y += 2.0;
    for line in &layout.subtitle {
        y += 16.0;
        let _ = writeln!(
            svg,
            r##"<text class="subtitle" x="{MARGIN}" y="{y}" fill="#444">{}</text>"##,
            escape(line)
        );
    }
    if layout.multiples {
        for (k, panel) in panels.iter().enumerate() {
            // Over the panel's first cell (the top of its column in its block of rows).
            let Some(top) = layout.cells.iter().find(|c| c.panel == k) else {
                continue;
            };
            let x = top.x;
            let lines = wrap(&panel.title, cell + GAP, FONT);
            let first = top.y - 8.0 - 15.0 * (lines.len().min(2) - 1) as f64;
            for (j, line) in lines.iter().take(2).enumerate() {
                let _ = writeln!(
                    svg,
                    r#"<text x="{x}" y="{}" font-weight="bold">{}</text>"#,
                    first + 15.0 * j as f64,
                    escape(line)
                );
            }
        }
    }

    // The orthographic views share one scale, the perspective views one camera and scale.
    let center = (scene.lo + scene.hi) / 2.0;
    let camera = Camera::new(center, (scene.hi - scene.lo).norm() / 2.0);
    let axis_length = round_length(scene.extent / 4.0);
    let base = panels.iter().find_map(|p| p.origin).unwrap_or(scene.lo);
    let inner = cell - PAD - TOP_PAD;
    // The orthographic views drawn share one scale: the largest span along their axes fills
    // a cell (a figure of side views alone is not shrunk by the scene's depth).
    let span = scene.hi - scene.lo;
    let ortho_extent = views
        .iter()
        .filter_map(|v| v.axis_indices())
        .map(|(a, b)| span[a].max(span[b]))
        .fold(0.0, f64::max)
        .max(1e-6);
    for c in &layout.cells {
        let mut pr = Projection {
            view: c.view,
            camera,
            scale: 1.0,
            offset: Vector2::zeros(),
            size: cell,
        };
        let (a, b) = if c.view == View::Perspective {
            let triad = (0..3).map(|k| base + Vector3::ith(k, axis_length * 1.2));
            let all: Vec<Vector2<f64>> = panels
                .iter()
                .flat_map(points)
                .chain(panels.iter().flat_map(|p| &p.arrows).map(|a| scene.label_room(a)))
                .chain(triad)
                .filter(finite)
                .map(|p| pr.raw(&p))
                .collect();
            let (mut a, mut b) = (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY));
            for q in &all {
                a = a.inf(q);
                b = b.sup(q);
            }
            if a.x > b.x {
                (Vector2::zeros(), Vector2::zeros())
            } else {
                (a, b)
            }
        } else {
            let (a, b) = (pr.raw(&scene.lo), pr.raw(&scene.hi));
            (a.inf(&b), a.sup(&b))
        };
        pr.scale = if c.view == View::Perspective {
            inner / (b - a).amax().max(1e-12)
        } else {
            inner / ortho_extent
        };
        // Centred in the cell below the title: the centre (a + b) / 2 goes (TOP_PAD - PAD) / 2
        // below the cell's centre.
        pr.offset = Vector2::new(cell / 2.0, (cell - (TOP_PAD - PAD)) / 2.0) - (a + b) / 2.0 * pr.scale;
        cell_svg(
            &mut svg,
            &panels[c.panel],
            &pr,
            c,
            &scene,
            axis_length,
            layout.multiples,
        );
    }
    for (k, x, y, lines) in &legend.items {
        legend_entry(&mut svg, &figure.legend[*k], *x, *y, lines);
    }
    svg.push_str("</svg>\n");
    svg
}

/// The views drawn by default: every view but an orthographic one in which the curves and
/// markers span less than [`FLAT_VIEW`](super::FLAT_VIEW) of their extent on both axes.
fn shown_views(panels: &[Panel]) -> Vec<View> {
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for p in panels.iter().flat_map(|p| {
        p.curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .chain(p.markers.iter().map(|m| m.point))
    }) {
        if finite(&p) {
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
    }
    let span = hi - lo;
    let extent = span.amax();
    VIEWS
        .into_iter()
        .filter(|v| match v.axis_indices() {
            Some((a, b)) if extent.is_finite() && extent > 0.0 => span[a].max(span[b]) >= super::FLAT_VIEW * extent,
            _ => true,
        })
        .collect()
}

/// Pixel points as an SVG `points` list, leaving out points closer than [`THIN`] to the last
/// one kept (the last point is always kept): the dense samples of a backbone cost file size
/// and rendering time but nothing visible below a pixel.
fn polyline(points: impl Iterator<Item = Vector2<f64>>) -> String {
    let points: Vec<Vector2<f64>> = points.collect();
    let mut out = String::new();
    let mut last: Option<Vector2<f64>> = None;
    for (k, q) in points.iter().enumerate() {
        let keep = match last {
            None => true,
            Some(l) => (q - l).norm() >= THIN || k + 1 == points.len(),
        };
        if keep {
            if last.is_some() {
                out.push(' ');
            }
            let _ = write!(out, "{:.1},{:.1}", q.x, q.y);
            last = Some(*q);
        }
    }
    out
}

/// Smallest spacing of the points written for a curve (px): half a pixel.
const THIN: f64 = 0.5;

fn cell_svg(
    svg: &mut String,
    panel: &Panel,
    pr: &Projection,
    c: &Cell,
    scene: &Scene,
    axis_length: f64,
    multiples: bool,
) {
    let size = pr.size;
    let _ = writeln!(svg, r#"<g transform="translate({:.1},{:.1})">"#, c.x, c.y);
    let _ = writeln!(
        svg,
        r##"<rect width="{size}" height="{size}" fill="white" stroke="#999"/>"##
    );
    if pr.view != View::Perspective {
        ticks_svg(svg, pr, c, scene);
    }
    svg.push_str("<g clip-path=\"url(#cell)\">\n");
    for d in &panel.disks {
        if !finite(&d.center) {
            continue;
        }
        let _ = writeln!(
            svg,
            r##"<polygon class="disk" fill="#9a9a9a" fill-opacity="0.1" stroke="{DISK_COLOR}" stroke-width="0.8" stroke-opacity="0.7" stroke-linejoin="round" points="{}"/>"##,
            polyline(rim(d).map(|p| pr.px(&p)))
        );
    }
    for curve in &panel.curves {
        let points: Vec<Vector2<f64>> = curve.points.iter().filter(|p| finite(p)).map(|p| pr.px(p)).collect();
        if points.len() < 2 {
            continue;
        }
        let dash = curve
            .dash
            .as_ref()
            .map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#));
        let _ = writeln!(
            svg,
            r#"<polyline fill="none" stroke="{}" stroke-width="{}" stroke-opacity="{}" stroke-linejoin="round" stroke-linecap="round"{dash} points="{}"/>"#,
            curve.color,
            curve.width,
            curve.opacity,
            polyline(points.into_iter())
        );
    }
    for m in panel.markers.iter().filter(|m| finite(&m.point)) {
        let q = pr.px(&m.point);
        let _ = writeln!(
            svg,
            r#"<circle cx="{:.2}" cy="{:.2}" r="{}" fill="{}"/>"#,
            q.x, q.y, m.radius, m.color
        );
    }
    if let Some(origin) = panel.origin.filter(finite) {
        let b = pr.px(&origin);
        let _ = writeln!(
            svg,
            r#"<rect x="{:.2}" y="{:.2}" width="7" height="7" fill="black"/>"#,
            b.x - 3.5,
            b.y - 3.5
        );
    }
    if pr.view == View::Perspective {
        let origin = panel.origin.unwrap_or(scene.lo);
        let b = pr.px(&origin);
        for (k, name) in ["x", "y", "z"].iter().enumerate() {
            let (q, l) = (
                pr.px(&(origin + Vector3::ith(k, axis_length))),
                pr.px(&(origin + Vector3::ith(k, axis_length * 1.15))),
            );
            let _ = writeln!(
                svg,
                r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="black" stroke-width="1.5"/>"#,
                b.x, b.y, q.x, q.y
            );
            halo_text(svg, l.x, l.y + 4.0, "middle", r#" font-weight="bold""#, name);
        }
    }
    svg.push_str("</g>\n");
    // Arrows are not clipped; their labels keep inside the cell, clear of each other, the
    // markers and the curves.
    let mut points: Vec<Vector2<f64>> = panel
        .curves
        .iter()
        .flat_map(|c| c.points.iter().filter(|p| finite(p)).map(|p| pr.px(p)))
        .collect();
    // The arrows' shafts too, sampled every few pixels.
    for a in panel.arrows.iter().filter(|a| finite(&a.point) && finite(&a.vector)) {
        let (q0, q1) = (pr.px(&a.point), pr.px(&scene.arrow_head(a)));
        let n = ((q1 - q0).norm() / 3.0).ceil().max(1.0) as usize;
        points.extend((0..=n).map(|k| q0 + (q1 - q0) * (k as f64 / n as f64)));
    }
    let markers = panel
        .markers
        .iter()
        .filter(|m| finite(&m.point))
        .map(|m| pr.px(&m.point))
        .collect();
    let mut room = Room::new(points, markers);
    // Forces before distributed loads, the largest first: a short arrow's label then moves
    // off the long shaft beside it rather than taking the long arrow's place.
    let mut order: Vec<&super::Arrow> = panel.arrows.iter().collect();
    order.sort_by(|a, b| {
        let key = |x: &super::Arrow| (x.kind != super::ArrowKind::Force, -x.vector.norm());
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    for a in order {
        arrow_svg(svg, pr, a, scene, &mut room);
    }
    let title = if multiples {
        r##" fill="#555""##.to_string()
    } else {
        r#" font-weight="bold""#.to_string()
    };
    halo_text(svg, 8.0, 18.0, "start", &title, c.view.title());
    if pr.view == View::Perspective {
        halo_text(
            svg,
            0.0,
            size + 17.0,
            "start",
            r##" fill="#555""##,
            &format!(
                "world axes at the base, {} {} long",
                super::axes::significant(axis_length * scene.unit.per_metre),
                scene.unit.name
            ),
        );
    }
    svg.push_str("</g>\n");
}

/// Grid lines, tick marks and numbers, and axis labels of an orthographic cell.
fn ticks_svg(svg: &mut String, pr: &Projection, c: &Cell, scene: &Scene) {
    let size = pr.size;
    let (h, v) = pr.view.axes();
    let unit = scene.unit;
    // The window in world coordinates (m): pixel 0..size on each axis.
    let h_range = (-pr.offset.x / pr.scale, (size - pr.offset.x) / pr.scale);
    let v_range = (-pr.offset.y / pr.scale, (size - pr.offset.y) / pr.scale);
    // About 6 ticks over the cell, at least 36 px apart so numbers (`-200`: 29 px) do not
    // touch.
    let step = tick_step(size / pr.scale, 6.0, 36.0 / pr.scale);
    let inside = |q: f64| (2.0..=size - 2.0).contains(&q);
    for t in ticks(h_range.0, h_range.1, step) {
        let x = pr.offset.x + t * pr.scale;
        if !inside(x) {
            continue;
        }
        let _ = writeln!(
            svg,
            r##"<line x1="{x:.2}" y1="0" x2="{x:.2}" y2="{size}" stroke="#e6e6e6"/><line x1="{x:.2}" y1="{size}" x2="{x:.2}" y2="{}" stroke="#666"/><text class="tick" x="{x:.2}" y="{}" text-anchor="middle" fill="#333">{}</text>"##,
            size + 5.0,
            size + 17.0,
            tick_label(t, step, unit)
        );
    }
    for t in ticks(v_range.0, v_range.1, step) {
        let y = size - (pr.offset.y + t * pr.scale);
        if !inside(y) {
            continue;
        }
        let _ = writeln!(
            svg,
            r##"<line x1="0" y1="{y:.2}" x2="{size}" y2="{y:.2}" stroke="#e6e6e6"/><line x1="-5" y1="{y:.2}" x2="0" y2="{y:.2}" stroke="#666"/>"##
        );
        if c.numbers_left {
            let _ = writeln!(
                svg,
                r##"<text class="tick" x="-8" y="{:.2}" text-anchor="end" fill="#333">{}</text>"##,
                y + 4.0,
                tick_label(t, step, unit)
            );
        }
    }
    let _ = writeln!(
        svg,
        r##"<text class="axis-label" x="{}" y="{}" text-anchor="middle" fill="#333">{h} ({})</text>"##,
        size / 2.0,
        size + 33.0,
        unit.name
    );
    if c.numbers_left {
        let _ = writeln!(
            svg,
            r##"<text class="axis-label" transform="translate(-44,{}) rotate(-90)" text-anchor="middle" fill="#333">{v} ({})</text>"##,
            size / 2.0,
            unit.name
        );
    }
}
