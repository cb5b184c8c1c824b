"""The initial state of a logged run, estimated from what it measured.

A simulation of a logged run (:func:`uvsim.simulate.simulate_run`, calibration's batches,
the fitting windows, the open-loop predictions) starts from the run's first measured
position, attitude and velocities: the first valid sample, or a quadratic least-squares
fit over its first :data:`INITIAL_WINDOW_S` seconds evaluated at the first sample.  What
the run did not log starts at zero (velocities optionally differentiated from the logged
motion), and a pressure sensor's depth stands in for a missing ``z``.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import SimulationError
from uvsim.kinematics import euler_to_quat, quat_to_rotation, unwrap_angles

INITIAL_VELOCITY_MODES = ("zero", "differentiate")

#: Window (s) over which the initial position and attitude are estimated by a
#: quadratic least-squares fit evaluated at the first sample: a single noisy
#: sample (2-5 mm, 5-10 mrad) as initial state biases a whole 14-s simulation.
INITIAL_WINDOW_S = 0.5


def _initial_value(t: np.ndarray, a: np.ndarray, window_s: float) -> np.ndarray:
    """Per column of ``a`` (n, k): quadratic fit over the valid samples in the first
    ``window_s`` seconds evaluated at ``t[0]`` (>= 5 samples), else the first valid
    value; NaN for columns with no valid sample."""
    out = np.full(a.shape[1], np.nan)
    for j in range(a.shape[1]):
        ok = np.flatnonzero(np.isfinite(a[:, j]))
        if not ok.size:
            continue
        sel = ok[t[ok] <= t[ok[0]] + window_s]
        if window_s > 0 and sel.size >= 5:
            c = np.polyfit(t[sel] - t[0], a[sel, j], 2)
            out[j] = np.polyval(c, 0.0)
        else:
            out[j] = a[ok[0], j]
    return out


def check_initial_window(window_s, duration: float | None = None, where: str = "initial window") -> float:
    """``window_s`` checked: finite, >= 0 and, given the run's ``duration``, not longer than it (the fit
    would silently use the whole run); a SimulationError naming ``where`` otherwise."""
    try:
        w = float(window_s)
    except (TypeError, ValueError):
        w = float("nan")
    if not (np.isfinite(w) and w >= 0):
        raise SimulationError(f"{where} {window_s!r}: expected a finite number of seconds >= 0 (0: the first "
                              "measured sample)")
    if duration is not None and w > duration:
        raise SimulationError(f"{where} {w:g} s is longer than the run ({duration:.3g} s); expected a few tenths "
                              f"of a second at its start (calibration uses {INITIAL_WINDOW_S:g} s), or 0")
    return w


def initial_state_from_run(run, *, initial_velocity: str = "zero", window_s: float = 0.0, sensors=None
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Initial state of a logged run from what it measured (partial initial state).

    Returns ``(pos0 (3,), q0 (4,), nu0 (6,), nu0_known (6,) bool)``.  Position and
    attitude (as unwrapped Euler angles) are the first valid sample (``window_s = 0``,
    the default, as ``uvsim simulate`` does) or a quadratic fit over the first
    ``window_s`` seconds evaluated at the first sample (calibration and diagnosis use
    :data:`INITIAL_WINDOW_S`); axes and angles not logged start at 0 (a run with roll and
    pitch only starts at yaw 0).  Without a logged ``z``, the depth of a pressure sensor
    gives it: ``z = depth - (R r_p)_z`` with ``r_p = sensors["pressure"]`` (default the
    body origin).  Velocities are the first logged sample where present; where absent,
    ``initial_velocity="zero"`` (runs start at rest, seed 000) or ``"differentiate"`` (a
    Savitzky-Golay derivative of the logged motion at the start,
    :mod:`uvsim.estimation.derivatives`)."""
    if initial_velocity not in INITIAL_VELOCITY_MODES:
        raise SimulationError(f"initial_velocity {initial_velocity!r}: expected one of {INITIAL_VELOCITY_MODES}")
    check_initial_window(window_s)
    t = run.t
    pos = _initial_value(t, run.position, window_s)
    pos0 = np.where(np.isfinite(pos), pos, 0.0)
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    if run.has_attitude:
        e = unwrap_angles(run.euler)
        e0 = _initial_value(t, e, window_s)
        q0 = euler_to_quat(np.where(np.isfinite(e0), e0, 0.0))
    if not np.isfinite(pos[2]) and getattr(run, "has_depth", False):
        d0 = _initial_value(t, run.depth[:, None], window_s)[0]
        if np.isfinite(d0):
            r_p = (sensors or {}).get("pressure")
            off = float(quat_to_rotation(q0)[2] @ np.asarray(r_p, float)) if r_p is not None else 0.0
            pos0[2] = d0 - off
    vel = run.velocity
    v0 = vel[0]
    known = np.isfinite(v0)
    nu0 = np.where(known, v0, 0.0)
    if initial_velocity == "differentiate" and not known.all():
        from uvsim.estimation.derivatives import initial_velocity_estimate

        est = initial_velocity_estimate(run)
        nu0 = np.where(known, nu0, np.where(np.isfinite(est), est, 0.0))
    return pos0, q0, nu0, known
