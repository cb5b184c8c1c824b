"""Shared set-up of the kernel prototypes: the vehicle and its parameter vector from uvsim's
own :class:`uvsim.model.Model`, the parameter directions of the joint stage, inputs, and
uvsim's simulation as the reference.

Problem sizes (measured on the timing dataset's joint stage, docs/records/performance_kernel.md):
a linearization simulates 18 windows of 200 RK4 steps (2 s at 100 Hz) for 1 + 34 + 9 = 44
parameter sets: the base point, 34 free parameters (``z_b``, 6 added masses, 8 thruster gains,
8 reverse ratios, 5 linear and 6 quadratic damping coefficients) and 9 free node components.
"""
from __future__ import annotations

import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)

import equations as eq  # noqa: E402

VEHICLE = "bluerov2_heavy"
ADDED = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")
LINEAR = ("X_u", "Z_w", "K_p", "M_q", "N_r")  # the joint stage's free linear terms (Y_v is not free)
QUAD = ("X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")
ALL_LINEAR = ("X_u", "Y_v", "Z_w", "K_p", "M_q", "N_r")
K = 8
#: the joint stage's 34 free parameters (report.json free_parameters of the timing dataset)
FREE = (("z_b",) + ADDED + sum(((f"thruster_gain_{i}", f"thruster_reverse_{i}") for i in range(1, K + 1)), ())
        + LINEAR + QUAD)
#: the joint stage's 9 free node components, as state directions: attitude (3, tangent) and nu (6)
N_NODE = 9
#: a parameter point away from the defaults (so gains and reverse ratios act), for the checks
OVERRIDES = {"thruster_gain_2": 0.9, "thruster_reverse_5": 0.8, "thruster_gain_7": 1.05, "X_udot": 6.0,
             "N_rdot": 0.12, "z_b": -0.03, "X_u": -4.0, "N_rr": -1.2}


def load(overrides=None):
    """(uvsim Model with thrust inputs, parameter vector th (n_th,))."""
    import uvsim
    from uvsim.model import Model

    veh = uvsim.load_vehicle(VEHICLE)
    m = Model(veh, dict(overrides or {}), input_kind="thrust")
    return m, theta_of(m)


def theta_of(m, j: int = 0) -> np.ndarray:
    """The parameter vector of :mod:`equations` from a built uvsim Model (its parameter set ``j``)."""
    o = eq.layout(K)
    th = np.zeros(o["size"])

    def first(a):
        a = np.asarray(a, float).reshape(-1)
        return a[j] if a.size > 1 else a[0]

    def row(a, size):
        a = np.asarray(a, float).reshape(-1, size)
        return a[j] if a.shape[0] > 1 else a[0]

    th[o["Minv"]:o["Minv"] + 36] = row(m.Minv, 36)
    th[o["M"]:o["M"] + 36] = row(m.M, 36)
    p = m.params
    th[o["DL"]:o["DL"] + 6] = [first(p[k]) for k in ALL_LINEAR]
    th[o["DQ"]:o["DQ"] + 6] = [first(p[k]) for k in QUAD]
    W = first(m.weight)
    B = first(p["B"])
    th[o["WmB"]] = W - B
    r_g = row(m.weight_r_g, 3)
    r_b = np.array([first(p[k]) for k in ("x_b", "y_b", "z_b")])
    th[o["h"]:o["h"] + 3] = W * r_g - B * r_b
    act = [t for t in m.terms if t.kind == "actuators"][0]
    th[o["B"]:o["B"] + 6 * K] = np.asarray(act.matrix).reshape(-1)
    th[o["gain"]:o["gain"] + K] = [first(p[f"thruster_gain_{i}"]) for i in range(1, K + 1)]
    th[o["rev"]:o["rev"] + K] = [first(p[f"thruster_reverse_{i}"]) for i in range(1, K + 1)]
    return th


def theta_rows(m) -> np.ndarray:
    """(n, n_th): every parameter set of a batched Model."""
    return np.stack([theta_of(m, j) for j in range(m.n)])


def batch_overrides(n: int, seed: int = 0) -> dict:
    """One parameter set per trajectory, +-20 % around the vehicle's (as uvsim's core benchmark)."""
    import uvsim

    p = uvsim.load_vehicle(VEHICLE).parameters()
    rng = np.random.default_rng(seed)
    return {k: p[k] * rng.uniform(0.8, 1.2, n) for k in ("I_xx", "I_yy", "I_zz") + ADDED + ALL_LINEAR + QUAD}


