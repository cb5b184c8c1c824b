"""Noise from the sensor, not from smoothness (issue 48, item 4): a channel whose error an
estimator or rounding hides from the fourth differences gets a floor (the rounding's
``q / sqrt(12)``, an attitude filter's :data:`~uvsim.estimation.noise.FILTER_FLOOR`), a level
declared in the vehicle file (``sensors.noise``) replaces the estimate, and that one level is what
the fits, the diagnosis' costs and shares, report.json and the plots divide by."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from uvsim.calibration.fitness import abs_error_fitness
from uvsim.diagnosis.residual import concentration
from uvsim.estimation.noise import (FILTER_FLOOR, filter_output, noise_sigma, quantisation_sigma, quantum,
                                    sample_kind)
from uvsim.fitting import verdict
from uvsim.fitting.evaluate import open_loop
from uvsim.kinematics import quat_to_euler, wrap
from uvsim.logs import Run
from uvsim.measurements import measurements_for
from uvsim.metrics import channel_series
from uvsim.scenarios import field
from uvsim.vehicle import load_vehicle

DEG = np.pi / 180.0


# ----------------------------------------------------------------------------- the field logs' filter
@pytest.fixture(scope="module")
def field_case():
    """Three 20 s runs of the field-log generator (clean case, 10 Hz): the autopilot's
    complementary filter logs roll, pitch and yaw (yaw to 0.01 deg) beside a gyro; the truth's
    attitude is kept to measure the filter's real error."""
    spec = field.sample_field(0, "clean", duration=20.0, n_train=2, n_validation=1, log_hz=10.0)
    sim = field.simulate_field(spec)
    tables = field.log_tables(spec, sim)
    runs = [Run(r["name"], None, tab, dof="mixed", split=r["split"]) for r, tab in zip(spec["runs"], tables)]
    step = int(round(spec["control_hz"] / spec["log_hz"]))
    # the filter's error against the truth at the logged rows: what a perfect model would leave
    truth_err = [np.sqrt(np.mean(wrap(sim["rpy"][i] - quat_to_euler(sim["quat"][i]))[::step] ** 2, axis=0))
                 for i in range(len(runs))]
    return runs, truth_err


def test_the_filters_angles_get_a_noise_within_a_factor_of_their_real_error(field_case):
    runs, truth_err = field_case
    for run, err in zip(runs, truth_err):
        m = measurements_for(run)
        d = m.describe()
        for j, c in enumerate(("roll", "pitch", "yaw")):
            # the estimate sees only the integrated gyro noise and the rounding: ~1e-4 rad, 50-1000x too small
            assert d[c]["estimate"] < err[j] / 30, (run.name, c, d[c]["estimate"], err[j])
            assert d[c]["source"] == "floor" and d[c]["sigma"] == FILTER_FLOOR[c]
            assert err[j] / 10 < d[c]["sigma"] < 10 * err[j], (run.name, c, d[c]["sigma"], err[j])
        # the raw sensors keep their estimate: the gyro, the accelerometer, the pressure sensor, the DVL
        assert all(d[c]["source"] == "estimated" for c in d if c not in ("roll", "pitch", "yaw"))
        # the yaw is rounded to 0.01 deg: the resolution is read from the data, and its repeats and
        # equal steps are not taken for a held or interpolated sensor (all rows are measurements)
        assert d["yaw"]["quantum"] == pytest.approx(0.01 * DEG, rel=1e-6)
        assert d["yaw"]["sampling"] == "native" and d["yaw"]["samples_used"] == run.t.size
        assert any("yaw: noise 0.0175 rad, the floor of an attitude filter's output" in n for n in m.notes)


def test_yaw_no_longer_carries_the_cost(field_case):
    """The issue's observation: with the estimated levels 93-100 % of the given model's open-loop
    cost is yaw; with the filter's floor the yaw is one channel among others."""
    runs, _ = field_case
    veh = load_vehicle("bluerov2_heavy")
    meas = [measurements_for(r, veh) for r in runs]
    res = open_loop(veh, runs, meas=meas)
    raw = [measurements_for(r, veh, noise={c: m.describe()[c]["estimate"] for c in ("roll", "pitch", "yaw")})
           for r, m in zip(runs, meas)]  # the levels as they were estimated before the floor
    share = {x["name"]: x["share"] for x in concentration(meas, res)["by_channel"]}
    share_raw = {x["name"]: x["share"] for x in concentration(raw, res)["by_channel"]}
    assert share_raw["yaw"] > 0.9
    assert share["yaw"] < 0.5, share


