"""tdcr in PyTorch: solves as differentiable functions of tensions or pull-ins, loads, E and
routing offsets.

    import torch, tdcr, tdcr.torch
    robot = tdcr.cases.prototype()
    tension = torch.tensor([[1.0, 0, 0, 0, 0], [0, 2.0, 0, 0, 0]], dtype=torch.float64, requires_grad=True)
    tip = tdcr.torch.solve_tip(robot, tension=tension)   # (2, 3), m
    tip[:, 2].sum().backward()                           # tension.grad: (2, 5), m/N

The forward pass solves every row of the batch (the leading dimensions) on all cores; the
backward pass gives the gradient by the implicit function theorem: one transposed solve
with the factors of each row's converged Jacobian (docs/sensitivity.md, "Adjoint gradients"), not finite
differences. Inputs (each optional, one batch shape B): `tension` (*B, k) N, or
`displacement` (*B, k) m (every tendon's actuator pull-in: its tension is solved for, and
the gradient holds the pull-ins), `tip_force`, `tip_moment`, `distributed_force`,
`base_position` (*B, 3) world frame, `youngs_modulus` (*B,) Pa, `routing_offset` (*B, k, 2)
m (body-frame x, y of each tendon's straight routing; every routing must be straight:
`tdcr.linearize` takes `routing.I.x` columns of single tendons); inputs left out keep the
robot's values.
Needs the `torch` extra (`pip install "./python[torch]"`).
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
import torch

from . import _differentiable as core
from ._differentiable import INPUTS, Shape
from ._native import Robot

__all__ = ["Shape", "TipModel", "solve", "solve_tip"]


class _Solve(torch.autograd.Function):
    """The autograd node: forward solves (numpy in, tensors out), backward is one
    `Linearization.vjp`."""

    @staticmethod
    def forward(ctx: Any, robot: Robot, names: tuple, samples: Any, options: dict, *tensors: torch.Tensor):  # type: ignore[override]
        inputs = {n: t.detach().cpu().numpy() for n, t in zip(names, tensors)}
        lin, batch = core.solve(robot, inputs, samples, options)
        out = core.outputs(lin, batch)
        ctx.lin, ctx.robot, ctx.names, ctx.batch = lin, robot, names, batch
        ctx.like = [(t.dtype, t.device) for t in tensors]
        ref = tensors[0]
        return tuple(torch.as_tensor(np.ascontiguousarray(o), dtype=ref.dtype, device=ref.device) for o in out)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx: Any, *cotangents: torch.Tensor):  # type: ignore[override]
        cots = [None if c is None else c.detach().cpu().numpy() for c in cotangents]
        grads = core.gradients(ctx.lin, ctx.robot, ctx.names, ctx.batch, cots)
        out = [torch.as_tensor(g, dtype=d, device=dev) for g, (d, dev) in zip(grads, ctx.like)]
        return (None, None, None, None, *out)


def solve(
    robot: Robot,
    *,
    tension: Optional[torch.Tensor] = None,
    displacement: Optional[torch.Tensor] = None,
    tip_force: Optional[torch.Tensor] = None,
    tip_moment: Optional[torch.Tensor] = None,
    distributed_force: Optional[torch.Tensor] = None,
    base_position: Optional[torch.Tensor] = None,
    youngs_modulus: Optional[torch.Tensor] = None,
    routing_offset: Optional[torch.Tensor] = None,
    samples: Optional[Sequence[float]] = None,
    **options: Any,
) -> Shape:
    """Solves `robot` with the given inputs (module docs) for every row of their batch shape
    B; returns `Shape(tip_position (*B, 3), tip_rotation (*B, 3, 3), points (*B, K, 3))`,
    differentiable with respect to every input tensor. `samples`: arc lengths (m) of the K
    backbone points. `options`: as `tdcr.solve_batch` (collocation). Raises `ValueError`
    for inputs of the wrong shape, the first failed row's `tdcr.Error` otherwise."""
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
    tensors = {n: torch.as_tensor(v) for n, v in given.items() if v is not None}
    # Inputs with fewer batch dimensions broadcast against the others (autograd sums back).
    if not tensors:
        raise ValueError(f"give at least one input tensor: {', '.join(INPUTS)}")
    for n, t in tensors.items():
        core.batch_shape(robot, {n: tuple(t.shape)})
    leads = [t.shape[: t.dim() - len(core.trailing(robot, n))] for n, t in tensors.items()]
    common = torch.broadcast_shapes(*leads)
    names = tuple(tensors)
    expanded = [t.expand(tuple(common) + tuple(core.trailing(robot, n))) for n, t in tensors.items()]
    out = _Solve.apply(robot, names, None if samples is None else list(samples), options, *expanded)
    return Shape(*out)


def solve_tip(robot: Robot, **inputs: Any) -> torch.Tensor:
    """The tip position (*B, 3) of `solve(robot, **inputs)`, differentiable."""
    return solve(robot, **inputs).tip_position


class TipModel(torch.nn.Module):
    """`solve` as a module: `TipModel(robot, inputs=("tension",), samples=None, **options)`;
    `forward(*tensors)` takes the inputs in that order and returns the `Shape`."""

    def __init__(self, robot: Robot, inputs: Sequence[str] = ("tension",), samples: Optional[Sequence[float]] = None, **options: Any) -> None:
        super().__init__()
        for name in inputs:
            core.trailing(robot, name)
        self.robot, self.inputs, self.samples, self.options = robot, tuple(inputs), samples, options

    def forward(self, *tensors: torch.Tensor) -> Shape:  # type: ignore[override]
        if len(tensors) != len(self.inputs):
            raise ValueError(f"TipModel takes {len(self.inputs)} tensor(s) {self.inputs}, got {len(tensors)}")
        return solve(self.robot, samples=self.samples, **dict(zip(self.inputs, tensors)), **self.options)

