"""The report's notes from Python (issue 25: at a perfectly symmetric bifurcation the solve
picks a side, says so and names the mirror state): the same sentences the command line
prints as `note:` lines, kept by pickling."""

import pickle
import subprocess

import numpy as np

import tdcr
from conftest import _binary

ROD = {"length": 0.5, "outer_radius": 0.001, "youngs_modulus": 200e9, "poisson_ratio": 0.3}
# Euler's load of the clamped-free column, pi^2 EI / (4 L^2) (N).
P_CR = np.pi**2 * 200e9 * np.pi / 4 * 0.001**4 / (4 * 0.5**2)


def column(ratio):
    """Issue 25's perfect column: a steel rod standing along +z under a dead tip force of
    `ratio` times Euler's load, no gravity, no tendons."""
    return tdcr.Robot(rod=ROD, loads={"tip_force": [0.0, 0.0, -ratio * P_CR]})


def test_a_perfect_column_past_eulers_load_says_which_side_it_took_as_the_command_line_does():
    below = tdcr.solve(column(0.9)).report
    assert below.notes == [] and below.stability == "stable"
    robot = column(1.5)
    report = tdcr.solve(robot).report
    assert report.stability == "stable" and report.path == "load_path"
    assert len(report.notes) == 1 and "mirror image" in report.notes[0], report.notes
    # The command line prints the same sentence on standard error.
    out = subprocess.run(
        [str(_binary()), "solve", "-"], input=robot.to_toml(), capture_output=True, text=True, check=True
    )
    notes = [line.split(": ", 2)[2] for line in out.stderr.splitlines() if line.startswith("note: ")]
    assert notes == report.notes
    # Pickling keeps them.
    assert pickle.loads(pickle.dumps(report)).notes == report.notes
