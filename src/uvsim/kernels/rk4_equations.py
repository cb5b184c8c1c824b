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

:func:`rhs` is written for one lane of a block of trajectories (one column of ``(13, B)``
states): :func:`advance` runs the rows in blocks of :data:`BLOCK`, whose loops over the lanes
the compiler turns into vector instructions (the same operations in the same order, so the
same numbers as one row at a time); :func:`accelerations` runs the states in such blocks.
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
KERNEL_FUNCTIONS = ("_dof_force", "_tether_add", "_coriolis_sub", "rhs", "_check_block", "_rk4_block", "rk4_block",
                    "_rhs_lanes", "rhs_block", "advance", "accelerations")
#: Those compiled into their callers (LLVM's ``alwaysinline``), so that a loop over the lanes of a
#: block is one loop body that LLVM vectorises.
INLINED = ("_dof_force", "_tether_add", "_coriolis_sub", "rhs", "_check_block", "_rk4_block", "_rhs_lanes")

#: Trajectories per block of :func:`advance`: one lane of a vector register each (8 doubles in
#: AVX-512's 512 bits).
BLOCK = 8
# rows of a block's work array (:func:`rk4_block`), each of BLOCK lanes
W_Y = 0        # state (13)
W_S = 13       # a stage's state (13)
W_K1 = 26      # the four stages' derivatives (13 each)
W_K2 = 39
W_K3 = 52
W_K4 = 65
W_ACC = 78     # the first stage's acceleration (6)
W_TAU = 84     # held actuator force (6)
W_H = 90       # step (1)
W_TH = 91      # parameters (N_TH)
W_ROWS = W_TH + N_TH

# bits of ``parts``
CURRENT = 1
COUPLED = 2
TETHER = 4


