//! Rods of segments whose section and precurvature jump where one segment meets the next
//! (`Rod::segmented`): an analytic two-arc answer, both solvers, global equilibrium and
//! the observed order 4 across a section jump.

use tdcr::analysis::equilibrium;
use tdcr::model::rod::shear_modulus;
use tdcr::nalgebra::{Matrix3, Vector3};
use tdcr::{Loads, Robot, Rod, Routing, Section, Segment, Tendon, collocation, shooting, so3};

/// A tube segment of `length` (m), radii (m) and E (Pa) at nu = 0.3, with precurvature u*.
fn tube(length: f64, outer: f64, inner: f64, e: f64, u_star: Vector3<f64>) -> Segment {
    // black_box: computed at run time as a robot file's numbers are (the compiler may fold
    // powi of literals to a different last bit).
    let [outer, inner, e] = std::hint::black_box([outer, inner, e]);
    Segment {
        length,
        section: Section::tube(outer, inner, e, shear_modulus(e, 0.3)),
        precurvature: u_star,
    }
}

/// A stiff proximal tube and a soft, precurved distal rod: the bending stiffness drops by
/// a factor of 13.6 at s = 0.15 m and the precurvature jumps there.
fn two_sections() -> Rod {
    Rod::segmented(&[
        tube(0.15, 0.0008, 0.0005, 60e9, Vector3::zeros()),
        tube(0.1, 0.0004, 0.0, 60e9, Vector3::new(0.0, 3.0, 0.0)),
    ])
}

/// A two-section robot with a tendon ending at the section jump, one to the tip, and a
/// tip force out of the bending plane.
fn robot() -> Robot {
    let mut loads = Loads::none();
    loads.tip_force = Vector3::new(0.0, 0.05, -0.02);
    Robot::new(two_sections())
        .with_tendon(Tendon::new(Routing::polar(0.004, 0.0), 2.0).ending_at(0.15))
        .with_tendon(Tendon::new(Routing::polar(0.004, 90.0), 0.4))
        .with_loads(loads)
}

#[test]
fn segments_are_breakpoints_and_sections_jump_there() {
    let rod = two_sections();
    assert_eq!(rod.length, 0.25);
    assert_eq!(rod.segment_ends(), vec![0.15]);
    let robot = Robot::new(rod.clone());
    assert_eq!(robot.breakpoints(), vec![0.15]);
    let (left, right) = (rod.section_on(0.15, 0.15), rod.section_on(0.15, 0.25));
    assert_eq!(left.section, rod.section_at(0.1).section);
    assert_eq!(right.section, rod.section_at(0.2).section);
    assert!(left.section.kbt[0] > 10.0 * right.section.kbt[0]);
    assert_eq!(rod.reference_on(0.15, 0.15).u_star, Vector3::zeros());
    assert_eq!(rod.reference_on(0.15, 0.25).u_star, Vector3::new(0.0, 3.0, 0.0));
    // A mesh puts a node on each side of the segment end.
    let mesh = tdcr::advanced::mesh::Mesh::uniform(&robot, 10).unwrap();
    let at: Vec<usize> = (0..mesh.nodes.len()).filter(|&k| mesh.nodes[k].s == 0.15).collect();
    assert_eq!(at.len(), 2);
}

/// A pure tip moment about body y bends each segment into an arc of curvature
/// u* + M / (E I) of its own: the tip pose is two arcs composed.
#[test]
fn a_tip_moment_bends_each_segment_into_its_own_arc() {
    let m = 0.002; // N m about world y (= body y along the planar shape)
    let mut loads = Loads::none();
    loads.tip_moment = Vector3::new(0.0, m, 0.0);
    let robot = Robot::new(two_sections()).with_loads(loads);
    let mut p = Vector3::zeros();
    let mut r = Matrix3::identity();
    for (start, end) in [(0.0, 0.15), (0.15, 0.25)] {
        let mid = 0.5 * (start + end);
        let k = robot.rod.reference_at(mid).u_star[1] + m / robot.rod.section_at(mid).section.kbt[1];
        let h = end - start;
        // An arc of curvature k about body y: p' = R e3, R' = R [k e2]^.
        let local = Vector3::new((1.0 - (k * h).cos()) / k, 0.0, (k * h).sin() / k);
        p += r * local;
        r *= so3::exp(&Vector3::new(0.0, k * h, 0.0));
    }
    let tip = |sol: &tdcr::Solution| (sol.tip_position(), sol.tip().R);
    let colloc = collocation::solve(&robot, &Default::default()).unwrap();
    let shoot = shooting::solve(&robot, &Default::default()).unwrap();
    for (name, sol) in [("collocation", &colloc), ("shooting", &shoot)] {
        let (tp, tr) = tip(sol);
        eprintln!("{name}: tip error {:.2e} m, {tp:?} vs {p:?}", (tp - p).norm());
        // 1e-9 L: constant curvature on each segment is integrated to well below the
        // default tolerance 1e-6 L; the rest is Newton's and the integrator's tolerance.
        assert!((tp - p).norm() < 1e-9 * 0.25, "{name}");
        assert!((tr - r).norm() < 1e-8, "{name}");
    }
}

