"""Battery-aware thrust: the T200 voltage family, the ``voltage`` log column and its
path through simulate / simulate_batch / RunBatch (issue 11 item 3)."""
from __future__ import annotations

import csv

import numpy as np
import pandas as pd
import pytest

from uvsim.calibration.batching import prepare_runs, simulate_rows
from uvsim.errors import LogFormatError, SimulationError, VehicleError
from uvsim.logs import Run
from uvsim.simulate import simulate, simulate_batch, simulate_run
from uvsim.thrusters import KGF_TO_N, load_thrust_curve
from uvsim.vehicle import load_vehicle, vehicle_from_dict
from uvsim.voltage_curves import FAMILIES

FAMILY = {"voltage_table": "t200", "nominal_voltage": 16.0}


def _sheet(volts: int):
    """A shipped sheet read with the csv module only (independent of uvsim): pwm, thrust N."""
    with open(FAMILIES["t200"] / f"t200_{volts}v.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return (np.array([float(r["pwm_us"]) for r in rows]),
            np.array([float(r["thrust_kgf"]) * KGF_TO_N for r in rows]))


@pytest.fixture(scope="module")
def family():
    return load_thrust_curve(FAMILY)


def _vehicle_with_curve(curve):
    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"] = dict(d["thrusters"], curve=curve)
    return vehicle_from_dict(d, source="test")


# ------------------------------------------------------------------------ the curve
@pytest.mark.parametrize("volts", [10, 12, 14, 16, 18, 20])
def test_family_reproduces_each_sheet_at_its_voltage(family, volts):
    pwm, thr = _sheet(volts)
    got = family.thrust(pwm, voltage=np.full(pwm.shape, float(volts)))
    np.testing.assert_allclose(got, thr, rtol=0, atol=1e-12)


def test_family_is_linear_in_voltage_and_pwm_between_points(family, rng):
    p14, t14 = _sheet(14)
    _, t16 = _sheet(16)
    pwm = rng.uniform(1100, 1900, 500)
    v = rng.uniform(14, 16, 500)
    w = (v - 14) / 2
    expect = (1 - w) * np.interp(pwm, p14, t14) + w * np.interp(pwm, p14, t16)
    np.testing.assert_allclose(family.thrust(pwm, voltage=v), expect, atol=1e-9)


def test_sagging_voltage_lowers_thrust_and_nominal_is_default(family):
    pwm = np.array([1300.0, 1700.0, 1900.0])
    hi, lo = family.thrust(pwm, voltage=16.0), family.thrust(pwm, voltage=12.0)
    assert np.all(np.abs(lo) < np.abs(hi))
    assert lo[2] == pytest.approx(_sheet(12)[1][-1])  # 36.4 N at 1900 us and 12 V
    np.testing.assert_array_equal(family.thrust(pwm), hi)
    np.testing.assert_array_equal(family.thrust(pwm, voltage=np.array([np.nan, 16.0, np.nan])), hi)


@pytest.mark.parametrize("bad", [9.99, 20.01, np.inf])
def test_voltage_outside_the_measured_range_is_an_error(family, bad):
    with pytest.raises(SimulationError, match="supply voltage .* outside the valid range"):
        family.thrust(np.array([1600.0]), voltage=np.array([bad]))


def test_family_spec_errors_name_the_field():
    with pytest.raises(VehicleError, match="voltage_table: unknown"):
        load_thrust_curve({"voltage_table": "t300"}, field="thrusters.curve")
    with pytest.raises(VehicleError, match="nominal_voltage 25 V is outside"):
        load_thrust_curve({"voltage_table": "t200", "nominal_voltage": 25})
    with pytest.raises(VehicleError, match="unknown key"):
        load_thrust_curve({"voltage_table": "t200", "nominal_volts": 15})


def test_inverse_at_a_monotone_voltage_round_trips(family):
    thr = np.array([-30.0, -5.0, 0.0, 5.0, 45.0])
    np.testing.assert_allclose(family.thrust(family.pwm(thr, voltage=20.0), voltage=20.0), thr, atol=1e-9)


