"""Sensor pieces of the calibration (issue 14): the attitude-filter lag (estimate and
measurement model), the GA fitness on measurement models, the resumable joint fit."""
import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

import uvsim
from realsensor_data import make_dataset
from uvsim.calibration.fitness import abs_error_fitness
from uvsim.estimation.lag import estimate_attitude_lag, first_order_lag
from uvsim.fitting import fit, make_space
from uvsim.fitting.objective import WindowedProblem
from uvsim.logs import Run, read_dataset
from uvsim.measurements import measurements_for


def _loop_lag(t, x, tau, y0):
    y = np.empty_like(x)
    y[0] = y0
    for k in range(1, len(x)):
        a = np.exp(-(t[k] - t[k - 1]) / tau)
        y[k] = a * y[k - 1] + (1 - a) * x[k]
    return y


@pytest.mark.parametrize("uniform", [True, False])
def test_first_order_lag_matches_the_recursion(uniform):
    rng = np.random.default_rng(0)
    t = np.arange(200) * 0.01 if uniform else np.cumsum(rng.uniform(0.005, 0.015, 200))
    x = np.stack([np.sin(3 * t), np.cos(2 * t)], 1)
    y = first_order_lag(t, x[None], 0.2, y0=np.array([0.3, -0.1]))[0]
    for j in range(2):
        np.testing.assert_allclose(y[:, j], _loop_lag(t, x[:, j], 0.2, [0.3, -0.1][j]), atol=1e-12)
    np.testing.assert_array_equal(first_order_lag(t, x, 0.0), x)


def _run(t, cols):
    base = {"t": t, **{c: np.zeros(t.size) for c in "XYZKMN"}}
    return Run("r", None, pd.DataFrame({**base, **cols}))


def test_attitude_lag_estimated_from_the_gyro():
    """Roll/pitch from a lagged filter, gyro with bias: the estimate recovers the time
    constant (the angles are made here with scipy, independently of uvsim)."""
    rng = np.random.default_rng(1)
    t = np.arange(0, 20, 0.01)
    roll = 0.3 * np.sin(1.3 * t) + 0.1 * np.sin(3.1 * t)
    pitch = 0.2 * np.sin(0.9 * t + 1.0)
    yaw = 0.5 * t
    R = Rotation.from_euler("ZYX", np.column_stack([yaw, pitch, roll]))
    # body rates from finite differences of the rotation (independent of uvsim's kinematics)
    dR = R[1:] * R[:-1].inv()
    w = R[:-1].inv().apply(dR.as_rotvec()) / 0.01
    w = np.vstack([w, w[-1]])
    runs = []
    for tau in (0.15,):
        cols = {c: w[:, j] + 0.01 * (j + 1) + rng.normal(0, 0.002, t.size) for j, c in enumerate("pqr")}
        cols["roll"] = _loop_lag(t, roll, tau, roll[0]) + rng.normal(0, 0.005, t.size)
        cols["pitch"] = _loop_lag(t, pitch, tau, pitch[0]) + rng.normal(0, 0.005, t.size)
        runs.append(_run(t, cols))
    est = estimate_attitude_lag(runs)
    assert est["tau"] == pytest.approx(0.15, rel=0.05)
    assert est["rms_with"] < 0.3 * est["rms_without"]
    assert estimate_attitude_lag([_run(t, {"roll": roll})])["tau"] is None  # no gyro: nothing to estimate


def test_lagged_attitude_model_and_window_restarts():
    t = np.arange(0, 4, 0.02)
    roll = 0.2 * np.sin(2 * t)
    logged = _loop_lag(t, roll, 0.2, roll[0])
    run = _run(t, {"roll": logged + 1e-6 * np.cos(9 * t), "pitch": 1e-6 * np.sin(7 * t)})
    m = measurements_for(run, None, noise={"attitude": 0.01}, attitude_lag=0.2)
    y = np.zeros((t.size, 13))
    y[:, 3:7] = Rotation.from_euler("ZYX", np.column_stack([0 * t, 0 * t, roll])).as_quat()[:, [3, 0, 1, 2]]
    pred = m.predict(y)["attitude"]
    # the lagged truth reproduces the log: exactly once the start (a line fit to the log
    # over 0.1 s, off by its curvature) has decayed, within 1 mrad before
    np.testing.assert_allclose(pred[:, 0], logged, atol=1.5e-3)
    np.testing.assert_allclose(pred[50:, 0], logged[50:], atol=1e-5)
    # restarted at window starts from the logged value: each window depends on its own states only
    mw = m.for_windows([0, 50, 100, 150])
    y2 = y.copy()
    y2[:50, 3:7] = np.array([1.0, 0, 0, 0])  # change the first window only
    p1, p2 = mw.predict(y)["attitude"], mw.predict(y2)["attitude"]
    np.testing.assert_array_equal(p1[50:], p2[50:])
    np.testing.assert_allclose(p1[:, 0], logged, atol=2e-3)
    assert m.for_windows([0, 50]) is not m and measurements_for(run, None).for_windows([0, 50]).attitude_lag == 0
    # windows of one length are filtered in one call: the same numbers as one by one (and with a
    # batch of states and a last, shorter window), to round-off: one by one, each window's filter
    # coefficient comes from its own first time step, equal on a uniform clock to the last bits
    mw = m.for_windows([0, 40, 80, 120, 160, 185])
    Y = np.stack([y, y2])
    batched = mw.predict(Y)["attitude"]
    object.__setattr__(mw, "_uniform", False)  # the one-by-one path
    np.testing.assert_allclose(batched, mw.predict(Y)["attitude"], rtol=0, atol=1e-12)
    with pytest.raises(uvsim.errors.CalibrationError, match="attitude_lag"):
        measurements_for(run, None, attitude_lag=float("nan"))


