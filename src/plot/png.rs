//! PNG pictures: the figure's SVG rendered with resvg (pure Rust), text set in the system's
//! fonts.
//!
//! Fonts are loaded once per process from the system's font folders (fontconfig's list on
//! Linux, the system folders on macOS and Windows). The figure names Helvetica, Arial,
//! DejaVu Sans and Liberation Sans; the generic `sans-serif` and resvg's fallback `serif`
//! are set to the first of these found, else to any font found, so any installed font sets
//! the text. On a machine without fonts (a bare container) the PNG has no text and
//! [`Png::text`] is false; install a font (for example Debian's `fonts-dejavu-core`) or use
//! SVG, which names the fonts for the viewer to find.

use crate::error::{Result, invalid};
use resvg::tiny_skia::{Pixmap, Transform};
use resvg::usvg::{self, fontdb};
use std::sync::{Arc, OnceLock};

/// Families tried for `sans-serif`, in order.
const PREFERRED: [&str; 4] = ["Helvetica", "Arial", "DejaVu Sans", "Liberation Sans"];

/// A rendered PNG image.
#[derive(Clone, Debug, PartialEq)]
pub struct Png {
    /// The PNG file's bytes.
    pub data: Vec<u8>,
    /// Width (px).
    pub width: u32,
    /// Height (px).
    pub height: u32,
    /// Whether a font was found to set the text in; false: the image has no text.
    pub text: bool,
}

/// The system fonts, loaded on first use.
fn fonts() -> Arc<fontdb::Database> {
    static FONTS: OnceLock<Arc<fontdb::Database>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut db = fontdb::Database::new();
            db.load_system_fonts();
            let families: Vec<String> = db
                .faces()
                .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
                .collect();
            let chosen = PREFERRED
                .iter()
                .find(|p| families.iter().any(|f| f == *p))
                .map(|p| p.to_string())
                .or_else(|| families.first().cloned());
            if let Some(family) = chosen {
                db.set_sans_serif_family(family.clone());
                db.set_serif_family(family);
            }
            Arc::new(db)
        })
        .clone()
}

/// Whether the system has a font for the PNG's text.
pub fn fonts_found() -> bool {
    !fonts().is_empty()
}

/// Renders the SVG document `svg` at `scale` pixels per SVG pixel.
pub fn render(svg: &str, scale: f64) -> Result<Png> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 16.0) {
        return Err(invalid(
            "scale",
            format!("is {scale}, not in (0, 16]"),
            "render at 1 (the SVG's size) or 2 (double resolution)",
        ));
    }
    let fontdb = fonts();
    let text = !fontdb.is_empty();
    let options = usvg::Options {
        fontdb,
        ..Default::default()
    };
    let tree = usvg::Tree::from_str(svg, &options).map_err(|e| {
        invalid(
            "svg",
            format!("cannot be read: {e}"),
            "the figure's SVG is malformed; report it",
        )
    })?;
    let size = tree.size();
    let (width, height) = (
        (size.width() as f64 * scale).round() as u32,
        (size.height() as f64 * scale).round() as u32,
    );
    let mut pixmap = Pixmap::new(width, height).ok_or_else(|| {
        invalid(
            "scale",
            format!("gives an image of {width} x {height} px, which cannot be allocated"),
            "use a smaller scale",
        )
    })?;
    resvg::render(
        &tree,
        Transform::from_scale(scale as f32, scale as f32),
        &mut pixmap.as_mut(),
    );
    let data = pixmap
        .encode_png()
        .map_err(|e| invalid("png", format!("cannot be encoded: {e}"), "use SVG output instead"))?;
    Ok(Png {
        data,
        width,
        height,
        text,
    })
}
