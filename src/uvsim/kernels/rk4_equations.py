"""The rigid-body RK4 of :mod:`uvsim.model` written for a compiler (issue 46, item 3).

Plain Python on scalars and small arrays, so that numba compiles these functions as they are
(:mod:`uvsim.kernels.numba_rk4`), and so that they also run uncompiled (slowly) where numba is
not installed, which is how the tests check the packing of parameters without it.

What the functions cover is what :func:`uvsim.kernels.plan.compiled_plan` accepts: a model with
no term states, no mass changes and no time-varying current, whose forces are

* restoring, ``tau_g = k G`` with ``k = R^T e_3`` (:mod:`uvsim.forces.restoring`, Fossen 2021
  eq. 4.6 written linear in ``k``);
* diagonal and coupled damping on ``nu_r`` (:mod:`uvsim.forces.damping`, seed 000 eq. 7-9,
  paper sign);
* actuators, whose force is held over each sample interval with the input (it depends on the
  input, the voltage and parameters only): computed by :class:`uvsim.forces.actuators.Actuators`
  itself, in numpy, and passed in as ``tau_act``;
* a constant NED current (seed 000 eq. 1-2; the split Coriolis form of :meth:`Model.rhs`);
* one tether (:mod:`uvsim.effects.tether`: pull towards the anchor beyond the slack length,
  cross-flow and lumped drag at the attachment point, 3-D or horizontal).

Which optional parts a model has is the bit mask ``parts`` (:data:`CURRENT`, :data:`COUPLED`,
:data:`TETHER`).

The equations are :meth:`uvsim.model.Model.rhs`'s, in the same order and the same homogeneous
form of the rotation (:func:`uvsim.bilinear.rot_qrate`), and :func:`advance` is
:func:`uvsim.simulate._rk4_steps`'s loop: ``tests/test_kernels.py`` holds the two to 1e-10 on
states and accelerations for random parameter sets, inputs and currents.  Symbols as in
Fossen 2021: ``nu = [u, v, w, p, q, r]``, ``M = M_RB + M_A``, ``C(nu) nu = [w x a; v x a + w x b]``
with ``[a; b] = M nu`` (eq. 3.46).
"""
from __future__ import annotations

import math

import numpy as np

# --- layout of one parameter row ``th`` ------------------------------------------------------
O_MINV = 0     # (M_RB + M_A)^-1, row-major 6x6
O_M = 36       # M = M_RB + M_A
O_MRB = 72     # M_RB (with the terms' fixed masses)
O_MA = 108     # M_A
O_G = 144      # restoring: tau_g[j] = sum_i k_i G[i, j], G (3, 6) row-major
O_DL = 162     # diagonal damping, linear (6), paper sign
O_DQ = 168     # diagonal damping, quadratic (6)
O_CL = 174     # coupled damping, linear 6x6 row-major
O_CQ = 210     # coupled damping, quadratic 6x6
O_VC = 246     # constant current, NED (3), m/s
O_TE = 249     # tether: attachment r_a (3, body, m), anchor p_0 (3, NED, m), horizontal (1 or 0),
#                tension T_0 (N), stiffness k (N/m), slack length L_s (m), cross-flow drag
#                1/2 rho C_d D l / 3 (kg/m), lumped drag c_l (N s^2/m^2)
N_TH = 261

#: The functions numba compiles (:mod:`uvsim.kernels.numba_rk4`), callees first.
KERNEL_FUNCTIONS = ("_tether_add", "_coriolis_sub", "rhs", "advance", "accelerations")

# bits of ``parts``
CURRENT = 1
COUPLED = 2
TETHER = 4


