"""CasADi prototype: :mod:`equations` evaluated once with SX symbols (the module's default
helpers accept SX: ``abs`` is ``fabs``, ``x < 0`` an SX comparison, ``x ** 0.5`` ``pow``),
giving a symbolic RK4 step; sensitivities by ``jtimes`` (forward mode, all directions at
once) of that step; the time loop ``mapaccum``; windows ``map``.  Evaluated by CasADi's
SX virtual machine, or (``jit=True``) compiled to C by the system compiler at run time.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

import equations as eq

_CACHE = {}


def _opts(jit: bool):
    if not jit:
        return {}
    return {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O2"], "verbose": False}}


def step_function(k: int, n_th: int):
    y = ca.SX.sym("y", 13)
    f = ca.SX.sym("f", k)
    th = ca.SX.sym("th", n_th)
    h = ca.SX.sym("h")
    yn = ca.vertcat(*eq.rk4_step([y[i] for i in range(13)], [f[i] for i in range(k)],
                                 [th[i] for i in range(n_th)], k, h))
    return y, f, th, h, yn


def trajectory(k: int, n_th: int, n_steps: int, jit: bool = False):
    """Function (y0 (13,), F (k, n_steps), th (n_th,), H (1, n_steps)) -> Y (13, n_steps)."""
    key = ("traj", k, n_th, n_steps, jit)
    if key not in _CACHE:
        y, f, th, h, yn = step_function(k, n_th)
        step = ca.Function("step", [y, f, th, h], [yn])
        acc = step.mapaccum("traj", n_steps)
        y0, Fs, th1, Hs = ca.MX.sym("y0", 13), ca.MX.sym("F", k, n_steps), ca.MX.sym("th", n_th), ca.MX.sym("H", 1, n_steps)
        _CACHE[key] = ca.Function("traj_c", [y0, Fs, th1, Hs], [acc(y0, Fs, ca.repmat(th1, 1, n_steps), Hs)], _opts(jit))
    return _CACHE[key]


def sens_trajectory(k: int, n_th: int, n_dir: int, n_steps: int, jit: bool = False):
    """Function (y0, S0 (13, d), F, th, dth (n_th, d), H) -> (Y, S (13, d * n_steps))."""
    key = ("sens", k, n_th, n_dir, n_steps, jit)
    if key not in _CACHE:
        y, f, th, h, yn = step_function(k, n_th)
        S = ca.SX.sym("S", 13, n_dir)
        dth = ca.SX.sym("dth", n_th, n_dir)
        Sn = ca.jtimes(yn, ca.vertcat(y, th), ca.vertcat(S, dth))
        step = ca.Function("sstep", [y, S, f, th, dth, h], [yn, Sn])
        acc = step.mapaccum("straj", n_steps, 2)
        y0, S0, Fs = ca.MX.sym("y0", 13), ca.MX.sym("S0", 13, n_dir), ca.MX.sym("F", k, n_steps)
        th1, dth1, Hs = ca.MX.sym("th", n_th), ca.MX.sym("dth", n_th, n_dir), ca.MX.sym("H", 1, n_steps)
        out = acc(y0, S0, Fs, ca.repmat(th1, 1, n_steps), ca.repmat(dth1, 1, n_steps), Hs)
        _CACHE[key] = ca.Function("straj_c", [y0, S0, Fs, th1, dth1, Hs], out, _opts(jit))
    return _CACHE[key]


def simulate(Y0, F, TH, hs, jit: bool = False):
    n, n_t, k = F.shape
    TH = np.broadcast_to(TH, (n, TH.shape[-1]))
    fn = trajectory(k, TH.shape[1], n_t - 1, jit)
    out = np.empty((n, n_t, 13))
    H = np.asarray(hs, float)[None, :]
    for j in range(n):
        Y = fn(Y0[j], F[j, :-1].T, TH[j], H)
        out[j, 0] = Y0[j]
        out[j, 1:] = np.asarray(Y).T
    return out


def simulate_mapped(Y0, F, TH, hs, jit: bool = False, parallel: str = "serial"):
    """All rows in one call (``Function.map`` over the rows)."""
    n, n_t, k = F.shape
    TH = np.broadcast_to(TH, (n, TH.shape[-1]))
    key = ("map", k, TH.shape[1], n_t - 1, n, jit, parallel)
    if key not in _CACHE:
        _CACHE[key] = trajectory(k, TH.shape[1], n_t - 1, jit).map(n, parallel)
    fn = _CACHE[key]
    H = np.asarray(hs, float)[None, :]
    Fa = np.transpose(F[:, :-1], (2, 0, 1)).reshape(k, n * (n_t - 1))  # (k, n * steps), row-major blocks
    Y = np.asarray(fn(Y0.T, Fa, TH.T, np.tile(H, (1, n))))  # (13, n * steps)
    out = np.empty((n, n_t, 13))
    out[:, 0] = Y0
    out[:, 1:] = Y.reshape(13, n, n_t - 1).transpose(1, 2, 0)
    return out


def linearize(Y0, F, th, dth, dy0, hs, jit: bool = False):
    """Y0 (W, 13), F (W, n_t, k), th (n_th,), dth (p, n_th), dy0 (W, q, 13).
    Returns (Y (W, n_t, 13), J (W, p + q, n_t, 13))."""
    W, n_t, k = F.shape
    p, q = dth.shape[0], dy0.shape[1]
    d = p + q
    N = n_t - 1
    fn = sens_trajectory(k, th.size, d, N, jit)
    dTH = np.concatenate([dth, np.zeros((q, th.size))], 0).T  # (n_th, d)
    H = np.asarray(hs, float)[None, :]
    Y = np.empty((W, n_t, 13))
    J = np.empty((W, d, n_t, 13))
    for w in range(W):
        S0 = np.concatenate([np.zeros((p, 13)), dy0[w]], 0).T  # (13, d)
        Yw, Sw = fn(Y0[w], S0, F[w, :-1].T, th, dTH, H)
        Y[w, 0] = Y0[w]
        Y[w, 1:] = np.asarray(Yw).T
        J[w, :, 0] = S0.T
        J[w, :, 1:] = np.asarray(Sw).reshape(13, N, d).transpose(2, 1, 0)
    return Y, J
