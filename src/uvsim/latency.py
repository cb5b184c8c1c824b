"""Sensor latency: the logged inputs applied later than their time stamps.

An autopilot logs its actuator commands when it sends them, but its sensors (IMU, attitude
filter, pressure sensor) reach the log some tens of milliseconds after the motion they
measure (ArduSub's sensor and telemetry path).  When every logged sensor is ``d`` seconds
late, a prediction of the log is the model driven by the inputs ``d`` seconds late: the
sensor at time ``t`` reads the state at ``t - d``, which for a time-invariant model is the
state at ``t`` of the model whose inputs are delayed by ``d`` (up to the first ``d`` seconds,
where the delayed inputs hold the first logged value).

A vehicle file states it as ``sensors.latency`` (s; docs/model.md, "Sensor latency"); every
prediction of a log (open-loop validation, the windowed fits, diagnosis) then uses
:func:`delay_inputs`.  The calibration can estimate it (``latency="auto"``,
:func:`uvsim.calibration.latency_estimate.scan_latency`).

The inputs are held over each sample interval (zero-order hold, as the simulator applies
them).  The input held over ``[t_i, t_(i+1)]`` after a delay ``d`` is the logged input at
``t_i - d``, linearly interpolated between samples: for a whole number of sample intervals
it is exactly an earlier sample; between two, the blend is the interval's average input to
first order, which keeps a prediction smooth in ``d``.  Before the first sample the first
input is held.  The delayed run records the delay (``Run.input_delay``) and the run as
logged (``Run.as_logged``); commands report the delay, nothing is resampled silently.
"""
from __future__ import annotations

import numpy as np

from uvsim.logged_run import Run


def delay_inputs(run: Run, delay: float) -> Run:
    """``run`` with its inputs applied ``delay`` s after their time stamps (module docstring).

    Idempotent: a run already delayed by ``delay`` is returned as it is; a run delayed by
    another amount is delayed from the run as logged."""
    delay = float(delay)
    if delay < 0 or not np.isfinite(delay):
        raise ValueError(f"run {run.name}: input delay {delay!r} s: expected a finite delay >= 0")
    if run.input_delay == delay:
        return run
    src = run.as_logged if run.as_logged is not None else run
    if delay == 0.0:
        return src
    t = src.t
    df = src.data.copy()
    for c in src.input_columns:
        u = src.data[c].to_numpy()
        df[c] = np.interp(t - delay, t, u)  # before t[0]: u[0] (np.interp holds the end values)
    out = src.derived(df)  # (interpolated between the run's validated inputs: not validated again)
    out.notes = [*src.notes, f"inputs applied {delay * 1000:.1f} ms after their time stamps (sensor latency)"]
    out.input_delay = delay
    out.as_logged = src
    return out


def runs_for(vehicle, runs) -> list:
    """``runs`` as ``vehicle`` predicts them: their inputs delayed by its ``sensor_latency``."""
    d = float(getattr(vehicle, "sensor_latency", 0.0) or 0.0)
    return [delay_inputs(r, d) for r in runs]
