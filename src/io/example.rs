//! The sample files printed by `tdcr example`: the commented robot file (the paper's
//! prototype, [`crate::cases::prototype`], with tendon 1 at 2.94 N, i.e. reference case S), a
//! parameter table for `tdcr batch` with it, and for `tdcr calibrate` the prototype in the
//! paper's frame with synthetic measurements of Table 2's experiments.

use crate::Routing;
use crate::cases::{self, GaussianNoise, paper_frame_rotation, prototype_in_paper_frame, table2_measurement};
use crate::fit::calibration::{CalibrationOptions, Measurement, Parameters, predict};
use crate::io::csv_table::CsvTable;
use nalgebra::Vector3;
use std::fmt::Write as _;

/// The prototype as a commented robot file, with tendon 1 pulled at 2.94 N
/// ([`crate::cases::case_s`]); reading it gives that robot exactly.
pub fn example() -> String {
    EXAMPLE.to_string()
}

/// A parameter table for `tdcr batch` with [`example`]'s robot: tendon 1 from 0 to 6 N in
/// steps of 1 N, each without a tip load and with the paper's 10 g and 20 g masses
/// (`tip_force.z` 0, -0.098, -0.196 N): 21 rows, CSV.
pub fn example_cases() -> String {
    let mut table = CsvTable::new(["tension.1", "tip_force.z"]);
    for k in 0..=6 {
        for fz in [0.0, -0.098, -0.196] {
            table.numbers([f64::from(k), fz]);
        }
    }
    table.finish()
}

/// The prototype in the paper's frame ([`cases::prototype_in_paper_frame`]) as a robot file
/// for `tdcr calibrate`: nominal E, the base at the nominal XYZ Euler angles (180, 0, -90)
/// deg (away from the angles' singularity, which the frame of [`example`] sits on), gravity
/// along +y, the five tendons of Table 1 at 0 N (the experiments CSV gives the tensions),
/// a fixed mesh of 32 intervals (smooth tips for the fit, docs/calibration.md).
pub fn paper_frame_example() -> String {
    let g = paper_frame_rotation() * Vector3::new(0.0, 0.0, -cases::WEIGHT_PER_LENGTH);
    let [a, b, c] = cases::PAPER_NOMINAL_EULER_DEG;
    let mut text = format!(
        "# The prototype of Rucker & Webster (2011) in the paper's frame: the base at the nominal\n\
         # XYZ Euler angles of section 5.1, gravity along +y (`tdcr example paper-robot`).\n\n\
         [rod]\nlength = {}\nouter_radius = {}\nyoungs_modulus = {:e}\npoisson_ratio = {}\n\n\
         [base]\nposition = [0.0, 0.0, 0.0]\neuler_xyz_deg = [{a:?}, {b:?}, {c:?}]\n\n\
         [loads]\ndistributed_force = [{:?}, {:?}, {:?}]   # N/m, self weight\n",
        cases::LENGTH,
        cases::RADIUS,
        cases::YOUNGS_MODULUS,
        cases::POISSON_RATIO,
        g.x + 0.0,
        g.y + 0.0,
        g.z + 0.0
    );
    for (i, routing) in cases::prototype_routings().iter().enumerate() {
        let routing = match routing {
            Routing::Straight { x, y } => format!("{{ kind = \"straight\", x = {x:?}, y = {y:?} }}"),
            Routing::Helical { radius, turns, phase } => {
                format!("{{ kind = \"helical\", radius = {radius:?}, turns = {turns:?}, phase = {phase:?} }}")
            }
            Routing::Custom(_) => unreachable!("the prototype's routings are straight or helical"),
        };
        let _ = write!(
            text,
            "\n[[tendon]]   # tendon {}\nrouting = {routing}\ntension = 0.0\n",
            i + 1
        );
    }
    text.push_str("\n[solver]\nintervals = 32\n");
    text
}

