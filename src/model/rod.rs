//! The elastic backbone: length, cross-section stiffness and reference (stress-free) strains.

use nalgebra::Vector3;
use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;

/// Stiffness of one cross-section: `kse` = diag(GA, GA, EA) (N), the paper's D, and
/// `kbt` = diag(E Ixx, E Iyy, G J) (N m^2), the paper's C with torsion G J (docs/reference.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// Shear and extension stiffness (GA, GA, EA), body frame, N.
    pub kse: Vector3<f64>,
    /// Bending and torsion stiffness (E Ixx, E Iyy, G J), body frame, N m^2.
    pub kbt: Vector3<f64>,
}

/// Shear modulus from Young's modulus and Poisson's ratio, G = E / (2 (1 + nu)) (Pa).
pub fn shear_modulus(youngs_modulus: f64, poisson_ratio: f64) -> f64 {
    youngs_modulus / (2.0 * (1.0 + poisson_ratio))
}

impl Section {
    /// A solid circular section of `radius` (m), Young's modulus `e` and shear modulus `g` (Pa).
    pub fn solid_circle(radius: f64, e: f64, g: f64) -> Self {
        Self::tube(radius, 0.0, e, g)
    }

    /// A circular tube with `outer` and `inner` radii (m), moduli `e`, `g` (Pa).
    pub fn tube(outer: f64, inner: f64, e: f64, g: f64) -> Self {
        let area = PI * (outer.powi(2) - inner.powi(2));
        let i = PI / 4.0 * (outer.powi(4) - inner.powi(4));
        Self::explicit(e * area, g * area, e * i, e * i, g * 2.0 * i)
    }

    /// Explicit stiffnesses: EA and GA (N), E Ixx, E Iyy and G J (N m^2).
    pub fn explicit(ea: f64, ga: f64, eixx: f64, eiyy: f64, gj: f64) -> Self {
        Section {
            kse: Vector3::new(ga, ga, ea),
            kbt: Vector3::new(eixx, eiyy, gj),
        }
    }
}

/// Section stiffness and its arc-length derivative at one s (eq. 4 needs D', C').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionPoint {
    /// Stiffness at s.
    pub section: Section,
    /// d kse / ds (N/m).
    pub kse_s: Vector3<f64>,
    /// d kbt / ds (N m).
    pub kbt_s: Vector3<f64>,
}

/// Reference strains and their derivatives at one s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrainPoint {
    /// v*(s), body frame, dimensionless.
    pub v_star: Vector3<f64>,
    /// u*(s), body frame, rad/m.
    pub u_star: Vector3<f64>,
    /// dv*/ds (1/m).
    pub v_star_s: Vector3<f64>,
    /// du*/ds (rad/m^2).
    pub u_star_s: Vector3<f64>,
}

/// How the stiffness varies along the backbone.
#[derive(Clone)]
pub enum Stiffness {
    /// The same section everywhere.
    Uniform(Section),
    /// A section (with exact derivative) given as a function of s (m).
    Varying(Arc<dyn Fn(f64) -> SectionPoint + Send + Sync>),
    /// One section per segment of a [`Rod::segmented`] rod: `sections[k]` on the segment
    /// that ends at `ends[k]` (m, increasing, the last at the tip).
    Segments {
        /// Where each segment ends (m).
        ends: Vec<f64>,
        /// Each segment's section.
        sections: Vec<Section>,
    },
}

/// The stress-free shape of the backbone, as strains.
#[derive(Clone)]
pub enum ReferenceStrains {
    /// Straight and unstretched: v* = (0, 0, 1), u* = 0.
    Straight,
    /// Constant strains (constant precurvature u*, body frame, rad/m).
    Constant {
        /// v*, dimensionless.
        v_star: Vector3<f64>,
        /// u*, rad/m.
        u_star: Vector3<f64>,
    },
    /// Strains with exact derivatives as a function of s (m).
    Varying(Arc<dyn Fn(f64) -> StrainPoint + Send + Sync>),
    /// One constant precurvature per segment of a [`Rod::segmented`] rod (v* = (0, 0, 1)):
    /// `u_star[k]` (body frame, rad/m) on the segment that ends at `ends[k]` (m).
    Segments {
        /// Where each segment ends (m).
        ends: Vec<f64>,
        /// Each segment's precurvature u* (body frame, rad/m).
        u_star: Vec<Vector3<f64>>,
    },
}

/// One segment of a rod whose section or precurvature changes from segment to segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The segment's length (m).
    pub length: f64,
    /// Its cross-section stiffness.
    pub section: Section,
    /// Its constant precurvature u* (body frame, rad/m); zero for a straight segment.
    pub precurvature: Vector3<f64>,
}

