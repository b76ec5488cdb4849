"""Gradients by the adjoint (tdcr.linearize, tdcr.torch, tdcr.jax): against the forward
sensitivities, and against finite differences of full solves (torch.autograd.gradcheck,
jax.test_util.check_grads) in double precision. The torch and jax tests are skipped
without those extras (.ci/extras runs them)."""

import re

import numpy as np
import pytest

import tdcr

# A fixed mesh and Newton at its rounding floor: finite differences of full solves then see
# a smooth function (an adaptive mesh would jump between meshes as parameters move).
OPTIONS = dict(intervals=32, residual_tolerance=1e-12)


def robot():
    """The prototype with two tendons pulled, gravity and a tip force (all tension-controlled)."""
    r = tdcr.cases.prototype().with_tensions([1.5, 0.0, 0.8, 0.0, 0.0])
    return r.with_parameters({"tip_force.y": 0.05})


def test_vjp_of_the_tip_is_a_row_of_the_tip_sensitivities():
    r = robot()
    params = {f"tension.{i + 1}": [t] for i, t in enumerate(r.tensions)}
    params["tip_force.y"] = [0.05]
    lin = tdcr.linearize(r, params, **OPTIONS)
    solved = tdcr.solve(r, **OPTIONS)
    np.testing.assert_array_equal(lin.tip_position[0], solved.tip_position)
    sens = tdcr.tip_sensitivities(r, solved)
    for axis in range(3):
        cot = np.zeros((1, 3))
        cot[0, axis] = 1.0
        g = lin.vjp(tip_position=cot)[0]
        # 1e-10: the adjoint and the forward solves share dF/dq; they differ by rounding
        scale = np.abs(sens.tension).max()
        np.testing.assert_allclose(g[:5], sens.tension[axis], rtol=1e-10, atol=1e-10 * scale)
        np.testing.assert_allclose(g[5], sens.tip_force[axis, 1], rtol=1e-10)


def test_linearize_refuses_samples_off_the_rod_and_bad_parameters():
    r = robot()
    with pytest.raises(tdcr.InvalidInput, match="outside the rod"):
        tdcr.linearize(r, {"tension.1": [1.0]}, samples=[1.0])
    with pytest.raises(tdcr.InvalidInput, match="routing is not straight"):
        tdcr.linearize(r, {"routing.5.x": [0.0]})
    lin = tdcr.linearize(r, {"tension.1": [1.0, 2.0]}, samples=[0.1])
    with pytest.raises(tdcr.InvalidInput, match=r"shape \(2, 1, 3\)"):
        lin.vjp(points=np.zeros((2, 2, 3)))


def pulled():
    """The prototype with tendon 1 pulled in by 5 mm (its tension solved) and tendon 3 at a
    tension, gravity and a tip force."""
    return robot().with_displacements([0.005, None, None, None, None])


def test_pull_in_and_routing_gradients_match_differences_of_solves():
    r = pulled()
    names = ["displacement.1", "routing.2.y", "routing.3.x", "tension.3"]
    values = [0.005, 0.008, -0.008, 0.8]
    samples = [0.12]
    lin = tdcr.linearize(r, {n: [v] for n, v in zip(names, values)}, samples=samples, **OPTIONS)
    cot_tip = np.array([[0.7, -0.4, 0.9]])
    cot_points = np.array([[[0.2, 0.5, -0.3]]])
    g = lin.vjp(tip_position=cot_tip, points=cot_points)[0]

    def loss(parameters):
        s = tdcr.solve(r.with_parameters(parameters), **OPTIONS)
        return cot_tip[0] @ s.tip_position + cot_points[0, 0] @ s.at(samples[0]).p

    for j, (name, value) in enumerate(zip(names, values)):
        step = 1e-4 * max(abs(value), 0.008)
        base = dict(zip(names, values))
        up, down = dict(base), dict(base)
        up[name], down[name] = value + step, value - step
        difference = (loss(up) - loss(down)) / (2 * step)
        # 1e-6 of the largest gradient: central differences of full solves at a 1e-4
        # relative step (truncation ~1e-8, solve noise ~1e-7; tests/adjoint.rs)
        assert abs(g[j] - difference) <= 1e-6 * np.abs(g).max(), (name, g[j], difference)


def test_torch_gradcheck_on_tensions_loads_and_youngs_modulus():
    torch = pytest.importorskip("torch")
    import tdcr.torch as tt

    r = robot()
    samples = [0.1, 0.2]
    tension = torch.tensor([[1.5, 0.3, 0.8, 0.2, 0.1], [0.4, 1.1, 0.2, 0.3, 0.9]], dtype=torch.float64, requires_grad=True)
    loads = torch.tensor([[0.02, 0.05, -0.03], [0.0, -0.04, 0.01]], dtype=torch.float64, requires_grad=True)
    moment = torch.tensor([0.001, -0.002, 0.0005], dtype=torch.float64, requires_grad=True)
    # E in units of 1e10 Pa, so that gradcheck's step (1e-6) is a relative step.
    modulus = torch.tensor([6.0, 5.0], dtype=torch.float64, requires_grad=True)

    def shape(t, f, fe, m, e):
        out = tt.solve(r, tension=t, tip_force=f, distributed_force=fe, tip_moment=m, youngs_modulus=e * 1e10, samples=samples, **OPTIONS)
        return out.tip_position, out.tip_rotation, out.points

    # Tolerances: finite differences of full solves at a 1e-6 step (truncation 1e-12, solve
    # noise about 1e-13 m / 1e-6); outputs are 0.1 m, derivatives 1e-2 to 1 m/N.
    assert torch.autograd.gradcheck(shape, (tension, loads, loads, moment, modulus), eps=1e-6, atol=1e-6, rtol=1e-4)


