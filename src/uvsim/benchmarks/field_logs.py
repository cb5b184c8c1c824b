"""``uvsim bench diagnose-field``: the diagnosis on field-like logs the project owns (issue 48, item 5).

Each case is drawn by :func:`uvsim.scenarios.field.sample_field` (a BlueROV2 Heavy under an
ArduSub-like autopilot: STABILIZE / DEPTH HOLD with heading hold on a compass-less attitude filter,
the Heavy's mixer, PWM at 10 or 5 Hz, a DVL at 5 Hz with drop-outs, a pressure sensor off the
origin, a topside clock with +-15 ms of jitter, truth hydrodynamics that differ from the given
model in values and structure) and written by the generator, which imports nothing from the
fitting code.  It is then diagnosed the way a user would: ``uvsim diagnose --data DIR --json
REPORT`` in a process of its own, with nothing but the dataset (no ``--retune``).

Case ``i`` of a benchmark from ``--seed S`` is :data:`~uvsim.scenarios.field.CASES` ``[i mod 10]``
with seed ``S + i``: ``clean``, ``dead``, ``reversed``, ``weak``, ``fouled`` (thruster faults),
``current`` (turning), ``weight`` (a lead weight under depth hold), ``tether`` (from a spool), and
the two outside the catalogue, ``tilted_thruster`` and ``depth_drag``.

Per case: the expected answer (truth.yaml), the named effects and variants, **right set named**
(the named effects are exactly the expected one; for a clean log nothing; outside the catalogue:
the verdict says the residual is not explained), **right variant** (a thruster fault: the unit, and
dead named dead, reversed named reversed), **validation fixed** (the diagnosis' ``model_verdict``
is *better*), **false effects** on clean logs, the exit code and the seconds.  Records go to a
JSON-lines file as they finish, so an interrupted benchmark resumes.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from uvsim.benchmarks.records import append_record, load_records
from uvsim.errors import UvsimError
from uvsim.progress import as_progress

#: Seconds after which one diagnosis is stopped and recorded as not diagnosed.
TIMEOUT = 3600.0


def judge(expected, rep: dict | None) -> dict:
    """The benchmark's record of one report against the truth's ``expected`` answer."""
    if rep is None:
        return {"named": [], "named_variants": [], "answers": [], "right_set": False, "right_variant": None,
                "validation_fixed": None, "false_effects": None, "verdict": None, "unexplained": None}
    effects = rep.get("effects") or []
    named = sorted({e["effect"] for e in effects})
    variants = [f"{e['effect']}:{e['variant']}" for e in effects]
    answers = [e.get("answer") for e in effects]
    v = rep.get("verdict") or {}
    mv = rep.get("model_verdict")
    fixed = None if mv is None else mv.get("status") == "better"
    right_variant = None
    if expected == "none":
        right = not named
    elif expected == "outside_catalogue":
        right = bool(v.get("unexplained"))
    else:
        right = named == [expected["effect"]]
        if expected["effect"] == "thruster_gain":
            hit = [e for e in effects if e["effect"] == "thruster_gain" and e["variant"] == expected["variant"]]
            right_variant = bool(hit) and (expected.get("answer") != "dead"
                                           or "no thrust" in str(hit[0].get("answer") or ""))
    return {"named": named, "named_variants": variants, "answers": answers, "right_set": bool(right),
            "right_variant": right_variant, "validation_fixed": fixed if expected != "none" else None,
            "false_effects": len(named) if expected == "none" else None, "verdict": v.get("status"),
            "unexplained": v.get("unexplained"), "model_verdict": None if mv is None else mv.get("status"),
            "base_model": (rep.get("base_model") or {}).get("variant")}


def _env() -> dict:
    """The environment of the diagnosis' process: this uvsim first on the path."""
    import uvsim

    src = str(Path(uvsim.__file__).resolve().parents[1])
    env = dict(os.environ)
    env["PYTHONPATH"] = src + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def run_one(seed: int, case: str, *, workers: int = 1, tmp: Path | None = None, timeout: float = TIMEOUT,
            duration=None) -> dict:
    """Generate one field case and diagnose it with the command line; returns its record."""
    from uvsim.scenarios.field import generate_field, sample_field

    spec = sample_field(seed, case, duration=duration)
    with tempfile.TemporaryDirectory(dir=tmp) as d:
        out = generate_field(spec, Path(d) / "ds")
        report = Path(d) / "report.json"
        cmd = [sys.executable, "-m", "uvsim.cli", "diagnose", "--data", str(out), "--json", str(report), "--quiet",
               "--workers", str(workers)]
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, env=_env(), timeout=timeout)
            code, tail = proc.returncode, (proc.stderr or "").strip().splitlines()[-3:]
        except subprocess.TimeoutExpired:
            code, tail = None, [f"stopped after {timeout:g} s"]
        seconds = time.perf_counter() - t0
        rep = json.loads(report.read_text()) if report.is_file() else None
    rec = {"seed": seed, "case": case, "expected": spec["expected"], "fault": spec["fault"],
           "log_hz": spec["log_hz"], "exit_code": code, "diagnosed": rep is not None,
           "error": None if rep is not None else " | ".join(tail), "seconds": seconds, **judge(spec["expected"], rep)}
    if rep is not None:
        rec["rmse_before"], rec["rmse_after"] = rep.get("rmse_before"), rep.get("rmse_after")
    return rec


