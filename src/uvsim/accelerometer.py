"""The accelerometer's measurement equation: the specific force at a point of the body.

An accelerometer at ``r`` (body frame) measures the specific force, the acceleration of
that point less gravity, in body axes::

    f = v_dot + omega x v + omega_dot x r + omega x (omega x r) - g R^T e_3

(the velocity of a body point, ``v + omega x r``, differentiated in the rotating body frame,
less gravity; ``nu = [v, omega]``, ``nu_dot`` the model's acceleration, ``R^T e_3`` the NED
down axis in body axes; a level vehicle at rest reads ``(0, 0, -g)``).  The measurement
model of the ``acc_x..acc_z`` columns (:mod:`uvsim.measurements`).
"""
from __future__ import annotations

import numpy as np

from uvsim.kinematics import cross_components, down_axis_components


def specific_force(y: np.ndarray, nu_dot: np.ndarray, r_imu: np.ndarray | None, g: float) -> np.ndarray:
    """Accelerometer specific force (..., n, 3) at body point ``r_imu`` (module
    docstring): ``v_dot + omega x v + omega_dot x r + omega x (omega x r) - g R^T e_3``.

    Parameters
    ----------
    y : (..., n, n_y) states (``y[..., 3:7]`` the quaternion, ``y[..., 7:13]`` nu).
    nu_dot : (..., n, 6) accelerations.
    r_imu : (3,) IMU position on the body, or None (the body origin).
    g : gravity, m/s^2.
    """
    c = _components(np.asarray(y, float)[..., 3:13])
    f = _specific_force(c[4:10], _components(nu_dot), down_axis_components(*c[:4]), r_imu, g)
    return np.stack(f, axis=-1)


def _components(a: np.ndarray) -> np.ndarray:
    """``a`` (..., k) as a component-major copy (k, ...): each component contiguous."""
    return np.moveaxis(np.asarray(a, float), -1, 0).copy()


def _specific_force(nu, nu_dot, k, r_imu: np.ndarray | None, g: float) -> tuple:
    """:func:`specific_force` component by component: ``nu`` and ``nu_dot`` are sequences
    of 6 arrays of one shape ``S`` (e.g. (..., n); :func:`_components`), ``k`` the 3
    components of the down axis ``R^T e_3`` (:func:`uvsim.kinematics.down_axis_components`).
    The same operations in the same order as the (..., 3)-array formula, so the same values
    to the last bit, with cross products written out (:func:`uvsim.kinematics.cross_components`).
    Returns the 3 components of the specific force, each shape ``S``."""
    v, w = nu[0:3], nu[3:6]
    vd, wd = nu_dot[0:3], nu_dot[3:6]
    wv = cross_components(w, v)
    f = [vd[i] + wv[i] - g * k[i] for i in range(3)]
    if r_imu is not None and np.any(r_imu):
        r = np.asarray(r_imu, float)
        tangential = cross_components(wd, r)
        centripetal = cross_components(w, cross_components(w, r))
        f = [f[i] + tangential[i] + centripetal[i] for i in range(3)]
    return f
