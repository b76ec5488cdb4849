//! The options every picture of `solve` and `sweep` takes (title, subtitle, views, size,
//! text size), and the parsing of `--views`.

use clap::Args;
use tdcr::plot::{Figure, View};

/// How a shape picture is laid out (docs/cli.md, "Pictures").
#[derive(Args, Debug, Clone, Default)]
pub struct PictureArgs {
    /// The picture's title instead of the file name and what was solved (`--title ""`: none).
    #[arg(long, value_name = "TEXT", requires = "plot")]
    pub title: Option<String>,
    /// Leave out the subtitle (the solver's statistics or the swept ranges).
    #[arg(long, requires = "plot")]
    pub no_subtitle: bool,
    /// The views drawn, comma-separated, in order: top, side, front, perspective (default:
    /// every view that shows more than a dot or a stub).
    #[arg(long, value_name = "VIEWS", value_parser = parse_views, requires = "plot")]
    pub views: Option<Views>,
    /// The picture's width in px (SVG units; a PNG has twice as many pixels); the views
    /// shrink or grow to fill it (default: 430 px views).
    #[arg(long, value_name = "PX", value_parser = parse_width, requires = "plot")]
    pub width: Option<f64>,
    /// Body text size in px at the picture's width (default 12; titles and ticks follow).
    #[arg(long, value_name = "PX", value_parser = parse_font_size, requires = "plot")]
    pub font_size: Option<f64>,
}

/// A list of views (`--views`).
#[derive(Clone, Debug)]
pub struct Views(pub Vec<View>);

impl PictureArgs {
    /// `figure` with these options applied.
    pub fn apply(&self, figure: &mut Figure) {
        if let Some(title) = &self.title {
            figure.title = title.clone();
        }
        if self.no_subtitle {
            figure.subtitle.clear();
        }
        figure.views = self.views.as_ref().map(|v| v.0.clone());
        figure.width = self.width;
        figure.font_size = self.font_size;
    }
}

fn parse_views(text: &str) -> Result<Views, String> {
    let mut views = Vec::new();
    for name in text.split(',').map(str::trim) {
        let view = View::from_name(name).ok_or_else(|| {
            format!("`{name}` is not a view; the views are top, side, front and perspective (e.g. side,perspective)")
        })?;
        if views.contains(&view) {
            return Err(format!("the view `{name}` is given twice"));
        }
        views.push(view);
    }
    Ok(Views(views))
}

/// Widths from 200 px (two small views) to 10 000 px.
fn parse_width(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(w) if (200.0..=10_000.0).contains(&w) => Ok(w),
        _ => Err(format!("`{text}` is not a width from 200 to 10000 px")),
    }
}

/// Text sizes from 4 to 48 px.
fn parse_font_size(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(f) if (4.0..=48.0).contains(&f) => Ok(f),
        _ => Err(format!("`{text}` is not a text size from 4 to 48 px")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_parse_in_order_and_reject_unknown_or_repeated_names() {
        assert_eq!(
            parse_views("side, perspective").unwrap().0,
            vec![View::Side, View::Perspective]
        );
        assert!(parse_views("side,iso").unwrap_err().contains("`iso` is not a view"));
        assert!(parse_views("top,top").unwrap_err().contains("twice"));
    }
}
