"""How channels logged at different rates are weighted (issue 21): per second of log by default
in the calibration, so a 10 Hz depth beside a 100 Hz IMU is not outweighed tenfold; and a
channel named like its group (``depth``) weighted once, not squared."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from uvsim.calibration import Calibrator
from uvsim.calibration.calibrator import DEFAULT_SAMPLE_WEIGHTING
from uvsim.calibration.inputs import combine_weights
from uvsim.errors import CalibrationError
from uvsim.logs import Run
from uvsim.measurements import RunMeasurements, measurements_for
from uvsim.signals import channel_weight, per_second_factors


def _imu_depth_run(depth_every: int = 10) -> Run:
    """20 s of a 100 Hz gyro and a depth sensor logged every ``depth_every``-th row (NaN between)."""
    t = np.arange(0.0, 20.0, 0.01)
    rng = np.random.default_rng(0)
    d = pd.DataFrame({"t": t, "p": 0.1 * np.sin(t), "q": 0.1 * np.cos(t), "r": 0.05 * np.sin(2 * t)})
    for c in ("p", "q", "r"):
        d[c] += 0.003 * rng.standard_normal(t.size)
    depth = 1.0 + 0.1 * np.sin(0.5 * t) + 0.01 * rng.standard_normal(t.size)
    depth[np.arange(t.size) % depth_every != 0] = np.nan
    d["depth"] = depth
    for i in range(1, 9):
        d[f"pwm_{i}"] = 1500.0
    return Run("imu_depth", None, d)


def test_a_channel_named_like_its_group_is_weighted_once():
    m = RunMeasurements("a", np.arange(3.0), {}, {}, 9.81, {"depth": 10.0, "attitude": 2.0, "roll": 0.5})
    np.testing.assert_allclose(m.channel_weights("depth"), [10.0])  # was 100: group x channel, both "depth"
    np.testing.assert_allclose(m.channel_weights("attitude"), [1.0, 2.0, 2.0])
    assert channel_weight({"depth": 3.0}, "depth", "depth") == 3.0
    assert combine_weights({"depth": 1.0}, {"depth": 3.0})["depth"] == 3.0


def test_per_second_factors_weight_a_slow_channel_up_by_the_rate_ratio():
    run = _imu_depth_run(10)
    m = measurements_for(run, sample_weighting="per_second")
    assert m.rate_factors == pytest.approx({"depth": 10.0, "p": 1.0, "q": 1.0, "r": 1.0})
    assert per_second_factors(m.groups) == m.rate_factors
    assert measurements_for(run).rate_factors == {}  # per_sample: the function's default
    # the residual vector: depth entries sqrt(10) larger, the gyro's unchanged
    pred = {g: np.zeros_like(grp.values) for g, grp in m.groups.items()}
    per_sample = measurements_for(run).normalized(pred)
    per_second = m.normalized(pred)
    n_depth = int(m.used("depth").sum())
    assert n_depth == 200
    np.testing.assert_allclose(per_second[:n_depth], np.sqrt(10.0) * per_sample[:n_depth])
    np.testing.assert_allclose(per_second[n_depth:], per_sample[n_depth:])
    # the user's weights multiply the factors
    w = measurements_for(run, weights={"depth": 2.0, "p": 0.0}, sample_weighting="per_second")
    np.testing.assert_allclose(w.channel_weights("depth"), [20.0])
    np.testing.assert_allclose(w.channel_weights("rates"), [0.0, 1.0, 1.0])


def test_dropouts_do_not_weight_a_channel_up():
    run = _imu_depth_run(10)
    gone = run.data["depth"].to_numpy().copy()
    gone[500:1500] = np.nan  # the depth sensor silent for 10 of the 20 s
    run.data["depth"] = gone
    assert measurements_for(run, sample_weighting="per_second").rate_factors["depth"] == pytest.approx(10.0)


def test_channels_at_one_rate_are_unaffected():
    m = measurements_for(_imu_depth_run(1), sample_weighting="per_second")
    assert m.rate_factors == pytest.approx({"depth": 1.0, "p": 1.0, "q": 1.0, "r": 1.0})


def test_bad_sample_weighting_is_a_clear_error():
    with pytest.raises(CalibrationError, match="sample_weighting 'per_minute'.*per_sample"):
        measurements_for(_imu_depth_run(), sample_weighting="per_minute")
    with pytest.raises(CalibrationError, match="sample_weighting"):
        Calibrator(sample_weighting="per_minute").fit([_imu_depth_run()], "bluerov2_heavy")
    assert DEFAULT_SAMPLE_WEIGHTING == "per_second" == Calibrator().sample_weighting


@pytest.mark.slow
def test_on_independent_data_per_second_weighting_stops_trading_depth(tmp_path):
    """Benchmark seed 10 of ``uvsim bench calibrate-structural`` (the independent generator: T200s on
    the 12 V curve, a weak thruster, a 100 Hz IMU beside a 10 Hz depth sensor): weighted per sample,
    the fit traded validation depth for the IMU channels (Fit % 6.2 points below the start's,
    refused); per second of log it gains there too (+13.0 points, accepted; 2026-11-26).  Both fits
    leave the accelerometer's offset out (``acc_bias=False``, as the calibration did then): the
    per-run offset the model then lacks is the correlated IMU misfit that per-sample weighting
    trades depth for.  With the offset fitted (the default since 2026-11-27) the per-sample fit no
    longer loses depth on this seed (+0.8 points), so the offset was part of what it traded."""
    from uvsim.benchmarks.calibration_structural import judge, scenario
    from uvsim.scenarios import generate, sample_scenario

    out = generate(sample_scenario(10, profile="realsensor", **scenario(10)), tmp_path / "ds")
    rec = {w: judge(Calibrator(free="z_b", sample_weighting=w, acc_bias=False).fit(out).report_)
           for w in ("per_sample", "per_second")}
    sample, second = rec["per_sample"], rec["per_second"]
    assert "depth" in sample["worse"], sample
    assert second["gain"]["depth"] > sample["gain"]["depth"] + 10, (sample["gain"], second["gain"])
    assert not second["worse"] and second["check_ok"], second
