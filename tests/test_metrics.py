"""Tests of uvsim.metrics (shared residual metrics), checked against hand computations."""
import numpy as np
import pytest

from uvsim import metrics as M


def test_fit_percent_hand_computation():
    y = np.array([1.0, 2.0, 3.0, 4.0])
    yh = np.array([1.0, 2.0, 3.0, 5.0])
    # ||y - yh|| = 1, ||y - mean|| = sqrt(2.25 + 0.25 + 0.25 + 2.25) = sqrt(5)
    assert M.fit_percent(y, yh) == pytest.approx(100 * (1 - 1 / np.sqrt(5)))
    assert M.fit_percent(y, y) == pytest.approx(100.0)
    assert M.fit_percent(y, np.full(4, y.mean())) == pytest.approx(0.0)
    assert np.isnan(M.fit_percent(np.ones(4), np.ones(4)))


def test_nan_samples_are_skipped_not_zero_filled():
    y = np.array([1.0, np.nan, 2.0, 3.0, 4.0])
    yh = np.array([1.0, 100.0, 2.0, 3.0, 5.0])
    assert M.fit_percent(y, yh) == pytest.approx(100 * (1 - 1 / np.sqrt(5)))
    assert M.rmse(y - yh) == pytest.approx(np.sqrt(1 / 4))
    # NRMSE: RMSE / range of the measured values (seed 000 sec. 5)
    assert M.nrmse(y, yh) == pytest.approx(0.5 / 3.0)


def test_group_fit_uses_frobenius_norms():
    y = np.array([[0.0, 1.0], [1.0, 3.0], [2.0, 5.0]])
    yh = y + np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    num = np.sqrt(2.0)
    den = np.sqrt(np.sum((y - y.mean(axis=0)) ** 2))
    assert M.fit_percent(y, yh) == pytest.approx(100 * (1 - num / den))


def _depth_only(n=50, name="r"):
    import pandas as pd

    from uvsim.logs import Run
    from uvsim.measurements import measurements_for

    t = np.linspace(0, 5, n)
    z = 0.5 * np.sin(t) + 0.001 * np.random.default_rng(n).standard_normal(n)  # noise: every sample native
    run = Run(name, None, pd.DataFrame({"t": t, "X": 0.0, "Y": 0.0, "Z": 0.0, "K": 0.0, "M": 0.0, "N": 0.0,
                                        "depth": z}))
    return run, measurements_for(run, None, noise={"depth": 0.01})


def test_depth_only_run_metrics():
    run, m = _depth_only()
    z = run.depth
    met = M.measurement_metrics(m, {"depth": (z + 0.01)[:, None]})
    assert set(met["channels"]) == {"depth"}
    assert met["depth_m"] == pytest.approx(0.01)
    assert met["channels"]["depth"]["fit_percent"] == pytest.approx(
        100 * (1 - np.linalg.norm(np.full_like(z, 0.01)) / np.linalg.norm(z - z.mean())))
    assert "attitude_rad" not in met


def test_pooled_metrics_pool_samples():
    (r1, m1), (r2, m2) = _depth_only(10, "a"), _depth_only(30, "b")
    met = [M.measurement_metrics(m1, {"depth": (r1.depth + 0.1)[:, None]}),
           M.measurement_metrics(m2, {"depth": (r2.depth + 0.2)[:, None]})]
    assert M.pooled_group_rmse(met)["depth_m"] == pytest.approx(np.sqrt((10 * 0.01 + 30 * 0.04) / 40))
    sst = sum(float(np.sum((r.depth - r.depth.mean()) ** 2)) for r in (r1, r2))
    assert M.pooled_fit_percent(met)["depth"] == pytest.approx(100 * (1 - np.sqrt((10 * 0.01 + 30 * 0.04) / sst)))