def test_ga_fitness_on_measurement_models():
    """Noise-normalized mean absolute error per channel (hand computation); a constant
    gyro offset costs nothing; a diverged row scores inf."""
    t = np.arange(0, 2, 0.1)
    rng = np.random.default_rng(3)
    run = _run(t, {"depth": 1.0 + 0.01 * np.sin(t), "p": rng.normal(0, 1e-3, t.size),
                   "q": rng.normal(0, 1e-3, t.size), "r": rng.normal(0, 1e-3, t.size)})
    m = measurements_for(run, None, noise={"depth": 0.01, "rates": 0.002}, weights={"q": 0, "r": 0})
    y = np.zeros((3, t.size, 13))
    y[..., 3] = 1.0
    y[:, :, 2] = 1.0 + 0.01 * np.sin(t)
    y[1, :, 2] += 0.02  # depth 2 sigma off
    y[1, :, 10] = run.velocity[:, 3] - 0.05  # a gyro offset of 0.05 rad/s: a bias, not an error
    y[2, 5:, 2] = np.nan  # diverged
    y[0, :, 10] = run.velocity[:, 3]
    f = abs_error_fitness(m, m.predict(y))
    assert f[0] == pytest.approx(0.0, abs=1e-9)
    assert f[1] == pytest.approx(2.0, rel=1e-9)
    assert np.isinf(f[2])
    assert abs_error_fitness(m, m.predict(y), gyro_bias=False)[1] == pytest.approx(2.0 + 0.05 / 0.002, rel=1e-6)


def test_joint_fit_resumes_identically(tmp_path):
    """An interrupted fit continued from its checkpoint state gives the uninterrupted result."""
    d = make_dataset(tmp_path / "d", truth={"K_pdot": 0.2, "N_rr": -0.5}, seed=7, n_train=2, n_val=1,
                     duration=6.0, dofs=("roll", "yaw"))
    ds = read_dataset(d)
    veh = uvsim.load_vehicle(ds.vehicle_file)
    runs = ds.train
    meas = [measurements_for(r, veh, attitude_lag=0.1) for r in runs]
    space = make_space(veh.parameters(), ["K_pdot", "N_rr", "K_p"])
    ref = fit(veh, runs, space, meas=meas, horizons=(1.0, 3.0), max_iter=6)

    class Store:
        def __init__(self, stop_after=None):
            self.state, self.saves, self.stop_after = None, 0, stop_after

        def load(self):
            return self.state

        def save(self, state, progress=""):
            self.state = state
            self.saves += 1
            if self.saves == self.stop_after:
                raise KeyboardInterrupt

    for stop in (2, 5, 100):  # inside stage 1, inside stage 2, after everything
        store = Store(stop)
        if stop < 100:
            with pytest.raises(KeyboardInterrupt):
                fit(veh, runs, space, meas=meas, horizons=(1.0, 3.0), max_iter=6, checkpoint=store)
        else:
            fit(veh, runs, space, meas=meas, horizons=(1.0, 3.0), max_iter=6, checkpoint=store)
        store.stop_after = None
        again = fit(veh, runs, space, meas=meas, horizons=(1.0, 3.0), max_iter=6, checkpoint=store)
        assert again.values == ref.values and again.cost == ref.cost, stop
        assert [s["iterations"] for s in again.stages] == [s["iterations"] for s in ref.stages]
        assert again.std == ref.std


def test_windowed_problem_restarts_the_lag_at_its_windows(tmp_path):
    d = make_dataset(tmp_path / "d", truth={}, seed=2, n_train=1, n_val=0, duration=5.0, dofs=("roll",))
    ds = read_dataset(d)
    veh = uvsim.load_vehicle(ds.vehicle_file)
    m = measurements_for(ds.runs[0], veh, attitude_lag=0.1)
    prob = WindowedProblem(veh, ds.runs, [m], make_space(veh.parameters(), ["K_p"]), 2.0)
    assert list(prob.meas[0].restart_rows) == [s for s, _ in prob.lay.bounds[0]]
    assert m.restart_rows is None  # the caller's model is not changed
