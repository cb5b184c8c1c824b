"""Constant tensors that turn the bilinear parts of the equations of motion into one
outer product and one matrix product (fewer numpy calls per stage, which is what
dominates the cost of small batches).

For vectors ``a`` (n, i) and ``b`` (n, j), ``bilinear(a, b, E) = (a (x) b).reshape(n, i*j) @ E``
evaluates ``out_k = sum_ij E[i*j.., k] a_i b_j`` for every row.  The tensors are built
numerically from the reference formulas (below), so they are exactly those formulas.
"""
from __future__ import annotations

import numpy as np


def matvec(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``M x`` per row for a shared ``M`` (i, j) or per-row ``M`` (n, i, j); ``x`` (n, j)."""
    if M.ndim == 2:
        return x @ M.T
    return np.einsum("nij,nj->ni", M, x)


def bilinear(a: np.ndarray, b: np.ndarray, E: np.ndarray) -> np.ndarray:
    n = a.shape[0]
    return (a[:, :, None] * b[:, None, :]).reshape(n, -1) @ E


def _tensor(f, na: int, nb: int) -> np.ndarray:
    """Tensor E with bilinear(a, b, E) == f(a, b) for a bilinear ``f``."""
    rows = []
    for i in range(na):
        for j in range(nb):
            a = np.zeros(na)
            b = np.zeros(nb)
            a[i] = b[j] = 1.0
            rows.append(f(a, b))
    return np.array(rows)


def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _rot_flat(q, p):
    """Row-major R(q) entries as the bilinear form q_i q_j (unit quaternion; seed 003 eq. 3)."""
    # R = (w^2 - e.e) I + 2 e e^T + 2 w S(e), written with q = p so that q_i q_j -> entry
    w, x, y, z = q
    W, X, Y, Z = p
    return np.array([
        w * W + x * X - y * Y - z * Z, 2 * (x * Y - z * W) / 1, 2 * (x * Z + y * W) / 1,
        2 * (x * Y + z * W), w * W - x * X + y * Y - z * Z, 2 * (y * Z - x * W),
        2 * (x * Z - y * W), 2 * (y * Z + x * W), w * W - x * X - y * Y + z * Z,
    ])


def _quat_rate(q, w):
    """q_dot = 1/2 q (x) [0, w] (seed 003 eq. 2, 4)."""
    qw, qx, qy, qz = q
    p, qq, r = w
    return 0.5 * np.array([-qx * p - qy * qq - qz * r, qw * p + qy * r - qz * qq,
                           qw * qq + qz * p - qx * r, qw * r + qx * qq - qy * p])


def _coriolis(nu, ab):
    """C(nu) nu = [w x a; v x a + w x b] with [a; b] = M nu (Fossen 2021 eq. 3.46)."""
    v, w = nu[:3], nu[3:]
    a, b = ab[:3], ab[3:]
    return np.concatenate([_cross(w, a), _cross(v, a) + _cross(w, b)])


#: (16, 9): bilinear(q, q, ROT) = R(q) row-major, for unit q.  Symmetrized in (i, j).
ROT = _tensor(_rot_flat, 4, 4)
ROT = 0.5 * (ROT + ROT.reshape(4, 4, 9).transpose(1, 0, 2).reshape(16, 9))
#: (12, 4): bilinear(q, w, QRATE) = quaternion rate
QRATE = _tensor(_quat_rate, 4, 3)
#: (36, 6): bilinear(nu, M nu, CORIOLIS) = C(nu) nu
CORIOLIS = _tensor(_coriolis, 6, 6)
#: (9, 3): bilinear(a, b, CROSS) = a x b
CROSS = _tensor(_cross, 3, 3)

#: (40, 13): bilinear(q, [q, nu], ROT_QRATE) = [R(q) row-major (9), q_dot (4)]; the
#: linear-velocity part of nu does not enter.
ROT_QRATE = np.zeros((4, 10, 13))
ROT_QRATE[:, :4, :9] = ROT.reshape(4, 4, 9)
ROT_QRATE[:, 7:, 9:] = QRATE.reshape(4, 3, 4)
ROT_QRATE = ROT_QRATE.reshape(40, 13)


#: Batch size from which :func:`rot_qrate` is faster than ``bilinear(q, [q, nu], ROT_QRATE)``
#: (measured on 2 cores: 68 vs 101 us at 1232 rows, 26 vs 7 us at 50; docs/performance.md).
WRITTEN_OUT_ROWS = 512


def rot_qrate(y: np.ndarray) -> np.ndarray:
    """``[R(q) row-major (9), q_dot (4)]`` (n, 13) for states ``y`` (n, 13+): the same
    formulas as ``ROT_QRATE`` (seed 003 eq. 2-4), written out per column (fewer flops than
    the 40-column outer product on large batches)."""
    n = y.shape[0]
    w, x, yy, z, p, q, r = np.ascontiguousarray(y[:, [3, 4, 5, 6, 10, 11, 12]].T)
    out = np.empty((n, 13))
    ww, xx, y2, zz = w * w, x * x, yy * yy, z * z
    xy, xz, yz, wx, wy, wz = x * yy, x * z, yy * z, w * x, w * yy, w * z
    out[:, 0] = ww + xx - y2 - zz
    out[:, 1] = 2 * (xy - wz)
    out[:, 2] = 2 * (xz + wy)
    out[:, 3] = 2 * (xy + wz)
    out[:, 4] = ww - xx + y2 - zz
    out[:, 5] = 2 * (yz - wx)
    out[:, 6] = 2 * (xz - wy)
    out[:, 7] = 2 * (yz + wx)
    out[:, 8] = ww - xx - y2 + zz
    out[:, 9] = -0.5 * (x * p + yy * q + z * r)
    out[:, 10] = 0.5 * (w * p + yy * r - z * q)
    out[:, 11] = 0.5 * (w * q + z * p - x * r)
    out[:, 12] = 0.5 * (w * r + x * q - yy * p)
    return out
