"""Messages and pictures from Python (issue 26, item 5): plausibility warnings as
`tdcr.PlausibilityWarning`, the likely cause of a failure, tendons numbered from 1, and the
pictures (matplotlib and the command line's SVG/PNG)."""

import warnings

import numpy as np
import pytest

import tdcr


def test_a_200_m_rod_warns():
    robot = tdcr.cases.case_s()
    long = tdcr.Robot.from_toml(robot.to_toml().replace("length = 0.242", "length = 200.0"))
    with pytest.warns(tdcr.PlausibilityWarning, match="200 m"):
        try:
            tdcr.solve(long, intervals=4, max_iterations=1, continuation=False)
        except tdcr.Error:
            pass  # the warning is the point; a 200 m rod of this section may not solve
    assert issubclass(tdcr.PlausibilityWarning, UserWarning)


def test_a_plausible_robot_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tdcr.solve(tdcr.cases.case_h())
        tdcr.Solver(tdcr.cases.case_s()).solve()


def test_a_failure_names_its_likely_causes():
    soft = tdcr.cases.case_h().with_parameters({"youngs_modulus": 1e3})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tdcr.PlausibilityWarning)
        with pytest.raises(tdcr.Error) as raised:
            tdcr.solve(soft, intervals=8, max_iterations=2, continuation=False)
    error = raised.value
    assert "likely causes:" in str(error)
    assert any("Young's modulus 1000 Pa" in c for c in error.likely_causes)
    # A failure of a plausible robot has none.
    with pytest.raises(tdcr.NotConverged) as raised:
        tdcr.solve(tdcr.cases.case_h(), max_iterations=1, continuation=False)
    assert raised.value.likely_causes == []


def test_tendons_are_numbered_from_1():
    robot = tdcr.cases.case_s()
    with pytest.raises(tdcr.InvalidInput, match=r"`tendon\[2\]\.tension` is -1 N"):
        robot.with_tensions([1.0, -1.0, 0.0, 0.0, 0.0])


def test_figure_writes_svg_and_png(tmp_path):
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot)
    tdcr.figure(robot, solution, tmp_path / "shape.svg", views=["side", "top"], width=600, title="H")
    svg = (tmp_path / "shape.svg").read_text()
    assert svg.startswith("<svg") and "side view" in svg and "tendon 5" in svg
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # a machine without fonts
        tdcr.figure(robot, solution, str(tmp_path / "shape.png"))
    assert (tmp_path / "shape.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(tdcr.InvalidInput, match="not a view"):
        tdcr.figure(robot, solution, tmp_path / "x.svg", views=["above"])
    with pytest.raises(tdcr.InvalidInput, match="width 50"):
        tdcr.figure(robot, solution, tmp_path / "x.svg", width=50)


def test_matplotlib_plot_draws_backbone_and_tendons():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    solution = tdcr.solve(tdcr.cases.case_h())
    ax = solution.plot()
    lines = ax.get_lines()
    assert len(lines) == 1 + 5  # backbone and five tendon paths
    np.testing.assert_array_equal(np.asarray(lines[0].get_data_3d()).T, solution.p)
    assert [l.get_linestyle() for l in lines[1:]] == ["--"] * 4 + ["-"]
    # The labels are shown (user25: they were set, but no legend was drawn).
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts[0] == "backbone" and texts[1] == "tendon 1 (slack)" and texts[5].startswith("tendon 5 (")
    assert tdcr.plot(solution, ax, tendons=False) is ax
