//! Text in the SVG documents: fonts and sizes, escaping, estimated widths, wrapping at a
//! width, and labels with a white halo.

use std::fmt::Write;

/// Body font size (px).
pub(super) const FONT: f64 = 12.0;
/// Title font size (px).
pub(super) const TITLE_FONT: f64 = 17.0;
/// Average glyph advance over the font size, to estimate text widths: 0.6 holds for
/// DejaVu Sans, the widest of the fonts named; Helvetica and Arial are narrower.
const ADVANCE: f64 = 0.6;
/// Font families, first found first: the common sans-serif faces of macOS, Windows and Linux.
pub(super) const FONT_FAMILY: &str = "Helvetica, Arial, 'DejaVu Sans', 'Liberation Sans', sans-serif";

/// `text` with `&`, `<` and `>` escaped for SVG.
pub(super) fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Estimated width (px) of `text` at font size `size`.
pub(super) fn text_width(text: &str, size: f64) -> f64 {
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

/// A text element with a white halo, legible over lines.
pub(super) fn halo_text(svg: &mut String, x: f64, y: f64, anchor: &str, extra: &str, text: &str) {
    let _ = writeln!(
        svg,
        r#"<text x="{x:.1}" y="{y:.1}" text-anchor="{anchor}" stroke="white" stroke-width="3" stroke-linejoin="round" paint-order="stroke"{extra}>{}</text>"#,
        escape(text)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

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
