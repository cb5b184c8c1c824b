"""``uvsim bench diagnose``: the diagnosis on randomized scenarios it has never seen.

Each scenario is drawn by :func:`uvsim.scenarios.sample_scenario` (profile ``diagnose``:
the BlueROV2 Heavy with every base coefficient perturbed within +-10 % of seed 000
Table 5, force / thrust / PWM inputs at 10-100 Hz, 1-5 mm and 0.002-0.01 rad of
motion-capture noise, steps, reversals, sinusoids, free decays, telegraph inputs and
spirals, neutral or trimmed buoyancy, and 0, 1 or 2 effects of random type, variant and
magnitude), written by the independent truth model of :mod:`uvsim.scenarios` and
diagnosed with :func:`uvsim.diagnosis.diagnose` from the nominal model handed to the
user, re-tuning the base coefficients (:data:`BASE_RETUNE`).

Per scenario it records the true and the named effects, whether the name is right, the
open-loop validation RMSE before and after, and the seconds; results go to a JSON-lines
file as they come, so an interrupted benchmark resumes where it stopped.  The summary
gives the confusion matrix (true effect set vs named set), the detection rate per
effect, the false-positive rate on clean data, the share of correct detections whose
validation RMSE at least halved, and seconds per dataset.
"""
from __future__ import annotations

import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from uvsim.benchmarks.records import append_record, load_records
from uvsim.errors import UvsimError
from uvsim.progress import as_progress

#: The base coefficients the benchmark re-tunes in every model (added mass and damping of
#: all six DOFs; the rigid-body inertia enters only with the added inertia, and mass and
#: buoyancy are measured quantities in seed 000 Table 2).
BASE_RETUNE = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot", "X_u", "Y_v", "Z_w", "K_p", "M_q", "N_r",
               "X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")
#: Scenario effect types -> catalogue names (a weak thruster is a thruster gain below 1).
TRUTH_TO_CATALOGUE = {"weak_thruster": "thruster_gain"}
#: Probability of a clean scenario among the single-effect-or-clean ones.
P_CLEAN = 0.25


def _label(names) -> str:
    return "+".join(sorted(names)) if names else "none"


def _main_group(rmse: dict) -> str | None:
    for k in ("position_m", "depth_m", "attitude_rad", "rates_radps"):
        if k in rmse:
            return k
    return None


def run_scenario(seed: int, n_effects: int, *, workers: int = 1, retune=BASE_RETUNE, profile: str = "diagnose",
                 tmp: Path | None = None) -> dict:
    """Generate and diagnose one scenario; returns its record (module docstring)."""
    from uvsim.diagnosis import diagnose
    from uvsim.scenarios import generate, load_truth, sample_scenario

    with tempfile.TemporaryDirectory(dir=tmp) as d:
        spec = sample_scenario(seed, profile=profile, n_effects=n_effects)
        out = generate(spec, Path(d) / "ds")
        truth = load_truth(out)
        t0 = time.perf_counter()
        diag = diagnose(out, retune=list(retune), workers=workers)
        seconds = time.perf_counter() - t0
    true = sorted({TRUTH_TO_CATALOGUE.get(e["type"], e["type"]) for e in truth["effects"]})
    rep = diag.report
    named = sorted({e["effect"] for e in rep["effects"]})
    g = _main_group(rep["rmse_before"])
    before, after = (rep["rmse_before"].get(g), rep["rmse_after"].get(g)) if g else (None, None)
    return {"seed": seed, "n_effects": n_effects, "input_kind": truth.get("input_kind"),
            "rate_hz": truth.get("rate_hz"),
            "truth": [{"type": e["type"], "variant": e.get("variant"), "snr": e.get("effect_snr"),
                       "detectable": e.get("detectable")} for e in truth["effects"]],
            "true": true, "named": named, "named_variants": [f"{e['effect']}:{e['variant']}" for e in rep["effects"]],
            "correct": true == named, "rmse_group": g, "rmse_before": before, "rmse_after": after,
            "halved": (after is not None and before is not None and after <= 0.5 * before) if true else None,
            "validation_cost_per_entry": rep["validation_cost_per_entry"],
            "confidence": rep["confidence"], "seconds": seconds, "fits": rep["fits"],
            "verdict": (rep.get("verdict") or {}).get("status"), "base_model": (rep.get("base_model") or {}).get("variant"),
            "worst_group_change": worst_group_change(rep),
            "steps": [_step_digest(st) for st in rep["steps"]]}


def worst_group_change(rep: dict) -> float | None:
    """Largest relative change of a logged channel's open-loop validation MSE caused by a
    chosen candidate (the verdict's numbers, uvsim.fitting.verdict; > 0: worse); None when
    nothing was chosen."""
    worst = None
    for st in rep["steps"]:
        for c in st["candidates"]:
            g = (c.get("compare") or {}).get("guard")
            if c.get("chosen") and g:
                for d in g["channels"].values():
                    worst = d["mse_ratio"] - 1.0 if worst is None else max(worst, d["mse_ratio"] - 1.0)
    return worst


