"""Window-start ("node") states estimated from a log, and which parts of them a fit frees.

A windowed fit (:mod:`uvsim.fitting.objective`) restarts the simulation at the start
of every window from a node state.  Its reference value comes from the log where the
log determines it, else from a simulation of the whole run with the current model:

* position: the logged axes by a local quadratic least-squares fit over
  ``+-NODE_HALF_WINDOW_S`` around the node time (one-sided at the ends); a run that
  logs only the depth of a pressure sensor gets ``z = depth - (R r_p)_z``; a run without
  x/y but with the attitude and a DVL their dead-reckoned track
  (:mod:`uvsim.fitting.dead_reckoning`, with the loose "model" prior);
* attitude: logged Euler angles (unwrapped) the same way; missing angles from the
  reference simulation;
* velocities: logged (DVL, gyro) values smoothed the same way; else the slope of the
  local fit of the position (rotated into the body frame) and of the Euler angles
  (Fossen 2021 eq. 2.28-2.29); else the reference simulation.

Every node component is a nuisance variable of the fit (the tangent perturbation
``[dp (3, NED), dtheta (3, body rotation vector), dnu (6)]``) with a prior centred on
the reference whose standard deviation says how far the reference can be trusted
(:data:`PRIOR_SIGMA`): the measurements of the window pin the node down (multiple
shooting, Bock & Plitt 1984).  Fixing the pose at the smoothed measurement instead (a
plain windowed prediction) was tried and biased the added masses by 3 % on the shipped
tank data: a 1.4 mrad heading error of a smoothed node grows into millimetres of
position error along a 2 s window, the size of the noise.
(:data:`PRIOR_SIGMA`).
"""
from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np

from uvsim.estimation.derivatives import euler_rates_to_body
from uvsim.fitting.dead_reckoning import dead_reckoned_xy
from uvsim.kinematics import euler_to_quat, quat_to_euler, quat_to_rotation, unwrap_angles

