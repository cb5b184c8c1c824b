"""``diagnose``: residual -> candidate effects -> refit -> before/after, by forward selection.

Procedure (issue 10; docs/diagnose.md gives the method with its references):

1. **Baseline.**  The given model, with the base coefficients named in ``retune``
   re-fitted (started from their equation-error estimate), on the training runs by the
   windowed prediction error of :mod:`uvsim.fitting` (multiple shooting, node states and
   gyro biases as nuisance parameters).
2. **Screen** (:meth:`Selector.step <uvsim.diagnosis.selector.Selector.step>`): every
   candidate variant (:mod:`uvsim.diagnosis.candidates`) is fitted to the inverse-dynamics
   residual of the current model together with the current free parameters (a fraction
   of a second each, no simulation); the share of the residual it removes ranks the
   effects, picks each effect's variant and seeds the parameters.
3. **Fit** the best through the simulator (windowed output error on the training runs),
   jointly with the re-tuned coefficients and the effects accepted before.
4. **Judge** (:mod:`uvsim.diagnosis.decision`): physical values, an in-sample robust Wald
   test, and a validation improvement confirmed by a block bootstrap over windows; the
   simplest sufficient variant and the most parsimonious effect win
   (:mod:`uvsim.diagnosis.step_choice`).
5. **Forward selection.**  The accepted effect joins the model and steps 2-4 repeat with
   the remaining effects until nothing significant is left or ``max_effects`` are in.  Step 0
   tries the base model's thrust curve alone (:data:`STEP0_VARIANTS`); when it is accepted, the
   effects that screen at least as well are fitted on the given model too, and one that explains
   the validation runs clearly better takes step 1 in its place
   (:func:`uvsim.diagnosis.step_choice.base_effect_challenge`).
6. **Report** every step (before/after costs, each candidate's numbers and why it was
   or was not accepted), the validation RMSE of the given and the corrected model (of free
   simulations, or on closed-loop logs of windowed predictions: :func:`judged_prediction`),
   and the corrected vehicle.

With a ``checkpoint`` every finished fit is saved (atomically); a run resumed from it
repeats none of them and reaches the same answer.
"""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from uvsim.fit_settings import DEFAULT_HORIZON  # noqa: F401 (its home: uvsim.fit_settings)
from uvsim.blas import single_thread
from uvsim.checkpoint import Checkpoint, fingerprint
from uvsim.diagnosis.candidates import BASE_MODEL, EFFECTS
from uvsim.diagnosis.decision import LEVEL, MIN_RELATIVE, VAL_LEVEL, WALD_P, open_loop_verdict
from uvsim.diagnosis.residual import concentration, verdict
from uvsim.diagnosis.selector import VARIANT_SHARE, Selector
from uvsim.diagnosis.step_choice import (alternative_challenger, base_effect_challenge, base_effect_kept,
                                         blocked_fallback, inertia_challenger, parsimonious, richer_challenger,
                                         simplest_sufficient, still_needed, unit_beside_base)
from uvsim.diagnosis.summary import parameter_reports, retuned_report, row_report, summary_message
from uvsim.diagnosis.unit_choice import every_gain_step, unit_forms, unit_in_every_gain
from uvsim.estimation.lag import attitude_lag_setting
from uvsim.errors import CalibrationError
from uvsim.fitting.evaluate import check_judge_horizon, judged_prediction, pooled
from uvsim.fitting.verdict import compare as compare_models
from uvsim.latency import runs_for
from uvsim.logs import Dataset, read_dataset
from uvsim.signals import check_signal_settings
from uvsim.plausibility import check_runs, parse_allow
from uvsim.progress import as_progress
from uvsim.fitting.worker_pool import WorkerPool, with_worker_pool
from uvsim.schema import check_workers, is_whole_number
from uvsim.vehicle import load_vehicle

#: What a resumed diagnosis must keep equal (for the checkpoint's mismatch message).
RESUME_NEEDS = "dataset, vehicle and settings (--retune, --only, --noise, --weights, --horizon, --top, --max-iter)"

