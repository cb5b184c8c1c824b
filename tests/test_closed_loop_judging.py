"""Issue 48, item 2: judging models validly on closed-loop logs.

A vehicle flown under an autopilot (depth hold, heading hold) is logged with the inputs the loop
chose; the given model flown open loop with them over a whole run leaves the data, so whole-run
free simulations cannot tell two models apart.  The diagnosis then judges predictions over windows
of a few seconds, each started from the logged state (uvsim.fitting.evaluate.windowed), and says
so in report.json (``judged``); open-loop tank data keep whole-run free simulations."""
from __future__ import annotations

import copy

import numpy as np
import pytest

from contract_data import SHIPPED_DATASET
from uvsim.fitting.evaluate import (CLOSED_LOOP_HORIZON_S, DECLARED_CLOSED_LOOP_HORIZON_S, judged_prediction, open_loop,
                                   windowed)
from uvsim.fitting.verdict import compare
from uvsim.latency import runs_for
from uvsim.logs import read_dataset
from uvsim.measurements import measurements_for
from uvsim.vehicle import load_vehicle


def _field(tmp_path, seed, case, duration=None):
    from uvsim.scenarios.field import generate_field, sample_field

    out = generate_field(sample_field(seed, case, duration=duration), tmp_path / f"{case}{seed}")
    ds = read_dataset(out)
    veh = load_vehicle(ds.vehicle_file)
    val = runs_for(veh, ds.validation)
    return veh, val, [measurements_for(r, veh, run_weight=1.0) for r in val]


@pytest.fixture(scope="module")
def dead(tmp_path_factory):
    return _field(tmp_path_factory.mktemp("closed"), 1, "dead", duration=12.0)


def test_each_window_starts_on_the_logged_state(dead):
    veh, val, meas = dead
    res = windowed(veh, val, 4.0, meas=meas)
    for run, r, m in zip(val, res, meas):
        assert r["horizon_s"] == 4.0 and r["starts"][0] == 0 and len(r["starts"]) == 3   # 12 s in 4-s windows
        assert np.all(np.isfinite(r["states"]))                                            # every row owned
        e = m.residuals(r["pred"])
        for s in r["starts"]:   # the attitude at each window's start is the logged one (filter noise only)
            assert np.nanmax(np.abs(e["attitude"][s])) < 0.02
        # a window's error grows from its start: the first rows of windows are closer than their ends
        first = np.concatenate([np.abs(e["depth"][s:s + 2, 0]) for s in r["starts"]])
        assert np.nanmean(first) < np.sqrt(np.nanmean(e["depth"] ** 2))


def test_a_window_as_long_as_the_run_is_one_free_simulation(dead):
    veh, val, meas = dead
    (w,) = windowed(veh, val[:1], 100.0, meas=meas[:1])
    (f,) = open_loop(veh, val[:1], meas=meas[:1])
    assert w["starts"] == [0]
    # the same simulation from the same start attitude (velocities: the logged ones near the start)
    assert np.allclose(w["states"][0, 3:7], f["states"][0, 3:7], atol=1e-9)


def _undeclared(runs):
    """Copies of ``runs`` whose log does not say whether they were flown in closed loop."""
    out = [copy.copy(r) for r in runs]
    for r in out:
        r.closed_loop = None
    return out


def test_closed_loop_logs_are_judged_over_windows_and_tank_runs_over_whole_runs(dead):
    veh, val, meas = dead
    assert all(r.closed_loop for r in val)            # the field generator's log says so
    j = judged_prediction(veh, val, meas)
    assert j["prediction"] == "windows" and j["horizon_s"] == DECLARED_CLOSED_LOOP_HORIZON_S == 1.0
    assert j["declared"] == [r.name for r in val] and "flown under an autopilot" in j["why"]
    assert j["left_data"]                             # recorded beside it
    # not declared: the given model's free simulation leaves the data, so windows all the same
    j = judged_prediction(veh, _undeclared(val), meas)
    assert j["prediction"] == "windows" and j["horizon_s"] == CLOSED_LOOP_HORIZON_S and j["left_data"]
    assert "declared" not in j and "leaves the validation data" in j["why"]
    assert judged_prediction(veh, val, meas, "whole")["horizon_s"] is None
    assert judged_prediction(veh, val, meas, 2.5)["horizon_s"] == 2.5
    tank = read_dataset(SHIPPED_DATASET)
    tveh = load_vehicle(tank.vehicle_file or tank.vehicle)
    tval = runs_for(tveh, tank.validation)
    jt = judged_prediction(tveh, tval, [measurements_for(r, tveh, run_weight=1.0) for r in tval])
    assert jt["prediction"] == "whole runs" and jt["horizon_s"] is None


def test_the_caveat_says_what_was_judged(dead):
    from uvsim.commands.checks import diagnosis_caveats

    veh, val, meas = dead
    rep = {"judged": judged_prediction(veh, val, meas), "rmse_before": {}, "rmse_after": {}}
    (c,) = diagnosis_caveats(rep, val)
    assert "were flown under an autopilot (closed_loop in the manifest)" in c and "windows of 1 s" in c
    undeclared = _undeclared(val)
    rep = {"judged": judged_prediction(veh, undeclared, meas), "rmse_before": {}, "rmse_after": {}}
    (c,) = diagnosis_caveats(rep, undeclared)
    assert "leaves the validation data" in c and f"windows of {CLOSED_LOOP_HORIZON_S:g} s" in c


