"""Solving from Python: agreement with the Rust command line, array shapes and dtypes,
options, reports, the JSON and pickle round trips, sensitivities, sweeps and inverse
statics."""

import json
import pickle

import numpy as np
import pytest

import tdcr

EXAMPLE = tdcr.example()


def test_cases_match_the_command_line(cli):
    # The command line solves `tdcr example` (case S by construction) and the same file with
    # case H's loads; Python solves its own cases. 1e-12 m: the bound (both are the
    # same computation, so they agree far below it).
    s = cli(["solve", "-", "--format", "json"], EXAMPLE)
    h = cli(["solve", "-", "--format", "json", "--tension", "1=0", "--tension", "5=4.91", "--tip-force", "0,0,-0.196"], EXAMPLE)
    for case, json in [(tdcr.cases.case_s(), s), (tdcr.cases.case_h(), h)]:
        solution = tdcr.solve(case)
        assert np.abs(solution.tip_position - np.array(json["tip"]["position"])).max() <= 1e-12
        assert np.abs(solution.tip_rotation - np.array(json["tip"]["rotation"])).max() <= 1e-12
        assert solution.report.iterations == json["iterations"]
    # And the reference tips of the Rust crate: 1e-6 m, the mesh error of the default 32
    # intervals (docs/validation.md).
    assert np.abs(tdcr.solve(tdcr.cases.case_h()).tip_position - tdcr.cases.TIP_H).max() < 1e-6


def test_a_file_a_dict_and_keywords_give_the_same_robot(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_text(EXAMPLE)
    from_file = tdcr.Robot.from_file(path)
    tables = {
        "rod": {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125},
        "base": {"position": [0.0, 0.0, 0.0], "rotation": np.array([[0, 0, 1.0], [0, 1, 0], [-1, 0, 0]])},
        "loads": {"distributed_force": (0.0, 0.0, -0.47)},
        "tendon": [
            {"routing": {"kind": "straight", "x": 0.008, "y": 0.0}, "tension": 2.94},
            {"routing": {"kind": "straight", "x": 0.0, "y": 0.008}, "tension": 0.0},
            {"routing": {"kind": "straight", "x": -0.008, "y": 0.0}, "tension": 0.0},
            {"routing": {"kind": "straight", "x": 0.0, "y": -0.008}, "tension": 0.0},
            {"routing": {"kind": "helical", "radius": 0.008, "turns": 1}, "tension": 0.0},
        ],
    }
    from_dict = tdcr.Robot.from_dict(tables)
    from_keywords = tdcr.Robot(tables["rod"], tendons=tables["tendon"], loads=tables["loads"], base=tables["base"])
    tips = [tdcr.solve(r).tip_position for r in [tdcr.cases.case_s(), from_file, from_dict, from_keywords]]
    for tip in tips[1:]:
        assert np.array_equal(tip, tips[0])


def test_arrays_have_their_shapes_and_dtypes():
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot, intervals=20)
    n = len(solution.s)
    assert n == 21
    shapes = {"s": (n,), "p": (n, 3), "R": (n, 3, 3), "v": (n, 3), "u": (n, 3), "n": (n, 3), "m": (n, 3), "tip_position": (3,), "tip_rotation": (3, 3)}
    for name, shape in shapes.items():
        array = getattr(solution, name)
        assert array.shape == shape and array.dtype == np.float64, name
    assert np.all(np.diff(solution.s) >= 0) and solution.s[0] == 0.0 and solution.s[-1] == robot.length
    assert np.array_equal(solution.p[-1], solution.tip_position)
    paths = solution.tendon_paths
    assert len(paths) == 5 and all(p.shape == (n, 3) and p.dtype == np.float64 for p in paths)
    state = solution.at(0.1)
    assert state.p.shape == (3,) and state.R.shape == (3, 3) and state.v.shape == (3,) and state.u.shape == (3,)
    assert np.array_equal(solution.at(robot.length).p, solution.tip_position)
    assert robot.tensions.shape == (5,) and robot.base_rotation.shape == (3, 3)
    report = solution.report
    assert report.converged and report.termination_code == "converged" and report.method == "collocation"
    # One meaning per name (front25): `termination` is the sentence the solution JSON holds.
    assert report.termination == json.loads(solution.to_json())["termination"]
    assert report.termination != "converged" and report.to_dict()["termination_code"] == "converged"
    # A direct solve on one mesh: every iteration is in the history of its one Newton run.
    assert report.load_steps == 0 and report.meshes == 1 and report.path == "direct"
    assert report.iterations >= 1 and report.history.shape == (report.iterations,)
    assert report.timings["total"] > 0.0 and report.intervals == 20
    # A fixed mesh (`intervals` alone): no tolerance, still the deferred-correction estimate.
    assert report.tolerance is None and report.tolerance_met is None
    assert report.tip_error_estimate == report.error_estimate["tip_position_m"] > 0.0


