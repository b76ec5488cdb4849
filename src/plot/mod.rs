//! Pictures of solved shapes, as SVG (written by hand) or PNG (the SVG rendered with resvg).
//!
//! A [`Figure`] holds one or more [`Panel`]s. One panel is drawn in four views: top (XY),
//! side (XZ) and front (YZ), all at one scale with ticks in mm, and a perspective view. Several
//! panels are drawn as small multiples: a column per panel, a row per view, every cell at the
//! same scale and window, so the columns compare directly. A shape ([`Panel::add_shape`]) is
//! its backbone, its tendon paths (thin; slack ones dashed), spacer disks, arrows for the tip
//! force and point loads (length proportional to force, labelled in N) and small arrows for a
//! distributed force; [`shape_legend`] names each of them, tendons with their routing, the
//! turns they truly make over their own length ([`crate::Tendon::turns`]) and their tension.
//!
//! ```
//! use tdcr::plot::{Figure, Style, shape_legend};
//! let robot = tdcr::cases::case_s();
//! let solution = tdcr::collocation::solve(&robot, &Default::default()).unwrap();
//! let mut figure = Figure::new("case S");
//! let style = Style::new("#1f77b4");
//! figure.add_shape(&robot, &solution, &style);
//! figure.legend = shape_legend(&robot, &style);
//! let svg = figure.to_svg();
//! assert!(svg.starts_with("<svg") && svg.contains("perspective"));
//! assert!(svg.contains("tendon 1 (thin line): straight at (8, 0) mm; 2.94 N"));
//! ```

mod arrow;
mod axes;
mod chart;
mod layout;
mod legend;
mod png;
mod scene;
mod shape;
mod svg;
mod tension;
mod text;
mod view;

pub use axes::significant;
pub use chart::{Chart, Mark, Segment};
pub use png::{Png, fonts_found};
pub use shape::{
    FORCE_COLOR, default_disks, disk_radius, routing_label, shape_legend, solved_shape_legend, tendon_description,
    tendon_label, tendon_path, turns_label,
};
pub use view::{VIEWS, View};

use crate::error::{Result, invalid};
use crate::{Robot, Solution};
use nalgebra::{Matrix3, Vector3};
use std::path::Path;

/// Colours for tendon numbers 1, 2, ... (cycled): colour-blind safe, the Okabe-Ito colours
/// without black (the backbone's) and yellow (too light on white), then two of Paul Tol's
/// (wine, indigo).
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#882255", "#332288",
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

/// A spacer disk: a circle in the cross-section plane at a point of the backbone.
#[derive(Clone, Debug, PartialEq)]
pub struct Disk {
    /// Centre (m), world frame: the backbone point.
    pub center: Vector3<f64>,
    /// Orientation of the cross-section, body to world: the disk lies in the plane of the
    /// body x and y axes.
    pub rotation: Matrix3<f64>,
    /// Radius (m).
    pub radius: f64,
}

/// What an [`Arrow`]'s vector is; each kind has its own length scale in a figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArrowKind {
    /// A force (N): the longest force arrow of the figure is 20 % of the scene's extent.
    Force,
    /// A distributed force (N/m): the longest is 6 % of the scene's extent, drawn thin.
    Distributed,
}

/// An arrow from a world point along a load.
#[derive(Clone, Debug, PartialEq)]
pub struct Arrow {
    /// Where the load acts (m), world frame: the arrow's tail.
    pub point: Vector3<f64>,
    /// The load, world frame (N for [`ArrowKind::Force`], N/m for
    /// [`ArrowKind::Distributed`]).
    pub vector: Vector3<f64>,
    /// Which scale its length follows.
    pub kind: ArrowKind,
    /// SVG colour.
    pub color: String,
    /// Text beside the head (e.g. `0.196 N`), if any.
    pub label: Option<String>,
}

/// A legend entry's sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symbol {
    /// A line segment (stroke width and dash from the entry).
    Line,
    /// A spacer disk seen edge-on, on a backbone.
    Disk,
    /// An arrow.
    Arrow,
    /// A dot.
    Dot,
    /// A line shading from the entry's colour (left) toward white (right): a tendon with
    /// friction, darker where its tension is higher ([`solved_shape_legend`]).
    Ramp,
}

