"""``uvsim simulate`` on a logged run."""
from __future__ import annotations

import numpy as np
import pandas as pd

import uvsim
from uvsim.cli import main
from uvsim.logs import read_run


def _run_file(tmp_path):
    t = np.arange(0, 4.0, 0.02)
    U = np.zeros((t.size, 6))
    U[:, 0], U[:, 5] = 10.0, 0.5
    truth = uvsim.simulate("bluerov2_heavy", t, U, pos0=[1.0, 2.0, 3.0])
    df = truth.to_pandas()[["t", "x", "y", "z", "qw", "qx", "qy", "qz", "X", "Y", "Z", "K", "M", "N"]]
    p = tmp_path / "run.csv"
    df.to_csv(p, index=False)
    return p, truth


def test_simulate_cli_reproduces_run(tmp_path, capsys):
    p, truth = _run_file(tmp_path)
    out = tmp_path / "out.csv"
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(p), "--out", str(out)]) == 0
    df = pd.read_csv(out)
    assert list(df.columns[:17]) == ["t", "x", "y", "z", "qw", "qx", "qy", "qz", "roll", "pitch", "yaw",
                                     "u", "v", "w", "p", "q", "r"]
    assert np.abs(df[["x", "y", "z"]].to_numpy() - truth.position).max() < 1e-9
    # the written file is itself a valid run
    assert read_run(out).has_position


def test_simulate_cli_current_moves_the_vehicle(tmp_path):
    p, truth = _run_file(tmp_path)
    out = tmp_path / "out.csv"
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(p), "--out", str(out), "--current", "0.2,0,0"]) == 0
    df = pd.read_csv(out)
    assert df.x.iloc[-1] - truth.position[-1, 0] > 0.2


def test_simulate_cli_errors(tmp_path, capsys):
    p, _ = _run_file(tmp_path)
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(p), "--out", str(tmp_path / "o.csv"),
                 "--current", "0.2,0"]) == 2
    assert "--current" in capsys.readouterr().err
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(tmp_path / "nope.csv"),
                 "--out", str(tmp_path / "o.csv")]) == 2
    assert "nope.csv" in capsys.readouterr().err
