"""Batches on a Dask cluster: the parameter rows are cut into chunks, each chunk is one
Dask task that runs `tdcr.solve_parameters` (all cores of its worker, GIL released), and
the chunk results are concatenated in row order. Scheduling, retries and data movement are
Dask's; this module only cuts and joins.

    from dask.distributed import Client
    import tdcr, tdcr.distributed
    client = Client("tcp://scheduler:8786")      # or LocalCluster(n_workers=2)
    robot = tdcr.cases.prototype()
    result = tdcr.distributed.solve_parameters(client, robot, {"tension.1": t1, "tension.2": t2}, chunk_size=500)
    result["tip_position"]                       # (M, 3), the same as tdcr.solve_parameters locally

The workers need the `tdcr` package installed (the same wheel as the client).
"""

from __future__ import annotations

from typing import Any, Dict, List, Mapping

import numpy as np

from . import _native

__all__ = ["chunks", "join", "solve_chunk", "solve_parameters"]


def chunks(parameters: Mapping[str, Any], chunk_size: int) -> List[Dict[str, np.ndarray]]:
    """Cuts a dict of equal-length 1-D arrays into consecutive chunks of at most
    `chunk_size` rows (the last may be shorter), in row order."""
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise _native.InvalidInput(f"chunk_size is {chunk_size!r}; give a whole number >= 1")
    columns = {name: _column(name, values) for name, values in parameters.items()}
    rows = None
    for name, values in columns.items():
        if rows is not None and len(values) != rows:
            raise _native.InvalidInput(
                f"parameter `{name}` has {len(values)} values but another has {rows}: give every parameter one value per row"
            )
        rows = len(values)
    rows = rows or 0
    return [
        {name: values[start : start + chunk_size] for name, values in columns.items()}
        for start in range(0, rows, chunk_size)
    ]


def _column(name: Any, values: Any) -> np.ndarray:
    """A parameter's values as a 1-D float64 array, refused as `tdcr.solve_parameters`
    refuses them (`tdcr.InvalidInput` with the same message)."""
    if not isinstance(name, str):
        raise _native.InvalidInput("parameter names must be strings")
    try:
        raw = np.asarray(values)
        if raw.dtype.kind == "b":
            raise _native.InvalidInput(f"parameter `{name}` holds booleans; give numbers")
        column = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError, RecursionError):
        column = None
    if column is None or column.ndim != 1:
        raise _native.InvalidInput(f"parameter `{name}` must be a 1-D sequence of numbers")
    return column


def solve_chunk(robot_toml: str, parameters: Dict[str, np.ndarray], options: Dict[str, Any]) -> Dict[str, Any]:
    """One task: the robot (as robot-file text) solved for every row of `parameters`
    with `tdcr.solve_parameters`; runs on a worker."""
    robot = _native.Robot.from_toml(robot_toml, "<dask task>")
    return _native.solve_parameters(robot, parameters, **options)


def solve_parameters(
    client: Any,
    robot: _native.Robot,
    parameters: Mapping[str, Any],
    chunk_size: int = 256,
    retries: int = 0,
    **options: Any,
) -> Dict[str, Any]:
    """`tdcr.solve_parameters(robot, parameters, **options)` on a Dask cluster: one task per
    chunk of `chunk_size` rows, submitted with `client.map` (Dask reruns a task up to
    `retries` times when its worker fails), gathered and joined in row order. Returns the
    same dict as the local call, with every key the options ask for (`delivered_I`,
    `tip_rotation`, the points...), bitwise identical to it."""
    text = robot.to_toml()
    parts = chunks(parameters, chunk_size)
    # Names and options checked here, as the local call checks them, before any task runs.
    _native.solve_parameters(robot, {name: np.zeros(0) for name in parameters}, **options)
    futures = client.map(solve_chunk, [text] * len(parts), parts, [options] * len(parts), pure=False, retries=retries)
    results = client.gather(futures)
    if not results:
        return _native.solve_parameters(robot, dict(parameters), **options)
    return join(results)


def join(results: List[Dict[str, Any]]) -> Dict[str, Any]:
    """The chunks' results as one, in row order: every key the local call returns, arrays
    concatenated along their first axis (rows) and lists chained."""
    joined: Dict[str, Any] = {}
    for key, first in results[0].items():
        parts = [r[key] for r in results]
        if isinstance(first, np.ndarray):
            joined[key] = np.concatenate(parts)
        else:
            joined[key] = [item for part in parts for item in part]
    return joined
