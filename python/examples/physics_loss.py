"""Train a small network on tdcr data with a physics loss.

The network maps a desired tip position to five tendon tensions (an inverse model). Its
training data are tips of random tension rows solved by `tdcr.solve_parameters`; the loss
is physical: the network's tensions are solved by tdcr (tdcr.torch, gradients by the
adjoint) and the solved tip is compared with the desired one, so no tension labels are
needed and the network learns whatever tensions reach the tip. Needs the `torch` extra;
runs in a few seconds.
"""

import numpy as np
import torch

import tdcr
import tdcr.torch as tt

torch.manual_seed(0)
robot = tdcr.cases.prototype()
rng = np.random.default_rng(0)

# Data: tips of 256 random tension rows (tendons 1 and 3 pulled, 0 to 2 N).
rows = 256
tensions = np.zeros((rows, 5))
tensions[:, [0, 2]] = rng.uniform(0.0, 2.0, size=(rows, 2))
table = tdcr.solve_parameters(robot, {f"tension.{i + 1}": tensions[:, i] for i in range(5)})
tips = torch.tensor(table["tip_position"][table["converged"]], dtype=torch.float64)
mean, scale = tips.mean(0), tips.std(0) + 1e-9

net = torch.nn.Sequential(
    torch.nn.Linear(3, 32), torch.nn.Tanh(), torch.nn.Linear(32, 2), torch.nn.Softplus()
).double()
optimizer = torch.optim.Adam(net.parameters(), lr=0.02)
zeros = torch.zeros(1, dtype=torch.float64)


def tensions_of(tip):
    """The network's five tensions for desired tips (B, 3): tendons 1 and 3, others 0."""
    pulled = net((tip - mean) / scale)
    z = zeros.expand(tip.shape[0], 1)
    return torch.cat([pulled[:, :1], z, pulled[:, 1:], z, z], dim=1)


for epoch in range(30):
    batch = tips[torch.randperm(len(tips))[:64]]
    optimizer.zero_grad()
    solved = tt.solve_tip(robot, tension=tensions_of(batch))
    loss = ((solved - batch) ** 2).sum(-1).mean()  # the physics loss, m^2
    loss.backward()
    optimizer.step()
    if epoch % 5 == 0:
        print(f"epoch {epoch:2d}  rms tip error {loss.item() ** 0.5 * 1e3:7.3f} mm")

with torch.no_grad():
    error = (tt.solve_tip(robot, tension=tensions_of(tips)) - tips).norm(dim=-1)
print(f"after training: rms tip error {error.pow(2).mean().sqrt().item() * 1e3:.3f} mm over {len(tips)} tips")
