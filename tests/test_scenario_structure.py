"""Issue 21's structural overrides of the scenario generator (uvsim.scenarios): thruster
position errors, time-stamp jitter, sensor latency and pilot inputs.  Each is off by default
(every existing spec is unchanged), changes what it should and nothing else, is recorded in
the spec, and the calibration benchmark draws them without moving its earlier draws."""
from __future__ import annotations

import hashlib
import json

import numpy as np
import pandas as pd
import pytest
import yaml

from uvsim.benchmarks.calibration_structural import scenario
from uvsim.logs import read_dataset
from uvsim.scenarios import OVERRIDES, ScenarioError, ScenarioSpec, generate, load_truth, sample_scenario
from uvsim.scenarios.generate import simulate_spec, vehicles
from uvsim.scenarios.inputs import THRUST_MARGIN, force_profile, thrust_utilization
from uvsim.scenarios.vehicle_data import load_vehicle_data

NEW = ("thruster_position_error", "time_jitter", "sensor_latency", "pilot_inputs")
SMALL = dict(n_runs=1, n_validation=1, duration=4, rate_hz=100.0)


def _hash(spec) -> str:
    return hashlib.sha256(json.dumps(spec.to_dict(), sort_keys=True).encode()).hexdigest()[:16]


def _run(d, split="val"):
    """The first CSV of a dataset whose name starts with ``split``."""
    return pd.read_csv(sorted(d.glob(f"{split}_*.csv"))[0])


def _diff_keys(a: dict, b: dict, prefix="") -> set:
    """Dotted paths at which two nested dicts differ."""
    out = set()
    for k in set(a) | set(b):
        p = f"{prefix}{k}"
        if k not in a or k not in b:
            out.add(p)
        elif isinstance(a[k], dict) and isinstance(b[k], dict):
            out |= _diff_keys(a[k], b[k], p + ".")
        elif a[k] != b[k]:
            out.add(p)
    return out


# ----------------------------------------------------------------------------- defaults unchanged
#: sha256 of the spec dicts, computed before the structural overrides were added.
PINNED = {("realsensor", 0): "905710d629f57bbd", ("realsensor", 1): "c2de6e69498b473e",
          ("realsensor", 7): "898c0a4967145020", ("diagnose", 0): "dbc20968f8e96a68",
          ("issue10_timing", 0): "2fe731d79c3ebada"}


def test_default_specs_are_unchanged():
    for (profile, seed), h in PINNED.items():
        assert _hash(sample_scenario(seed, profile=profile)) == h, (profile, seed)
    s = sample_scenario(0, profile="realsensor")
    assert s.rate_hz == 200.0 and len(s.runs) == 11 and s.runs[0]["pos0"] == [-0.285638, -0.438383, 1.069731]
    assert s.runs[0]["yaw0"] == 2.040764 and s.sensors["imu"]["gyro_sigma"] == 0.003297
    assert "clock" not in s.sensors and "thruster_offsets" not in s.vehicle
    assert all(r["shape"]["shape"] == "telegraph" for r in s.runs)
    # the overrides at their "off" values change nothing
    off = dict(thruster_position_error=0, time_jitter=0.0, sensor_latency=0.0, pilot_inputs=False)
    assert _hash(sample_scenario(0, profile="realsensor", **off)) == PINNED[("realsensor", 0)]


def test_benchmark_keeps_its_earlier_draws_and_adds_the_new_classes():
    # perturbation, n_effects, curve_voltage of seeds 0-7 as drawn before the new classes
    before = {0: (0.282, 0, 14), 1: (0.362, 1, None), 2: (0.332, 0, None), 3: (0.36, 0, 14), 4: (0.319, 0, None),
              5: (0.29, 0, None), 6: (0.294, 1, None), 7: (0.204, 0, 14)}
    for seed, (p, n, v) in before.items():
        d = scenario(seed)
        assert (d["perturbation"], d["n_effects"], d.get("curve_voltage")) == (p, n, v)
    # the benchmark's spec without the new keys is the one it drew before (seed 0)
    old = {k: v for k, v in scenario(0).items() if k not in NEW}
    assert _hash(sample_scenario(0, profile="realsensor", **old)) == "c724795b99aa4c28"
    draws = [scenario(s) for s in range(300)]
    for key, lo, hi in (("thruster_position_error", 0.01, 0.03), ("time_jitter", 0.001, 0.005),
                        ("sensor_latency", 0.01, 0.05)):
        vals = [d[key] for d in draws if key in d]
        assert 0.25 < len(vals) / 300 < 0.42 and all(lo <= x <= hi for x in vals), key
    assert 0.25 < sum(d.get("pilot_inputs", False) for d in draws) / 300 < 0.42
    for s, d in enumerate(draws[:60]):          # every key is an override sample_scenario takes
        assert set(d) <= set(OVERRIDES)
        sample_scenario(s, profile="realsensor", **d)


