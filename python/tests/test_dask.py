"""The same batch on a Dask cluster: a LocalCluster of two worker processes gives the local
`solve_parameters` result bitwise, and what a task returns or raises comes back as the
local call's object or exception."""

import numpy as np
import pytest
from dask import distributed  # python/requirements-ci.txt installs it

import tdcr
import tdcr.distributed


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            yield client


def test_dask_cluster_equals_local_batch(client):
    robot = tdcr.cases.prototype()
    tensions = np.random.default_rng(3).uniform(0.0, 3.0, size=(60, 4))
    parameters = {f"tension.{i + 1}": tensions[:, i] for i in range(4)}
    local = tdcr.solve_parameters(robot, parameters)
    remote = tdcr.distributed.solve_parameters(client, robot, parameters, chunk_size=16, retries=1)
    assert np.array_equal(remote["tip_position"], local["tip_position"])
    assert np.array_equal(remote["converged"], local["converged"]) and remote["error"] == local["error"]
    assert np.array_equal(remote["iterations"], local["iterations"])
    assert remote["stability"] == local["stability"] and len(local["stability"]) == 60


def test_results_and_exceptions_travel_through_dask(client):
    # Issue 30: a NotConverged raised in a task reached the caller as a bare Exception
    # (its report did not pickle), which `except tdcr.NotConverged` never caught.
    robot = tdcr.cases.case_h()
    solution = tdcr.solve(robot)
    with pytest.raises(tdcr.NotConverged) as e:
        client.submit(tdcr.solve, robot, max_iterations=1, continuation=False, pure=False).result()
    assert e.value.report.termination_code == "max_iterations" and e.value.report.iterations == 1
    sens = client.submit(tdcr.tip_sensitivities, robot, solution).result()
    assert np.array_equal(sens.compliance, tdcr.tip_sensitivities(robot, solution).compliance)
    shear = tdcr.Robot(
        rod={"length": 0.2, "outer_radius": 0.001, "youngs_modulus": 2e11, "shear_modulus": 8e10},
        tendons=[{"routing": {"kind": "straight", "x": 0.001, "y": 0.0}, "tension": 1.0}],
    )
    rows = {"tension.1": [0.5, 1.0]}
    remote = tdcr.distributed.solve_parameters(client, shear, rows, chunk_size=1)
    assert np.array_equal(remote["tip_position"], tdcr.solve_parameters(shear, rows)["tip_position"])


def test_chunks_cover_the_rows_in_order():
    parts = tdcr.distributed.chunks({"tension.1": np.arange(10.0)}, 4)
    assert [len(p["tension.1"]) for p in parts] == [4, 4, 2]
    assert np.array_equal(np.concatenate([p["tension.1"] for p in parts]), np.arange(10.0))
    with pytest.raises(tdcr.InvalidInput):
        tdcr.distributed.chunks({"tension.1": [1.0]}, 0)


def test_every_output_the_options_ask_for_comes_back(client):
    # A new user's check: the cluster's result had only the five default keys, so
    # `delivered_I` (a tendon with friction), `tip_orientation`, `error_estimate` and
    # `points` were dropped without a word while the local call returned them.
    robot = tdcr.cases.prototype().with_parameters({"friction.1": 0.1})
    rows = {"tension.1": np.linspace(0.5, 3.0, 12), "tension.2": np.linspace(0.0, 1.0, 12)}
    options = dict(orientation=True, error_estimate=True, points=3)
    local = tdcr.solve_parameters(robot, rows, **options)
    remote = tdcr.distributed.solve_parameters(client, robot, rows, chunk_size=5, **options)
    assert sorted(remote) == sorted(local) and "delivered_1" in local
    for key, value in local.items():
        if isinstance(value, np.ndarray):
            assert np.array_equal(remote[key], value), key
        else:
            assert remote[key] == value, key
