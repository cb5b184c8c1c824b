"""Diagnosis building blocks: noise estimate, inverse-dynamics force residual, the
criterion, evidence on clean data, and the ``uvsim diagnose`` command."""
from __future__ import annotations

import json

import numpy as np
import pytest

import uvsim
from uvsim.calibration.batching import simulate_dataset
from uvsim.cli import main
from uvsim.diagnosis import force_residual, noise_levels
from uvsim.diagnosis.fit import bic, effective_n
from uvsim.diagnosis.signatures import evidence
from uvsim.synthetic import generate_dataset

VEH = uvsim.load_vehicle("bluerov2_heavy")


def _data(path, effects=None, seed=7, **kw):
    args = dict(runs_per_dof=2, validation_per_dof=1, duration=10.0, rate=10.0,
                signals=("position", "mocap_attitude"), seed=seed, effects=effects)
    args.update(kw)
    return generate_dataset("bluerov2_heavy", path, **args)


def test_noise_levels_match_the_generated_noise(tmp_path):
    ds = _data(tmp_path / "d", rate=20.0)
    est = noise_levels(ds.runs)
    assert est["position"] == pytest.approx(0.002, rel=0.2)
    assert est["attitude"] == pytest.approx(0.005, rel=0.25)


def test_force_residual_recovers_a_known_vertical_force(tmp_path):
    """A 3 N extra weight at the body origin: the NED down force residual averages +3 N,
    the other components about 0 (hand computation: f = w k, no moment)."""
    ds = _data(tmp_path / "b", [{"type": "ballast", "weight": 3.0}], rate=20.0)
    runs = [r for r in ds.runs if r.dof in ("surge", "sway", "yaw")]
    pred = simulate_dataset(VEH, runs)
    F = np.concatenate([force_residual(VEH, r, p["states"])["ned"] for r, p in zip(runs, pred)])
    mean = np.nanmean(F, axis=0)
    assert mean[2] == pytest.approx(3.0, abs=0.3)
    assert np.all(np.abs(mean[:2]) < 0.3)
    assert np.all(np.abs(mean[3:]) < 0.05)
    ev = {e["signature"]: e for e in evidence(VEH, runs, [force_residual(VEH, r, p["states"])
                                                           for r, p in zip(runs, pred)])}
    assert ev["constant in NED"]["present"] and "ballast" in ev["constant in NED"]["points_to"]


def test_force_residual_on_clean_data_is_noise(tmp_path):
    ds = _data(tmp_path / "c", rate=20.0)
    pred = simulate_dataset(VEH, ds.runs)
    fr = [force_residual(VEH, r, p["states"]) for r, p in zip(ds.runs, pred)]
    ev = evidence(VEH, ds.runs, fr)
    assert not any(e["present"] for e in ev), [(e["signature"], e["strength"]) for e in ev]
    B = np.concatenate([f["body"] for f in fr])
    assert np.all(np.abs(np.nanmean(B, axis=0)) < [0.2, 0.2, 0.2, 0.02, 0.02, 0.02])


def test_force_residual_masks_what_a_depth_only_log_cannot_give(tmp_path):
    ds = _data(tmp_path / "z", signals=("depth", "imu_attitude", "rates"))
    run = ds.runs[0]
    pred = simulate_dataset(VEH, [run])
    fr = force_residual(VEH, run, pred[0]["states"])
    assert np.isnan(fr["body"][:, :3]).all()          # no u, v from depth alone
    assert np.isfinite(fr["body"][10:-10, 3:]).all()  # moments from the gyro
    assert list(fr["measured"]) == [False, False, False, True, True, True]


def test_bic_and_effective_sample_size():
    assert effective_n(1000, 0.0) == 1000
    assert effective_n(1000, 0.9) == pytest.approx(1000 * 0.1 / 1.9)
    # halving the RMS (RSS / 4) with 2 parameters at n_eff = 50
    d = bic(25.0, 100, 2, 50.0) - bic(100.0, 100, 0, 50.0)
    assert d == pytest.approx(50 * np.log(0.25) + 2 * np.log(50))


def test_cli_diagnose_writes_report_vehicle_and_plots(tmp_path, capsys):
    _data(tmp_path / "d", [{"type": "thruster_lag", "time_constant": 0.3}])
    rc = main(["diagnose", "--data", str(tmp_path / "d"), "--vehicle", "bluerov2_heavy", "--json",
               str(tmp_path / "r.json"), "--out", str(tmp_path / "fixed.yaml"), "--plots", str(tmp_path / "p"),
               "--quiet", "--only", "thruster_lag,current"])
    assert rc == 0
    out = capsys.readouterr().out
    assert "thruster_lag" in out and "before" in out and "after" in out
    rep = json.loads((tmp_path / "r.json").read_text())
    for key in ("effect", "parameters", "candidates", "rmse_before", "rmse_after", "per_run", "evidence"):
        assert key in rep
    assert rep["effect"] == "thruster_lag"
    for c in rep["candidates"]:
        assert {"name", "parameters", "train_rmse", "validation_rmse", "score", "accepted", "why"} <= set(c)
    fixed = uvsim.load_vehicle(tmp_path / "fixed.yaml")
    assert [e.kind for e in fixed.effects] == ["thruster_lag"]
    assert fixed.parameters()["thruster_lag_time_constant"] == pytest.approx(
        rep["parameters"]["thruster_lag_time_constant"]["value"])
    assert "diagnosed" in (tmp_path / "fixed.yaml").read_text()
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == [
        "candidates.png", "force_residuals.png", "residuals_over_time.png"]


def test_cli_diagnose_bad_input_is_one_line_error(tmp_path, capsys):
    rc = main(["diagnose", "--data", str(tmp_path / "nope"), "--vehicle", "bluerov2_heavy", "--quiet"])
    assert rc == 2
    assert "error" in capsys.readouterr().err


@pytest.mark.parametrize("kw, match", [({"noise": {"pos": 0.002}}, "unknown signal group"),
                                       ({"weights": {"attitude": -1.0}}, "positive"),
                                       ({"only": ["tether", "wave"]}, "unknown candidate")])
def test_diagnose_rejects_bad_options(tmp_path, kw, match):
    from uvsim.diagnosis import diagnose
    from uvsim.errors import CalibrationError

    ds = _data(tmp_path / "o", duration=4.0)
    with pytest.raises(CalibrationError, match=match):
        diagnose(ds, "bluerov2_heavy", **kw)