def test_options_reach_the_solver():
    robot = tdcr.cases.case_s()
    refined = tdcr.solve(robot, tol=1e-9)
    # tol is relative to the rod length: the estimate meets 1e-9 L, which at this tight
    # tolerance is the order-6 answer's (docs/numerics.md), far below the default's.
    assert refined.report.tolerance == 1e-9 and refined.report.tolerance_met is True
    assert refined.report.tip_error_estimate <= 1e-9 * robot.length
    assert refined.report.tip_error_estimate < 1e-2 * tdcr.solve(robot).report.tip_error_estimate
    # The estimate says which answer it belongs to, and a pickle keeps it.
    assert refined.report.error_estimate["order"] == 6
    assert tdcr.solve(robot).report.error_estimate["order"] == 4
    assert pickle.loads(pickle.dumps(refined)).report.error_estimate == refined.report.error_estimate
    shot = tdcr.solve(robot, method="shooting")
    assert shot.report.method == "shooting"
    # 1e-6 m: shooting's integration error and collocation's 32-interval mesh error.
    assert np.abs(shot.tip_position - refined.tip_position).max() < 1e-6
    warm = tdcr.solve(robot.with_parameters({"tension.1": 3.0}), warm_start=refined)
    assert warm.report.converged
    # A file's [solver] table is the default the options change.
    fine = tdcr.Robot.from_toml(EXAMPLE.replace("# intervals = 32", "intervals = 48"))
    assert fine.method == "collocation" and tdcr.solve(fine).report.intervals == 48


def test_every_bad_input_raises_its_class_with_the_command_line_message():
    with pytest.raises(tdcr.FileError) as e:
        tdcr.Robot.from_toml(EXAMPLE.replace("tension = 2.94", "tension = -1.0"), "bad.toml")
    assert str(e.value).startswith("bad.toml:") and "`tendon[1].tension` is -1 N, but a tendon can only pull" in str(e.value)
    assert e.value.problems[0][2] == "tendon[1].tension"
    with pytest.raises(tdcr.FileError, match="has no \\[rod\\] table"):
        tdcr.Robot.from_dict({"base": {"position": [0, 0, 0]}})
    with pytest.raises(tdcr.InvalidInput, match="cannot read robot file"):
        tdcr.Robot.from_file("/nonexistent/robot.toml")
    with pytest.raises(tdcr.InvalidInput, match="unknown option `tolerance`"):
        tdcr.solve(tdcr.cases.case_s(), tolerance=1e-9)
    with pytest.raises(tdcr.InvalidInput, match="options.tolerance"):
        tdcr.solve(tdcr.cases.case_s(), tol=-1.0)
    with pytest.raises(tdcr.InvalidInput, match="names tendon 6, but the robot has 5"):
        tdcr.cases.case_s().with_parameters({"tension.6": 1.0})
    with pytest.raises(tdcr.InvalidInput, match="a tendon can only pull"):
        tdcr.cases.case_s().with_tensions([-1.0, 0, 0, 0, 0])
    with pytest.raises(tdcr.NotConverged, match="collocation did not converge") as e:
        tdcr.solve(tdcr.cases.case_h(), max_iterations=1, continuation=False)
    assert e.value.report.termination_code == "max_iterations"
    with pytest.raises(tdcr.IntervalCap, match="needs more than the cap of 64 intervals"):
        tdcr.solve(tdcr.cases.case_h(), tol=1e-14, max_intervals=64)
    with pytest.raises(tdcr.InvalidInput, match="not a Solution.to_json text"):
        tdcr.Solution.from_json('{"format": "other"}')
    for cls in [tdcr.InvalidInput, tdcr.FileError, tdcr.SingularRouting, tdcr.NotConverged, tdcr.IntervalCap, tdcr.Breakdown]:
        assert issubclass(cls, tdcr.Error)


