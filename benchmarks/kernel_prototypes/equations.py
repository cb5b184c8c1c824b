"""The BlueROV2 model's equations written once, for every kernel prototype (issue 46, item 1).

One trajectory's state derivative and RK4 step, written with nothing but indexing,
``+ - * /`` and three helpers (``_abs``, ``_neg``, ``_sqrt``) looked up as module globals.
That is the whole contract, and it is what lets one text run as:

* numpy, batched: components are arrays of shape (n,) (``y`` component-major (13, n));
* numba: :mod:`kernel_numba` compiles these very functions (their code objects, with the
  globals re-bound to jitted helpers: the real ones, or the complex-step ones);
* JAX: components are traced jnp scalars (``jax.vmap`` for batches, ``jax.jvp`` for
  sensitivities);
* CasADi: components are SX scalars (symbolic step, ``jtimes`` for sensitivities).

The physics is uvsim's for a vehicle with restoring, diagonal damping and thrusters and no
current (src/uvsim/model.py, forces/): rotation and quaternion rate in the homogeneous form
of ``uvsim.bilinear`` (stage states are not unit quaternions, so the form matters beyond
round-off), ``C(nu) nu = [w x a; v x a + w x b]`` with ``[a; b] = M nu``, restoring
``[(W - B) k; h x k]`` with ``k = R^T e_3`` and ``h = W r_g - B r_b``, diagonal damping
``(D_L + D_Q |nu|) nu`` (paper sign) and thrusts ``tau = B_alloc (gain * f * (rev where f < 0))``.

Parameters enter as one vector ``th`` (:func:`layout`): what uvsim's ``prepare`` steps
compute once per model (``M``, ``M^-1``, ...), so the kernel does no inverse.
"""

NQ = 13  # state size: x y z, qw qx qy qz, u v w p q r


def layout(k):
    """Offsets of the parameter vector ``th`` for ``k`` thrusters."""
    o = {}
    i = 0
    for name, size in (("Minv", 36), ("M", 36), ("DL", 6), ("DQ", 6), ("WmB", 1), ("h", 3),
                       ("B", 6 * k), ("gain", k), ("rev", k)):
        o[name] = i
        i += size
    o["size"] = i
    return o


def _abs(x):  # re-bound per backend (jnp / SX / complex step)
    return abs(x)


def _neg(x):  # 1 where x < 0 else 0; x is an input (never differentiated)
    return 1.0 * (x < 0)


def _sqrt(x):
    return x ** 0.5