def _step_digest(st: dict) -> dict:
    """What a step fitted and why each was (not) accepted: enough to read a failure."""
    return {"chosen": st.get("chosen"),
            "fitted": [{"candidate": f"{c['effect']}:{c['variant']}", "accepted": c["accepted"],
                        "validation_cost": c.get("validation_cost_per_entry"), "why": c["why"]}
                       for c in st["candidates"]],
            "screened": {f"{c['effect']}:{c['variant']}": c["screening_reduction"] for c in st["screened"]}}


def summarize(records: list[dict]) -> dict:
    """Confusion matrix, detection rates, false-positive rate, RMSE halving, timing."""
    conf = Counter((_label(r["true"]), _label(r["named"])) for r in records)
    single = [r for r in records if r["n_effects"] <= 1]
    two = [r for r in records if r["n_effects"] == 2]
    clean = [r for r in records if not r["true"]]
    det: dict = {}
    for r in records:
        for e in r["true"]:
            d = det.setdefault(e, [0, 0])
            d[1] += 1
            d[0] += int(e in r["named"])
    correct_det = [r for r in records if r["true"] and r["correct"]]
    secs = np.array([r["seconds"] for r in records]) if records else np.zeros(0)
    return {
        "scenarios": len(records),
        "single_or_clean": {"n": len(single), "correct": sum(r["correct"] for r in single),
                            "correct_rate": (sum(r["correct"] for r in single) / len(single)) if single else None},
        "two_effects": {"n": len(two), "both_named": sum(r["correct"] for r in two),
                        "both_named_rate": (sum(r["correct"] for r in two) / len(two)) if two else None},
        "false_positive_rate_clean": (sum(bool(r["named"]) for r in clean) / len(clean)) if clean else None,
        "clean_scenarios": len(clean),
        "detection_rate": {e: {"found": a, "of": b, "rate": a / b} for e, (a, b) in sorted(det.items())},
        "halved_share_of_correct_detections": (sum(bool(r["halved"]) for r in correct_det) / len(correct_det))
        if correct_det else None,
        "correct_detections": len(correct_det),
        "seconds_per_dataset": {"mean": float(secs.mean()) if secs.size else None,
                                "median": float(np.median(secs)) if secs.size else None,
                                "max": float(secs.max()) if secs.size else None},
        "confusion": [{"true": t, "named": n, "count": c} for (t, n), c in sorted(conf.items())],
        "worst_group_change": max((r["worst_group_change"] for r in records
                                   if r.get("worst_group_change") is not None), default=None),
        "accepted_worsening_a_group_over_10pct": sum((r.get("worst_group_change") or 0.0) > 0.10 for r in records),
    }


def plan(n: int, seed: int, two_effects: int = 0) -> list[tuple[int, int]]:
    """(seed, n_effects) of the benchmark: ``n`` single-effect or clean scenarios (clean
    with probability :data:`P_CLEAN`, drawn from ``seed``) and ``two_effects`` two-effect ones."""
    rng = np.random.default_rng(seed)
    out = [(seed + i, 0 if rng.random() < P_CLEAN else 1) for i in range(n)]
    out += [(seed + n + i, 2) for i in range(two_effects)]
    return out


def run_benchmark(n: int, seed: int, *, two_effects: int = 0, workers: int = 1, results: str | Path | None = None,
                  progress=None, stages=None) -> dict:
    """Run (or resume) the benchmark; ``results`` is the JSON-lines file of finished
    scenarios (kept between runs).  Returns the summary plus the records.  ``progress``:
    callable(line) of each finished scenario; ``stages``: each scenario as a stage
    (:func:`uvsim.progress.as_progress`)."""
    if n < 0 or two_effects < 0 or (n + two_effects) == 0:
        raise UvsimError(f"--scenarios {n} / --two-effects {two_effects}: need at least one scenario")
    say = progress or (lambda m: None)
    path = Path(results) if results else None
    done = load_records(path, lambda rec: (rec["seed"], rec["n_effects"]), say, "scenario")
    records = []
    todo = plan(n, seed, two_effects)
    for i, (s, k) in enumerate(todo, 1):
        if (s, k) in done:
            records.append(done[(s, k)])
            continue
        with as_progress(stages).stage(f"[{i}/{len(todo)}] seed {s}, {k} effect(s)"):
            rec = run_scenario(s, k, workers=workers)
        records.append(rec)
        append_record(path, rec)
        say(f"[{i}/{len(todo)}] seed {s}: true {_label(rec['true'])}, named {_label(rec['named'])} "
            f"({'ok' if rec['correct'] else 'WRONG'}), {rec['seconds']:.1f} s")
    return {"summary": summarize(records), "records": records}
