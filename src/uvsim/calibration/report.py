"""Open-loop evaluation of a calibrated model and the calibration report.

Every run (training and validation) is simulated from its estimated initial state with
its logged inputs (:func:`uvsim.fitting.evaluate.open_loop`) and compared with what it
logged through the one measure (:mod:`uvsim.metrics`).  When the starting model's free
simulation leaves the validation data (a vehicle flown under an autopilot the model does not
have), the runs are predicted over windows from the logged states instead, as diagnosis does
(:func:`uvsim.fitting.evaluate.judged_prediction`; the report's ``judged``): the verdict, the
RMSEs, Fit % and the plots all show those predictions.  A run that logs gyro rates is
compared after removing its gyro bias: the joint fit's estimate for a training run; for a
validation run (and for the initial model) the median rate residual of the run (a constant
sensor offset, estimated from the run itself as a bias-calibrated gyro would be; not a model
parameter).  The verdict (:func:`calibration_verdict`) compares the fitted model with the
start on the same predictions.
"""
from __future__ import annotations

import time

import numpy as np

from uvsim.calibration.params import EFFECTIVE_INERTIA, LINEAR_DAMPING, QUADRATIC_DAMPING
from uvsim.fitting.evaluate import judged_prediction, judged_predictions
from uvsim.fitting.objective import ATTITUDE_BIAS_SIGMA, acc_bias_sd, gyro_bias_sd
from uvsim.fitting.verdict import compare
from uvsim.metrics import pooled_fit_percent, pooled_group_rmse

#: 1-sigma above this fraction of the value: reported as "weakly_determined".
WEAK_RELATIVE_SIGMA = 0.25


def evaluate_runs(vehicle, runs, meas, gyro_bias: dict | None = None, *, initial_velocity: str = "zero",
                  judged_as: dict | None = None) -> dict:
    """Per run name: ``{"metrics", "pred", "states", "gyro_bias"}`` of the open-loop
    simulation of ``vehicle`` (:func:`uvsim.fitting.evaluate.open_loop`: start-aligned position,
    gyro biases of ``gyro_bias`` (run name -> (3,)) or else the run's median rate residual), or
    of its predictions over windows when ``judged_as`` (a
    :func:`uvsim.fitting.evaluate.judged_prediction` record) says so."""
    return {r["name"]: r for r in judged_predictions(vehicle, runs, judged_as or {}, meas=meas, gyro_bias=gyro_bias,
                                                     initial_velocity=initial_velocity)}


def judged_for(cal, runs, meas) -> dict:
    """How the verdict compares the models (:func:`uvsim.fitting.evaluate.judged_prediction`
    with the starting model on the validation runs, else on the training runs)."""
    split = "validation" if any(r.split == "validation" for r in runs) else "train"
    idx = [i for i, r in enumerate(runs) if r.split == split]
    if not idx:
        return judged_prediction(None, [], [], "whole")
    return judged_prediction(cal.initial_vehicle_, [runs[i] for i in idx], [meas[i] for i in idx],
                             cal.judge_horizon, initial_velocity=cal.initial_velocity, who="starting",
                             split="training" if split == "train" else split)


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
        "channels": {c: {k: v[k] for k in ("rmse", "nrmse", "fit_percent", "n", "unit")}
                     for c, v in m["channels"].items()},
        "gyro_bias": fitted["gyro_bias"],
    }


def calibration_verdict(runs, fitted: dict, initial: dict, meas: dict) -> dict | None:
    """The verdict (:func:`uvsim.fitting.verdict.compare`) on the fitted model against the model
    the user started from, on the validation runs' free simulations, every logged channel (also
    those a zero weight left out of the fit).  Without validation runs the training runs are
    compared instead (a weaker check: the fit has seen them; ``split`` says which).  None
    without runs."""
    split = "validation" if any(r.split == "validation" for r in runs) else "train"
    sel = [r for r in runs if r.split == split]
    if not sel:
        return None
    v = compare([meas[r.name] for r in sel], [initial[r.name]["pred"] for r in sel],
                [fitted[r.name]["pred"] for r in sel], names=("the starting model", "the fitted model"))
    v["split"] = split
    if split == "train":
        v["message"] += " (no validation runs: compared on the training runs, which the fit has seen)"
    return v


