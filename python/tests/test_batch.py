"""Batches: `solve_batch` equals one-by-one solves bitwise, keeps input order, releases the
GIL, and returns or raises failures; `solve_parameters` is its array form."""

import threading
import time

import numpy as np
import pytest

import tdcr


def random_tensions(rows, seed):
    return np.random.default_rng(seed).uniform(0.0, 3.0, size=(rows, 4))


def parameters(tensions):
    return {f"tension.{i + 1}": tensions[:, i] for i in range(4)}


def test_batch_equals_sequential_solves_bitwise_in_input_order():
    robot = tdcr.cases.prototype()
    tensions = random_tensions(24, 1)
    robots = [robot.with_tensions([*row, 0.0]) for row in tensions]
    batch = tdcr.solve_batch(robots, intervals=24)
    from_parameters = tdcr.solve_batch(robot, parameters(tensions), intervals=24)
    for r, a, b in zip(robots, batch, from_parameters):
        one = tdcr.solve(r, intervals=24)
        assert np.array_equal(a.p, one.p) and np.array_equal(a.R, one.R) and np.array_equal(b.p, one.p)
    arrays = tdcr.solve_parameters(robot, parameters(tensions), intervals=24)
    assert arrays["tip_position"].shape == (24, 3) and arrays["converged"].dtype == np.bool_
    assert np.array_equal(arrays["tip_position"], np.array([s.tip_position for s in batch]))
    assert arrays["iterations"].dtype == np.int64 and arrays["error"] == [""] * 24


def test_batch_releases_the_gil():
    robot = tdcr.cases.prototype()
    tensions = random_tensions(400, 2)
    counts = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
            if n % 1000 == 0:
                counts.append((time.perf_counter(), n))

    thread = threading.Thread(target=count)
    thread.start()
    start = time.perf_counter()
    tdcr.solve_batch(robot, parameters(tensions), intervals=64)
    end = time.perf_counter()
    done.set()
    thread.join()
    during = [n for t, n in counts if start < t < end]
    # The counter advanced during the batch: with the GIL held it could not run at all.
    assert len(during) >= 2 and during[-1] > during[0]


def test_failures_are_raised_or_returned_with_their_index():
    robot = tdcr.cases.case_h()
    options = dict(max_iterations=1, continuation=False)
    with pytest.raises(tdcr.NotConverged) as e:
        tdcr.solve_batch([tdcr.cases.case_s(), robot], **options)
    assert e.value.index in (0, 1)
    out = tdcr.solve_batch([robot, robot], errors="return", **options)
    assert all(isinstance(x, tdcr.NotConverged) for x in out) and [x.index for x in out] == [0, 1]
    arrays = tdcr.solve_parameters(robot, {"tension.5": [4.91]}, **options)
    assert not arrays["converged"][0] and np.isnan(arrays["tip_position"][0]).all()
    assert "did not converge" in arrays["error"][0]
    with pytest.raises(tdcr.InvalidInput, match="unknown parameter `mass`"):
        tdcr.solve_batch(robot, {"mass": [1.0]})
    with pytest.raises(tdcr.InvalidInput, match="has 1 values but another has 2"):
        tdcr.solve_batch(robot, {"tension.1": [1.0, 2.0], "tension.2": [1.0]})


def test_tension_parameters_make_a_displacement_controlled_tendon_tension_controlled():
    # Issue 23: `tension.1` used to set only the starting guess of a displacement-controlled
    # tendon's tension; now it means what Robot.with_tensions and the CLI's --tension mean.
    robot = tdcr.cases.prototype()
    pulled = robot.with_displacements([0.002, None, None, None, None])
    tensions = np.array([1.0, 2.5])
    reference = [tdcr.solve(robot.with_tensions([t, 0, 0, 0, 0])) for t in tensions]
    for name, solutions in [
        ("solve_batch", tdcr.solve_batch(pulled, {"tension.1": tensions})),
        ("sweep", tdcr.sweep(pulled, {"tension.1": tensions})),
        ("with_parameters", [tdcr.solve(pulled.with_parameters({"tension.1": t})) for t in tensions]),
    ]:
        for s, r in zip(solutions, reference):
            # 1e-8 m: warm and cold solves both stop at the scaled residual 1e-11, which
            # leaves the tip about 1e-8 m from the exact discrete solution.
            assert np.abs(s.tip_position - r.tip_position).max() < 1e-8, name
    assert pulled.with_parameters({"tension.1": 1.0}).displacements == [None] * 5
