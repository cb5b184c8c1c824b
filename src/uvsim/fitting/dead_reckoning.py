"""The horizontal track of a run that logs no x/y, dead-reckoned from its attitude and DVL.

Most ROV logs have no horizontal position (no USBL, no GPS under water) but have the attitude
and the DVL's velocity over ground.  A model term that reads the horizontal position (a tether's
pull towards its anchor, :class:`uvsim.effects.tether.Tether`) then needs one, and a window of a
closed-loop log needs the position the vehicle had at the window's start, not the run's start.
Integrating the DVL's body velocity rotated by the logged attitude is what an ROV's own navigation
does without a position fix (DVL dead reckoning: Fossen 2021 sec. 13.1 "strapdown navigation";
Kinsey, Eustice & Whitcomb 2006, "A survey of underwater vehicle navigation", IFAC MCMC, sec. 3):

    p_xy(t) = p_xy(t_0) + int_{t_0}^{t} [R(roll, pitch, yaw) v_DVL]_xy dt

from the run's start (``p_xy(t_0)`` = 0, where a free simulation of the whole run starts it,
:func:`uvsim.initial_state.initial_state_from_run`), trapezoidal between samples, the DVL's drop-outs
bridged linearly in time (a drop-out of a few seconds at a few dm/s: a few dm of track, below the
position prior of a model reference, :data:`uvsim.fitting.nodes.PRIOR_SIGMA`).  Its error grows
with the heading's (an attitude filter without a compass drifts with the gyro bias: 0.3 deg/s
over a 40 s run is 12 deg, 20 % of the distance run) and the DVL's; it is a reference with a loose
prior in a fit and a window's start in a prediction, not a measurement.
"""
from __future__ import annotations

import numpy as np

from uvsim.kinematics import euler_to_quat, quat_to_rotation, unwrap_angles

#: Least share of a run's samples with a logged u and v for a track: fewer and the bridged
#: drop-outs would be the track.
MIN_VELOCITY_SHARE = 0.2


def dead_reckoned_xy(run) -> np.ndarray | None:
    """North and east (n, 2) of ``run`` dead-reckoned from its logged attitude and body velocity
    (module docstring), from 0 at its first sample; None when the run logs x or y itself, lacks
    the whole attitude, or logs u and v in fewer than :data:`MIN_VELOCITY_SHARE` of its samples."""
    pos = run.position
    if np.isfinite(pos[:, :2]).any() or not run.has_full_attitude:
        return None
    t = np.asarray(run.t, float)
    vel = np.asarray(run.velocity[:, :3], float)
    ok = np.isfinite(vel[:, 0]) & np.isfinite(vel[:, 1])
    if t.size < 2 or ok.sum() < max(2, MIN_VELOCITY_SHARE * t.size):
        return None
    vb = np.empty((t.size, 3))
    for j in range(3):
        f = np.isfinite(vel[:, j])
        vb[:, j] = np.interp(t, t[f], vel[f, j]) if f.sum() >= 2 else 0.0
    e = unwrap_angles(run.euler)
    if not np.isfinite(e).all():
        for j in range(3):
            f = np.isfinite(e[:, j])
            if f.sum() < 2:
                return None
            e[:, j] = np.interp(t, t[f], e[f, j])
    R = quat_to_rotation(euler_to_quat(e))
    vn = np.einsum("nij,nj->ni", R, vb)[:, :2]
    out = np.zeros((t.size, 2))
    out[1:] = np.cumsum(0.5 * (vn[1:] + vn[:-1]) * np.diff(t)[:, None], axis=0)
    return out