def rhs(y, tau_act, th, parts, out, l):
    """State derivative of lane ``l`` of a block of ``B`` trajectories into ``out[:, l]``: states
    ``y`` (13, B), held actuator forces ``tau_act`` (6, B) (N, N m), parameters ``th`` (N_TH, B)
    (one column per lane), ``out`` (13, B).  A lane reads and writes its own column only, so
    that a loop over the lanes (:func:`rk4_block`) is one vector instruction per operation; one
    trajectory is a block of one (``B = 1``, ``l = 0``)."""
    has_current = (parts & CURRENT) != 0
    qw = y[3, l]
    qx = y[4, l]
    qy = y[5, l]
    qz = y[6, l]
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
    u = y[7, l]
    v = y[8, l]
    w = y[9, l]
    p = y[10, l]
    q = y[11, l]
    r = y[12, l]
    # current seen from the body: nu_r = nu - [R^T v_c; 0], nu_c_dot = [-omega x R^T v_c; 0]
    ur = u
    vr = v
    wr = w
    c0 = 0.0
    c1 = 0.0
    c2 = 0.0
    if has_current:
        vn = th[O_VC, l]
        ve = th[O_VC + 1, l]
        vd = th[O_VC + 2, l]
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
    # restoring (k = third row of R), then diagonal and coupled damping, then actuators
    tau = (_dof_force(0, nr, R20, R21, R22, tau_act, th, parts, l), _dof_force(1, nr, R20, R21, R22, tau_act, th, parts, l),
           _dof_force(2, nr, R20, R21, R22, tau_act, th, parts, l), _dof_force(3, nr, R20, R21, R22, tau_act, th, parts, l),
           _dof_force(4, nr, R20, R21, R22, tau_act, th, parts, l), _dof_force(5, nr, R20, R21, R22, tau_act, th, parts, l))
    if (parts & TETHER) != 0:
        tau = _tether_add(tau, y, l, R00, R01, R02, R10, R11, R12, R20, R21, R22, nr, th)
    if has_current:
        tau = _coriolis_sub(tau, u, v, w, p, q, r, th, O_MRB, l)
        t0, t1, t2, t3, t4, t5 = _coriolis_sub(tau, ur, vr, wr, p, q, r, th, O_MA, l)
        t0 = t0 + th[O_MA + 0, l] * c0 + th[O_MA + 1, l] * c1 + th[O_MA + 2, l] * c2
        t1 = t1 + th[O_MA + 6, l] * c0 + th[O_MA + 7, l] * c1 + th[O_MA + 8, l] * c2
        t2 = t2 + th[O_MA + 12, l] * c0 + th[O_MA + 13, l] * c1 + th[O_MA + 14, l] * c2
        t3 = t3 + th[O_MA + 18, l] * c0 + th[O_MA + 19, l] * c1 + th[O_MA + 20, l] * c2
        t4 = t4 + th[O_MA + 24, l] * c0 + th[O_MA + 25, l] * c1 + th[O_MA + 26, l] * c2
        t5 = t5 + th[O_MA + 30, l] * c0 + th[O_MA + 31, l] * c1 + th[O_MA + 32, l] * c2
    else:
        t0, t1, t2, t3, t4, t5 = _coriolis_sub(tau, u, v, w, p, q, r, th, O_M, l)
    out[7, l] = th[O_MINV + 0, l] * t0 + th[O_MINV + 1, l] * t1 + th[O_MINV + 2, l] * t2 + th[O_MINV + 3, l] * t3 + th[O_MINV + 4, l] * t4 + th[O_MINV + 5, l] * t5
    out[8, l] = th[O_MINV + 6, l] * t0 + th[O_MINV + 7, l] * t1 + th[O_MINV + 8, l] * t2 + th[O_MINV + 9, l] * t3 + th[O_MINV + 10, l] * t4 + th[O_MINV + 11, l] * t5
    out[9, l] = th[O_MINV + 12, l] * t0 + th[O_MINV + 13, l] * t1 + th[O_MINV + 14, l] * t2 + th[O_MINV + 15, l] * t3 + th[O_MINV + 16, l] * t4 + th[O_MINV + 17, l] * t5
    out[10, l] = th[O_MINV + 18, l] * t0 + th[O_MINV + 19, l] * t1 + th[O_MINV + 20, l] * t2 + th[O_MINV + 21, l] * t3 + th[O_MINV + 22, l] * t4 + th[O_MINV + 23, l] * t5
    out[11, l] = th[O_MINV + 24, l] * t0 + th[O_MINV + 25, l] * t1 + th[O_MINV + 26, l] * t2 + th[O_MINV + 27, l] * t3 + th[O_MINV + 28, l] * t4 + th[O_MINV + 29, l] * t5
    out[12, l] = th[O_MINV + 30, l] * t0 + th[O_MINV + 31, l] * t1 + th[O_MINV + 32, l] * t2 + th[O_MINV + 33, l] * t3 + th[O_MINV + 34, l] * t4 + th[O_MINV + 35, l] * t5
    # kinematics: p_dot = R nu_1, q_dot = 1/2 q (x) [0, omega] (seed 003 eq. 1-4)
    out[0, l] = R00 * u + R01 * v + R02 * w
    out[1, l] = R10 * u + R11 * v + R12 * w
    out[2, l] = R20 * u + R21 * v + R22 * w
    out[3, l] = -0.5 * (qx * p + qy * q + qz * r)
    out[4, l] = 0.5 * (qw * p + qy * r - qz * q)
    out[5, l] = 0.5 * (qw * q + qz * p - qx * r)
    out[6, l] = 0.5 * (qw * r + qx * q - qy * p)


def _dof_force(j, nr, R20, R21, R22, tau_act, th, parts, l):
    """DOF ``j``'s restoring force (k = third row of R), diagonal damping (paper sign), coupled
    damping and held actuator force for lane ``l``, on ``nu_r = nr``."""
    t = R20 * th[O_G + j, l] + R21 * th[O_G + 6 + j, l] + R22 * th[O_G + 12 + j, l]
    t = t + (th[O_DL + j, l] + th[O_DQ + j, l] * abs(nr[j])) * nr[j]
    if (parts & COUPLED) != 0:
        for i in range(6):
            t = t + th[O_CL + 6 * j + i, l] * nr[i] + th[O_CQ + 6 * j + i, l] * (abs(nr[i]) * nr[i])
    return t + tau_act[j, l]


