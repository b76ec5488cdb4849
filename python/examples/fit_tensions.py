"""Fit tendon tensions to a target shape by gradient descent through tdcr.torch.

The target is the backbone of the prototype at known tensions, sampled at eight arc
lengths; starting from other tensions, Adam moves them to reduce the mean squared distance
between the solved and the target points. Each step is one solve and one adjoint solve
(docs/python.md, "Gradients"). Needs the `torch` extra; runs in about a second.
"""

import torch

import tdcr
import tdcr.torch as tt

robot = tdcr.cases.prototype()
length = robot.length
samples = [length * (j + 1) / 8 for j in range(8)]
truth = torch.tensor([1.2, 0.0, 0.5, 0.0, 0.3], dtype=torch.float64)
target = tt.solve(robot, tension=truth, samples=samples).points.detach()

# Tensions cannot be negative: optimize z with tension = softplus(z).
z = torch.full((5,), -1.0, dtype=torch.float64, requires_grad=True)
optimizer = torch.optim.Adam([z], lr=0.2)
for step in range(150):
    optimizer.zero_grad()
    tension = torch.nn.functional.softplus(z)
    points = tt.solve(robot, tension=tension, samples=samples).points
    loss = ((points - target) ** 2).sum(-1).mean()
    loss.backward()
    optimizer.step()
    if step % 30 == 0:
        print(f"step {step:3d}  rms distance {loss.item() ** 0.5 * 1e3:8.4f} mm  tensions {tension.detach().numpy().round(3)}")

# Five tendons over-determine the shape (antagonistic pairs cancel), so the fit reaches the
# target shape with tensions that need not be the truth's.
tension = torch.nn.functional.softplus(z).detach()
rms = loss.item() ** 0.5
print(f"fitted tensions {tension.numpy().round(4)} N (truth {truth.numpy()}), rms distance {rms * 1e3:.2e} mm")
assert rms < 1e-4 * length, "the fit did not reach the target shape"
