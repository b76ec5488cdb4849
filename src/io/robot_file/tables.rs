//! The serde tables of a robot file, one per TOML table, as deserialized and before any
//! check: unknown keys are rejected, missing required fields reported by serde.

use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, de::DeserializeOwned};
use std::fmt;
use std::marker::PhantomData;

/// A world- or body-frame vector as written in the file, `[x, y, z]`.
pub(super) type Vec3 = [f64; 3];

/// An array of exactly `N` entries of `T`: a longer or shorter one is an error that gives the
/// length found and the length expected (serde's own arrays read the first `N` entries and
/// ignore the rest). `what` says what the entries are.
struct Exact<T, const N: usize> {
    what: &'static str,
    entries: PhantomData<T>,
}

impl<'de, T: DeserializeOwned + Copy + Default, const N: usize> Visitor<'de> for Exact<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array of {N} {}", self.what)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut out = [T::default(); N];
        let mut found = 0;
        while found < N {
            match seq.next_element::<T>()? {
                Some(x) => out[found] = x,
                None => break,
            }
            found += 1;
        }
        // Count the extra entries whatever their type: the length is the problem.
        while seq.next_element::<IgnoredAny>()?.is_some() {
            found += 1;
        }
        if found == N {
            Ok(out)
        } else {
            Err(de::Error::custom(format_args!(
                "has {found} entries, but must have {N} ({})",
                self.what
            )))
        }
    }
}

/// An optional `[x, y, z]` of exactly three numbers.
fn vector<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec3>, D::Error> {
    d.deserialize_seq(Exact::<f64, 3> {
        what: "numbers x, y, z",
        entries: PhantomData,
    })
    .map(Some)
}

/// An optional 3 x 3 matrix given as exactly three rows of exactly three numbers.
fn rows<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[Vec3; 3]>, D::Error> {
    /// One row of the matrix.
    #[derive(Clone, Copy, Default)]
    struct Row(Vec3);
    impl<'de> Deserialize<'de> for Row {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Row, D::Error> {
            d.deserialize_seq(Exact::<f64, 3> {
                what: "numbers in each row",
                entries: PhantomData,
            })
            .map(Row)
        }
    }
    d.deserialize_seq(Exact::<Row, 3> {
        what: "rows of 3 numbers",
        entries: PhantomData,
    })
    .map(|r| Some(r.map(|row| row.0)))
}

/// `[rod]`: the backbone rod, a tube (`inner_radius` 0, the default, for a solid rod), with
/// `poisson_ratio` or `shear_modulus` for the torsion stiffness.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RodTable {
    pub(super) length: f64,
    pub(super) outer_radius: f64,
    #[serde(default)]
    pub(super) inner_radius: f64,
    pub(super) youngs_modulus: f64,
    pub(super) poisson_ratio: Option<f64>,
    pub(super) shear_modulus: Option<f64>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) precurvature: Option<Vec3>,
}

/// One `[[segment]]`: a stretch of the backbone of `length` (m), from the end of the one
/// before it, with its section given by geometry (`outer_radius`, `inner_radius`,
/// `youngs_modulus`, `poisson_ratio` or `shear_modulus`, as in `[rod]`) or by stiffnesses
/// (`bending_stiffness` E I and `torsion_stiffness` G J in N m^2, `axial_stiffness` E A and
/// `shear_stiffness` G A in N), one form whole (checked in `segments`), and its constant
/// `precurvature` (rad/m, body frame).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SegmentTable {
    pub(super) length: f64,
    pub(super) outer_radius: Option<f64>,
    pub(super) inner_radius: Option<f64>,
    pub(super) youngs_modulus: Option<f64>,
    pub(super) poisson_ratio: Option<f64>,
    pub(super) shear_modulus: Option<f64>,
    pub(super) bending_stiffness: Option<f64>,
    pub(super) torsion_stiffness: Option<f64>,
    pub(super) axial_stiffness: Option<f64>,
    pub(super) shear_stiffness: Option<f64>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) precurvature: Option<Vec3>,
}

/// `[base]`: where the rod starts, with its rotation as `rotation` rows or `euler_xyz_deg`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BaseTable {
    #[serde(default, deserialize_with = "vector")]
    pub(super) position: Option<Vec3>,
    #[serde(default, deserialize_with = "rows")]
    pub(super) rotation: Option<[Vec3; 3]>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) euler_xyz_deg: Option<Vec3>,
}

/// `[loads]`: distributed and tip loads, and the `[[loads.point]]` point loads.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LoadsTable {
    #[serde(default, deserialize_with = "vector")]
    pub(super) distributed_force: Option<Vec3>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) distributed_moment: Option<Vec3>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) tip_force: Option<Vec3>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) tip_moment: Option<Vec3>,
    /// Follower tip force, tip body frame (N).
    #[serde(default, deserialize_with = "vector")]
    pub(super) follower_tip_force: Option<Vec3>,
    /// Follower tip moment, tip body frame (N m).
    #[serde(default, deserialize_with = "vector")]
    pub(super) follower_tip_moment: Option<Vec3>,
    /// Follower force per length, body frame (N/m).
    #[serde(default, deserialize_with = "vector")]
    pub(super) follower_distributed_force: Option<Vec3>,
    #[serde(default)]
    pub(super) point: Vec<PointTable>,
}

