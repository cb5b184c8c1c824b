"""First-order lag of logged Euler angles (attitude filters), estimated from the gyro.

An attitude filter (an EKF or a complementary filter in an autopilot) reports roll,
pitch (and yaw) that trail the true motion.  uvsim models this as a first-order lag
with time constant ``tau``, in the discrete form used on each logged sample::

    y_k = a_k y_(k-1) + (1 - a_k) x_k,      a_k = exp(-(t_k - t_(k-1)) / tau)

(``x`` the true angle, ``y`` the reported one; the exact response of
``tau dy/dt = x - y`` to an ``x`` that steps at each sample).  :func:`first_order_lag`
applies it; the measurement model of the attitude uses it when ``attitude_lag`` is set
(:mod:`uvsim.measurements`).

:func:`estimate_attitude_lag` estimates ``tau`` from the runs themselves, without a
vehicle model: the gyro measures the body rates without lag, so the Euler angles
integrated from it (Fossen 2021 eq. 2.29, ``theta_dot = T(theta) omega``, with the
logged angles in ``T``), lagged by ``tau``, must match the logged angles up to a
constant offset and a linear drift per run and angle (the integration constant and
the gyro bias).  The ``tau`` that minimizes the sum of squared differences over all
runs and angles is found by a bounded scalar search (:func:`scipy.optimize.minimize_scalar`).
The angles in ``T(theta)`` are themselves lagged; a second pass uses the logged angles
with the first estimate's lag undone (``x = y + tau dy/dt``, ``dy/dt`` the lagged
gyro-derived angle rate), which matters when the vehicle turns fast.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.estimation.noise import sample_kind
from uvsim.kinematics import unwrap_angles

#: Largest lag searched, s.
MAX_LAG_S = 1.0
#: An estimated lag shorter than this many sample intervals is not used: the logged inputs'
#: zero-order hold and the sampling alone make the angles trail by about half an interval.
LAG_MIN_SAMPLES = 1.5
#: Relative tolerance for "uniform" time steps (lfilter path).
UNIFORM_RTOL = 1e-6


def uniform_steps(dt: np.ndarray) -> bool:
    """True when the time steps ``dt`` are uniform to :data:`UNIFORM_RTOL` (the one-coefficient
    filter of :func:`first_order_lag`)."""
    return bool(dt.size) and bool(np.ptp(dt) <= UNIFORM_RTOL * max(float(np.median(dt)), 1e-300))


def first_order_lag(t: np.ndarray, x: np.ndarray, tau: float, y0=None) -> np.ndarray:
    """Lagged signal (module docstring) of ``x`` (..., n, k) at times ``t`` (n,), started
    at ``y0`` (..., k) (default ``x`` at the first sample)."""
    x = np.asarray(x, float)
    y0 = x[..., 0, :] if y0 is None else np.broadcast_to(np.asarray(y0, float), x[..., 0, :].shape)
    if tau <= 0 or x.shape[-2] < 2:
        return x.copy()
    dt = np.diff(np.asarray(t, float))
    out = np.empty_like(x)
    out[..., 0, :] = y0
    if uniform_steps(dt):
        a = float(np.exp(-dt[0] / tau))
        from scipy.signal import lfilter  # here, not at import (0.6 s of every command's start)

        out[..., 1:, :], _ = lfilter([1.0 - a], [1.0, -a], x[..., 1:, :], axis=-2, zi=(a * y0)[..., None, :])
        return out
    a = np.exp(-dt / tau)
    for i in range(1, x.shape[-2]):
        out[..., i, :] = a[i - 1] * out[..., i - 1, :] + (1.0 - a[i - 1]) * x[..., i, :]
    return out


def body_rates_to_euler_rates(euler: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """ZYX Euler-angle rates (n, 3) from body rates ``omega`` (n, 3) at angles
    ``euler`` (n, 3) (Fossen 2021 eq. 2.29)."""
    phi, theta = euler[:, 0], euler[:, 1]
    p, q, r = omega.T
    sp, cp, ct, tt = np.sin(phi), np.cos(phi), np.cos(theta), np.tan(theta)
    return np.stack([p + sp * tt * q + cp * tt * r, cp * q - sp * r, (sp * q + cp * r) / ct], 1)


def _pieces(run, tau: float = 0.0):
    """(t, logged angles (n, k), native (n, k), gyro-integrated angles (n, k), angle
    indices) of one run, or None when it logs no Euler angle or no full gyro; ``tau``:
    a lag to undo in the angles used for ``T(theta)``."""
    if not (run.has_euler and run.has_rates):
        return None
    t = run.t
    w = run.velocity[:, 3:]
    ok = np.isfinite(w).all(axis=1)
    if ok.sum() < 10:
        return None
    mask = run.euler_mask
    e = unwrap_angles(run.euler)
    e_full = np.where(np.isfinite(e), e, 0.0)  # a missing yaw does not enter roll/pitch rates (small angles)
    tk = t[ok]
    edot = body_rates_to_euler_rates(e_full[ok], w[ok])
    if tau > 0:  # undo the lag of the angles in T(theta): x = y + tau dy/dt
        e_full = e_full.copy()
        e_full[ok] = e_full[ok] + tau * first_order_lag(tk, edot, tau)
        edot = body_rates_to_euler_rates(e_full[ok], w[ok])
    g = np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * (edot[1:] + edot[:-1]) * np.diff(tk)[:, None], 0)])
    idx = [j for j in range(3) if mask[j]]
    native = np.stack([sample_kind(tk, e[ok, j]).native & np.isfinite(e[ok, j]) for j in idx], 1)
    return tk, e[ok][:, idx], native, g[:, idx], idx


def _sse(tau, pieces) -> float:
    total = 0.0
    for tk, L, native, G, _ in pieces:
        Gl = first_order_lag(tk, G, tau)
        for j in range(L.shape[1]):
            m = native[:, j]
            if m.sum() < 5:
                continue
            d = L[m, j] - Gl[m, j]
            A = np.stack([np.ones(m.sum()), tk[m] - tk[0]], 1)
            coef, *_ = np.linalg.lstsq(A, d, rcond=None)
            r = d - A @ coef
            total += float(r @ r)
    return total


def estimate_attitude_lag(runs, *, max_lag: float = MAX_LAG_S) -> dict:
    """Time constant of the attitude filter that logged ``runs`` (module docstring).

    Returns dict with ``tau`` (s; None when no run logs both Euler angles and gyro rates),
    ``per_run`` ({run name: tau}), ``rms_without`` and ``rms_with`` (rad, RMS of the
    difference between logged and gyro-integrated angles, offsets and drifts removed,
    without and with the lag), ``runs_used``.
    """
    if not max_lag > 0:
        raise CalibrationError(f"max_lag must be > 0, got {max_lag!r}")
    def best(pcs):
        from scipy.optimize import minimize_scalar  # here, not at import (0.4 s of every command's start)

        res = minimize_scalar(lambda tau: _sse(tau, pcs), bounds=(0.0, max_lag), method="bounded",
                              options={"xatol": 1e-4})
        return float(res.x)

    tau = 0.0
    for _ in range(2):  # second pass: the angles in T(theta) with the first estimate's lag undone
        pieces, names = [], []
        for r in runs:
            pc = _pieces(r, tau)
            if pc is not None:
                pieces.append(pc)
                names.append(r.name)
        if not pieces:
            return {"tau": None, "per_run": {}, "rms_without": None, "rms_with": None, "runs_used": []}
        tau = best(pieces)
    n = sum(int(p[2].sum()) for p in pieces)
    return {"tau": tau, "per_run": {nm: best([pc]) for nm, pc in zip(names, pieces)},
            "rms_without": float(np.sqrt(_sse(0.0, pieces) / n)), "rms_with": float(np.sqrt(_sse(tau, pieces) / n)),
            "runs_used": names}


def lag_time_constant(value, *, expected: str = "a time constant >= 0 s") -> float:
    """``value`` as a lag time constant in s (finite, >= 0), else :class:`CalibrationError`
    naming ``attitude_lag``, what was ``expected`` and what was given."""
    try:
        tau = float(value)
    except (TypeError, ValueError):
        tau = float("nan")
    if not (np.isfinite(tau) and tau >= 0):
        raise CalibrationError(f"attitude_lag: expected {expected}, got {value!r}")
    return tau


def attitude_lag_setting(runs, setting="auto") -> dict:
    """The attitude lag a fit uses (shared by calibration and diagnosis).

    ``setting``: ``"auto"`` (estimated from the runs' gyro and logged angles by
    :func:`estimate_attitude_lag`, used when longer than :data:`LAG_MIN_SAMPLES` sample
    intervals, else 0) or a time constant in s (0: none).  Returns a dict with ``tau`` (s,
    the value to use) and ``source``; with ``"auto"`` also the estimate's fields and
    ``estimated_tau``."""
    if isinstance(setting, str):
        if setting != "auto":
            raise CalibrationError(f"attitude_lag {setting!r}: expected 'auto' or a time constant in s")
        est = estimate_attitude_lag(runs)
        dt = float(np.median([np.median(np.diff(r.t)) for r in runs]))
        tau = est["tau"] if est["tau"] is not None and est["tau"] > LAG_MIN_SAMPLES * dt else 0.0
        return {**est, "tau": float(tau), "estimated_tau": est["tau"],
                "source": "estimated from the gyro and the logged angles"}
    tau = lag_time_constant(setting, expected="a time constant >= 0 s or 'auto'")
    longest = max((float(r.t[-1] - r.t[0]) for r in runs), default=float("inf"))
    if tau > longest:  # the logged angles would barely move over any run: a unit slip (ms?) or a typo
        raise CalibrationError(f"attitude_lag {setting!r}: a filter lag of {tau:g} s is longer than the longest run "
                               f"({longest:.3g} s), so the logged angles would hardly follow the motion; expected "
                               "the attitude filter's time constant in s (typically 0.01-1 s), 'auto' or 0")
    return {"tau": tau, "source": "given"}
