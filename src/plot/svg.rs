//! The SVG document of a [`Figure`]: the layout of panels and views, ticks and axis labels,
//! curves, disks, arrows, the wrapped header and the legend.

use super::axes::{Unit, round_length, tick_label, tick_step, ticks, unit_for};
use super::shape::DISK_COLOR;
use super::{Arrow, ArrowKind, Figure, LegendEntry, Panel, Symbol};
use nalgebra::{Vector2, Vector3};
use std::fmt::Write;

/// Outer margin (px).
const MARGIN: f64 = 24.0;
/// Space between a cell's frame and what it shows (px).
const PAD: f64 = 14.0;
/// Space between a cell's top edge and what it shows, below the view's title (px).
const TOP_PAD: f64 = 28.0;
/// Gutter left of a cell: tick numbers and the vertical axis label (px).
const LEFT: f64 = 58.0;
/// Gutter under a cell: tick numbers and the horizontal axis label (px).
const BOTTOM: f64 = 42.0;
/// Space between the cells of a row that has no tick numbers on the left (px).
const GAP: f64 = 16.0;
/// Height of the panel titles over the columns of small multiples (px).
const COLUMN_HEAD: f64 = 40.0;
/// Cell size of the single-panel layout (px).
const CELL: f64 = 430.0;
/// Width the small multiples aim at (px); cells between [`MIN_CELL`] and [`MAX_CELL`].
const MULTIPLES_WIDTH: f64 = 1560.0;
/// Smallest cell of small multiples (px).
const MIN_CELL: f64 = 180.0;
/// Largest cell of small multiples (px).
const MAX_CELL: f64 = 300.0;
/// Body font size (px).
const FONT: f64 = 12.0;
/// Title font size (px).
const TITLE_FONT: f64 = 17.0;
/// Average glyph advance over the font size, to estimate text widths: 0.6 holds for
/// DejaVu Sans, the widest of the fonts named; Helvetica and Arial are narrower.
const ADVANCE: f64 = 0.6;
/// The longest force arrow, relative to the scene's extent.
const FORCE_FRACTION: f64 = 0.2;
/// The longest distributed-load arrow, relative to the scene's extent.
const DISTRIBUTED_FRACTION: f64 = 0.06;
/// Sides of the polygon a disk is drawn as.
const DISK_SIDES: usize = 36;
/// Font families, first found first: the common sans-serif faces of macOS, Windows and Linux.
pub(super) const FONT_FAMILY: &str = "Helvetica, Arial, 'DejaVu Sans', 'Liberation Sans', sans-serif";

/// The views, in panel order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum View {
    Top,
    Side,
    Front,
    Perspective,
}

const VIEWS: [View; 4] = [View::Top, View::Side, View::Front, View::Perspective];

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

    /// The world direction out of the screen, towards the viewer (orthographic views).
    fn toward_viewer(self) -> Vector3<f64> {
        match self {
            View::Top => Vector3::z(),
            View::Side => -Vector3::y(),
            View::Front => Vector3::x(),
            View::Perspective => Vector3::zeros(),
        }
    }
}

/// The perspective camera: eye position and orthonormal right, up, forward axes.
#[derive(Clone, Copy)]
pub(super) struct Camera {
    eye: Vector3<f64>,
    right: Vector3<f64>,
    up: Vector3<f64>,
    forward: Vector3<f64>,
}

impl Camera {
    /// A camera looking at `center` from azimuth -60 deg and elevation 25 deg (the x-z plane
    /// seen obliquely, z up), at 4 times the scene radius so the distortion stays mild.
    pub(super) fn new(center: Vector3<f64>, radius: f64) -> Self {
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

    pub(super) fn project(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let q = p - self.eye;
        // Points behind the eye cannot occur (the eye is 4 radii out); guard the division.
        let depth = q.dot(&self.forward).max(1e-12);
        Vector2::new(q.dot(&self.right), q.dot(&self.up)) / depth
    }
}

/// A projection of world points to the pixels of one cell.
struct Projection {
    view: View,
    camera: Camera,
    /// px per unit of [`Projection::raw`] (px/m in the orthographic views).
    scale: f64,
    /// px.
    offset: Vector2<f64>,
    /// Cell size (px).
    size: f64,
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