/// The robot of [`paper_frame_example`] with the paper's calibrated parameters (E = 230 GPa,
/// XYZ Euler angles (177.8, 2.2, -89.7) deg): the "truth" that synthetic measurements come from.
pub fn calibration_truth() -> Parameters {
    let nominal = Parameters::of(&prototype_in_paper_frame());
    Parameters {
        youngs_modulus: cases::PAPER_CALIBRATED_YOUNGS_MODULUS,
        euler: Vector3::from(cases::PAPER_CALIBRATED_EULER_DEG).map(f64::to_radians),
        ..nominal
    }
}

/// Synthetic measurements of the 32 experiments of Table 2 for [`paper_frame_example`]'s
/// robot: the loads of each experiment, the tip solved with [`calibration_truth`] plus
/// Gaussian noise of `noise` m per coordinate (seed 2011, so the same numbers every time).
///
/// # Errors
/// A solve that does not converge (none does at the paper's loads).
pub fn example_experiments(noise: f64) -> crate::Result<Vec<Measurement>> {
    let robot = prototype_in_paper_frame();
    let mut experiments: Vec<Measurement> = cases::table2()
        .iter()
        .map(|e| table2_measurement(e, &paper_frame_rotation()))
        .collect();
    let tips = predict(
        &robot,
        &calibration_truth(),
        &experiments,
        &CalibrationOptions::default(),
    )?;
    let mut gauss = GaussianNoise::new(2011);
    for (e, tip) in experiments.iter_mut().zip(tips) {
        e.measured_tip = tip + noise * Vector3::new(gauss.next(), gauss.next(), gauss.next());
    }
    Ok(experiments)
}

const EXAMPLE: &str = r#"# tdcr robot file: the prototype of Rucker & Webster (2011), section 5, with tendon 1
# pulled at 2.94 N (reference case S). SI units throughout; vectors are [x, y, z].
# Every field is described in docs/robot-file.md. Check a file with `tdcr check FILE`.

[rod]                            # the elastic backbone: a spring-steel rod
length = 0.242                   # m, backbone length L
outer_radius = 0.0004            # m (diameter 0.8 mm)
# inner_radius = 0.0             # m, for a tube; default 0 (solid)
youngs_modulus = 210e9           # Pa
poisson_ratio = 0.3125           # or shear_modulus (Pa), not both
# precurvature = [0.0, 0.0, 0.0] # rad/m, body frame; default straight

[base]                           # the clamped base; default: origin, identity
position = [0.0, 0.0, 0.0]       # m, world frame
# Rows of R(0) (body to world): here the backbone (body z) points along world +x and
# body x along world -z.
rotation = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
# euler_xyz_deg = [0.0, 90.0, 0.0]   # instead of rotation: R = Rx(a) Ry(b) Rz(c), degrees

[loads]                          # world frame; every field defaults to zero
distributed_force = [0.0, 0.0, -0.47]   # N/m: weight of rod, disks and tendons
# distributed_moment = [0.0, 0.0, 0.0]  # N m/m
tip_force = [0.0, 0.0, 0.0]             # N; a 10 g mass is [0.0, 0.0, -0.098]
tip_moment = [0.0, 0.0, 0.0]            # N m
# [[loads.point]]                       # a point load on the rod (repeatable)
# s = 0.121                             # m, where it acts, in (0, length]
# force = [0.0, 0.0, -0.05]             # N
# moment = [0.0, 0.0, 0.0]              # N m

# Tendons are numbered 1, 2, ... in file order, as in `tdcr solve --tension 2=1.5`.
# Routings are in the body frame: (x, y) is the offset in the cross-section.

[[tendon]]                       # tendon 1
routing = { kind = "straight", x = 0.008, y = 0.0 }   # m
tension = 2.94                   # N, >= 0
# end = 0.242                    # m, where the tendon is attached; default the tip
# friction = 0.1                 # capstan friction coefficient in its channels (docs/friction.md)
# motion = "pull"                # or "release": the way it slides in full slip; default pull
# stiffness = 2000.0             # N, E_t A_t: an elastic tendon (a load history needs it)

[[tendon]]                       # tendon 2
routing = { kind = "straight", x = 0.0, y = 0.008 }
tension = 0.0

[[tendon]]                       # tendon 3
routing = { kind = "straight", x = -0.008, y = 0.0 }
tension = 0.0