#: Validation cost per residual entry (in squared noise sigmas) below which the model
#: is "at the noise level" (confidence "high").
AT_NOISE = 1.5
#: The base-model variants fitted before any effect (issue 22, "thrust model first": a curve
#: mismatch is absorbed before actuator faults are judged).  The hydrodynamic re-tunes compete
#: with the effects from step 1 on: fitted first they absorb the drag of a tether or the pull of
#: a current (foreign case b: the tether named after base_model:hydrodynamics left 221 mm of validation
#: RMSE, 9 mm alone).  ``supply_voltage`` exists for thrusters on a voltage-family curve only.
STEP0_VARIANTS = ("thrust_scale", "supply_voltage")
@dataclass
class Diagnosis:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    report : JSON-serializable dict (keys in docs/diagnose.md).
    vehicle_before, vehicle_after : the given and the corrected vehicle.
    effects : accepted (Candidate, fitted values) in the order they were chosen.
    train, validation : the runs.
    open_loop_before, open_loop_after : per validation run, the predictions the verdict judged
        (report ``judged``: free simulations, :func:`uvsim.fitting.evaluate.open_loop`, or windows on
        closed-loop logs, :func:`uvsim.fitting.evaluate.windowed`) of the given and corrected model.
    """

    report: dict
    vehicle_before: object
    vehicle_after: object
    effects: list
    train: list
    validation: list
    open_loop_before: list = field(repr=False, default_factory=list)
    open_loop_after: list = field(repr=False, default_factory=list)
    measurements_validation: list = field(repr=False, default_factory=list)


def _split(dataset: Dataset) -> tuple[list, list, str]:
    train, val = dataset.train, dataset.validation
    if val and train:
        return train, val, "from the manifest"
    runs = dataset.runs
    if len(runs) < 3:
        raise CalibrationError(f"{dataset.path}: need at least 3 runs to diagnose (training and validation), "
                               f"got {len(runs)}: log more runs, or cut a long one into runs with a segments file "
                               "(uvsim import ... --segments, docs/import_export.md)")
    val = runs[2::3]
    train = [r for r in runs if r not in val]
    return train, val, ("the manifest has no training/validation split: every third run is used for validation "
                        f"({', '.join(r.name for r in val)})")


def _one_blas_thread(fn):
    """``fn`` run with one BLAS thread (:func:`uvsim.blas.single_thread`).  The screening's least
    squares (:mod:`uvsim.diagnosis.regression`: thousands of small problems on ~10^4 residual rows)
    only synchronised the threads of a multi-threaded BLAS: one screening of the tethered tank
    dataset took 7 s with them and 1.8 s with one thread on a loaded 2-core machine
    (docs/performance.md).  The fits' worker processes give the parallelism."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_thread():
            return fn(*args, **kwargs)
    return wrapper