#: Half-width (s) of the local quadratic fits at node times.  0.3 s at 50 Hz is 31 samples
#: (noise of the fitted value ~ sigma / 4, of the slope ~ sigma / 0.1 s); short against the
#: 1-3 s time constants of an ROV.
NODE_HALF_WINDOW_S = 0.3
#: ... widened for a channel logged slower, to this many of its own sample intervals either side,
#: so that the fit has the 5 samples it needs (:func:`local_fit`'s ``min_samples``): a 5 Hz DVL or
#: a 5 Hz topside log gets +-0.5 s.  At +-0.3 s such a channel held 3 samples, every local fit was
#: empty, and the node took the whole-run simulation's value instead (field logs: every DVL
#: velocity, and on 5 Hz logs every angle and rate, from a simulation that had lost the heading).
NODE_SPAN_INTERVALS = 2.5
#: Prior standard deviations of free node components, by how the reference was obtained:
#: "measured" (a sensor of that quantity: DVL, gyro, logged angle, depth; a few noise
#: sigmas of a smoothed value), "derived" (slope of a smoothed position/angle), "model"
#: (the reference simulation: loose).  Units m, rad, m/s, rad/s.
PRIOR_SIGMA = {
    "measured": np.array([0.01, 0.01, 0.01, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.02]),
    "derived": np.array([0.05, 0.05, 0.05, 0.1, 0.1, 0.1, 0.05, 0.05, 0.05, 0.1, 0.1, 0.1]),
    "model": np.array([1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]),
}
TANGENT_NAMES = ("x", "y", "z", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r")


#: Local fits kept (:func:`local_fit`): a diagnosis builds the same runs' windows for each of its
#: fits; on the timing dataset these fits took 0.7 s of its 15 (docs/records/performance_kernel.md).
LOCAL_FIT_CACHE = 4096
_local_fits: OrderedDict = OrderedDict()
_local_fits_lock = threading.Lock()  # fits run from several threads share it safely


def local_fit(t: np.ndarray, x: np.ndarray, t0: np.ndarray, half: float, *, min_samples: int = 5):
    """Value and slope at times ``t0`` (W,) of local quadratic least-squares fits of
    ``x`` (n,) (NaN skipped) over ``[t0 - half, t0 + half]`` (shifted inside the run at
    its ends).  Returns (value (W,), slope (W,)); NaN where fewer than ``min_samples``.
    The answers of the last :data:`LOCAL_FIT_CACHE` calls are kept, keyed by a digest of the
    inputs' bytes, and returned as copies."""
    t, x, t0 = (np.ascontiguousarray(a, dtype=float) for a in (t, x, t0))
    h = hashlib.blake2b(digest_size=20)
    for a in (t, x, t0, np.array([half, min_samples], float)):
        h.update(np.array(a.shape, np.int64).tobytes())
        h.update(a.tobytes())
    key = h.digest()
    with _local_fits_lock:
        hit = _local_fits.get(key)
        if hit is not None:
            _local_fits.move_to_end(key)
    if hit is None:
        hit = _local_fit(t, x, t0, half, min_samples)
        with _local_fits_lock:
            _local_fits[key] = hit
            while len(_local_fits) > LOCAL_FIT_CACHE:
                _local_fits.popitem(last=False)
    return hit[0].copy(), hit[1].copy()


def half_width(t: np.ndarray, x: np.ndarray, least: float = NODE_HALF_WINDOW_S,
               intervals: float = NODE_SPAN_INTERVALS) -> float:
    """A local fit's half-width (s) for channel ``x`` (n,) at times ``t``: ``least`` (the nodes':
    :data:`NODE_HALF_WINDOW_S`), or ``intervals`` (:data:`NODE_SPAN_INTERVALS`) of the channel's median
    interval between valid samples when longer."""
    tv = t[np.isfinite(x)]
    if tv.size < 2:
        return least
    return max(least, intervals * float(np.median(np.diff(tv))))


def _local_fit(t, x, t0, half: float, min_samples: int):
    ok = np.isfinite(x)
    val = np.full(t0.size, np.nan)
    slope = np.full(t0.size, np.nan)
    if ok.sum() < min_samples:
        return val, slope
    tv, xv = t[ok], x[ok]
    span = 2 * half
    for i, c in enumerate(t0):
        lo = min(max(c - half, tv[0]), max(tv[-1] - span, tv[0]))
        sel = (tv >= lo - 1e-12) & (tv <= lo + span + 1e-12)
        if sel.sum() < min_samples:
            continue
        dt = tv[sel] - c
        A = np.stack([np.ones_like(dt), dt, dt * dt], 1)
        coef, *_ = np.linalg.lstsq(A, xv[sel], rcond=None)
        val[i], slope[i] = coef[0], coef[1]
    return val, slope


class NodeModel:
    """Reference node states of one run and which components are free.

    Parameters
    ----------
    run : :class:`uvsim.logs.Run`.
    meas : its :class:`uvsim.measurements.RunMeasurements`.

    Attributes
    ----------
    free : (12,) bool, free tangent components (module docstring).
    """

    def __init__(self, run, meas):
        self.run, self.meas = run, meas
        self.free = np.ones(12, bool)

    def references(self, idx: np.ndarray, ref_states: np.ndarray, *, xy_track: bool = True
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Reference states (W, 13) at sample rows ``idx`` (W,) and the prior standard
        deviation (W, 12) of each tangent component.  ``ref_states`` (n, 13+) is a
        simulation of the whole run with the current model (used where the log gives
        nothing).  ``xy_track``: x/y not logged are the dead-reckoned track's (when some term
        reads them; else they only shift a window, and the reference simulation's are kept)."""
        run = self.run
        t = run.t
        t0 = t[idx]
        W = idx.size
        ref = ref_states[idx, :13].copy()
        kind = np.full((W, 12), "model", dtype=object)
        e_ref = quat_to_euler(ref[:, 3:7])
        euler = e_ref.copy()
        if run.has_attitude:
            e_log = unwrap_angles(run.euler)
            lag = float(getattr(self.meas, "attitude_lag", 0.0))
            for j in np.flatnonzero(run.euler_mask):
                v, s = local_fit(t, e_log[:, j], t0, half_width(t, e_log[:, j]))
                if lag > 0:  # a lagged attitude filter: x = y + tau dy/dt undoes the lag
                    v = v + lag * s
                ok = np.isfinite(v)
                euler[ok, j] = v[ok]
                kind[ok, 3 + j] = "measured"
        q = euler_to_quat(euler)
        ref[:, 3:7] = q
        R = quat_to_rotation(q)
        pos = run.position
        vned = np.full((W, 3), np.nan)
        for j in range(3):
            if np.isfinite(pos[:, j]).any():
                v, s = local_fit(t, pos[:, j], t0, half_width(t, pos[:, j]))
                ok = np.isfinite(v)
                ref[ok, j] = v[ok]
                kind[ok, j] = "measured"
                vned[:, j] = s
        if xy_track and kind[0, 0] == "model" and kind[0, 1] == "model":
            # no x/y logged: the track dead-reckoned from the attitude and the DVL, where the whole
            # run's simulation of a closed-loop log has lost the heading (uvsim.fitting.dead_reckoning)
            track = dead_reckoned_xy(run)
            if track is not None:
                ref[:, :2] = track[idx]
        if run.has_depth and kind[0, 2] != "measured":
            d, _ = local_fit(t, run.depth, t0, half_width(t, run.depth))
            r_p = self.meas.sensors.get("pressure")
            off = R[:, 2, :] @ r_p if r_p is not None else 0.0
            ok = np.isfinite(d)
            ref[ok, 2] = (d - off)[ok]
            kind[ok, 2] = "measured"
        # velocities: logged (DVL / gyro) > derived from the smoothed pose > the model
        vel = run.velocity
        for j in range(6):
            if np.isfinite(vel[:, j]).any():
                v, _ = local_fit(t, vel[:, j], t0, half_width(t, vel[:, j]))
                ok = np.isfinite(v)
                ref[ok, 7 + j] = v[ok]
                kind[ok, 6 + j] = "measured"
        if np.isfinite(vned).all() and run.has_full_attitude:
            vb = np.einsum("wji,wj->wi", R, vned)
            sel = kind[:, 6:9] == "model"
            ref[:, 7:10] = np.where(sel, vb, ref[:, 7:10])
            kind[:, 6:9] = np.where(sel, "derived", kind[:, 6:9])
        if run.has_full_attitude:
            e_log = unwrap_angles(run.euler)
            slopes = np.stack([local_fit(t, e_log[:, j], t0, half_width(t, e_log[:, j]))[1] for j in range(3)], 1)
            if np.isfinite(slopes).all():
                w = euler_rates_to_body(euler, slopes)
                sel = kind[:, 9:12] == "model"
                ref[:, 10:13] = np.where(sel, w, ref[:, 10:13])
                kind[:, 9:12] = np.where(sel, "derived", kind[:, 9:12])
        sigma = np.empty((W, 12))
        for name, s in PRIOR_SIGMA.items():
            m = kind == name
            sigma[m] = np.broadcast_to(s, (W, 12))[m]
        return ref, sigma