def _tether_add(tau, y, l, R00, R01, R02, R10, R11, R12, R20, R21, R22, nr, th):
    """``tau + [f; r_a x f]`` (6 numbers) of the tether for lane ``l``
    (:meth:`uvsim.effects.tether.Tether.forces`, body frame)."""
    o = O_TE
    ra0 = th[o, l]
    ra1 = th[o + 1, l]
    ra2 = th[o + 2, l]
    if th[o + 6, l] == 0.0:  # 3-D: d_b = R^T (p_0 - p) - r_a
        dn0 = th[o + 3, l] - y[0, l]
        dn1 = th[o + 4, l] - y[1, l]
        dn2 = th[o + 5, l] - y[2, l]
        d0 = R00 * dn0 + R10 * dn1 + R20 * dn2 - ra0
        d1 = R01 * dn0 + R11 * dn1 + R21 * dn2 - ra1
        d2 = R02 * dn0 + R12 * dn1 + R22 * dn2 - ra2
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        Lm = max(L, 1e-9)
        e0 = d0 / Lm
        e1 = d1 / Lm
        e2 = d2 / Lm
    else:  # horizontal: d = (p_0 - p - R r_a) north/east only, e_b = R^T e
        h0 = th[o + 3, l] - y[0, l] - (R00 * ra0 + R01 * ra1 + R02 * ra2)
        h1 = th[o + 4, l] - y[1, l] - (R10 * ra0 + R11 * ra1 + R12 * ra2)
        L = math.sqrt(h0 * h0 + h1 * h1)
        Lm = max(L, 1e-9)
        en0 = h0 / Lm
        en1 = h1 / Lm
        e0 = R00 * en0 + R10 * en1
        e1 = R01 * en0 + R11 * en1
        e2 = R02 * en0 + R12 * en1
    pull = th[o + 7, l] + th[o + 8, l] * max(0.0, L - th[o + 9, l])
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
    c = th[o + 10, l] * math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    f0 = f0 - c * n0
    f1 = f1 - c * n1
    f2 = f2 - c * n2
    c = th[o + 11, l] * math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    f0 = f0 - c * v0
    f1 = f1 - c * v1
    f2 = f2 - c * v2
    return (tau[0] + f0, tau[1] + f1, tau[2] + f2, tau[3] + (ra1 * f2 - ra2 * f1), tau[4] + (ra2 * f0 - ra0 * f2),
            tau[5] + (ra0 * f1 - ra1 * f0))


def _coriolis_sub(tau, u, v, w, p, q, r, th, o, l):
    """``tau - C(nu) nu`` (6 numbers) with ``[a; b] = M nu`` for the 6x6 ``M`` at ``th[o:o + 36, l]``."""
    a0 = th[o + 0, l] * u + th[o + 1, l] * v + th[o + 2, l] * w + th[o + 3, l] * p + th[o + 4, l] * q + th[o + 5, l] * r
    a1 = th[o + 6, l] * u + th[o + 7, l] * v + th[o + 8, l] * w + th[o + 9, l] * p + th[o + 10, l] * q + th[o + 11, l] * r
    a2 = th[o + 12, l] * u + th[o + 13, l] * v + th[o + 14, l] * w + th[o + 15, l] * p + th[o + 16, l] * q + th[o + 17, l] * r
    b0 = th[o + 18, l] * u + th[o + 19, l] * v + th[o + 20, l] * w + th[o + 21, l] * p + th[o + 22, l] * q + th[o + 23, l] * r
    b1 = th[o + 24, l] * u + th[o + 25, l] * v + th[o + 26, l] * w + th[o + 27, l] * p + th[o + 28, l] * q + th[o + 29, l] * r
    b2 = th[o + 30, l] * u + th[o + 31, l] * v + th[o + 32, l] * w + th[o + 33, l] * p + th[o + 34, l] * q + th[o + 35, l] * r
    return (tau[0] - (q * a2 - r * a1), tau[1] - (r * a0 - p * a2), tau[2] - (p * a1 - q * a0),
            tau[3] - ((v * a2 - w * a1) + (q * b2 - r * b1)), tau[4] - ((w * a0 - u * a2) + (r * b0 - p * b2)),
            tau[5] - ((u * a1 - v * a0) + (p * b1 - q * b0)))


def _check_block(w):
    """Raise unless ``w`` is a C-contiguous (W_ROWS, BLOCK) float64 array.  Also what tells the
    compiler the shape and strides of ``w`` in the code after it (:func:`rk4_block`)."""
    if w.shape[0] != W_ROWS or w.shape[1] != BLOCK or w.strides[0] != 8 * BLOCK or w.strides[1] != 8:
        raise ValueError("a block's work array must be a C-contiguous (W_ROWS, BLOCK) float64 array")


