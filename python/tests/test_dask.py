"""The same batch on a Dask cluster: a LocalCluster of two worker processes gives the local
`solve_parameters` result bitwise."""

import numpy as np
import pytest
from dask import distributed  # python/requirements-ci.txt installs it

import tdcr
import tdcr.distributed


def test_dask_cluster_equals_local_batch():
    robot = tdcr.cases.prototype()
    tensions = np.random.default_rng(3).uniform(0.0, 3.0, size=(60, 4))
    parameters = {f"tension.{i + 1}": tensions[:, i] for i in range(4)}
    local = tdcr.solve_parameters(robot, parameters)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = tdcr.distributed.solve_parameters(client, robot, parameters, chunk_size=16, retries=1)
    assert np.array_equal(remote["tip_position"], local["tip_position"])
    assert np.array_equal(remote["converged"], local["converged"]) and remote["error"] == local["error"]
    assert np.array_equal(remote["iterations"], local["iterations"])
    assert remote["stability"] == local["stability"] and len(local["stability"]) == 60


def test_chunks_cover_the_rows_in_order():
    parts = tdcr.distributed.chunks({"tension.1": np.arange(10.0)}, 4)
    assert [len(p["tension.1"]) for p in parts] == [4, 4, 2]
    assert np.array_equal(np.concatenate([p["tension.1"] for p in parts]), np.arange(10.0))
    with pytest.raises(tdcr.InvalidInput):
        tdcr.distributed.chunks({"tension.1": [1.0]}, 0)
