//! Where everything of a figure goes: the document's width, the grid of cells (one panel in
//! four views, or small multiples: a column per panel, a row per view) and the header.

use super::Figure;
use super::text::{FONT, TITLE_FONT, wrap};
use super::view::{VIEWS, View};

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
/// Smallest cell of small multiples (px).
const MIN_CELL: f64 = 180.0;
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
    /// Top of the cell grid (below the header) and of the legend (px).
    pub(super) grid_top: f64,
    pub(super) legend_top: f64,
    pub(super) multiples: bool,
}

/// The layout of `figure` with `panels` panels: one panel in four cells (2 x 2), several as
/// small multiples (a column per panel, a row per view) at a common cell size.
pub(super) fn layout(figure: &Figure, panels: usize) -> Layout {
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