# ----------------------------------------------------------------- through the model
def _surge_inputs(n=120, dt=0.05, pwm=1750.0):
    t = np.arange(n) * dt
    u = np.full((n, 8), 1500.0)
    u[:, :4] = pwm
    u[n // 2:, 4:] = 1650.0
    return t, u


def test_simulation_at_a_constant_voltage_equals_the_fixed_curve_of_that_sheet():
    """The 20 V sheet is monotone, so it is also a valid fixed table: the voltage-aware
    vehicle fed 20 V must move exactly like a vehicle whose curve is that sheet."""
    p20, t20 = _sheet(20)
    fixed = _vehicle_with_curve({"pwm": p20.tolist(), "thrust": t20.tolist()})
    aware = _vehicle_with_curve(FAMILY)
    t, u = _surge_inputs()
    a = simulate(fixed, t, u, input_kind="pwm").y
    b = simulate(aware, t, u, input_kind="pwm", voltage=np.full(t.size, 20.0)).y
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
    c = simulate(aware, t, u, input_kind="pwm").y  # nominal 16 V: slower
    assert c[-1, 0] < 0.9 * a[-1, 0]


def test_voltage_is_held_over_each_interval_like_the_inputs():
    aware = _vehicle_with_curve(FAMILY)
    t, u = _surge_inputs(n=60)
    u[:, 4:] = 1500.0  # horizontal thrusters only: pure surge
    v = np.where(np.arange(t.size) < 30, 16.0, 11.0)
    full = simulate(aware, t, u, input_kind="pwm", voltage=v).y
    first = simulate(aware, t[:31], u[:31], input_kind="pwm", voltage=v[:31]).y
    # the first 30 intervals use 16 V only: the voltage of row 30 acts from t[30] on
    np.testing.assert_array_equal(full[:31], first)
    nominal = simulate(aware, t, u, input_kind="pwm").y
    np.testing.assert_array_equal(full[:31], nominal[:31])
    # from the same state at row 30, one interval at 11 V gains less surge speed than at 16 V
    assert full[31, 7] - full[30, 7] < 0.7 * (nominal[31, 7] - nominal[30, 7])


def test_fixed_curve_vehicle_does_not_use_voltage_and_stays_bit_identical():
    veh = load_vehicle("bluerov2_heavy")
    t, u = _surge_inputs()
    a = simulate(veh, t, u, input_kind="pwm").y
    b = simulate(veh, t, u, input_kind="pwm", voltage=np.linspace(16.8, 12.0, t.size)).y
    np.testing.assert_array_equal(a, b)
    assert not veh.actuators.voltage_dependent
    assert _vehicle_with_curve(FAMILY).actuators.voltage_dependent


def test_simulate_batch_rows_get_their_own_voltage():
    aware = _vehicle_with_curve(FAMILY)
    t, u = _surge_inputs(n=40)
    V = np.stack([np.full(t.size, 12.0), np.full(t.size, 18.0)])
    batch = simulate_batch(aware, t, np.stack([u, u]), input_kind="pwm", voltage=V).y
    for i in range(2):
        single = simulate(aware, t, u, input_kind="pwm", voltage=V[i]).y
        np.testing.assert_allclose(batch[i], single, rtol=1e-12, atol=1e-14)


def test_bad_voltage_arrays_are_rejected():
    aware = _vehicle_with_curve(FAMILY)
    t, u = _surge_inputs(n=10)
    with pytest.raises(SimulationError, match="voltage: expected shape"):
        simulate(aware, t, u, input_kind="pwm", voltage=np.full(3, 16.0))
    with pytest.raises(SimulationError, match="not a positive finite"):
        simulate(aware, t, u, input_kind="pwm", voltage=np.full(t.size, -1.0))


# --------------------------------------------------------------- log column and batches
def _run(name, voltage=None, n=50):
    t, u = _surge_inputs(n=n)
    df = pd.DataFrame(u, columns=[f"pwm_{i + 1}" for i in range(8)])
    df.insert(0, "t", t)
    df["z"] = 0.0
    if voltage is not None:
        df["voltage"] = voltage
    return Run(name=name, path=None, data=df)


def test_voltage_column_is_held_between_samples_and_validated():
    v = np.full(50, np.nan)
    v[0], v[20] = 16.2, 14.0
    run = _run("r", v)
    held = run.voltage
    assert np.all(held[:20] == 16.2) and np.all(held[20:] == 14.0)
    assert _run("plain").voltage is None
    v0 = v.copy()
    v0[0] = np.nan
    with pytest.raises(LogFormatError, match="'voltage', row 0 is empty"):
        _run("bad", v0)
    v1 = v.copy()
    v1[20] = -3.0
    with pytest.raises(LogFormatError, match="row 20: -3.0 V is not a positive"):
        _run("bad", v1)


def test_simulate_run_and_run_batch_carry_the_voltage():
    aware = _vehicle_with_curve(FAMILY)
    sag = np.linspace(16.5, 12.5, 50)
    runs = [_run("sag", sag), _run("none", n=40)]
    batch = prepare_runs(runs)
    assert batch.voltage.shape == (2, 50)
    assert np.all(np.isnan(batch.voltage[1]))
    y = simulate_rows(aware, batch, np.arange(2))
    for i, run in enumerate(runs):
        ref = simulate_run(aware, run, initial_window_s=0.5).y
        n = len(run.t)
        np.testing.assert_allclose(y[i, :n, :13], ref[:, :13], rtol=1e-9, atol=1e-12)
    assert batch.subset([0]).voltage.shape == (1, 50)
