"""Open-loop evaluation of a calibrated model and the calibration report's metrics.

Every run (training and validation) is simulated from its estimated initial state with
its logged inputs (:func:`uvsim.fitting.evaluate.open_loop`) and compared with what it
logged through the measurement models (:func:`uvsim.metrics.measurement_metrics`).  A
run that logs gyro rates is compared after removing its gyro bias: the joint fit's
estimate for a training run; for a validation run (and for the initial model) the
median rate residual of the run (a constant sensor offset, estimated from the run
itself as a bias-calibrated gyro would be; not a model parameter).
"""
from __future__ import annotations

import numpy as np

from uvsim.fitting.evaluate import open_loop
from uvsim.metrics import measurement_metrics, pooled_group_rmse


def evaluate_runs(vehicle, runs, meas, gyro_bias: dict | None = None, *, initial_velocity: str = "zero") -> dict:
    """Per run name: ``{"metrics", "pred", "states", "gyro_bias"}`` of the open-loop
    simulation of ``vehicle`` (module docstring); ``gyro_bias``: run name -> (3,) known
    biases (the others are estimated as the median rate residual)."""
    out = {}
    for run, m, r in zip(runs, meas, open_loop(vehicle, runs, meas=meas, initial_velocity=initial_velocity)):
        pred = r["pred"]
        b = None
        if m.has_gyro:
            if gyro_bias and run.name in gyro_bias:
                b = np.asarray(gyro_bias[run.name], float)
            else:
                e = m.residuals(pred)["rates"]
                with np.errstate(all="ignore"):
                    b = np.array([np.nanmedian(e[:, j]) if np.isfinite(e[:, j]).any() else 0.0 for j in range(3)])
            pred = m.predict(r["states"], r["nu_dot"], b)
        out[run.name] = {"metrics": measurement_metrics(m, pred), "pred": pred, "states": r["states"],
                         "gyro_bias": None if b is None else [float(x) for x in b]}
    return out


def pooled_fit_percent(metrics_list) -> dict[str, float]:
    """Per channel, the Fit % of several runs pooled:
    ``100 (1 - sqrt(sum ||e||^2) / sqrt(sum ||y - mean_run(y)||^2))`` (each run's channel
    centred on its own mean), from per-run :func:`uvsim.metrics.measurement_metrics`."""
    err: dict[str, float] = {}
    var: dict[str, float] = {}
    for m in metrics_list:
        for c, d in m["channels"].items():
            f, n, r = d["fit_percent"], d["n"], d["rmse"]
            if not (n and np.isfinite(f) and np.isfinite(r) and f < 100):
                continue
            e2 = r * r * n
            err[c] = err.get(c, 0.0) + e2
            var[c] = var.get(c, 0.0) + e2 / (1.0 - f / 100.0) ** 2
    return {c: float(100.0 * (1.0 - np.sqrt(err[c] / var[c]))) for c in err if var[c] > 0}


def run_entry(run, fitted: dict, initial: dict) -> dict:
    """The report's ``per_run`` entry of one run from its fitted and initial evaluations."""
    m, m0 = fitted["metrics"], initial["metrics"]
    return {
        "dof": run.dof, "split": run.split, "weight": run.weight,
        "rmse": {k: v for k, v in m.items() if k not in ("channels", "groups")},
        "nrmse": {c: v["nrmse"] for c, v in m["channels"].items()},
        "fit_percent": {**{c: v["fit_percent"] for c, v in m["channels"].items()},
                        **{g: v["fit_percent"] for g, v in m["groups"].items()}},
        "initial_rmse": {k: v for k, v in m0.items() if k not in ("channels", "groups")},
        "initial_fit_percent": {c: v["fit_percent"] for c, v in m0["channels"].items()},
        "channels": m["channels"],
        "gyro_bias": fitted["gyro_bias"],
    }


def pooled(evals: dict, runs, split: str) -> tuple[dict, dict]:
    """(group RMSEs, channel Fit %) pooled over the runs of ``split``."""
    ms = [evals[r.name]["metrics"] for r in runs if r.split == split]
    return (pooled_group_rmse(ms), pooled_fit_percent(ms)) if ms else ({}, {})
