"""``uvsim bench diagnose-structural``: diagnosis when the data differ from the model in structure.

The randomized benchmark of :mod:`uvsim.benchmarks.scenarios` hands the diagnosis a model
whose only error is in values, and re-tunes them.  Real data differ in structure (issue
22), so this benchmark draws scenarios from the independent truth generator
(:mod:`uvsim.scenarios`) in four classes, each diagnosed the way a user would run it:

``base_error``        clean data, every base coefficient of the truth 10 % off (uniform,
                      profile ``diagnose``), diagnosed *without* ``--retune``: the right
                      answer is no effect (the base model being off is its own answer).
``curve_mismatch``    PWM runs through the T200 curve measured at another supply voltage
                      (12, 14, 18 or 20 V; the model's file says 16 V), base coefficients
                      exact, no effect or one: the right answer is the true set, no thruster
                      fault invented from the curve.
``out_of_catalogue``  a periodic force or a payload pod (weight and float at different
                      points), base exact: the right answer is the verdict "not explained"
                      (or "partly explained") with no effect named on a search bound.
``imu_depth``         IMU + 10 Hz depth, no position (profile ``realsensor``), no effect or
                      one, base coefficients and z_b re-tuned as in the real-sensor test.

Per scenario: the truth, the named set, the verdict, the largest open-loop worsening of
any logged channel that an accepted candidate caused (the verdict's numbers), and seconds.
Records go to a JSON-lines file as they finish, so an interrupted run resumes.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from uvsim.benchmarks.scenarios import BASE_RETUNE, TRUTH_TO_CATALOGUE, worst_group_change
from uvsim.benchmarks.records import append_record, load_records
from uvsim.errors import UvsimError
from uvsim.progress import as_progress

CLASSES = ("base_error", "curve_mismatch", "out_of_catalogue", "imu_depth")
#: Seed offset of each class (so the classes draw different scenarios from one --seed).
OFFSET = {"base_error": 0, "curve_mismatch": 10000, "out_of_catalogue": 20000, "imu_depth": 30000}
#: Small scenarios (10 training runs of 8-12 s at 20-50 Hz) keep a class at ~20 s per dataset.
SMALL = dict(n_runs=10, duration=[8, 12])


def _overrides(cls: str, seed: int) -> tuple[str, dict, list]:
    """(profile, sample_scenario overrides, retune) of one scenario of class ``cls``."""
    rng = np.random.default_rng([seed, CLASSES.index(cls)])
    if cls == "base_error":
        return "diagnose", {**SMALL, "n_effects": 0, "perturbation": 0.1,
                            "rate_hz": float(rng.choice([20.0, 50.0]))}, []
    if cls == "curve_mismatch":
        return "diagnose", {**SMALL, "n_effects": int(rng.random() < 0.5), "perturbation": 0.0,
                            "curve_voltage": int(rng.choice([12, 14, 18, 20])),
                            "rate_hz": float(rng.choice([20.0, 50.0]))}, []
    if cls == "out_of_catalogue":
        kind = str(rng.choice(["periodic_force", "payload_pod"]))
        return "diagnose", {**SMALL, "effects": [kind], "perturbation": 0.0,
                            "rate_hz": float(rng.choice([20.0, 50.0]))}, []
    if cls == "imu_depth":
        return "realsensor", {"n_runs": 8, "duration": [10, 14], "n_effects": int(rng.random() < 0.5)}, \
            [*BASE_RETUNE, "z_b"]
    raise UvsimError(f"structural benchmark: class {cls!r}; expected one of {list(CLASSES)}")


def run_one(cls: str, seed: int, *, supply: bool = False, workers: int = 1, tmp: Path | None = None) -> dict:
    """Generate and diagnose one scenario of class ``cls``; returns its record.  ``supply``: the
    model's thrusters on the T200 voltage family (its file's 16 V), so that the base model's
    ``supply_voltage`` is a candidate (:func:`uvsim.benchmarks.calibration_structural.on_voltage_family`)."""
    from uvsim.benchmarks.calibration_structural import dataset_vehicle_on_family
    from uvsim.diagnosis import diagnose
    from uvsim.scenarios import generate, load_truth, sample_scenario

    profile, over, retune = _overrides(cls, seed)
    with tempfile.TemporaryDirectory(dir=tmp) as d:
        spec = sample_scenario(seed, profile=profile, **over)
        out = generate(spec, Path(d) / "ds")
        truth = load_truth(out)
        t0 = time.perf_counter()
        model = dataset_vehicle_on_family(out) if supply else None
        rep = diagnose(out, model, retune=retune, workers=workers).report
        seconds = time.perf_counter() - t0
    true = sorted({TRUTH_TO_CATALOGUE.get(e["type"], e["type"]) for e in truth["effects"]
                   if e.get("catalogued", True)})
    ooc = [e["type"] for e in truth["effects"] if not e.get("catalogued", True)]
    named = sorted({e["effect"] for e in rep["effects"]})
    v = rep.get("verdict") or {}
    if cls == "out_of_catalogue":
        ok = bool(v.get("unexplained"))
    else:
        ok = named == true
    return {"class": cls, "seed": seed, "supply": supply, "input_kind": truth.get("input_kind"),
            "rate_hz": truth.get("rate_hz"),
            "curve": spec.vehicle.get("truth_curve"), "truth": [e["type"] for e in truth["effects"]],
            "true": true, "out_of_catalogue": ooc, "named": named,
            "named_variants": [f"{e['effect']}:{e['variant']}" for e in rep["effects"]],
            "base_model": (rep.get("base_model") or {}).get("variant"), "verdict": v.get("status"),
            "unexplained": v.get("unexplained"), "correct": ok, "worst_group_change": worst_group_change(rep),
            "rmse_before": rep["rmse_before"], "rmse_after": rep["rmse_after"], "seconds": seconds,
            "fits": rep["fits"]}


def summarize(records: list[dict]) -> dict:
    out: dict = {"scenarios": len(records), "classes": {}}
    for cls in CLASSES:
        rs = [r for r in records if r["class"] == cls]
        if not rs:
            continue
        clean = [r for r in rs if not r["true"] and cls != "out_of_catalogue"]
        secs = np.array([r["seconds"] for r in rs])
        out["classes"][cls] = {
            "n": len(rs), "correct": sum(r["correct"] for r in rs), "rate": sum(r["correct"] for r in rs) / len(rs),
            "clean": len(clean), "false_positives_clean": sum(bool(r["named"]) for r in clean),
            "named_anything": sum(bool(r["named"]) for r in rs),
            "base_model_answers": sum(bool(r["base_model"]) for r in rs),
            "seconds_mean": float(secs.mean()), "seconds_max": float(secs.max())}
    worst = [r["worst_group_change"] for r in records if r["worst_group_change"] is not None]
    out["worst_group_change_of_an_accepted_candidate"] = max(worst) if worst else None
    out["accepted_candidates_worsening_a_group_over_10pct"] = sum(w > 0.10 for w in worst)
    return out


def run_benchmark(n: int, seed: int, *, classes=CLASSES, supply: bool = False, workers: int = 1,
                  results: str | Path | None = None, progress=None, stages=None) -> dict:
    """``n`` scenarios per class from ``seed`` (resumed from ``results``, JSON lines); ``progress``:
    callable(line) of each finished one; ``stages``: each as a stage (:func:`uvsim.progress.as_progress`)."""
    if n < 1:
        raise UvsimError(f"--scenarios {n}: need at least one scenario per class")
    bad = [c for c in classes if c not in CLASSES]
    if bad:
        raise UvsimError(f"--only {bad}: unknown class(es); expected {list(CLASSES)}")
    say = progress or (lambda m: None)
    path = Path(results) if results else None
    done = load_records(path, lambda rec: (rec["class"], rec["seed"], rec.get("supply", False)), say, "scenario")
    todo = [(c, seed + OFFSET[c] + i) for c in classes for i in range(n)]
    records = []
    for i, (c, s) in enumerate(todo, 1):
        if (c, s, supply) in done:
            records.append(done[(c, s, supply)])
            continue
        with as_progress(stages).stage(f"[{i}/{len(todo)}] {c} seed {s}"):
            rec = run_one(c, s, supply=supply, workers=workers)
        records.append(rec)
        append_record(path, rec)
        say(f"[{i}/{len(todo)}] {c} seed {s}: truth {rec['truth'] or 'none'}, named {rec['named'] or 'none'}, "
            f"verdict {rec['verdict']} ({'ok' if rec['correct'] else 'WRONG'}), {rec['seconds']:.1f} s")
    return {"summary": summarize(records), "records": records}
