"""The one measure: each logged channel's error and what is computed from it.

A channel's error is :meth:`uvsim.measurements.RunMeasurements.residuals`: measured minus
predicted in the channel's unit, at the channel's own samples, with angles as wrapped
differences of Euler angles.  Everything that judges or reports a model reads it through
this module: the calibration's and the diagnosis' verdict (:mod:`uvsim.fitting.verdict`),
report.json, the CLI tables and the plots; the fits minimize the same errors divided by a
per-channel scale (:mod:`uvsim.measurements`).

Per channel ``c`` of one run, over the samples where both the measurement and the
prediction exist (``n`` of them):

* ``sse = sum e^2`` and ``rmse = sqrt(sse / n)``;
* ``sst = sum (y - mean y)^2``, the measured channel's own spread about its run mean (angles
  unwrapped along time);
* ``fit_percent = 100 (1 - sqrt(sse / sst))`` (system identification's Fit, Ljung's
  ``compare``): 100 is perfect, 0 no better than the run mean, negative worse;
* ``nrmse = rmse / (max y - min y)``, seed 000 sec. 5's normalization.

Pooled over runs (:func:`pooled_metrics`) the sums add: ``rmse = sqrt(sum sse / sum n)``,
``fit_percent = 100 (1 - sqrt(sum sse / sum sst))``.  A group's RMSE (``position_m``,
``attitude_rad`` ...) is the RMS length of the error vector of its logged channels,
``sqrt(sum_c mse_c)`` (for position the 3-D distance; for attitude the Euler-angle error
vector, which is the attitude error angle for small errors).
"""
from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from uvsim.kinematics import unwrap_angles
from uvsim.signals import UNITS

#: Report-key unit suffix of each measurement group (``position_m``, ``acceleration_mps2``, ...).
UNIT_SUFFIX = {"position": "m", "depth": "m", "attitude": "rad", "velocity": "mps", "rates": "radps",
               "acceleration": "mps2"}


# ----------------------------------------------------------------------------- plain formulas
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


def fit_from_sums(sse: float, sst: float) -> float:
    """Fit % from a channel's sum of squared errors and its measured sum of squares about the
    run means (module docstring); NaN for a constant channel, -inf for a diverged prediction."""
    if not sst > 0:
        return float("nan")
    return float(100.0 * (1.0 - np.sqrt(sse / sst))) if np.isfinite(sse) else float("-inf")


# ----------------------------------------------------------------------------- channel series
def channel_series(meas, pred, rows: np.ndarray | None = None) -> dict:
    """Every logged channel of one run as the measure sees it.

    Parameters
    ----------
    meas : :class:`uvsim.measurements.RunMeasurements` of the run.
    pred : its predicted measurements (:meth:`~uvsim.measurements.RunMeasurements.predict`),
        arrays (n, k).
    rows : optional (n,) bool, the rows taken (e.g. the horizon over which two models are
        compared, :mod:`uvsim.fitting.verdict`); default all.

    Returns
    -------
    dict channel -> {"group", "unit", "measured" (n,) bool: rows that are a measurement of it
    (within ``rows``), "valid" (n,) bool: those with a finite prediction too, "y" (n,) measured (angles unwrapped along time), "y_hat" (n,)
    predicted (angles on the measured value's branch, so ``y - y_hat`` is the wrapped error),
    "e" (n,) the error ``y - y_hat`` (NaN outside ``valid``), "sigma": the channel's noise
    level}, in the order of the measurement model's groups.
    """
    out = {}
    res = meas.residuals(pred)
    for g, grp in meas.groups.items():
        y = np.where(grp.valid, grp.values, np.nan)
        if g == "attitude":
            y = unwrap_angles(y)
        for j, c in enumerate(grp.channels):
            if not grp.logged[j]:
                continue
            e = res[g][:, j]
            measured = np.isfinite(y[:, j]) if rows is None else np.isfinite(y[:, j]) & rows
            ok = measured & np.isfinite(e)
            e = np.where(ok, e, np.nan)
            out[c] = {"group": g, "unit": UNITS[g], "measured": measured, "valid": ok, "y": y[:, j], "y_hat": y[:, j] - e, "e": e,
                      "sigma": float(grp.sigma[j])}
    return out


