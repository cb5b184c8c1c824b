"""Timings of the kernel prototypes beside uvsim's numpy path (issue 46, item 1).

    .venv-proto/bin/python benchmarks/kernel_prototypes/bench_kernels.py BACKEND [--repeat 5] [--json FILE]

BACKEND: uvsim (today's numpy path), numpy1 (the one source run by numpy), numba, jax, casadi (virtual machine), casadi-jit (C
generated and compiled by the system compiler).  One backend per process, so import and
compile times are its own.  Every figure is the best of ``--repeat`` rounds, wall clock and
the process's CPU time (``time.process_time``, all its threads: less sensitive to other
work on a shared machine, but it counts XLA's worker threads for JAX), with the load average before and after.

Figures (all one core, float64, thrust inputs, BlueROV2 Heavy, 50 Hz):

* ``single``: one trajectory of 3,000 RK4 steps (uvsim bench's ``single_rk4_steps_per_s`` size);
* ``batch64`` / ``batch1024``: 64 / 1,024 trajectories of 700 steps, each with its own inertia,
  added mass and damping (as uvsim bench's batched figure);
* ``lin``: one linearization of the timing dataset's joint stage: 18 windows of 200 steps,
  states and Jacobian for 34 parameters + 9 node components.  uvsim: the batched forward
  difference simulation it does today (44 parameter sets x 18 windows = 792 rows of 200
  steps; ``WindowedProblem.simulate`` inside ``linearize``); numba also as forward differences
  with the compiled kernel (``lin_fd``); the others exact (complex step, jvp, jtimes).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

T_IMPORT0 = time.perf_counter()
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import numpy as np  # noqa: E402

import common as c  # noqa: E402

DT = 0.02


def timed(fn, repeat):
    la0 = c.load_avg()
    wall, cpu = [], []
    for _ in range(repeat):
        t0, p0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - p0)
    return {"wall_best": min(wall), "cpu_best": min(cpu), "wall_all": wall, "load_before": la0, "load_after": c.load_avg()}


def first_call(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("backend", choices=["uvsim", "numpy1", "numba", "jax", "casadi", "casadi-jit"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--only", default="single,batch64,batch1024,lin")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    b = a.backend
    only = a.only.split(",")
    t0 = time.perf_counter()
    if b == "numba":
        import kernel_numba as mod
    elif b == "jax":
        import kernel_jax as mod
    elif b.startswith("casadi"):
        import kernel_casadi as mod
    else:
        import uvsim.simulate  # noqa: F401
        mod = None
    if b == "numpy1":  # the one source run by numpy, component-major (the would-be fallback)
        class mod:  # noqa: N801
            simulate = staticmethod(c.simulate_numpy)
    out = {"backend": b, "import_s": time.perf_counter() - t0, "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
           "load_start": c.load_avg(), "first_call_s": {}, "figures": {}}
    jit = b == "casadi-jit"
    m, th = c.load()

    def sim_fn(n, n_t, seed):
        t = np.arange(n_t) * DT
        hs = np.diff(t)
        F = c.thrust_inputs(n, n_t, DT, seed)
        y0 = c.initial_states(n, seed)
        if n == 1:
            mm, TH = m, th[None]
        else:
            mm = c.reference_model(c.batch_overrides(n, seed), n=n)
            TH = c.theta_rows(mm)
        if b == "uvsim":
            return lambda: c.reference(mm, t, F, y0)
        if b == "jax" and n == 1:
            return lambda: mod.simulate_one(y0[0], F[0], TH[0], hs)
        if b.startswith("casadi"):
            if n == 1:
                return lambda: mod.simulate(y0, F, TH, hs, jit=jit)
            return lambda: mod.simulate_mapped(y0, F, TH, hs, jit=jit)
        return lambda: mod.simulate(y0, F, TH, hs)

    for name, n, n_t in (("single", 1, 3001), ("batch64", 64, 701), ("batch1024", 1024, 701)):
        if name not in only:
            continue
        fn = sim_fn(n, n_t, 1)
        out["first_call_s"][name] = first_call(fn)
        r = timed(fn, a.repeat)
        r["steps_per_s_wall"] = n * (n_t - 1) / r["wall_best"]
        r["steps_per_s_cpu"] = n * (n_t - 1) / r["cpu_best"]
        out["figures"][name] = r
        print(name, f"{r['steps_per_s_wall']:.4g} steps/s (cpu {r['steps_per_s_cpu']:.4g}), load {r['load_before']}",
              flush=True)

    if "lin" in only:
        W, L = 18, 201
        t = np.arange(L) * DT * 0.5  # 100 Hz, 2-s windows as the timing dataset
        hs = np.diff(t)
        F = c.thrust_inputs(W, L, 0.01, 2, hold_s=0.5)
        y0 = c.initial_states(W, 2)
        dth = c.theta_seeds(m, th)
        dy0 = c.node_seeds(y0)
        p, q = dth.shape[0], dy0.shape[1]
        if b == "uvsim":
            # today's forward differences: 1 + p + q parameter sets x W windows, one batched call
            ov = {}
            base = m.params
            rows = 1 + p + q
            for j, name in enumerate(c.FREE):
                v = np.full(rows, float(np.asarray(base[name]).reshape(-1)[0]))
                v[1 + j] += 1e-5 * max(1.0, abs(v[0]))
                ov[name] = np.repeat(v, W)
            mm = c.reference_model(ov, n=rows * W)
            Y0 = np.tile(y0, (rows, 1))
            for k in range(q):
                Y0[(1 + p + k) * W:(2 + p + k) * W] += 1e-5 * dy0[:, k]
            FF = np.tile(F, (rows, 1, 1))

            def lin():
                c.reference(mm, t, FF, Y0)
            fns = {"lin": lin}
        elif b == "numpy1":
            fns = {}
        elif b == "numba":
            fns = {"lin": lambda: mod.linearize(y0, F, th, dth, dy0, hs),
                   "lin_fd": lambda: mod.linearize_fd(y0, F, th, dth, dy0, hs)}
        elif b.startswith("casadi"):
            fns = {"lin": lambda: mod.linearize(y0, F, th, dth, dy0, hs, jit=jit)}
        else:
            fns = {"lin": lambda: mod.linearize(y0, F, th, dth, dy0, hs)}
        for name, fn in fns.items():
            out["first_call_s"][name] = first_call(fn)
            r = timed(fn, a.repeat)
            out["figures"][name] = r
            print(name, f"{r['wall_best']:.4g} s (cpu {r['cpu_best']:.4g}), load {r['load_before']}", flush=True)
    out["load_end"] = c.load_avg()
    print(json.dumps({k: v for k, v in out.items() if k != "figures"}))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
