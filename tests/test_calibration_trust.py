"""Issue 21 (part): a calibration is not a success when the joint fit stopped at its
iteration limit (the never-worse check is pinned in test_calibration_mixed.py, on the
real-sensor-like dataset where a fit made depth worse than its start)."""
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


def test_the_iteration_limit_is_not_reported_as_success(heave, tmp_path, capsys):
    """The joint fit converges in 3 iterations here; with --max-iter 1 it stops at the limit,
    which is 'unfinished' (exit 2), never a silent success."""
    argv = ["calibrate", "--data", str(heave), "--vehicle", "bluerov2_heavy", "--population", "6",
            "--generations", "2", "--seed", "3", "--max-iter", "1", "--out", str(tmp_path / "f.yaml"),
            "--json", str(tmp_path / "r.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unfinished: the joint fit's last stage stopped at the iteration limit (1 iterations)" in err
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["refinement"]["stages"][-1]["message"].startswith("maximum number of iterations")
    assert not rep["status"]["ok"]


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