def theta_seeds(m, th) -> np.ndarray:
    """d th / d p for the 34 free parameters, (34, n_th): the derivative of what Model
    prepares (M, M^-1, h, ...) with respect to each named parameter."""
    o = eq.layout(K)
    Minv = th[o["Minv"]:o["Minv"] + 36].reshape(6, 6)
    B = np.asarray(m.params["B"], float).reshape(-1)[0]
    S = np.zeros((len(FREE), th.size))
    for j, name in enumerate(FREE):
        if name in ADDED:
            i = ADDED.index(name)
            dM = np.zeros((6, 6))
            dM[i, i] = 1.0
            S[j, o["M"]:o["M"] + 36] = dM.reshape(-1)
            S[j, o["Minv"]:o["Minv"] + 36] = (-Minv @ dM @ Minv).reshape(-1)
        elif name == "z_b":
            S[j, o["h"] + 2] = -B
        elif name in ALL_LINEAR:
            S[j, o["DL"] + ALL_LINEAR.index(name)] = 1.0
        elif name in QUAD:
            S[j, o["DQ"] + QUAD.index(name)] = 1.0
        elif name.startswith("thruster_gain_"):
            S[j, o["gain"] + int(name.rsplit("_", 1)[1]) - 1] = 1.0
        elif name.startswith("thruster_reverse_"):
            S[j, o["rev"] + int(name.rsplit("_", 1)[1]) - 1] = 1.0
    return S


def node_seeds(y0) -> np.ndarray:
    """d y0 for the 9 node directions (n, 9, 13): attitude tangent (q (x) [0, e_i / 2]) and nu."""
    y0 = np.atleast_2d(y0)
    n = y0.shape[0]
    out = np.zeros((n, N_NODE, 13))
    from uvsim.kinematics import quat_multiply

    for i in range(3):
        e = np.zeros(4)
        e[1 + i] = 0.5
        out[:, i, 3:7] = quat_multiply(y0[:, 3:7], e)
    for i in range(6):
        out[:, 3 + i, 7 + i] = 1.0
    return out


def thrust_inputs(n: int, n_t: int, dt: float, seed: int = 0, hold_s: float = 1.0, amp: float = 15.0):
    """Telegraph thrusts (n, n_t, 8), N: each thruster holds a random level in [-amp, amp] for
    ``hold_s`` seconds (every DOF excited, both thrust signs, so the reverse ratios act)."""
    rng = np.random.default_rng(seed)
    m = int(np.ceil(n_t * dt / hold_s)) + 1
    lev = rng.uniform(-amp, amp, (n, m, K))
    idx = (np.arange(n_t) * dt / hold_s).astype(int)
    return np.ascontiguousarray(lev[:, idx, :])


def initial_states(n: int, seed: int = 1) -> np.ndarray:
    """(n, 13) initial states: some attitude and velocity (as windows start mid-run)."""
    from uvsim.kinematics import euler_to_quat

    rng = np.random.default_rng(seed)
    y0 = np.zeros((n, 13))
    y0[:, 0:3] = rng.normal(0, 1, (n, 3))
    y0[:, 3:7] = euler_to_quat(rng.uniform(-0.3, 0.3, (n, 3)))
    y0[:, 7:10] = rng.normal(0, 0.2, (n, 3))
    y0[:, 10:13] = rng.normal(0, 0.2, (n, 3))
    return y0


def reference(m, t, F, y0) -> np.ndarray:
    """uvsim's own batched RK4 (the numpy path the kernel is checked against): (n, n_t, 13)."""
    from uvsim.simulate import _rk4_loop

    n = F.shape[0]
    return _rk4_loop(m, np.broadcast_to(t, (n, t.size)), F, np.asarray(y0, float), 1, "raise")


def reference_model(overrides, n=1):
    import uvsim
    from uvsim.model import Model

    return Model(uvsim.load_vehicle(VEHICLE), dict(overrides or {}), n=n, input_kind="thrust")


def simulate_numpy(y0, F, th, hs):
    """The one source run by numpy, batched: y0 (n, 13), F (n, n_t, k), th (n_th,) or (n, n_th),
    hs (n_t - 1,) step lengths.  Returns (n, n_t, 13)."""
    n, n_t, k = F.shape
    Y = np.empty((n, n_t, 13))
    Y[:, 0] = y0
    y = tuple(np.ascontiguousarray(y0.T))
    thc = th if th.ndim == 1 else np.ascontiguousarray(th.T)
    Fc = np.ascontiguousarray(np.transpose(F, (1, 2, 0)))  # (n_t, k, n)
    for i in range(n_t - 1):
        y = eq.rk4_step(y, Fc[i], thc, k, hs[i])
        Y[:, i + 1] = np.stack(y, -1)
    return Y


def load_avg() -> str:
    with open("/proc/loadavg") as fh:
        return " ".join(fh.read().split()[:3])


def best_of(fn, repeat: int = 5, number: int = 1):
    """(best seconds per call over ``repeat`` rounds of ``number`` calls, all rounds, load before, load after)."""
    la0 = load_avg()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return min(times), times, la0, load_avg()


def du_mb(paths) -> float:
    out = subprocess.run(["du", "-sk", *paths], capture_output=True, text=True).stdout
    return sum(int(line.split()[0]) for line in out.splitlines()) / 1024.0
