//! `[[segment]]`: a backbone given as segments joined end to end, each with its own section
//! and precurvature, and tendons that end where a segment ends (`end_segment`): the rules of
//! these tables and the rod they build ([`Rod::segmented`]).

use super::check::Checker;
use super::tables::{SegmentTable, TendonTable};
use crate::model::rod::{Rod, Section, Segment, Stiffness, shear_modulus};
use nalgebra::Vector3;

/// The stiffness keys of a segment given by its stiffnesses, with their units.
const STIFFNESS_KEYS: [(&str, &str); 4] = [
    ("bending_stiffness", " N m^2"),
    ("torsion_stiffness", " N m^2"),
    ("axial_stiffness", " N"),
    ("shear_stiffness", " N"),
];

impl SegmentTable {
    /// The four stiffnesses as given: E I, G J (N m^2), E A, G A (N).
    fn stiffnesses(&self) -> [Option<f64>; 4] {
        [
            self.bending_stiffness,
            self.torsion_stiffness,
            self.axial_stiffness,
            self.shear_stiffness,
        ]
    }

    /// Whether any key of the geometric form is given.
    fn has_geometry(&self) -> bool {
        [
            self.outer_radius,
            self.inner_radius,
            self.youngs_modulus,
            self.poisson_ratio,
            self.shear_modulus,
        ]
        .iter()
        .any(Option::is_some)
    }

    /// The segment of the library (the table passed its checks).
    fn segment(&self) -> Segment {
        let section = if self.has_geometry() {
            let e = self.youngs_modulus.unwrap_or(f64::NAN);
            let g = match (self.poisson_ratio, self.shear_modulus) {
                (Some(nu), _) => shear_modulus(e, nu),
                (None, g) => g.unwrap_or(f64::NAN),
            };
            Section::tube(
                self.outer_radius.unwrap_or(f64::NAN),
                self.inner_radius.unwrap_or(0.0),
                e,
                g,
            )
        } else {
            let [ei, gj, ea, ga] = self.stiffnesses().map(|k| k.unwrap_or(f64::NAN));
            Section::explicit(ea, ga, ei, ei, gj)
        };
        Segment {
            length: self.length,
            section,
            precurvature: self.precurvature.map_or_else(Vector3::zeros, Vector3::from),
        }
    }
}

/// The rod of segments that passed their checks.
pub(super) fn rod(segments: &[SegmentTable]) -> Rod {
    Rod::segmented(&segments.iter().map(SegmentTable::segment).collect::<Vec<_>>())
}

/// Where each segment of `rod` ends (m, the last at the tip); empty for a rod without
/// segments. The same sums [`Rod::segmented`] formed, so a tendon that ends at a segment's
/// end ends exactly at the breakpoint there.
pub(super) fn ends(rod: &Rod) -> Vec<f64> {
    match &rod.stiffness {
        Stiffness::Segments { ends, .. } => ends.clone(),
        _ => Vec::new(),
    }
}

/// The backbone's length of `segments` (m), NaN unless every one was read.
pub(super) fn length(segments: &[Option<SegmentTable>]) -> f64 {
    let mut total = 0.0;
    for g in segments {
        match g {
            Some(g) => total += g.length,
            None => return f64::NAN,
        }
    }
    total
}

