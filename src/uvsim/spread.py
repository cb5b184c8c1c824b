"""Where a model's prediction has left the data: its RMSE against the spread of the measured signal.

A model whose RMSE in a channel exceeds :data:`EXPLODE_FACTOR` times the spread of the measured
signal (the RMS of its deviation from the run mean) predicts nothing there.  The commands' sanity
checks (:mod:`uvsim.commands.checks`) and the diagnosis' choice of how to judge closed-loop logs
(:func:`uvsim.fitting.evaluate.judged_prediction`, calibration's and diagnosis') use this one test.  Light to import (the commands
import it at start-up).
"""
from __future__ import annotations

import math
from typing import Mapping

import numpy as np

#: A model whose RMSE exceeds this many times the spread of the measured signal predicts nothing
#: there: its simulation "exploded" or left the data.
EXPLODE_FACTOR = 10.0


def signal_spread(runs) -> dict[str, float]:
    """{group_unit key: spread of the measured signal} over ``runs``: the RMS, over runs and
    logged channels, of each channel's deviation from its run mean (angles unwrapped)."""
    from uvsim.kinematics import quat_to_euler, unwrap_angles
    from uvsim.signals import GROUPS
    from uvsim.metrics import UNIT_SUFFIX

    ss: dict[str, float] = {}
    nn: dict[str, int] = {}
    for run in runs:
        for g in run.signals():
            if g == "attitude":
                a = run.euler if not run.has_quaternion else quat_to_euler(run.quaternion)
                a = unwrap_angles(a)
            else:
                cols = [c for c in GROUPS[g] if c in run.data.columns]
                a = run.data[cols].to_numpy(float)
            a = a[:, np.isfinite(a).any(axis=0)]
            if a.size == 0:
                continue
            dev = a - np.nanmean(a, axis=0)
            ok = np.isfinite(dev)
            ss[g] = ss.get(g, 0.0) + float(np.sum(dev[ok] ** 2))
            nn[g] = nn.get(g, 0) + int(ok.sum())
    return {f"{g}_{UNIT_SUFFIX[g]}": float(np.sqrt(ss[g] / nn[g])) for g in ss if nn[g] and g in UNIT_SUFFIX}


def beyond_spread(rmse: Mapping[str, float], spread: Mapping[str, float]) -> set[str]:
    """The keys of ``rmse`` not finite or beyond EXPLODE_FACTOR x the measured ``spread``."""
    return {k for k, v in rmse.items()
            if v is None or not math.isfinite(v) or (spread.get(k, 0) > 0 and v > EXPLODE_FACTOR * spread[k])}
