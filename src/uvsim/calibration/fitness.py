"""Seed 000's GA fitness on the measurement models.

Seed 000 (sec. 4.4 ii) scores a candidate by "the sum of absolute differences between
the simulated and real data".  uvsim compares every logged channel through its
measurement model (:mod:`uvsim.measurements`: depth at the pressure sensor, partial
Euler angles, specific force at the IMU, gyro rates, ...), so the GA works on whatever
a run logged.  For one run and a batch of simulated parameter sets::

    fitness = sum_c  w_c  mean_i |e_ci| / sigma_c

over the channels ``c`` with weight ``w_c > 0`` and their native samples ``i`` (held or
interpolated cells are not measurements), ``e`` the measured minus predicted value
(wrapped for angles) and ``sigma_c`` the channel's noise level: the noise-normalized
mean absolute error, so metres, radians and rad/s add up.  Gyro channels are compared
after removing the run's median rate residual: a constant gyro bias is a sensor
offset, not a model error (the joint stage fits it, :mod:`uvsim.fitting`).
"""
from __future__ import annotations

import numpy as np


def abs_error_fitness(meas, pred, *, gyro_bias: bool = True) -> np.ndarray:
    """Fitness (P,) of one run (module docstring).

    Parameters
    ----------
    meas : :class:`uvsim.measurements.RunMeasurements` of the run (its weights select
        the channels).
    pred : its predicted measurements for P parameter sets (group -> (P, n, k)).
    gyro_bias : remove the median rate residual of each gyro channel first.

    Returns
    -------
    (P,) fitness, ``inf`` for a diverged simulation.
    """
    res = meas.residuals(pred)
    total = np.zeros(np.shape(next(iter(res.values())))[:-2]) if res else np.zeros(0)
    for g, e in res.items():
        grp = meas.groups[g]
        w = meas.channel_weights(g)
        for j in np.flatnonzero(grp.logged & (w > 0)):
            valid = grp.valid[:, j]
            if not valid.any():
                continue
            ej = e[..., valid, j]
            if g == "rates" and gyro_bias:
                ej = ej - np.median(ej, axis=-1, keepdims=True)
            total = total + w[j] * np.mean(np.abs(ej), axis=-1) / grp.sigma[j]
    return np.where(np.isfinite(total), total, np.inf)


def used_channels(meas) -> list[str]:
    """Channels of ``meas`` with a positive weight and at least one native sample."""
    out = []
    for g, grp in meas.groups.items():
        w = meas.channel_weights(g)
        out += [c for j, c in enumerate(grp.channels) if grp.logged[j] and w[j] > 0 and grp.valid[:, j].any()]
    return out
