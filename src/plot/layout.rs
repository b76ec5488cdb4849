//! Where everything of a figure goes: the document's width, the grid of cells (one panel in
//! four views, or small multiples: a column per panel, a row per view) and the header.

use super::Figure;
use super::text::{FONT, TITLE_FONT, wrap};
use super::view::View;

/// Outer margin (px).
pub(super) const MARGIN: f64 = 24.0;
/// Space between a cell's frame and what it shows (px).
pub(super) const PAD: f64 = 14.0;
/// Space between a cell's top edge and what it shows, below the view's title (px).
pub(super) const TOP_PAD: f64 = 28.0;
/// Gutter left of a cell: tick numbers and the vertical axis label (px).
pub(super) const LEFT: f64 = 58.0;
/// Gutter under a cell: tick numbers and the horizontal axis label (px).
const BOTTOM: f64 = 42.0;
/// Space between the cells of a row that has no tick numbers on the left (px).
pub(super) const GAP: f64 = 16.0;
/// Height of the panel titles over the columns of small multiples (px).
const COLUMN_HEAD: f64 = 40.0;
/// Cell size of the single-panel layout (px).
const CELL: f64 = 430.0;
/// Width the small multiples aim at (px); cells between [`MIN_CELL`] and [`MAX_CELL`].
const MULTIPLES_WIDTH: f64 = 1560.0;
/// Smallest cell of small multiples at their automatic size (px).
const MIN_CELL: f64 = 180.0;
/// Smallest cell of any layout, when a width is asked for (px): tick numbers need room.
const LEAST_CELL: f64 = 100.0;
/// Largest cell of small multiples (px).
const MAX_CELL: f64 = 300.0;

/// One cell: a view of one panel at a position in the document.
pub(super) struct Cell {
    pub(super) panel: usize,
    pub(super) view: View,
    pub(super) x: f64,
    pub(super) y: f64,
    /// Tick numbers and the axis label on the left side.
    pub(super) numbers_left: bool,
}

/// The document's layout: its size, the cells and where the header and legend go.
pub(super) struct Layout {
    pub(super) width: f64,
    pub(super) cell: f64,
    pub(super) cells: Vec<Cell>,
    /// Lines of the title and the subtitle.
    pub(super) title: Vec<String>,
    pub(super) subtitle: Vec<String>,
    /// Top of the legend (px).
    pub(super) legend_top: f64,
    pub(super) multiples: bool,
}

/// The layout of `figure` with `panels` panels drawn in `views`, `width` px wide if given
/// (in the layout's own px, before any zoom): one panel in a cell per view (four in 2 x 2,
/// fewer in one row), several as small multiples (a column per panel, a row per view) at a
/// common cell size.
pub(super) fn layout(figure: &Figure, panels: usize, views: &[View], width: Option<f64>) -> Layout {
    let multiples = panels > 1;
    // Small multiples wrap after `figure.columns` panels into blocks of rows.
    let wrap_at = figure.columns.unwrap_or(panels).clamp(1, panels.max(1));
    let blocks = panels.div_ceil(wrap_at);
    let columns = if multiples {
        wrap_at
    } else if views.len() == 4 {
        2
    } else {
        views.len().max(1)
    };
    let cell = match (width, multiples) {
        (Some(w), true) => ((w - 2.0 * MARGIN - LEFT - (columns - 1) as f64 * GAP) / columns as f64).max(LEAST_CELL),
        (Some(w), false) => ((w - 2.0 * MARGIN) / columns as f64 - LEFT).max(LEAST_CELL),
        (None, true) => ((MULTIPLES_WIDTH - 2.0 * MARGIN - LEFT - (columns - 1) as f64 * GAP) / columns as f64)
            .clamp(MIN_CELL, MAX_CELL),
        (None, false) => CELL,
    };
    let width = if multiples {
        2.0 * MARGIN + LEFT + columns as f64 * cell + (columns - 1) as f64 * GAP
    } else {
        2.0 * MARGIN + columns as f64 * (LEFT + cell)
    };
    let text_width = width - 2.0 * MARGIN;
    let title = if figure.title.trim().is_empty() {
        Vec::new()
    } else {
        wrap(&figure.title, text_width, TITLE_FONT)
    };
    let subtitle: Vec<String> = figure
        .subtitle
        .iter()
        .filter(|line| !line.trim().is_empty())
        .flat_map(|line| wrap(line, text_width, FONT))
        .collect();
    let header = if title.is_empty() && subtitle.is_empty() {
        MARGIN
    } else {
        MARGIN + 21.0 * title.len() as f64 + 16.0 * subtitle.len() as f64 + 14.0
    };
    let grid_top = header + if multiples { COLUMN_HEAD } else { 0.0 };
    let mut cells = Vec::new();
    // Height of one block of small multiples: its views' rows and the next block's titles.
    let block = views.len() as f64 * (cell + BOTTOM) + COLUMN_HEAD;
    if multiples {
        for (row, &view) in views.iter().enumerate() {
            for panel in 0..panels {
                let (b, column) = (panel / wrap_at, panel % wrap_at);
                cells.push(Cell {
                    panel,
                    view,
                    x: MARGIN + LEFT + column as f64 * (cell + GAP),
                    y: grid_top + b as f64 * block + row as f64 * (cell + BOTTOM),
                    numbers_left: column == 0,
                });
            }
        }
    } else {
        for (k, &view) in views.iter().enumerate() {
            cells.push(Cell {
                panel: 0,
                view,
                x: MARGIN + LEFT + (k % columns) as f64 * (cell + LEFT),
                y: grid_top + (k / columns) as f64 * (cell + BOTTOM),
                numbers_left: true,
            });
        }
    }
    let rows = if multiples {
        views.len() * blocks
    } else {
        views.len().div_ceil(columns)
    };
    let titles = if multiples {
        (blocks - 1) as f64 * COLUMN_HEAD
    } else {
        0.0
    };
    Layout {
        width,
        cell,
        cells,
        title,
        subtitle,
        legend_top: grid_top + rows as f64 * (cell + BOTTOM) + titles + 6.0,
        multiples,
    }
}
