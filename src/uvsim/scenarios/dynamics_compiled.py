"""The truth model's right-hand side and RK4 (:mod:`uvsim.scenarios.dynamics`) compiled by numba.

The generator's time goes into :meth:`Plant.rhs <uvsim.scenarios.dynamics.Plant.rhs>`: ~60 numpy
operations on arrays of a few elements, 120-200 us a call however few trajectories it advances
(issue 46, docs/records/performance.md). Here the same equations, in the same order, are written
on scalars per trajectory for numba (the optional extra ``uvsim[fast]``), which the generator
uses where numba is installed (the sums of the wrenches and of the drag along the flow are the
only terms added in another order):

* :func:`rhs` is :meth:`Plant.rhs` without the extra wrenches, which stay Python callables: the
  caller sums them and passes the sum in ``tau_w``, added where :meth:`Plant.rhs` adds them;
* :func:`advance` is :func:`~uvsim.scenarios.dynamics.integrate`'s loop, for plants without
  extra wrenches.

The numpy form in :mod:`uvsim.scenarios.dynamics` stays the reference (and the path without
numba); ``tests/test_truth_compiled.py`` holds the two to 1e-12 on derivatives and 1e-10 on
trajectories. Like the numpy form, this module imports nothing of the fitting code (the truth is
written apart from it, issue 21) and not :mod:`uvsim.kernels` (the fitted model's kernel).

Parameters of a plant are packed per trajectory in the columns of ``th`` (``(K, n)``, rows at the
offsets below, matrices row-major); :func:`pack` builds it.
"""
from __future__ import annotations

import functools
import types

import numpy as np

# --- rows of the packed parameters ``th`` (K, n) --------------------------------------------
O_MASS = 0      # m, kg
O_RG = 1        # r_g (3), m
O_IO = 4        # I_o (3x3), kg m^2
O_MA = 13       # M_A (6x6)
O_DL = 49       # linear damping (6), paper sign
O_DQ = 55       # quadratic damping (6)
O_LOAD = 61     # sum of the vertical point loads, N (+ down)
O_LM = 62       # their moment sum F_i r_i (3), N m
O_MINV = 65     # (M_RB + M_A)^-1 (6x6)
O_DF = 101      # quadratic drag along the relative velocity (3), paper sign
O_ACT = 104     # per actuator: 1/T (a), lagged 1.0/0.0 (a), allocation (6 x a)


def pack(plant) -> np.ndarray:
    """The packed parameters ``(K, n)`` of a :class:`~uvsim.scenarios.dynamics.Plant`."""
    n, a = plant.n, plant.n_actuators
    M_inv = plant.M_inv if plant.M_inv.ndim == 3 else np.repeat(plant.M_inv[:, :, None], n, axis=2)
    rows = [plant.mass[None], plant.r_g, plant.inertia.reshape(9, n), plant.added_mass.reshape(36, n),
            plant.linear, plant.quadratic, plant.load[None], plant.load_moment, M_inv.reshape(36, n),
            plant.along_flow, plant.rate, plant.lagged.astype(float), plant.allocation.reshape(6 * a, n)]
    th = np.ascontiguousarray(np.concatenate([np.asarray(r, dtype=float).reshape(-1, n) for r in rows]))
    assert th.shape[0] == O_ACT + 8 * a
    return th


def _rotation(q0, q1, q2, q3):
    """``R(q)``, body->NED, of a unit quaternion (Fossen 2021 eq. 2.72): the 9 entries row by row."""
    return (1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2),
            2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1),
            2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2))