def test_a_solution_and_a_robot_round_trip():
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot, tol=1e-8)
    back = tdcr.Solution.from_json(solution.to_json())
    for name in ["s", "p", "R", "v", "u", "n", "m", "tip_position"]:
        assert np.array_equal(getattr(back, name), getattr(solution, name)), name
    assert np.array_equal(back.at(0.123).R, solution.at(0.123).R)
    assert back.report.iterations == solution.report.iterations
    assert back.report.tip_error_estimate == solution.report.tip_error_estimate
    assert back.report.timings == solution.report.timings
    assert np.array_equal(pickle.loads(pickle.dumps(solution)).p, solution.p)
    again = pickle.loads(pickle.dumps(robot))
    assert again.to_toml() == robot.to_toml()
    assert np.array_equal(tdcr.solve(again).tip_position, tdcr.solve(robot).tip_position)


def test_tip_sensitivities_match_a_finite_difference():
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot)
    sens = tdcr.tip_sensitivities(robot, solution)
    assert sens.tension.shape == (6, 5) and sens.compliance.shape == (6, 6) and sens.youngs_modulus.shape == (6,)
    assert np.array_equal(sens.compliance[:, :3], sens.tip_force)
    h = 1e-3  # N: central difference, truncation error O(h^2) times the third derivative
    up = tdcr.solve(robot.with_parameters({"tension.5": 4.91 + h})).tip_position
    down = tdcr.solve(robot.with_parameters({"tension.5": 4.91 - h})).tip_position
    # 1e-7 m/N: h^2 = 1e-6 N^2 times third derivatives of order 0.1 m/N^3, plus Newton noise 1e-9 m / h.
    assert np.abs((up - down) / (2 * h) - sens.tension[:3, 4]).max() < 1e-7


def test_sweep_warm_starts_to_the_cold_answers():
    robot = tdcr.cases.prototype()
    tensions = np.linspace(0.0, 3.0, 7)
    swept = tdcr.sweep(robot, {"tension.1": tensions})
    assert len(swept) == 7
    for t, solution in zip(tensions, swept):
        cold = tdcr.solve(robot.with_tensions([t, 0, 0, 0, 0]))
        # 1e-8 m: both stop at the scaled Newton residual 1e-11, which leaves the tip about
        # 1e-8 m from the exact discrete solution (docs/numerics.md).
        assert np.abs(solution.tip_position - cold.tip_position).max() < 1e-8


def test_solve_tensions_finds_case_s_from_its_tip():
    target = tdcr.solve(tdcr.cases.case_s()).tip_position
    result = tdcr.solve_tensions(tdcr.cases.prototype(), target, max_tension=5.0, free_tendons=[0])
    assert result.reachable and result.tensions.shape == (5,)
    # 1e-3 N: the 1e-6 m tip tolerance over a tip sensitivity of a few cm/N.
    assert abs(result.tensions[0] - 2.94) < 1e-3
    assert result.position_error <= 1e-6


def test_solve_displacements_recovers_a_pull_in():
    robot = tdcr.cases.prototype()
    pulled = robot.with_displacements([None, 0.003, None, None, None])
    target = tdcr.solve(pulled, intervals=32).tip_position
    result = tdcr.solve_displacements(robot, target, max_displacement=0.01, free_tendons=[1])
    assert result.reachable and result.displacements.shape == (5,)
    # 1e-6 m: the 1e-6 m tip tolerance over a tip sensitivity of about 25 m/m.
    assert abs(result.displacements[1] - 0.003) < 1e-6
    assert result.bounds == ["held", "inside", "held", "held", "held"]
    with pytest.raises(tdcr.InvalidInput, match="max_displacement"):
        tdcr.solve_displacements(robot, target, max_displacement=0.3)