def _sums(s: dict) -> dict:
    """sse, sst, n and the range of one channel series (:func:`channel_series`); ``sse`` is inf
    when the prediction is not finite at a measured sample (a diverged simulation: its error
    is not small, it is unbounded) and ``n`` then counts the measured samples."""
    ok = s["measured"]
    e, y = s["e"][ok], s["y"][ok]
    n = int(ok.sum())
    sse = float(np.sum(e * e)) if np.isfinite(e).all() else float("inf")
    return {"sse": sse, "sst": float(np.sum((y - y.mean()) ** 2)) if n else 0.0, "n": n,
            "span": float(np.ptp(y)) if n else float("nan")}


# ----------------------------------------------------------------------------- metrics of runs
def measurement_metrics(meas, pred, rows: np.ndarray | None = None) -> dict:
    """Per-channel and per-group metrics of one run (module docstring).

    Returns
    -------
    dict with ``channels`` ({channel: {"rmse", "nrmse", "fit_percent", "n", "unit", "group",
    "sse", "sst"}}), ``groups`` ({group: {"rmse", "fit_percent", "n"}}) and ``<group>_<unit>``
    keys with the group RMSEs (``position_m``, ``depth_m``, ``attitude_rad`` ...).  A channel
    whose prediction is not finite at some measured sample (a diverged simulation) has an
    infinite RMSE; pass ``rows`` to compare over a horizon where it is finite.
    """
    channels = {}
    for c, s in channel_series(meas, pred, rows).items():
        d = _sums(s)
        r = float(np.sqrt(d["sse"] / d["n"])) if d["n"] else float("nan")
        channels[c] = {"rmse": r, "nrmse": r / d["span"] if d["n"] and d["span"] > 0 else float("nan"),
                       "fit_percent": fit_from_sums(d["sse"], d["sst"]), "n": d["n"], "unit": s["unit"],
                       "group": s["group"], "sse": d["sse"], "sst": d["sst"]}
    return _with_groups({"channels": channels})


def _with_groups(m: dict) -> dict:
    """``m`` with ``groups`` and ``<group>_<unit>`` keys derived from its channels."""
    groups: dict = {}
    for c, d in m["channels"].items():
        g = groups.setdefault(d["group"], {"mse": 0.0, "sse": 0.0, "sst": 0.0, "n": 0})
        mse = d["sse"] / d["n"] if d["n"] else float("nan")
        g["mse"] += mse
        g["sse"] += d["sse"]
        g["sst"] += d["sst"]
        g["n"] = max(g["n"], d["n"])
    out = {"channels": m["channels"], "groups": {}}
    for g, d in groups.items():
        r = float(np.sqrt(d["mse"]))
        out["groups"][g] = {"rmse": r, "fit_percent": fit_from_sums(d["sse"], d["sst"]), "n": d["n"]}
        out[f"{g}_{UNIT_SUFFIX[g]}"] = r
    return out


def pooled_metrics(metrics_list: Iterable[Mapping]) -> dict:
    """Several runs' :func:`measurement_metrics` pooled sample by sample (module docstring):
    the same keys, without ``nrmse``."""
    acc: dict = {}
    for m in metrics_list:
        for c, d in m["channels"].items():
            a = acc.setdefault(c, {"sse": 0.0, "sst": 0.0, "n": 0, "unit": d["unit"], "group": d["group"]})
            a["sse"] += d["sse"]
            a["sst"] += d["sst"]
            a["n"] += d["n"]
    channels = {c: {"rmse": float(np.sqrt(a["sse"] / a["n"])) if a["n"] else float("nan"),
                    "fit_percent": fit_from_sums(a["sse"], a["sst"]), **a} for c, a in acc.items()}
    return _with_groups({"channels": channels})


def pooled_group_rmse(metrics_list) -> dict[str, float]:
    """Group RMSEs over several runs pooled sample by sample; keys ``<group>_<unit>``."""
    p = pooled_metrics(metrics_list)
    return {k: v for k, v in p.items() if k not in ("channels", "groups")}


def pooled_fit_percent(metrics_list) -> dict[str, float]:
    """Per channel, the Fit % of several runs pooled (module docstring)."""
    return {c: d["fit_percent"] for c, d in pooled_metrics(metrics_list)["channels"].items()
            if np.isfinite(d["fit_percent"])}