impl Checker<'_> {
    /// The rules of `[[segment]]` number `i` (from 0): a positive length, a section whole in
    /// one of its two forms (geometry or the four stiffnesses), a finite precurvature.
    pub(super) fn segment(&mut self, i: usize, g: &SegmentTable) {
        let path = format!("segment[{}]", i + 1);
        let field = |key: &str| format!("{path}.{key}");
        self.positive(&field("length"), g.length, " m");
        let given: Vec<&str> = STIFFNESS_KEYS
            .iter()
            .zip(g.stiffnesses())
            .filter_map(|((key, _), k)| k.map(|_| *key))
            .collect();
        match (g.has_geometry(), given.first()) {
            (true, Some(key)) => self.report(
                &field(key),
                "is given together with the section's geometry: give a segment's section by its \
                 geometry (`outer_radius`, `inner_radius`, `youngs_modulus`, `poisson_ratio` or \
                 `shear_modulus`) or by its four stiffnesses (`bending_stiffness`, `torsion_stiffness`, \
                 `axial_stiffness`, `shear_stiffness`), not a mix"
                    .into(),
            ),
            (false, None) => self.report(
                &path,
                format!(
                    "in [[segment]] #{} has no section: give `outer_radius` (m), `youngs_modulus` (Pa) and \
                     `poisson_ratio` (or `shear_modulus`), or the four stiffnesses `bending_stiffness` (E I), \
                     `torsion_stiffness` (G J) in N m^2 and `axial_stiffness` (E A), `shear_stiffness` (G A) in N",
                    i + 1
                ),
            ),
            (true, None) => {
                for (key, value, unit) in [
                    ("outer_radius", g.outer_radius, "m"),
                    ("youngs_modulus", g.youngs_modulus, "Pa"),
                ] {
                    if value.is_none() {
                        self.report(
                            &field(key),
                            format!(
                                "is required but missing in [[segment]] #{} ({unit}), which gives its section \
                                 by its geometry",
                                i + 1
                            ),
                        );
                    }
                }
                self.tube(
                    &path,
                    g.outer_radius.unwrap_or(1.0),
                    g.inner_radius.unwrap_or(0.0),
                    g.youngs_modulus.unwrap_or(1.0),
                    (g.poisson_ratio, g.shear_modulus),
                );
            }
            (false, Some(_)) => {
                for ((key, unit), value) in STIFFNESS_KEYS.iter().zip(g.stiffnesses()) {
                    match value {
                        Some(k) => self.positive(&field(key), k, unit),
                        None => self.report(
                            &field(key),
                            format!(
                                "is required but missing in [[segment]] #{}: a section given by its \
                                 stiffnesses needs all four of `bending_stiffness`, `torsion_stiffness`, \
                                 `axial_stiffness` and `shear_stiffness`",
                                i + 1
                            ),
                        ),
                    }
                }
            }
        }
        self.vector(&field("precurvature"), &g.precurvature, " rad/m");
    }

    /// The rules of `end_segment` of `[[tendon]]` number `i` (from 0) in a file of
    /// `segments` `[[segment]]` tables: a segment's number, 1 to `segments`, and not with `end`.
    pub(super) fn end_segment(&mut self, i: usize, t: &TendonTable, segments: usize) {
        let Some(k) = t.end_segment else {
            return;
        };
        let field = format!("tendon[{}].end_segment", i + 1);
        if t.end.is_some() {
            self.report(
                &field,
                "is given together with `end`: say where the tendon ends by `end` (m) or by the \
                 number of the segment it ends at (`end_segment`), not both"
                    .into(),
            );
        } else if segments == 0 {
            self.report(
                &field,
                format!(
                    "is {k}, but the file gives the rod as [rod], which has no segments: give `end` (m), \
                     or give the backbone as [[segment]] tables"
                ),
            );
        } else if k == 0 || k > segments {
            self.report(
                &field,
                format!(
                    "is {k}, but the file has {segments} [[segment]] table(s): give a segment's number, 1 to \
                     {segments} (segment 1 starts at the base)"
                ),
            );
        }
    }
}

/// A problem's wording for a file with both `[rod]` and `[[segment]]`.
pub(super) const BOTH: &str = "has both [rod] and [[segment]] tables: give the backbone as one [rod] \
    (a uniform rod) or as [[segment]] tables (each with its own length, section and precurvature), not both";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_add_up_and_unread_segments_give_nan() {
        let table = |length: f64| SegmentTable {
            length,
            outer_radius: Some(0.001),
            inner_radius: None,
            youngs_modulus: Some(1e9),
            poisson_ratio: Some(0.3),
            shear_modulus: None,
            bending_stiffness: None,
            torsion_stiffness: None,
            axial_stiffness: None,
            shear_stiffness: None,
            precurvature: None,
        };
        assert_eq!(length(&[Some(table(0.1)), Some(table(0.2))]), 0.1 + 0.2);
        assert!(length(&[Some(table(0.1)), None]).is_nan());
        let built = rod(&[table(0.1), table(0.2)]);
        assert_eq!(ends(&built), vec![0.1, 0.1 + 0.2]);
        assert_eq!(built.length, 0.1 + 0.2);
    }
}
