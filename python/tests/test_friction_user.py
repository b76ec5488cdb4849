"""Friction as a Python user meets it (issue 24): the tension along a tendon anywhere
(`Solution.tension_at`, the library's `Solution::tension_at`), calibration of mu from
loading and unloading steps (`calibrate(motions=...)`, the CSV's `motion` column of
`tdcr calibrate`), and an empty history as bad input."""

import numpy as np
import pytest
import tdcr

ROD = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}
ROUTING = {"kind": "straight", "x": 0.008, "y": 0.0}


def rough(mu, tension=2.94, motion="pull", stiffness=None):
    tendon = {"routing": ROUTING, "tension": tension, "friction": mu, "motion": motion}
    if stiffness is not None:
        tendon["stiffness"] = stiffness
    return tdcr.Robot(rod=ROD, tendons=[tendon, {"routing": {"kind": "straight", "x": -0.008, "y": 0.0}, "tension": 1.0}])


def test_tension_at_follows_the_capstan_law_between_the_path_points():
    solution = tdcr.solve(rough(0.1))
    tensions = solution.tendon_tensions[0]
    s = solution.s[np.concatenate(([True], np.diff(solution.s) > 0))][: len(tensions)]
    # At the path's points: the stored tensions, bit for bit.
    assert [solution.tension_at(0, x) for x in s] == list(tensions)
    assert solution.tension_at(0, 0.0) == solution.tendons[0]["tension"] == 2.94
    assert solution.tension_at(0, 0.242) == solution.tendons[0]["delivered_tension"]
    # Between two points: log-linear, so the geometric mean at the middle (1e-15 relative:
    # rounding of exp and log).
    middle = solution.tension_at(0, 0.5 * (s[3] + s[4]))
    assert abs(middle / np.sqrt(tensions[3] * tensions[4]) - 1.0) < 1e-15
    assert tensions[4] < middle < tensions[3]
    # A tendon without friction: its tension everywhere.
    assert solution.tension_at(1, 0.1) == 1.0
    with pytest.raises(tdcr.InvalidInput, match="i = 2, but the solution has 2 tendon"):
        solution.tension_at(2, 0.1)
    with pytest.raises(tdcr.InvalidInput, match="not finite"):
        solution.tension_at(0, float("nan"))


def test_calibrate_fits_mu_from_loading_and_unloading_steps():
    loads = [1.0, 2.0, 3.0, 4.0]
    motions = ["pull"] * 4 + ["release"] * 4
    tensions = np.array([[t, 1.0] for t in loads + loads])
    forces = np.zeros((8, 3))
    tips = np.array([tdcr.solve(rough(0.1, t, m)).tip_position for t, m in zip(tensions[:, 0], motions)])

    def fitted(motions):
        fit = tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["friction"], motions=motions)
        (line,) = [x for x in fit.robot.to_toml().splitlines() if x.startswith("friction")]
        return fit, float(line.split("=")[1])

    fit, mu = fitted(motions)
    assert fit.converged
    # Noise-free data on the solver's own meshes: mu back to 1e-9, as test_friction.py.
    assert abs(mu - 0.1) < 1e-9
    # Every step taken as a loading one fits the unloading tips with another mu, worse.
    wrong, mu_wrong = fitted(None)
    # 1e-5 m: the unloading tips lie millimetres from the loading ones at mu = 0.1, so a
    # single-motion fit misses them by far more than 10 um; 1e-9 m: noise-free data.
    assert abs(mu_wrong - 0.1) > 1e-3 and wrong.rms_error > 1e-5 and fit.rms_error < 1e-9
    with pytest.raises(tdcr.InvalidInput, match="7 motions for 8 measurements"):
        tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["friction"], motions=motions[1:])
    with pytest.raises(tdcr.InvalidInput, match='motions\\[0\\] is "up"'):
        tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["friction"], motions=["up"] + motions[1:])


def test_calibrate_says_when_the_fit_does_not_explain_the_data():
    loads = [1.0, 2.0, 3.0, 4.0]
    motions = ["pull"] * 4 + ["release"] * 4
    tensions = np.array([[t, 1.0] for t in loads + loads])
    forces = np.zeros((8, 3))
    tips = np.array([tdcr.solve(rough(0.1, t, m)).tip_position for t, m in zip(tensions[:, 0], motions)])
    # The CLI's name `mu` is the Python name `friction`; noise-free data fit to 1e-9 m.
    good = tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["mu"], motions=motions, noise=1e-4)
    assert good.names == ["mu"] and good.poor_fit is None and abs(good.friction - 0.1) < 1e-9
    # Every step taken as a loading one misses the unloading tips by millimetres, far above
    # a stated 10 um: warned, with friction's own likely cause among the causes.
    with pytest.warns(tdcr.PoorFitWarning, match="does not explain the data"):
        bad = tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["friction"], noise=1e-5)
    assert "sticks" in bad.poor_fit and "does not explain the data" in bad.poor_fit
    with pytest.raises(tdcr.InvalidInput, match="`noise` is -1"):
        tdcr.calibrate(rough(0.05), tensions, forces, tips, fit=["mu"], noise=-1.0)


def test_a_robot_reads_its_friction_back():
    robot = rough(0.1, motion="release")
    assert robot.frictions == [0.1, None]
    assert robot.motions == ["release", None]
    assert robot.with_parameters({"friction.2": 0.3}).frictions == [0.1, 0.3]


def test_an_empty_history_is_bad_input():
    robot = rough(0.1, 0.0, stiffness=2000.0)
    with pytest.raises(tdcr.InvalidInput, match="gives no rows"):
        tdcr.history(robot, {"tension.1": []})
    with pytest.raises(tdcr.InvalidInput, match="gives no rows"):
        tdcr.history(robot, {"tension.1": np.array([])}, up_down=True)


def test_figure_legend_gives_the_delivered_tension(tmp_path):
    # The picture's legend, like `tdcr solve --plot`'s, gives the tension a tendon with
    # friction delivers at its termination (it knows the solution, not the robot only).
    robot = rough(0.1)
    tdcr.figure(robot, tdcr.solve(robot), tmp_path / "shape.svg")
    svg = (tmp_path / "shape.svg").read_text()
    assert "friction 0.1, pulled in" in svg and "N delivered" in svg