def rhs(y, f_e, th, current, has_current, has_cg, tau_w, out):
    """:meth:`Plant.rhs <uvsim.scenarios.dynamics.Plant.rhs>` into ``out`` (n_y, n): states ``y``
    (n_y, n), held commands ``f_e`` (a, n), packed parameters ``th`` (K, n), NED current (3, n),
    the flags of the plant, the extra wrenches' sum ``tau_w`` (6, n)."""
    n = y.shape[1]
    a = f_e.shape[0]
    nu_r = np.empty(6)
    am = np.empty(6)
    tau = np.empty(6)
    for j in range(n):
        q0, q1, q2, q3 = y[3, j], y[4, j], y[5, j], y[6, j]
        u, v, w = y[7, j], y[8, j], y[9, j]
        p, q, r = y[10, j], y[11, j], y[12, j]
        R00, R01, R02, R10, R11, R12, R20, R21, R22 = _rotation(q0, q1, q2, q3)
        cx = cy = cz = 0.0
        if has_current:
            cN, cE, cD = current[0, j], current[1, j], current[2, j]
            cx = R00 * cN + R10 * cE + R20 * cD      # R^T v_c
            cy = R01 * cN + R11 * cE + R21 * cD
            cz = R02 * cN + R12 * cE + R22 * cD
            nu_r[0], nu_r[1], nu_r[2] = u - cx, v - cy, w - cz
        else:
            nu_r[0], nu_r[1], nu_r[2] = u, v, w
        nu_r[3], nu_r[4], nu_r[5] = p, q, r
        for i in range(6):                           # [a1; a2] = M_A nu_r
            s = 0.0
            for k in range(6):
                s += th[O_MA + 6 * i + k, j] * nu_r[k]
            am[i] = s
        Iw0 = th[O_IO + 0, j] * p + th[O_IO + 1, j] * q + th[O_IO + 2, j] * r
        Iw1 = th[O_IO + 3, j] * p + th[O_IO + 4, j] * q + th[O_IO + 5, j] * r
        Iw2 = th[O_IO + 6, j] * p + th[O_IO + 7, j] * q + th[O_IO + 8, j] * r
        # omega x (v, a1, a2, I_o omega, eps)
        wxv0, wxv1, wxv2 = q * w - r * v, r * u - p * w, p * v - q * u
        wxa10, wxa11, wxa12 = q * am[2] - r * am[1], r * am[0] - p * am[2], p * am[1] - q * am[0]
        wxa20, wxa21, wxa22 = q * am[5] - r * am[4], r * am[3] - p * am[5], p * am[4] - q * am[3]
        wxI0, wxI1, wxI2 = q * Iw2 - r * Iw1, r * Iw0 - p * Iw2, p * Iw1 - q * Iw0
        wxe0, wxe1, wxe2 = q * q3 - r * q2, r * q1 - p * q3, p * q2 - q * q1
        k0, k1, k2 = R20, R21, R22                   # R^T e_3
        vr0, vr1, vr2 = nu_r[0], nu_r[1], nu_r[2]
        vxa0 = vr1 * am[2] - vr2 * am[1]
        vxa1 = vr2 * am[0] - vr0 * am[2]
        vxa2 = vr0 * am[1] - vr1 * am[0]
        m0, m1, m2 = th[O_LM, j], th[O_LM + 1, j], th[O_LM + 2, j]
        mxk0, mxk1, mxk2 = m1 * k2 - m2 * k1, m2 * k0 - m0 * k2, m0 * k1 - m1 * k0
        for i in range(6):
            tau[i] = th[O_DL + i, j] * nu_r[i] + th[O_DQ + i, j] * abs(nu_r[i]) * nu_r[i]
        speed = np.sqrt(nu_r[0] * nu_r[0] + nu_r[1] * nu_r[1] + nu_r[2] * nu_r[2])
        for i in range(3):
            tau[i] += th[O_DF + i, j] * speed * nu_r[i]
        mass, load = th[O_MASS, j], th[O_LOAD, j]
        tau[0] += load * k0 - mass * wxv0 - wxa10
        tau[1] += load * k1 - mass * wxv1 - wxa11
        tau[2] += load * k2 - mass * wxv2 - wxa12
        tau[3] += mxk0 - wxI0 - vxa0 - wxa20
        tau[4] += mxk1 - wxI1 - vxa1 - wxa21
        tau[5] += mxk2 - wxI2 - vxa2 - wxa22
        if has_cg:
            g0, g1, g2 = th[O_RG, j], th[O_RG + 1, j], th[O_RG + 2, j]
            wg0, wg1, wg2 = q * g2 - r * g1, r * g0 - p * g2, p * g1 - q * g0
            tau[0] -= mass * (q * wg2 - r * wg1)
            tau[1] -= mass * (r * wg0 - p * wg2)
            tau[2] -= mass * (p * wg1 - q * wg0)
            tau[3] -= mass * (g1 * wxv2 - g2 * wxv1)
            tau[4] -= mass * (g2 * wxv0 - g0 * wxv2)
            tau[5] -= mass * (g0 * wxv1 - g1 * wxv0)
        o_rate, o_lag, o_alloc = O_ACT, O_ACT + a, O_ACT + 2 * a
        for i in range(6):
            s = 0.0
            for k in range(a):
                d = y[13 + k, j] if th[o_lag + k, j] > 0.0 else f_e[k, j]
                s += th[o_alloc + a * i + k, j] * d
            tau[i] += s + tau_w[i, j]
        if has_current:
            # + M_A nu_c_dot, nu_c_dot = [-omega x R^T v_c; 0]
            wc0, wc1, wc2 = q * cz - r * cy, r * cx - p * cz, p * cy - q * cx
            for i in range(6):
                tau[i] -= th[O_MA + 6 * i, j] * wc0 + th[O_MA + 6 * i + 1, j] * wc1 + th[O_MA + 6 * i + 2, j] * wc2
        out[0, j] = R00 * u + R01 * v + R02 * w
        out[1, j] = R10 * u + R11 * v + R12 * w
        out[2, j] = R20 * u + R21 * v + R22 * w
        out[3, j] = -0.5 * (q1 * p + q2 * q + q3 * r)
        out[4, j] = 0.5 * (q0 * p - wxe0)
        out[5, j] = 0.5 * (q0 * q - wxe1)
        out[6, j] = 0.5 * (q0 * r - wxe2)
        for i in range(6):
            s = 0.0
            for k in range(6):
                s += th[O_MINV + 6 * i + k, j] * tau[k]
            out[7 + i, j] = s
        for k in range(a):
            out[13 + k, j] = th[o_rate + k, j] * (f_e[k, j] - y[13 + k, j])