/// One legend line: a sample and its label.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// Text.
    pub label: String,
    /// SVG colour.
    pub color: String,
    /// SVG dash pattern, `None` for solid.
    pub dash: Option<String>,
    /// Stroke width of a line sample (px).
    pub width: f64,
    /// The sample drawn.
    pub symbol: Symbol,
}

impl LegendEntry {
    /// An entry with a `symbol` sample in `color`, solid, 2.5 px wide.
    pub fn new(symbol: Symbol, label: &str, color: &str) -> Self {
        LegendEntry {
            label: label.to_string(),
            color: color.to_string(),
            dash: None,
            width: 2.5,
            symbol,
        }
    }

    /// A line sample: `LegendEntry::new(Symbol::Line, label, color)`.
    pub fn line(label: &str, color: &str) -> Self {
        Self::new(Symbol::Line, label, color)
    }

    /// The same entry with the line sample `width` px wide.
    pub fn width(mut self, width: f64) -> Self {
        self.width = width;
        self
    }

    /// The same entry dashed with the SVG pattern `dash` (e.g. `"5 3"`).
    pub fn dash(mut self, dash: &str) -> Self {
        self.dash = Some(dash.to_string());
        self
    }
}

/// How [`Panel::add_shape`] draws one solution.
#[derive(Clone, Debug, PartialEq)]
pub struct Style {
    /// Backbone colour.
    pub color: String,
    /// Backbone dash pattern, `None` for solid.
    pub dash: Option<String>,
    /// Draw tendons with zero tension too (thin, dashed). Default false: pulled ones only.
    pub slack_tendons: bool,
    /// Colour tendons by their number from [`PALETTE`] rather than with the backbone's
    /// colour. Default false.
    pub tendon_colors: bool,
    /// Backbone and tendon opacity. Default 1.
    pub opacity: f64,
    /// Spacer disks drawn, evenly spaced at s = k L / n, k = 1..n (the robot model has no
    /// disks: they are for the picture only). `None` (default): [`default_disks`], disks
    /// about 2.5 tendon offsets apart (12 on the paper's prototype); `Some(0)`: none.
    pub disks: Option<usize>,
    /// The robot's own spacer disks (a robot file's `[disks]`): drawn at their positions
    /// and radius (the default radius if they have none) instead of [`Style::disks`].
    /// Default `None`.
    pub placed_disks: Option<crate::Disks>,
    /// Arrows for the tip force and point loads, labelled in N. Default true.
    pub loads: bool,
    /// Small arrows along the backbone for a distributed force, the largest labelled in N/m.
    /// Default true.
    pub distributed_load: bool,
}

impl Style {
    /// A solid backbone in `color` with its pulled tendons drawn along, default disks and
    /// load arrows.
    pub fn new(color: &str) -> Self {
        Style {
            color: color.to_string(),
            dash: None,
            slack_tendons: false,
            tendon_colors: false,
            opacity: 1.0,
            disks: None,
            placed_disks: None,
            loads: true,
            distributed_load: true,
        }
    }
}

/// What one panel shows: shapes, curves, disks and arrows in world coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    /// Title over the panel's column (small multiples; unused for a single panel).
    pub title: String,
    /// Curves, drawn in order.
    pub curves: Vec<Curve>,
    /// Markers, drawn over the curves.
    pub markers: Vec<Marker>,
    /// Spacer disks, drawn under the curves.
    pub disks: Vec<Disk>,
    /// Load arrows, drawn over everything.
    pub arrows: Vec<Arrow>,
    /// The base, drawn as a square; the perspective view's world axes start here (m). The
    /// first base added if `None`.
    pub origin: Option<Vector3<f64>>,
}

impl Panel {
    /// An empty panel with a title.
    pub fn new(title: &str) -> Self {
        Panel {
            title: title.to_string(),
            ..Default::default()
        }
    }
}

