"""The numpy layer under `tdcr.torch` and `tdcr.jax`: named inputs (tension or pull-in
vectors, load vectors, E, routing offsets) to the parameter columns of `tdcr.linearize`, its outputs back to arrays with
the inputs' batch shape, and cotangents through `Linearization.vjp` to gradients shaped
like the inputs. docs/python.md ("Gradients") describes the interface."""

from __future__ import annotations

from typing import Any, Dict, List, Mapping, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from ._native import Linearization, Robot, linearize

#: The inputs a differentiable solve accepts (their per-row shapes: `trailing`).
VECTORS = ("tip_force", "tip_moment", "distributed_force", "base_position")
INPUTS = ("tension", "displacement") + VECTORS + ("youngs_modulus", "routing_offset")
_AXES = ("x", "y", "z")


class Shape(NamedTuple):
    """Outputs of a differentiable solve, with the inputs' batch shape B in front."""

    tip_position: Any
    """(*B, 3) tip position, m, world frame."""
    tip_rotation: Any
    """(*B, 3, 3) tip orientation R (body to world)."""
    points: Any
    """(*B, K, 3) backbone points p(s_j) at the K `samples`, m (K = 0 without samples)."""


def trailing(robot: Robot, name: str) -> Tuple[int, ...]:
    """The per-row shape of input `name`: (k,) for `tension` and `displacement`, (3,) for a
    vector, () for E, (k, 2) for `routing_offset` (x, y of each tendon's straight routing)."""
    if name in ("tension", "displacement"):
        return (robot.tendon_count,)
    if name == "routing_offset":
        return (robot.tendon_count, 2)
    if name in VECTORS:
        return (3,)
    if name == "youngs_modulus":
        return ()
    raise TypeError(f"unknown input `{name}`; the inputs are {', '.join(INPUTS)}")


def columns(name: str, shape: Tuple[int, ...]) -> List[str]:
    """The parameter columns (as `tdcr batch` names them) of input `name`, in the row-major
    order of its per-row shape."""
    if name in ("tension", "displacement"):
        return [f"{name}.{i + 1}" for i in range(shape[0])]
    if name == "routing_offset":
        return [f"routing.{i + 1}.{a}" for i in range(shape[0]) for a in _AXES[:2]]
    if name in VECTORS:
        return [f"{name}.{a}" for a in _AXES]
    return [name]


def batch_shape(robot: Robot, shapes: Mapping[str, Tuple[int, ...]]) -> Tuple[int, ...]:
    """The common batch shape of the inputs (their shapes without the per-row shape); raises
    `ValueError` naming an input whose trailing shape is wrong or whose batch shape differs."""
    batch: Optional[Tuple[int, ...]] = None
    for name, shape in shapes.items():
        tail = trailing(robot, name)
        if tuple(shape[len(shape) - len(tail):]) != tail or len(shape) < len(tail):
            raise ValueError(
                f"input `{name}` has shape {tuple(shape)}; give (..., {', '.join(map(str, tail))})"
                if tail
                else f"input `{name}` has shape {tuple(shape)}; give a scalar per row"
            )
        lead = tuple(shape[: len(shape) - len(tail)])
        if batch is None:
            batch = lead
        elif lead != batch:
            raise ValueError(
                f"input `{name}` has batch shape {lead}, another {batch}; broadcast the inputs to one batch shape"
            )
    if batch is None:
        raise ValueError(f"give at least one input to differentiate: {', '.join(INPUTS)}")
    if "tension" in shapes and "displacement" in shapes:
        raise ValueError(
            "give `tension` or `displacement`, not both: each sets how every tendon is driven "
            "(a tension input, or a pull-in whose tension is solved for)"
        )
    return batch


def solve(
    robot: Robot, inputs: Mapping[str, np.ndarray], samples: Optional[Sequence[float]], options: Dict[str, Any]
) -> Tuple[Linearization, Tuple[int, ...]]:
    """Solves every row of the inputs (numpy arrays, one batch shape) with `tdcr.linearize`."""
    arrays = {k: np.asarray(v, dtype=np.float64) for k, v in inputs.items()}
    batch = batch_shape(robot, {k: v.shape for k, v in arrays.items()})
    rows = int(np.prod(batch, dtype=np.int64))
    parameters: Dict[str, np.ndarray] = {}
    for name, value in arrays.items():
        flat = value.reshape(rows, -1)
        for j, column in enumerate(columns(name, trailing(robot, name))):
            parameters[column] = flat[:, j]
    return linearize(robot, parameters, samples=samples, **options), batch


def outputs(lin: Linearization, batch: Tuple[int, ...]) -> Shape:
    """The outputs of `lin` as numpy arrays with the batch shape in front."""
    k = len(lin.samples)
    return Shape(
        lin.tip_position.reshape(batch + (3,)),
        lin.tip_rotation.reshape(batch + (3, 3)),
        lin.points.reshape(batch + (k, 3)),
    )


def gradients(
    lin: Linearization,
    robot: Robot,
    names: Sequence[str],
    batch: Tuple[int, ...],
    cotangents: Sequence[Optional[np.ndarray]],
) -> List[np.ndarray]:
    """dloss/dinput for each input in `names` (in the order its columns were given to
    `solve`), from cotangents on (tip_position, tip_rotation, points) (None: zero)."""
    rows = int(np.prod(batch, dtype=np.int64))
    k = len(lin.samples)
    shapes = ((rows, 3), (rows, 3, 3), (rows, k, 3))
    flat = [None if c is None else np.asarray(c, dtype=np.float64).reshape(s) for c, s in zip(cotangents, shapes)]
    g = lin.vjp(tip_position=flat[0], tip_rotation=flat[1], points=flat[2])
    out = []
    at = 0
    for name in names:
        tail = trailing(robot, name)
        width = len(columns(name, tail))
        out.append(g[:, at : at + width].reshape(batch + tail))
        at += width
    return out
