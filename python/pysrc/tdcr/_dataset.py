"""`tdcr.dataset`: sample parameter rows, solve them in chunks with `solve_parameters`, keep
each finished chunk on disk (so an interrupted run resumes where it stopped), and join the
chunks into one `.npz` (or `.parquet`, with pyarrow) column by column, so memory stays that
of one chunk whatever the number of rows. docs/python.md, "Datasets"."""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
import zipfile
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from ._native import InvalidInput, Robot, solve_parameters

SAMPLINGS = ("uniform", "latin_hypercube")


def _rows_and_names(ranges: Optional[Mapping[str, Sequence[float]]], given: Optional[Mapping[str, Any]], rows: Optional[int]) -> Tuple[int, List[str]]:
    if (ranges is None) == (given is None):
        raise InvalidInput("dataset: give either `ranges` (name -> (low, high)) with `rows`, or `given` (name -> array)")
    if given is not None:
        lengths = {len(np.asarray(v)) for v in given.values()}
        if len(lengths) != 1:
            raise InvalidInput(f"dataset: the `given` arrays have lengths {sorted(lengths)}; give one length")
        return lengths.pop(), list(given)
    if rows is None or rows < 1:
        raise InvalidInput(f"dataset: `rows` is {rows}; give the number of rows to sample (>= 1)")
    for name, bounds in ranges.items():
        low, high = bounds
        if not (np.isfinite(low) and np.isfinite(high) and low <= high):
            raise InvalidInput(f"dataset: range of `{name}` is ({low}, {high}); give finite (low, high) with low <= high")
    return rows, list(ranges)


class _Sampler:
    """The rows' inputs, chunk by chunk, the same on every run with the same seed."""

    def __init__(self, ranges, given, rows, sampling, seed):
        if sampling not in SAMPLINGS:
            raise InvalidInput(f"dataset: sampling=\"{sampling}\"; use one of {', '.join(SAMPLINGS)}")
        self.ranges, self.given, self.rows, self.sampling, self.seed = ranges, given, rows, sampling, seed
        # Latin hypercube: each parameter's strata, one per row, in a random order.
        self.strata = None
        if given is None and sampling == "latin_hypercube":
            rng = np.random.default_rng([seed, 0])
            self.strata = {name: rng.permutation(rows) for name in ranges}

    def chunk(self, index: int, start: int, stop: int) -> Dict[str, np.ndarray]:
        if self.given is not None:
            return {k: np.asarray(v, dtype=np.float64)[start:stop] for k, v in self.given.items()}
        rng = np.random.default_rng([self.seed, 1, index])
        out = {}
        for name, (low, high) in self.ranges.items():
            u = rng.random(stop - start)
            if self.strata is not None:
                u = (self.strata[name][start:stop] + u) / self.rows
            out[name] = low + (high - low) * u
        return out


def _progress(done: int, total: int, began: float, finished: bool) -> None:
    elapsed = time.perf_counter() - began
    rate = done / elapsed if elapsed > 0 else 0.0
    left = (total - done) / rate if rate > 0 else 0.0
    end = "\n" if finished else ""
    sys.stderr.write(f"\rdataset: {done}/{total} rows, {elapsed:.1f} s, {rate:.0f} rows/s, {left:.0f} s left {end}")
    sys.stderr.flush()


def _columns(chunk: Dict[str, np.ndarray], table: Dict[str, Any]) -> Dict[str, np.ndarray]:
    """The arrays a chunk file keeps: the inputs by name, then the outputs."""
    out = {f"parameter:{k}": v for k, v in chunk.items()}
    for key, value in table.items():
        if key == "stability":
            out[key] = np.asarray(value, dtype="<U8")
        elif key != "error":
            out[key] = np.asarray(value)
    failed = np.flatnonzero(~np.asarray(table["converged"]))
    out["failed"] = failed
    out["failed_error"] = np.asarray([table["error"][i] for i in failed], dtype=str)
    return out


