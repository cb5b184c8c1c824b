"""Issue 45: one measure, one verdict (uvsim.fitting.verdict, uvsim.metrics).

Runs and errors are made by hand here (tests/verdict_data.py), so each test knows every
channel's error exactly; the end-to-end cases (calibration, diagnosis) are in the tests of
those commands."""
from __future__ import annotations

import numpy as np
import pytest

from uvsim.fitting.verdict import EQUIVALENCE, MATERIAL, compare, score, table
from uvsim.kinematics import euler_to_quat
from uvsim.metrics import channel_series, measurement_metrics, pooled_metrics
from verdict_data import CHANNELS, errors, logged_run, model, prediction


def _two(scale_b: dict, seed: int = 0, n_runs: int = 2, **kw):
    runs = [logged_run(seed + i, name=f"val_{i:02d}") for i in range(n_runs)]
    ms = [model(r) for r in runs]
    errs = [errors(m, seed + 10 + i) for i, m in enumerate(ms)]
    pa = [prediction(m, e) for m, e in zip(ms, errs)]
    pb = [prediction(m, e, scale_b) for m, e in zip(ms, errs)]
    return ms, pa, pb, compare(ms, pa, pb, names=("A", "B"), **kw)


def test_better_when_every_channel_improves():
    ms, pa, pb, v = _two({c: 0.5 for c in CHANNELS})
    assert v["status"] == "better" and v["ok"] and v["exit_code"] == 0
    assert v["pooled"]["rmse_change"] == pytest.approx(-0.5, abs=1e-9)  # every RMSE halved
    assert set(v["channels"]) == set(CHANNELS) and v["better"] == list(v["channels"]) and not v["worse"]
    assert v["message"].startswith("better: pooled error -50 %")


def test_a_channel_traded_for_the_others_is_a_trade_off_naming_it():
    """B halves every channel's error but makes depth 30 % worse in every block."""
    ms, pa, pb, v = _two({**{c: 0.5 for c in CHANNELS}, "depth": 1.3})
    assert v["status"] == "trade-off" and not v["ok"] and v["exit_code"] == 3
    assert v["worse"] == ["depth"]
    d = v["channels"]["depth"]
    assert d["rmse_change"] == pytest.approx(0.3, abs=1e-9) and d["rmse_b"] > d["rmse_a"]
    assert "depth +30 %" in v["message"] and "trade-off" in v["message"]


def test_worse_when_the_pooled_error_is_not_lower():
    ms, pa, pb, v = _two({c: 1.2 for c in CHANNELS})
    assert v["status"] == "worse" and v["exit_code"] == 2 and not v["pooled"]["better"]
    # the same model twice is not better either: no change is not an improvement
    ms, pa, pb, v = _two({})
    assert v["status"] == "worse" and v["pooled"]["change"] == 0.0 and not v["worse"]
    assert "not better than A beyond the comparison's noise" in v["message"]


def test_changes_within_the_equivalence_margin_are_no_change():
    """Every block 0.5 % worse in roll (paired, so 'significant'), the rest halved: better."""
    assert EQUIVALENCE >= 0.01
    ms, pa, pb, v = _two({**{c: 0.5 for c in CHANNELS}, "roll": 1.005})
    assert v["status"] == "better" and "roll" not in v["worse"]
    assert v["channels"]["roll"]["p_worse"] == 0.0


def test_a_loss_carried_by_one_block_is_within_the_noise_but_a_material_one_is_not():
    runs = [logged_run(i, name=f"val_{i:02d}") for i in range(2)]
    ms = [model(r) for r in runs]
    errs = [errors(m, 20 + i) for i, m in enumerate(ms)]
    pa = [prediction(m, e) for m, e in zip(ms, errs)]
    half = {c: 0.5 for c in CHANNELS}
    # B: every channel halved, and pitch 4x worse over one second of one run only
    eb = [dict(e) for e in errs]
    t = ms[0].t
    eb[0]["pitch"] = np.where((t > 10) & (t < 11), 4.0, 0.5) * errs[0]["pitch"]
    pb = [prediction(m, e, {**half, "pitch": 1.0}) for m, e in zip(ms, eb)]
    v = compare(ms, pa, pb)
    assert "pitch" not in v["worse"] and v["status"] == "better"
    # pitch twice as bad everywhere: worse whatever the rest does
    pb = [prediction(m, e, {**half, "pitch": 2.0}) for m, e in zip(ms, errs)]
    v = compare(ms, pa, pb)
    assert v["worse"] == ["pitch"] and v["status"] == "trade-off"


def test_few_blocks_still_catch_a_material_loss():
    """One 8 s validation run (three blocks): depth 2.5 times worse cannot reach the Bonferroni
    level, but a material loss (> MATERIAL) worse in LEVEL of the resamples counts."""
    r = logged_run(3, duration=8.0)
    m = model(r)
    e = errors(m, 4)
    pa = [prediction(m, e)]
    pb = [prediction(m, e, {**{c: 0.6 for c in CHANNELS}, "depth": 2.5})]
    v = compare([m], pa, pb)
    assert v["channels"]["depth"]["rmse_change"] > MATERIAL
    assert "depth" in v["worse"] and v["status"] == "trade-off"


