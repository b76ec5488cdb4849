//! The legend under the cells: entries laid out in columns with wrapped labels, and each
//! entry's symbol (line, disk, arrow, dot) and text.

use super::layout::MARGIN;
use super::tension::{LIGHTEST, lighter};
use super::text::{FONT, escape, text_width, wrap};
use super::{LegendEntry, Symbol};
use std::fmt::Write;

/// The legend laid out in columns: each entry's wrapped label lines and position.
pub(super) struct LegendLayout {
    /// (entry, x, y of the first baseline, label lines).
    pub(super) items: Vec<(usize, f64, f64, Vec<String>)>,
    pub(super) height: f64,
}

/// Width of a legend entry's symbol and the space after it (px).
const SYMBOL: f64 = 38.0;
/// Segments of a [`Symbol::Ramp`] sample.
const RAMP_STEPS: usize = 6;
/// Line height of legend labels (px).
const LEGEND_LINE: f64 = 15.0;

/// `legend` laid out in up to 4 columns across `width` (px) from `top` (px).
pub(super) fn legend_layout(legend: &[LegendEntry], width: f64, top: f64) -> LegendLayout {
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

/// One legend entry: its symbol at (`x`, `y`) (px, `y` the first baseline) and its label `lines`.
pub(super) fn legend_entry(svg: &mut String, entry: &LegendEntry, x: f64, y: f64, lines: &[String]) {
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
        Symbol::Ramp => {
            // Six segments from the colour to its lightest shade, narrowing by a third.
            for k in 0..RAMP_STEPS {
                let share = k as f64 / (RAMP_STEPS - 1) as f64;
                let _ = write!(
                    svg,
                    r#"<line x1="{}" y1="{mid}" x2="{}" y2="{mid}" stroke="{}" stroke-width="{}"/>"#,
                    x + 30.0 * k as f64 / RAMP_STEPS as f64,
                    x + 30.0 * (k + 1) as f64 / RAMP_STEPS as f64,
                    lighter(color, LIGHTEST * share),
                    entry.width * (1.0 - share / 3.0)
                );
            }
            writeln!(svg)
        }
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
