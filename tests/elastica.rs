//! A classical nonlinear rod benchmark at default settings: the cantilever under a dead tip
//! load perpendicular to its straight axis, the elastica whose tip Bisshopp & Drucker ("Large
//! deflection of cantilever beams", Quarterly of Applied Mathematics 3(3), 1945) give in
//! closed form by elliptic integrals (`cases::analytic::elastica_tip`). tests/analytic.rs
//! compares the two solvers with it on tight settings; this test solves as a user would.

use nalgebra::Vector3;
use tdcr::cases::analytic::elastica_tip;
use tdcr::{Loads, Robot, Rod, Section, collocation};

#[test]
fn cantilever_under_a_dead_tip_load_is_the_elastica_at_default_settings() {
    let (length, ei) = (1.0, 1.0);
    // Stiff in shear and extension (EA = GA = 1e8 EI / L^2 against P <= 10 EI / L^2): the
    // Cosserat rod is the inextensible, unshearable elastica to P / EA <= 1e-7. (With 1e9 the
    // default solve fails: docs/validation.md.)
    let rod = Rod::new(length, Section::explicit(1e8, 1e8, ei, ei, 1.0));
    for alpha in [1.0, 2.0, 5.0, 10.0] {
        let force = alpha * ei / (length * length);
        let robot = Robot::new(rod.clone()).with_loads(Loads::none().with_tip_force(Vector3::new(force, 0.0, 0.0)));
        let solution = collocation::solve(&robot, &Default::default()).unwrap();
        let tip = solution.tip_position();
        let tangent = solution.tip().R * Vector3::z();
        // (deflection along the load, position along the axis) / L; sin theta_L = alpha z^2 / 2.
        let (x, z) = elastica_tip(alpha);
        let theta = (alpha * z * z / 2.0).asin();
        let angle = tangent.x.atan2(tangent.z);
        eprintln!(
            "alpha {alpha}: x/L {x:.6}, z/L {z:.6}, tip angle {theta:.6} rad; tdcr off by {:.1e} L, {:.1e} L, {:.1e} rad",
            tip.x / length - x,
            tip.z / length - z,
            angle - theta
        );
        // 3e-7 L: the default tip tolerance of 1e-7 L plus shear and extension, P / EA <= 1e-7
        // (measured at most 1.0e-7 L)
        assert!(
            (tip.x - x * length).abs() < 3e-7 * length,
            "alpha {alpha}: {tip} vs ({x}, {z})"
        );
        assert!(
            (tip.z - z * length).abs() < 3e-7 * length,
            "alpha {alpha}: {tip} vs ({x}, {z})"
        );
        // 1e-12 L: the load is in the xz plane
        assert!(tip.y.abs() < 1e-12 * length, "{tip}");
        // 3e-7 rad: the default tip orientation tolerance of 1e-7 rad and the same shear
        // (measured at most 3.4e-8 rad)
        assert!((angle - theta).abs() < 3e-7, "alpha {alpha}: {angle} vs {theta}");
    }
}