def rk4_block(w, parts, substeps):
    """One sample interval of RK4 (``substeps`` steps) for every lane of a block, in place.

    ``w`` (W_ROWS, BLOCK), C-contiguous, holds the block's numbers, one column per trajectory, in
    the rows ``W_*``: the states (13 rows, updated), the held actuator forces (6, N, N m), the
    step ``h`` (1, s), the parameters (N_TH) and, out, the acceleration of the first stage of the
    first step (6, m/s^2, rad/s^2); the rest is scratch.  Its shape and strides are checked first,
    which tells the compiler that every part is a fixed offset from one address, so that no
    lane's reads overlap another part's writes: each loop over the lanes becomes one vector
    instruction per operation."""
    _check_block(w)
    if parts == 0:  # the common model (no current, coupled damping or tether): a body with no branches
        _rk4_block(w, 0, substeps)
    else:
        _rk4_block(w, parts, substeps)


def _rk4_block(w, parts, substeps):
    """:func:`rk4_block`'s steps (compiled into it twice: with ``parts`` 0, where the compiler drops the
    optional parts' branches from the lanes' loops, and with ``parts`` as given)."""
    yc = w[W_Y:W_Y + 13]
    ys = w[W_S:W_S + 13]
    k1 = w[W_K1:W_K1 + 13]
    k2 = w[W_K2:W_K2 + 13]
    k3 = w[W_K3:W_K3 + 13]
    k4 = w[W_K4:W_K4 + 13]
    acc = w[W_ACC:W_ACC + 6]
    tau_act = w[W_TAU:W_TAU + 6]
    th = w[W_TH:W_TH + N_TH]
    h = w[W_H]
    for sub in range(substeps):
        _rhs_lanes(w, parts)  # k1
        if sub == 0:
            for c in range(6):
                for l in range(BLOCK):
                    acc[c, l] = k1[7 + c, l]
        for c in range(13):
            for l in range(BLOCK):
                ys[c, l] = yc[c, l] + (0.5 * h[l]) * k1[c, l]
        for l in range(BLOCK):
            rhs(ys, tau_act, th, parts, k2, l)
        for c in range(13):
            for l in range(BLOCK):
                ys[c, l] = yc[c, l] + (0.5 * h[l]) * k2[c, l]
        for l in range(BLOCK):
            rhs(ys, tau_act, th, parts, k3, l)
        for c in range(13):
            for l in range(BLOCK):
                ys[c, l] = yc[c, l] + h[l] * k3[c, l]
        for l in range(BLOCK):
            rhs(ys, tau_act, th, parts, k4, l)
        for c in range(13):
            for l in range(BLOCK):
                yc[c, l] = yc[c, l] + (h[l] / 6.0) * (k1[c, l] + 2.0 * (k2[c, l] + k3[c, l]) + k4[c, l])
        for l in range(BLOCK):
            s = math.sqrt(yc[3, l] * yc[3, l] + yc[4, l] * yc[4, l] + yc[5, l] * yc[5, l] + yc[6, l] * yc[6, l])
            for c in range(3, 7):
                yc[c, l] = yc[c, l] / s


def rhs_block(w, parts):
    """:func:`rhs` for every lane of a block: the derivative of the states ``w[W_Y:W_Y + 13]`` into
    ``w[W_K1:W_K1 + 13]``; ``w`` as in :func:`rk4_block` (and checked the same way, which is what
    lets the compiler vectorise the loop over the lanes)."""
    _check_block(w)
    if parts == 0:
        _rhs_lanes(w, 0)
    else:
        _rhs_lanes(w, parts)


def _rhs_lanes(w, parts):
    """:func:`rhs_block`'s loop (compiled into it twice, as :func:`_rk4_block`)."""
    y = w[W_Y:W_Y + 13]
    tau_act = w[W_TAU:W_TAU + 6]
    th = w[W_TH:W_TH + N_TH]
    out = w[W_K1:W_K1 + 13]
    for l in range(BLOCK):
        rhs(y, tau_act, th, parts, out, l)


