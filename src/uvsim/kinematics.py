"""Attitude kinematics: unit quaternions (scalar first, body -> NED), rotation
matrices and ZYX Euler angles.

Conventions (docs/model.md):  q = [eta, eps1, eps2, eps3] rotates body-frame vectors
into NED, ``v_ned = R(q) @ v_body``.  ZYX Euler angles (roll phi, pitch theta,
yaw psi) give the same rotation as R = Rz(psi) Ry(theta) Rx(phi) (Fossen 2021,
eq. 2.18).  All functions broadcast over leading axes: shapes are ``(..., 4)``
for quaternions, ``(..., 3)`` for Euler angles and ``(..., 3, 3)`` for matrices.
"""
from __future__ import annotations

import numpy as np


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """Return ``q / |q|`` with the scalar part made non-negative, shape ``(..., 4)``."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_to_rotation(q: np.ndarray) -> np.ndarray:
    """Rotation matrix body -> NED from a unit quaternion (seed 003 eq. 3;
    Fossen 2021 eq. 2.72).  ``q`` shape ``(..., 4)``, returns ``(..., 3, 3)``."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - z * w)
    R[..., 0, 2] = 2 * (x * z + y * w)
    R[..., 1, 0] = 2 * (x * y + z * w)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - x * w)
    R[..., 2, 0] = 2 * (x * z - y * w)
    R[..., 2, 1] = 2 * (y * z + x * w)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quat_down_axis(q: np.ndarray) -> np.ndarray:
    """The NED down axis in body coordinates, ``k = R(q)^T e_3``: the third row of
    :func:`quat_to_rotation` (same formulas, so the same values to the last bit), without
    the other six entries.  Depth sensors and accelerometers need only this row.

    Parameters
    ----------
    q : (..., 4) unit quaternions (scalar first, body -> NED).

    Returns
    -------
    (..., 3) array ``[R_20, R_21, R_22]``.
    """
    q = np.asarray(q, dtype=float)
    return np.stack(down_axis_components(q[..., 0], q[..., 1], q[..., 2], q[..., 3]), axis=-1)


def down_axis_components(w, x, y, z) -> tuple:
    """:func:`quat_down_axis` from the quaternion's components, each an array of one shape
    ``S`` (e.g. rows of a component-major copy, which hot loops read faster than the
    strided components of a state array).  Returns ``(k_0, k_1, k_2)``, each shape ``S``."""
    return 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)


def cross_components(a, b) -> tuple:
    """Cross product ``a x b`` of vectors given as component sequences ``(a_0, a_1, a_2)``
    and ``(b_0, b_1, b_2)`` (arrays or scalars broadcasting to one shape ``S``), written out:
    the same values as :func:`numpy.cross`, with no interleaved (..., 3) arrays.
    Returns ``(c_0, c_1, c_2)``, each shape ``S``."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


def euler_to_quat(euler: np.ndarray) -> np.ndarray:
    """Unit quaternion from ZYX Euler angles ``[roll, pitch, yaw]`` (rad),
    shape ``(..., 3)`` -> ``(..., 4)`` (Fossen 2021 eq. 2.84)."""
    e = np.asarray(euler, dtype=float)
    cr, sr = np.cos(e[..., 0] / 2), np.sin(e[..., 0] / 2)
    cp, sp = np.cos(e[..., 1] / 2), np.sin(e[..., 1] / 2)
    cy, sy = np.cos(e[..., 2] / 2), np.sin(e[..., 2] / 2)
    q = np.stack(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ],
        axis=-1,
    )
    return quat_normalize(q)


def quat_to_euler(q: np.ndarray) -> np.ndarray:
    """ZYX Euler angles ``[roll, pitch, yaw]`` (rad) from a unit quaternion.

    Roll and yaw are in (-pi, pi], pitch in [-pi/2, pi/2].  At pitch = +-90 deg
    the split between roll and yaw is not unique (gimbal lock of the *angles*;
    the quaternion itself has no singularity): there roll is set to 0.
    Shape ``(..., 4)`` -> ``(..., 3)``.
    """
    q = np.asarray(q, dtype=float)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    s = np.clip(2 * (w * y - x * z), -1.0, 1.0)
    pitch = np.arcsin(s)
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    lock = np.abs(s) > 1 - 1e-12
    if np.any(lock):
        # At the lock only yaw - sign(s) roll is defined; put it all in yaw.
        yaw = np.where(lock, -np.sign(s) * 2 * np.arctan2(x, w), yaw)
        roll = np.where(lock, 0.0, roll)
    return np.stack([roll, pitch, yaw], axis=-1)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b``, shapes ``(..., 4)``."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def attitude_error_angle(q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """Angle (rad, in [0, pi]) of the rotation taking attitude ``q_b`` to ``q_a``;
    the attitude error used in every RMSE.  Shapes ``(..., 4)`` -> ``(...)``."""
    # 2 atan2(|vec(q_a^* q_b)|, |scalar(q_a^* q_b)|): well conditioned for small angles,
    # unlike 2 arccos(|q_a . q_b|), whose round-off floor is ~3e-8 rad
    d = quat_multiply(quat_conjugate(q_a), q_b)
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))


def unwrap_angles(angles: np.ndarray, axis: int = 0) -> np.ndarray:
    """Continuous angle history (``numpy.unwrap`` along ``axis``).  Missing (NaN)
    samples stay NaN and are skipped: each series is unwrapped over its valid samples."""
    a = np.asarray(angles, dtype=float)
    ok = np.isfinite(a)
    if ok.all():
        return np.unwrap(a, axis=axis)
    out = np.moveaxis(a.copy(), axis, -1)
    flat = out.reshape(-1, out.shape[-1])
    for row in flat:
        sel = np.isfinite(row)
        if sel.any():
            row[sel] = np.unwrap(row[sel])
    return np.moveaxis(flat.reshape(out.shape), -1, axis)


def wrap(a):
    """Angles wrapped to (-pi, pi].

    ``(a + pi) % 2 pi - pi``, with the remainder (numpy's slowest element-wise step here)
    taken only where ``a + pi`` is outside [0, 2 pi): inside, the remainder of a value by
    a larger positive one is the value itself, exactly, so the result is the same to the
    last bit (NaN stays NaN)."""
    t = np.asarray(a) + np.pi
    if t.ndim == 0:
        return t % (2 * np.pi) - np.pi
    far = ~((t >= 0) & (t < 2 * np.pi))
    if far.any():
        t[far] = t[far] % (2 * np.pi)
    t -= np.pi
    return t


def rotation_vector_error(q_meas: np.ndarray, q_pred: np.ndarray) -> np.ndarray:
    """Rotation vector (rad, body frame of the measurement) of ``q_meas^-1 (x) q_pred``.

    Shapes broadcast, (..., 4) -> (..., 3); its norm is the attitude error angle.
    Smooth at zero error (unlike the angle itself), so it suits least squares."""
    dq = quat_multiply(quat_conjugate(q_meas), q_pred)
    sgn = np.where(dq[..., :1] < 0, -1.0, 1.0)
    v = dq[..., 1:] * sgn
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    w = np.abs(dq[..., :1])
    ang = 2.0 * np.arctan2(s, w)
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(s > 1e-12, ang / np.where(s > 1e-12, s, 1.0), 2.0)
    return v * factor