# ----------------------------------------------------------------------------- the gate and the floors
def _run(t, cols: dict) -> Run:
    d = pd.DataFrame({"t": t, **cols})
    for i in range(1, 9):
        d[f"pwm_{i}"] = 1500.0
    return Run("r", None, d)


def _imu_run(att_sigma: float, seed: int = 1, rate_hz: float = 10.0) -> Run:
    """60 s of a turning vehicle: Euler angles with white noise ``att_sigma`` beside a gyro of
    0.003 rad/s (an independent attitude sensor when ``att_sigma`` is well above 0.003 / rate_hz)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 60.0, 1.0 / rate_hz)
    ang = np.stack([0.05 * np.sin(0.7 * t), 0.04 * np.cos(0.5 * t), 0.8 * np.sin(0.1 * t)], 1)
    rates = np.gradient(ang, t, axis=0)
    cols = {c: ang[:, j] + att_sigma * rng.standard_normal(t.size) for j, c in enumerate(("roll", "pitch", "yaw"))}
    cols.update({c: rates[:, j] + 0.003 * rng.standard_normal(t.size) for j, c in enumerate("pqr")})
    return _run(t, cols)


def test_an_attitude_with_noise_of_its_own_keeps_its_estimate():
    """Angles whose noise (2 mrad) is far above the gyro's over a sample (0.3 mrad at 10 Hz) are a
    measurement, not a filter's output: estimated, below the floor and not raised to it."""
    d = measurements_for(_imu_run(0.002)).describe()
    for c in ("roll", "pitch", "yaw"):
        assert d[c]["source"] == "estimated" and d[c]["sigma"] == pytest.approx(0.002, rel=0.2)
        assert d[c]["sigma"] < FILTER_FLOOR[c]
    # the same angles as a gyro integrated by a filter: no noise of their own
    d = measurements_for(_imu_run(1e-5)).describe()
    assert all(d[c]["source"] == "floor" and d[c]["sigma"] == FILTER_FLOOR[c] for c in ("roll", "pitch", "yaw"))
    # without a gyro there is no telling: the estimate stands
    no_gyro = _imu_run(1e-5)
    no_gyro.data = no_gyro.data.drop(columns=["p", "q", "r"])
    assert measurements_for(no_gyro).describe()["roll"]["source"] == "estimated"
    assert filter_output(1e-4, 0.003, 0.1) and not filter_output(0.002, 0.003, 0.1)


def test_rounding_is_a_floor_and_does_not_look_like_a_held_sensor():
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 60.0, 0.1)
    smooth = 2.0 + 0.05 * np.sin(0.05 * t)                   # a slow depth: under 1 mm per sample
    q = 0.001
    rounded = np.round(smooth / q) * q                       # logged to 1 mm, no noise to see
    assert quantum(rounded) == pytest.approx(q) and quantum(smooth) == 0.0
    assert quantisation_sigma(q) == pytest.approx(q / np.sqrt(12))
    lv = measurements_for(_run(t, {"depth": rounded})).groups["depth"].noise[0]
    assert lv.source == "floor" and lv.sigma == pytest.approx(q / np.sqrt(12)) and lv.estimate < lv.sigma
    # a noisy sensor logged to the same resolution shows its own noise: estimated, above the rounding
    noisy = np.round((smooth + 0.004 * rng.standard_normal(t.size)) / q) * q
    lv = measurements_for(_run(t, {"depth": noisy})).groups["depth"].noise[0]
    assert lv.source == "estimated" and lv.sigma == pytest.approx(0.004, rel=0.25)
    # a filter's slow yaw (a motion and the integrated gyro noise) rounded to 0.01 deg repeats values
    # and steps by equal amounts now and then: still every row a sample
    walk = np.cumsum(1.3e-4 * rng.standard_normal(t.size))
    yaw = np.round(np.degrees(0.3 * np.sin(0.05 * t) + walk), 2) * DEG
    assert (np.diff(yaw) == 0).mean() > 0.2 or (np.abs(np.diff(yaw, 2)) < 1e-12).mean() > 0.3
    assert sample_kind(t, yaw).kind == "native"
    # a 10 Hz sensor held or interpolated on a 100 Hz log (rounded as well) is still found out
    t100 = np.arange(0.0, 60.0, 0.01)
    x10 = np.round((0.3 * np.sin(0.2 * t) + 0.004 * rng.standard_normal(t.size)) / q) * q
    held = np.repeat(x10, 10)[:t100.size]
    assert sample_kind(t100, held).kind == "held"
    assert sample_kind(t100, np.interp(t100, t, x10)).kind == "interpolated"


