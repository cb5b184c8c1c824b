"""Hand-made runs and predictions for the verdict's tests (imported by tests/test_verdict.py and
tests/test_diagnosis_guard.py): a logged run with position, depth, Euler angles and rates, its
measurement model, and predictions whose errors are chosen channel by channel, so the tests
know every channel's error exactly without any simulator."""
from __future__ import annotations

import numpy as np
import pandas as pd

from uvsim.logs import Run
from uvsim.measurements import measurements_for

CHANNELS = ("x", "y", "depth", "roll", "pitch", "yaw", "p", "q", "r")


def logged_run(seed: int = 0, duration: float = 30.0, rate: float = 20.0, name: str = "val_01", **extra) -> Run:
    """A run of slow sinusoids in every channel (not a simulation: the verdict needs none)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate)
    cols = {"t": t, **{k: 0.0 for k in ("X", "Y", "Z", "K", "M", "N")}}
    for i, c in enumerate(CHANNELS):
        amp = 0.5 if c in ("x", "y", "depth") else 0.2
        cols[c] = amp * np.sin(2 * np.pi * t / (7.0 + i) + rng.uniform(0, 6)) + (1.0 if c == "depth" else 0.0)
    cols.update(extra)
    return Run(name, None, pd.DataFrame(cols), split="validation")


def model(run: Run, noise: float = 0.01, **kw):
    """The run's measurement model with a given noise level for every channel (no estimation)."""
    return measurements_for(run, None, noise={c: noise for c in CHANNELS if c in run.data.columns}, **kw)


def errors(meas, seed: int, size: float = 0.05) -> dict:
    """Smooth random error series per channel, (n,), of RMS about ``size`` (correlated over
    seconds, as a free simulation's errors are)."""
    rng = np.random.default_rng(seed)
    out = {}
    for g, grp in meas.groups.items():
        for j, c in enumerate(grp.channels):
            if grp.logged[j]:
                w = rng.standard_normal(meas.n)
                k = np.ones(25) / 25
                e = np.convolve(w, k, mode="same")
                out[c] = size * e / np.sqrt(np.mean(e * e))
    return out


def prediction(meas, err: dict, scale: dict | None = None) -> dict:
    """Predicted measurements with error ``scale[c] * err[c]`` in each channel (measured minus
    predicted), angles wrapped like the measurement model does."""
    scale = scale or {}
    out = {}
    for g, grp in meas.groups.items():
        p = np.array(grp.values, float).copy()
        for j, c in enumerate(grp.channels):
            if grp.logged[j]:
                p[:, j] = p[:, j] - scale.get(c, 1.0) * err[c]
        out[g] = p
    return out