#[test]
fn the_two_solvers_agree_across_a_section_jump() {
    let robot = robot();
    let colloc = collocation::solve(
        &robot,
        &collocation::Options {
            tolerance: Some(1e-9),
            ..Default::default()
        },
    )
    .unwrap();
    let shoot = shooting::solve(
        &robot,
        &shooting::Options {
            integration_tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap();
    let gap = (colloc.tip_position() - shoot.tip_position()).norm();
    eprintln!("tip gap {gap:.2e} m, tip {:?}", colloc.tip_position());
    // 1e-8 L: both solvers are asked for about 1e-9 L at the tip.
    assert!(gap < 1e-8 * robot.length(), "gap {gap:.3e} m");
    // The tip moves far from straight: the jump is exercised, not a small perturbation.
    assert!(colloc.tip_position()[0].abs() > 0.02);
    for sol in [&colloc, &shoot] {
        let e = equilibrium::imbalance(&robot, sol);
        // 1e-8: the global balance holds to the solvers' accuracy.
        assert!(e.max() < 1e-8, "{e:?}");
    }
    // The nodes on the two sides of the segment end carry the moments of their own
    // sections: m = R C (u - u*) with the left section and u* = 0 on the left, the right
    // section and its precurvature on the right.
    let k = colloc.nodes.iter().position(|n| n.s == 0.15).unwrap();
    let (a, b) = (&colloc.nodes[k], &colloc.nodes[k + 1]);
    assert_eq!(a.s, b.s);
    let (ka, kb) = (
        robot.rod.section_on(0.15, 0.15).section.kbt,
        robot.rod.section_on(0.15, 0.25).section.kbt,
    );
    let u_star = Vector3::new(0.0, 3.0, 0.0);
    // 1e-12: the same products, up to rounding.
    let left = a.R * a.u.component_mul(&ka);
    let right = b.R * (b.u - u_star).component_mul(&kb);
    assert!((a.m - left).norm() < 1e-12 * left.norm());
    assert!((b.m - right).norm() < 1e-12 * right.norm());
    // The curvature itself jumps: the soft, precurved side bends much more.
    assert!((b.u - a.u).norm() > 1.0, "{} vs {}", a.u, b.u);
}

#[test]
fn observed_order_is_four_across_a_section_jump() {
    let robot = robot();
    // Reference: shooting at integration tolerance 1e-13 (tip error about 1e-11 m, below
    // the smallest collocation error used here, about 1e-8 m).
    let reference = shooting::solve(
        &robot,
        &shooting::Options {
            integration_tolerance: 1e-13,
            ..Default::default()
        },
    )
    .unwrap()
    .tip_position();
    let points: Vec<(f64, f64)> = [8usize, 16, 32, 64]
        .iter()
        .map(|&n| {
            let sol = collocation::solve(&robot, &collocation::Options::fixed(n)).unwrap();
            let h = robot.length() / n as f64;
            (h.ln(), (sol.tip_position() - reference).norm().ln())
        })
        .collect();
    let m = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0 / m, a.1 + p.1 / m));
    let num: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let order = num / den;
    eprintln!("observed order across the section jump: {order:.3} ({points:?})");
    // 0.3: the bound around the scheme's order 4 that tests/convergence.rs uses.
    assert!((order - 4.0).abs() < 0.3, "observed order {order:.3}");
}

/// The robot of `robot()` as a robot file: one segment by geometry, one by stiffnesses
/// (those of `two_sections`' second segment), tendons ending by segment number.
fn robot_file(distal: &str) -> String {
    format!(
        r#"
[[segment]]
length = 0.15
outer_radius = 0.0008
inner_radius = 0.0005
youngs_modulus = 60e9
poisson_ratio = 0.3

[[segment]]
length = 0.1
{distal}
precurvature = [0.0, 3.0, 0.0]

[loads]
tip_force = [0.0, 0.05, -0.02]

[[tendon]]
routing = {{ kind = "straight", radius = 0.004, angle_deg = 0 }}
tension = 2.0
end_segment = 1
[[tendon]]
routing = {{ kind = "straight", radius = 0.004, angle_deg = 90 }}
tension = 0.4
end_segment = 2
"#
    )
}