def frame(y, current, has_current, R, nu_r):
    """What an extra wrench sees (:class:`~uvsim.scenarios.dynamics.Context`), into ``R``
    (3, 3, n, body->NED, Fossen 2021 eq. 2.72) and ``nu_r`` (6, n, body velocity relative to the
    water) of states ``y`` (n_y, n) in a NED current (3, n)."""
    for j in range(y.shape[1]):
        r = _rotation(y[3, j], y[4, j], y[5, j], y[6, j])
        for i in range(9):
            R[i // 3, i % 3, j] = r[i]
        for i in range(3):
            c = R[0, i, j] * current[0, j] + R[1, i, j] * current[1, j] + R[2, i, j] * current[2, j] \
                if has_current else 0.0
            nu_r[i, j] = y[7 + i, j] - c
            nu_r[3 + i, j] = y[10 + i, j]


def advance(t, commands, y0, th, current, has_current, has_cg, max_step, renormalize, Y, A):
    """:func:`~uvsim.scenarios.dynamics.integrate`'s loop into ``Y`` (n_t, n_y, n) and ``A``
    (n_t, 6, n) for a plant without extra wrenches; returns the index of the first sample whose
    state is not finite (-1: none).

    Written in loops with one call of :func:`rhs`: with array expressions and four calls it took
    12.3 s to compile on a 2-core EPYC, 2.9 s so (docs/records/performance.md)."""
    n_y, n = y0.shape
    tau_w = np.zeros((6, n))
    y = y0.copy()
    yt = np.empty((n_y, n))
    K = np.empty((4, n_y, n))
    n_t = t.shape[0]
    for k in range(n_t):
        for i in range(n_y):
            for j in range(n):
                Y[k, i, j] = y[i, j]
        last = k == n_t - 1
        m, h = 1, 0.0
        if not last:
            dt = t[k + 1] - t[k]
            m = max(1, int(np.ceil(dt / max_step - 1e-9)))
            h = dt / m
        for s in range(m):
            for st in range(4):
                c = 0.0 if st == 0 else (0.5 * h if st < 3 else h)
                for i in range(n_y):
                    for j in range(n):
                        yt[i, j] = y[i, j] if st == 0 else y[i, j] + c * K[st - 1, i, j]
                rhs(yt, commands[k], th, current, has_current, has_cg, tau_w, K[st])
                if st == 0 and s == 0:
                    for i in range(6):
                        for j in range(n):
                            A[k, i, j] = K[0, 7 + i, j]
                if last:
                    break
            if last:
                break
            for i in range(n_y):
                for j in range(n):
                    y[i, j] = y[i, j] + (h / 6.0) * (K[0, i, j] + 2.0 * (K[1, i, j] + K[2, i, j]) + K[3, i, j])
            if renormalize:
                for j in range(n):
                    nq = np.sqrt(y[3, j] ** 2 + y[4, j] ** 2 + y[5, j] ** 2 + y[6, j] ** 2)
                    for i in range(3, 7):
                        y[i, j] /= nq
        if not last:
            for i in range(n_y):
                for j in range(n):
                    if not np.isfinite(y[i, j]):
                        return k + 1
    return -1


@functools.lru_cache(maxsize=None)
def compiled():
    """``(rhs, advance, frame)`` compiled by numba (on first use; numba caches the machine code beside
    this module), or None where numba is not installed (the numpy form runs)."""
    try:
        import numba
    except ImportError:
        return None
    g = dict(globals())        # each function rebuilt over globals whose callees are the compiled ones

    def jit(f):
        g[f.__name__] = numba.njit(types.FunctionType(f.__code__, g, f.__name__), cache=True, error_model="numpy")
        return g[f.__name__]

    jit(_rotation)
    fast_rhs = jit(rhs)
    return fast_rhs, jit(advance), jit(frame)
