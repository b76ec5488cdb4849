"""Friction on Python's front end (issue 24, docs/friction.md's last section): the
standard errors and noise estimate `tdcr calibrate` prints, on `Calibration`; the friction
coefficient as a named column of `Solver.tip_jacobian` (`friction.I`)."""

import pickle

import numpy as np
import pytest
import tdcr

ROD = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}


def rough(mu, tension=2.94, motion="pull"):
    tendon = {"routing": {"kind": "straight", "x": 0.008, "y": 0.0}, "tension": tension, "friction": mu, "motion": motion}
    other = {"routing": {"kind": "straight", "x": -0.008, "y": 0.0}, "tension": 1.0}
    return tdcr.Robot(rod=ROD, tendons=[tendon, other])


def test_calibration_has_standard_errors_and_the_noise_estimate():
    loads = [1.0, 2.0, 3.0, 4.0]
    motions = ["pull"] * 4 + ["release"] * 4
    tensions = np.array([[t, 1.0] for t in loads + loads])
    forces = np.zeros((8, 3))
    exact = np.array([tdcr.solve(rough(0.1, t, m)).tip_position for t, m in zip(tensions[:, 0], motions)])
    noise = 1e-4
    tips = exact + np.random.default_rng(7).normal(0.0, noise, exact.shape)
    fit = tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["youngs_modulus", "friction"], motions=motions)
    assert fit.converged
    assert fit.names == ["E", "mu"]
    assert list(fit.standard_errors) == fit.names
    se = fit.standard_errors
    assert se["E"] > 0.0 and se["mu"] > 0.0
    # The truth within 4 standard errors (a 6e-5 chance each of failing with a correct
    # error; the seed is fixed, so the test is deterministic).
    assert abs(fit.friction - 0.1) < 4.0 * se["mu"], (fit.friction, se)
    assert abs(fit.youngs_modulus - 210e9) < 4.0 * se["E"], (fit.youngs_modulus, se)
    # sigma from 24 coordinates less 2 unknowns: within a factor 2 of the noise drawn.
    assert 0.5 * noise < fit.noise_estimate < 2.0 * noise
    # Twice the noise, about twice the errors (the same draw scaled: sigma and the errors
    # scale with it; 10 %: the fit's nonlinearity at 0.2 mm).
    wider = tdcr.calibrate(
        rough(0.05), tensions, forces, exact + 2.0 * (tips - exact), fit=["youngs_modulus", "friction"], motions=motions
    )
    assert abs(wider.standard_errors["mu"] / se["mu"] - 2.0) < 0.2
    # Kept by pickling.
    back = pickle.loads(pickle.dumps(fit))
    assert back.standard_errors == se and back.noise_estimate == fit.noise_estimate and back.friction == fit.friction


def test_standard_errors_are_in_the_attributes_units():
    robot = tdcr.cases.case_s()
    loads = [1.0, 2.0, 3.0]
    tensions = np.array([[t, 0.0, 0.0, 0.0, 0.0] for t in loads] + [[0.0, t, 0.0, 0.0, 0.0] for t in loads])
    forces = np.zeros((6, 3))
    tips = np.array([tdcr.solve(robot.with_tensions(t)).tip_position for t in tensions])
    tips += np.random.default_rng(3).normal(0.0, 1e-4, tips.shape)
    fit = tdcr.calibrate(robot, tensions, forces, tips, fit=["youngs_modulus", "base_position"])
    assert list(fit.standard_errors) == ["E", "x0", "y0", "z0"]
    # Base position errors in m: a tenth of a millimetre of noise on 6 tips gives errors of
    # that order, not of mm or of um.
    assert all(1e-6 < fit.standard_errors[k] < 1e-3 for k in ["x0", "y0", "z0"]), fit.standard_errors
    assert fit.friction == 0.0
    # The angles' errors in degrees, as `euler_deg`: 0.1 mm at a 0.24 m lever is about
    # 4e-4 rad, 0.02 deg (case S's base is at beta = 90 deg, where alpha and gamma are not
    # told apart: their errors are tens of degrees; beta's is not).
    angles = tdcr.calibrate(robot, tensions, forces, tips, fit=["euler"])
    assert 2e-3 < angles.standard_errors["beta"] < 0.2, angles.standard_errors
    assert angles.standard_errors["alpha"] > 1.0, angles.standard_errors


def test_solver_tip_jacobian_takes_friction_by_name():
    solver = tdcr.Solver(rough(0.1))
    solver.solve()
    column = solver.tip_jacobian("friction.1")
    full = solver.tip_sensitivities().friction
    assert column.shape == (6, 1)
    # 1e-12 of the column: the same stencil and factors; only the order of sums may differ.
    assert np.max(np.abs(column[:, 0] - full[:, 0])) <= 1e-12 * np.linalg.norm(full[:, 0])
    with pytest.raises(tdcr.InvalidInput, match="friction"):
        solver.tip_jacobian("friction.2")