    /// Pixel coordinates inside the cell, y down.
    fn px(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let r = self.raw(p) * self.scale + self.offset;
        Vector2::new(r.x, self.size - r.y)
    }
}

/// What every cell shares: the scene's bounds and the arrow scales.
struct Scene {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    /// Largest side of the bounding box (m).
    extent: f64,
    /// Arrow length per unit of force (m/N) and of distributed force (m per N/m).
    force_scale: f64,
    distributed_scale: f64,
    unit: Unit,
}

impl Scene {
    fn arrow_scale(&self, kind: ArrowKind) -> f64 {
        match kind {
            ArrowKind::Force => self.force_scale,
            ArrowKind::Distributed => self.distributed_scale,
        }
    }

    fn arrow_head(&self, a: &Arrow) -> Vector3<f64> {
        a.point + a.vector * self.arrow_scale(a.kind)
    }

    /// A point beyond the head of a labelled arrow, kept inside the views so the label fits.
    fn label_room(&self, a: &Arrow) -> Vector3<f64> {
        let room = if a.label.is_some() { 0.06 * self.extent } else { 0.0 };
        self.arrow_head(a) + a.vector.try_normalize(0.0).unwrap_or_default() * room
    }
}

fn finite(p: &Vector3<f64>) -> bool {
    p.iter().all(|x| x.is_finite())
}

/// Points on the rim of a disk.
fn rim(d: &super::Disk) -> impl Iterator<Item = Vector3<f64>> + '_ {
    (0..DISK_SIDES).map(move |k| {
        let t = std::f64::consts::TAU * k as f64 / DISK_SIDES as f64;
        d.center + d.rotation * Vector3::new(d.radius * t.cos(), d.radius * t.sin(), 0.0)
    })
}

/// Every point drawn in a panel except the arrow heads.
fn points(panel: &Panel) -> impl Iterator<Item = Vector3<f64>> + '_ {
    panel
        .curves
        .iter()
        .flat_map(|c| c.points.iter().copied())
        .chain(panel.markers.iter().map(|m| m.point))
        .chain(panel.origin)
        .chain(panel.arrows.iter().map(|a| a.point))
        .chain(panel.disks.iter().flat_map(rim))
        .filter(finite)
}

fn bounds(points: impl Iterator<Item = Vector3<f64>>) -> (Vector3<f64>, Vector3<f64>) {
    let (mut lo, mut hi) = (Vector3::repeat(f64::INFINITY), Vector3::repeat(f64::NEG_INFINITY));
    for p in points {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    if lo.x > hi.x {
        (Vector3::zeros(), Vector3::zeros())
    } else {
        (lo, hi)
    }
}

fn scene(panels: &[Panel]) -> Scene {
    let (lo, hi) = bounds(panels.iter().flat_map(points));
    let extent = (hi - lo).amax().max(1e-6);
    let largest = |kind: ArrowKind| {
        panels
            .iter()
            .flat_map(|p| &p.arrows)
            .filter(|a| a.kind == kind && finite(&a.vector))
            .map(|a| a.vector.norm())
            .fold(0.0, f64::max)
    };
    let per = |fraction: f64, largest: f64| {
        if largest > 0.0 {
            fraction * extent / largest
        } else {
            0.0
        }
    };
    let mut scene = Scene {
        lo,
        hi,
        extent,
        force_scale: per(FORCE_FRACTION, largest(ArrowKind::Force)),
        distributed_scale: per(DISTRIBUTED_FRACTION, largest(ArrowKind::Distributed)),
        unit: unit_for(extent),
    };
    let heads: Vec<Vector3<f64>> = panels
        .iter()
        .flat_map(|p| &p.arrows)
        .map(|a| scene.label_room(a))
        .filter(finite)
        .collect();
    let (lo, hi) = bounds([scene.lo, scene.hi].into_iter().chain(heads));
    scene.lo = lo;
    scene.hi = hi;
    scene.extent = (hi - lo).amax().max(1e-6);
    scene
}

pub(super) fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Estimated width (px) of `text` at font size `size`.
fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * ADVANCE
}