/// One `[[loads.point]]`: a force and moment at arc length `s`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PointTable {
    pub(super) s: f64,
    #[serde(default, deserialize_with = "vector")]
    pub(super) force: Option<Vec3>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) moment: Option<Vec3>,
}

/// One `[[tendon]]`: its routing, its `tension` (N) or actuator `displacement` (m, one of
/// the two), optionally where it ends (`end` in m, or `end_segment`, the number of the
/// `[[segment]]` at whose end it ends), for an elastic tendon its `stiffness`
/// E_t A_t (N) and `free_length` (m) between the base and the actuator, and its `friction`
/// coefficient in the channels with the `motion` modelled (`pull` or `release`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TendonTable {
    pub(super) routing: RoutingTable,
    pub(super) tension: Option<f64>,
    pub(super) displacement: Option<f64>,
    pub(super) end: Option<f64>,
    /// The 1-based `[[segment]]` whose end the tendon ends at (instead of `end`).
    pub(super) end_segment: Option<usize>,
    pub(super) stiffness: Option<f64>,
    pub(super) free_length: Option<f64>,
    pub(super) friction: Option<f64>,
    pub(super) motion: Option<MotionName>,
}

/// The `motion` of a tendon with friction, as written in the file.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum MotionName {
    Pull,
    Release,
}

/// A tendon's `routing`, chosen by its `kind`: `straight` or `helical`.
#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub(super) enum RoutingTable {
    /// At (`x`, `y`) or, in polar form, at `radius` and `angle_deg`: one of the two pairs,
    /// whole (checked in `check`).
    Straight {
        x: Option<f64>,
        y: Option<f64>,
        radius: Option<f64>,
        angle_deg: Option<f64>,
    },
    /// `turns_per_rod_length`, or its old name `turns` (the same meaning), one of them
    /// required; the starting angle as `phase` (rad) or `angle_deg`, at most one (checked
    /// in `check`).
    Helical {
        radius: f64,
        turns_per_rod_length: Option<f64>,
        turns: Option<f64>,
        phase: Option<f64>,
        angle_deg: Option<f64>,
    },
}

/// `[solver]`: the solver and its options, each optional (the library default if not given).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SolverTable {
    pub(super) method: Option<MethodName>,
    pub(super) intervals: Option<usize>,
    /// The old name of `intervals`, still accepted.
    pub(super) nodes: Option<usize>,
    pub(super) tolerance: Option<f64>,
    pub(super) max_intervals: Option<usize>,
    /// The old name of `max_intervals`, still accepted.
    pub(super) max_nodes: Option<usize>,
    pub(super) residual_tolerance: Option<f64>,
    pub(super) max_iterations: Option<usize>,
    pub(super) continuation: Option<bool>,
    pub(super) equilibrium: Option<EquilibriumKey>,
    pub(super) integration_tolerance: Option<f64>,
}

/// The `method` of `[solver]`: the solver's name as written in the file.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum MethodName {
    Collocation,
    Shooting,
}

/// The `equilibrium` of `[solver]`: `"load_path"` (the default) or `"nearest"`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub(super) enum EquilibriumKey {
    LoadPath,
    Nearest,
}

/// `[disks]`: spacer disks, `count` evenly spaced or at `positions` (one of the two), each
/// of `mass` (kg, with `gravity` in m/s^2, world) or `weight` (N, world) (one of the two),
/// with an optional `radius` (m) for pictures.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DisksTable {
    pub(super) count: Option<usize>,
    pub(super) positions: Option<Vec<f64>>,
    pub(super) mass: Option<f64>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) gravity: Option<Vec3>,
    #[serde(default, deserialize_with = "vector")]
    pub(super) weight: Option<Vec3>,
    pub(super) radius: Option<f64>,
}

/// `[model]`: which variant of the model to solve, each key optional (the library default,
/// the coupled model with corner forces, if not given).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ModelTable {
    pub(super) corner_forces: Option<bool>,
    pub(super) tendons: Option<TendonModelKey>,
    pub(super) rod: Option<RodModelKey>,
}

/// The `rod` of `[model]`: `"cosserat"` (the default) or `"kirchhoff"`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub(super) enum RodModelKey {
    Cosserat,
    Kirchhoff,
}

/// The `tendons` of `[model]`: `"coupled"` (the default) or `"point_moment"`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub(super) enum TendonModelKey {
    Coupled,
    PointMoment,
}

/// The tables a robot file may have, in the order docs/robot-file.md describes them.
pub(super) const TABLES: &str = "[rod] (or [[segment]]), [base], [loads], [disks], [[tendon]], [model], [solver]";
