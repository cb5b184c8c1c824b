"""The field-log generator of issue 48 item 5 (uvsim.scenarios.field, uvsim.scenarios.autopilot):
an ArduSub-like closed loop whose logs ``uvsim diagnose`` reads as they are, written apart from
the fitting code."""
from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from generator_imports import ALLOWED, fitting_modules_loaded, uvsim_imports_outside_scenarios
from uvsim.scenarios import autopilot as ap
from uvsim.scenarios import field
from uvsim.scenarios.vehicle_data import load_vehicle_data

SMALL = dict(duration=15.0, n_train=2, n_validation=1, log_hz=10.0)


def _still(spec: dict) -> dict:
    """The same spec with every stick centred and every run in DEPTH HOLD."""
    spec = copy.deepcopy(spec)
    for r in spec["runs"]:
        r["sticks"] = {k: [[0.0, 0.0]] for k in ap.STICK_USE}
        r["mode"] = "depth_hold"
    return spec


@pytest.fixture(scope="module")
def weight_still():
    spec = _still(field.sample_field(4, "weight", **SMALL))
    return spec, field.simulate_field(spec)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    spec = field.sample_field(7, "reversed", **SMALL)
    return spec, field.generate_field(spec, tmp_path_factory.mktemp("field") / "ds")


def test_the_generator_imports_nothing_from_the_fitting_code():
    pkg = Path(field.__file__).parent
    for f in (pkg / "field.py", pkg / "autopilot.py"):
        outside = uvsim_imports_outside_scenarios(f)
        assert outside <= ALLOWED, (f.name, outside - ALLOWED)
    # (uvsim.model and uvsim.simulate are loaded by ``import uvsim`` itself; the sources above use neither)
    assert fitting_modules_loaded(
        "from uvsim.scenarios.field import generate_field, sample_field; "
        "generate_field(sample_field(1, 'dead', duration=3.0, n_train=1, n_validation=1), "
        "pathlib.Path(tempfile.mkdtemp()) / 'ds')") == []


def test_the_mixer_is_ardusubs_vectored_6dof_frame():
    # AP_Motors6DOF.cpp, setup_motors, SUB_FRAME_VECTORED_6DOF: (roll, pitch, yaw, throttle, forward, lateral)
    assert ap.MOTOR_FACTORS.tolist() == [
        [0, 0, 1, 0, -1, 1], [0, 0, -1, 0, -1, -1], [0, 0, -1, 0, 1, 1], [0, 0, 1, 0, 1, -1],
        [1, -1, 0, -1, 0, 0], [-1, -1, 0, -1, 0, 0], [1, 1, 0, -1, 0, 0], [-1, 1, 0, -1, 0, 0]]
    veh = load_vehicle_data()
    dirs = ap.motor_directions(veh.thruster_directions, veh.thruster_positions)
    assert dirs.tolist() == [-1, -1, 1, 1, 1, 1, 1, 1]   # the file orients T1, T2 for pure surge
    A = veh.allocation()
    # each pilot/controller axis, mixed alone, pushes the vehicle along that axis (thrust ~ output)
    want = {0: 3, 1: 4, 2: 5, 3: 2, 4: 0, 5: 1}            # roll->K, pitch->M, yaw->N, throttle->Z, fwd->X, lat->Y
    for axis, dof in want.items():
        cmd = np.zeros((6, 1))
        cmd[axis] = 0.3
        tau = A @ (dirs[:, None] * ap.mix(cmd[:3], cmd[3:]))
        sign = -1.0 if axis == 3 else 1.0                   # throttle up = -Z (NED)
        assert sign * tau[dof, 0] > 0
        group = slice(0, 3) if dof < 3 else slice(3, 6)        # forces against forces, moments against moments
        others = np.delete(tau[group, 0], dof % 3)
        assert np.abs(others).max() < 1e-9
    # the horizontal thrusters sit 8.5 cm below the origin: forward thrust also pitches (M = z X)
    tau = A @ (dirs[:, None] * ap.mix(np.zeros((3, 1)), np.array([[0.0], [0.3], [0.0]])))
    assert tau[4, 0] == pytest.approx(0.085 * tau[0, 0])
    assert ap.pwm(np.array([[1.0], [-1.0]]), np.array([1.0, -1.0])).ravel().tolist() == [1900.0, 1900.0]
    assert ap.mix(np.array([[5.0], [0.0], [0.0]]), np.zeros((3, 1))).max() <= 1.0   # rpy scaled into range