# ----------------------------------------------------------------------------- declared levels
def test_a_declared_level_is_the_one_every_judgement_uses(field_case):
    """``sensors.noise`` of the vehicle file replaces the estimate and the floors; the noise option
    replaces it in turn; and the one level reaches the fits' residuals, the GA's fitness, the
    diagnosis' costs and shares, report.json's ``noise`` and the plots' series."""
    runs, _ = field_case
    run = runs[0]
    base = load_vehicle("bluerov2_heavy")
    d = base.to_dict()
    d["sensors"] = {**d.get("sensors", {}), "noise": {"yaw": 0.03, "depth": 0.007, "rates": 0.004}}
    from uvsim.vehicle import vehicle_from_dict

    veh = vehicle_from_dict(d, source="declared.yaml")
    m = measurements_for(run, veh)
    desc = m.describe()
    for c, s in (("yaw", 0.03), ("depth", 0.007), ("p", 0.004), ("r", 0.004)):
        assert desc[c]["sigma"] == s and desc[c]["source"] == "declared", (c, desc[c])
    assert "sensors.noise.rates" in desc["p"]["basis"] and "sensors.noise.yaw" in desc["yaw"]["basis"]
    assert desc["roll"]["source"] == "floor"                     # not declared: the filter's floor
    assert desc["yaw"]["estimate"] < 1e-3                        # the estimate is kept for the report
    assert any("yaw: noise 0.03 rad, declared in the vehicle file" in n for n in m.notes)
    # the noise option (--noise) comes first
    assert measurements_for(run, veh, noise={"yaw": 0.05}).describe()["yaw"]["sigma"] == 0.05

    # the one level everywhere: a prediction, its residuals divided by the declared level ...
    pred = open_loop(veh, [run], meas=[m])[0]["pred"]
    e = m.residuals(pred)
    z_yaw = e["attitude"][:, 2][m.groups["attitude"].valid[:, 2]] / 0.03
    # ... the fits' residual vector (channel-major within each group, in the order of the groups)
    r = m.normalized(pred, fill=0.0)
    start = sum(int(m.used(g).sum()) for g in list(m.groups)[:list(m.groups).index("attitude")])
    start += int(m.used("attitude")[:, :2].sum())
    np.testing.assert_allclose(r[start:start + z_yaw.size], z_yaw)
    # ... the GA's fitness (yaw alone)
    only_yaw = measurements_for(run, veh, weights={g: 0.0 for g in m.groups if g != "attitude"} |
                                {"roll": 0.0, "pitch": 0.0})
    P = {g: v[None] for g, v in pred.items()}
    assert abs_error_fitness(only_yaw, P)[0] == pytest.approx(np.mean(np.abs(z_yaw)))
    # ... the diagnosis' cost and shares
    conc = concentration([m], [{"pred": pred}])
    share = {x["name"]: x["share"] for x in conc["by_channel"]}
    assert share["yaw"] * conc["total"] == pytest.approx(np.sum(z_yaw ** 2))
    # ... report.json's noise (calibration and diagnosis both embed describe()) and the plots' series
    series = channel_series(m, pred)
    assert series["yaw"]["sigma"] == desc["yaw"]["sigma"] == 0.03
    assert series["depth"]["sigma"] == desc["depth"]["sigma"] == 0.007
    # a different declaration changes the fit's weighting and the shares but nothing else: the errors
    # are the same, and the verdict between two models (calibration's and the diagnosis' guard), whose
    # score weighs each channel by its own error (uvsim.fitting.verdict), is the same
    m2 = measurements_for(run, base)
    assert m2.describe()["yaw"]["sigma"] == FILTER_FLOOR["yaw"]
    np.testing.assert_allclose(m2.residuals(pred)["attitude"], e["attitude"])
    other = veh.with_parameters({"N_r": 2.0 * veh.parameters()["N_r"]})
    pred_b = open_loop(other, [run], meas=[m])[0]["pred"]
    v1, v2 = (verdict.compare([mm], [pred], [pred_b], n_boot=200) for mm in (m, m2))
    assert v1["pooled"] == v2["pooled"] and v1["status"] == v2["status"]


def test_the_commands_print_one_note_per_floor_for_all_runs(field_case):
    """calibrate and diagnose print a floor or a declaration once, with the runs it holds for."""
    from uvsim.commands.calibration_output import note_lines

    runs, _ = field_case
    lines = note_lines([n for r in runs for n in measurements_for(r).notes])
    yaw = [ln for ln in lines if ln.startswith("note: yaw: noise 0.0175 rad, the floor of an attitude filter's")]
    assert len(yaw) == 1 and yaw[0].endswith(f"({len(runs)} runs: {', '.join(r.name for r in runs)})"), lines
    assert "declare sensors.noise.yaw in the vehicle file" in yaw[0]
