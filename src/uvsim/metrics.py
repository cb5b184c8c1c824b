"""Residual metrics shared by calibration and diagnosis.

Everything here works on *signals*: a mapping from a signal group to an array
whose last axis holds that group's channels and whose second-to-last axis is
time::

    "position"   (..., n, 3)  x, y, z NED (m)
    "quaternion" (..., n, 4)  body->NED, scalar first
    "velocity"   (..., n, 3)  u, v, w body (m/s)
    "rates"      (..., n, 3)  p, q, r body (rad/s)

A *measured* signal mapping comes from a logged run (:func:`signals_from_run`)
and contains only the groups the run logged, with NaN for absent axes (a
depth-only run has ``position[:, :2]`` all NaN) and for missing samples.  A
*predicted* mapping comes from simulator states (:func:`signals_from_states`)
and is complete; leading batch axes (e.g. one per parameter set) broadcast.
Missing (NaN) measured samples are skipped, never zero-filled.

Metrics (per channel and per group, see :func:`run_metrics`):

* RMSE: ``sqrt(mean(e^2))`` over the valid samples.
* NRMSE: RMSE divided by the range (max - min) of the measured channel, the
  normalization of seed 000 sec. 5 ("RMSE 0.015, normalized RMSE 3.5 %").
* Fit (system identification, Ljung's ``compare``; issue 7):
  ``Fit = 100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` in percent; 100 is a
  perfect fit, 0 is no better than the mean, it is negative when worse.  For a
  group the norms are Frobenius norms over its channels (each channel about its
  own mean).
* ``position_m``: RMSE of the 3-D position error ``sqrt(mean |p - p_hat|^2)``
  over samples where every logged axis is present (only the logged axes count,
  so a depth-only run gives the depth RMSE).
* ``attitude_rad``: RMSE of the attitude error angle
  (:func:`uvsim.kinematics.attitude_error_angle`).

Angles as channels (roll, pitch, yaw) are compared with wrapped differences
(in (-pi, pi]) and their Fit uses the unwrapped measured angle.

For fitting, :func:`residual_components` gives per-group error components
(position and velocity differences, the rotation vector of the attitude error
``q_meas^-1 (x) q_pred``, rate differences) and :func:`normalized_residuals`
turns them into one vector, each group divided by a scale (e.g. a stated noise
level) and multiplied by the square root of a per-group weight, so metres, radians
and rad/s can be summed.  Calibration compares runs through the measurement models
instead (:func:`measurement_metrics`, :mod:`uvsim.measurements`).
"""
from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.kinematics import attitude_error_angle, quat_to_euler
from uvsim.measurements import UNITS, channel_weight, rotation_vector_error, wrap

#: Signal groups and their channel names, in a fixed order.
GROUPS = {
    "position": ("x", "y", "z"),
    "attitude": ("roll", "pitch", "yaw"),
    "velocity": ("u", "v", "w"),
    "rates": ("p", "q", "r"),
}
#: Unit of each group (for report keys such as ``position_m``).
GROUP_UNITS = {"position": "m", "attitude": "rad", "velocity": "mps", "rates": "radps"}
_SIGNAL_KEY = {"position": "position", "attitude": "quaternion", "velocity": "velocity", "rates": "rates"}


# ----------------------------------------------------------------------------- signal extraction
def signals_from_run(run) -> dict[str, np.ndarray]:
    """Measured signals of a :class:`uvsim.logs.Run` (only the groups it logged).

    Returns
    -------
    dict with some of "position" (n, 3), "quaternion" (n, 4), "velocity" (n, 3),
    "rates" (n, 3); NaN marks absent axes and missing samples.
    """
    out: dict[str, np.ndarray] = {}
    groups = run.signals()
    if "position" in groups:
        out["position"] = run.position
    if "attitude" in groups:
        out["quaternion"] = run.quaternion
    vel = run.velocity
    if "velocity" in groups:
        out["velocity"] = vel[:, :3]
    if "rates" in groups:
        out["rates"] = vel[:, 3:]
    return out


def signals_from_states(y: np.ndarray) -> dict[str, np.ndarray]:
    """Predicted signals from simulator states ``y`` (..., n, n_y) (columns as in
    :mod:`uvsim.model`: position 0:3, quaternion 3:7, nu 7:13)."""
    y = np.asarray(y)
    return {
        "position": y[..., 0:3],
        "quaternion": y[..., 3:7],
        "velocity": y[..., 7:10],
        "rates": y[..., 10:13],
    }


def present_groups(measured: Mapping[str, np.ndarray]) -> list[str]:
    """Signal groups (position, attitude, velocity, rates) present in ``measured``."""
    return [g for g in GROUPS if _SIGNAL_KEY[g] in measured]