def pooled(evals: dict, runs, split: str) -> tuple[dict, dict]:
    """(group RMSEs, channel Fit %) pooled over the runs of ``split``."""
    ms = [evals[r.name]["metrics"] for r in runs if r.split == split]
    return (pooled_group_rmse(ms), pooled_fit_percent(ms)) if ms else ({}, {})


def identifiability_report(cal) -> dict:
    """The report's ``identifiability``: the joint stage's analysis plus weakly determined
    parameters, bounds and physical-limit hits, the excitation screen and the effective
    inertias with a held rigid-body moment."""
    res = cal.fit_
    if res is None:
        return {"not_excited": cal.screen_["not_excited"]}
    out = dict(res.identifiability)
    out["weakly_determined"] = [k for k, s in res.std.items()
                                if s is not None and s > WEAK_RELATIVE_SIGMA * abs(res.values[k])]
    out["at_bound"] = list(res.at_bounds)
    out["physical_limit"] = list(res.physical_limit)
    out["not_excited"] = list(cal.screen_["not_excited"])
    out["excitation_relative_sigma"] = dict(cal.screen_["relative_sigma"])
    eff = []
    for d, (a, b) in EFFECTIVE_INERTIA.items():
        if b in res.values and a not in res.values:
            eff.append(f"{a} + {b} ({a} fixed at {cal.vehicle_.parameters()[a]:.6g})")
    out["effective_inertia"] = eff
    return out


def effective_inertia_sigma(cal) -> dict:
    """1-sigma of each DOF's effective inertia (rigid + added) from the joint covariance."""
    res = cal.fit_
    out = {}
    for d, (a, b) in EFFECTIVE_INERTIA.items():
        if res is None or not ({a, b} & set(res.names)):
            out[d] = None
            continue
        v = np.zeros(len(res.names))
        for k in (a, b):
            if k in res.names:
                v[res.names.index(k)] = 1.0
        out[d] = float(np.sqrt(max(v @ res.covariance @ v, 0.0)))
    return out


#: A fitted gyro bias beyond this many prior sds is flagged: it explains what the dynamics do not.
BIAS_FLAG_SD = 3.0


def gyro_bias_flags(res, sd: float) -> list[str]:
    """Runs and axes whose fitted gyro bias is more than :data:`BIAS_FLAG_SD` prior sds
    (``sd``, rad/s): the bias then absorbs a misfit of the dynamics (issue 21: 0.081 rad/s in
    r where the vehicle's own EKF estimated at most 0.017)."""
    return _bias_flags({} if res is None else res.gyro_bias, "pqr", sd, "gyro bias", "rad/s",
                       "in-run bias", "(a misfit of the model, or a wrong sensors.imu.gyro_bias_sd)")


def _bias_flags(biases: dict, axes: str, sd: float, what: str, unit: str, spec: str, why: str) -> list[str]:
    """One sentence per run and axis whose fitted sensor bias is beyond :data:`BIAS_FLAG_SD` prior sds."""
    return [f"run {run}: {what} in {axis} {x:+.4f} {unit} is {abs(x) / sd:.1f} sd of the IMU's {spec} ({sd:g} "
            f"{unit}): it explains what the dynamics do not {why}"
            for run, b in biases.items() for axis, x in zip(axes, b) if abs(x) > BIAS_FLAG_SD * sd]


def acc_bias_flags(res, sd: float) -> list[str]:
    """Runs and axes whose fitted accelerometer offset is more than :data:`BIAS_FLAG_SD` prior
    sds (``sd``, m/s^2): a constant force per unit mass the dynamics do not give (a misfit of
    the model: buoyancy, a current, a tether; or a wrong ``sensors.imu.acc_bias_sd``)."""
    return _bias_flags({} if res is None else getattr(res, "acc_bias", {}), "xyz", sd, "accelerometer offset",
                       "m/s^2", "offset", "(a misfit of the model, e.g. buoyancy, a current or a tether; "
                       "or a wrong sensors.imu.acc_bias_sd)")