# ----------------------------------------------------------------------------- thruster positions
def test_thruster_position_error_moves_only_the_truths_thrusters(tmp_path):
    base = sample_scenario(3, profile="realsensor", **SMALL)
    spec = sample_scenario(3, profile="realsensor", thruster_position_error=0.02, **SMALL)
    assert _diff_keys(base.to_dict(), spec.to_dict()) == {"vehicle.thruster_position_error",
                                                          "vehicle.thruster_offsets", "description"}
    off = np.array(spec.vehicle["thruster_offsets"])
    nominal = load_vehicle_data()
    assert off.shape == (nominal.n_thrusters, 3) and np.abs(off).max() <= 0.02 and np.abs(off).max() > 0.01
    _, truth = vehicles(spec)
    assert np.allclose(truth.thruster_positions, nominal.thruster_positions + off)
    assert not np.allclose(truth.allocation(), nominal.allocation())           # moment arms moved
    assert np.allclose(truth.allocation()[:3], nominal.allocation()[:3])       # directions kept

    a, b = generate(base, tmp_path / "a"), generate(spec, tmp_path / "b")
    units = lambda doc: np.array([u["position"] for u in doc["thrusters"]["units"]])  # noqa: E731
    model = yaml.safe_load((b / "myrov.yaml").read_text())
    assert np.array_equal(units(model), nominal.thruster_positions)            # the model keeps the file's
    assert (a / "myrov.yaml").read_text() == (b / "myrov.yaml").read_text()
    rec = load_truth(b)
    assert np.allclose(units(rec["vehicle"]), nominal.thruster_positions + off)
    assert rec["structure"]["thruster_positions"]["offsets_m"] == spec.vehicle["thruster_offsets"]
    ra, rb = _run(a), _run(b)
    pwm = [c for c in ra.columns if c.startswith("pwm_")]
    assert ra[pwm].equals(rb[pwm]) and ra["t"].equals(rb["t"])                 # same commands (file's geometry)
    assert not np.allclose(ra[["p", "q", "r"]], rb[["p", "q", "r"]])             # another response
    # a thruster matter: PWM by default where a profile would draw force inputs
    assert sample_scenario(0, profile="issue10_timing", thruster_position_error=0.02).input_kind == "pwm"
    assert sample_scenario(0, profile="diagnose", thruster_position_error=0.02).input_kind == "pwm"


# ----------------------------------------------------------------------------- time jitter
def test_time_jitter_stamps_rows_and_the_log_reader_takes_them(tmp_path):
    sigma = 0.002
    base = sample_scenario(4, profile="realsensor", **SMALL)
    spec = sample_scenario(4, profile="realsensor", time_jitter=sigma, **SMALL)
    assert _diff_keys(base.to_dict(), spec.to_dict()) == {"sensors.clock", "description"}
    a, b = generate(base, tmp_path / "a"), generate(spec, tmp_path / "b")
    for name in ("run", "val"):
        ra, rb = _run(a, name), _run(b, name)
        assert ra.drop(columns="t").equals(rb.drop(columns="t"))                # inputs and readings unchanged
        t, grid = rb["t"].to_numpy(), ra["t"].to_numpy()
        assert np.all(np.diff(t) > 0)
        e = t - grid
        assert np.abs(e).max() < 5 * sigma and 0.7 * sigma < e.std() < 1.3 * sigma
    ds = read_dataset(b)                                                        # uvsim's log reader
    run = ds.runs[0]
    assert np.allclose(run.t, _run(b, "run")["t"]) and not np.allclose(np.diff(run.t), 0.01)
    assert load_truth(b)["structure"]["time_jitter_s"] == sigma