@pytest.mark.slow
def test_the_true_weight_under_depth_hold_is_better_over_windows(tmp_path):
    """Field-log benchmark case 6 (a 2.5 N lead weight under depth hold): the model with the true
    weight is judged better than the given one over 5-s windows, and without it the depth error
    of a window grows with its length (the drift the hold hides over a whole run)."""
    veh, val, meas = _field(tmp_path, 6, "weight")
    vb = veh.with_effects([{"type": "ballast", "weight": 0.5}])
    over = {"ballast_weight": 2.481, "ballast_x": 0.065, "ballast_y": -0.193, "ballast_z": -0.112}
    a = windowed(veh, val, CLOSED_LOOP_HORIZON_S, meas=meas)
    b = windowed(vb, val, CLOSED_LOOP_HORIZON_S, meas=meas, overrides=over)
    v = compare(meas, [r["pred"] for r in a], [r["pred"] for r in b])
    assert v["status"] == "better" and v["channels"]["depth"]["rmse_b"] < 0.5 * v["channels"]["depth"]["rmse_a"]
    short = compare(meas, [r["pred"] for r in windowed(veh, val, 2.0, meas=meas)], [r["pred"] for r in a])
    assert short["channels"]["depth"]["rmse_b"] > 2 * short["channels"]["depth"]["rmse_a"]


def test_evidence_says_what_was_compared():
    """An effect accepted on the validation runs' evidence says whether whole runs or windows were
    compared (closed-loop logs are judged over windows: 'free simulation' would be wrong there)."""
    from uvsim.diagnosis.decision import open_loop_evidence

    guard = {"ok": True, "why": "better", "channels": {"z": {"mse_ratio": 0.2, "better": True, "rmse_change": -0.55}}}
    cmp = {"guard": dict(guard, horizon_s=None), "wald": {"p": 1e-12}, "relative": 0.4, "p_better": 1.0}
    assert "free simulation" in open_loop_evidence(cmp)
    cmp["guard"] = dict(guard, horizon_s=5.0)
    why = open_loop_evidence(cmp)
    assert "5-s windows" in why and "free simulation" not in why


def test_calibrate_judges_closed_loop_logs_as_diagnose_does(tmp_path):
    """Calibrate chooses what the verdict compares by the same rule as diagnose (issue 45: one
    verdict): on a log that says its runs were flown under an autopilot (and whose start model
    leaves the data), windows from the logged states, and the verdict's per-channel RMSEs, the
    report's RMSEs and the plots' predictions are those windows' (the start model's windowed RMSE,
    recomputed here, is the verdict's)."""
    from uvsim.calibration import Calibrator
    from uvsim.calibration.report import judged_for
    from uvsim.metrics import pooled_metrics
    from uvsim.scenarios.field import generate_field, sample_field

    out = generate_field(sample_field(1, "dead", duration=12.0), tmp_path / "dead1")
    cal = Calibrator(max_iter=3).fit(out)
    rep = cal.report_
    h = DECLARED_CLOSED_LOOP_HORIZON_S
    assert rep["judged"]["prediction"] == "windows" and rep["judged"]["horizon_s"] == h
    assert rep["judged"]["declared"] and rep["judged"]["left_data"] and "autopilot" in rep["judged"]["why"]
    ds = read_dataset(out)
    val = runs_for(cal.initial_vehicle_, ds.validation)
    meas = [cal.evaluation_["meas"][r.name] for r in val]
    again = windowed(cal.initial_vehicle_, val, h, meas=meas)
    ch = pooled_metrics([r["metrics"] for r in again])["channels"]
    for c, v in rep["verdict"]["channels"].items():
        assert v["rmse_a"] == pytest.approx(ch[c]["rmse"], rel=1e-9), c
    assert cal.predict(val)[val[0].name]["horizon_s"] == h
    # asked for whole runs, the same data are judged on free simulations
    cal.judge_horizon = "whole"
    assert judged_for(cal, ds.runs, cal._meas(ds.runs))["horizon_s"] is None


def test_calibrate_refuses_a_judge_horizon_it_cannot_use():
    from uvsim.calibration import Calibrator
    from uvsim.errors import CalibrationError

    with pytest.raises(CalibrationError, match="judge_horizon"):
        Calibrator(judge_horizon="5 s").fit(SHIPPED_DATASET)


def test_the_supply_voltage_choice_is_judged_by_the_same_rule(dead):
    """--supply-voltage auto keeps its refit by a verdict on the training runs: judged like the
    calibration's own (windows where the first fit's free simulation leaves the data)."""
    from uvsim.calibration.supply_voltage import training_verdict

    veh, val, meas = dead
    v = training_verdict(veh, veh.with_parameters({"X_uu": veh.parameters()["X_uu"] * 1.1}), val, meas)
    assert v["judged"]["prediction"] == "windows" and v["judged"]["split"] == "training"
    assert v["status"] in ("better", "trade-off", "worse")
    assert training_verdict(veh, veh, val, meas, judge_horizon="whole")["judged"]["horizon_s"] is None


@pytest.mark.parametrize("command", ["calibrate", "diagnose"])
@pytest.mark.parametrize("value", ["-1", "nan", "five"])
def test_a_judge_horizon_option_it_cannot_use_is_an_error_naming_the_option(command, value, tmp_path, capsys):
    from uvsim.cli import main

    args = [command, "--data", str(SHIPPED_DATASET), f"--judge-horizon={value}", "--no-progress"]
    rc = main(args + (["--out", str(tmp_path / "fit.yaml")] if command == "calibrate" else []))
    err = capsys.readouterr().err
    assert rc != 0 and "--judge-horizon" in err and value in err, err
