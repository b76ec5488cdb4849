//! What every cell of a figure shares: the bounds of everything drawn (arrow heads and their
//! labels included) and the scales of the force and distributed-load arrows.

use super::axes::{Unit, unit_for};
use super::{Arrow, ArrowKind, Disk, Panel};
use nalgebra::Vector3;

/// The longest force arrow, relative to the scene's extent.
const FORCE_FRACTION: f64 = 0.2;
/// The longest distributed-load arrow, relative to the scene's extent.
const DISTRIBUTED_FRACTION: f64 = 0.06;
/// Sides of the polygon a disk is drawn as.
const DISK_SIDES: usize = 36;

/// What every cell shares: the scene's bounds and the arrow scales.
pub(super) struct Scene {
    pub(super) lo: Vector3<f64>,
    pub(super) hi: Vector3<f64>,
    /// Largest side of the bounding box (m).
    pub(super) extent: f64,
    /// Arrow length per unit of force (m/N) and of distributed force (m per N/m).
    pub(super) force_scale: f64,
    pub(super) distributed_scale: f64,
    pub(super) unit: Unit,
}

impl Scene {
    pub(super) fn arrow_scale(&self, kind: ArrowKind) -> f64 {
        match kind {
            ArrowKind::Force => self.force_scale,
            ArrowKind::Distributed => self.distributed_scale,
        }
    }

    pub(super) fn arrow_head(&self, a: &Arrow) -> Vector3<f64> {
        a.point + a.vector * self.arrow_scale(a.kind)
    }

    /// A point beyond the head of a labelled arrow, kept inside the views so the label fits.
    pub(super) fn label_room(&self, a: &Arrow) -> Vector3<f64> {
        let room = if a.label.is_some() { 0.06 * self.extent } else { 0.0 };
        self.arrow_head(a) + a.vector.try_normalize(0.0).unwrap_or_default() * room
    }
}

/// Whether every coordinate of `p` is finite (non-finite points are not drawn).
pub(super) fn finite(p: &Vector3<f64>) -> bool {
    p.iter().all(|x| x.is_finite())
}

/// Points on the rim of a disk.
pub(super) fn rim(d: &Disk) -> impl Iterator<Item = Vector3<f64>> + '_ {
    (0..DISK_SIDES).map(move |k| {
        let t = std::f64::consts::TAU * k as f64 / DISK_SIDES as f64;
        d.center + d.rotation * Vector3::new(d.radius * t.cos(), d.radius * t.sin(), 0.0)
    })
}

/// Every point drawn in a panel except the arrow heads.
pub(super) fn points(panel: &Panel) -> impl Iterator<Item = Vector3<f64>> + '_ {
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

/// The smallest box holding `points` (lower and upper corner, m); zeros when empty.
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

/// The scene of `panels`: their bounds (with room for the arrows and their labels) and the
/// arrow scales, the longest arrow of each kind a fixed fraction of the extent.
pub(super) fn scene(panels: &[Panel]) -> Scene {
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
