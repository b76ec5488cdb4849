"""Counts, stability verdicts, load paths, the `equilibrium` option and tendon states
(issues 14, 16 and 17) from Python, checked against the command line and against the
library's own reference numbers."""

import pickle

import numpy as np
import pytest

import tdcr

EXAMPLE = tdcr.example()

R1_TENDONS = [(0.015, 0.0, 15.0), (0.0, 0.015, 0.0), (-0.015, 0.0, 0.0), (0.0, -0.015, 0.0)]


def r1(solver=None):
    """Robot r1 of issue 14: a 0.5 m steel rod of 1 mm radius standing along +z with its
    self weight, tendon 1 at (15 mm, 0) pulled with 15 N, and a 3 N tip force along -z."""
    return tdcr.Robot(
        rod={"length": 0.5, "outer_radius": 0.001, "youngs_modulus": 200e9, "poisson_ratio": 0.3},
        tendons=[{"routing": {"kind": "straight", "x": x, "y": y}, "tension": t} for x, y, t in R1_TENDONS],
        loads={"distributed_force": [0.0, 0.0, -0.24], "tip_force": [0.0, 0.0, -3.0]},
        base={"position": [0.0, 0.0, 0.0], "rotation": np.eye(3)},
        solver=solver,
    )


def test_a_default_solve_of_the_prototype_is_stable_direct_and_counted_as_the_command_line(cli):
    solution = tdcr.solve(tdcr.cases.case_s())
    report = solution.report
    assert report.stability == "stable" and report.path == "direct"
    assert report.folds == [] and report.bifurcations == []
    assert report.stability_detail == {
        "verdict": "stable",
        "unstable_directions": 0,
        "conjugate_point_s": None,
        "reason": None,
        "growth": None,
        "growth_rate": None,
        "flutter_frequency": None,
    }
    assert report.stability_message == "stable"
    assert report.iterations == report.newton_steps + report.chord_steps
    assert report.newton_steps >= 1 and report.load_steps == 0 and report.meshes >= 1
    assert report.jacobian_evaluations == report.evaluations["jacobian"] >= report.newton_steps
    assert 0.0 < report.timings["stability"] <= report.timings["total"]
    assert "stability=stable" in repr(report) and "path=direct" in repr(report) and "stable" in repr(solution)
    # The command line solves the same file: every count and the verdict agree.
    json = cli(["solve", "-", "--format", "json"], EXAMPLE)
    counts = json["counts"]
    assert report.iterations == json["iterations"]
    assert report.newton_steps == counts["newton_steps"] and report.chord_steps == counts["chord_steps"]
    assert report.jacobian_evaluations == counts["jacobian_evaluations"]
    assert report.evaluations["residual"] == counts["residual_evaluations"]
    assert report.load_steps == counts["load_steps"] and report.meshes == counts["meshes"]
    assert json["stability"]["verdict"] == "stable" and json["stability"]["path"] == "direct"
    # to_dict is the same report in one flat dict.
    d = report.to_dict()
    for name in ["iterations", "newton_steps", "chord_steps", "load_steps", "meshes", "jacobian_evaluations", "stability", "path"]:
        assert d[name] == getattr(report, name), name
    assert d["unstable_directions"] == 0 and d["conjugate_point_s"] is None and d["stability_reason"] is None
    assert d["time_stability"] == report.timings["stability"] and d["folds"] == []


@pytest.fixture(scope="module")
def r1_solutions():
    """r1 solved by default (the load path) and with equilibrium="nearest"."""
    robot = r1()
    return robot, tdcr.solve(robot), tdcr.solve(robot, equilibrium="nearest")


def test_r1_follows_the_load_path_to_a_stable_state_and_nearest_finds_the_unstable_s_shape(cli, r1_solutions):
    robot, default, nearest = r1_solutions
    report = default.report
    assert report.converged and report.path == "load_path" and report.stability == "stable"
    assert report.load_steps >= 1 and report.iterations == report.newton_steps + report.chord_steps
    # Regression value, not an independent reference: the loaded-from-rest tip the solver
    # gave when issue 14 was filed. 1e-4 m: the issue quotes it to 0.1 mm.
    assert np.linalg.norm(default.tip_position - np.array([0.3684, 0.0, -0.0365])) < 1e-4
    # Newton from the guess: the S-shape bending against the pulled tendon, unstable.
    s_shape = nearest.report
    assert s_shape.converged and s_shape.path == "direct" and s_shape.stability == "unstable"
    assert nearest.tip_position[0] < 0.0
    detail = s_shape.stability_detail
    assert detail["verdict"] == "unstable" and detail["unstable_directions"] >= 1 and detail["reason"] is None
    assert 0.0 <= detail["conjugate_point_s"] < robot.length
    assert s_shape.stability_message.startswith("UNSTABLE")
    # The command line solves the robot's file to the same state with the same verdict.
    json = cli(["solve", "-", "--format", "json"], robot.to_toml())
    assert json["stability"]["verdict"] == "stable" and json["stability"]["path"] == "load_path"
    assert json["stability"]["folds"] == report.folds and json["stability"]["bifurcations"] == report.bifurcations
    assert np.abs(np.array(json["tip"]["position"]) - default.tip_position).max() <= 1e-12