def channel_mask(measured: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per group, which channels are logged at all: bool array (k,)."""
    out = {}
    for g in present_groups(measured):
        a = measured[_SIGNAL_KEY[g]]
        if g == "attitude":
            out[g] = np.full(3, bool(np.isfinite(a).all(axis=-1).any()))
        else:
            out[g] = np.isfinite(a).any(axis=-2)
    return out


# ----------------------------------------------------------------------------- residual components
def residual_components(measured: Mapping[str, np.ndarray],
                        predicted: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Error components, per group present in ``measured``.

    Returns
    -------
    dict group -> array (..., n, 3): ``measured - predicted`` for position,
    velocity and rates; the attitude-error rotation vector
    (:func:`rotation_vector_error`) for attitude.  NaN where the measurement is
    missing (and where the prediction is non-finite).
    """
    out = {}
    for g in present_groups(measured):
        key = _SIGNAL_KEY[g]
        m = np.asarray(measured[key])
        p = np.asarray(predicted[key])
        if g == "attitude":
            out[g] = rotation_vector_error(m, p)
        else:
            out[g] = m - p
    return out


# ----------------------------------------------------------------------------- scalar metrics
def rmse(err: np.ndarray, axis=None) -> np.ndarray:
    """Root mean square of ``err`` over non-NaN samples (NaN if none)."""
    err = np.asarray(err, float)
    ok = np.isfinite(err)
    n = ok.sum(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(np.where(ok, err * err, 0.0).sum(axis=axis) / n)


def nrmse(y: np.ndarray, y_hat: np.ndarray) -> float:
    """RMSE / (max - min of the measured ``y``) over samples where both are finite."""
    y, y_hat = np.asarray(y, float), np.asarray(y_hat, float)
    ok = np.isfinite(y) & np.isfinite(y_hat)
    if not ok.any():
        return float("nan")
    span = float(np.ptp(y[ok]))
    r = float(rmse(y[ok] - y_hat[ok]))
    return r / span if span > 0 else float("nan")


def fit_percent(y: np.ndarray, y_hat: np.ndarray) -> float:
    """System-identification fit ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` (percent).

    ``y`` and ``y_hat`` have shape (n,) or (n, k); samples (rows) with any NaN in
    ``y`` or ``y_hat`` are skipped; for (n, k) each column is centred on its own
    mean and the norms are Frobenius norms.  NaN when ``y`` is constant."""
    y = np.asarray(y, float)
    y_hat = np.asarray(y_hat, float)
    if y.ndim == 1:
        y, y_hat = y[:, None], y_hat[:, None]
    ok = np.isfinite(y).all(axis=1) & np.isfinite(y_hat).all(axis=1)
    if ok.sum() < 2:
        return float("nan")
    y, y_hat = y[ok], y_hat[ok]
    den = np.linalg.norm(y - y.mean(axis=0))
    if den == 0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / den))


def _channel_series(measured, predicted, g):
    """(y, y_hat, err) arrays (n, 3) for group ``g`` of one run; angles unwrapped."""
    if g == "attitude":
        qm = np.asarray(measured["quaternion"])
        qp = np.asarray(predicted["quaternion"])
        ok = np.isfinite(qm).all(axis=-1)
        em = np.full(qm.shape[:-1] + (3,), np.nan)
        em[ok] = quat_to_euler(qm[ok])
        ep = quat_to_euler(qp)
        err = wrap(em - ep)
        if ok.any():  # unwrap the measured angles along time over the valid samples
            em[ok] = np.unwrap(em[ok], axis=0)
        y_hat = em - err  # the prediction on the measured angle's branch
        return em, y_hat, err
    key = _SIGNAL_KEY[g]
    y = np.asarray(measured[key], float)
    y_hat = np.broadcast_to(np.asarray(predicted[key], float), y.shape)
    return y, y_hat, y - y_hat