def test_depth_hold_keeps_the_measured_depth_while_the_open_loop_model_drifts(weight_still):
    from uvsim.scenarios.truth import simulate_truth

    spec, sim = weight_still
    d = sim["depth"][:, 100:]                                 # after the first 2 s
    assert np.ptp(d, axis=1).max() < 0.08                     # the autopilot holds it within centimetres
    # the same PWM, open loop, on the truth without the weight (the model lacks it): it rises
    nominal, veh = field.truth_vehicle(spec)
    step = 5
    t = sim["t"][::step]
    out = simulate_truth(veh, t, sim["pwm"][:, ::step], "pwm", pos0=sim["pos"][:, 0], quat0=sim["quat"][:, 0])
    drift = np.abs(out["pos"][:, -1, 2] - sim["pos"][:, -1, 2])
    assert drift.min() > 0.3, drift


def test_heading_hold_holds_the_filter_yaw_and_the_true_heading_drifts_with_the_gyro_bias(weight_still):
    spec, sim = weight_still
    from scipy.spatial.transform import Rotation

    T = sim["t"][-1]
    for i, r in enumerate(spec["runs"]):
        est = np.unwrap(sim["rpy"][i, :, 2])
        true = np.unwrap(Rotation.from_quat(sim["quat"][i][:, [1, 2, 3, 0]]).as_euler("ZYX")[:, 0])
        # the filter's yaw is held (to a few degrees: small yaw outputs fall in the T200's dead band,
        # 1472-1528 us, so the hold limit-cycles until the integrator builds up)
        assert np.ptp(est[50:]) < np.radians(4.0)
        # the filter integrates r + b_r (no compass): its yaw runs ahead of the truth by b_r t, so
        # holding it turns the vehicle at -b_r
        drift = (true[-1] - true[0]) - (est[-1] - est[0])
        assert drift == pytest.approx(-r["gyro_bias"][2] * T, abs=0.1 * abs(r["gyro_bias"][2]) * T + 1e-3)


def test_a_dead_thrusters_pwm_varies_while_its_thrust_is_zero():
    spec = field.sample_field(3, "dead", duration=10.0, n_train=1, n_validation=1)
    sim = field.simulate_field(spec)
    k = spec["fault"]["thruster"] - 1
    assert np.ptp(sim["pwm"][:, :, k]) > 20 and np.all(sim["thrust"][:, :, k] == 0.0)
    others = np.delete(sim["thrust"], k, axis=2)
    assert np.abs(others).max() > 1.0


def test_the_dataset_reads_as_it_is_with_jittered_stamps_dvl_gaps_and_the_truth(dataset):
    from uvsim.logs import read_dataset

    spec, out = dataset
    ds = read_dataset(out)
    assert [r.split for r in ds.runs] == ["train", "train", "validation"]
    assert ds.vehicle_file is not None and ds.vehicle_file.name == "myrov.yaml"
    run = ds.runs[0]
    cols = set(run.data.columns)
    assert {f"pwm_{i}" for i in range(1, 9)} | {"roll", "pitch", "yaw", "p", "q", "r", "acc_x", "depth", "u"} <= cols
    t = run.data["t"].to_numpy()
    grid = np.arange(t.size) / spec["log_hz"]
    assert np.all(np.diff(t) > 0)                             # stamps increase
    err = t - grid
    assert np.abs(err).max() <= field.CLOCK_JITTER + 1e-9 and np.std(err) > 0.004   # +-15 ms, uniform
    yaw_deg = np.degrees(run.data["yaw"].to_numpy())
    assert np.allclose(yaw_deg, np.round(yaw_deg, 2), atol=1e-9)                 # 0.01 deg
    # DVL at 5 Hz with drop-outs: NaN between its samples at 10 Hz, and gaps longer than 0.5 s
    u = run.data["u"].to_numpy()
    have = np.flatnonzero(np.isfinite(u))
    assert np.all(np.isnan(u[1::2])) and np.diff(t[have]).max() > 0.5
    for a, b in spec["runs"][0]["dvl_dropouts"]:
        assert np.all(np.isnan(u[(grid >= a) & (grid < b)]))
    truth = yaml.safe_load((out / "truth.yaml").read_text())
    k = spec["fault"]["thruster"]
    assert truth["expected"] == {"effect": "thruster_gain", "variant": f"reversed_{k}"}
    assert truth["fault"] == {"thruster": k, "gain": -1.0} and truth["case"] == "reversed"
    assert truth["vehicle"]["factors"]["Z_wdot"] >= 1.10 and "coupled_drag" in truth["vehicle"]
    # the pressure sensor sits 0.1-0.2 m off the origin, and the given model says where
    p = np.asarray(truth["sensors"]["pressure"]["position"])
    assert 0.09 <= np.linalg.norm(p) <= 0.22
    model = yaml.safe_load(ds.vehicle_file.read_text())
    assert model["sensors"]["pressure"]["position"] == p.tolist()
    assert model["added_mass"] == load_vehicle_data().document["added_mass"]   # the shipped coefficients