def rhs(y, tau_act, th, parts, out, tau):
    """State derivative of one trajectory into ``out`` (13,): state ``y`` (13,), the held
    actuator force ``tau_act`` (6,), parameters ``th`` (N_TH,); ``tau`` (6,) is scratch."""
    has_current = (parts & CURRENT) != 0
    has_coupled = (parts & COUPLED) != 0
    qw = y[3]
    qx = y[4]
    qy = y[5]
    qz = y[6]
    # rotation body -> NED, the homogeneous form of uvsim.bilinear.rot_qrate
    ww = qw * qw
    xx = qx * qx
    yy = qy * qy
    zz = qz * qz
    xy = qx * qy
    xz = qx * qz
    yz = qy * qz
    wx = qw * qx
    wy = qw * qy
    wz = qw * qz
    R00 = ww + xx - yy - zz
    R01 = 2 * (xy - wz)
    R02 = 2 * (xz + wy)
    R10 = 2 * (xy + wz)
    R11 = ww - xx + yy - zz
    R12 = 2 * (yz - wx)
    R20 = 2 * (xz - wy)
    R21 = 2 * (yz + wx)
    R22 = ww - xx - yy + zz
    u = y[7]
    v = y[8]
    w = y[9]
    p = y[10]
    q = y[11]
    r = y[12]
    # current seen from the body: nu_r = nu - [R^T v_c; 0], nu_c_dot = [-omega x R^T v_c; 0]
    ur = u
    vr = v
    wr = w
    c0 = 0.0
    c1 = 0.0
    c2 = 0.0
    if has_current:
        vn = th[O_VC]
        ve = th[O_VC + 1]
        vd = th[O_VC + 2]
        b0 = vn * R00 + ve * R10 + vd * R20
        b1 = vn * R01 + ve * R11 + vd * R21
        b2 = vn * R02 + ve * R12 + vd * R22
        ur = u - b0
        vr = v - b1
        wr = w - b2
        c0 = -(q * b2 - r * b1)
        c1 = -(r * b0 - p * b2)
        c2 = -(p * b1 - q * b0)
    nr = (ur, vr, wr, p, q, r)
    for j in range(6):
        # restoring (k = third row of R), then diagonal damping (paper sign), then actuators
        t = R20 * th[O_G + j] + R21 * th[O_G + 6 + j] + R22 * th[O_G + 12 + j]
        t = t + (th[O_DL + j] + th[O_DQ + j] * abs(nr[j])) * nr[j]
        if has_coupled:
            for i in range(6):
                t = t + th[O_CL + 6 * j + i] * nr[i] + th[O_CQ + 6 * j + i] * (abs(nr[i]) * nr[i])
        tau[j] = t + tau_act[j]
    if (parts & TETHER) != 0:
        _tether_add(tau, y, R00, R01, R02, R10, R11, R12, R20, R21, R22, nr, th)
    if has_current:
        _coriolis_sub(tau, u, v, w, p, q, r, th, O_MRB)
        _coriolis_sub(tau, ur, vr, wr, p, q, r, th, O_MA)
        cd = (c0, c1, c2)
        for j in range(6):
            tau[j] = tau[j] + th[O_MA + 6 * j] * cd[0] + th[O_MA + 6 * j + 1] * cd[1] + th[O_MA + 6 * j + 2] * cd[2]
    else:
        _coriolis_sub(tau, u, v, w, p, q, r, th, O_M)
    t0 = tau[0]
    t1 = tau[1]
    t2 = tau[2]
    t3 = tau[3]
    t4 = tau[4]
    t5 = tau[5]
    out[7] = th[O_MINV + 0] * t0 + th[O_MINV + 1] * t1 + th[O_MINV + 2] * t2 + th[O_MINV + 3] * t3 + th[O_MINV + 4] * t4 + th[O_MINV + 5] * t5
    out[8] = th[O_MINV + 6] * t0 + th[O_MINV + 7] * t1 + th[O_MINV + 8] * t2 + th[O_MINV + 9] * t3 + th[O_MINV + 10] * t4 + th[O_MINV + 11] * t5
    out[9] = th[O_MINV + 12] * t0 + th[O_MINV + 13] * t1 + th[O_MINV + 14] * t2 + th[O_MINV + 15] * t3 + th[O_MINV + 16] * t4 + th[O_MINV + 17] * t5
    out[10] = th[O_MINV + 18] * t0 + th[O_MINV + 19] * t1 + th[O_MINV + 20] * t2 + th[O_MINV + 21] * t3 + th[O_MINV + 22] * t4 + th[O_MINV + 23] * t5
    out[11] = th[O_MINV + 24] * t0 + th[O_MINV + 25] * t1 + th[O_MINV + 26] * t2 + th[O_MINV + 27] * t3 + th[O_MINV + 28] * t4 + th[O_MINV + 29] * t5
    out[12] = th[O_MINV + 30] * t0 + th[O_MINV + 31] * t1 + th[O_MINV + 32] * t2 + th[O_MINV + 33] * t3 + th[O_MINV + 34] * t4 + th[O_MINV + 35] * t5
    # kinematics: p_dot = R nu_1, q_dot = 1/2 q (x) [0, omega] (seed 003 eq. 1-4)
    out[0] = R00 * u + R01 * v + R02 * w
    out[1] = R10 * u + R11 * v + R12 * w
    out[2] = R20 * u + R21 * v + R22 * w
    out[3] = -0.5 * (qx * p + qy * q + qz * r)
    out[4] = 0.5 * (qw * p + qy * r - qz * q)
    out[5] = 0.5 * (qw * q + qz * p - qx * r)
    out[6] = 0.5 * (qw * r + qx * q - qy * p)


