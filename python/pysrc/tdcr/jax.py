"""tdcr in JAX: solves as differentiable functions of tensions or pull-ins, loads, E and
routing offsets, with a
`jax.custom_vjp` whose forward and backward passes call tdcr through `jax.pure_callback`,
so they work under `jax.jit`; under `jax.vmap` the callback receives the whole batch and
solves it on all cores.

    import jax, jax.numpy as jnp, tdcr, tdcr.jax
    jax.config.update("jax_enable_x64", True)
    robot = tdcr.cases.prototype()
    loss = lambda t: tdcr.jax.solve_tip(robot, tension=t)[..., 2].sum()
    jax.grad(loss)(jnp.array([1.0, 0, 0, 0, 0]))          # (5,), m/N

Inputs and outputs as `tdcr.torch` (docs/python.md, "Gradients"). The backward pass solves
the rows again (the residuals a `custom_vjp` keeps are arrays, not solver state), then one
transposed solve per row. Results are float64 when x64 is enabled, else cast to the
inputs' dtype. Needs the `jax` extra (`pip install "./python[jax]"`).
"""

from __future__ import annotations

from typing import Any, Dict, Optional, Sequence, Tuple

import jax
import jax.numpy as jnp
import numpy as np

from . import _differentiable as core
from ._differentiable import INPUTS, Shape
from ._native import Robot

__all__ = ["Shape", "solve", "solve_tip"]


def _result_shapes(batch: Tuple[int, ...], k: int, dtype: Any) -> Shape:
    return Shape(
        jax.ShapeDtypeStruct(batch + (3,), dtype),
        jax.ShapeDtypeStruct(batch + (3, 3), dtype),
        jax.ShapeDtypeStruct(batch + (k, 3), dtype),
    )


def _function(robot: Robot, names: Tuple[str, ...], samples: Optional[Tuple[float, ...]], options: Tuple[Tuple[str, Any], ...]) -> Any:
    """The custom_vjp function of the inputs `names` for one robot, samples and options."""
    opts: Dict[str, Any] = dict(options)
    k = 0 if samples is None else len(samples)
    tails = [core.trailing(robot, n) for n in names]

    def batch_of(arrays: Sequence[Any]) -> Tuple[int, ...]:
        return tuple(arrays[0].shape[: arrays[0].ndim - len(tails[0])])

    def forward_host(*arrays: np.ndarray) -> Shape:
        lin, batch = core.solve(robot, dict(zip(names, arrays)), samples, opts)
        dtype = arrays[0].dtype
        return Shape(*(np.ascontiguousarray(o).astype(dtype) for o in core.outputs(lin, batch)))

    def backward_host(*arrays: np.ndarray) -> Tuple[np.ndarray, ...]:
        inputs, cots = arrays[: len(names)], arrays[len(names) :]
        lin, batch = core.solve(robot, dict(zip(names, inputs)), samples, opts)
        grads = core.gradients(lin, robot, names, batch, list(cots))
        return tuple(g.astype(a.dtype) for g, a in zip(grads, inputs))

    def call_forward(*arrays: Any) -> Shape:
        shapes = _result_shapes(batch_of(arrays), k, arrays[0].dtype)
        return Shape(*jax.pure_callback(forward_host, tuple(shapes), *arrays, vmap_method="broadcast_all"))

    @jax.custom_vjp
    def f(*arrays: Any) -> Shape:
        return call_forward(*arrays)

    def f_fwd(*arrays: Any) -> Tuple[Shape, Tuple[Any, ...]]:
        return call_forward(*arrays), arrays

    def f_bwd(arrays: Tuple[Any, ...], cot: Shape) -> Tuple[Any, ...]:
        shapes = tuple(jax.ShapeDtypeStruct(a.shape, a.dtype) for a in arrays)
        return tuple(jax.pure_callback(backward_host, shapes, *arrays, *cot, vmap_method="broadcast_all"))

    f.defvjp(f_fwd, f_bwd)
    return f


def solve(
    robot: Robot,
    *,
    tension: Any = None,
    displacement: Any = None,
    tip_force: Any = None,
    tip_moment: Any = None,
    distributed_force: Any = None,
    base_position: Any = None,
    youngs_modulus: Any = None,
    routing_offset: Any = None,
    samples: Optional[Sequence[float]] = None,
    **options: Any,
) -> Shape:
    """Solves `robot` with the given inputs for every row of their batch shape B; returns
    `Shape(tip_position (*B, 3), tip_rotation (*B, 3, 3), points (*B, K, 3))`,
    differentiable (reverse mode) with respect to every input. As `tdcr.torch.solve`."""
    given = dict(
        tension=tension,
        displacement=displacement,
        tip_force=tip_force,
        tip_moment=tip_moment,
        distributed_force=distributed_force,
        base_position=base_position,
        youngs_modulus=youngs_modulus,
        routing_offset=routing_offset,
    )
    arrays = {n: jnp.asarray(v) for n, v in given.items() if v is not None}
    if not arrays:
        raise ValueError(f"give at least one input array: {', '.join(INPUTS)}")
    for n, a in arrays.items():
        core.batch_shape(robot, {n: tuple(a.shape)})
    leads = [a.shape[: a.ndim - len(core.trailing(robot, n))] for n, a in arrays.items()]
    common = tuple(np.broadcast_shapes(*leads))
    dtype = jnp.result_type(*arrays.values(), float)
    expanded = [jnp.broadcast_to(a.astype(dtype), common + core.trailing(robot, n)) for n, a in arrays.items()]
    key = None if samples is None else tuple(float(s) for s in samples)
    f = _function(robot, tuple(arrays), key, tuple(sorted(options.items())))
    return f(*expanded)


def solve_tip(robot: Robot, **inputs: Any) -> Any:
    """The tip position (*B, 3) of `solve(robot, **inputs)`, differentiable."""
    return solve(robot, **inputs).tip_position
