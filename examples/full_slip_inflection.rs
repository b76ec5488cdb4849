//! Full-slip friction solves whose bending reverses inside the rod (docs/friction.md
//! section 8, "honest19"): the prototype with tendons with friction whose bending changes
//! sign along the rod (opposite tendons, a tip load against a tendon, random loads), each
//! solved at the default tolerance and at tight ones. Prints, per solve: whether the
//! reference bends both ways, the default solve's intervals, tip estimate, `tolerance_met`,
//! true tip error and error / estimate (tip position and rotation), the reference's
//! intervals, and its distance from a solve on a fixed uniform mesh, which has no node
//! placed at a kink and no error control (how far the reference itself is converged).
//!
//! `full_slip_inflection [RANDOM] [REFERENCE] [CHECK]`: RANDOM random solves (seeded; 40
//! unless given) after the named ones; REFERENCE the reference's tolerance in L (1e-11);
//! CHECK the uniform mesh's intervals (8192; `none` skips it).

use nalgebra::Vector3;
use tdcr::{Friction, Robot, Solution, cases, collocation};

/// SplitMix64: a small seeded generator, so the random solves are the same on every run.
struct Random(u64);

impl Random {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The prototype with the given tensions on tendons 1 to 4 and friction `mu` on each
/// tendon listed in `rough` (pull), with the tip loads given.
fn robot(tensions: [f64; 4], rough: &[(usize, f64)], force: Vector3<f64>, moment: Vector3<f64>) -> Robot {
    let mut robot = cases::prototype().with_tensions(&[tensions[0], tensions[1], tensions[2], tensions[3], 0.0]);
    for &(i, mu) in rough {
        robot.tendons[i].friction = Some(Friction::pull(mu));
    }
    robot.loads.tip_force = force;
    robot.loads.tip_moment = moment;
    robot
}

/// The links of `solution` over which the bending (u_x, u_y) reverses.
fn reversals(solution: &Solution) -> usize {
    solution
        .nodes
        .windows(2)
        .filter(|w| w[1].s > w[0].s && w[0].u.x * w[1].u.x + w[0].u.y * w[1].u.y <= 0.0)
        .count()
}

fn solve(robot: &Robot, tolerance: f64) -> Result<Solution, tdcr::Error> {
    let options = collocation::Options {
        tolerance: Some(tolerance),
        ..Default::default()
    };
    collocation::solve(robot, &options)
}

/// The angle (rad) between two orientations, from the skew part of their relative rotation
/// (exact to rounding for small angles, where the trace's arccos is not).
fn angle(a: &Solution, b: &Solution) -> f64 {
    let r = a.tip().R.transpose() * b.tip().R;
    let w = Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]);
    (0.5 * w.norm()).asin()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let random: usize = args.first().map_or(40, |a| a.parse().expect("RANDOM is a count"));
    let reference: f64 = args.get(1).map_or(1e-11, |a| a.parse().expect("REFERENCE is a number"));
    let check: Option<usize> = match args.get(2).map(String::as_str) {
        Some("none") => None,
        Some(a) => Some(a.parse().expect("CHECK is a count")),
        None => Some(8192),
    };
    let zero = Vector3::zeros();
    let both = [(0, 0.1), (2, 0.1)];
    let mut named: Vec<(String, Robot)> = Vec::new();
    for t in [1.47, 1.96, 2.46, 3.44, 4.91] {
        named.push((
            format!("T3 {t} N, T1 1 N"),
            robot([1.0, 0.0, t, 0.0], &both, zero, zero),
        ));
    }
    for t in [0.49, 0.98, 1.47] {
        named.push((
            format!("T1 {t} N, T3 1 N"),
            robot([t, 0.0, 1.0, 0.0], &both, zero, zero),
        ));
    }
    for m in [0.01, 0.02] {
        named.push((
            format!("T1 2 N, tip moment {m} N m"),
            robot([2.0, 0.0, 0.0, 0.0], &[(0, 0.1)], zero, Vector3::new(0.0, -m, 0.0)),
        ));
    }
    named.push((
        "T1 3 N, tip force 0.2 N up".into(),
        robot([3.0, 0.0, 0.0, 0.0], &[(0, 0.1)], Vector3::new(0.0, 0.0, 0.2), zero),
    ));
    // Random solves, half of them planar: tendons 1 and 3 (which bend the rod in the
    // vertical plane its weight bends it in) with friction, random tensions and
    // coefficients, a random tip moment about the horizontal normal to the rod; and half in
    // 3-D: an opposite pair (1 and 3, or 2 and 4) with a random tip moment across the rod.
    let mut rng = Random(19);
    for k in 0..random {
        let planar = k % 2 == 0;
        let pair = if planar || rng.uniform(0.0, 1.0) < 0.5 { 0 } else { 1 };
        let mut tensions = [0.0; 4];
        tensions[pair] = rng.uniform(0.2, 3.0);
        tensions[pair + 2] = rng.uniform(0.2, 3.0);
        let rough = [(pair, rng.uniform(0.05, 0.3)), (pair + 2, rng.uniform(0.05, 0.3))];
        let across = if planar { 0.0 } else { rng.uniform(-0.005, 0.005) };
        let moment = Vector3::new(across, rng.uniform(-0.005, 0.005), 0.0);
        let kind = if planar { "planar" } else { "3-D" };
        named.push((format!("random {k} ({kind})"), robot(tensions, &rough, zero, moment)));
    }
    let length = cases::prototype().length();
    println!(
        "tolerance {:.2e} m; reference at {reference:.0e} L, checked on {check:?} uniform intervals",
        1e-7 * length
    );
    println!("case | rev | int | est m | met | err m | err/est | rot err/est | ref int | ref check m");
    let (mut worst, mut worst_rot, mut missed, mut most) = (0.0_f64, 0.0_f64, 0, 0);
    for (name, robot) in &named {
        let default = match tdcr::solve(robot, &Default::default()) {
            Ok(s) => s,
            Err(e) => {
                println!("{name} | default fails: {e}");
                continue;
            }
        };
        let exact = match solve(robot, reference) {
            Ok(s) => s,
            Err(e) => {
                println!("{name} | reference fails: {e}");
                continue;
            }
        };
        let checked = check.map(|intervals| {
            let options = collocation::Options {
                tolerance: None,
                intervals,
                max_intervals: intervals.max(collocation::Options::default().max_intervals),
                ..Default::default()
            };
            collocation::solve(robot, &options).map(|s| (s.tip_position() - exact.tip_position()).norm())
        });
        let report = &default.report;
        let estimate = report.error_estimate.expect("an estimate");
        let error = (default.tip_position() - exact.tip_position()).norm();
        let rotation = angle(&default, &exact);
        let ratio = error / estimate.tip_position;
        let ratio_rot = rotation / estimate.tip_rotation;
        if reversals(&exact) > 0 {
            worst = worst.max(ratio);
            worst_rot = worst_rot.max(ratio_rot);
            most = most.max(report.intervals);
        }
        if report.tolerance_met != Some(true) {
            missed += 1;
        }
        println!(
            "{name} | {} | {} | {:.2e} | {:?} | {error:.2e} | {ratio:.3} | {ratio_rot:.3} | {} | {}",
            reversals(&exact),
            report.intervals,
            estimate.tip_position,
            report.tolerance_met,
            exact.report.intervals,
            match checked {
                Some(Ok(d)) => format!("{d:.1e}"),
                Some(Err(e)) => format!("fails: {e}"),
                None => "-".into(),
            }
        );
    }
    println!(
        "with a reversal: worst error / estimate {worst:.3} (rotation {worst_rot:.3}), most intervals {most}; \
         {missed} default solves miss their tolerance"
    );
}