def test_equilibrium_in_the_solver_table_is_the_default_the_keyword_changes(r1_solutions):
    robot, default, nearest = r1_solutions
    from_table = r1(solver={"equilibrium": "nearest"})
    assert "equilibrium = \"nearest\"" in from_table.to_toml()
    solved = tdcr.solve(from_table)
    assert solved.report.stability == "unstable" and np.array_equal(solved.tip_position, nearest.tip_position)
    # Pickling keeps the setting (through the robot file).
    again = tdcr.solve(pickle.loads(pickle.dumps(from_table)))
    assert np.array_equal(again.tip_position, nearest.tip_position)
    back = tdcr.solve(from_table, equilibrium="load_path")
    assert back.report.path == "load_path" and np.array_equal(back.tip_position, default.tip_position)


def test_stability_and_counts_round_trip_through_json_and_pickle(r1_solutions):
    _, default, nearest = r1_solutions
    for solution in [default, nearest, tdcr.solve(tdcr.cases.case_h())]:
        for back in [tdcr.Solution.from_json(solution.to_json()), pickle.loads(pickle.dumps(solution))]:
            a, b = solution.report, back.report
            assert b.to_dict() == a.to_dict()
            assert b.stability_detail == a.stability_detail and b.stability_message == a.stability_message
            assert b.timings == a.timings
            assert back.tendons == solution.tendons
    with pytest.raises(tdcr.InvalidInput, match="older tdcr"):
        tdcr.Solution.from_json(default.to_json().replace("tdcr-solution-3", "tdcr-solution-2"))


def test_a_bad_equilibrium_raises_invalid_input_naming_the_choices():
    robot = tdcr.cases.case_s()
    with pytest.raises(tdcr.InvalidInput, match='"load_path" or "nearest"') as e:
        tdcr.solve(robot, equilibrium="closest")
    assert '"closest"' in str(e.value) and isinstance(e.value, tdcr.Error)
    with pytest.raises(tdcr.InvalidInput, match="option `equilibrium` must be a string"):
        tdcr.solve(robot, equilibrium=1)
    with pytest.raises(tdcr.InvalidInput, match="closest"):
        tdcr.solve_batch([robot], equilibrium="closest")
    with pytest.raises(tdcr.InvalidInput, match="closest"):
        tdcr.sweep(robot, {"tension.1": [1.0]}, equilibrium="closest")
    with pytest.raises(tdcr.FileError, match="equilibrium"):
        r1(solver={"equilibrium": "closest"})


def test_tension_controlled_tendon_states():
    robot = tdcr.cases.case_s()
    solution = tdcr.solve(robot)
    states = solution.tendons
    assert len(states) == robot.tendon_count == 5
    assert all(set(t) == {"tension", "delivered_tension", "displacement", "length", "reference_length", "slack"} for t in states)
    assert all(t["delivered_tension"] == t["tension"] for t in states)  # no friction
    assert [t["tension"] for t in states] == list(robot.tensions) == list(solution.tensions)
    assert all(t["slack"] == 0.0 for t in states)
    # The straight tendons run parallel to the straight unloaded rod: their reference
    # length is L (1e-12 m: the quadrature of |p_i'| = 1 on the mesh, rounding only).
    for t in states[:4]:
        assert abs(t["reference_length"] - robot.length) < 1e-12
    # The pulled tendon shortens on the side it bends towards; its pull-in is the
    # difference (inextensible): reference_length - length.
    pulled = states[0]
    assert pulled["length"] < pulled["reference_length"]
    assert abs(pulled["displacement"] - (pulled["reference_length"] - pulled["length"])) < 1e-15