# ----------------------------------------------------------------------------- latency
def test_latency_delays_imu_attitude_and_depth_by_the_latency(tmp_path):
    lat, m = 0.1, 10                  # 10 samples at 100 Hz, one sample of the 10 Hz depth sensor
    over = dict(SMALL, depth_mode="native")
    base = sample_scenario(6, profile="realsensor", **over)
    spec = sample_scenario(6, profile="realsensor", sensor_latency=lat, **over)
    assert _diff_keys(base.to_dict(), spec.to_dict()) == {"sensors.imu.latency", "sensors.euler.latency",
                                                          "sensors.depth.latency", "description"}
    a, b = generate(base, tmp_path / "a"), generate(spec, tmp_path / "b")
    ra, rb = _run(a), _run(b)
    pwm = [c for c in ra.columns if c.startswith("pwm_")]
    assert ra[pwm + ["t"]].equals(rb[pwm + ["t"]])                              # inputs at their own times
    gs = spec.sensors["imu"]["gyro_sigma"]
    for cols, sigma in ((["p", "q", "r"], gs), (["roll", "pitch"], spec.sensors["euler"]["sigma"])):
        x, y = rb[cols].to_numpy(), ra[cols].to_numpy()
        # the same noise realization at each row: late[k] - on_time[k - m] is the noise n_k - n_(k-m)
        shifted = x[m:] - y[:-m]
        assert 0.7 < shifted.std() / (np.sqrt(2) * sigma) < 1.3 and np.abs(shifted).max() < 6 * np.sqrt(2) * sigma
    x, y = rb[["p", "q", "r"]].to_numpy(), ra[["p", "q", "r"]].to_numpy()
    assert np.abs(x[m:] - y[m:]).max() > 5 * np.abs(x[m:] - y[:-m]).max()     # unshifted: another signal
    # before the run starts the delayed sensors see the vehicle at rest: the gyro reads its bias
    assert np.abs(rb[["p", "q", "r"]].to_numpy()[:m] - spec.runs[-1]["gyro_bias"]).max() < 5 * gs
    dz = rb["depth"].to_numpy()[::m], ra["depth"].to_numpy()[::m]              # the sensor's own samples
    assert np.abs(dz[0][1:] - dz[1][:-1]).max() < 6 * np.sqrt(2) * spec.sensors["depth"]["sigma"]


def test_a_latency_between_samples_is_the_truth_at_that_time():
    # at 100 Hz a latency of 15 ms lies between the samples; the 200 Hz run of the same seed has
    # t - 15 ms on its grid and the same inputs (telegraph switches lie on a 10 ms grid)
    small = dict(n_runs=1, n_validation=1, duration=3)
    a = sample_scenario(5, profile="realsensor", rate_hz=100.0, sensor_latency=0.015, **small)
    b = sample_scenario(5, profile="realsensor", rate_hz=200.0, **small)
    assert a.runs[0]["shape"] == b.runs[0]["shape"] and a.effects == b.effects
    ra, rb = simulate_spec(a, with_snr=False), simulate_spec(b, with_snr=False)
    d, k = ra["delayed"][0.015], np.arange(2, 301)
    for key in ("pos", "quat", "nu", "nu_dot"):
        assert np.abs(d[key][:, k] - rb["sim"][key][:, 2 * k - 3]).max() < 1e-9, key
        assert np.allclose(d[key][:, :2], 0.0) if key == "nu_dot" else np.allclose(d[key][:, :2],
                                                                                   ra["sim"][key][:, :1])
    # and the log-time truth is what it is without a latency
    rc = simulate_spec(sample_scenario(5, profile="realsensor", rate_hz=100.0, **small), with_snr=False)
    assert np.abs(ra["sim"]["pos"] - rc["sim"]["pos"]).max() < 1e-8