def advance(y, T, TAU, TH, substeps, parts, Y, ACC, want_acc, i0, speed_max, first_bad):
    """RK4 over the ``m`` sample intervals from ``i0`` for every row, in place.

    ``y`` (n, 13) the states at ``T[:, i0]`` (updated to ``T[:, i0 + m]``); ``T`` (n, n_t)
    the run's sample times (s); ``TAU`` (n, m, 6) actuator forces held over each interval
    (N, N m); ``TH`` (n, N_TH); ``Y`` (n, n_t, 13) receives the states at
    ``T[:, i0 + 1:i0 + m + 1]``; ``ACC`` (n, n_t, 6) the acceleration at each interval's start
    (first RK4 stage) when ``want_acc``.  The whole run's arrays with the offset ``i0`` rather
    than a chunk's views: their layout, and so the compiled signature, is the same for every
    call.  As in ``_rk4_steps``, a row is checked at every 16th interval and the last, and a row
    whose state is not finite or whose speed reaches ``speed_max`` becomes NaN from then on (its
    non-finite earlier states NaN too), with the interval recorded in ``first_bad`` (n,) (-1:
    never).

    The rows run in blocks of :data:`BLOCK` (:func:`rk4_block`), one lane each; the lanes past
    the last row of the last block repeat its last row and are not written."""
    n = y.shape[0]
    m = TAU.shape[1]
    n_t = T.shape[1]
    w = np.empty((W_ROWS, BLOCK))
    dead = np.empty(BLOCK, np.bool_)
    last_check = np.empty(BLOCK, np.int64)
    for r0 in range(0, n, BLOCK):
        nl = min(BLOCK, n - r0)
        for l in range(BLOCK):
            row = r0 + min(l, nl - 1)
            for c in range(N_TH):
                w[W_TH + c, l] = TH[row, c]
            for c in range(13):
                w[W_Y + c, l] = y[row, c]
            dead[l] = first_bad[row] >= 0
            last_check[l] = -1
        for i in range(m):
            for l in range(BLOCK):
                row = r0 + min(l, nl - 1)
                w[W_H, l] = (T[row, i0 + i + 1] - T[row, i0 + i]) / substeps
                for c in range(6):
                    w[W_TAU + c, l] = TAU[row, i, c]
            rk4_block(w, parts, substeps)
            g = i0 + i
            check = (g & 15) == 15 or g == n_t - 2
            for l in range(nl):
                row = r0 + l
                if dead[l]:
                    for c in range(13):
                        Y[row, g + 1, c] = np.nan
                    if want_acc:
                        for c in range(6):
                            ACC[row, g, c] = np.nan
                    continue
                for c in range(13):
                    Y[row, g + 1, c] = w[W_Y + c, l]
                if want_acc:
                    for c in range(6):
                        ACC[row, g, c] = w[W_ACC + c, l]
                if check:
                    ok = True
                    for c in range(13):
                        if not math.isfinite(w[W_Y + c, l]):
                            ok = False
                    for c in range(7, 13):
                        if abs(w[W_Y + c, l]) >= speed_max:
                            ok = False
                    if not ok:
                        dead[l] = True
                        first_bad[row] = g
                        for j in range(i0 + last_check[l] + 2, g + 2):
                            for c in range(13):
                                if not math.isfinite(Y[row, j, c]):
                                    Y[row, j, c] = np.nan
                        for c in range(13):
                            y[row, c] = np.nan
                    last_check[l] = i
        for l in range(nl):
            if not dead[l]:
                for c in range(13):
                    y[r0 + l, c] = w[W_Y + c, l]


def accelerations(Y, TAU, TH, parts, ACC):
    """The acceleration ``nu_dot`` of every parameter row at every given state, in place:
    ``Y`` (N, 13) states (shared by the rows), ``TAU`` (P, N, 6) the held actuator forces
    (N, N m), ``TH`` (P, N_TH) the parameter rows; ``ACC`` (P, N, 6) receives :func:`rhs`'s
    ``out[7:13]`` (m/s^2, rad/s^2).  What the equation error (:mod:`uvsim.fitting.equation_error`)
    evaluates along a measured motion for a batch of parameter sets (no integration).  The states
    run in blocks of :data:`BLOCK` lanes (:func:`rhs_block`), the last block's spare lanes
    repeating its last state."""
    P = TH.shape[0]
    N = Y.shape[0]
    w = np.empty((W_ROWS, BLOCK))
    for p in range(P):
        for c in range(N_TH):
            for l in range(BLOCK):
                w[W_TH + c, l] = TH[p, c]
        for s0 in range(0, N, BLOCK):
            nl = min(BLOCK, N - s0)
            for l in range(BLOCK):
                s = s0 + min(l, nl - 1)
                for c in range(13):
                    w[W_Y + c, l] = Y[s, c]
                for c in range(6):
                    w[W_TAU + c, l] = TAU[p, s, c]
            rhs_block(w, parts)
            for l in range(nl):
                for c in range(6):
                    ACC[p, s0 + l, c] = w[W_K1 + 7 + c, l]
