"""Friction in the analyses of the Python package: d(tip)/d(mu) against a central difference
of full solves, its pickle round trip, and `calibrate(fit=["friction"])`."""

import pickle

import numpy as np
import tdcr

ROD = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}
ROUTING = {"kind": "straight", "x": 0.008, "y": 0.0}


def rough(mu, tension=2.94):
    return tdcr.Robot(rod=ROD, tendons=[{"routing": ROUTING, "tension": tension, "friction": mu}])


def test_tip_sensitivity_to_mu_matches_a_central_difference():
    solution = tdcr.solve(rough(0.1))
    sens = tdcr.tip_sensitivities(rough(0.1), solution)
    assert sens.friction.shape == (6, 1)
    h = 1e-4  # central difference in mu: truncation O(h^2), far below the 1e-5 asked
    fd = (tdcr.solve(rough(0.1 + h)).tip_position - tdcr.solve(rough(0.1 - h)).tip_position) / (2 * h)
    # 1e-5 relative: both sides solve on their own adaptive meshes (error estimate 1e-9 m
    # per solve, divided by h), not the fixed mesh of the Rust test.
    assert np.linalg.norm(sens.friction[:3, 0] - fd) <= 1e-5 * np.linalg.norm(fd)
    again = pickle.loads(pickle.dumps(sens))
    assert np.array_equal(again.friction, sens.friction)


def test_calibrate_fits_the_friction_coefficient():
    tensions = np.array([[1.0], [2.0], [3.0]])
    forces = np.zeros((3, 3))
    tips = np.array([tdcr.solve(rough(0.1, t)).tip_position for t in tensions[:, 0]])
    fit = tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["friction"])
    assert fit.converged and fit.names == ["mu"]
    # Noise-free data on the solver's own meshes: mu back to 1e-9 (measured 3e-12).
    (line,) = [x for x in fit.robot.to_toml().splitlines() if x.startswith("friction")]
    assert abs(float(line.split("=")[1]) - 0.1) < 1e-9


def held(mu, pull_in):
    """Tendon 1 elastic (E_t A_t = 2000 N, 0.1 m free) with friction, held at `pull_in` (m)."""
    tendon = {"routing": ROUTING, "displacement": pull_in, "friction": mu, "stiffness": 2000.0, "free_length": 0.1}
    return tdcr.Robot(rod=ROD, tendons=[tendon])


def test_tip_sensitivity_to_a_pull_in_held_with_friction_matches_a_central_difference():
    # docs/friction.md section 3b, "Derivatives at a held pull-in": the base tension follows
    # the pull-in through the stretch of the varying tension. 64 fixed intervals on both
    # sides, so the differences see the same discretization.
    solution = tdcr.solve(held(0.1, 0.012), intervals=64, residual_tolerance=1e-12)
    sens = tdcr.tip_sensitivities(held(0.1, 0.012), solution)
    h = 4e-6  # m of pull-in: truncation about (h / q)^2 = 1e-7 relative
    up = tdcr.solve(held(0.1, 0.012 + h), intervals=64, residual_tolerance=1e-12).tip_position
    down = tdcr.solve(held(0.1, 0.012 - h), intervals=64, residual_tolerance=1e-12).tip_position
    fd = (up - down) / (2 * h)
    # 1e-6 relative, as tests/friction_pull_in.rs (measured here: 1.9e-8, and 1.2e-9 for mu)
    assert np.linalg.norm(sens.displacement[:3, 0] - fd) <= 1e-6 * np.linalg.norm(fd)
    h = 2e-4  # of mu, as tests/friction_pull_in.rs
    up = tdcr.solve(held(0.1 + h, 0.012), intervals=64, residual_tolerance=1e-12).tip_position
    down = tdcr.solve(held(0.1 - h, 0.012), intervals=64, residual_tolerance=1e-12).tip_position
    fd = (up - down) / (2 * h)
    assert np.linalg.norm(sens.friction[:3, 0] - fd) <= 1e-6 * np.linalg.norm(fd)


def test_a_solve_with_friction_has_the_verdict_of_its_linearized_dynamics():
    # Pulled and released, the prototype's tendon at 2.94 N with mu = 0.1 is stable
    # (docs/stability.md, "Tendons with friction"), no longer "unknown".
    for motion in ["pull", "release"]:
        robot = tdcr.Robot(
            rod=ROD, tendons=[{"routing": ROUTING, "tension": 2.94, "friction": 0.1, "motion": motion}]
        )
        report = tdcr.solve(robot).report
        assert report.stability == "stable", report.stability_detail
        assert report.stability_detail["reason"] is None