def rhs(y, f, th, k):
    """State derivative (13-tuple) of state ``y`` (13 components), thrusts ``f`` (k) and
    parameters ``th`` (:func:`layout`)."""
    oMi = 0
    oM = 36
    oDL = 72
    oDQ = 78
    oW = 84
    oh = 85
    oB = 88
    og = 88 + 6 * k
    orv = 88 + 7 * k
    qw = y[3]
    qx = y[4]
    qy = y[5]
    qz = y[6]
    u = y[7]
    v = y[8]
    w = y[9]
    p = y[10]
    q = y[11]
    r = y[12]
    # rotation body -> NED, homogeneous form (uvsim.bilinear.rot_qrate)
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
    # restoring: [(W - B) k; h x k], k = third row of R
    WmB = th[oW]
    h0 = th[oh]
    h1 = th[oh + 1]
    h2 = th[oh + 2]
    t0 = WmB * R20
    t1 = WmB * R21
    t2 = WmB * R22
    t3 = h1 * R22 - h2 * R21
    t4 = h2 * R20 - h0 * R22
    t5 = h0 * R21 - h1 * R20
    # damping (paper sign)
    t0 = t0 + (th[oDL] + th[oDQ] * _abs(u)) * u
    t1 = t1 + (th[oDL + 1] + th[oDQ + 1] * _abs(v)) * v
    t2 = t2 + (th[oDL + 2] + th[oDQ + 2] * _abs(w)) * w
    t3 = t3 + (th[oDL + 3] + th[oDQ + 3] * _abs(p)) * p
    t4 = t4 + (th[oDL + 4] + th[oDQ + 4] * _abs(q)) * q
    t5 = t5 + (th[oDL + 5] + th[oDQ + 5] * _abs(r)) * r
    # thrusters: per-unit gain and reverse ratio, then the allocation matrix
    for i in range(k):
        fi = f[i]
        ng = _neg(fi)
        fe = th[og + i] * (fi * (ng * th[orv + i] + (1.0 - ng)))
        t0 = t0 + th[oB + i] * fe
        t1 = t1 + th[oB + k + i] * fe
        t2 = t2 + th[oB + 2 * k + i] * fe
        t3 = t3 + th[oB + 3 * k + i] * fe
        t4 = t4 + th[oB + 4 * k + i] * fe
        t5 = t5 + th[oB + 5 * k + i] * fe
    # Coriolis-centripetal: [a; b] = M nu, C(nu) nu = [w x a; v x a + w x b]
    a0 = th[oM] * u + th[oM + 1] * v + th[oM + 2] * w + th[oM + 3] * p + th[oM + 4] * q + th[oM + 5] * r
    a1 = th[oM + 6] * u + th[oM + 7] * v + th[oM + 8] * w + th[oM + 9] * p + th[oM + 10] * q + th[oM + 11] * r
    a2 = th[oM + 12] * u + th[oM + 13] * v + th[oM + 14] * w + th[oM + 15] * p + th[oM + 16] * q + th[oM + 17] * r
    b0 = th[oM + 18] * u + th[oM + 19] * v + th[oM + 20] * w + th[oM + 21] * p + th[oM + 22] * q + th[oM + 23] * r
    b1 = th[oM + 24] * u + th[oM + 25] * v + th[oM + 26] * w + th[oM + 27] * p + th[oM + 28] * q + th[oM + 29] * r
    b2 = th[oM + 30] * u + th[oM + 31] * v + th[oM + 32] * w + th[oM + 33] * p + th[oM + 34] * q + th[oM + 35] * r
    t0 = t0 - (q * a2 - r * a1)
    t1 = t1 - (r * a0 - p * a2)
    t2 = t2 - (p * a1 - q * a0)
    t3 = t3 - (v * a2 - w * a1 + q * b2 - r * b1)
    t4 = t4 - (w * a0 - u * a2 + r * b0 - p * b2)
    t5 = t5 - (u * a1 - v * a0 + p * b1 - q * b0)
    # nu_dot = M^-1 tau
    d0 = th[oMi] * t0 + th[oMi + 1] * t1 + th[oMi + 2] * t2 + th[oMi + 3] * t3 + th[oMi + 4] * t4 + th[oMi + 5] * t5
    d1 = th[oMi + 6] * t0 + th[oMi + 7] * t1 + th[oMi + 8] * t2 + th[oMi + 9] * t3 + th[oMi + 10] * t4 + th[oMi + 11] * t5
    d2 = th[oMi + 12] * t0 + th[oMi + 13] * t1 + th[oMi + 14] * t2 + th[oMi + 15] * t3 + th[oMi + 16] * t4 + th[oMi + 17] * t5
    d3 = th[oMi + 18] * t0 + th[oMi + 19] * t1 + th[oMi + 20] * t2 + th[oMi + 21] * t3 + th[oMi + 22] * t4 + th[oMi + 23] * t5
    d4 = th[oMi + 24] * t0 + th[oMi + 25] * t1 + th[oMi + 26] * t2 + th[oMi + 27] * t3 + th[oMi + 28] * t4 + th[oMi + 29] * t5
    d5 = th[oMi + 30] * t0 + th[oMi + 31] * t1 + th[oMi + 32] * t2 + th[oMi + 33] * t3 + th[oMi + 34] * t4 + th[oMi + 35] * t5
    # kinematics: p_dot = R nu_1, q_dot = 1/2 q (x) [0, w]
    return (R00 * u + R01 * v + R02 * w,
            R10 * u + R11 * v + R12 * w,
            R20 * u + R21 * v + R22 * w,
            -0.5 * (qx * p + qy * q + qz * r),
            0.5 * (qw * p + qy * r - qz * q),
            0.5 * (qw * q + qz * p - qx * r),
            0.5 * (qw * r + qx * q - qy * p),
            d0, d1, d2, d3, d4, d5)


def _lin(y, c, d):
    """``y + c d`` for 13-tuples (written out: numba builds no tuple from a generator)."""
    return (y[0] + c * d[0], y[1] + c * d[1], y[2] + c * d[2], y[3] + c * d[3],
            y[4] + c * d[4], y[5] + c * d[5], y[6] + c * d[6], y[7] + c * d[7],
            y[8] + c * d[8], y[9] + c * d[9], y[10] + c * d[10], y[11] + c * d[11],
            y[12] + c * d[12])


def rk4_step(y, f, th, k, h):
    """One RK4 step of length ``h`` with the inputs held, then the quaternion renormalized
    (uvsim.simulate._rk4_steps).  Returns the 13-tuple of the new state."""
    k1 = rhs(y, f, th, k)
    k2 = rhs(_lin(y, 0.5 * h, k1), f, th, k)
    k3 = rhs(_lin(y, 0.5 * h, k2), f, th, k)
    k4 = rhs(_lin(y, h, k3), f, th, k)
    c = h / 6.0
    yn = (y[0] + c * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0]), y[1] + c * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1]),
          y[2] + c * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2]), y[3] + c * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3]),
          y[4] + c * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4]), y[5] + c * (k1[5] + 2.0 * (k2[5] + k3[5]) + k4[5]),
          y[6] + c * (k1[6] + 2.0 * (k2[6] + k3[6]) + k4[6]), y[7] + c * (k1[7] + 2.0 * (k2[7] + k3[7]) + k4[7]),
          y[8] + c * (k1[8] + 2.0 * (k2[8] + k3[8]) + k4[8]), y[9] + c * (k1[9] + 2.0 * (k2[9] + k3[9]) + k4[9]),
          y[10] + c * (k1[10] + 2.0 * (k2[10] + k3[10]) + k4[10]), y[11] + c * (k1[11] + 2.0 * (k2[11] + k3[11]) + k4[11]),
          y[12] + c * (k1[12] + 2.0 * (k2[12] + k3[12]) + k4[12]))
    s = _sqrt(yn[3] * yn[3] + yn[4] * yn[4] + yn[5] * yn[5] + yn[6] * yn[6])
    return (yn[0], yn[1], yn[2], yn[3] / s, yn[4] / s, yn[5] / s, yn[6] / s,
            yn[7], yn[8], yn[9], yn[10], yn[11], yn[12])