/// A picture: a title, subtitle lines, panels and a legend.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Figure {
    /// Title line (wrapped to the figure's width); empty for none.
    pub title: String,
    /// Lines under the title (e.g. the solver used), each wrapped to the figure's width;
    /// empty for none.
    pub subtitle: Vec<String>,
    /// One panel: a cell per view of it; several: small multiples.
    pub panels: Vec<Panel>,
    /// Legend entries, under the views.
    pub legend: Vec<LegendEntry>,
    /// The views drawn, in order. `None` (default): every view that shows something
    /// ([`VIEWS`] without an orthographic view in which the whole scene spans less than
    /// [`FLAT_VIEW`] of its extent on both axes, such as the top view of an upright rod).
    pub views: Option<Vec<View>>,
    /// The picture's width (SVG px; a PNG has [`PNG_SCALE`] times as many pixels): the cells
    /// shrink or grow to fill it. `None` (default): cells of 430 px for one panel, 180 to 300
    /// px for small multiples.
    pub width: Option<f64>,
    /// Size of the body text (SVG px at the picture's width; titles and tick numbers in
    /// proportion). `None` (default): 12 px. At a given width, larger text means smaller
    /// drawings: for a journal column, e.g. 520 px (1040 PNG pixels) with 9 px text.
    pub font_size: Option<f64>,
    /// Small multiples: panels per row before the next row of panels starts (each panel keeps
    /// its views in a column). `None` (default): every panel in one row.
    pub columns: Option<usize>,
}

/// An orthographic view is left out by default when the scene spans less than this share of
/// its extent along both of the view's axes: it would show a dot or a short stub in an
/// empty cell.
pub const FLAT_VIEW: f64 = 0.05;

/// A picture file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// SVG (vector; the default).
    Svg,
    /// PNG at twice the SVG's pixel size.
    Png,
}

impl Format {
    /// The format a file name asks for: `.png` (any case) is PNG; `.svg` or no extension is
    /// SVG; any other extension is an error.
    pub fn from_path(path: &Path) -> Result<Format> {
        let extension = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("svg") | None => Ok(Format::Svg),
            Some(other) => Err(invalid(
                "plot",
                format!(
                    "file {} has the extension .{other}, not a picture format tdcr writes",
                    path.display()
                ),
                "name it FILE.svg (vector) or FILE.png (raster)",
            )),
        }
    }
}

/// Pixels per SVG pixel of PNG files written by [`Figure::render`].
pub const PNG_SCALE: f64 = 2.0;

impl Figure {
    /// An empty figure with a title.
    pub fn new(title: &str) -> Self {
        Figure {
            title: title.to_string(),
            ..Default::default()
        }
    }

    /// The last panel, created if there is none: where [`Figure::add_shape`] draws.
    pub fn panel_mut(&mut self) -> &mut Panel {
        if self.panels.is_empty() {
            self.panels.push(Panel::default());
        }
        let last = self.panels.len() - 1;
        &mut self.panels[last]
    }

    /// Starts a new panel titled `title` and returns it.
    pub fn add_panel(&mut self, title: &str) -> &mut Panel {
        self.panels.push(Panel::new(title));
        self.panel_mut()
    }

    /// Adds a solved shape to the last panel ([`Panel::add_shape`]).
    pub fn add_shape(&mut self, robot: &Robot, solution: &Solution, style: &Style) {
        self.panel_mut().add_shape(robot, solution, style);
    }

    /// The figure as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        svg::document(self)
    }

    /// The figure as a PNG image at `scale` pixels per SVG pixel (1: the SVG's size), text
    /// in the system's fonts (see [`Png::text`]).
    pub fn to_png(&self, scale: f64) -> Result<Png> {
        png::render(&self.to_svg(), scale)
    }

    /// The figure as the bytes of a file in `format` (PNG at [`PNG_SCALE`]), and whether its
    /// text could be set (false only for PNG on a system without fonts).
    pub fn render(&self, format: Format) -> Result<(Vec<u8>, bool)> {
        match format {
            Format::Svg => Ok((self.to_svg().into_bytes(), true)),
            Format::Png => self.to_png(PNG_SCALE).map(|png| (png.data, png.text)),
        }
    }
}

#[cfg(test)]
mod tests;