def test_a_zero_weight_takes_a_channel_out_of_the_fit_not_out_of_the_verdict():
    r = logged_run(5)
    m = model(r, weights={"depth": 0.0, "acceleration": 0.0})
    assert not m.used("depth").any()                     # out of every fit
    e = errors(m, 6)
    v = compare([m], [prediction(m, e)], [prediction(m, e, {**{c: 0.5 for c in CHANNELS}, "depth": 3.0})])
    assert "depth" in v["channels"] and v["worse"] == ["depth"] and v["status"] == "trade-off"


def test_a_model_that_diverges_is_compared_over_its_finite_horizon_and_named():
    r = logged_run(7)
    m = model(r)
    e = errors(m, 8)
    good = prediction(m, e, {c: 0.5 for c in CHANNELS})
    blown = {g: np.where((m.t >= 12.0)[:, None], np.nan, v) for g, v in good.items()}
    start = prediction(m, e)
    # B diverges where A does not: worse, said so, whatever the finite part says
    v = compare([m], [start], [blown])
    assert v["status"] == "worse" and v["diverged"] == ["val_01"] and "diverges" in v["message"]
    assert v["horizon"]["val_01"]["compared_s"] == pytest.approx(12.0 - 0.05)
    # A (the start) diverges and B does not: B judged over the horizon A stays finite, every channel
    a_blown = {g: np.where((m.t >= 12.0)[:, None], np.nan, v) for g, v in start.items()}
    v = compare([m], [a_blown], [good])
    assert v["status"] == "better" and set(v["channels"]) == set(CHANNELS) and not v["diverged"]
    assert v["horizon"]["val_01"]["diverged"] == ["A"] and "compared val_01 over its first 12.0" in v["message"]
    # the report's metrics do not hide a diverged simulation as a shorter one
    assert np.isinf(measurement_metrics(m, blown)["channels"]["x"]["rmse"])


def test_one_wrapped_euler_error_for_quaternion_and_euler_logs():
    """A yaw crossing +-pi, logged as angles and as a quaternion: the same channel errors (a
    few mrad, not 2 pi), the same metrics and the same verdict."""
    t = np.arange(0.0, 20.0, 0.05)
    wobble = 0.002 * np.random.default_rng(9).standard_normal((t.size, 3))  # a sensor's noise, not a ramp
    yaw = (3.0 + 0.02 * t + wobble[:, 2] + np.pi) % (2 * np.pi) - np.pi
    eul = np.stack([0.1 * np.sin(t) + wobble[:, 0], 0.05 * np.cos(t) + wobble[:, 1], yaw], 1)
    q = euler_to_quat(eul)
    base = {"t": t, **{k: 0.0 for k in ("X", "Y", "Z", "K", "M", "N")}}
    r_e = logged_run(0, duration=20.0, **{"roll": eul[:, 0], "pitch": eul[:, 1], "yaw": eul[:, 2]})
    import pandas as pd
    from uvsim.logs import Run

    r_q = Run("val_01", None, pd.DataFrame({**base, "qw": q[:, 0], "qx": q[:, 1], "qy": q[:, 2], "qz": q[:, 3]}),
              split="validation")
    pred_eul = eul + np.array([0.003, -0.002, 0.004])
    for r in (r_e, r_q):
        m = model(r)
        p = {g: (pred_eul if g == "attitude" else np.array(grp.values)) for g, grp in m.groups.items()}
        ser = channel_series(m, p)
        np.testing.assert_allclose(ser["yaw"]["e"], -0.004, atol=1e-9)
        np.testing.assert_allclose(ser["roll"]["e"], -0.003, atol=1e-9)
        # the prediction drawn is the prediction (on the measured branch), not y minus another error
        np.testing.assert_allclose(np.unwrap(ser["yaw"]["y_hat"]) - np.unwrap(pred_eul[:, 2]), 0.0, atol=1e-9)


def test_report_metrics_pool_the_same_sums_the_verdict_uses():
    ms, pa, pb, v = _two({**{c: 0.5 for c in CHANNELS}, "depth": 1.3}, n_runs=3)
    pooled_b = pooled_metrics([measurement_metrics(m, p) for m, p in zip(ms, pb)])
    pooled_a = pooled_metrics([measurement_metrics(m, p) for m, p in zip(ms, pa)])
    for c, d in v["channels"].items():
        assert d["rmse_b"] == pytest.approx(pooled_b["channels"][c]["rmse"], rel=1e-12)
        assert d["fit_a"] == pytest.approx(pooled_a["channels"][c]["fit_percent"], rel=1e-12)
    lines = table(v)
    assert any(line.strip().startswith("depth") and line.rstrip().endswith("worse") for line in lines)


def test_the_score_ranks_models_and_needs_no_noise_level():
    """The pooled score is the same whatever noise level the measurement model states (it is the
    log-likelihood with each channel's variance estimated from its own errors)."""
    ms, pa, pb, v = _two({c: 0.5 for c in CHANNELS}, n_runs=1)
    s_a, s_b = score(ms, pa), score(ms, pb)
    assert s_b - s_a == pytest.approx(2 * np.log(0.5), rel=1e-12)
    m_loud = model(logged_run(0, name="val_00"), noise=10.0)
    assert score([m_loud], pa) == pytest.approx(s_a, rel=1e-12)
