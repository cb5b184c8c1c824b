"""Open-loop predictions of logged runs and their metrics (what users compare).

``open_loop(vehicle, runs)`` simulates every run from its estimated initial state
(:func:`uvsim.simulate.initial_state_from_run`, start smoothed over
:data:`uvsim.simulate.INITIAL_WINDOW_S`) with its logged inputs, all runs of one input
kind in one batched call, and returns per run the states, the predicted measurements
(:mod:`uvsim.measurements`) and their metrics (:func:`uvsim.metrics.measurement_metrics`).
This is the "validation RMSE" of calibration and diagnosis reports: the error of a free
simulation over the whole run, not of the windowed predictions the fits use.
"""
from __future__ import annotations

import numpy as np

from uvsim.blas import single_thread
from uvsim.fitting.fitter import group_by_input
from uvsim.fitting.parameters import ParameterSpace
from uvsim.fitting.windows import whole_runs
from uvsim.measurements import measurements_for
from uvsim.metrics import measurement_metrics, pooled_group_rmse
from uvsim.vehicle import load_vehicle


def open_loop(vehicle, runs, *, overrides=None, meas=None, initial_velocity: str = "zero",
              gyro_bias: dict | None = None, noise=None, weights=None) -> list[dict]:
    """Per run (in order): ``{"name", "states" (n, n_y), "nu_dot" (n, 6) or None,
    "pred" (predicted measurements), "metrics"}`` of a free simulation (module docstring).

    ``overrides``: named parameter values; ``gyro_bias``: run name -> (3,) bias added to
    the predicted gyro rates (e.g. from a fit); ``meas``: the runs' measurement models
    (built with ``noise``/``weights`` when omitted)."""
    veh = load_vehicle(vehicle)
    runs = list(runs)
    if meas is None:
        meas = [measurements_for(r, veh, noise=noise, weights=weights) for r in runs]
    out: list = [None] * len(runs)
    for idx in group_by_input(runs):
        group = [runs[i] for i in idx]
        space = ParameterSpace([], veh.parameters(), dict(overrides or {}))
        with single_thread():
            Y, acc, _ = whole_runs(veh, group, [meas[i].sensors for i in idx], space, np.zeros(0),
                                   initial_velocity=initial_velocity,
                                   accel=any(meas[i].needs_acceleration for i in idx))
        for j, i in enumerate(idx):
            m = runs[i].t.size
            b = None if not gyro_bias or runs[i].name not in gyro_bias else np.asarray(gyro_bias[runs[i].name])
            y = Y[j, :m]
            a = None if acc is None else acc[j, :m]
            pred = meas[i].predict(y, a, b)
            out[i] = {"name": runs[i].name, "states": y, "nu_dot": a, "pred": pred,
                      "metrics": measurement_metrics(meas[i], pred)}
    return out


def pooled(results: list) -> dict:
    """Group RMSEs pooled over runs (outputs of :func:`open_loop`)."""
    return pooled_group_rmse([r["metrics"] for r in results])
