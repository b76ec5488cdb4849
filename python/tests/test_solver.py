"""The stateful `tdcr.Solver` (issue 26, item 1): warm solves and control Jacobians equal
the stateless functions' results; only the columns asked for; reset; messages."""

import numpy as np
import pytest

import tdcr


def stepped(robot):
    """A control step: a solver that solved `robot` and took its tension Jacobian, then
    solved `robot` with its most pulled tendon 0.05 N harder (warm); the stateless warm
    solve of it."""
    solver = tdcr.Solver(robot)
    first = solver.solve()
    solver.tip_jacobian()
    tension = np.array(robot.tensions, dtype=float)
    i = int(np.argmax(tension))
    tension[i] += 0.05
    warm = solver.solve(tension=tension)
    stateless = tdcr.solve(robot.with_parameters({f"tension.{i + 1}": tension[i]}), warm_start=first)
    return solver, warm, stateless


@pytest.mark.parametrize("case", [tdcr.cases.case_s, tdcr.cases.case_h])
def test_warm_solve_and_jacobian_equal_the_stateless_ones(case):
    solver, warm, stateless = stepped(case())
    # 1e-12 m on a 0.24 m rod: both run chord steps on the factors of the Jacobian at
    # `first` (the stateless solve factors it for its warm start, the solver kept it from
    # tip_jacobian), so they agree to rounding.
    np.testing.assert_allclose(warm.p, stateless.p, rtol=0, atol=1e-12)
    jacobian = solver.tip_jacobian(["tension"])
    full = tdcr.tip_sensitivities(solver.robot, warm).tension
    assert jacobian.shape == full.shape == (6, 5)
    # 1e-12 relative: the same Jacobian, right-hand sides and solves.
    np.testing.assert_allclose(jacobian, full, rtol=0, atol=1e-12 * np.abs(full).max())
    # Only the columns asked for, in order; the default is every tension.
    some = solver.tip_jacobian(["tip_force.z", "tension.5"])
    everything = tdcr.tip_sensitivities(solver.robot, warm)
    # 1e-10 for the tip force: tip_sensitivities contracts its right-hand side with the six
    # tip multipliers (transposed solves), which differs from the forward solve by rounding
    # times the condition number (~1e5; tests/adjoint.rs).
    np.testing.assert_allclose(some[:, 0], everything.tip_force[:, 2], rtol=0, atol=1e-10 * np.abs(everything.tip_force).max())
    np.testing.assert_allclose(some[:, 1], full[:, 4], rtol=0, atol=1e-12 * np.abs(full).max())
    np.testing.assert_array_equal(solver.tip_jacobian(), jacobian)


def test_backbone_jacobian_at_the_tip_is_the_tip_jacobians_position_rows():
    solver = tdcr.Solver(tdcr.cases.case_h())
    solution = solver.solve()
    length = solution.s[-1]
    backbone = solver.backbone_jacobian([0.0, 0.5 * length, length], "tension")
    assert backbone.shape == (3, 3, 5)
    assert np.abs(backbone[0]).max() < 1e-12  # the base is clamped
    tip = solver.tip_jacobian("tension")
    np.testing.assert_allclose(backbone[2], tip[:3], rtol=0, atol=1e-12 * np.abs(tip).max())


def test_parameters_stay_set_and_reset_starts_cold():
    solver = tdcr.Solver(tdcr.cases.case_s(), intervals=32)
    solver.solve({"tip_force.z": -0.1})
    again = solver.solve()
    fresh = tdcr.solve(tdcr.cases.case_s().with_parameters({"tip_force.z": -0.1}), intervals=32)
    np.testing.assert_allclose(again.tip_position, fresh.tip_position, rtol=0, atol=1e-12)
    solver.reset()
    assert solver.solution is None
    cold = solver.solve()
    assert cold.report.iterations >= 1
    np.testing.assert_array_equal(cold.tip_position, fresh.tip_position)


def test_messages_say_what_is_missing():
    solver = tdcr.Solver()
    with pytest.raises(tdcr.InvalidInput, match="no robot yet"):
        solver.solve()
    solver = tdcr.Solver(tdcr.cases.case_s())
    with pytest.raises(tdcr.InvalidInput, match="nothing solved yet"):
        solver.tip_jacobian()
    solver.solve()
    with pytest.raises(tdcr.InvalidInput, match="names tendon 9"):
        solver.tip_jacobian(["tension.9"])
    with pytest.raises(tdcr.InvalidInput, match="not a column"):
        solver.tip_jacobian(["load_scale"])
    with pytest.raises(tdcr.InvalidInput, match="one per tendon"):
        solver.solve(tension=[1.0, 2.0])
    with pytest.raises(tdcr.InvalidInput, match="outside the rod"):
        solver.backbone_jacobian([1.0])


def test_warm_solves_without_a_jacobian_agree_to_the_newton_stop():
    robot = tdcr.cases.case_h()
    solver = tdcr.Solver(robot)
    first = solver.solve()
    warm = solver.solve({"tension.5": 4.95})
    stateless = tdcr.solve(robot.with_parameters({"tension.5": 4.95}), warm_start=first)
    # 1e-10 of the rod length: here the chord steps start on the last Newton matrix of the
    # first solve, not on the Jacobian at its solution, and both stop when the estimated
    # remaining scaled error is below the Newton stop's 1e-10 (collocation/newton.rs).
    np.testing.assert_allclose(warm.p, stateless.p, rtol=0, atol=1e-10 * 0.242)


@pytest.mark.parametrize("case", [tdcr.cases.case_s, tdcr.cases.case_h])
def test_solver_tip_sensitivities_equal_the_stateless_ones(case):
    robot = case()
    solver = tdcr.Solver(robot)
    first = solver.solve(tension=0.99 * np.array(robot.tensions, dtype=float))
    warm = solver.solve(tension=np.array(robot.tensions, dtype=float))
    ours = solver.tip_sensitivities()
    theirs = tdcr.tip_sensitivities(solver.robot, warm)
    assert type(ours) is type(theirs)
    for name in ["tension", "displacement", "friction", "tip_force", "tip_moment", "base_position", "base_rotation", "youngs_modulus"]:
        a, b = getattr(ours, name), getattr(theirs, name)
        assert a.shape == b.shape
        # 1e-12 relative: the same Jacobian values, right-hand sides and solves (the
        # solver factors the one its verdict evaluated at the solution); rounding only.
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max(), err_msg=name)
    # Given a solution that is not the last (the first one, of the robot at 0.99 times the
    # tensions), the Jacobian is assembled as the stateless function assembles it.
    before = robot.with_parameters({f"tension.{i + 1}": 0.99 * t for i, t in enumerate(robot.tensions)})
    other = solver.tip_sensitivities(before, first)
    np.testing.assert_array_equal(other.tension, tdcr.tip_sensitivities(before, first).tension)
    assert not np.array_equal(other.tension, ours.tension)
    with pytest.raises(tdcr.InvalidInput, match="give both"):
        solver.tip_sensitivities(robot)