def _tether_add(tau, y, R00, R01, R02, R10, R11, R12, R20, R21, R22, nr, th):
    """``tau += [f; r_a x f]`` of the tether (:meth:`uvsim.effects.tether.Tether.forces`, body frame)."""
    o = O_TE
    ra0 = th[o]
    ra1 = th[o + 1]
    ra2 = th[o + 2]
    if th[o + 6] == 0.0:  # 3-D: d_b = R^T (p_0 - p) - r_a
        dn0 = th[o + 3] - y[0]
        dn1 = th[o + 4] - y[1]
        dn2 = th[o + 5] - y[2]
        d0 = R00 * dn0 + R10 * dn1 + R20 * dn2 - ra0
        d1 = R01 * dn0 + R11 * dn1 + R21 * dn2 - ra1
        d2 = R02 * dn0 + R12 * dn1 + R22 * dn2 - ra2
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        Lm = max(L, 1e-9)
        e0 = d0 / Lm
        e1 = d1 / Lm
        e2 = d2 / Lm
    else:  # horizontal: d = (p_0 - p - R r_a) north/east only, e_b = R^T e
        h0 = th[o + 3] - y[0] - (R00 * ra0 + R01 * ra1 + R02 * ra2)
        h1 = th[o + 4] - y[1] - (R10 * ra0 + R11 * ra1 + R12 * ra2)
        L = math.sqrt(h0 * h0 + h1 * h1)
        Lm = max(L, 1e-9)
        en0 = h0 / Lm
        en1 = h1 / Lm
        e0 = R00 * en0 + R10 * en1
        e1 = R01 * en0 + R11 * en1
        e2 = R02 * en0 + R12 * en1
    pull = th[o + 7] + th[o + 8] * max(0.0, L - th[o + 9])
    f0 = pull * e0
    f1 = pull * e1
    f2 = pull * e2
    # the attachment point's velocity relative to the water: nu_r1 + omega x r_a
    v0 = nr[0] + (nr[4] * ra2 - nr[5] * ra1)
    v1 = nr[1] + (nr[5] * ra0 - nr[3] * ra2)
    v2 = nr[2] + (nr[3] * ra1 - nr[4] * ra0)
    ve = v0 * e0 + v1 * e1 + v2 * e2
    n0 = v0 - ve * e0
    n1 = v1 - ve * e1
    n2 = v2 - ve * e2
    c = th[o + 10] * math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    f0 = f0 - c * n0
    f1 = f1 - c * n1
    f2 = f2 - c * n2
    c = th[o + 11] * math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    f0 = f0 - c * v0
    f1 = f1 - c * v1
    f2 = f2 - c * v2
    tau[0] = tau[0] + f0
    tau[1] = tau[1] + f1
    tau[2] = tau[2] + f2
    tau[3] = tau[3] + (ra1 * f2 - ra2 * f1)
    tau[4] = tau[4] + (ra2 * f0 - ra0 * f2)
    tau[5] = tau[5] + (ra0 * f1 - ra1 * f0)


def _coriolis_sub(tau, u, v, w, p, q, r, th, o):
    """``tau -= C(nu) nu`` with ``[a; b] = M nu`` for the 6x6 ``M`` at ``th[o:o + 36]``."""
    a0 = th[o + 0] * u + th[o + 1] * v + th[o + 2] * w + th[o + 3] * p + th[o + 4] * q + th[o + 5] * r
    a1 = th[o + 6] * u + th[o + 7] * v + th[o + 8] * w + th[o + 9] * p + th[o + 10] * q + th[o + 11] * r
    a2 = th[o + 12] * u + th[o + 13] * v + th[o + 14] * w + th[o + 15] * p + th[o + 16] * q + th[o + 17] * r
    b0 = th[o + 18] * u + th[o + 19] * v + th[o + 20] * w + th[o + 21] * p + th[o + 22] * q + th[o + 23] * r
    b1 = th[o + 24] * u + th[o + 25] * v + th[o + 26] * w + th[o + 27] * p + th[o + 28] * q + th[o + 29] * r
    b2 = th[o + 30] * u + th[o + 31] * v + th[o + 32] * w + th[o + 33] * p + th[o + 34] * q + th[o + 35] * r
    tau[0] = tau[0] - (q * a2 - r * a1)
    tau[1] = tau[1] - (r * a0 - p * a2)
    tau[2] = tau[2] - (p * a1 - q * a0)
    tau[3] = tau[3] - ((v * a2 - w * a1) + (q * b2 - r * b1))
    tau[4] = tau[4] - ((w * a0 - u * a2) + (r * b0 - p * b2))
    tau[5] = tau[5] - ((u * a1 - v * a0) + (p * b1 - q * b0))