#[test]
fn a_robot_file_of_segments_is_the_library_robot() {
    let geometry = "outer_radius = 0.0004\nyoungs_modulus = 60e9\npoisson_ratio = 0.3";
    let file = tdcr::io::parse(&robot_file(geometry), "segments.toml").unwrap();
    let (library, parsed) = (robot(), &file.robot);
    assert_eq!(parsed.rod.segment_ends(), library.rod.segment_ends());
    assert_eq!(parsed.tendons[0].termination, Some(0.15));
    assert_eq!(parsed.tendons[1].end(0.25), 0.25);
    let tip = |r: &Robot| collocation::solve(r, &Default::default()).unwrap().tip_position();
    // The same numbers in the same order: the same answer, bitwise.
    assert_eq!(tip(parsed), tip(&library));
    // The second segment by its four stiffnesses, those its geometry gives.
    let k = library.rod.section_at(0.2).section;
    let stiffnesses = format!(
        "bending_stiffness = {:e}\ntorsion_stiffness = {:e}\naxial_stiffness = {:e}\nshear_stiffness = {:e}",
        k.kbt[0], k.kbt[2], k.kse[2], k.kse[0]
    );
    let by_stiffness = tdcr::io::parse(&robot_file(&stiffnesses), "segments.toml").unwrap();
    assert_eq!(tip(&by_stiffness.robot), tip(&library));
}

#[test]
fn segment_tables_report_what_is_wrong() {
    let errors = |text: &str| tdcr::io::parse(text, "bad.toml").unwrap_err().to_string();
    let mixed = errors(&robot_file(
        "outer_radius = 0.0004\nyoungs_modulus = 60e9\npoisson_ratio = 0.3\nbending_stiffness = 1e-3",
    ));
    assert!(
        mixed.contains("segment[2].bending_stiffness") && mixed.contains("not a mix"),
        "{mixed}"
    );
    let partial = errors(&robot_file("bending_stiffness = 1e-3\naxial_stiffness = 3e4"));
    assert!(
        partial.contains("segment[2].torsion_stiffness") && partial.contains("all four"),
        "{partial}"
    );
    assert!(partial.contains("segment[2].shear_stiffness"), "{partial}");
    let none = errors(&robot_file(""));
    assert!(none.contains("has no section"), "{none}");
    let past = errors(
        &robot_file("outer_radius = 0.0004\nyoungs_modulus = 60e9\npoisson_ratio = 0.3")
            .replace("end_segment = 2", "end_segment = 3"),
    );
    assert!(
        past.contains("tendon[2].end_segment") && past.contains("1 to 2"),
        "{past}"
    );
    let both = format!(
        "[rod]\nlength = 0.1\nouter_radius = 0.001\nyoungs_modulus = 1e9\npoisson_ratio = 0.3\n{}",
        robot_file("outer_radius = 0.0004\nyoungs_modulus = 60e9\npoisson_ratio = 0.3")
    );
    assert!(
        errors(&both).contains("has both [rod] and [[segment]]"),
        "{}",
        errors(&both)
    );
    let uniform = "[rod]\nlength = 0.1\nouter_radius = 0.001\nyoungs_modulus = 1e9\npoisson_ratio = 0.3\n\
                   [[tendon]]\nrouting = { kind = \"straight\", x = 0.002, y = 0.0 }\ntension = 1.0\nend_segment = 1\n";
    assert!(errors(uniform).contains("has no segments"), "{}", errors(uniform));
}

#[test]
fn a_robot_of_segments_writes_back_to_the_same_robot() {
    let geometry = "outer_radius = 0.0004\nyoungs_modulus = 60e9\npoisson_ratio = 0.3";
    let file = tdcr::io::parse(&robot_file(geometry), "segments.toml").unwrap();
    let text = file.to_toml().unwrap();
    assert!(text.contains("[[segment]]"), "{text}");
    let back = tdcr::io::parse(&text, "again.toml").unwrap();
    assert_eq!(format!("{:?}", back.robot), format!("{:?}", file.robot));
}

#[test]
fn inconsistent_segments_are_input_errors_not_panics() {
    let mut rod = two_sections();
    if let tdcr::model::rod::Stiffness::Segments { sections, .. } = &mut rod.stiffness {
        sections.pop();
    }
    let e = Robot::new(rod).validate().unwrap_err().to_string();
    assert!(
        e.contains("rod.segments") && e.contains("2 segment end(s) but 1"),
        "{e}"
    );
    let negative = Rod::segmented(&[
        tube(0.15, 0.0008, 0.0, 60e9, Vector3::zeros()),
        tube(-0.05, 0.0008, 0.0, 60e9, Vector3::zeros()),
    ]);
    let e = Robot::new(negative).validate().unwrap_err().to_string();
    assert!(
        e.contains("segment 2 ending at") && e.contains("not after its start"),
        "{e}"
    );
}
