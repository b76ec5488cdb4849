//! Observed order of convergence of the collocation scheme (Hermite-Simpson, order 4).

use tdcr::{cases, collocation, shooting};

fn observed_order(robot: &tdcr::Robot) -> f64 {
    // Reference: shooting at integration tolerance 1e-12 (tip error ~1e-10 m, below the
    // smallest collocation error used here, ~2e-8 m).
    let reference = shooting::solve(
        robot,
        &shooting::Options {
            integration_tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap()
    .tip_position();
    let meshes = [8usize, 16, 32, 64];
    let points: Vec<(f64, f64)> = meshes
        .iter()
        .map(|&n| {
            let sol = collocation::solve(robot, &collocation::Options::fixed(n)).unwrap();
            let h = robot.length() / n as f64;
            (h.ln(), (sol.tip_position() - reference).norm().ln())
        })
        .collect();
    // Least-squares slope of log(error) against log(h).
    let m = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / m, sy / m);
    let num: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

#[test]
fn helical_case_converges_at_fourth_order() {
    let order = observed_order(&cases::case_h());
    eprintln!("observed order, case H: {order:.3}");
    // 0.3: the bound around the scheme's order 4
    assert!((order - 4.0).abs() < 0.3, "observed order {order:.3}");
}

#[test]
fn straight_case_converges_at_fourth_order() {
    let order = observed_order(&cases::case_s());
    eprintln!("observed order, case S: {order:.3}");
    // 0.3: the bound around the scheme's order 4
    assert!((order - 4.0).abs() < 0.3, "observed order {order:.3}");
}

#[test]
fn adaptive_refinement_meets_the_tip_tolerance() {
    let robot = cases::case_h();
    // 1e-8 L = 2.4e-9 m: below the default, above the reference tip's own 5e-10 m error.
    let tol = 1e-8;
    let sol = collocation::solve(
        &robot,
        &collocation::Options {
            intervals: 8,
            tolerance: Some(tol),
            ..Default::default()
        },
    )
    .unwrap();
    let exact = nalgebra::Vector3::from(cases::TIP_H);
    let err = (sol.tip_position() - exact).norm();
    let estimate = sol.report.error_estimate.unwrap();
    eprintln!(
        "adaptive: {} intervals, estimate {:.2e}, true error {err:.2e}",
        sol.report.intervals, estimate.tip_position
    );
    assert_eq!(sol.report.tolerance_met, Some(true));
    assert!(estimate.tip_position <= tol * robot.length() && estimate.tip_rotation <= tol);
    // 1.5x: the estimate is asymptotically exact (ratio within 1 % on this mesh) and the
    // reference itself is good to 5e-10 m
    assert!(err < 1.5 * tol * robot.length(), "true error {err:.3e} m");
}

#[test]
fn refinement_cap_is_reported() {
    let robot = cases::case_h();
    let err = collocation::solve(
        &robot,
        &collocation::Options {
            intervals: 8,
            tolerance: Some(1e-14),
            max_intervals: 64,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, tdcr::Error::IntervalCap { cap: 64, .. }), "{err}");
    assert!(err.to_string().contains("max_intervals"));
}
