"""Issue 21 (part) and 45: a joint fit stopped at its iteration limit is never a silent
success: it is judged by the verdict like any other fit, and reported as unfinished beside it
(the verdict itself is pinned in test_verdict.py and test_calibration_mixed.py)."""
from __future__ import annotations

import json

import pytest

from uvsim.cli import main
from uvsim.synthetic import generate_dataset

SMALL = dict(runs_per_dof=2, validation_per_dof=1, duration=6.0, rate=20.0)


@pytest.fixture(scope="module")
def heave(tmp_path_factory):
    d = tmp_path_factory.mktemp("heave") / "d"
    generate_dataset("bluerov2_heavy", d, dofs=["heave"], seed=2, **SMALL)
    return d


def test_the_iteration_limit_is_reported_beside_the_verdict(heave, tmp_path, capsys):
    """The joint fit converges in 3 iterations here; with --max-iter 1 it stops at the limit:
    the exit status is the verdict's on the model it reached, and the verdict line, the error
    (if any) and the report's ``status.caveats`` say it is unfinished."""
    argv = ["calibrate", "--data", str(heave), "--vehicle", "bluerov2_heavy", "--population", "6",
            "--generations", "2", "--seed", "3", "--max-iter", "1", "--out", str(tmp_path / "f.yaml"),
            "--json", str(tmp_path / "r.json")]
    code = main(argv)
    text = capsys.readouterr()
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["refinement"]["stages"][-1]["message"].startswith("maximum number of iterations")
    assert code == rep["status"]["exit_code"] == {"better": 0, "trade-off": 3, "worse": 2}[rep["verdict"]["status"]]
    assert rep["status"]["verdict"] == rep["verdict"]["status"]
    assert any(c.startswith("unfinished: the joint fit's last stage stopped at the iteration limit (1 iterations)")
               for c in rep["status"]["caveats"])
    assert "unfinished" in text.out and "unfinished" in rep["status"]["why"]


def test_without_validation_runs_the_check_compares_on_the_training_runs(tmp_path, capsys):
    """No validation run: the fitted model is still compared with its start, on the training
    runs (report verdict.split 'train', and the message says so), never skipped."""
    d = tmp_path / "d"
    generate_dataset("bluerov2_heavy", d, dofs=["heave"], seed=2, **{**SMALL, "validation_per_dof": 0})
    argv = ["calibrate", "--data", str(d), "--vehicle", "bluerov2_heavy_initial", "--population", "6",
            "--generations", "2", "--seed", "3", "--out", str(tmp_path / "f.yaml"), "--json", str(tmp_path / "r.json"),
            "--keep-worse"]
    assert main(argv) in (0, 2, 3)
    v = json.loads((tmp_path / "r.json").read_text())["verdict"]
    assert v is not None and v["split"] == "train" and v["channels"]
    assert "compared on the training runs" in v["message"]


def test_start_alignment_removes_a_start_offset_and_keeps_a_drift():
    """Every open-loop prediction (uvsim.fitting.evaluate.open_loop) shifts predicted depth by its
    mean residual over the first 3 s (the shared, noisy start), never by anything later: a
    constant offset disappears, a drift that starts after the window stays."""
    import numpy as np

    from uvsim.fitting.evaluate import align_start
    from uvsim.logs import Run
    from uvsim.measurements import measurements_for
    import pandas as pd

    t = np.arange(0.0, 20.0, 0.1)
    depth = 1.0 + 0.1 * np.sin(t)
    run = Run("r", None, pd.DataFrame({"t": t, "X": 0.0, "Y": 0.0, "Z": 0.0, "K": 0.0, "M": 0.0, "N": 0.0,
                                       "depth": depth}))
    m = measurements_for(run, None, noise={"depth": 0.01})
    a = align_start(m, {"depth": (depth + 0.03)[:, None]})["depth"][:, 0]
    np.testing.assert_allclose(a, depth, atol=1e-12)
    b = align_start(m, {"depth": (depth + 0.02 * np.clip(t - 5.0, 0.0, None))[:, None]})["depth"][:, 0]
    assert np.max(np.abs(b - depth)) == pytest.approx(0.02 * (t[-1] - 5.0), rel=1e-9)


def test_a_fit_is_not_refused_for_what_its_start_model_does_on_the_same_runs(monkeypatch):
    """Issue 45: the sanity check's "the simulation diverged" counts a channel only where the
    starting model's simulation stays finite and within EXPLODE_FACTOR x the measured spread
    (a closed-loop log of an open-loop unstable vehicle makes both explode; the verdict then
    compares them over the horizon both stay finite)."""
    from uvsim.commands import checks

    monkeypatch.setattr(checks, "_spread", lambda runs: {"depth_m": 0.01, "rates_radps": 0.1})
    fit = {"depth_m": 1.0, "rates_radps": float("nan")}
    assert len(checks.rmse_problems(fit, [], "training RMSE")) == 2            # no start: absolute
    assert checks.rmse_problems(fit, [], "training RMSE", {"depth_m": 2.0, "rates_radps": float("inf")}) == []
    probs = checks.rmse_problems(fit, [], "training RMSE", {"depth_m": 0.02, "rates_radps": 0.05})
    assert len(probs) == 2 and all("where the starting model's did not" in p for p in probs)
    assert "depth_m = 1 is 100 times the spread" in probs[0]
    assert checks.rmse_problems({"depth_m": 0.05}, [], "training RMSE", {"depth_m": 0.02}) == []
    # where both leave the data, the verdict stands and a caveat says so
    from types import SimpleNamespace

    rep = {"training_rmse": fit, "initial_training_rmse": {"depth_m": 2.0, "rates_radps": 0.05},
           "validation_rmse": {}, "initial_validation_rmse": {}, "refinement": {"stages": [{"message": "ok"}]}}
    cav = checks.calibration_caveats(rep, SimpleNamespace(runs=[]))
    assert len(cav) == 1 and "on the train runs the simulations of both models leave the data (depth_m" in cav[0]
    assert checks.rmse_problems(fit, [], "training RMSE", rep["initial_training_rmse"])[0].startswith(
        "training RMSE rates_radps is not finite")
