"""Checks of the kernel prototypes (not collected by pytest: testpaths = tests).

    .venv-proto/bin/python benchmarks/kernel_prototypes/check_kernels.py [numba jax casadi]

1. States: each backend against uvsim's own batched RK4 (``uvsim.simulate._rk4_loop`` on a
   Model built with the same overrides, thrust inputs), 4 trajectories x 30 s at 50 Hz, away
   from the default parameters so that gains and reverse ratios act: max |difference| <= 1e-10.
2. Jacobians (34 parameters + 9 node directions, 4 windows of 200 steps): each backend's
   exact derivative against the others' (<= 1e-10, relative to the largest entry), and
   against central differences of uvsim's simulation itself (overrides +- h; initial state
   +- h), which agree to the differences' own truncation error (<= 1e-5 relative per direction).
"""
from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as c  # noqa: E402

TOL_STATE = 1e-10
TOL_JAC_AD = 1e-10
TOL_JAC_FD = 1e-5


def main(backends):
    ok = True
    m, th = c.load(c.OVERRIDES)
    dt = 0.02
    n_t = 1501
    t = np.arange(n_t) * dt
    hs = np.diff(t)
    n = 4
    F = c.thrust_inputs(n, n_t, dt)
    y0 = c.initial_states(n)
    Yr = c.reference(c.reference_model(c.OVERRIDES, n=n), t, F, y0)
    Ynp = c.simulate_numpy(y0, F, th, hs)
    print(f"numpy (one source) vs uvsim: states max |diff| {np.abs(Ynp - Yr).max():.2e}")
    ok &= np.abs(Ynp - Yr).max() <= TOL_STATE
    mods = {}
    for b in backends:
        mods[b] = __import__(f"kernel_{b}")
        Y = mods[b].simulate(y0, F, th, hs)
        e = np.abs(Y - Yr).max()
        print(f"{b:7s} vs uvsim: states max |diff| {e:.2e} (30 s, 4 trajectories)")
        ok &= e <= TOL_STATE
        if b == "casadi":
            Y = mods[b].simulate(y0, F, th, hs, jit=True)
            e = np.abs(Y - Yr).max()
            print(f"casadi-jit vs uvsim: states max |diff| {e:.2e}")
            ok &= e <= TOL_STATE
    # Jacobians over a window of the joint stage's length
    L = 201
    dth = c.theta_seeds(m, th)
    dy0 = c.node_seeds(y0)
    J = {}
    for b, mod in mods.items():
        Yl, J[b] = mod.linearize(y0, F[:, :L], th, dth, dy0, hs[:L - 1])
        e = np.abs(Yl - Yr[:, :L]).max()
        print(f"{b:7s} linearization: primal vs uvsim {e:.2e}")
        ok &= e <= TOL_STATE
    names = list(J)
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            a, b = J[names[i]], J[names[j]]
            e = np.abs(a - b).max() / np.abs(a).max()
            print(f"Jacobian {names[i]} vs {names[j]}: max |diff| / max |J| = {e:.2e}")
            ok &= e <= TOL_JAC_AD
    # central differences of uvsim's own simulation
    Jfd = np.empty_like(J[names[0]])
    for jdir, name in enumerate(c.FREE):
        base = m.params[name] if name in m.params else 0.0
        h = 1e-6 * max(1.0, abs(float(np.asarray(base).reshape(-1)[0])))
        Ys = []
        for s in (1, -1):
            ov = dict(c.OVERRIDES)
            ov[name] = float(np.asarray(base).reshape(-1)[0]) + s * h
            Ys.append(c.reference(c.reference_model(ov, n=n), t[:L], F[:, :L], y0))
        Jfd[:, jdir] = (Ys[0] - Ys[1]) / (2 * h)
    mref = c.reference_model(c.OVERRIDES, n=n)
    for q in range(c.N_NODE):
        h = 1e-6
        Ys = []
        for s in (1, -1):
            yy = y0 + s * h * dy0[:, q]
            yy[:, 3:7] /= np.linalg.norm(yy[:, 3:7], axis=1, keepdims=True)
            Ys.append(c.reference(mref, t[:L], F[:, :L], yy))
        Jfd[:, len(c.FREE) + q] = (Ys[0] - Ys[1]) / (2 * h)
    for b in names:
        scale = np.abs(J[b]).max(axis=(0, 2, 3))
        e = (np.abs(J[b] - Jfd).max(axis=(0, 2, 3)) / scale)
        worst = int(np.argmax(e))
        label = (c.FREE + tuple(f"node_{i}" for i in range(c.N_NODE)))[worst]
        print(f"Jacobian {b:7s} vs central differences of uvsim: worst direction {label}: {e.max():.2e} (relative)")
        ok &= e.max() <= TOL_JAC_FD
    print("OK" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["numba", "jax", "casadi"]))