# ----------------------------------------------------------------------------- pilot inputs
def test_pilot_inputs_are_smooth_multi_dof_and_within_range():
    over = dict(n_runs=2, n_validation=1, duration=12, rate_hz=100.0)
    base = sample_scenario(2, profile="realsensor", **over)
    spec = sample_scenario(2, profile="realsensor", pilot_inputs=True, **over)
    diff = _diff_keys(base.to_dict(), spec.to_dict())
    assert diff == {"runs", "description"}
    for rb, rp in zip(base.runs, spec.runs):                                    # only the shapes differ
        keep = ("dof", "split", "weight", "duration", "pos0", "yaw0", "gyro_bias", "acc_bias")
        assert {k: rb[k] for k in keep} == {k: rp[k] for k in keep}
        assert rp["shape"]["shape"] == "pilot" and rp["name"].endswith("_pilot_mixed")
    veh = load_vehicle_data()
    table, A = veh.curve, veh.allocation()
    dead = np.flatnonzero(table.thrust_n == 0.0)
    lo, hi = table.pwm_us[dead[0]], table.pwm_us[dead[-1]]
    rp, rt = simulate_spec(spec, with_snr=False), simulate_spec(base, with_snr=False)
    for i, r in enumerate(spec.runs):
        n = rp["n_samples"][i]
        t = rp["t"][:n]
        tau = force_profile(r["shape"], t)
        assert thrust_utilization(tau, A, table, rp["trim"]) <= THRUST_MARGIN + 1e-9
        assert (np.abs(tau) > 1e-9).sum(axis=1).max() >= 2                       # several DOFs at once
        u, ut = rp["logged"][i][:n], rt["logged"][i][:n]
        assert u.min() >= table.pwm_range[0] and u.max() <= table.pwm_range[1]
        step, same = np.abs(np.diff(u, axis=0)), ((u[:-1] >= hi) & (u[1:] >= hi)) | ((u[:-1] <= lo) & (u[1:] <= lo))
        assert step[same].max() <= 25                                            # us per 10 ms beside the dead band
        assert step.max() <= (hi - lo) + 15                                      # a crossing jumps the dead band
        assert np.abs(np.diff(ut, axis=0)).max() > 2 * step.max()                # telegraph jumps far more


# ----------------------------------------------------------------------------- spec round trip
def test_truth_yaml_regenerates_the_same_data(tmp_path):
    spec = sample_scenario(1, profile="realsensor", thruster_position_error=0.02, time_jitter=0.003,
                           sensor_latency=0.02, pilot_inputs=True, n_runs=1, n_validation=1, duration=3,
                           rate_hz=100.0)
    a = generate(spec, tmp_path / "a")
    b = generate(load_truth(a)["spec"], tmp_path / "b")
    for f in sorted(p.name for p in a.iterdir()):
        assert (a / f).read_bytes() == (b / f).read_bytes(), f


# ----------------------------------------------------------------------------- bad values
@pytest.mark.parametrize("over, match", [
    ({"thruster_position_error": -0.01}, "thruster_position_error = -0.01; expected a number in .0, 0.1. m"),
    ({"thruster_position_error": 0.5}, "thruster_position_error"),
    ({"thruster_position_error": "2cm"}, "thruster_position_error"),
    ({"thruster_position_error": True}, "thruster_position_error"),
    ({"thruster_position_error": 0.02, "input_kind": "force"}, "thruster_position_error with input_kind 'force'"),
    ({"time_jitter": -0.001}, "time_jitter = -0.001; expected a number in .0, 0.02. s"),
    ({"time_jitter": 0.1}, "time_jitter"),
    ({"time_jitter": None}, "time_jitter"),
    ({"sensor_latency": 2.0}, "sensor_latency = 2.0; expected a number in .0, 1. s"),
    ({"sensor_latency": float("nan")}, "sensor_latency"),
    ({"pilot_inputs": "yes"}, "pilot_inputs = 'yes'; expected True or False"),
    ({"pilot_inputs": 1}, "pilot_inputs"),
])
def test_bad_structural_overrides_are_named(over, match):
    with pytest.raises(ScenarioError, match=match):
        sample_scenario(0, profile="realsensor", **over)


def test_bad_structural_spec_fields_are_named(tmp_path):
    with pytest.raises(ScenarioError, match="pilot_inputs with profile 'diagnose'"):
        sample_scenario(0, profile="diagnose", pilot_inputs=True)
    d = sample_scenario(0, profile="realsensor", sensor_latency=0.02, **SMALL).to_dict()
    d["sensors"]["imu"]["latency"] = -1
    with pytest.raises(ScenarioError, match=r"sensors.imu.latency = -1; expected seconds"):
        ScenarioSpec.from_dict(d)
    d = sample_scenario(0, profile="realsensor", time_jitter=0.002, **SMALL).to_dict()
    d["sensors"]["clock"] = {"jitter": 0}
    with pytest.raises(ScenarioError, match="sensors.clock.jitter"):
        ScenarioSpec.from_dict(d)
    d = sample_scenario(0, profile="realsensor", thruster_position_error=0.02, **SMALL).to_dict()
    d["vehicle"]["thruster_offsets"] = [[0.01, 0.0, 0.0]]
    with pytest.raises(ScenarioError, match="vehicle.thruster_offsets"):
        generate(d, tmp_path / "x")