def advance(y, T, TAU, TH, substeps, parts, Y, ACC, want_acc, i0, n_t, speed_max, first_bad):
    """RK4 over ``m`` sample intervals for every row, in place.

    ``y`` (n, 13) the states at ``T[:, 0]`` (updated to ``T[:, m]``); ``T`` (n, m + 1) sample
    times; ``TAU`` (n, m, 6) actuator forces held over each interval; ``TH`` (n, N_TH);
    ``Y`` (n, m, 13) receives the states at ``T[:, 1:]``; ``ACC`` (n, m, 6) the acceleration at
    each interval's start (first RK4 stage) when ``want_acc``.  ``i0`` is the global index of
    the first interval and ``n_t`` the run's number of samples: as in ``_rk4_steps``, a row is
    checked at every 16th interval and the last, and a row whose state is not finite or whose
    speed reaches ``speed_max`` becomes NaN from then on (its non-finite earlier states NaN
    too), with the interval recorded in ``first_bad`` (n,) (-1: never)."""
    n = y.shape[0]
    m = TAU.shape[1]
    k1 = np.empty(13)
    k2 = np.empty(13)
    k3 = np.empty(13)
    k4 = np.empty(13)
    ys = np.empty(13)
    yc = np.empty(13)
    tau = np.empty(6)
    for row in range(n):
        th = TH[row]
        for c in range(13):
            yc[c] = y[row, c]
        dead = first_bad[row] >= 0
        last_check = -1
        for i in range(m):
            if dead:
                for c in range(13):
                    Y[row, i, c] = np.nan
                if want_acc:
                    for c in range(6):
                        ACC[row, i, c] = np.nan
                continue
            h = (T[row, i + 1] - T[row, i]) / substeps
            tau_act = TAU[row, i]
            for sub in range(substeps):
                rhs(yc, tau_act, th, parts, k1, tau)
                if want_acc and sub == 0:
                    for c in range(6):
                        ACC[row, i, c] = k1[7 + c]
                for c in range(13):
                    ys[c] = yc[c] + (0.5 * h) * k1[c]
                rhs(ys, tau_act, th, parts, k2, tau)
                for c in range(13):
                    ys[c] = yc[c] + (0.5 * h) * k2[c]
                rhs(ys, tau_act, th, parts, k3, tau)
                for c in range(13):
                    ys[c] = yc[c] + h * k3[c]
                rhs(ys, tau_act, th, parts, k4, tau)
                for c in range(13):
                    yc[c] = yc[c] + (h / 6.0) * (k1[c] + 2.0 * (k2[c] + k3[c]) + k4[c])
                s = math.sqrt(yc[3] * yc[3] + yc[4] * yc[4] + yc[5] * yc[5] + yc[6] * yc[6])
                for c in range(3, 7):
                    yc[c] = yc[c] / s
            for c in range(13):
                Y[row, i, c] = yc[c]
            g = i0 + i
            if (g & 15) == 15 or g == n_t - 2:
                ok = True
                for c in range(13):
                    if not math.isfinite(yc[c]):
                        ok = False
                for c in range(7, 13):
                    if abs(yc[c]) >= speed_max:
                        ok = False
                if not ok:
                    dead = True
                    first_bad[row] = g
                    for j in range(last_check + 1, i + 1):
                        for c in range(13):
                            if not math.isfinite(Y[row, j, c]):
                                Y[row, j, c] = np.nan
                    for c in range(13):
                        yc[c] = np.nan
                last_check = i
        for c in range(13):
            y[row, c] = yc[c]


def accelerations(Y, TAU, TH, parts, ACC):
    """The acceleration ``nu_dot`` of every parameter row at every given state, in place:
    ``Y`` (N, 13) states (shared by the rows), ``TAU`` (P, N, 6) the held actuator forces,
    ``TH`` (P, N_TH) the parameter rows; ``ACC`` (P, N, 6) receives :func:`rhs`'s
    ``out[7:13]``.  What the equation error (:mod:`uvsim.fitting.equation_error`) evaluates
    along a measured motion for a batch of parameter sets (no integration)."""
    P = TH.shape[0]
    N = Y.shape[0]
    out = np.empty(13)
    tau = np.empty(6)
    yc = np.empty(13)
    for p in range(P):
        th = TH[p]
        for s in range(N):
            for c in range(13):
                yc[c] = Y[s, c]
            rhs(yc, TAU[p, s], th, parts, out, tau)
            for c in range(6):
                ACC[p, s, c] = out[7 + c]
