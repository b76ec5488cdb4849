"""Datasets that stream: the optional outputs of solve_parameters (one meaning with `tdcr
batch`), tdcr.dataset's sampling, resumption and files, and the memory of a 10^5-row batch."""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import tdcr


def robot():
    return tdcr.cases.prototype()


def rotation_of(q):
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_solve_parameters_outputs_are_the_solutions():
    r = robot()
    params = {"tension.1": [0.5, 2.0], "tip_force.y": [0.0, 0.05]}
    table = tdcr.solve_parameters(r, params, orientation=True, error_estimate=True, points=4)
    for i in range(2):
        s = tdcr.solve(r.with_parameters({k: v[i] for k, v in params.items()}))
        q = table["tip_orientation"][i]
        assert q[0] >= 0
        # 1e-14: a rotation from its quaternion, to rounding
        np.testing.assert_allclose(rotation_of(q), s.tip_rotation, atol=1e-14)
        assert table["error_estimate"][i] == s.report.tip_error_estimate
        for j, sj in enumerate(np.linspace(0.0, s.length, 4)):
            np.testing.assert_array_equal(table["points"][i, j], s.at(sj).p)
    with pytest.raises(tdcr.InvalidInput, match="at least 2"):
        tdcr.solve_parameters(r, params, points=1)


def test_solve_parameters_gives_the_numbers_of_tdcr_batch_and_of_solve(tmp_path, cli_text):
    # 300 random rows (four tensions, a sideways tip force): the library solves every row
    # cold with one reused workspace per thread, in Python as in `tdcr batch`, so the
    # numbers are equal (not close), and each is `tdcr.solve`'s of the row alone.
    rng = np.random.default_rng(26)
    params = {f"tension.{i}": rng.uniform(0.0, 3.0, 300).round(6) for i in range(1, 5)}
    params["tip_force.x"] = rng.uniform(-0.1, 0.1, 300).round(6)
    table = tdcr.solve_parameters(robot(), params, error_estimate=True)
    names = list(params)
    rows = "\n".join(",".join(repr(float(params[n][k])) for n in names) for k in range(300))
    (tmp_path / "cases.csv").write_text(",".join(names) + "\n" + rows + "\n")
    (tmp_path / "robot.toml").write_text(cli_text(["example", "robot"]))
    out = cli_text(["batch", "cases.csv", "--robot", "robot.toml", "--stability", "--error-estimate"], cwd=tmp_path)
    lines = out.splitlines()
    header = lines[0].split(",")
    assert len(lines) == 301 and table["converged"].all()
    for k, line in enumerate(lines[1:]):
        cells = dict(zip(header, line.split(",")))
        tip = [float(cells[f"tip_{a}"]) for a in "xyz"]
        # Exact: the same computation, written by the CLI in a format that reads back bitwise.
        assert tip == table["tip_position"][k].tolist(), k
        assert int(cells["iterations"]) == table["iterations"][k]
        assert cells["stability"] == table["stability"][k]
        assert float(cells["error_estimate"]) == table["error_estimate"][k]
    for k in range(0, 300, 50):
        s = tdcr.solve(robot().with_parameters({n: float(params[n][k]) for n in names}))
        np.testing.assert_array_equal(s.tip_position, table["tip_position"][k])


def test_dataset_latin_hypercube_fills_every_stratum(tmp_path):
    path = tmp_path / "lhs.npz"
    tdcr.dataset(robot(), path, ranges={"tension.1": (0.0, 2.0), "tension.3": (0.0, 1.0)}, rows=40, sampling="latin_hypercube", chunk_size=16)
    with np.load(path) as z:
        for name, high in [("tension.1", 2.0), ("tension.3", 1.0)]:
            strata = np.floor(z[f"parameter:{name}"] / high * 40).astype(int)
            assert sorted(strata) == list(range(40))
        assert z["tip_position"].shape == (40, 3) and z["converged"].all()
    assert not os.path.exists(str(path) + ".parts")


def test_dataset_resumes_an_interrupted_run(tmp_path, monkeypatch):
    ranges = {"tension.2": (0.0, 2.0), "tip_force.z": (-0.05, 0.0)}
    whole = tmp_path / "whole.npz"
    tdcr.dataset(robot(), whole, ranges=ranges, rows=25, chunk_size=10, orientation=True, points=3)
    import tdcr._dataset as ds

    calls = []
    real = ds.solve_parameters

    def interrupted(*args, **kwargs):
        if len(calls) == 1:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(ds, "solve_parameters", interrupted)
    part = tmp_path / "part.npz"
    with pytest.raises(KeyboardInterrupt):
        tdcr.dataset(robot(), part, ranges=ranges, rows=25, chunk_size=10, orientation=True, points=3)
    assert len(os.listdir(str(part) + ".parts")) == 2  # the manifest and one chunk
    with pytest.raises(tdcr.InvalidInput, match="other arguments"):
        tdcr.dataset(robot(), part, ranges=ranges, rows=26, chunk_size=10, orientation=True, points=3)
    monkeypatch.setattr(ds, "solve_parameters", real)
    tdcr.dataset(robot(), part, ranges=ranges, rows=25, chunk_size=10, orientation=True, points=3)
    with np.load(whole) as a, np.load(part) as b:
        assert sorted(a.keys()) == sorted(b.keys())
        for key in a.keys():
            np.testing.assert_array_equal(a[key], b[key])


