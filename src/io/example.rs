//! The commented robot file printed by `tdcr example`: the paper's prototype
//! ([`crate::cases::prototype`]) with tendon 1 at 2.94 N, i.e. reference case S.

/// The prototype as a commented robot file, with tendon 1 pulled at 2.94 N
/// ([`crate::cases::case_s`]); reading it gives that robot exactly.
pub fn example() -> String {
    EXAMPLE.to_string()
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
}
