"""Thrust curves across the export: the PWM -> thrust tables written into the gz-sim SDF (for
the PWM bridge) and UUV Simulator's LinearInterp conversion, read back from the files and
compared with uvsim's curves every 1 us; battery-aware curves carry every voltage sheet to
gz-sim and are warned for UUV Simulator (no voltage input)."""
from __future__ import annotations

import re

import numpy as np
import pytest

from uvsim.export.gz_sim import gz_sdf, parse_gz_sdf
from uvsim.export.replay import replay_check
from uvsim.export.thrust_tables import curve_knots, file_thrust_check, thrust_table_check
from uvsim.export.uuv_simulator import parse_uuv_xacro, uuv_xacro
from uvsim.vehicle import load_vehicle, vehicle_from_dict


def _battery_heavy():
    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"]["curve"] = {"voltage_table": "t200", "nominal_voltage": 16.0}
    return vehicle_from_dict(d, source="heavy-battery")


@pytest.mark.parametrize("name", ["bluerov2_heavy", "bluerov2_heavy_initial", "bluerov2_vectored_standin"])
def test_tables_in_both_files_reproduce_the_curve(name):
    veh = load_vehicle(name)
    for target, text, parse in (("gz-sim", gz_sdf(veh)[0], parse_gz_sdf),
                                ("uuv-simulator", uuv_xacro(veh)[0], parse_uuv_xacro)):
        rows = file_thrust_check(veh, parse(text), target)
        assert len(rows) == len(veh.actuators.names)
        for r in rows:
            assert r["max_error_N"] < 1e-9, (target, r)
            assert r["clamp_ok"] and r.get("clamp_ok_pwm", True), (target, r)


def test_the_check_sees_a_table_that_misses_the_dead_band():
    curve = load_vehicle("bluerov2_heavy").actuators.curves[0]
    pwm, thrust = curve_knots(curve)
    keep = (pwm < curve.deadband[0] - 1) | (pwm > curve.deadband[1] + 1)   # drop the dead band's edges
    chk = thrust_table_check(curve, pwm[keep], thrust[keep])
    assert chk["max_error_N"] > 0.05


@pytest.mark.slow
def test_battery_aware_curve_goes_to_gz_sim_with_every_sheet_and_replays_under_a_sagging_battery():
    veh = _battery_heavy()
    curve = veh.actuators.curves[0]
    text, warnings = gz_sdf(veh)
    assert any("battery voltage" in w and "bridge must apply" in w for w in warnings)
    p = parse_gz_sdf(text)
    th = p["thrusters"][0]
    assert sorted(th["sheets"]) == [float(v) for v in curve.voltages]
    for v, sheet in th["sheets"].items():   # each sheet read back equals the curve at that voltage
        np.testing.assert_allclose(np.interp(th["pwm"], th["pwm"], sheet),
                                   curve.thrust(th["pwm"], np.full(th["pwm"].shape, v)), atol=1e-12)
    # the plugin's clamp keeps the strongest sheet (20 V) uncut
    assert th["max"] >= float(np.max(curve.thrust(th["pwm"], np.full(th["pwm"].shape, 20.0)))) - 1e-12
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 15.0, 0.02)
    U = np.rint(rng.uniform(1380, 1620, (8, 1)) * np.ones((1, t.size))).T
    U[t > 7.5] = 3000 - U[t > 7.5]                  # reverse every thruster halfway
    volts = np.linspace(16.4, 13.2, t.size)          # a battery sagging from 16.4 V to 13.2 V
    r = replay_check(veh, t, U, input_kind="pwm", target="gz-sim", physics_step=0.0005, voltage=volts)
    assert not r.diverged and r.position_m < 0.01 and r.attitude_rad < 0.001, r.summary()
    # a bridge that ignored the voltage (the nominal sheet throughout) would not follow uvsim
    nominal_only = re.sub(r'\s*<thrust_n voltage="[^"]*">[^<]*</thrust_n>', "", text)
    assert nominal_only != text and not parse_gz_sdf(nominal_only)["thrusters"][0]["sheets"]
    r16 = replay_check(veh, t, U, input_kind="pwm", target="gz-sim", physics_step=0.0005, text=nominal_only,
                       voltage=volts)
    assert r16.position_m > 0.05, r16.summary()


def test_uuv_simulator_is_warned_that_its_table_has_no_voltage_input():
    _, warnings = uuv_xacro(_battery_heavy())
    assert any("LinearInterp has no voltage input" in w for w in warnings)