def test_dataset_parquet_has_the_batch_column_names(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "d.parquet"
    tdcr.dataset(robot(), path, given={"tension.1": [0.5, 1.0, 1.5]}, chunk_size=2, orientation=True, points=2)
    table = pq.read_table(path)
    for name in ["tension.1", "tip_x", "q_w", "p2_z", "stability", "error"]:
        assert name in table.column_names


def test_a_batch_of_100000_rows_stays_under_100_mb(tmp_path):
    # In a fresh interpreter, so that the peak RSS is this batch's. The rows are cheap
    # (one straight tendon from 0 to 0.5 N) to keep the test's time modest; memory per row
    # does not depend on the row. A few rows first, so that the code pages and the thread
    # pool are in memory before the peak is read.
    script = textwrap.dedent(
        """
        import numpy as np, tdcr
        def peak():
            with open("/proc/self/status") as status:
                return int(next(line.split()[1] for line in status if line.startswith("VmHWM:"))) * 1024
        robot = tdcr.cases.prototype()
        tdcr.solve_parameters(robot, {"tension.1": np.linspace(0.0, 0.5, 64)}, orientation=True)
        t = np.linspace(0.0, 0.5, 100_000)
        before = peak()
        table = tdcr.solve_parameters(robot, {"tension.1": t}, orientation=True)
        assert table["converged"].all()
        arrays = sum(a.nbytes for a in table.values() if isinstance(a, np.ndarray))
        lists = sum(8 * len(a) for a in table.values() if isinstance(a, list))
        print(peak(), before, arrays + lists)
        """
    )
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True, text=True)
    # VmHWM: the peak RSS of this process's own memory. Not ru_maxrss, which Linux
    # carries across exec from the forking parent (pytest, larger than the batch by then).
    peak, before, kept = (int(v) for v in out.stdout.split()[-3:])
    mb = 2**20
    assert peak < 100 * mb, f"peak RSS {peak / mb:.0f} MB"
    # The call adds what it returns (7.7 MB here: the arrays and the lists' pointers) and
    # nothing else of size: no copy of the inputs, no arrays grown by doubling (measured:
    # 0.1 MB beyond the returned table; 2 MB leaves room for one chunk's buffers and the
    # allocator's per-thread arenas, not for a copy of a column or a doubled array).
    assert peak - before < kept + 2 * mb, f"the call took {(peak - before) / mb:.1f} MB, returning {kept / mb:.1f} MB"


def test_tendons_with_friction_get_delivered_columns_as_tdcr_batch_writes_them(tmp_path, cli_text):
    # Tendon 1 has friction in the robot, tendon 3 from a `friction.3` parameter (0 in one
    # row, which then delivers its tension); tendons 2 and 4 get no key, as in `tdcr batch`.
    r = robot().with_parameters({"friction.1": 0.1})
    params = {"tension.1": [2.0, 1.0], "tension.3": [1.5, 2.5], "friction.3": [0.2, 0.0]}
    table = tdcr.solve_parameters(r, params)
    assert [k for k in table if k.startswith("delivered")] == ["delivered_1", "delivered_3"]
    for i in range(2):
        s = tdcr.solve(r.with_parameters({k: v[i] for k, v in params.items()}))
        assert table["delivered_1"][i] == s.tendons[0]["delivered_tension"] < params["tension.1"][i]
        assert table["delivered_3"][i] == s.tendons[2]["delivered_tension"]
    assert table["delivered_3"][1] == 2.5
    assert not any(k.startswith("delivered") for k in tdcr.solve_parameters(robot(), {"tension.1": [1.0]}))
    (tmp_path / "robot.toml").write_text(cli_text(["example", "robot"]))
    (tmp_path / "cases.csv").write_text("tension.1,tension.3,friction.3\n2.0,1.5,0.2\n1.0,2.5,0.0\n")
    out = cli_text(["batch", "cases.csv", "--robot", "robot.toml", "--friction", "1=0.1"], cwd=tmp_path)
    lines = out.splitlines()
    header = lines[0].split(",")
    for k, line in enumerate(lines[1:]):
        cells = dict(zip(header, line.split(",")))
        # Exact: the same computation, written by the CLI in a format that reads back bitwise.
        assert float(cells["delivered_1"]) == table["delivered_1"][k]
        assert float(cells["delivered_3"]) == table["delivered_3"][k]
    path = tmp_path / "d.npz"
    tdcr.dataset(r, path, given=params, chunk_size=1)
    with np.load(path) as z:
        np.testing.assert_array_equal(z["delivered_3"], table["delivered_3"])