def test_tip_sensitivities_of_a_displacement_controlled_robot():
    pulled = lambda q: tdcr.cases.prototype().with_displacements([q, None, None, None, None])
    # One fixed mesh for all three solves, so that the difference sees one discretization.
    solution = tdcr.solve(pulled(0.003), intervals=32)
    sens = tdcr.tip_sensitivities(pulled(0.003), solution)
    assert sens.displacement.shape == (6, 5) and not sens.tension[:, 0].any()
    h = 1e-5
    fd = (tdcr.solve(pulled(0.003 + h), intervals=32).tip_position - tdcr.solve(pulled(0.003 - h), intervals=32).tip_position) / (2 * h)
    # 1e-6 relative: central differences err by about h^2 (1e-10) plus the solves' remaining
    # error, about 1e-10 L (Newton's error-oriented stop), over h: 1e-7 of the 25 m/m here.
    assert np.abs(fd - sens.displacement[:3, 0]).max() <= 1e-6 * np.abs(fd).max()


def test_calibrate_recovers_a_stiffer_rod_from_synthetic_tips():
    robot = tdcr.cases.prototype()
    truth = robot.with_parameters({"youngs_modulus": 1.05 * 210e9})
    tensions = np.array([[2.94, 0, 0, 0, 0], [0, 2.94, 0, 0, 0], [0, 0, 1.96, 0, 0], [0, 0, 0, 0, 4.91]])
    forces = np.array([[0.0, 0.0, -0.098]] * 4)
    tips = np.array(
        [
            # On calibrate's fixed 32-interval mesh, so the synthetic tips are its model's own.
            tdcr.solve(
                truth.with_tensions(list(t)).with_parameters({"tip_force.z": f[2]}), intervals=32, residual_tolerance=1e-12
            ).tip_position
            for t, f in zip(tensions, forces)
        ]
    )
    fit = tdcr.calibrate(robot, tensions, forces, tips, fit=["youngs_modulus"])
    assert fit.converged and fit.names == ["E"]
    # 1e-6: the library's own calibration check (synthetic tips exact to the solve precision).
    assert abs(fit.youngs_modulus / (1.05 * 210e9) - 1.0) < 1e-6
    assert fit.tips.shape == (4, 3) and fit.tip_errors.shape == (4,) and fit.max_error < 1e-8
    with pytest.raises(tdcr.InvalidInput, match="cannot fit `mass`"):
        tdcr.calibrate(robot, tensions, forces, tips, fit=["mass"])


def test_every_public_name_has_a_docstring():
    for name in tdcr.__all__:
        if name == "__version__":
            continue
        obj = getattr(tdcr, name)
        assert (obj.__doc__ or "").strip(), name
        if isinstance(obj, type) and not issubclass(obj, BaseException):
            for attr, member in vars(obj).items():
                if not attr.startswith("_"):
                    assert (member.__doc__ or "").strip(), f"{name}.{attr}"
    assert "warm_start" in tdcr.solve.__doc__ and "tol" in tdcr.solve.__doc__


def test_friction_keywords_and_the_tension_along_the_tendon():
    import tdcr

    rod = {"length": 0.242, "outer_radius": 0.0004, "youngs_modulus": 210e9, "poisson_ratio": 0.3125}
    routing = {"kind": "straight", "x": 0.008, "y": 0.0}
    smooth = tdcr.Robot(rod=rod, tendons=[{"routing": routing, "tension": 2.94}])
    rough = tdcr.Robot(rod=rod, tendons=[{"routing": routing, "tension": 2.94, "friction": 0.1}])
    released = tdcr.Robot(
        rod=rod, tendons=[{"routing": routing, "tension": 2.94, "friction": 0.1, "motion": "release"}]
    )
    a, b, c = (tdcr.solve(r) for r in (smooth, rough, released))
    assert a.tendons[0]["delivered_tension"] == 2.94
    assert b.tendons[0]["delivered_tension"] < 2.94 < c.tendons[0]["delivered_tension"]
    along = b.tendon_tensions[0]
    assert along[0] == 2.94 and along[-1] == b.tendons[0]["delivered_tension"]
    assert all(x >= y for x, y in zip(along, along[1:]))