def dataset(
    robot: Robot,
    path: "os.PathLike[str] | str",
    *,
    ranges: Optional[Mapping[str, Sequence[float]]] = None,
    rows: Optional[int] = None,
    given: Optional[Mapping[str, Any]] = None,
    sampling: str = "uniform",
    seed: int = 0,
    chunk_size: int = 20_000,
    orientation: bool = False,
    error_estimate: bool = False,
    points: int = 0,
    progress: Optional[bool] = None,
    **options: Any,
) -> str:
    """Samples `rows` parameter rows (`ranges`: name -> (low, high), names as `tdcr batch`
    columns; `sampling` "uniform" or "latin_hypercube"; `seed`) or takes `given` (name ->
    array), solves them in chunks of `chunk_size` rows with `solve_parameters` (its
    `orientation`, `error_estimate`, `points` and solver `options`), and writes `path`:
    `.npz` (the parameter columns as `parameter:NAME`, then `converged`, `tip_position`,
    `iterations`, `stability`, the optional outputs, `delivered_I` for each tendon I with
    friction (the delivered tension, N), and `failed` / `failed_error`: the
    failed rows and their messages) or `.parquet` (pyarrow; one flat column each, named as
    `tdcr batch` names them: tip_x, q_w, p1_x, delivered_1, ...). Finished chunks are kept in
    `path + ".parts"` until the end, so calling again with the same arguments resumes an
    interrupted run (other arguments raise `tdcr.InvalidInput`). `progress`: a line on
    stderr with rows/s and the time left (None: when stderr is a terminal). Returns the
    path written."""
    path = os.fspath(path)
    kind = "parquet" if path.endswith(".parquet") else "npz" if path.endswith(".npz") else None
    if kind is None:
        raise InvalidInput(f"dataset: `{path}` must end in .npz or .parquet")
    if chunk_size < 1:
        raise InvalidInput(f"dataset: chunk_size is {chunk_size}; give at least 1")
    if kind == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InvalidInput("dataset: writing .parquet needs pyarrow (pip install pyarrow); or write .npz") from None
    total, names = _rows_and_names(ranges, given, rows)
    sampler = _Sampler(ranges, given, total, sampling, seed)
    parts = path + ".parts"
    manifest = {
        "robot": robot.to_toml(),
        "names": names,
        "rows": total,
        "ranges": None if ranges is None else {k: list(map(float, v)) for k, v in ranges.items()},
        "given": given is not None,
        "sampling": sampling,
        "seed": seed,
        "chunk_size": chunk_size,
        "outputs": [orientation, error_estimate, points],
        "options": sorted((k, repr(v)) for k, v in options.items()),
    }
    os.makedirs(parts, exist_ok=True)
    manifest_path = os.path.join(parts, "manifest.json")
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            if json.load(f) != json.loads(json.dumps(manifest)):
                raise InvalidInput(
                    f"dataset: {parts} holds chunks of a run with other arguments; remove it, or call with that run's arguments to resume it"
                )
    else:
        with open(manifest_path, "w") as f:
            json.dump(manifest, f)
    show = sys.stderr.isatty() if progress is None else progress
    chunks = [(i, s, min(s + chunk_size, total)) for i, s in enumerate(range(0, total, chunk_size))]
    began, done_now, shown = time.perf_counter(), 0, False
    for index, start, stop in chunks:
        file = os.path.join(parts, f"chunk-{index:06d}.npz")
        if os.path.exists(file):
            continue
        inputs = sampler.chunk(index, start, stop)
        table = solve_parameters(
            robot, inputs, orientation=orientation, error_estimate=error_estimate, points=points, progress=False, **options
        )
        tmp = file + ".tmp.npz"
        np.savez(tmp, **_columns(inputs, table))
        os.replace(tmp, file)
        done_now += stop - start
        if show and time.perf_counter() - began > 1.0:
            _progress(done_now, total, began, False)
            shown = True
    if shown:
        _progress(done_now, total, began, True)
    files = [os.path.join(parts, f"chunk-{i:06d}.npz") for i, _, _ in chunks]
    (_join_parquet if kind == "parquet" else _join_npz)(files, path, total)
    shutil.rmtree(parts)
    return path


def _join_npz(files: List[str], path: str, total: int) -> None:
    """One .npz from the chunk files, each array streamed chunk by chunk into its .npy
    member (the `failed` row indices offset to the whole table)."""
    with np.load(files[0]) as first:
        keys = list(first.keys())
    tmp = path + ".tmp.npz"
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_STORED, allowZip64=True) as archive:
        for key in keys:
            parts = []
            for f in files:
                with np.load(f) as z:
                    a = z[key]
                parts.append((a.dtype, a.shape))
            dtype = np.result_type(*[d for d, _ in parts]) if parts[0][0].kind != "U" else max((d for d, _ in parts), key=lambda d: d.itemsize)
            length = sum(s[0] for _, s in parts)
            header = {"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": False, "shape": (length,) + parts[0][1][1:]}
            with archive.open(key + ".npy", "w", force_zip64=True) as out:
                np.lib.format.write_array_header_2_0(out, header)
                offset = 0
                for f in files:
                    with np.load(f) as z:
                        a = z[key]
                        rows = len(z["converged"])
                    if key == "failed":
                        a = a + offset
                    out.write(np.ascontiguousarray(a, dtype=dtype).tobytes())
                    offset += rows
    os.replace(tmp, path)


def _flat(key: str, a: np.ndarray) -> Dict[str, np.ndarray]:
    """The flat Parquet columns of one array, named as `tdcr batch` names them."""
    if key.startswith("parameter:"):
        return {key[len("parameter:"):]: a}
    if key == "tip_position":
        return {f"tip_{c}": a[:, i] for i, c in enumerate("xyz")}
    if key == "tip_orientation":
        return {f"q_{c}": a[:, i] for i, c in enumerate("wxyz")}
    if key == "points":
        return {f"p{j + 1}_{c}": a[:, j, i] for j in range(a.shape[1]) for i, c in enumerate("xyz")}
    return {key: a}


def _join_parquet(files: List[str], path: str, total: int) -> None:
    """One Parquet file from the chunk files, a row group per chunk (failed rows' messages
    as an `error` column)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    writer = None
    tmp = path + ".tmp.parquet"
    try:
        for f in files:
            with np.load(f) as z:
                columns: Dict[str, Any] = {}
                for key in z.keys():
                    if key not in ("failed", "failed_error"):
                        columns.update(_flat(key, z[key]))
                error = np.full(len(z["converged"]), "", dtype=object)
                error[z["failed"]] = z["failed_error"]
                columns["error"] = error
            table = pa.table({k: pa.array(v) for k, v in columns.items()})
            if writer is None:
                writer = pq.ParquetWriter(tmp, table.schema)
            writer.write_table(table)
    finally:
        if writer is not None:
            writer.close()
    os.replace(tmp, path)