def run_metrics(measured: Mapping[str, np.ndarray], predicted: Mapping[str, np.ndarray]) -> dict:
    """Per-channel and per-group metrics of one run.

    Parameters
    ----------
    measured : signals of one run (:func:`signals_from_run`), arrays (n, k).
    predicted : signals of one simulated run (:func:`signals_from_states`), (n, k).

    Returns
    -------
    dict with
      ``channels``: {channel: {"rmse", "nrmse", "fit_percent", "n"}} for each
      logged channel (x, y, z, roll, pitch, yaw, u, v, w, p, q, r);
      ``groups``: {group: {"rmse", "fit_percent", "n"}} where the position RMSE is
      the 3-D error RMSE and the attitude RMSE the error-angle RMSE;
      ``position_m`` / ``attitude_rad`` / ``velocity_mps`` / ``rates_radps``:
      the group RMSEs (only for logged groups).
    """
    channels, groups, out = {}, {}, {}
    mask = channel_mask(measured)
    for g in present_groups(measured):
        names = GROUPS[g]
        y, y_hat, err = _channel_series(measured, predicted, g)
        logged = mask[g]
        for j, name in enumerate(names):
            if not logged[j]:
                continue
            ok = np.isfinite(y[:, j]) & np.isfinite(err[:, j])
            channels[name] = {
                "rmse": float(rmse(err[ok, j])) if ok.any() else float("nan"),
                "nrmse": nrmse(y[:, j], y_hat[:, j]),
                "fit_percent": fit_percent(y[:, j], y_hat[:, j]),
                "n": int(ok.sum()),
            }
        cols = np.flatnonzero(logged)
        if g == "attitude":
            qm = np.asarray(measured["quaternion"])
            ok = np.isfinite(qm).all(axis=-1)
            e = attitude_error_angle(qm[ok], np.asarray(predicted["quaternion"])[ok])
            r = float(rmse(e)) if ok.any() else float("nan")
            n = int(np.isfinite(e).sum())
        else:
            ok = np.isfinite(y[:, cols]).all(axis=1)
            e = err[ok][:, cols]
            r = float(np.sqrt(np.nanmean(np.sum(e * e, axis=1)))) if ok.any() else float("nan")
            n = int(ok.sum())
        groups[g] = {"rmse": r, "fit_percent": fit_percent(y[:, cols], y_hat[:, cols]), "n": n}
        out[f"{g}_{GROUP_UNITS[g]}"] = r
    out["channels"] = channels
    out["groups"] = groups
    return out


def pooled_rmse(pairs: Iterable[tuple[Mapping, Mapping]]) -> dict[str, float]:
    """Group RMSEs over several runs pooled sample by sample.

    ``pairs`` yields (measured, predicted) per run.  Returns e.g.
    ``{"position_m": ..., "attitude_rad": ...}`` for the groups any run logged
    (position: 3-D error over each run's logged axes; attitude: error angle)."""
    sq: dict[str, float] = {}
    cnt: dict[str, int] = {}
    for measured, predicted in pairs:
        m = run_metrics(measured, predicted)
        for g, d in m["groups"].items():
            if d["n"] and np.isfinite(d["rmse"]):
                sq[g] = sq.get(g, 0.0) + d["rmse"] ** 2 * d["n"]
                cnt[g] = cnt.get(g, 0) + d["n"]
            elif d["n"]:
                sq[g] = float("nan")
                cnt[g] = cnt.get(g, 0) + d["n"]
    return {f"{g}_{GROUP_UNITS[g]}": float(np.sqrt(sq[g] / cnt[g])) for g in GROUPS if g in cnt}


# ----------------------------------------------------------------------------- normalization
def component_weights(group: str, weights: Mapping[str, float] | None) -> np.ndarray:
    """Weights (3,) of a group's components: ``weights[group]`` (default 1) times
    ``weights[channel]`` (default 1) for each of its channels (e.g. ``{"attitude": 2,
    "roll": 0}``).  Attitude components are the error rotation vector's body x, y, z
    parts, which are the roll, pitch, yaw errors for small tilts."""
    return np.array([channel_weight(weights, group, c) for c in GROUPS[group]])


def normalized_residuals(measured: Mapping[str, np.ndarray], predicted: Mapping[str, np.ndarray],
                         scales: Mapping[str, float], weights: Mapping[str, float] | None = None,
                         *, run_weight: float = 1.0, fill: float | None = None) -> np.ndarray:
    """One residual vector for least squares.

    Each present group's components (:func:`residual_components`) are divided by
    ``scales[group]`` and multiplied by ``sqrt(w * run_weight)`` with ``w`` from
    :func:`component_weights` (default 1), then the entries where the measurement exists and
    the weight is non-zero are
    concatenated in a fixed order (so the vector length does not depend on the
    parameters).  Non-finite predictions (a diverged simulation) are replaced by
    ``fill`` (default: raise :class:`CalibrationError`).  Batch axes are not
    supported here; pass one run."""
    weights = dict(weights or {})
    comps = residual_components(measured, predicted)
    parts = []
    for g, e in comps.items():
        key = _SIGNAL_KEY[g]
        m = np.asarray(measured[key])
        valid = np.isfinite(m).all(axis=-1, keepdims=True) if g == "attitude" else np.isfinite(m)
        w = component_weights(g, weights)
        valid = np.broadcast_to(valid, e.shape) & (w > 0)
        # channel-major order (each channel's time series contiguous), so that
        # neighbouring entries are neighbouring samples (used for autocorrelation)
        r = (e / scales[g] * np.sqrt(w * run_weight)).T[valid.T]
        bad = ~np.isfinite(r)
        if bad.any():
            if fill is None:
                raise CalibrationError(f"non-finite prediction in signal {g!r} (diverged simulation)")
            r = np.where(bad, fill, r)
        parts.append(r)
    return np.concatenate(parts) if parts else np.zeros(0)


