"""Velocities and accelerations from logged positions / attitudes.

Where a run does not log body velocities, rates or accelerations, they are
obtained by differentiating the *smoothed* signal with a Savitzky-Golay filter
(:func:`scipy.signal.savgol_filter` with ``deriv=1`` or ``2``): a local
least-squares polynomial of order ``polyorder`` over a window of ``window_s``
seconds is fitted around each sample and differentiated analytically, which
smooths and differentiates in one step (Savitzky & Golay 1964).  On stamps that
are not uniform (a topside log's clock jitter) the local fits use each window's
actual time offsets (:mod:`uvsim.estimation.savgol`); nothing is resampled.
Missing samples (NaN) raise :class:`uvsim.errors.CalibrationError`: a derivative
is not taken across a gap.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.estimation.savgol import is_uniform, savgol_on_stamps
from uvsim.kinematics import quat_to_rotation

#: Default smoothing window (s) and polynomial order.  0.5 s at 50 Hz is 25
#: samples: long against 2-5 mm motion-capture noise, short against the
#: ~1-2 s time constants of the tank runs.
DEFAULT_WINDOW_S = 0.5
DEFAULT_POLYORDER = 3


def smooth_derivative(t: np.ndarray, x: np.ndarray, *, deriv: int = 1, window_s: float = DEFAULT_WINDOW_S,
                      polyorder: int = DEFAULT_POLYORDER, what: str = "signal") -> np.ndarray:
    """``deriv``-th time derivative of ``x`` (n,) or (n, k) sampled at ``t`` (n,).

    Savitzky-Golay filter over ``window_s`` seconds (odd number of samples, at
    least ``polyorder + 2``), ``mode="interp"`` at the ends."""
    x = np.asarray(x, float)
    if not np.all(np.isfinite(x)):
        raise CalibrationError(f"{what}: has missing (NaN) samples; cannot differentiate across gaps")
    t = np.asarray(t, float)
    d = np.diff(t)
    if d.size and not np.all(d > 0):
        raise CalibrationError(f"{what}: time stamps do not increase; cannot differentiate")
    dt = float(np.median(d)) if d.size else 1.0
    n = x.shape[0]
    win = int(round(window_s / dt)) | 1
    win = max(win, polyorder + 2 + (polyorder + 2 + 1) % 2)
    if win > n:
        win = n if n % 2 else n - 1
    if win <= polyorder:
        raise CalibrationError(f"{what}: {n} samples are too few for a degree-{polyorder} Savitzky-Golay derivative")
    if not is_uniform(t):  # jittered stamps: the local fits on the actual time offsets
        return savgol_on_stamps(t, x, win, polyorder, deriv)
    from scipy.signal import savgol_filter  # here, not at import: scipy.signal costs 0.6 s of every command's start

    return savgol_filter(x, win, polyorder, deriv=deriv, delta=dt, axis=0, mode="interp")


def euler_rates_to_body(euler: np.ndarray, euler_dot: np.ndarray) -> np.ndarray:
    """Body rates p, q, r (n, 3) from ZYX Euler angles and their derivatives
    (Fossen 2021 eq. 2.28-2.29, inverse of T(Theta))."""
    phi, th = euler[:, 0], euler[:, 1]
    dphi, dth, dpsi = euler_dot[:, 0], euler_dot[:, 1], euler_dot[:, 2]
    p = dphi - dpsi * np.sin(th)
    q = dth * np.cos(phi) + dpsi * np.cos(th) * np.sin(phi)
    r = -dth * np.sin(phi) + dpsi * np.cos(th) * np.cos(phi)
    return np.stack([p, q, r], -1)


def body_velocity(run, *, window_s: float = DEFAULT_WINDOW_S, polyorder: int = DEFAULT_POLYORDER) -> np.ndarray:
    """Body velocities and rates (n, 6) of a run: the logged columns where
    present, else derivatives of the smoothed logged position (rotated into the
    body frame with the logged attitude, level if none) and Euler angles.  NaN
    where neither is available (e.g. u, v of a depth-only run)."""
    out = run.velocity.copy()
    t = run.t
    q = run.quaternion if run.has_attitude else np.tile([1.0, 0, 0, 0], (len(t), 1))
    if run.has_position and not np.isfinite(out[:, :3]).all():
        pos = run.position
        have = np.isfinite(pos).any(axis=0)
        vned = np.zeros_like(pos)
        for j in np.flatnonzero(have):
            vned[:, j] = smooth_derivative(t, pos[:, j], window_s=window_s, polyorder=polyorder,
                                           what=f"{run.name}: column {'xyz'[j]}")
        R = quat_to_rotation(q)
        vb = np.einsum("nji,nj->ni", R, vned)  # R^T v_ned
        # a body axis is known only if every NED axis it depends on was logged
        dep = np.abs(R) > 1e-6
        known = ~np.any(dep & ~have[None, :, None], axis=1)  # (n, 3): body axis i needs have[j] wherever R[j,i] != 0
        vb = np.where(known, vb, np.nan)
        out[:, :3] = np.where(np.isfinite(out[:, :3]), out[:, :3], vb)
    if run.has_attitude and not np.isfinite(out[:, 3:]).all():
        e = np.unwrap(run.euler, axis=0)
        ed = smooth_derivative(t, e, window_s=window_s, polyorder=polyorder, what=f"{run.name}: attitude")
        w = euler_rates_to_body(e, ed)
        out[:, 3:] = np.where(np.isfinite(out[:, 3:]), out[:, 3:], w)
    return out


def body_acceleration(run, nu: np.ndarray | None = None, *, window_s: float = DEFAULT_WINDOW_S,
                      polyorder: int = DEFAULT_POLYORDER) -> np.ndarray:
    """d(nu)/dt (n, 6) by Savitzky-Golay differentiation of the body velocities
    (logged or from :func:`body_velocity`); NaN columns where nu is unknown."""
    nu = body_velocity(run, window_s=window_s, polyorder=polyorder) if nu is None else nu
    out = np.full_like(nu, np.nan)
    for j in range(6):
        if np.isfinite(nu[:, j]).all():
            out[:, j] = smooth_derivative(run.t, nu[:, j], window_s=window_s, polyorder=polyorder,
                                          what=f"{run.name}: velocity {j}")
    return out


#: Window (s) and order of the fit behind the initial-velocity estimate: at the
#: first sample the Savitzky-Golay fit is one-sided, so it uses a longer window and
#: a quadratic to keep the noise of the estimated velocity down.
INITIAL_WINDOW_S, INITIAL_POLYORDER = 1.0, 2


def initial_velocity_estimate(run, *, window_s: float = INITIAL_WINDOW_S,
                              polyorder: int = INITIAL_POLYORDER) -> np.ndarray:
    """nu at the first sample (6,) from :func:`body_velocity` (NaN where unknown)."""
    try:
        return body_velocity(run, window_s=window_s, polyorder=polyorder)[0]
    except CalibrationError:
        return np.full(6, np.nan)
