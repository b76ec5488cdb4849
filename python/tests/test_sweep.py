"""Sweeps and traces from Python: the library's sweep with its events (the command line's
`tdcr sweep` runs the same one) and `trace`, checked against the command line."""

import csv
import io

import numpy as np
import pytest

import tdcr

EXAMPLE = tdcr.example()


def buckled():
    """About twice Euler's load on a 0.5 m rod buckled towards -x by a 10 mN imperfection,
    and a tendon on the +x side (docs/stability.md): pulled with 1 N the robot ends bent
    towards +x, a jump of the tip of about 0.8 m."""
    return tdcr.Robot(
        rod={"length": 0.5, "outer_radius": 0.001, "youngs_modulus": 200e9, "poisson_ratio": 0.3},
        tendons=[{"routing": {"kind": "straight", "x": 0.015, "y": 0.0}, "tension": 0.0}],
        loads={"distributed_force": [0.0, 0.0, -0.24], "tip_force": [-0.01, 0.0, -3.0]},
    )


def rows(text):
    return list(csv.DictReader(io.StringIO(text)))


def test_a_sweep_reports_the_command_lines_jump_verdicts_and_tips(cli_text):
    robot = buckled()
    swept = tdcr.sweep(robot, {"tension.1": np.linspace(0.0, 2.0, 3)})
    table = rows(cli_text(["sweep", "-", "--tension", "1=0:2:3"], robot.to_toml()))
    assert len(swept) == len(table) == 3
    assert swept.jumps == [1]
    assert "snap-through" in swept.events[1] and swept.events[0] is None and swept.events[2] is None
    assert [e or "" for e in swept.events] == [r["event"] for r in table]
    assert [s.report.stability for s in swept] == [r["stability"] for r in table]
    assert [s.report.path for s in swept] == [r["path"] for r in table]
    cli_tips = np.array([[float(r["tip_x"]), float(r["tip_y"]), float(r["tip_z"])] for r in table])
    # 1e-12 m: the same computation; the CSV prints round-trip digits.
    assert np.abs(swept.tip_positions - cli_tips).max() <= 1e-12
    assert swept.tip_positions.shape == (3, 3)
    assert np.array_equal(swept[-1].tip_position, swept.solutions[2].tip_position)
    with pytest.raises(IndexError):
        swept[3]


def test_a_failed_sweep_step_keeps_the_steps_before_it():
    with pytest.raises(tdcr.InvalidInput, match="can only pull") as e:
        tdcr.sweep(tdcr.cases.prototype(), {"tension.1": [1.0, 2.0, -1.0]})
    assert e.value.index == 2
    assert len(e.value.partial) == 2 and e.value.partial.events == [None, None]


def test_trace_is_the_command_lines_branch(cli_text):
    traced = tdcr.trace(tdcr.Robot.from_toml(EXAMPLE), "tension.1", 0.0, 4.0)
    table = rows(cli_text(["trace", "-", "--param", "tension.1=0:4"], EXAMPLE))
    assert traced.parameter == "tension.1" and traced.stopped is None
    assert len(traced.values) == len(table) >= 20
    assert traced.stability == [r["stability"] for r in table] == ["stable"] * len(table)
    assert traced.folds == [] and not any(traced.fold)
    # 1e-12: the same computation; the CSV prints round-trip digits.
    assert np.abs(traced.values - np.array([float(r["tension.1"]) for r in table])).max() <= 1e-12
    assert traced.tip_positions.shape == (len(table), 3)
    with pytest.raises(tdcr.InvalidInput, match="sweep E instead"):
        tdcr.trace(tdcr.Robot.from_toml(EXAMPLE), "youngs_modulus", 1e11, 2e11)
