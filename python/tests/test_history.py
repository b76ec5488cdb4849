"""`tdcr.history`: a load history with stick/slip friction (docs/friction.md section 8),
the same library call as `tdcr sweep --history`: the loop closes, the way back lies on the
other side, the zones, a failed step's `partial`, and pickling."""

import pickle

import numpy as np
import pytest

import tdcr

ROD = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3}
ROUTING = {"kind": "straight", "x": 0.008, "y": 0.0}


def robot(stiffness=2000.0, tension=0.0):
    tendon = {"routing": ROUTING, "tension": tension, "friction": 0.1}
    if stiffness is not None:
        tendon["stiffness"] = stiffness
    return tdcr.Robot(rod=ROD, tendons=[tendon])


def test_up_down_closes_a_loop_whose_way_back_is_on_the_other_side():
    tensions = np.linspace(0.0, 2.0, 11)
    h = tdcr.history(robot(), {"tension.1": tensions}, up_down=True)
    assert len(h) == 21
    tips = h.tip_positions
    rest = tips[0]
    # Back at 0 N the tendon is slack and the rod where it started (1e-9 m: two solves of
    # the same robot to the residual tolerance).
    assert np.linalg.norm(tips[20] - rest) < 1e-9
    # At 0 N no normal force: slack, the CLI's name too (not `release`).
    assert h.zones[0][0][1] == [(0.0, 0.242, "slack")] and h.zones[20][0][1] == [(0.0, 0.242, "slack")]
    for k in range(1, 10):
        assert np.linalg.norm(tips[20 - k] - rest) > np.linalg.norm(tips[k] - rest)
    # The first step back slides out near the base and sticks beyond, holding the
    # delivered tension of the top.
    tendon, zones = h.zones[11][0]
    assert tendon == 0
    assert zones[0][2] == "release" and zones[-1][2] == "stick"
    top = h[10].tendons[0]["delivered_tension"]
    # 1e-9 N: the stuck tip keeps its material, so its tension, to the solver's tolerance
    assert abs(h[11].tendons[0]["delivered_tension"] - top) < 1e-9
    # Every step has an estimate that meets the default tolerance, the stuck one too (from
    # its split meshes: order 4 with one tendon with friction, on more intervals than the
    # history's mesh; docs/friction.md section 8, "ord23").
    assert all(step.report.tolerance_met for step in h)
    assert h[11].report.error_estimate["order"] == 4
    assert h[11].report.intervals > h[10].report.intervals
    again = pickle.loads(pickle.dumps(h))
    assert np.array_equal(again.tip_positions, h.tip_positions)
    assert again.zones == h.zones


def test_the_history_keeps_its_inputs_and_directions_and_draws_its_loop(tmp_path):
    tensions = np.linspace(0.0, 2.0, 3)
    h = tdcr.history(robot(), {"tension.1": tensions}, up_down=True)
    assert list(h.inputs["tension.1"]) == [0.0, 1.0, 2.0, 1.0, 0.0]
    assert h.directions == ["from_rest", "up", "up", "down", "down"]
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    ax = tdcr.plot_history(h)
    # Four segments: two up (solid), two down (dashed), one legend entry each.
    assert len(ax.lines) == 4
    assert [line.get_linestyle() for line in ax.lines] == ["-", "-", "--", "--"]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "loading: the input rises",
        "unloading: the input falls",
    ]
    ax.figure.savefig(tmp_path / "loop.png")
    # The x axis is the swept input labelled with the library's unit, as the command line's
    # loop is (main labelled it "tension.1", without the unit).
    assert h.loop_x()[0] == "tension.1 (N)" and ax.get_xlabel() == "tension.1 (N)"
    np.testing.assert_array_equal(h.loop_x()[1], h.inputs["tension.1"])
    assert pickle.loads(pickle.dumps(h)).loop_x()[0] == "tension.1 (N)"
    # The default y axis is the library's tip displacement (m there, mm here), one definition
    # with the command line's picture; the other quantities by name.
    np.testing.assert_array_equal(ax.lines[1].get_ydata(), 1e3 * h.tip_displacements[1:3])
    assert ax.get_ylabel() == "tip displacement from the first step (mm)"
    tips = h.tip_positions
    np.testing.assert_array_equal(h.tip_displacements, np.linalg.norm(tips - tips[0], axis=1))
    label, z = h.loop_axis("tip_z")
    assert label == "tip z (mm)"
    np.testing.assert_array_equal(z, 1e3 * tips[:, 2])
    ax = tdcr.plot_history(h, y="bending_angle")
    assert ax.get_ylabel() == "bending angle (deg)"
    angles = h.loop_axis("bending_angle")[1]
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), angles[0:2])
    # The first step at 0 N without loads is straight (1e-9 deg: rounding of the solve).
    assert abs(angles[0]) < 1e-9 and angles[2] > 1.0
    with pytest.raises(tdcr.InvalidInput, match="tip_displacement, bending_angle"):
        tdcr.plot_history(h, y="angle")