def summarize(records: list[dict]) -> dict:
    """The metrics of docs/diagnose.md, "Field logs"."""
    single = [r for r in records if isinstance(r["expected"], dict)]
    clean = [r for r in records if r["expected"] == "none"]
    outside = [r for r in records if r["expected"] == "outside_catalogue"]
    dead = [r for r in single if r["expected"].get("answer") == "dead"]
    rev = [r for r in single if str(r["expected"].get("variant", "")).startswith("reversed")]
    secs = np.array([r["seconds"] for r in records]) if records else np.zeros(1)
    per_case = {}
    for r in records:
        d = per_case.setdefault(r["case"], {"n": 0, "right": 0, "fixed": 0})
        d["n"] += 1
        d["right"] += bool(r["right_set"])
        d["fixed"] += bool(r.get("validation_fixed"))
    return {
        "cases": len(records),
        "diagnosed": sum(r["diagnosed"] for r in records),
        "single_effects": len(single),
        "single_named_and_fixed": sum(bool(r["right_set"] and r["validation_fixed"]) for r in single),
        "single_named": sum(bool(r["right_set"]) for r in single),
        "clean": len(clean), "clean_with_false_effects": sum(bool(r["false_effects"]) for r in clean),
        "false_effects_on_clean": sum(r["false_effects"] or 0 for r in clean),
        "outside": len(outside), "outside_not_explained": sum(bool(r["right_set"]) for r in outside),
        "dead": len(dead), "dead_named_dead": sum(bool(r["right_variant"]) for r in dead),
        "reversed": len(rev), "reversed_named_reversed": sum(bool(r["right_variant"]) for r in rev),
        "per_case": per_case,
        "seconds_mean": float(secs.mean()), "seconds_max": float(secs.max()),
    }


def run_benchmark(n: int, seed: int, *, cases=None, workers: int = 1, results: str | Path | None = None,
                  progress=None, duration=None, stages=None) -> dict:
    """``n`` cases from ``seed`` (module docstring), resumed from ``results`` (JSON lines); ``progress``:
    callable(line) of each finished case; ``stages``: each as a stage (:func:`uvsim.progress.as_progress`)."""
    from uvsim.scenarios.field import CASES

    if n < 1:
        raise UvsimError(f"--scenarios {n}: need at least one case")
    pool = list(cases or CASES)
    bad = [c for c in pool if c not in CASES]
    if bad:
        raise UvsimError(f"--only {bad}: unknown case(s); expected some of {list(CASES)}")
    say = progress or (lambda m: None)
    path = Path(results) if results else None
    done = load_records(path, lambda rec: (rec["seed"], rec["case"]), say, "case")
    todo = [(seed + i, pool[i % len(pool)]) for i in range(n)]
    records = []
    for i, (s, c) in enumerate(todo, 1):
        rec = done.get((s, c))
        if rec is None:
            with as_progress(stages).stage(f"[{i}/{len(todo)}] {c} seed {s}"):
                rec = run_one(s, c, workers=workers, duration=duration)
            append_record(path, rec)
        records.append(rec)
        say(f"[{i}/{len(todo)}] {c} seed {s}: expected {_label(rec['expected'])}, named "
            f"{', '.join(rec['named_variants']) or 'none'} ({'right' if rec['right_set'] else 'WRONG'}"
            + ("" if rec["validation_fixed"] is None else
               f", validation {'fixed' if rec['validation_fixed'] else 'not fixed'}")
            + f"), exit {rec['exit_code']}, {rec['seconds']:.0f} s")
    return {"summary": summarize(records), "records": records}


def _label(expected) -> str:
    if isinstance(expected, dict):
        return f"{expected['effect']}:{expected['variant']}" if "variant" in expected else expected["effect"]
    return str(expected)