def test_seeded_and_reproducible(tmp_path):
    a, b = field.sample_field(11, **SMALL), field.sample_field(11, **SMALL)
    assert a == b and field.sample_field(12, **SMALL) != a
    spec = field.sample_field(11, "current", duration=4.0, n_train=1, n_validation=1)
    d1 = field.generate_field(spec, tmp_path / "a")
    # the caller's own flight (generate_field(..., sim=)) writes the same files
    d2 = field.generate_field(copy.deepcopy(spec), tmp_path / "b", sim=field.simulate_field(copy.deepcopy(spec)))
    for f in sorted(p.name for p in d1.iterdir()):
        assert (d1 / f).read_bytes() == (d2 / f).read_bytes(), f
    # every case and its expected answer
    answers = {c: field.sample_field(0, c, **SMALL)["expected"] for c in field.CASES}
    assert answers["clean"] == "none" and answers["tilted_thruster"] == answers["depth_drag"] == "outside_catalogue"
    assert answers["dead"]["answer"] == "dead" and answers["weight"] == {"effect": "ballast"}
    with pytest.raises(Exception, match="case"):
        field.sample_field(0, "kraken")


def test_the_benchmark_judges_the_answers():
    from uvsim.benchmarks.field_logs import judge, summarize

    rev = {"effect": "thruster_gain", "variant": "reversed_3"}
    rep = {"effects": [{"effect": "thruster_gain", "variant": "reversed_3", "answer": "thruster 3 pushes the wrong way"}],
           "verdict": {"status": "explained", "unexplained": False}, "model_verdict": {"status": "better"}}
    j = judge(rev, rep)
    assert j["right_set"] and j["right_variant"] and j["validation_fixed"]
    dead = {"effect": "thruster_gain", "variant": "unit_3", "answer": "dead"}
    rep_weak = {**rep, "effects": [{"effect": "thruster_gain", "variant": "unit_3", "answer": None}]}
    assert judge(dead, rep_weak)["right_set"] and not judge(dead, rep_weak)["right_variant"]
    j = judge("none", {**rep, "model_verdict": None})
    assert not j["right_set"] and j["false_effects"] == 1
    assert judge("outside_catalogue", {"effects": [], "verdict": {"unexplained": True}})["right_set"]
    assert not judge(rev, None)["right_set"]
    recs = [{"case": "reversed", "expected": rev, "seconds": 1.0, "diagnosed": True, **judge(rev, rep)}]
    s = summarize(recs)
    assert s["single_named_and_fixed"] == 1 and s["reversed_named_reversed"] == 1 and s["diagnosed"] == 1


@pytest.mark.slow
def test_bench_diagnose_field_runs_end_to_end(tmp_path):
    res = tmp_path / "field.jsonl"
    proc = subprocess.run([sys.executable, "-m", "uvsim.cli", "bench", "diagnose-field", "--scenarios", "2",
                           "--seed", "0", "--results", str(res)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "cases: 2" in proc.stdout and len(res.read_text().splitlines()) == 2
