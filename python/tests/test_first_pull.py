"""The control Jacobian of unloaded tendons with friction (user22, issue 24): a robot with
three tendons with friction, one pulled, the others at 0 N. Their tension columns are the
one-sided derivative of the first pull (docs/friction.md section 3, "Sensitivities"), the
same in `tip_sensitivities`, `tdcr solve --jacobian` (JSON) and inverse statics, which
starts from them (before: NaN columns, `null` in the JSON and a refusal)."""

import warnings

import numpy as np
import tdcr

ROD = {"length": 0.3, "outer_radius": 0.0005, "youngs_modulus": 60e9, "poisson_ratio": 0.33}
OPTIONS = {"intervals": 32, "residual_tolerance": 1e-12}


def robot(tensions=(3.0, 0.0, 0.0)):
    routings = [
        {"kind": "straight", "x": 0.006, "y": 0.0},
        {"kind": "straight", "x": -0.003, "y": 0.005196152422706632},
        {"kind": "helical", "radius": 0.006, "turns_per_rod_length": 0.5, "phase": 4.1887902047863905},
    ]
    tendons = [
        {"routing": r, "tension": t, "friction": mu, "stiffness": 1500.0}
        for r, t, mu in zip(routings, tensions, (0.15, 0.1, 0.2))
    ]
    return tdcr.Robot(rod=ROD, tendons=tendons)


def test_unloaded_tendons_with_friction_have_the_first_pull_column(cli, tmp_path):
    r = robot()
    solution = tdcr.solve(r, **OPTIONS)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        columns = tdcr.tip_sensitivities(r, solution).tension
    assert np.all(np.isfinite(columns)), columns
    # Each unloaded tendon against full solves on the same mesh at 1e-3 and 1e-4 N,
    # Richardson-extrapolated (the quotients are linear in h: tests/first_pull.rs).
    for i in (1, 2):

        def quotient(h):
            tensions = [3.0, 0.0, 0.0]
            tensions[i] = h
            pulled = tdcr.solve(robot(tensions), warm_start=solution, **OPTIONS)
            assert len(pulled.s) == len(solution.s)
            return (pulled.tip_position - solution.tip_position) / h

        extrapolated = (10.0 * quotient(1e-4) - quotient(1e-3)) / 9.0
        # 1e-6 relative: measured 2e-8 to 8e-8 on the prototype's cases; the solves' tip
        # rounding (about 3e-12 m) over 1e-4 N is 3e-8 m/N, 1e-6 of these columns.
        error = np.linalg.norm(columns[:3, i] - extrapolated) / np.linalg.norm(extrapolated)
        assert error < 1e-6, (i, columns[:3, i], extrapolated)
    # The command gives the same numbers for the same file and mesh (the JSON's
    # jacobian.tension), bit for bit: the same solve and the same linearization.
    plain = tdcr.solve(r, intervals=32)
    ours = tdcr.tip_sensitivities(r, plain).tension
    path = tmp_path / "robot.toml"
    path.write_text(r.to_toml())
    printed = cli(["solve", str(path), "--format", "json", "--jacobian", "--intervals", "32"])
    theirs = np.array(printed["jacobian"]["tension"], dtype=float)
    assert theirs.shape == (6, 3) and np.all(np.isfinite(theirs))
    assert np.array_equal(theirs, ours), theirs - ours


def test_inverse_statics_starts_from_unloaded_tendons_with_friction():
    target = tdcr.solve(robot()).tip_position
    found = tdcr.solve_tensions(robot((0.5, 0.0, 0.0)), target, max_tension=6.0)
    assert found.reachable, found.explanation
    # 1e-6 m: the inverse's default tolerance on the tip.
    assert np.linalg.norm(found.solution.tip_position - target) <= 1e-6
