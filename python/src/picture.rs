//! `tdcr.figure`: the command line's picture of a solved shape (SVG, or PNG through resvg;
//! `tdcr solve --plot`) written from Python.

use crate::errors::invalid;
use crate::robot::PyRobot;
use crate::solution::PySolution;
use pyo3::prelude::*;
use std::path::PathBuf;
use tdcr::plot::{Figure, Format, Style, View, solved_shape_legend};

/// figure(robot, solution, path, *, views=None, width=None, font_size=None, title=None, disks=None) -> None
///
/// Draws `solution` (a solution of `robot`) into `path` as `tdcr solve --plot` does: PNG if
/// the name ends in .png, else SVG; the backbone, the tendons in their colours (slack ones
/// dashed), spacer disks and the legend. `views`: a list of "top", "side", "front",
/// "perspective" (default: every view that shows more than a dot); `width`: the picture's
/// width in px, 200 to 10 000 (a PNG has twice as many pixels; default 430 px per view);
/// `font_size`: 4 to 48 px (default 12); `title` (default "solved shape"; "" for none);
/// `disks`: the number of spacer disks drawn (default: the robot file's, else about 2.5
/// tendon offsets apart; 0: none). Raises `tdcr.InvalidInput` for a bad option and
/// `tdcr.Error` when the file cannot be written; warns when no font is found for a PNG's text.
#[pyfunction]
#[pyo3(signature = (robot, solution, path, *, views=None, width=None, font_size=None, title=None, disks=None))]
#[allow(clippy::too_many_arguments)]
pub fn figure(
    py: Python<'_>,
    robot: &PyRobot,
    solution: &PySolution,
    path: PathBuf,
    views: Option<Vec<String>>,
    width: Option<f64>,
    font_size: Option<f64>,
    title: Option<String>,
    disks: Option<usize>,
) -> PyResult<()> {
    let format = Format::from_path(&path).map_err(crate::errors::to_py)?;
    let mut figure = Figure::new(title.as_deref().unwrap_or("solved shape"));
    if let Some(names) = views {
        let mut chosen = Vec::new();
        for name in &names {
            let view = View::from_name(name).ok_or_else(|| {
                invalid(format!(
                    "figure: `{name}` is not a view; the views are top, side, front and perspective"
                ))
            })?;
            chosen.push(view);
        }
        figure.views = Some(chosen);
    }
    if let Some(w) = width.filter(|w| !(200.0..=10_000.0).contains(w)) {
        return Err(invalid(format!("figure: width {w} px is not from 200 to 10000 px")));
    }
    if let Some(f) = font_size.filter(|f| !(4.0..=48.0).contains(f)) {
        return Err(invalid(format!("figure: font_size {f} px is not from 4 to 48 px")));
    }
    figure.width = width;
    figure.font_size = font_size;
    let r = &robot.file.robot;
    let mut style = Style::new("#000000");
    style.slack_tendons = true;
    style.tendon_colors = true;
    style.disks = disks;
    // The file's own disks, unless `disks` asks for others.
    style.placed_disks = robot.file.disks.clone().filter(|_| disks.is_none());
    figure.add_shape(r, &solution.solution, &style);
    figure.legend = solved_shape_legend(r, &solution.solution, &style);
    let (bytes, text) = py
        .detach(|| figure.render(format))
        .map_err(|e| crate::errors::Error::new_err(format!("figure: cannot draw {}: {e}", path.display())))?;
    std::fs::write(&path, bytes)
        .map_err(|e| crate::errors::Error::new_err(format!("figure: cannot write {}: {e}", path.display())))?;
    if !text {
        let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
        let message = c"no fonts found on this system, so the PNG has no text; install a font (for example fonts-dejavu-core) or write SVG";
        PyErr::warn(py, &category, message, 1)?;
    }
    Ok(())
}