def attitude_bias_flags(res) -> list[str]:
    """Runs whose fitted attitude-filter offset is more than :data:`BIAS_FLAG_SD` prior sds
    (:data:`uvsim.fitting.objective.ATTITUDE_BIAS_SIGMA`): a constant tilt the dynamics do not
    give, e.g. a centre of gravity or buoyancy off the vehicle file's (free ``x_b``, ``y_b``)."""
    out = []
    for run, b in ({} if res is None else getattr(res, "attitude_bias", {})).items():
        for axis, x in zip(("roll", "pitch"), b):
            if abs(x) > BIAS_FLAG_SD * ATTITUDE_BIAS_SIGMA:
                out.append(f"run {run}: attitude filter offset in {axis} {x:+.4f} rad is "
                           f"{abs(x) / ATTITUDE_BIAS_SIGMA:.1f} sd of a filter's tilt error ({ATTITUDE_BIAS_SIGMA:g} "
                           "rad): a constant tilt the dynamics do not give (a centre of gravity or buoyancy off "
                           "the vehicle file's: free x_b, y_b; or a misaligned IMU)")
    return out


def prior_report(res) -> dict:
    """The report's ``prior``: the data weight and, per freed parameter, the prior mean and
    sd, the posterior sd, how far the data moved it (in prior sds) and how much they
    determined it (``1 - posterior sd / prior sd``: 0 = the prior alone, 1 = the data alone)."""
    if res is None or not res.prior_sd:
        return {"used": False}
    par = {}
    for k in res.names:
        s0, s1 = res.prior_sd[k], res.std.get(k)
        par[k] = {"mean": res.prior_mean[k], "prior_sd": s0, "posterior_sd": s1,
                  "moved_prior_sd": (res.values[k] - res.prior_mean[k]) / s0,
                  "determined": None if s1 is None else max(0.0, 1.0 - s1 / s0)}
    return {"used": True, "data_weight": res.data_weight, "parameters": par}


