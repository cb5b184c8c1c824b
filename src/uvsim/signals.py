"""The measured signals: their groups, channels and units, and per channel its noise level and weight.

A log's measured columns (docs/log_format.md) fall into the signal groups of :data:`GROUPS`;
:mod:`uvsim.measurements` predicts them from the state, and its residuals are divided by a
channel's noise level (``sigma``) and multiplied by ``sqrt(weight)``.  The level of a channel
(:func:`noise_level`, kept with where it comes from as :class:`uvsim.estimation.noise.NoiseLevel`)
is, first found first:

1. given: the ``noise`` option (``--noise``), by channel then by group;
2. declared: the vehicle file's ``sensors.noise`` (:attr:`uvsim.vehicle.Vehicle.sensor_noise`),
   by channel then by group;
3. estimated on the channel's native samples (:func:`uvsim.estimation.noise.noise_sigma`), at
   least the rounding of a channel logged to a resolution (``q / sqrt(12)``) and, for an attitude
   angle that is an estimator's output (:func:`uvsim.estimation.noise.filter_output`: no more
   visible noise than the integrated gyro's), at least
   :data:`uvsim.estimation.noise.FILTER_FLOOR` (a *floor*).

A channel's weight is ``weights[group]`` x ``weights[channel]`` (:func:`channel_weight`), with
``sample_weighting="per_second"`` times :func:`per_second_factors`.  The fits check the
``noise``, ``weights`` and ``sample_weighting`` settings before any work
(:func:`check_signal_settings`, :func:`check_sample_weighting`).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Mapping

import numpy as np

from uvsim.fit_settings import SAMPLE_WEIGHTINGS
from uvsim.errors import CalibrationError
from uvsim.estimation.noise import (FILTER_FLOOR, FILTER_GATE, NoiseLevel, filter_output, noise_sigma,
                                    quantisation_sigma, quantum)
from uvsim.kinematics import unwrap_angles
from uvsim.log_columns import (ACCEL_COLUMNS, DEPTH_COLUMN, EULER_COLUMNS, POSITION_COLUMNS, RATE_COLUMNS,
                               VELOCITY_COLUMNS)
from uvsim.schema import did_you_mean

#: Signal groups and their channels, in a fixed order.
GROUPS = {
    "position": POSITION_COLUMNS,
    "depth": (DEPTH_COLUMN,),
    "attitude": EULER_COLUMNS,
    "velocity": VELOCITY_COLUMNS,
    "rates": RATE_COLUMNS,
    "acceleration": ACCEL_COLUMNS,
}
UNITS = {"position": "m", "depth": "m", "attitude": "rad", "velocity": "m/s", "rates": "rad/s",
         "acceleration": "m/s^2"}
CHANNEL_GROUP = {c: g for g, cs in GROUPS.items() for c in cs}


def channel_weight(weights: Mapping[str, float] | None, group: str, channel: str) -> float:
    """The weight of ``channel`` of ``group``: ``weights[group]`` x ``weights[channel]``
    (each default 1).  A channel named like its group (``depth``) is weighted once:
    ``{"depth": 10}`` weighs depth 10, not 100."""
    weights = weights or {}
    w = float(weights.get(group, 1.0))
    return w if channel == group else w * float(weights.get(channel, 1.0))


def _lookup(levels: Mapping[str, float], group: str, channel: str) -> float | None:
    """``levels`` of ``channel``, else of its ``group``, else None."""
    v = levels.get(channel, levels.get(group))
    return None if v is None else float(v)


def noise_level(group: str, channel: str, values: np.ndarray, native: np.ndarray, *,
                given: Mapping[str, float] | None = None, declared: Mapping[str, float] | None = None) -> NoiseLevel:
    """The noise level of ``channel`` of ``group`` (values (n,), native (n,) bool), without the
    attitude filter's floor (:func:`_filter_floor` adds it, it needs the gyro): ``given`` (the
    ``noise`` option), else ``declared`` (the vehicle file's ``sensors.noise``), else the
    fourth-difference estimate, at least the rounding of its resolution (module docstring).
    ``sigma`` is NaN with neither a level given nor 8 native samples."""
    if group == "attitude":
        values = unwrap_angles(values)
    est = noise_sigma(values, native)
    q = quantum(values, native)
    g, d = _lookup(given or {}, group, channel), _lookup(declared or {}, group, channel)
    if g is not None:
        key = channel if channel in (given or {}) else group
        return NoiseLevel(g, "declared", f"the noise option ({key})", est, q)
    unit = UNITS[group]
    if d is not None:
        key = channel if channel in (declared or {}) else group
        return NoiseLevel(d, "declared", f"the vehicle file (sensors.noise.{key})", est, q,
                          f"{channel}: noise {d:.3g} {unit}, declared in the vehicle file (sensors.noise.{key})")
    fq = quantisation_sigma(q)
    if q > 0 and fq > est:
        basis = f"the rounding of values logged to {q:.4g} {unit} (q / sqrt(12))"
        return NoiseLevel(fq, "floor", basis, est, q, f"{channel}: noise {fq:.3g} {unit}, {basis}, more than the "
                                                      "samples show")
    return NoiseLevel(est, "estimated", "fourth differences of the native samples", est, q)


def _filter_floor(groups: Mapping) -> None:
    """Raise the attitude angles that are an estimator's output to :data:`FILTER_FLOOR`
    (:func:`uvsim.estimation.noise.filter_output`; module docstring), in place, in ``groups``
    (name -> :class:`uvsim.measurements.Group`; :func:`uvsim.measurements.measurements_for` calls it)."""
    att, rates = groups.get("attitude"), groups.get("rates")
    if att is None or rates is None or not rates.logged.any():
        return
    s_gyro = float(np.median(rates.sigma[rates.logged]))
    for j, c in enumerate(att.channels):
        lv = att.noise[j]
        if lv is None or lv.source == "declared" or not FILTER_FLOOR[c] > lv.sigma:
            continue
        k = att.kinds[j]
        if k is None or not filter_output(lv.estimate, s_gyro, k.native_interval_s):
            continue
        att.noise[j] = replace(
            lv, sigma=FILTER_FLOOR[c], source="floor",
            basis=(f"an attitude filter's output (estimate {lv.estimate:.2g} rad, within {FILTER_GATE:g} x the gyro's "
                   f"noise over a sample, {s_gyro * k.native_interval_s:.2g} rad): the floor of an estimator's {c}"),
            note=(f"{c}: noise {FILTER_FLOOR[c]:.3g} rad, the floor of an attitude filter's output (its samples change "
                  f"only as the integrated gyro does and its error is not in them: declare sensors.noise.{c} in the "
                  "vehicle file to set it)"))
        att.sigma[j] = FILTER_FLOOR[c]


def check_sample_weighting(value) -> str:
    """``value`` if it is one of :data:`SAMPLE_WEIGHTINGS`, else a CalibrationError."""
    if value not in SAMPLE_WEIGHTINGS:
        raise CalibrationError(f"sample_weighting {value!r}: expected one of {list(SAMPLE_WEIGHTINGS)}")
    return value


def per_second_factors(groups: Mapping) -> dict:
    """Channel -> ``f_max / f_c``: the run's fastest native sample rate over the channel's own
    (``groups``: name -> :class:`uvsim.measurements.Group`).
    A channel's rate is one over the median interval between its native samples
    (``SampleKind.native_interval_s``, :class:`uvsim.estimation.noise.SampleKind`), so dropouts
    do not lower it: seconds without a sample carry no information, and the samples around
    them are not weighted up for them.

    Multiplied into a channel's weight, it makes every logged channel count per second of log
    rather than per sample: a 10 Hz depth beside a 100 Hz IMU gets 10.  When the model lacks
    something in the data (real logs always do), the residuals of every channel are correlated
    over seconds, far longer than a sample, so a 100 Hz channel does not carry ten times the
    information of a 10 Hz one although per-sample weighting counts it so (the sum of
    squared prediction errors weighs samples by their number, which is the maximum-likelihood
    weighting only for white residuals: Ljung 1999, ch. 7)."""
    rate = {c: 1.0 / grp.kinds[j].native_interval_s for grp in groups.values() for j, c in enumerate(grp.channels)
            if grp.kinds[j] is not None and grp.kinds[j].native_interval_s > 0}  # NaN (< 2 samples): left out
    top = max(rate.values(), default=0.0)
    return {c: top / r for c, r in rate.items()}


def check_signal_settings(noise=None, weights=None) -> None:
    """Refuse unknown signal names (with the nearest known one) and values that are not a
    positive noise level or a non-negative weight, in ``noise`` and ``weights`` ({name: value},
    groups or channels); the fits call it before any work."""
    known = list(GROUPS) + list(CHANNEL_GROUP)
    from uvsim.schema import require_mapping

    for what, d in (("noise", require_mapping(noise, "noise", error=CalibrationError, example="{'depth': 0.01}")),
                    ("weights", require_mapping(weights, "weights", error=CalibrationError,
                                                example="{'position': 1.0, 'depth': 0.0}"))):
        for k in sorted(set(d) - set(known)):
            raise CalibrationError(f"{what}: unknown signal {k!r}{did_you_mean(k, known)}; "
                                   f"expected groups {list(GROUPS)} or channels {list(CHANNEL_GROUP)}")
        for k, v in d.items():
            try:
                ok = np.isfinite(float(v)) and (float(v) > 0 if what == "noise" else float(v) >= 0)
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise CalibrationError(f"{what}.{k}: expected a {'positive' if what == 'noise' else 'non-negative'} "
                                       f"number, got {v!r}")