def case_s_tables(elastic):
    """Case S from keyword arguments; with `elastic` every tendon elastic (E_t A_t = 2000 N,
    0.1 m of free length: `stiffness` and `free_length` in the tendon dicts)."""
    routings = [
        {"kind": "straight", "x": 0.008, "y": 0.0},
        {"kind": "straight", "x": 0.0, "y": 0.008},
        {"kind": "straight", "x": -0.008, "y": 0.0},
        {"kind": "straight", "x": 0.0, "y": -0.008},
        {"kind": "helical", "radius": 0.008, "turns": 1},
    ]
    return tdcr.Robot(
        rod={"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125},
        tendons=[
            {"routing": r, "tension": 2.94 if i == 0 else 0.0, **({"stiffness": 2000.0, "free_length": 0.1} if elastic else {})}
            for i, r in enumerate(routings)
        ],
        loads={"distributed_force": [0.0, 0.0, -0.47]},
        base={"position": [0.0, 0.0, 0.0], "rotation": [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]},
    )


@pytest.mark.parametrize("elastic", [False, True])
def test_displacement_control_round_trips_to_the_same_tension(elastic):
    robot = case_s_tables(elastic)
    # A fixed mesh for both solves: the round trip compares two solves of one discrete system.
    first = tdcr.solve(robot, intervals=32)
    q = first.tendons[0]["displacement"]
    pulled = robot.with_displacements([q, None, None, None, None])
    assert pulled.displacements == [q, None, None, None, None]
    assert "q=" in repr(pulled)
    second = tdcr.solve(pulled, intervals=32)
    a, b = first.tendons[0]["tension"], second.tendons[0]["tension"]
    assert a == 2.94
    # 1e-9 relative: both are the same discrete solution at Newton tolerance 1e-11.
    assert abs(b - a) <= 1e-9 * a
    # 1e-10 m: a 1e-9 relative tension error moves the tip about 1e-10 m.
    assert np.abs(second.tip_position - first.tip_position).max() < 1e-10
    assert second.tendons[0]["displacement"] == q and second.tendons[0]["slack"] == 0.0
    # Held at its pull-in the same state is stable too (docs/stability.md,
    # "Displacement-controlled tendons": a length constraint can only stabilize).
    assert second.report.stability == "stable" and first.report.stability == "stable"
    assert second.report.stability_detail["unstable_directions"] == 0
    # The robot file keeps the displacement, the stiffness and the free length.
    again = tdcr.Robot.from_toml(pulled.to_toml())
    assert again.displacements == pulled.displacements and again.to_toml() == pulled.to_toml()
    assert np.array_equal(tdcr.solve(again, intervals=32).tip_position, second.tip_position)
    # with_tensions makes every tendon tension-controlled again.
    assert pulled.with_tensions([2.94, 0, 0, 0, 0]).displacements == [None] * 5


def test_elastic_tendons_pull_in_by_their_stretch():
    stiff = tdcr.solve(case_s_tables(False))
    soft_robot = case_s_tables(True)
    assert soft_robot.tendon_stiffnesses == [2000.0] * 5 and list(soft_robot.free_lengths) == [0.1] * 5
    soft = tdcr.solve(soft_robot)
    a, b = stiff.tendons[0], soft.tendons[0]
    # The same tension gives the same shape; the pull-in adds tau (l_ref + free) / (E_t A_t).
    stretch = 2.94 * (a["reference_length"] + 0.1) / 2000.0
    # 1e-12 m: the two differ only by the stretch term, computed from the same lengths.
    assert abs(b["displacement"] - a["displacement"] - stretch) < 1e-12


def test_a_tendon_let_out_goes_slack_and_exerts_nothing():
    # Case S's tendon 1 let out by 10 mm: far more than its length changes, so it is slack,
    # and the rod hangs as the prototype with every tendon slack.
    robot = tdcr.cases.case_s().with_displacements([-0.01, None, None, None, None])
    slack = tdcr.solve(robot, intervals=32)
    state = slack.tendons[0]
    assert state["tension"] == 0.0 and state["slack"] > 0.0 and state["displacement"] == -0.01
    free = tdcr.solve(tdcr.cases.prototype(), intervals=32)
    # 1e-10 m: the same discrete system to Newton tolerance.
    assert np.abs(slack.tip_position - free.tip_position).max() < 1e-10


def test_bad_tendon_inputs_raise_typed_errors():
    tendon = {"routing": {"kind": "straight", "x": 0.008, "y": 0.0}}
    rod = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}
    with pytest.raises(tdcr.FileError) as e:
        tdcr.Robot(rod, tendons=[{**tendon, "tension": 1.0, "displacement": 0.001}])
    assert e.value.problems[0][2] == "tendon[1].displacement"
    with pytest.raises(tdcr.FileError, match="neither `tension`"):
        tdcr.Robot(rod, tendons=[tendon])
    with pytest.raises(tdcr.InvalidInput, match="stiffness"):
        tdcr.Robot(rod, tendons=[{**tendon, "tension": 1.0, "stiffness": -5.0}])
    with pytest.raises(tdcr.InvalidInput, match="free_length"):
        tdcr.Robot(rod, tendons=[{**tendon, "tension": 1.0, "free_length": -0.1}])
    with pytest.raises(tdcr.InvalidInput, match="with_displacements got 1 displacement"):
        tdcr.cases.case_s().with_displacements([0.001])
    with pytest.raises(tdcr.InvalidInput, match="displacement"):
        tdcr.cases.case_s().with_displacements([float("nan"), None, None, None, None])