def build_report(cal, ds, runs, problems, ga, bounds_of, t0, t_ga, t_ref) -> dict:
    """The JSON-ready report of a fitted Calibrator (docs/calibration.md, report.json)."""
    meas = cal._meas(ds.runs, cal.signal_weights)
    gb = cal.fit_.gyro_bias if cal.fit_ is not None else None
    judged = judged_for(cal, ds.runs, meas)
    fitted = evaluate_runs(cal.vehicle_, ds.runs, meas, gb, initial_velocity=cal.initial_velocity, judged_as=judged)
    initial = evaluate_runs(cal.initial_vehicle_, ds.runs, meas, None, initial_velocity=cal.initial_velocity,
                            judged_as=judged)
    cal.evaluation_ = {"fitted": fitted, "initial": initial, "meas": {r.name: m for r, m in zip(ds.runs, meas)},
                       "judged": judged}
    per_run = {r.name: run_entry(r, fitted[r.name], initial[r.name]) for r in ds.runs}
    val, val_fit = pooled(fitted, ds.runs, "validation")
    tr, tr_fit = pooled(fitted, ds.runs, "train")
    val0, val0_fit = pooled(initial, ds.runs, "validation")
    tr0, _ = pooled(initial, ds.runs, "train")
    p = cal.vehicle_.parameters()
    p0 = cal.initial_vehicle_.parameters()
    res = cal.fit_
    settings = cal._settings()
    noise = {r.name: m.describe() for r, m in zip(ds.runs, meas)}
    return {
        "vehicle": cal.initial_vehicle_.name,
        "dataset": str(ds.path),
        "dofs": list(problems),
        "parameters": dict(cal.params_),
        "uncertainty": dict(cal.uncertainty_),
        # (a supply voltage kept by supply_voltage="auto": the start model's fixed curve is the family's nominal sheet)
        "initial_parameters": {k: float(p0[k] if k in p0 else cal.supply_voltage_["nominal_voltage"])
                               for k in cal.params_},
        "ga_parameters": dict(cal.ga_params_),
        "free_parameters": [] if res is None else list(res.names),
        "bounds": {k: [float(x) for x in bounds_of(k)] for k in cal.params_},
        "at_bounds": [] if res is None else list(res.at_bounds),
        "physical_limit": [] if res is None else list(res.physical_limit),
        "effective_inertia": {d: p[a] + p[b] for d, (a, b) in EFFECTIVE_INERTIA.items()},
        "effective_inertia_uncertainty": effective_inertia_sigma(cal),
        "linear_damping": {d: p[k] for d, k in LINEAR_DAMPING.items()},
        "quadratic_damping": {d: p[k] for d, k in QUADRATIC_DAMPING.items()},
        "gyro_bias": {} if res is None else dict(res.gyro_bias),
        "prior": prior_report(res),
        "gyro_bias_flags": gyro_bias_flags(res, gyro_bias_sd(cal.initial_vehicle_)),
        "attitude_bias": {} if res is None else dict(res.attitude_bias),
        "attitude_bias_flags": attitude_bias_flags(res),
        "acc_bias": {} if res is None else dict(getattr(res, "acc_bias", {})),
        "acc_bias_flags": acc_bias_flags(res, acc_bias_sd(cal.initial_vehicle_)),
        "validation_rmse": val, "validation_fit_percent": val_fit,
        "training_rmse": tr, "training_fit_percent": tr_fit,
        "initial_validation_rmse": val0, "initial_validation_fit_percent": val0_fit,
        "initial_training_rmse": tr0,
        "per_run": per_run,
        "verdict": calibration_verdict(ds.runs, fitted, initial, cal.evaluation_["meas"]),
        # what the verdict, the RMSEs, Fit % and the plots compare (whole runs, or windows on closed-loop logs)
        "judged": judged,
        "identifiability": cal.identifiability_,
        "refinement": {} if res is None else {"stages": res.stages, "cost": res.cost,
                                              "n_residuals": res.n_residuals},
        "signal_scales": noise,
        "noise": noise,
        "attitude_lag": cal.lag_,
        "sensor_latency": cal.latency_,
        # supply_voltage="auto": the refit on the T200 voltage family and whether it was kept (None: not asked)
        "supply_voltage_auto": getattr(cal, "supply_voltage_", None),
        "notes": sorted({n for m in meas for n in m.notes}),
        "run_weights": {r.name: float(cal._ga_run_weights.get(r.name, r.weight)) for r in runs},
        "training_runs": [r.name for r in runs],
        "evaluations": int(ga["evaluations"]),
        "generations_run": int(ga["generations_run"]),
        "ga_seconds": float(ga["wall_s"]),
        "refine_seconds": float(t_ref - t_ga),
        "wall_seconds": float(time.perf_counter() - t0),
        "settings": {**settings.__dict__, "margin": cal.margin, "workers": cal.workers, "dask": cal.dask,
                     "batch_rows": cal.batch_rows, "low_speed_exponent": cal.low_speed_exponent,
                     "signal_weights": dict(cal.signal_weights or {}), "noise": dict(cal.noise or {}),
                     "ga_channels": cal.ga_channels, "free": cal.free, "fix": cal.fix,
                     "bounds": {k: list(v) for k, v in (cal.bounds or {}).items()},
                     "refine": cal.refine, "horizons": cal._horizons(), "continuity": cal._continuity(),
                     "max_iter": cal.max_iter,
                     "gyro_bias": cal.gyro_bias, "acc_bias": cal.acc_bias, "screen": cal.screen,
                     "attitude_lag": cal.attitude_lag,
                     "latency": cal.latency, "supply_voltage": cal.supply_voltage,
                     "initial_velocity": cal.initial_velocity, "judge_horizon": cal.judge_horizon,
                     "prior": cal.prior, "loss": cal.loss,
                     "sample_weighting": cal.sample_weighting},
        "logbook": {d: [dict(rec) for rec in lb] for d, lb in ga["logbooks"].items()},
    }