/// The index of the segment of a rod with segments ending at `ends` that holds the stretch
/// of backbone ending at `segment_end` (m): the first segment that ends at or after it.
fn segment_index(ends: &[f64], segment_end: f64) -> usize {
    ends.iter()
        .position(|&e| e >= segment_end)
        .unwrap_or(ends.len().saturating_sub(1))
}

/// The geometry and material a circular rod was built from, kept so that validation can
/// name the input that is wrong (a negative radius would otherwise square away unnoticed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Outer radius (m).
    pub outer_radius: f64,
    /// Inner radius (m), 0 for a solid rod.
    pub inner_radius: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio nu, in (-1, 0.5].
    pub poisson_ratio: f64,
}

/// The elastic backbone.
#[derive(Clone, Debug)]
pub struct Rod {
    /// Backbone length L (m).
    pub length: f64,
    /// Cross-section stiffness along s.
    pub stiffness: Stiffness,
    /// Reference strains v*(s), u*(s).
    pub reference: ReferenceStrains,
    /// Geometry and material of a circular rod, when it was built from them.
    pub geometry: Option<Geometry>,
}

impl Rod {
    /// A straight rod of uniform section.
    pub fn new(length: f64, section: Section) -> Self {
        Rod {
            length,
            stiffness: Stiffness::Uniform(section),
            reference: ReferenceStrains::Straight,
            geometry: None,
        }
    }

    /// A straight solid circular rod of `radius` (m), Young's modulus `e` (Pa) and Poisson's
    /// ratio `nu`, torsion G J with G = E / (2 (1 + nu)).
    pub fn solid_circle(length: f64, radius: f64, e: f64, nu: f64) -> Self {
        Self::tube(length, radius, 0.0, e, nu)
    }

    /// A straight circular tube with `outer` and `inner` radii (m), Young's modulus `e` (Pa)
    /// and Poisson's ratio `nu`.
    pub fn tube(length: f64, outer: f64, inner: f64, e: f64, nu: f64) -> Self {
        let mut rod = Self::new(length, Section::tube(outer, inner, e, shear_modulus(e, nu)));
        rod.geometry = Some(Geometry {
            outer_radius: outer,
            inner_radius: inner,
            youngs_modulus: e,
            poisson_ratio: nu,
        });
        rod
    }

    /// The same rod with a constant precurvature `u_star` (body frame, rad/m).
    pub fn with_precurvature(mut self, u_star: Vector3<f64>) -> Self {
        self.reference = ReferenceStrains::Constant {
            v_star: Vector3::z(),
            u_star,
        };
        self
    }

    /// A straight rod of segments joined end to end, from the base: each with its own
    /// section and constant precurvature (both jump where one segment meets the next). Its
    /// length is the sum of the segments' lengths; the segment ends are breakpoints of the
    /// robot ([`Rod::segment_ends`]), so that meshes put a node on each side of them.
    pub fn segmented(segments: &[Segment]) -> Self {
        let mut ends = Vec::with_capacity(segments.len());
        let mut end = 0.0;
        for segment in segments {
            end += segment.length;
            ends.push(end);
        }
        Rod {
            length: end,
            stiffness: Stiffness::Segments {
                ends: ends.clone(),
                sections: segments.iter().map(|g| g.section).collect(),
            },
            reference: ReferenceStrains::Segments {
                ends,
                u_star: segments.iter().map(|g| g.precurvature).collect(),
            },
            geometry: None,
        }
    }

    /// Where the segments of a [`Rod::segmented`] rod meet (m, inside (0, L), increasing):
    /// the arc lengths where its section or precurvature may jump. Empty for other rods.
    pub fn segment_ends(&self) -> Vec<f64> {
        let mut out: Vec<f64> = self.segment_end_points().collect();
        out.sort_by(f64::total_cmp);
        out.dedup();
        out
    }

