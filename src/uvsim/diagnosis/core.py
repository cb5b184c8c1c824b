"""``diagnose``: residual -> signature -> candidate effects -> refit -> before/after.

Procedure (issue 6):

1. Simulate every run with the given model; output residuals (position,
   attitude, ... errors over time) and the inverse-dynamics generalized-force
   residual (:mod:`uvsim.diagnosis.residuals`).
2. Signature evidence on the force residual of the training runs
   (:mod:`uvsim.diagnosis.signatures`); it seeds the candidates.
3. For every catalogue effect (:mod:`uvsim.diagnosis.candidates`), fit its
   parameters on the training runs (least squares through the simulator,
   optionally re-tuning named base coefficients) and score it on the validation
   runs (:mod:`uvsim.diagnosis.fit`).
4. Decision rule: a candidate is *accepted* when
   (a) the baseline validation residual (the given model; with ``retune``, the
       given model with those base coefficients re-tuned) is above the noise
       level (normalized RMS > ``NOISE_LEVEL`` = 1.5 noise sigmas),
   (b) its BIC on the validation runs beats the baseline's by more than 10
       (``Delta BIC < -10``: "very strong" evidence on the Kass & Raftery 1995
       scale), with the effective sample size of the autocorrelated residual, and
   (c) it reduces the validation RMS by at least ``MIN_IMPROVEMENT`` = 20 %
       and the part of the residual it explains, ``sqrt(RMS_before^2 -
       RMS_after^2)``, is at least ``MIN_EXPLAINED`` = 2 noise sigmas (practical
       significance: with thousands of nearly white residuals BIC alone accepts
       tiny improvements, e.g. a 0.03 N "ballast" that only absorbs the error of
       the initial state on clean data);
   and its fitted values pass the effect's physical validation.  The accepted
   candidate with the lowest BIC is the answer; otherwise ``none`` (with
   ``retune``, the corrected vehicle then carries the re-tuned coefficients).
5. Confidence: ``high`` when the chosen effect brings the validation residual to
   within ``CONFIDENT`` = 2 noise sigmas (normalized RMS) or cuts its RMS at
   least tenfold (``EXPLAINED`` = 0.1: 99 % of the squared residual explained;
   long or unstable runs amplify the unavoidable error of the initial state, so
   a correct model need not reach the noise level), else ``partial`` (the effect
   explains part of the residual; something outside the catalogue, or a second
   effect, remains).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from uvsim.calibration.batching import prepare_runs
from uvsim.diagnosis import fit as fitmod
from uvsim.diagnosis.candidates import Candidate, build_candidates
from uvsim.diagnosis.residuals import force_residual, noise_levels, output_residuals, refine_initial_states
from uvsim.diagnosis.signatures import base_coefficient_evidence
from uvsim.diagnosis.signatures import evidence as signature_evidence
from uvsim.errors import CalibrationError, UvsimError, VehicleError
from uvsim.forces import make_term
from uvsim.logs import Dataset, read_dataset
from uvsim.plausibility import check_runs, parse_allow
from uvsim.vehicle import load_vehicle

NOISE_LEVEL = 1.5
DELTA_BIC = -10.0
MIN_IMPROVEMENT = 0.2
MIN_EXPLAINED = 2.0
CONFIDENT = 2.0
EXPLAINED = 0.1
_GROUP_TO_NOISE = {"position": "position", "attitude": "attitude", "velocity": "velocity", "rates": "rates"}


@dataclass
class Diagnosis:
    """Result of :func:`diagnose`: the JSON report plus the objects behind it.

    Attributes
    ----------
    report : JSON-serializable dict (keys in docs/diagnose.md).
    vehicle_before, vehicle_after : the given and the corrected vehicle.
    effect_term : the chosen effect (ForceTerm) or None.
    train, validation : the runs.
    residuals_before, residuals_after : per validation run, output residuals over time
        (:func:`uvsim.diagnosis.residuals.output_residuals`).
    force_before, force_after : per validation run, inverse-dynamics force residuals.
    """

    report: dict
    vehicle_before: object
    vehicle_after: object
    effect_term: object
    train: list
    validation: list
    residuals_before: list = field(repr=False, default_factory=list)
    residuals_after: list = field(repr=False, default_factory=list)
    force_before: list = field(repr=False, default_factory=list)
    force_after: list = field(repr=False, default_factory=list)


def _split(dataset: Dataset) -> tuple[list, list, str]:
    train, val = dataset.train, dataset.validation
    if val and train:
        return train, val, "from the manifest"
    runs = dataset.runs
    if len(runs) < 3:
        raise CalibrationError(f"{dataset.path}: need at least 3 runs to diagnose (training and validation), "
                               f"got {len(runs)}")
    val = runs[2::3]
    train = [r for r in runs if r not in val]
    return train, val, "manifest has no train/validation split: every third run is used for validation"


def _retune_spec(vehicle, names: Sequence[str] | None) -> dict:
    if not names:
        return {}
    from uvsim.calibration.params import parameter_bounds

    p = vehicle.parameters()
    unknown = [n for n in names if n not in p]
    if unknown:
        raise CalibrationError(f"retune: unknown base parameter(s) {unknown} of vehicle {vehicle.name}")
    b = parameter_bounds(list(names), p, margin=0.5)
    return {n: (float(p[n]), float(b[i, 0]), float(b[i, 1])) for i, n in enumerate(names)}


def _unit(effect_spec: dict | None, name: str) -> str:
    if effect_spec is None:
        return ""
    try:
        term = make_term(effect_spec)
        return term.units().get(name, "") if hasattr(term, "units") else ""
    except UvsimError:
        return ""


def _effect_with(cand: Candidate, params: Mapping[str, float]):
    """The effect term of ``cand`` with fitted ``params`` (validated: VehicleError if unphysical)."""
    term = make_term(dict(cand.effect))
    own = {k: v for k, v in params.items() if k in term.parameters()}
    return term.with_parameters(own)


def _group_rmse(d: dict) -> dict:
    return {k: float(v) for k, v in d.items()}


def _run_summary(m: dict) -> dict:
    out = {k: v for k, v in m.items() if k.endswith(("_m", "_rad", "_mps", "_radps"))}
    out["fit_percent"] = {g: d["fit_percent"] for g, d in m["groups"].items()}
    return out


def diagnose(data, vehicle=None, *, retune: Sequence[str] | None = None, only: Sequence[str] | None = None,
             noise: Mapping[str, float] | None = None, weights: Mapping[str, float] | None = None,
             max_nfev: int = 30, progress=None, allow=()) -> Diagnosis:
    """Diagnose which catalogue effect the model lacks (module docstring).

    Parameters
    ----------
    data : dataset directory (LOG_FORMAT) or a :class:`uvsim.logs.Dataset`.
    vehicle : the model (name, file or Vehicle); default the manifest's vehicle.
    retune : base coefficient names re-tuned together with every candidate
        (e.g. ``["X_u", "X_uu"]``), within +-50 % of their values.
    only : restrict the candidates to these catalogue names.
    noise : 1-sigma noise per signal group (position m, attitude rad, velocity
        m/s, rates rad/s); estimated from the data where not given.
    weights : per signal group weight (position, attitude, velocity, rates; default 1)
        multiplying its normalized residual's square in the fit and the score.
    max_nfev : function-evaluation budget of each least-squares fit.
    progress : optional callable ``progress(message)``.
    allow : names of plausibility checks (:mod:`uvsim.plausibility`) that may fail; every
        other check of the runs against the vehicle raises before any fit.

    Returns
    -------
    Diagnosis
    """
    say = progress or (lambda msg: None)
    dataset = data if isinstance(data, Dataset) else read_dataset(data)
    if vehicle is None:
        vehicle = dataset.vehicle_file or dataset.vehicle
        if vehicle is None:
            raise CalibrationError(f"{dataset.path}: no vehicle given and the manifest names none")
    veh = load_vehicle(vehicle)
    check_runs(dataset.runs, veh, parse_allow(allow, "allow"))  # units, sampling, PWM range
    train, val, split_note = _split(dataset)

    groups = ("position", "attitude", "velocity", "rates")
    for what, d in (("noise", noise), ("weights", weights)):
        for k, v in dict(d or {}).items():
            if k not in groups:
                raise CalibrationError(f"{what}: unknown signal group {k!r}; expected some of {', '.join(groups)}")
            if not (np.isfinite(v) and v > 0):
                raise CalibrationError(f"{what}.{k}: expected a positive number, got {v!r}")
    # noise level per run and signal group (IMU and motion-capture runs differ), user values win
    user_noise = dict(noise or {})
    scales_tr = [{**noise_levels([r]), **user_noise} for r in train]
    scales_va = [{**noise_levels([r]), **user_noise} for r in val]
    est = noise_levels(train + val)
    noise_used = {**est, **user_noise}
    # initial position/attitude: quadratic fit over the first second (residuals.refine_initial_states)
    batch_tr, batch_va = refine_initial_states(prepare_runs(train)), refine_initial_states(prepare_runs(val))
    for runs, scs, b in ((train, scales_tr, batch_tr), (val, scales_va, batch_va)):
        for r, sc, m in zip(runs, scs, b.measured):
            missing = [g for g in ("position", "attitude", "velocity", "rates") if _has(m, g) and g not in sc]
            if missing:
                raise CalibrationError(f"run {r.name}: cannot estimate the noise level of {missing} (too few "
                                       "samples); give it with noise={...} / --noise")

    # 1. baseline residuals -------------------------------------------------------
    say("simulating the given model")
    base_cand = Candidate("none", [], np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0))
    base_tr = fitmod.evaluate(veh, batch_tr, base_cand, np.zeros(0), scales_tr, weights)
    base_va = fitmod.evaluate(veh, batch_va, base_cand, np.zeros(0), scales_va, weights)
    fres_tr = [force_residual(veh, r, p["states"]) for r, p in zip(train, base_tr["predicted"])]
    fres_va = [force_residual(veh, r, p["states"]) for r, p in zip(val, base_va["predicted"])]

    # 2. signatures ---------------------------------------------------------------------
    ev = signature_evidence(veh, train, fres_tr)
    ev_base = base_coefficient_evidence(veh, train, fres_tr)

    # 3. candidates ---------------------------------------------------------------------
    dt = float(np.median(np.concatenate([np.diff(r.t) for r in train])))
    p_ref = batch_tr.pos0.mean(axis=0)
    depths = [r.position[:, 2] for r in train if r.has_position and np.isfinite(r.position[:, 2]).any()]
    z_max = float(max(np.nanmax(z) for z in depths)) if depths else None
    cands = build_candidates(ev, dt=dt, p_ref=p_ref, retune=_retune_spec(veh, retune), only=only, z_max=z_max)

    rho0 = fitmod.lag1_autocorrelation(batch_va, base_va["predicted"], scales_va)
    n_val = base_va["n"]
    n_eff = fitmod.effective_n(n_val, rho0)
    rms_given = float(np.sqrt(base_va["rss"] / n_val))

    results = []
    baseline = None
    for cand in cands:
        say(f"fitting {cand.name} ({cand.n_params} parameter(s))")
        try:
            fr = fitmod.fit(veh, batch_tr, cand, scales_tr, max_nfev=max_nfev, weights=weights)
        except (UvsimError, np.linalg.LinAlgError) as exc:
            results.append({"cand": cand, "error": str(exc)})
            continue
        problem = None
        if cand.effect is not None:
            try:
                _effect_with(cand, fr.params)
            except VehicleError as exc:
                problem = f"fitted values are not physical: {exc}"
        tr = fitmod.evaluate(veh, batch_tr, cand, fr.x, scales_tr, weights) if cand.n_params else base_tr
        va = fitmod.evaluate(veh, batch_va, cand, fr.x, scales_va, weights) if cand.n_params else base_va
        score = fitmod.bic(va["rss"], va["n"], cand.n_params, n_eff)
        item = {"cand": cand, "fit": fr, "train": tr, "val": va, "bic": score, "problem": problem}
        results.append(item)
        if cand.name == "none":
            baseline = item
    if baseline is None:
        raise CalibrationError("the baseline model could not be evaluated")

    # 4. decision -------------------------------------------------------------------------
    # reference: the baseline (the given model, or with --retune the re-tuned given model)
    rss0 = baseline["val"]["rss"]
    rms_ref = float(np.sqrt(rss0 / baseline["val"]["n"]))
    at_noise = rms_ref <= NOISE_LEVEL
    table = []
    best = None
    for item in results:
        cand = item["cand"]
        if "error" in item:
            table.append({"name": cand.name, "accepted": False, "why": f"fit failed: {item['error']}"})
            continue
        fr, va, tr = item["fit"], item["val"], item["train"]
        dbic = item["bic"] - baseline["bic"]
        improvement = 1.0 - float(np.sqrt(va["rss"] / rss0)) if rss0 > 0 else 0.0
        rms_c = float(np.sqrt(va["rss"] / va["n"]))
        explained = float(np.sqrt(max(rms_ref ** 2 - rms_c ** 2, 0.0)))
        accepted = False
        if cand.name == "none":
            why = "baseline (the model as given" + (", base coefficients re-tuned)" if cand.n_params else ")")
        elif item["problem"]:
            why = item["problem"]
        elif at_noise:
            why = (f"not needed: the baseline's validation residual is at the noise level "
                   f"({rms_ref:.2f} noise sigmas <= {NOISE_LEVEL})")
        elif dbic >= DELTA_BIC:
            why = f"not significant: Delta BIC = {dbic:.1f} (needs < {DELTA_BIC:g})"
        elif improvement < MIN_IMPROVEMENT:
            why = (f"too small: validation RMS reduced by {100 * improvement:.1f} % "
                   f"(needs >= {100 * MIN_IMPROVEMENT:.0f} %) although Delta BIC = {dbic:.1f}")
        elif explained < MIN_EXPLAINED:
            why = (f"too small: explains {explained:.2f} noise sigmas of the residual (needs >= {MIN_EXPLAINED:g}) "
                   f"although Delta BIC = {dbic:.1f} and the RMS drops {100 * improvement:.1f} %")
        else:
            accepted = True
            why = (f"significant: Delta BIC = {dbic:.1f} < {DELTA_BIC:g}, validation RMS reduced by "
                   f"{100 * improvement:.1f} %, explains {explained:.1f} noise sigmas")
        at_bound = [n for n, x, lo, hi in zip(cand.fit_names, fr.x, cand.lower, cand.upper)
                    if min(x - lo, hi - x) <= 1e-3 * (hi - lo)]
        if at_bound:
            why += f"; at a bound: {', '.join(at_bound)}"
        row = {
            "name": cand.name,
            "parameters": {k: {"value": v, "std": fr.std.get(k), "unit": _unit(cand.effect, k)}
                           for k, v in fr.params.items()},
            "fit_variables": dict(zip(cand.fit_names, map(float, fr.x))),
            "n_parameters": cand.n_params,
            "train_rmse": _group_rmse(tr["rmse"]),
            "validation_rmse": _group_rmse(va["rmse"]),
            "train_rms_noise_sigmas": float(np.sqrt(tr["rss"] / tr["n"])),
            "validation_rms_noise_sigmas": float(np.sqrt(va["rss"] / va["n"])),
            "score": {"criterion": "BIC", "bic": item["bic"], "delta_bic": float(dbic),
                      "validation_improvement": improvement, "explained_noise_sigmas": explained},
            "accepted": accepted,
            "at_bound": at_bound,
            "why": why,
            "notes": cand.notes,
            "function_evaluations": fr.nfev,
        }
        table.append(row)
        item["row"] = row
        if accepted and (best is None or item["bic"] < best["bic"]):
            best = item

    # 5. result -------------------------------------------------------------------------------
    veh_after, term = veh, None
    if best is not None:
        cand, fr = best["cand"], best["fit"]
        term = _effect_with(cand, fr.params)
        veh_after = veh.with_effects([term])
        base_vals = {k: fr.params[k] for k in fr.params if k in veh.parameters() and k not in term.parameters()}
        if base_vals:
            veh_after = veh_after.with_parameters(base_vals)
        after_tr, after_va = best["train"], best["val"]
        rms_after = float(np.sqrt(after_va["rss"] / after_va["n"]))
        confidence = "high" if (rms_after <= CONFIDENT or rms_after <= EXPLAINED * rms_given) else "partial"
        message = (f"{cand.name}: validation residual {rms_given:.2f} -> {rms_after:.2f} noise sigmas. "
                   + (("The residual after the fit is at the noise level." if rms_after <= CONFIDENT else
                       f"The fit explains {100 * (1 - (rms_after / rms_given) ** 2):.2f} % of the squared residual.")
                      if confidence == "high" else
                      f"The residual after the fit is still {rms_after:.1f} noise sigmas: {cand.name} explains part "
                      "of it; another effect (outside the catalogue, or a second one) remains."))
    else:
        after_tr, after_va = baseline["train"], baseline["val"]
        if baseline["cand"].n_params:  # --retune: keep the re-tuned base coefficients
            veh_after = veh.with_parameters(baseline["fit"].params)
        confidence = "none"
        if at_noise:
            message = (f"none: the validation residual ({rms_ref:.2f} noise sigmas"
                       + (", base coefficients re-tuned" if baseline["cand"].n_params else "")
                       + ") is at the noise level; no effect is needed.")
        else:
            scored = [r for r in table if "score" in r and r["name"] != "none"]
            top = max(scored, key=lambda r: r["score"]["explained_noise_sigmas"], default=None)
            best_txt = (f"; the best candidate, {top['name']}, explains {top['score']['explained_noise_sigmas']:.2f}"
                        if top else "")
            message = (f"none: no catalogue effect explains a significant part of the validation residual "
                       f"({rms_ref:.2f} noise sigmas{best_txt}). Well above 2 sigmas this points to an effect "
                       "outside the catalogue (or one needing parameters the candidates hold fixed); near 2 it is "
                       "the noise plus the error of the runs' initial states.")
            own = ev_base if ev_base is not None and ev_base["present"] else None
            if own is not None and not baseline["cand"].n_params:
                message += (f" The force residual follows each DOF's own velocity and acceleration (R2 = "
                            f"{own['strength']:.2f}): the base coefficients (damping, added mass, inertia) look off; "
                            "calibrate them (uvsim calibrate) or re-tune them here (--retune).")

    # force residuals after (validation runs), for plots and the evidence after
    fres_va_after = [force_residual(veh_after, r, p["states"]) for r, p in zip(val, after_va["predicted"])]

    per_run = {}
    for split, runs, before, after in (("train", train, base_tr, after_tr), ("validation", val, base_va, after_va)):
        for r in runs:
            per_run[r.name] = {"split": split, "dof": r.dof, "before": _run_summary(before["per_run"][r.name]),
                               "after": _run_summary(after["per_run"][r.name])}

    chosen = best if best is not None else baseline
    report = {
        "effect": best["cand"].name if best is not None else "none",
        "parameters": {k: {"value": v, "std": chosen["fit"].std.get(k), "unit": _unit(chosen["cand"].effect, k)}
                       for k, v in chosen["fit"].params.items()},
        "confidence": confidence,
        "message": message,
        "rmse_before": _group_rmse(base_va["rmse"]),
        "rmse_after": _group_rmse(after_va["rmse"]),
        "candidates": table,
        "per_run": per_run,
        "evidence": ev,
        "base_coefficients_evidence": ev_base,
        "criterion": {
            "name": "BIC on validation residuals",
            "formula": "BIC = n_eff ln(RSS/n) + p ln(n_eff), n_eff = n (1 - rho) / (1 + rho)",
            "n": int(n_val), "rho": rho0, "n_eff": n_eff,
            "accept": (f"baseline above {NOISE_LEVEL} noise sigmas, Delta BIC < {DELTA_BIC:g}, validation RMS "
                       f"reduced by >= {100 * MIN_IMPROVEMENT:.0f} %, explained part >= {MIN_EXPLAINED:g} noise sigmas, "
                       "physical parameter values"),
            "confidence_high": (f"validation RMS after <= {CONFIDENT} noise sigmas or <= {EXPLAINED} x the "
                                "given model's"),
            "residual_normalization": "each signal group divided by its noise level (per run)",
            "weights": dict(weights or {}),
        },
        "noise": {"pooled": noise_used, "per_run": {r.name: sc for r, sc in zip(train + val, scales_tr + scales_va)},
                  "estimated_from": "second differences of the raw signals (uvsim.diagnosis.residuals.noise_levels)"
                                    + ("; user-given: " + ", ".join(user_noise) if user_noise else "")},
        "baseline_validation_rms_noise_sigmas": rms_given,
        "reference_validation_rms_noise_sigmas": rms_ref,
        "vehicle": veh.name,
        "data": str(dataset.path),
        "runs": {"train": [r.name for r in train], "validation": [r.name for r in val], "split": split_note},
    }
    return Diagnosis(report, veh, veh_after, term, train, val,
                     output_residuals(val, base_va["predicted"]), output_residuals(val, after_va["predicted"]),
                     fres_va, fres_va_after)


def _has(measured: dict, group: str) -> bool:
    key = {"position": "position", "attitude": "quaternion", "velocity": "velocity", "rates": "rates"}[group]
    return key in measured


def save_fixed_vehicle(diag: Diagnosis, path) -> Path:
    """Write the corrected vehicle with provenance comments."""
    from uvsim.vehicle import save_vehicle

    rep = diag.report
    ann = {}
    term = diag.effect_term
    for k, d in rep["parameters"].items():
        std = d.get("std")
        key = k
        if term is not None and k in term.parameters():
            key = next((f.key for f in term.FIELDS if term.param_name(f.key) == k), k)
        ann[key] = (f"diagnosed: {d['value']:.6g} +- {std:.2g} {d['unit']}".rstrip() if std is not None
                    else "diagnosed")
    header = (f"{diag.vehicle_after.name}: corrected by `uvsim diagnose` on {rep['data']}\n"
              f"effect: {rep['effect']} ({rep['confidence']}); {rep['message']}\n"
              f"validation RMSE before {rep['rmse_before']} after {rep['rmse_after']}")
    return save_vehicle(diag.vehicle_after, path, header=header, annotations=ann)