[[tendon]]                       # tendon 4
routing = { kind = "straight", x = 0.0, y = -0.008 }
tension = 0.0

[[tendon]]                       # tendon 5: one helical turn per rod length L (< 0: left-handed)
routing = { kind = "helical", radius = 0.008, turns_per_rod_length = 1.0, phase = 0.0 }   # m, -, rad
tension = 0.0

[solver]                         # every field optional
method = "collocation"           # or "shooting" (the independent cross-check)
# tolerance = 1e-7               # tip error relative to the rod length (the default): the
#                                # mesh is chosen until the estimated tip error is below
#                                # 1e-7 L and 1e-7 rad
# intervals = 32                 # the starting mesh; alone (no tolerance), a fixed mesh
# max_intervals = 8192           # cap on intervals during refinement
# residual_tolerance = 1e-11     # Newton stopping test (scaled, dimensionless)
# max_iterations = 30            # Newton iterations per Newton run
# continuation = true            # follow the load path when Newton alone is not enough
# equilibrium = "load_path"      # or "nearest": Newton's root from the guess, stable or not

# [model]                        # the model variant; every field optional
# corner_forces = true           # false: the paper's jump conditions (no corner forces)
# tendons = "coupled"            # or "point_moment": tendons act by their end moments only
# rod = "cosserat"               # or "kirchhoff": inextensible and unshearable (v = v*)
"#;

#[cfg(test)]
mod tests {
    use crate::cases;

    #[test]
    fn example_reads_back_as_case_s() {
        let file = crate::io::parse(&super::example(), "example").unwrap();
        let (a, b) = (&file.robot, &cases::case_s());
        assert_eq!(a.length(), b.length());
        let (p, q) = (a.rod.section_at(0.0).section, b.rod.section_at(0.0).section);
        // 1e-15: the same formulas, but the compiler may fold powi for the constants of
        // `cases` differently from the run-time powi of the parsed values (last bit).
        assert!((p.kse - q.kse).component_div(&q.kse).amax() < 1e-15);
        assert!((p.kbt - q.kbt).component_div(&q.kbt).amax() < 1e-15);
        assert_eq!(a.base_rotation, b.base_rotation);
        assert_eq!(a.base_position, b.base_position);
        assert_eq!(a.loads.distributed_force.at(0.1), b.loads.distributed_force.at(0.1));
        assert_eq!(a.loads.tip_force, b.loads.tip_force);
        assert_eq!(a.tendons.len(), b.tendons.len());
        for (s, t) in a.tendons.iter().zip(&b.tendons) {
            assert_eq!(s.tension(), t.tension());
            assert_eq!(s.termination, t.termination);
            assert_eq!(s.routing.at(0.1, 0.242), t.routing.at(0.1, 0.242));
        }
        assert_eq!(file.solver.collocation, crate::collocation::Options::default());
    }

    #[test]
    fn the_sample_cases_read_as_a_parameter_table_for_the_example() {
        let table = crate::io::parameters::read("cases.csv", &super::example_cases()).unwrap();
        assert_eq!(table.len(), 21);
        let base = crate::io::parse(&super::example(), "example").unwrap().robot;
        let last = table.robot(&table.row(20), &base).unwrap();
        assert_eq!((last.tendons[0].tension(), last.loads.tip_force.z), (6.0, -0.196));
    }

    #[test]
    fn the_paper_frame_example_reads_back_as_the_prototype_in_the_paper_frame() {
        let file = crate::io::parse(&super::paper_frame_example(), "paper.toml").unwrap();
        let b = cases::prototype_in_paper_frame();
        // 1e-12: Euler angles in degrees through sin/cos against the exact frame matrix
        assert!((file.robot.base_rotation - b.base_rotation).amax() < 1e-12);
        assert_eq!(file.robot.tendons.len(), 5);
        let text = crate::io::experiments::to_csv(&super::example_experiments(1e-4).unwrap());
        let read = crate::io::experiments::parse_csv(&text, "experiments.csv", 5).unwrap();
        assert_eq!(read.len(), 32);
    }
}
