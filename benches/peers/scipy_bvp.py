"""Cases S and H (docs/model.md) solved by scipy's `solve_bvp` (a collocation solver of
order 4 with residual control), for the side-by-side table of docs/benchmarks.md.

The model is the one tdcr solves: Rucker and Webster's tendon-coupled Cosserat rod with
state y = (p, R column-major, v, u), the base pose fixed, the tip wrench balance with the
tendon forces and the tip force; the same equations as benches/peers/till_driver.cpp.
Cold: a straight rod along the base's z axis on 9 nodes. Warm: the solution at 0.99 times
the tension (its mesh and values). Times are thread CPU time (time.thread_time), medians.

Usage: python scipy_bvp.py TOL REPEATS [CASES]  (CASES: S, H or SH; default S)
-> one line per case and start: case start tol median_cpu_ms nodes tip_error_m, or
case start tol failed MESSAGE (H from the straight rod: solve_bvp stops on a singular
collocation Jacobian).
"""

import sys
import time

import numpy as np
from scipy.integrate import solve_bvp

L, RADIUS, E, NU = 0.242, 0.0004, 210e9, 0.3125
G = E / (2 * (1 + NU))
AREA = np.pi * RADIUS**2
I = np.pi * RADIUS**4 / 4
KSE = np.array([G * AREA, G * AREA, E * AREA])
KBT = np.array([E * I, E * I, G * 2 * I])
F_E = np.array([0.0, 0.0, -0.47])  # self weight (N/m), world
OFFSET = 0.008
R0 = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
E3 = np.array([0.0, 0.0, 1.0])


def hat(w):
    """Batched skew matrices of vectors w (3, m) -> (m, 3, 3)."""
    z = np.zeros(w.shape[1])
    return np.stack(
        [np.stack([z, -w[2], w[1]]), np.stack([w[2], z, -w[0]]), np.stack([-w[1], w[0], z])]
    ).transpose(2, 0, 1)


class Case:
    def __init__(self, helical, tension, tip_force, reference):
        self.helical = helical
        self.tension = tension
        self.tip_force = np.asarray(tip_force, float)
        self.reference = np.asarray(reference, float)

    def routing(self, s):
        """r, r', r'' in the body frame, shapes (3, m)."""
        s = np.atleast_1d(s)
        if not self.helical:
            r = np.tile([[OFFSET], [0.0], [0.0]], s.size)
            return r, np.zeros_like(r), np.zeros_like(r)
        w = 2 * np.pi / L
        c, sn, z = np.cos(w * s), np.sin(w * s), np.zeros(s.size)
        r = OFFSET * np.stack([c, sn, z])
        return r, OFFSET * w * np.stack([-sn, c, z]), -w * w * r

    def ode(self, s, y):
        m = y.shape[1]
        R = y[3:12].T.reshape(m, 3, 3).transpose(0, 2, 1)  # column-major storage
        v, u = y[12:15], y[15:18]
        r, r_s, r_ss = self.routing(s)
        pb_s = np.cross(u, r, axis=0) + r_s + v
        norm = np.linalg.norm(pb_s, axis=0)
        P = hat(pb_s)
        A = -(P @ P) * (self.tension / norm**3)[:, None, None]
        Rh = hat(r)
        Gm = -A @ Rh
        a = np.einsum("mij,jm->im", A, np.cross(u, pb_s, axis=0) + np.cross(u, r_s, axis=0) + r_ss)
        b = np.cross(r, a, axis=0)
        H = Rh @ Gm
        K = np.zeros((m, 6, 6))
        K[:, :3, :3] = np.diag(KSE) + A
        K[:, :3, 3:] = Gm
        K[:, 3:, :3] = Gm.transpose(0, 2, 1)
        K[:, 3:, 3:] = np.diag(KBT) + H
        nb = KSE[:, None] * (v - E3[:, None])
        mb = KBT[:, None] * u
        rhs = np.concatenate(
            [
                -np.cross(u, nb, axis=0) - np.einsum("mji,j->im", R, F_E) - a,
                -np.cross(u, mb, axis=0) - np.cross(v, nb, axis=0) - b,
            ]
        )
        vu_s = np.linalg.solve(K, rhs.T[:, :, None])[:, :, 0].T
        p_s = np.einsum("mij,jm->im", R, v)
        R_s = R @ hat(u)
        return np.concatenate([p_s, R_s.transpose(0, 2, 1).reshape(m, 9).T, vu_s])

    def bc(self, ya, yb):
        R_l = yb[3:12].reshape(3, 3).T
        v, u = yb[12:15], yb[15:18]
        r, r_s, _ = self.routing(L)
        pb_s = np.cross(u, r[:, 0]) + r_s[:, 0] + v
        fb = -self.tension * pb_s / np.linalg.norm(pb_s)
        force = -KSE * (v - E3) + fb + R_l.T @ self.tip_force
        moment = -KBT * u + np.cross(r[:, 0], fb)
        return np.concatenate([ya[:3], ya[3:12] - R0.T.reshape(9), force, moment])

    def solve(self, x, y, tol):
        sol = solve_bvp(self.ode, self.bc, x, y, tol=tol, max_nodes=100000)
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol


def straight(nodes):
    x = np.linspace(0, L, nodes)
    y = np.zeros((18, nodes))
    y[:3] = R0 @ np.vstack([np.zeros(nodes), np.zeros(nodes), x])
    y[3:12] = R0.T.reshape(9)[:, None]
    y[12:15] = E3[:, None]
    return x, y


def main():
    tol = float(sys.argv[1])
    repeats = int(sys.argv[2])
    cases = {
        "S": Case(False, 2.94, [0, 0, 0], [0.151823122, 0.0, -0.159529649]),
        "H": Case(True, 4.91, [0, 0, -0.196], [0.155616146, 0.0596521926, -0.158035195]),
    }
    chosen = sys.argv[3] if len(sys.argv) > 3 else "S"
    for name, case in cases.items():
        if name not in chosen:
            continue
        for start in ["cold", "warm"]:
            try:
                line = run(case, start, tol, repeats)
            except RuntimeError as e:
                line = f"{start} {tol:g} failed {e}"
            print(f"{name} {line}", flush=True)


def run(case, start, tol, repeats):
    """Median thread CPU time of `repeats` solves (after one untimed) and the last answer."""
    times = []
    full = case.tension
    for k in range(repeats + 1):
        x, y = straight(9)
        if start == "warm":
            case.tension = 0.99 * full
            previous = case.solve(x, y, tol)
            case.tension = full
            x, y = previous.x, previous.y
        t0 = time.thread_time()
        sol = case.solve(x, y, tol)
        t1 = time.thread_time()
        if k > 0:
            times.append(t1 - t0)
    error = np.linalg.norm(sol.sol(L)[:3] - case.reference)
    return f"{start} {tol:g} {1e3 * np.median(times):.4f} {sol.x.size} {error:.3e}"


if __name__ == "__main__":
    main()