def test_one_step_from_rest_is_the_pull_solve():
    h = tdcr.history(robot(), {"tension.1": [2.0]})
    direct = tdcr.solve(robot(tension=2.0))
    # 1e-10 m: the same equations on the same mesh
    assert np.linalg.norm(h[0].tip_position - direct.tip_position) < 1e-10


def test_a_rigid_tendon_that_sticks_raises_with_the_steps_before():
    # A model limit, not bad input (front25): the rigid tendon is valid, its stuck tension
    # indeterminate.
    with pytest.raises(tdcr.ModelLimit, match="stiffness") as caught:
        tdcr.history(robot(stiffness=None), {"tension.1": np.linspace(0.0, 2.0, 11)}, up_down=True)
    # Loading from rest slides all along; the first step back would stick.
    assert caught.value.index == 11
    assert len(caught.value.partial) == 11


def test_a_history_whose_mesh_solve_fails_raises_a_solver_failure_with_its_causes():
    # 1000 N bends the rod far past its tendon's limit: the full-slip solve of that step,
    # which chooses the history's mesh, fails before any step is solved.
    with pytest.raises(tdcr.NotConverged, match="no step was solved") as caught:
        tdcr.history(robot(), {"tension.1": [0.0, 2.0, 1000.0]})
    assert caught.value.likely_causes
    assert not hasattr(caught.value, "index")


def prototype_with_friction(tmp_path, actuation):
    """The prototype (self weight, tendon 1 loaded) with mu = 0.1 and E_t A_t = 2000 N on
    tendon 1, driven by `actuation` (a robot-file line), as tests/history_pull_in.rs."""
    tendon = f"{actuation}\nfriction = 0.1\nstiffness = 2000.0"
    text = tdcr.example().replace("tension = 2.94", tendon, 1)
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return tdcr.Robot.from_file(path)


def test_a_pull_in_history_closes_a_loop_whose_way_back_is_on_the_other_side(tmp_path):
    pull_ins = np.linspace(0.0, 0.02, 4)
    robot = prototype_with_friction(tmp_path, "displacement = 0.0")
    h = tdcr.history(robot, {"displacement.1": pull_ins}, up_down=True)
    assert len(h) == 7
    tips = h.tip_positions
    rest = tips[0]
    # Back at 0 m the tendon is slack and the rod where it started (1e-9 m: two solves of
    # the same robot to the residual tolerance, as for tensions).
    assert np.linalg.norm(tips[6] - rest) < 1e-9
    inputs = np.concatenate([pull_ins, pull_ins[-2::-1]])
    for k, step in enumerate(h):
        # The input is the pull-in each step holds (the same float the row gave).
        assert step.tendons[0]["displacement"] == inputs[k]
    for k in range(1, 3):
        up, down = h[k].tendons[0], h[6 - k].tendons[0]
        # Loading slides in all along, unloading out: the tension falls toward the
        # termination on the way up and rises on the way back.
        assert h.zones[k][0][1] == [(0.0, 0.242, "pull")]
        assert all(zone[2] == "release" for zone in h.zones[6 - k][0][1])
        assert up["delivered_tension"] < up["tension"] and down["delivered_tension"] > down["tension"]
        # The way back holds about the same integral of tension with less of it near the
        # base, so a lower base tension and a tip closer to rest (docs/friction.md section 8).
        assert down["tension"] < up["tension"]
        assert np.linalg.norm(tips[6 - k] - rest) < np.linalg.norm(tips[k] - rest)
    # A tension history driven by the solved base tensions gives the same tips (1e-9 m: the
    # pull-in loop stops at 1e-12 of the tension, each step solved to the residual tolerance).
    tensions = [step.tendons[0]["tension"] for step in h]
    again = tdcr.history(prototype_with_friction(tmp_path, "tension = 0.0"), {"tension.1": tensions})
    assert np.max(np.linalg.norm(again.tip_positions - tips, axis=1)) < 1e-9


def test_a_step_the_history_does_not_model_is_a_model_limit_not_bad_input():
    # user24: the prototype (friction 0.1, E_t A_t 2000 N on tendon 1) held at 2.94 N while
    # a sideways tip force rises to 0.05 N: step 2 would slide against friction away from
    # the base entry. The input is valid: `ModelLimit` (a `tdcr.Error`), not `InvalidInput`
    # (main raised InvalidInput).
    text = tdcr.example().replace(
        "tension = 2.94                   # N, >= 0\n",
        "tension = 2.94                   # N, >= 0\nfriction = 0.1\nstiffness = 2000.0\n",
        1,
    )
    proto = tdcr.Robot.from_toml(text)
    with pytest.raises(tdcr.ModelLimit, match="outside the model: `tendon\\[1\\].friction`") as caught:
        tdcr.history(proto, {"tip_force.y": np.linspace(0.0, 0.05, 5)}, up_down=True)
    assert not isinstance(caught.value, tdcr.InvalidInput)
    assert isinstance(caught.value, tdcr.Error)
    assert caught.value.index == 1 and len(caught.value.partial) == 1


def test_a_trace_of_a_robot_with_friction_is_a_model_limit():
    with pytest.raises(tdcr.ModelLimit, match="does not model friction yet"):
        tdcr.trace(robot(tension=1.0), "tension.1", 0.0, 1.0)