# ----------------------------------------------------------------------------- measurement models
#: Report-key unit suffix of each measurement group (``position_m``, ``acceleration_mps2``, ...).
UNIT_SUFFIX = {"position": "m", "depth": "m", "attitude": "rad", "velocity": "mps", "rates": "radps",
               "acceleration": "mps2"}


def measurement_metrics(meas, pred) -> dict:
    """Per-channel and per-group metrics of one run through its measurement model.

    Parameters
    ----------
    meas : :class:`uvsim.measurements.RunMeasurements`.
    pred : its predicted measurements (:meth:`~uvsim.measurements.RunMeasurements.predict`
        of one simulated run, arrays (n, k)).

    Returns
    -------
    dict with ``channels`` ({channel: {"rmse", "nrmse", "fit_percent", "n", "unit"}}, over
    the channel's native samples; angles as wrapped Euler-angle differences, Fit on the
    unwrapped measured angle), ``groups`` ({group: {"rmse", "fit_percent", "n"}}: position,
    velocity, rates, acceleration as the RMS of the 3-D error over the logged axes,
    attitude as the error angle for a full attitude) and ``<group>_<unit>`` keys with the
    group RMSEs (e.g. ``position_m``, ``depth_m``, ``attitude_rad``)."""
    from uvsim.kinematics import unwrap_angles

    channels, groups, out = {}, {}, {}
    res = meas.residuals(pred)
    for g, grp in meas.groups.items():
        names = grp.channels
        if g == "attitude":
            if grp.mode == "quaternion":
                y = quat_to_euler(grp.values)
                yh_raw = quat_to_euler(np.asarray(pred[g]))
            else:
                y = np.array(grp.values, float)
                yh_raw = np.asarray(pred[g], float)
            err = np.where(grp.valid, wrap(y - yh_raw), np.nan)
            y = unwrap_angles(np.where(grp.valid, y, np.nan))
            y_hat = y - err
        else:
            y = np.where(grp.valid, grp.values, np.nan)
            err = res[g]
            y_hat = y - err
        for j, c in enumerate(names):
            if not grp.logged[j]:
                continue
            ok = np.isfinite(err[:, j])
            channels[c] = {"rmse": float(rmse(err[ok, j])) if ok.any() else float("nan"),
                           "nrmse": nrmse(y[:, j], y_hat[:, j]), "fit_percent": fit_percent(y[:, j], y_hat[:, j]),
                           "n": int(ok.sum()), "unit": UNITS[g]}
        cols = np.flatnonzero(grp.logged)
        if g == "attitude" and grp.mode == "quaternion":
            e = np.linalg.norm(res[g], axis=1)
            r, n = float(rmse(e)), int(np.isfinite(e).sum())
        else:
            e = res[g][:, cols]
            okr = np.isfinite(e).all(axis=1)
            r = float(np.sqrt(np.mean(np.sum(e[okr] ** 2, axis=1)))) if okr.any() else float("nan")
            n = int(okr.sum())
        groups[g] = {"rmse": r, "fit_percent": fit_percent(y[:, cols], y_hat[:, cols]), "n": n}
        out[f"{g}_{UNIT_SUFFIX[g]}"] = r
    out["channels"] = channels
    out["groups"] = groups
    return out


def pooled_group_rmse(metrics_list) -> dict[str, float]:
    """Group RMSEs over several runs (outputs of :func:`measurement_metrics`), pooled
    sample by sample; keys ``<group>_<unit>``."""
    sq: dict[str, float] = {}
    cnt: dict[str, int] = {}
    for m in metrics_list:
        for g, d in m["groups"].items():
            if d["n"]:
                sq[g] = sq.get(g, 0.0) + (d["rmse"] ** 2 * d["n"] if np.isfinite(d["rmse"]) else np.inf)
                cnt[g] = cnt.get(g, 0) + d["n"]
    return {f"{g}_{UNIT_SUFFIX[g]}": float(np.sqrt(sq[g] / cnt[g])) for g in UNIT_SUFFIX if g in cnt}
