"""The structural-mismatch calibration benchmark (uvsim.benchmarks.calibration_structural):
its generator is written apart from the fitting code, its own verdict can say "worse", and
its scenarios differ from the model in structure."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import uvsim.scenarios
from uvsim.benchmarks.calibration_structural import judge, run_one, scenario

#: What the truth generator may import from uvsim: errors, file helpers and the log writer.
ALLOWED = {"uvsim.errors", "uvsim.files", "uvsim.logs"}


def test_the_generator_imports_nothing_from_the_fitting_code():
    pkg = Path(uvsim.scenarios.__file__).parent
    used = set()
    for f in pkg.glob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("uvsim"):
                used.add(node.module)
            elif isinstance(node, ast.Import):
                used.update(a.name for a in node.names if a.name.startswith("uvsim"))
    outside = {m for m in used if not m.startswith("uvsim.scenarios")}
    assert outside <= ALLOWED, outside - ALLOWED
    # and at run time: generating a dataset loads no fitting, calibration or measurement module
    code = ("import sys, tempfile, pathlib; from uvsim.scenarios import generate, sample_scenario; "
            "d = tempfile.mkdtemp(); generate(sample_scenario(3, profile='realsensor', n_runs=1, n_validation=1, "
            "duration=3, rate_hz=100.0), pathlib.Path(d) / 'ds'); "
            "print(sorted(m for m in sys.modules if m.startswith(('uvsim.fitting', 'uvsim.calibration', "
            "'uvsim.measurements', 'uvsim.diagnosis', 'uvsim.thrusters'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out


def test_scenarios_are_20_to_40_percent_off_and_half_on_another_curve():
    draws = [scenario(s) for s in range(200)]
    assert all(0.2 <= d["perturbation"] <= 0.4 for d in draws)
    share = sum("curve_voltage" in d for d in draws) / len(draws)
    assert 0.35 < share < 0.65
    assert {d.get("curve_voltage") for d in draws} - {None} == {12, 14, 18, 20}


def _report(before, after, *, ok=True, message="converged", run_before=None, run_after=None):
    per = {"val_1": {"split": "validation", "fit_percent": run_after or after,
                     "initial_fit_percent": run_before or before},
           "run_1": {"split": "train", "fit_percent": {"p": 0.0}, "initial_fit_percent": {"p": 99.0}}}
    return {"per_run": per, "never_worse": {"ok": ok, "fit_percent": after, "initial_fit_percent": before},
            "refinement": {"stages": [{"message": message}]}, "at_bounds": []}


def test_judge_says_worse_from_the_validation_fit_alone():
    j = judge(_report({"p": 60.0, "q": 50.0}, {"p": 70.0, "q": 48.5}))
    assert j["worse"] == ["q"] and j["gain"]["p"] == pytest.approx(10.0) and j["check_ok"]
    assert judge(_report({"p": 60.0}, {"p": 59.5}))["worse"] == []          # within 1 point
    assert not judge(_report({"p": 60.0}, {"p": 70.0}, ok=False))["check_ok"]
    assert not judge(_report({"p": 60.0}, {"p": 70.0}, message="maximum number of iterations reached"))["check_ok"]


def test_judge_uses_the_pooled_comparison_and_keeps_the_run_mean_beside_it():
    # a run whose r hardly moves swings its own Fit % by thousands of points (benchmark seed 35);
    # the judge reads the pooled figures of the check's comparison, the earlier judge is recorded
    j = judge(_report({"r": 70.0}, {"r": 99.8}, run_before={"r": -910.0}, run_after={"r": -25516.0}))
    assert j["worse"] == [] and j["gain"]["r"] == pytest.approx(29.8) and j["worse_run_mean"] == ["r"]


@pytest.mark.slow
def test_one_seed_end_to_end():
    rec = run_one(0)
    assert rec["error"] is None and rec["gain"] and rec["curve"] == "t200_14v_measured"
    # whatever the fit did, a fit worse than its start is not reported ok
    assert not rec["worse"] or not rec["check_ok"]


def test_benchmark_records_resume_and_bad_lines_are_named(tmp_path):
    from uvsim.benchmarks.records import append_record, load_records
    from uvsim.errors import UvsimError

    p = tmp_path / "r.jsonl"
    assert load_records(p, lambda r: r["seed"]) == {}
    append_record(p, {"seed": 1, "x": 2.0})
    append_record(p, {"seed": 2, "x": 3.0})
    said = []
    assert load_records(p, lambda r: r["seed"], said.append) == {1: {"seed": 1, "x": 2.0}, 2: {"seed": 2, "x": 3.0}}
    assert said == [f"resuming from {p}: 2 case(s) already done"]
    with p.open("a") as fh:
        fh.write("{not json\n")
    with pytest.raises(UvsimError, match=r"r.jsonl, line 3: not a benchmark record"):
        load_records(p, lambda r: r["seed"])