@_one_blas_thread
@with_worker_pool
def diagnose(data, vehicle=None, *, retune: Sequence[str] | None = None, only: Sequence[str] | None = None,
             noise: Mapping[str, float] | None = None, weights: Mapping[str, float] | None = None,
             horizon: float = DEFAULT_HORIZON, max_effects: int = 2, top: int = 3, max_iter: int = 12,
             workers: int = 1, progress=None, allow=(), checkpoint=None, resume=None,
             attitude_lag="auto", judge_horizon="auto") -> Diagnosis:
    """Diagnose which catalogue effects the model lacks (module docstring).

    Parameters
    ----------
    data : dataset directory (LOG_FORMAT) or a :class:`uvsim.logs.Dataset`.
    vehicle : the model (name, file or Vehicle); default the manifest's vehicle.
    retune : base coefficients re-fitted with every model (e.g. ``["X_uu", "N_rr"]``),
        within +-50 % (``uvsim.fitting.parameters.default_bounds``).
    only : restrict the candidate effects to these catalogue names.
    noise : 1-sigma noise by signal group or channel; estimated where not given.
    weights : weights by signal group or channel (0 leaves a channel out).
    horizon : window length of the fits, s.
    max_effects : largest number of effects added (forward selection steps).
    top : candidates fitted through the simulator per step (by screening rank).
    max_iter : Levenberg-Marquardt iterations per fit.
    workers : processes for the simulations (kept for the whole diagnosis,
        :class:`uvsim.fitting.worker_pool.WorkerPool`).
    progress : the stages (each fit, screening and validation) and notes: a callable(message)
        receiving each stage's name as it starts, or a :class:`uvsim.progress.Progress`.
    allow : names of plausibility checks (:mod:`uvsim.plausibility`) that may fail; every
        other finding is an error naming the file, column and row.
    checkpoint : file to which every finished fit is saved (atomically, after each fit).
    resume : checkpoint file to continue from (its finished fits are not repeated); it
        must come from the same dataset, vehicle and settings.  With ``checkpoint`` unset
        the resumed run keeps saving to ``resume``.
    attitude_lag : time constant (s) of the attitude filter that logged the Euler angles, or
        "auto" (default): estimated from the training runs' gyro and angles and used when
        longer than 1.5 sample intervals, as the calibration does
        (:func:`uvsim.estimation.lag.attitude_lag_setting`); 0: none.
    judge_horizon : what the verdict compares on the validation runs (:func:`judged_prediction`):
        "auto" (default: windows of :data:`uvsim.fitting.evaluate.DECLARED_CLOSED_LOOP_HORIZON_S` when
        the manifest says a validation run was flown under an autopilot, else whole runs, or windows of
        :data:`uvsim.fitting.evaluate.CLOSED_LOOP_HORIZON_S` when the given model's free simulation leaves
        the data), "whole", or a window length in seconds.
    """
    t_start = time.perf_counter()
    progress = as_progress(progress)
    say = progress.say
    dataset = data if isinstance(data, Dataset) else read_dataset(data)
    if vehicle is None:
        vehicle = dataset.vehicle_file or dataset.vehicle
        if vehicle is None:
            raise CalibrationError(f"{dataset.path}: no vehicle given and the manifest names none")
    veh = load_vehicle(vehicle)
    check_runs(dataset.runs, veh, parse_allow(allow, "allow"))  # units, sampling, PWM range
    if only is not None:
        unknown = sorted(set(only) - set(EFFECTS))
        if unknown:
            raise CalibrationError(f"unknown candidate effect(s) {unknown}; known: {', '.join(EFFECTS)}")
    check_signal_settings(noise, weights)
    n_workers = workers.workers if isinstance(workers, WorkerPool) else workers
    for name, value in (("max_effects", max_effects), ("top", top), ("max_iter", max_iter), ("workers", n_workers)):
        if not (is_whole_number(value) and value >= 1):
            raise CalibrationError(f"{name} must be a positive integer (1 or more), got {value!r}")
    check_workers(n_workers, "workers", error=CalibrationError)  # and not more processes than the machine runs
    if not (horizon is None or (np.isfinite(horizon) and horizon > 0)):
        raise CalibrationError(f"horizon must be a positive number of seconds, got {horizon!r}")
    check_judge_horizon(judge_horizon)
    train, val, split_note = _split(dataset)
    train, val = runs_for(veh, train), runs_for(veh, val)  # the vehicle's sensors.latency (uvsim.latency)
    lag = attitude_lag_setting(train, attitude_lag)
    kinds = {(r.input_kind, len(r.input_columns)) for r in train + val}
    if len(kinds) > 1:
        raise CalibrationError(f"{dataset.path}: runs mix input kinds {sorted(kinds)}; diagnose one kind at a time")
    key = fingerprint({"vehicle": veh.to_dict(), "runs": [(r.name, float(np.nansum(r.data.to_numpy())))
                                                          for r in train + val],
                       "retune": list(retune or []), "only": None if only is None else sorted(only),
                       "noise": noise, "weights": weights, "horizon": horizon, "top": top, "max_iter": max_iter,
                       "attitude_lag": lag["tau"], "judge_horizon": judge_horizon})
    store, on_fit = _checkpoint_store(checkpoint, resume, key, say)
    sel = Selector(veh, train, val, retune=retune, noise=noise, weights=weights, horizon=horizon,
                   max_iter=max_iter, workers=workers, say=progress, store=store, on_fit=on_fit,
                   attitude_lag=lag["tau"])

    judged = judged_prediction(veh, val, sel.meas_va, judge_horizon)
    sel.judge_horizon = judged["horizon_s"]
    if judged["prediction"] == "windows":
        say(f"the verdict compares {judged['why']}")
    # 1. baseline ----------------------------------------------------------------------
    values: dict = {}
    base_fit = None
    if sel.retune:
        start = sel.seed_retune(veh)
        sp = sel.space(veh, sel.retune, sel.retune_bounds, start, {})
        base_fit = sel.fit_train(veh, sp, "the baseline (re-tuned base coefficients)")
        values = dict(base_fit.values)
    with progress.stage(f"validation cost of the baseline ({len(val)} validation run(s))"):
        val_given = sel.validation(veh, {})
        val_cur = sel.validation(veh, values) if values else val_given
    retune_verdict, asked_retune = None, list(sel.retune)
    if values:
        # the re-tune is a change of the model like an effect: the baseline keeps it only when the
        # verdict on the validation runs' free simulations calls it better than the given model.
        # The effects' fits still free it beside each effect, and the verdict judges the two together.
        retune_verdict = open_loop_verdict(val_given["open_loop"], val_cur["open_loop"])
        if not retune_verdict["ok"]:
            say(f"the re-tune of {', '.join(sel.retune)} alone is not kept: {retune_verdict['message']}")
            values, val_cur = {}, val_given
    accepted: list = []
    accepted_values: list = []
    steps = []
    exclude: set = set()
    # step 0: the thrust curve first, judged like an effect; step 1..: effects and the rest of the base model
    base_first = only is None or BASE_MODEL in only
    plan = ([0] if base_first else []) + list(range(1, max_effects + 1))
    if not base_first:
        exclude.add(BASE_MODEL)

    def choose(st):
        """The step's winner: the simplest accepted candidate, or a fallback for one the verdict
        alone refused, then its variants' challenges (uvsim.diagnosis.step_choice) and a faulty
        thruster unit's forms (uvsim.diagnosis.unit_choice); None."""
        winners = [row for row in st["fitted"] if row.get("accepted")]
        best = parsimonious(winners)
        if best is None:
            best = blocked_fallback(sel, st, val_cur)
        if best is not None:
            best = richer_challenger(sel, best, st, val_cur) or best
            best = simplest_sufficient(sel, best, st, val_cur) or best
            best = alternative_challenger(sel, best, st, val_cur) or best
            best = inertia_challenger(sel, best, st, val_cur) or best
        # a faulty unit's two forms (its gain; its gain and reverse ratio) against each other and every gain
        return unit_forms(sel, best, st, val_cur) or best

    def record(k, st, best) -> dict:
        step_rep = {"step": k, "model": " + ".join(c.label for c in accepted) or "the given model",
                    "before_cost_per_entry": val_cur["per_entry"], "screening": st["screening"],
                    "screened": st["screened"], "candidates": [row_report(row, best) for row in st["fitted"]],
                    "chosen": None}
        steps.append(step_rep)
        return step_rep

    def adopt(best, step_rep) -> None:
        nonlocal values, val_cur
        c = best["candidate"]
        accepted.append(c)
        exclude.add(c.effect)
        # the candidate was fitted together with everything chosen before and the re-tuned
        # coefficients: its fit is the new model
        joint = best["result"]
        values = dict(best["all_values"])
        val_cur = best["val"]
        step_rep.update(chosen=c.label, after_cost_per_entry=val_cur["per_entry"],
                        joint_fit={"values": joint.values, "std": joint.std, "cost": joint.cost,
                                   "at_bounds": joint.at_bounds})
        accepted_values.append(joint)

    def forward(k) -> bool:
        """One forward-selection step (screen, fit, judge, choose); True when an effect joined."""
        st = sel.step(accepted, values, val_cur, exclude=exclude, only=[BASE_MODEL] if k == 0 else only, top=top,
                      k_step=k, variants=STEP0_VARIANTS if k == 0 else None)
        best = choose(st)
        challenge = None
        if k == 0 and best is not None and (only is None or set(only) - {BASE_MODEL}):
            # the base model's variant competes with the catalogue's effects on the given model
            # (base_effect_challenge): a dead unit must not be pre-empted by a thrust scale that
            # absorbs part of what it does.  Only effects that remove at least as much of the
            # equation error as the base model's variant are fitted to challenge it
            floor = next((r["screening_reduction"] for r in st["screened"]
                          if r["variant"] == best["candidate"].variant), None)
            st1 = sel.step(accepted, values, val_cur, exclude=exclude | {BASE_MODEL}, only=only, top=top, k_step=1,
                           floor=floor)
            best1 = choose(st1)
            why = base_effect_challenge(best, best1)
            challenge = {"base_model": best["candidate"].label, "screening_floor": floor,
                         "fitted": [row_report(row, best1) for row in st1["fitted"]],
                         "best_effect": None if best1 is None else best1["candidate"].label,
                         "kept": why is None}
            nested = None if why is None else unit_beside_base(sel, best, best1, st1["all_screened"])
            if nested is not None:
                challenge["nested"] = row_report(nested, nested if nested["accepted"] else None)
            if nested is not None and nested["accepted"]:
                # every gain won, but all except one unit's are the base model's common curve: the
                # nested model (the curve + that unit) is as good, so the base model stays and the
                # unit is the effect (step_choice.unit_beside_base)
                kept = (f"{best1['candidate'].label} on the given model is clearly better ({why}), but "
                        f"{nested['candidate'].label} beside it is as good")
                best["why"] += f"; kept against the effects on the given model ({kept})"
                challenge.update(why=kept, kept=True)
                step_rep = record(k, st, best)
                step_rep["base_challenge"] = challenge
                adopt(best, step_rep)
                adopt(nested, record(1, {"screening": None, "screened": [], "fitted": [nested]}, nested))
                # the scale kept here stands beside a unit the challenge found: the hydrodynamic variants
                # still compete in the later steps, as after a base model set aside (the catalogue leaves
                # out those that free the scale again, Selector.step)
                exclude.discard(BASE_MODEL)
                return True
            if why is not None:
                best["why"] += "; set aside: " + why
                record(k, st, None)["base_challenge"] = {**challenge, "fitted": "step 1", "why": why}
                adopt(best1, record(1, st1, best1))
                return True
            kept = base_effect_kept(best, best1)
            best["why"] += f"; kept against the effects on the given model ({kept})"
            challenge["why"] = kept
        step_rep = record(k, st, best)
        if k == 0 and best is not None and challenge is not None:
            step_rep["base_challenge"] = challenge
        if best is None:
            return False
        adopt(best, step_rep)
        return True

    for k in plan:
        if steps and steps[-1]["step"] >= k:  # step 1 taken already: its effect won against the base model
            continue
        if not forward(k) and k != 0:
            break
    # stepwise selection: each earlier effect must still earn its place beside the later ones
    # (backward elimination); when one is dropped, a forward step looks for what it stood in
    # for (a dropped effect is not tried again, so this ends)
    backward: list = []
    k_next = plan[-1] + 1
    for _ in range(max_effects):
        if len([c for c in accepted if c.effect != BASE_MODEL]) < 2:
            break
        accepted, values, val_cur, final_fit, rows = still_needed(sel, accepted, values, val_cur,
                                                                  accepted_values[-1])
        backward += rows
        if all(r["kept"] for r in rows):
            break
        accepted_values.append(final_fit)
        if not forward(k_next):
            break
        k_next += 1
    # every unit's gain in the final model: its outlying unit beside the base model with the thrust
    # scale free, as good with fewer parameters? (uvsim.diagnosis.unit_choice.unit_in_every_gain)
    again = unit_in_every_gain(sel, accepted, values, val_cur)
    if again is not None:
        steps.append(every_gain_step(again, accepted, val_cur, k_next))
        if again.get("chosen") is not None:
            accepted, values, val_cur = again["accepted"], again["values"], again["val"]
            accepted_values.append(again["fit"])
    # result ------------------------------------------------------------------------------
    veh_after = sel.vehicle_for(accepted)
    if values:
        veh_after = veh_after.with_parameters(values)
    with progress.stage(f"validation before / after ({len(val)} validation run(s))"):
        ol_before = sel.predictions(veh)
        ol_after = sel.predictions(veh_after)
    # the corrected model against the given one, as calibration judges a fit (None: unchanged)
    changed = bool(accepted) or bool(values)
    model_verdict = None
    if changed:
        model_verdict = compare_models(sel.meas_va, [o["pred"] for o in ol_before], [o["pred"] for o in ol_after],
                                       names=("the given model", "the corrected model"))
    final = accepted_values[-1] if accepted_values else None
    effects_rep, base_rep = parameter_reports(accepted, values, final, veh)
    names = [c.effect for c in accepted if c.effect != BASE_MODEL]
    at_noise = val_cur["per_entry"] <= AT_NOISE
    confidence = ("high" if at_noise else "partial") if names else "none"
    msg = summary_message(accepted, values, base_rep, val_given, val_cur, AT_NOISE, retune_verdict, asked_retune,
                          backward)
    verd = verdict(val_cur["per_entry"], names, concentration(sel.meas_va, ol_after, val), AT_NOISE,
                   base_model_off=base_rep is not None)
    if verd["status"] in ("partly explained", "not explained"):
        msg += " " + verd["message"][0].upper() + verd["message"][1:] + "."
    report = {
        "effects": effects_rep,
        "verdict": verd,
        "base_model": base_rep,
        "not_observable": sel.not_observable,
        "effect": names[0] if len(names) == 1 else ("none" if not names else "+".join(names)),
        "confidence": confidence,
        "message": msg,
        "retuned": retuned_report(sel, values, veh, final if final is not None else base_fit),
        "retune_verdict": None if retune_verdict is None else {"retune": asked_retune,
                                                               "status": retune_verdict["status"],
                                                               "kept": bool(retune_verdict["ok"]),
                                                               "message": retune_verdict["message"]},
        "model_verdict": model_verdict,
        "judged": judged,
        "steps": steps,
        "backward": backward,
        "rmse_before": pooled(ol_before),
        "rmse_after": pooled(ol_after),
        "validation_cost_per_entry": {"given": val_given["per_entry"], "baseline": steps[0]["before_cost_per_entry"]
                                      if steps else val_given["per_entry"], "final": val_cur["per_entry"]},
        "criterion": {"method": "robust Wald test in training and block bootstrap over validation windows "
                                "(uvsim.diagnosis.decision)", "wald_p": WALD_P, "validation_level": VAL_LEVEL,
                      "level": LEVEL, "min_relative": MIN_RELATIVE, "horizon_s": horizon,
                      "variant_share": VARIANT_SHARE, "at_noise": AT_NOISE},
        "noise": {r.name: m.describe() for r, m in zip(train + val, sel.meas_tr + sel.meas_va)},
        "sampling_notes": [n for m in sel.meas_tr + sel.meas_va for n in m.notes],
        "attitude_lag": lag,
        "vehicle": veh.name,
        "data": str(dataset.path),
        "runs": {"train": [r.name for r in train], "validation": [r.name for r in val], "split": split_note},
        "fits": sel.fits,
        "seconds": time.perf_counter() - t_start,
    }
    return Diagnosis(report, veh, veh_after, list(zip(accepted, [dict(values) for _ in accepted])), train, val,
                     ol_before, ol_after, sel.meas_va)


def _checkpoint_store(checkpoint, resume, key: str, say):
    """The store of finished fits (restored from ``resume``) and the callback that saves it."""
    store: dict = {}
    if resume is not None:
        ck = Checkpoint(resume, kind="diagnosis", key=key, what="the diagnosis", must_match=RESUME_NEEDS)
        store = dict(ck.load())
        say(f"resuming from {resume}: {len(store)} finished fit(s)")
    path = checkpoint if checkpoint is not None else resume
    if path is None:
        return store, None
    ck = Checkpoint(Path(path), kind="diagnosis", key=key, what="the diagnosis", must_match=RESUME_NEEDS)

    def on_fit(st):
        ck.save(st, progress=f"{len(st)} finished fit(s)")

    return store, on_fit