/// `text` broken at spaces into lines of at most `width` px at font size `size` (a word
/// longer than a line gets a line of its own).
pub(super) fn wrap(text: &str, width: f64, size: f64) -> Vec<String> {
    let max = ((width / (size * ADVANCE)).floor() as usize).max(8);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > max {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    // No orphans: a last line of a few characters (`N)`) takes the previous line's last word.
    let n = lines.len();
    if n >= 2
        && lines[n - 1].chars().count() < 10
        && let Some(cut) = lines[n - 2].rfind(' ')
    {
        let word = lines[n - 2][cut + 1..].to_string();
        if word.chars().count() + 1 + lines[n - 1].chars().count() <= max {
            lines[n - 2].truncate(cut);
            lines[n - 1] = format!("{word} {}", lines[n - 1]);
        }
    }
    lines
}

/// One cell: a view of one panel at a position in the document.
struct Cell {
    panel: usize,
    view: View,
    x: f64,
    y: f64,
    /// Tick numbers and the axis label on the left side.
    numbers_left: bool,
}

/// The document's layout: its size, the cells and where the header and legend go.
struct Layout {
    width: f64,
    cell: f64,
    cells: Vec<Cell>,
    /// Lines of the title and the subtitle.
    title: Vec<String>,
    subtitle: Vec<String>,
    /// Top of the cell grid (below the header) and of the legend (px).
    grid_top: f64,
    legend_top: f64,
    multiples: bool,
}

fn layout(figure: &Figure, panels: usize) -> Layout {
    let multiples = panels > 1;
    let cell = if multiples {
        ((MULTIPLES_WIDTH - 2.0 * MARGIN - LEFT - (panels - 1) as f64 * GAP) / panels as f64).clamp(MIN_CELL, MAX_CELL)
    } else {
        CELL
    };
    let width = if multiples {
        2.0 * MARGIN + LEFT + panels as f64 * cell + (panels - 1) as f64 * GAP
    } else {
        2.0 * MARGIN + 2.0 * (LEFT + cell)
    };
    let text_width = width - 2.0 * MARGIN;
    let title = wrap(&figure.title, text_width, TITLE_FONT);
    let subtitle: Vec<String> = figure
        .subtitle
        .iter()
        .flat_map(|line| wrap(line, text_width, FONT))
        .collect();
    let header = MARGIN + 21.0 * title.len() as f64 + 16.0 * subtitle.len() as f64 + 14.0;
    let grid_top = header + if multiples { COLUMN_HEAD } else { 0.0 };
    let mut cells = Vec::new();
    if multiples {
        for (row, &view) in VIEWS.iter().enumerate() {
            for panel in 0..panels {
                cells.push(Cell {
                    panel,
                    view,
                    x: MARGIN + LEFT + panel as f64 * (cell + GAP),
                    y: grid_top + row as f64 * (cell + BOTTOM),
                    numbers_left: panel == 0,
                });
            }
        }
    } else {
        for (k, &view) in VIEWS.iter().enumerate() {
            cells.push(Cell {
                panel: 0,
                view,
                x: MARGIN + LEFT + (k % 2) as f64 * (cell + LEFT),
                y: grid_top + (k / 2) as f64 * (cell + BOTTOM),
                numbers_left: true,
            });
        }
    }
    let rows = if multiples { VIEWS.len() } else { 2 };
    Layout {
        width,
        cell,
        cells,
        title,
        subtitle,
        grid_top,
        legend_top: grid_top + rows as f64 * (cell + BOTTOM) + 6.0,
        multiples,
    }
}

/// The legend laid out in columns: each entry's wrapped label lines and position.
struct LegendLayout {
    /// (entry, x, y of the first baseline, label lines).
    items: Vec<(usize, f64, f64, Vec<String>)>,
    height: f64,
}

/// Width of a legend entry's symbol and the space after it (px).
const SYMBOL: f64 = 38.0;
/// Line height of legend labels (px).
const LEGEND_LINE: f64 = 15.0;

fn legend_layout(legend: &[LegendEntry], width: f64, top: f64) -> LegendLayout {
    if legend.is_empty() {
        return LegendLayout {
            items: Vec::new(),
            height: 0.0,
        };
    }
    let available = width - 2.0 * MARGIN;
    let widest = legend
        .iter()
        .map(|e| SYMBOL + text_width(&e.label, FONT) + 24.0)
        .fold(0.0, f64::max);
    // Columns at least 420 px wide (longer labels wrap), at most 4.
    let columns = ((available / widest.min(420.0)).floor() as usize).clamp(1, legend.len().min(4));
    let column = available / columns as f64;
    let mut items = Vec::new();
    let mut y = top + 12.0;
    for row in legend.chunks(columns).enumerate() {
        let (r, entries) = row;
        let mut lines_in_row = 1;
        for (c, entry) in entries.iter().enumerate() {
            let lines = wrap(&entry.label, column - SYMBOL - 16.0, FONT);
            lines_in_row = lines_in_row.max(lines.len());
            items.push((r * columns + c, MARGIN + c as f64 * column, y, lines));
        }
        y += LEGEND_LINE * lines_in_row as f64 + 7.0;
    }
    LegendLayout { items, height: y - top }
}

/// The figure as a standalone SVG document.
pub(super) fn document(figure: &Figure) -> String {
    let empty = [Panel::default()];
    let panels: &[Panel] = if figure.panels.is_empty() {
        &empty
    } else {
        &figure.panels
    };
    let scene = scene(panels);
    let layout = layout(figure, panels.len());
    let legend = legend_layout(&figure.legend, layout.width, layout.legend_top);
    let width = layout.width;
    let height = (layout.legend_top + legend.height + MARGIN).ceil();
    let cell = layout.cell;

    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="{FONT_FAMILY}" font-size="{FONT}">"#
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
            let x = MARGIN + LEFT + k as f64 * (cell + GAP);
            let lines = wrap(&panel.title, cell + GAP, FONT);
            let first = layout.grid_top - 8.0 - 15.0 * (lines.len().min(2) - 1) as f64;
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
            inner / scene.extent
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

/// A text element with a white halo, legible over lines.
fn halo_text(svg: &mut String, x: f64, y: f64, anchor: &str, extra: &str, text: &str) {
    let _ = writeln!(
        svg,
        r#"<text x="{x:.1}" y="{y:.1}" text-anchor="{anchor}" stroke="white" stroke-width="3" stroke-linejoin="round" paint-order="stroke"{extra}>{}</text>"#,
        escape(text)
    );
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
    // Arrows are not clipped: their labels may reach over the frame.
    let mut placed = Vec::new();
    for a in &panel.arrows {
        arrow_svg(svg, pr, a, scene, &mut placed);
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
    // About 6 ticks over the cell, at least 45 px apart so numbers do not touch.
    let step = tick_step(size / pr.scale, 6.0, 45.0 / pr.scale);
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

/// One arrow: shaft and head in pixels from the projected tail and head; for a force along
/// the line of sight of an orthographic view, a circle with a dot (towards the viewer) or a
/// cross (away).
fn arrow_svg(svg: &mut String, pr: &Projection, a: &Arrow, scene: &Scene, placed: &mut Vec<[f64; 4]>) {
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

fn legend_entry(svg: &mut String, entry: &LegendEntry, x: f64, y: f64, lines: &[String]) {
    let color = &entry.color;
    let mid = y - 4.0;
    let dash = entry
        .dash
        .as_ref()
        .map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#));
    let _ = match entry.symbol {
        Symbol::Line => writeln!(
            svg,
            r#"<line x1="{x}" y1="{mid}" x2="{}" y2="{mid}" stroke="{color}" stroke-width="{}"{dash}/>"#,
            x + 30.0,
            entry.width
        ),
        Symbol::Disk => writeln!(
            svg,
            r##"<ellipse cx="{}" cy="{mid}" rx="3" ry="8" fill="#9a9a9a" fill-opacity="0.18" stroke="{color}" stroke-width="0.8"/><line x1="{x}" y1="{mid}" x2="{}" y2="{mid}" stroke="#000" stroke-width="2"/>"##,
            x + 15.0,
            x + 30.0
        ),
        Symbol::Arrow => writeln!(
            svg,
            r#"<line x1="{x}" y1="{mid}" x2="{}" y2="{mid}" stroke="{color}" stroke-width="1.8"{dash}/><polygon fill="{color}" points="{},{mid} {},{} {},{}"/>"#,
            x + 23.0,
            x + 30.0,
            x + 21.0,
            mid - 4.0,
            x + 21.0,
            mid + 4.0
        ),
        Symbol::Dot => writeln!(svg, r#"<circle cx="{}" cy="{mid}" r="3" fill="{color}"/>"#, x + 15.0),
    };
    for (k, line) in lines.iter().enumerate() {
        let _ = writeln!(
            svg,
            r#"<text class="legend" x="{}" y="{}">{}</text>"#,
            x + SYMBOL,
            y + LEGEND_LINE * k as f64,
            escape(line)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perspective_keeps_the_centre_on_the_axis() {
        let c = Camera::new(Vector3::new(0.1, 0.0, -0.1), 0.2);
        let q = c.project(&Vector3::new(0.1, 0.0, -0.1));
        // 1e-12: the centre lies on the optical axis up to rounding
        assert!(q.norm() < 1e-12);
    }

    #[test]
    fn long_lines_wrap_within_the_width() {
        let text = "collocation, adaptive: 3 meshes 32 -> 64 -> 128 intervals, 14 Newton iterations, \
                    estimated tip error 2.1e-9 m (tolerance 2.4e-8 m, met), residual 3e-13, 4.2 ms";
        let lines = wrap(text, 300.0, FONT);
        assert!(lines.len() > 1, "{lines:?}");
        assert!(lines.iter().all(|l| text_width(l, FONT) <= 300.0), "{lines:?}");
        assert_eq!(lines.join(" "), text);
    }
}
