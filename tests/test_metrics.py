"""Tests of uvsim.metrics (shared residual metrics), checked against hand computations."""
import numpy as np
import pytest

from uvsim.kinematics import attitude_error_angle, euler_to_quat
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


def _depth_only(n=50):
    t = np.linspace(0, 5, n)
    z = 0.5 * np.sin(t)
    pos = np.full((n, 3), np.nan)
    pos[:, 2] = z
    return t, {"position": pos}


def test_depth_only_run_metrics():
    t, meas = _depth_only()
    pred_pos = np.zeros((len(t), 3))
    pred_pos[:, 2] = meas["position"][:, 2] + 0.01
    pred_pos[:, 0] = 5.0  # x is not logged: must not count
    pred = {"position": pred_pos, "quaternion": np.tile([1.0, 0, 0, 0], (len(t), 1)),
            "velocity": np.zeros((len(t), 3)), "rates": np.zeros((len(t), 3))}
    m = M.run_metrics(meas, pred)
    assert set(m["channels"]) == {"z"}
    assert m["position_m"] == pytest.approx(0.01)
    z = meas["position"][:, 2]
    assert m["channels"]["z"]["fit_percent"] == pytest.approx(
        100 * (1 - np.linalg.norm(np.full_like(z, 0.01)) / np.linalg.norm(z - z.mean())))
    assert "attitude_rad" not in m


def test_attitude_metrics_and_wrapping():
    n = 40
    yaw = np.linspace(2.9, 3.3, n)  # crosses +-pi
    e = np.zeros((n, 3))
    e[:, 2] = (yaw + np.pi) % (2 * np.pi) - np.pi
    qm = euler_to_quat(e)
    ep = e.copy()
    ep[:, 2] = e[:, 2] - 0.05
    qp = euler_to_quat(ep)
    meas = {"quaternion": qm}
    pred = {"quaternion": qp, "position": np.zeros((n, 3))}
    m = M.run_metrics(meas, pred)
    assert m["attitude_rad"] == pytest.approx(0.05, rel=1e-6)
    assert m["channels"]["yaw"]["rmse"] == pytest.approx(0.05, rel=1e-6)  # wrapped, not ~2 pi
    assert np.allclose(np.linalg.norm(M.rotation_vector_error(qm, qp), axis=-1), attitude_error_angle(qm, qp))


def test_pooled_rmse_pools_samples():
    t, meas = _depth_only(10)
    p1 = {"position": np.nan_to_num(meas["position"]) + np.array([0, 0, 0.1])}
    t2, meas2 = _depth_only(30)
    p2 = {"position": np.nan_to_num(meas2["position"]) + np.array([0, 0, 0.2])}
    r = M.pooled_rmse([(meas, p1), (meas2, p2)])
    assert r["position_m"] == pytest.approx(np.sqrt((10 * 0.01 + 30 * 0.04) / 40))


def test_weights_and_residual_vector():
    n = 20
    pos = np.column_stack([np.linspace(0, 1, n), np.zeros(n), np.zeros(n)])
    pos[3, 0] = np.nan
    meas = {"position": pos}
    pred = {"position": np.nan_to_num(pos) + 0.01}
    r = M.normalized_residuals(meas, pred, {"position": 0.01})
    assert r.size == 3 * n - 1 and np.allclose(r, -1.0)
    r = M.normalized_residuals(meas, pred, {"position": 0.01}, {"y": 0, "z": 0})
    assert r.size == n - 1
