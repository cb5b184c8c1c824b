"""Issue 22 item 3 (every effect for every sensor set): a tether found from IMU + depth alone
(no x/y, no yaw), on data of the independent generator (:mod:`uvsim.scenarios`).

Two pieces make it findable: the diagnosis models the attitude filter's lag on the logged
roll and pitch as the calibration does (without it a 0.2 s lag left a residual far larger than
the tether's, and every candidate's robust Wald test failed), and with IMU + depth the tether
fitted through the simulator is its simplest variant with an attachment point (a pull at the
body origin shows only in depth and the accelerometer, while the gyro and the attitude see its
moment), from the catalogue's multi-start over four anchor directions."""
from __future__ import annotations

import numpy as np
import pytest

from uvsim.diagnosis.candidates import catalogue
from uvsim.diagnosis.selector import has_moment_arm
from uvsim.errors import CalibrationError
from uvsim.estimation.lag import attitude_lag_setting
from uvsim.logs import Run


def _lagged_run(tau, dt=0.01, T=20.0, seed=0):
    """Gyro p and a roll angle that trails its integral by a first-order lag ``tau``."""
    import pandas as pd

    from uvsim.estimation.lag import first_order_lag

    t = np.arange(0.0, T, dt)
    rng = np.random.default_rng(seed)
    p = np.convolve(rng.normal(size=t.size), np.ones(50) / 50, mode="same")
    roll = np.cumsum(p) * dt
    df = pd.DataFrame({"t": t, "p": p, "q": 0 * t, "r": 0 * t,
                       "roll": first_order_lag(t, roll[:, None], tau)[:, 0], "pitch": 0 * t,
                       **{c: np.zeros(t.size) for c in "XYZKMN"}})
    return Run("r", None, df)


def test_the_attitude_lag_setting_is_shared_and_checked():
    est = attitude_lag_setting([_lagged_run(0.2)])
    assert est["tau"] == pytest.approx(0.2, rel=0.1) and est["source"].startswith("estimated")
    # shorter than LAG_MIN_SAMPLES sample intervals: the sampling, not a filter
    assert attitude_lag_setting([_lagged_run(0.0)])["tau"] == 0.0
    assert attitude_lag_setting([_lagged_run(0.2)], 0.05) == {"tau": 0.05, "source": "given"}
    for bad in ("soon", -1.0, float("nan")):
        with pytest.raises(CalibrationError, match="attitude_lag"):
            attitude_lag_setting([_lagged_run(0.2)], bad)


def test_with_imu_and_depth_the_tether_fitted_has_an_attachment():
    cands = catalogue(input_kind="pwm", n_thrusters=8, dt=0.01, p_ref=np.zeros(3), has_position=False,
                      z_max=3.0, only=["tether", "ballast", "current"], exclude=set(), has_depth=True, base={})
    with_arm = {c.label for c in cands if has_moment_arm(c)}
    assert "tether:3d_attach" in with_arm and "tether:3d" not in with_arm
    assert "ballast:xy" in with_arm and not any(lbl.startswith("current") for lbl in with_arm)


@pytest.mark.slow
def test_a_tether_is_found_from_imu_and_depth_alone(tmp_path):
    """The docs' former limitation case: a surface-spool tether (T_0 = 1 N, k = 1 N/m beyond a
    2.54 m slack, cable drag, attached at (-0.009, 0.115, 0.068) m), 8 telegraph-PWM runs of
    10-14 s, 150 Hz IMU, roll and pitch from a 0.2 s filter, no yaw, 10 Hz depth, no x/y; every
    run starts at its own unlogged heading. Named with an attachment on the right side, and the
    open-loop depth and attitude errors fall by more than half (186 -> 39 mm, 41 -> 11 mrad
    when written, 2 workers, about 4 min)."""
    from uvsim.diagnosis import diagnose
    from uvsim.logs import read_dataset
    from uvsim.scenarios import generate, load_truth, sample_scenario

    spec = sample_scenario(1, profile="realsensor", effects=[{"type": "tether", "variant": "3d", "magnitude": 1.0}],
                           perturbation=0.0, perturb_z_b=False, n_runs=8, duration=[10, 14])
    d = generate(spec, tmp_path / "ds")
    runs = read_dataset(d).runs
    assert not any(r.has_position for r in runs) and not any("yaw" in r.data for r in runs)
    assert load_truth(d)["sensors"]["euler"]["time_constant"] == pytest.approx(0.2, rel=0.05)
    rep = diagnose(d, workers=2).report
    assert rep["attitude_lag"]["tau"] == pytest.approx(0.2, rel=0.1)
    assert [e["effect"] for e in rep["effects"]] == ["tether"], rep["message"]
    params = rep["effects"][0]["parameters"]
    assert params["tether_attach_y"]["value"] > 0.05          # the truth's attachment is 0.115 m to starboard
    assert rep["rmse_after"]["depth_m"] < 0.5 * rep["rmse_before"]["depth_m"]
    assert rep["rmse_after"]["attitude_rad"] < 0.5 * rep["rmse_before"]["attitude_rad"]
