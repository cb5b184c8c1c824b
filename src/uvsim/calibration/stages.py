"""The two stages of a :class:`uvsim.calibration.Calibrator` fit, set up from its settings.

* :func:`ga_stage` - the GA stage: each DOF's :class:`uvsim.calibration.evaluation.DofProblem`
  (its runs, channel weights, run weights, bounds), the batched evaluator, the checkpoint's
  fingerprint, then :func:`uvsim.calibration.ga.run_ga`;
* :func:`joint_stage` - the joint stage: the free set (kept and screened candidates), the
  checkpoint's fingerprint, the whole-run stage's judged scales, then
  :func:`uvsim.calibration.joint.run_joint`.

The engines are :mod:`uvsim.calibration.ga` and :mod:`uvsim.calibration.joint`; the order of
the stages, the refits and the report are :meth:`uvsim.calibration.Calibrator.fit`'s.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from uvsim.calibration.batching import prepare_runs
from uvsim.calibration.evaluation import BatchEvaluator, DofProblem
from uvsim.calibration.fitness import used_channels
from uvsim.calibration.ga import fingerprint, run_ga
from uvsim.calibration.inputs import combine_weights, run_amplitude
from uvsim.calibration.joint import JointCheckpoint, joint_checkpoint_path, run_joint
from uvsim.calibration.params import DOF_PARAMETERS, default_channel_weights
from uvsim.calibration import trade_off
from uvsim.calibration.selection import joint_candidates
from uvsim.errors import CalibrationError
from uvsim.fitting.evaluate import judged_scales

#: The joint stage's progress label by checkpoint tag (the first fit, the refits).
JOINT_LABELS = {"": "joint fit", ".latency": "joint fit again with the estimated sensor latency",
                ".supply": "joint fit on the T200 voltage family (--supply-voltage auto)", **trade_off.LABELS}
#: The joint stage stops when an iteration lowers the cost by less than this fraction of it
#: (:func:`uvsim.fitting.fit`'s ``ftol``). 1e-5 of a cost of N noise-normalized residuals is far
#: below the cost's own sampling spread (sqrt(2N)); with the tight continuity
#: (:data:`uvsim.fit_settings.DEFAULT_CONTINUITY`), ``fit``'s 1e-6 spent 16 more iterations on
#: the shipped tank dataset for changes in the 4th digit
#: (25 iterations, 30.5 s, against 9 and 13.3 s; docs/records/calibration.md, "Speed of the paper-size calibration").
JOINT_FTOL = 1e-5


def ga_stage(cal, veh, train, ga_dofs, fixed, bounds_of, base):
    uw = cal.signal_weights
    runs = [r for d in ga_dofs for r in train if r.dof == d]
    batch = prepare_runs(runs, initial_velocity=cal.initial_velocity, sensors=veh.sensors)
    meas, problems = [], {}
    for d in ga_dofs:
        w = combine_weights(default_channel_weights(d) if cal.ga_channels == "own" else {}, uw)
        idx = np.array([i for i, r in enumerate(runs) if r.dof == d])
        # per sample: the GA's fitness already averages each channel over its own samples
        ms = cal._meas([runs[i] for i in idx], w, run_weight=1.0, sample_weighting="per_sample")
        meas += ms
        if not any(used_channels(m) for m in ms):
            raise CalibrationError(
                f"dof {d}: its training runs log none of the signals its GA fitness uses "
                f"({sorted(c for c, v in w.items() if v > 0)}); logged: "
                f"{sorted({c for m in ms for g in m.groups.values() for c, ok in zip(g.channels, g.logged) if ok})}"
                f"; set signal_weights (--weights) or ga_channels='all'")
        rw = np.array([runs[i].weight for i in idx], float)
        if cal.low_speed_exponent:
            amp = np.array([run_amplitude(m) for m in ms])
            rw = rw * (amp / np.median(amp)) ** (-float(cal.low_speed_exponent))
        names = tuple(k for k in DOF_PARAMETERS[d] if k not in fixed)
        b = np.array([bounds_of(k) for k in names], float)
        init = np.array([base[k] for k in names])
        bad = [f"{k}: ({lo:g}, {hi:g}) do not contain the start value {v:g}"
               for k, (lo, hi), v in zip(names, b, init) if not lo <= v <= hi]
        if bad:
            raise CalibrationError("bounds for " + "; ".join(bad))
        problems[d] = DofProblem(d, names, b[:, 0], b[:, 1], init, idx, rw, w)
    cal._ga_run_weights = {runs[i].name: float(w) for p in problems.values()
                            for i, w in zip(p.run_index, p.run_weights)}
    evaluator = BatchEvaluator(veh, batch, problems, meas, cal.batch_rows, gyro_bias=cal.gyro_bias)
    key = fingerprint({
        "vehicle": veh.to_dict(), "runs": [(r.name, r.dof, r.weight, float(np.nansum(r.data.to_numpy())))
                                           for r in runs],
        "bounds": {d: p.lower.tolist() + p.upper.tolist() for d, p in problems.items()},
        "weights": {d: p.run_weights.tolist() for d, p in problems.items()},
        "signal_weights": {d: p.signal_weights for d, p in problems.items()}, "noise": cal.noise,
        "gyro_bias": cal.gyro_bias, "initial_velocity": cal.initial_velocity, "lag": cal.lag_["tau"]})
    hook = cal._hook(evaluator)
    try:
        ga = run_ga(problems, evaluator, hook, cal._settings(), checkpoint=cal.checkpoint,
                    resume=cal.resume if cal.resume is not None and Path(cal.resume).is_file() else None,
                    progress=cal._progress, problem_key=key)
    finally:
        hook.close()
    values = {}
    for d, p in problems.items():
        values.update(dict(zip(p.names, map(float, p.decode(ga["best"][d])))))
    return ga, values, problems


def joint_stage(cal, ds, start_veh, runs, meas, dofs, ga_dofs, fixed, extra, bounds_of, horizons, tag="",
               names=None, prior_mean=None):
    """The joint stage (:func:`uvsim.calibration.joint.run_joint`); ``names``: free exactly these
    (no screen); ``tag``: suffix of its checkpoint file; ``prior_mean``: the prior's means when
    not the start vehicle's values (the supply-voltage refit's vehicle has one more parameter)."""
    params = start_veh.parameters()
    keep = list(dict.fromkeys([k for k in joint_candidates(ga_dofs) if k not in fixed] + list(extra)))
    mixed = any(r.dof not in ga_dofs for r in runs)
    screen = [k for k in joint_candidates(dofs) if k not in fixed and k not in keep] if mixed else []
    if not cal.screen:
        keep, screen = keep + screen, []
    if names is not None:
        keep, screen = list(names), []
    names = keep + screen
    continuity = cal._continuity()
    key = fingerprint({
        "vehicle": start_veh.to_dict(), "runs": [(r.name, float(np.nansum(r.data.to_numpy()))) for r in runs],
        "keep": keep, "screen": screen, "bounds": {k: list(bounds_of(k)) for k in names},
        "horizons": horizons, "continuity": continuity, "ftol": JOINT_FTOL, "max_iter": cal.max_iter,
        "gyro_bias": cal.gyro_bias, "lag": cal.lag_["tau"],
        "weights": cal.signal_weights, "sample_weighting": cal.sample_weighting, "noise": cal.noise,
        "initial_velocity": cal.initial_velocity,
        "prior": bool(cal.prior), "uncertainty": cal.initial_vehicle_.uncertainty,
        # (the default loss leaves the key, and so earlier checkpoints, as they were)
        **({} if cal.loss == "linear" else {"loss": cal.loss}),
        "attitude_bias": bool(cal.attitude_bias),
        # (without the accelerometer bias the key, and so earlier checkpoints, as they were)
        **({"acc_bias": True} if cal.acc_bias else {})})
    ck_path = cal.checkpoint if cal.checkpoint is not None else cal.resume
    ck = None
    if ck_path is not None or cal.resume is not None:  # (tag: the refit with an estimated latency)
        ck = JointCheckpoint(None if ck_path is None else joint_checkpoint_path(f"{ck_path}{tag}"), key,
                             resume=None if cal.resume is None else joint_checkpoint_path(f"{cal.resume}{tag}"))
    iv = cal.initial_velocity

    def judged(H, values):  # the whole-run stage: each channel scaled by its own RMS error
        if H is not None:
            return None
        sc = judged_scales(start_veh, runs, meas, overrides=values, initial_velocity=iv)
        return [m.with_sigma(sc) for m in meas]

    return run_joint(start_veh, runs, meas, params, keep=keep, screen=screen,
                     bounds={k: bounds_of(k) for k in names}, horizons=horizons,
                     continuity=continuity, ftol=JOINT_FTOL, max_iter=int(cal.max_iter),
                     gyro_bias=bool(cal.gyro_bias), attitude_bias=bool(cal.attitude_bias),
                     acc_bias=bool(cal.acc_bias), initial_velocity=cal.initial_velocity,
                     workers=cal._workers(), checkpoint=ck, progress=cal._progress, label=JOINT_LABELS[tag],
                     prior_mean=(prior_mean or cal.initial_vehicle_.parameters()) if cal.prior else None,
                     prior_sd=cal.initial_vehicle_.uncertainty, loss=cal.loss, stage_meas=judged)