    /// The segment ends of [`Rod::segment_ends`] as the stiffness and the precurvature give
    /// them (inside (0, L), neither sorted nor deduplicated), without a buffer.
    pub(crate) fn segment_end_points(&self) -> impl Iterator<Item = f64> + '_ {
        let stiffness = match &self.stiffness {
            Stiffness::Segments { ends, .. } => &ends[..],
            _ => &[],
        };
        let reference = match &self.reference {
            ReferenceStrains::Segments { ends, .. } => &ends[..],
            _ => &[],
        };
        stiffness
            .iter()
            .chain(reference)
            .copied()
            .filter(|&s| s > 0.0 && s < self.length)
    }

    /// Checks the segments of a rod of segments: as many sections and precurvatures as
    /// segment ends, at least one, each segment of positive finite length, the last ending
    /// at the rod's length. Other rods have nothing to check here.
    ///
    /// # Errors
    /// [`crate::Error::InvalidInput`] on `rod.segments` saying which rule is broken.
    pub fn validate_segments(&self) -> crate::Result<()> {
        let lists: Vec<(&[f64], usize)> = [
            match &self.stiffness {
                Stiffness::Segments { ends, sections } => Some((&ends[..], sections.len())),
                _ => None,
            },
            match &self.reference {
                ReferenceStrains::Segments { ends, u_star } => Some((&ends[..], u_star.len())),
                _ => None,
            },
        ]
        .into_iter()
        .flatten()
        .collect();
        for (ends, values) in lists {
            let problem = if ends.is_empty() || ends.len() != values {
                Some(format!(
                    "has {} segment end(s) but {values} section(s) or precurvature(s)",
                    ends.len()
                ))
            } else if let Some(k) =
                (0..ends.len()).find(|&k| !(ends[k].is_finite() && ends[k] > if k == 0 { 0.0 } else { ends[k - 1] }))
            {
                Some(format!(
                    "has segment {} ending at {} m, not after its start",
                    k + 1,
                    crate::Readable(ends[k])
                ))
            } else if ends[ends.len() - 1] != self.length {
                Some(format!(
                    "ends at {} m, but the rod's length is {} m",
                    crate::Readable(ends[ends.len() - 1]),
                    crate::Readable(self.length)
                ))
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(crate::error::invalid(
                    "rod.segments",
                    problem,
                    "build the rod with Rod::segmented from segments of positive length",
                ));
            }
        }
        Ok(())
    }

    /// Section stiffness and its derivative at s; at a segment end, the section of the
    /// segment that ends there (the left limit). [`Rod::section_on`] chooses the side.
    pub fn section_at(&self, s: f64) -> SectionPoint {
        self.section_on(s, s)
    }

    /// Section stiffness and its derivative at s on the stretch of backbone that ends at
    /// `segment_end` (m, at or after s): which side of a segment end s is on, for a mesh
    /// node ([`crate::mesh::MeshNode::segment_end`]).
    pub fn section_on(&self, s: f64, segment_end: f64) -> SectionPoint {
        match &self.stiffness {
            Stiffness::Segments { ends, sections } => SectionPoint {
                section: sections[segment_index(ends, segment_end)],
                kse_s: Vector3::zeros(),
                kbt_s: Vector3::zeros(),
            },
            Stiffness::Uniform(section) => SectionPoint {
                section: *section,
                kse_s: Vector3::zeros(),
                kbt_s: Vector3::zeros(),
            },
            Stiffness::Varying(f) => f(s),
        }
    }

    /// Reference strains and their derivatives at s; at a segment end, those of the segment
    /// that ends there (the left limit). [`Rod::reference_on`] chooses the side.
    pub fn reference_at(&self, s: f64) -> StrainPoint {
        self.reference_on(s, s)
    }

    /// Reference strains and their derivatives at s on the stretch of backbone that ends at
    /// `segment_end` (m, at or after s), as [`Rod::section_on`].
    pub fn reference_on(&self, s: f64, segment_end: f64) -> StrainPoint {
        match &self.reference {
            ReferenceStrains::Segments { ends, u_star } => StrainPoint {
                v_star: Vector3::z(),
                u_star: u_star[segment_index(ends, segment_end)],
                v_star_s: Vector3::zeros(),
                u_star_s: Vector3::zeros(),
            },
            ReferenceStrains::Straight => StrainPoint {
                v_star: Vector3::z(),
                u_star: Vector3::zeros(),
                v_star_s: Vector3::zeros(),
                u_star_s: Vector3::zeros(),
            },
            ReferenceStrains::Constant { v_star, u_star } => StrainPoint {
                v_star: *v_star,
                u_star: *u_star,
                v_star_s: Vector3::zeros(),
                u_star_s: Vector3::zeros(),
            },
            ReferenceStrains::Varying(f) => f(s),
        }
    }
}

impl fmt::Debug for Stiffness {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stiffness::Uniform(s) => f.debug_tuple("Uniform").field(s).finish(),
            Stiffness::Varying(_) => f.write_str("Varying(<fn>)"),
            Stiffness::Segments { ends, sections } => f
                .debug_struct("Segments")
                .field("ends", ends)
                .field("sections", sections)
                .finish(),
        }
    }
}

impl fmt::Debug for ReferenceStrains {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReferenceStrains::Straight => f.write_str("Straight"),
            ReferenceStrains::Constant { v_star, u_star } => f
                .debug_struct("Constant")
                .field("v_star", v_star)
                .field("u_star", u_star)
                .finish(),
            ReferenceStrains::Varying(_) => f.write_str("Varying(<fn>)"),
            ReferenceStrains::Segments { ends, u_star } => f
                .debug_struct("Segments")
                .field("ends", ends)
                .field("u_star", u_star)
                .finish(),
        }
    }
}