def test_torch_module_and_batch_shapes():
    torch = pytest.importorskip("torch")
    import tdcr.torch as tt

    r = robot()
    model = tt.TipModel(r, inputs=("tension",), **OPTIONS)
    t = torch.full((2, 3, 5), 0.5, dtype=torch.float64, requires_grad=True)
    out = model(t)
    assert out.tip_position.shape == (2, 3, 3) and out.tip_rotation.shape == (2, 3, 3, 3)
    out.tip_position[..., 2].sum().backward()
    assert t.grad.shape == (2, 3, 5)
    single = tdcr.solve(r.with_tensions([0.5] * 5), **OPTIONS)
    np.testing.assert_array_equal(out.tip_position[1, 2].detach().numpy(), single.tip_position)
    with pytest.raises(ValueError, match="give"):
        tt.solve_tip(r, tension=torch.zeros(4, dtype=torch.float64))


def test_jax_check_grads_jit_and_vmap():
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    from jax.test_util import check_grads

    import tdcr.jax as tj

    r = robot()

    def f(t, fe, e):
        out = tj.solve(r, tension=t, distributed_force=fe, youngs_modulus=e * 1e10, samples=[0.15], **OPTIONS)
        return out.tip_position, out.tip_rotation, out.points

    t = jnp.array([1.5, 0.3, 0.8, 0.2, 0.1])
    fe = jnp.array([0.02, 0.05, -0.03])
    e = jnp.array(6.0)
    # Tolerances as the torch test (finite differences of full solves, step 1e-6).
    check_grads(f, (t, fe, e), order=1, modes=["rev"], eps=1e-6, atol=1e-6, rtol=1e-4)
    loss = lambda t: tj.solve_tip(r, tension=t, **OPTIONS)[2]
    g = jax.grad(loss)(t)
    np.testing.assert_array_equal(jax.jit(jax.grad(loss))(t), g)
    ts = jnp.stack([t, t * 0.5, t * 2.0])
    batched = jax.vmap(jax.grad(loss))(ts)
    np.testing.assert_allclose(batched[0], g, rtol=1e-12)
    np.testing.assert_allclose(batched[1], jax.grad(loss)(t * 0.5), rtol=1e-12)


def four_straight():
    """The prototype's four straight tendons alone (every routing straight, as
    `routing_offset` needs): the prototype's robot file without its last (helical) tendon."""
    text = tdcr.cases.prototype().to_toml()
    head, _, last = text.rpartition("[[tendon]]")
    # The tables after the last tendon's own ([tendon.routing] is part of it).
    after = re.search(r"\n\[(?!tendon\.)", last)
    robot = tdcr.Robot.from_toml(head + (last[after.start() :] if after else ""))
    assert robot.tendon_count == 4 and "helical" not in robot.to_toml()
    return robot


def test_torch_gradcheck_on_pull_ins_and_routing_offsets():
    torch = pytest.importorskip("torch")
    import tdcr.torch as tt

    r = four_straight()
    # Pull-ins in mm and offsets in cm, so that gradcheck's step (1e-6) is a relative step.
    # The two apart: a taut displacement-controlled tendon's offset has no derivative (its
    # pull-in holds its path length, which the offset moves), so the offsets are taken
    # under tensions.
    pull = torch.tensor([[5.0, 0.0, -3.0, 0.0], [4.0, -2.0, 0.0, 0.0]], dtype=torch.float64, requires_grad=True)
    offsets = torch.tensor(
        [[0.8, 0.0], [0.0, 0.8], [-0.8, 0.0], [0.0, -0.8]], dtype=torch.float64, requires_grad=True
    )
    tension = torch.tensor([1.5, 0.0, 0.7, 0.3], dtype=torch.float64)

    def pulled(q):
        out = tt.solve(r, displacement=q * 1e-3, samples=[0.1], **OPTIONS)
        return out.tip_position, out.points

    def routed(o):
        out = tt.solve(r, tension=tension, routing_offset=o * 1e-2, samples=[0.1], **OPTIONS)
        return out.tip_position, out.points

    # Tolerances as test_torch_gradcheck_on_tensions_loads_and_youngs_modulus.
    assert torch.autograd.gradcheck(pulled, (pull,), eps=1e-6, atol=1e-6, rtol=1e-4)
    assert torch.autograd.gradcheck(routed, (offsets,), eps=1e-6, atol=1e-6, rtol=1e-4)
    with pytest.raises(ValueError, match="not both"):
        tt.solve(r, tension=torch.zeros(4, dtype=torch.float64), displacement=pull[0])


def test_jax_check_grads_on_pull_ins_and_routing_offsets():
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    from jax.test_util import check_grads

    import tdcr.jax as tj

    r = four_straight()
    tension = jnp.array([1.5, 0.0, 0.7, 0.3])

    def pulled(q):
        return tj.solve(r, displacement=q * 1e-3, **OPTIONS).tip_position

    def routed(o):
        return tj.solve(r, tension=tension, routing_offset=o * 1e-2, **OPTIONS).tip_position

    q = jnp.array([5.0, 0.0, -3.0, 0.0])
    o = jnp.array([[0.8, 0.0], [0.0, 0.8], [-0.8, 0.0], [0.0, -0.8]])
    # Tolerances as the torch test (finite differences of full solves, step 1e-6); the
    # pull-ins and the offsets apart, as there.
    check_grads(pulled, (q,), order=1, modes=["rev"], eps=1e-6, atol=1e-6, rtol=1e-4)
    check_grads(routed, (o,), order=1, modes=["rev"], eps=1e-6, atol=1e-6, rtol=1e-4)
