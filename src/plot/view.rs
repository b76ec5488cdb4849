//! How world points become pixels: the four views of a shape (top, side, front and a
//! perspective), the perspective camera, and the projection of one cell.

use nalgebra::{Vector2, Vector3};

/// A view of a panel: three orthographic projections at one scale and a perspective.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Looking down the world z axis: x right, y up.
    Top,
    /// Looking along world +y: x right, z up.
    Side,
    /// Looking along world -x: y right, z up.
    Front,
    /// An oblique perspective (azimuth -60 deg, elevation 25 deg) with the world axes.
    Perspective,
}

/// Every view, in the order of the cells.
pub const VIEWS: [View; 4] = [View::Top, View::Side, View::Front, View::Perspective];

impl View {
    /// The view's name as the command line's `--views` writes it: `top`, `side`, `front`,
    /// `perspective`.
    pub fn name(self) -> &'static str {
        match self {
            View::Top => "top",
            View::Side => "side",
            View::Front => "front",
            View::Perspective => "perspective",
        }
    }

    /// The view named `name` ([`View::name`]), if any.
    pub fn from_name(name: &str) -> Option<View> {
        VIEWS.into_iter().find(|v| v.name() == name)
    }

    /// The world axes (0 = x, 1 = y, 2 = z) an orthographic view shows, horizontal then
    /// vertical; `None` for the perspective.
    pub(super) fn axis_indices(self) -> Option<(usize, usize)> {
        match self {
            View::Top => Some((0, 1)),
            View::Side => Some((0, 2)),
            View::Front => Some((1, 2)),
            View::Perspective => None,
        }
    }

    pub(super) fn title(self) -> &'static str {
        match self {
            View::Top => "top view (XY)",
            View::Side => "side view (XZ)",
            View::Front => "front view (YZ)",
            View::Perspective => "perspective",
        }
    }

    /// Axis names (horizontal, vertical) of an orthographic view.
    pub(super) fn axes(self) -> (&'static str, &'static str) {
        match self {
            View::Top => ("x", "y"),
            View::Side => ("x", "z"),
            View::Front => ("y", "z"),
            View::Perspective => ("", ""),
        }
    }

    /// The world direction out of the screen, towards the viewer (orthographic views).
    pub(super) fn toward_viewer(self) -> Vector3<f64> {
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
    pub(super) eye: Vector3<f64>,
    pub(super) right: Vector3<f64>,
    pub(super) up: Vector3<f64>,
    pub(super) forward: Vector3<f64>,
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
pub(super) struct Projection {
    pub(super) view: View,
    pub(super) camera: Camera,
    /// px per unit of [`Projection::raw`] (px/m in the orthographic views).
    pub(super) scale: f64,
    /// px.
    pub(super) offset: Vector2<f64>,
    /// Cell size (px).
    pub(super) size: f64,
}

impl Projection {
    /// Unscaled 2-D coordinates, vertical up.
    pub(super) fn raw(&self, p: &Vector3<f64>) -> Vector2<f64> {
        match self.view {
            View::Top => Vector2::new(p.x, p.y),
            View::Side => Vector2::new(p.x, p.z),
            View::Front => Vector2::new(p.y, p.z),
            View::Perspective => self.camera.project(p),
        }
    }

    /// Pixel coordinates inside the cell, y down.
    pub(super) fn px(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let r = self.raw(p) * self.scale + self.offset;
        Vector2::new(r.x, self.size - r.y)
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
}
