"""Tests of uvsim.logs: reading, validating and writing logged runs/datasets."""
from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.spatial.transform import Rotation

from uvsim import logs
from uvsim.errors import LogFormatError
from uvsim.logs import INPUT_KINDS, Dataset, Run, read_dataset, read_run, write_dataset, write_run

N = 6


def frame(**cols) -> pd.DataFrame:
    """A valid run: t, full position, Euler attitude and force inputs, with
    columns overridden / removed (value None) by keyword."""
    t = np.linspace(0.0, 0.5, N)
    base = {
        "t": t,
        "x": 0.1 * t, "y": -0.2 * t, "z": 1.0 + 0.05 * t,
        "roll": 0.01 * t, "pitch": -0.02 * t, "yaw": 0.3 + 0.1 * t,
        "X": np.full(N, 10.0), "Y": np.zeros(N), "Z": np.zeros(N),
        "K": np.zeros(N), "M": np.zeros(N), "N": np.full(N, 0.5),
    }
    base.update(cols)
    return pd.DataFrame({k: v for k, v in base.items() if v is not None})


def no_force(**cols):
    return {**{c: None for c in "XYZKMN"}, **cols}


def pwm(k=4, value=1500.0):
    return {f"pwm_{i}": np.full(N, value) for i in range(1, k + 1)}


def save(tmp_path, df, name="run.csv"):
    """Write ``df`` unvalidated (as a logger would) and return the path."""
    p = tmp_path / name
    df.to_csv(p, index=False)
    return p


def raises(path_or_text, *fragments):
    """pytest.raises matching every fragment (escaped) in order."""
    pat = ".*".join(re.escape(str(f)) for f in fragments)
    return pytest.raises(LogFormatError, match=re.compile(pat, re.S))


# ----------------------------------------------------------------- good input

def test_basic_run_properties(tmp_path):
    p = save(tmp_path, frame())
    run = read_run(p, dof="surge", weight=2, split="validation")
    assert run.name == "run" and run.path == p
    assert (run.dof, run.weight, run.split) == ("surge", 2.0, "validation")
    assert run.input_kind == "force" and run.n_thrusters is None
    assert run.inputs.shape == (N, 6)
    np.testing.assert_array_equal(run.inputs[:, 0], 10.0)
    np.testing.assert_array_equal(run.inputs[:, 5], 0.5)
    np.testing.assert_allclose(run.t, np.linspace(0, 0.5, N))
    assert list(run.data.index) == list(range(N))
    assert all(run.data.dtypes == np.float64)
    assert run.has_position and run.has_attitude
    assert not run.has_velocity and not run.has_rates
    assert run.signals() == ["position", "attitude"]
    assert np.isnan(run.velocity).all() and run.velocity.shape == (N, 6)
    assert "force" in INPUT_KINDS


def test_thrust_columns_in_index_order_and_n_thrusters(tmp_path):
    # columns deliberately out of order in the file; thrust_10 after thrust_2
    cols = {f"thrust_{i}": np.full(N, float(i)) for i in (10, 2, 1, 3, 4, 5, 6, 7, 8, 9)}
    p = save(tmp_path, frame(**no_force(**cols)))
    run = read_run(p, n_thrusters=10)
    assert run.input_kind == "thrust" and run.n_thrusters == 10
    np.testing.assert_array_equal(run.inputs[0], np.arange(1.0, 11.0))
    assert run.input_columns[:3] == ["thrust_1", "thrust_2", "thrust_3"]


def test_depth_only_run(tmp_path):
    df = frame(x=None, y=None, roll=None, pitch=None, yaw=None)
    run = read_run(save(tmp_path, df), dof="heave")
    pos = run.position
    assert pos.shape == (N, 3)
    assert np.isnan(pos[:, :2]).all()
    np.testing.assert_allclose(pos[:, 2], df["z"])
    assert run.has_position and not run.has_attitude
    assert np.isnan(run.quaternion).all() and np.isnan(run.euler).all()
    assert run.measured_columns == {"position": ["z"]}
    assert run.signals() == ["position"]


def test_rates_only_run(tmp_path):
    rng = np.random.default_rng(0)
    df = frame(**no_force(x=None, y=None, z=None, p=rng.normal(size=N), q=rng.normal(size=N),
                          r=rng.normal(size=N), **pwm(6)))
    run = read_run(save(tmp_path, df), n_thrusters=6)
    assert not run.has_position and run.has_attitude
    assert run.has_rates and not run.has_velocity
    vel = run.velocity
    assert np.isnan(vel[:, :3]).all()
    np.testing.assert_array_equal(vel[:, 3:], df[["p", "q", "r"]].to_numpy())
    assert run.signals() == ["attitude", "rates"]
    assert run.measured_columns["rates"] == ["p", "q", "r"]
    assert run.input_kind == "pwm" and run.n_thrusters == 6


def test_euler_columns_give_quaternion_matching_scipy(tmp_path):
    rng = np.random.default_rng(1)
    eul = np.column_stack([rng.uniform(-3, 3, N), rng.uniform(-1.4, 1.4, N), rng.uniform(-3, 3, N)])
    run = read_run(save(tmp_path, frame(roll=eul[:, 0], pitch=eul[:, 1], yaw=eul[:, 2])))
    # independent reference: scipy, intrinsic ZYX = yaw, pitch, roll; scalar-last
    ref = Rotation.from_euler("ZYX", eul[:, ::-1]).as_quat()[:, [3, 0, 1, 2]]
    q = run.quaternion
    sign = np.sign(np.sum(q * ref, axis=1))[:, None]
    np.testing.assert_allclose(q, sign * ref, atol=1e-12)
    np.testing.assert_array_equal(run.euler, eul)


def test_quaternion_columns_give_euler_and_are_normalized(tmp_path):
    rng = np.random.default_rng(2)
    eul = np.column_stack([rng.uniform(-3, 3, N), rng.uniform(-1.4, 1.4, N), rng.uniform(-3, 3, N)])
    q = Rotation.from_euler("ZYX", eul[:, ::-1]).as_quat()[:, [3, 0, 1, 2]]
    q_logged = q * 1.005  # within the 1e-2 tolerance; must come back normalized
    df = frame(roll=None, pitch=None, yaw=None, **dict(zip(["qw", "qx", "qy", "qz"], q_logged.T)))
    run = read_run(save(tmp_path, df))
    np.testing.assert_allclose(np.linalg.norm(run.quaternion, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(run.quaternion, q, atol=1e-12)
    np.testing.assert_allclose(run.euler, eul, atol=1e-9)
    assert run.measured_columns["attitude"] == ["qw", "qx", "qy", "qz"]


def test_nan_in_measured_signals_is_kept(tmp_path):
    z = np.linspace(1, 2, N)
    z[2] = np.nan
    roll = np.zeros(N)
    roll[3] = np.nan
    run = read_run(save(tmp_path, frame(z=z, roll=roll)))
    assert np.isnan(run.position[2, 2]) and np.isfinite(run.position[[0, 1, 3], 2]).all()
    assert np.isnan(run.quaternion[3]).all() and np.isfinite(run.quaternion[2]).all()
    assert np.isnan(run.euler[3, 0]) and np.isfinite(run.euler[3, 1:]).all()
    assert len(run.data) == N


def test_entirely_empty_column_counts_as_absent(tmp_path):
    p = tmp_path / "run.csv"
    df = frame(x=np.full(N, np.nan), u=np.full(N, np.nan))
    df.to_csv(p, index=False)
    run = read_run(p)
    assert "x" not in run.data.columns and "u" not in run.data.columns
    assert sorted(run.empty_columns) == ["u", "x"]
    assert np.isnan(run.position[:, 0]).all() and not run.has_velocity
    assert run.measured_columns["position"] == ["y", "z"]


def test_extra_columns_are_kept(tmp_path):
    run = read_run(save(tmp_path, frame(mag_x=np.ones(N))))
    assert run.extra_columns == ["mag_x"]
    np.testing.assert_array_equal(run.data["mag_x"], 1.0)


@pytest.mark.parametrize("names, suggested", [
    (("ax", "ay", "az"), "acc_x, acc_y, acc_z"),           # what some converters write
    (("accel_x", "accel_y", "accel_z"), "acc_x, acc_y, acc_z"),
    (("acc_x_mps2", "acc_y_mps2", "acc_z_mps2"), "acc_x, acc_y, acc_z"),   # a unit suffix
    (("ACC_X", "ACC_Y", "ACC_Z"), "acc_x, acc_y, acc_z"),   # case
    (("gx", "gy", "gz"), "p, q, r"), (("gyro_x",), "p"), (("wz",), "r"),
    (("phi", "theta", "psi"), "roll, pitch, yaw"), (("roll_deg",), "roll"),
    (("quat_w", "quat_x", "quat_y", "quat_z"), "qw, qx, qy, qz"), (("q0", "q1", "q2", "q3"), "qw, qx, qy, qz"),
    (("vx", "vy", "vz"), "u, v, w"),
    (("depth_m",), "depth"), (("pressure_depth",), "depth"),
])
def test_a_format_column_under_another_name_is_refused_with_the_format_name(tmp_path, names, suggested):
    """No silent loss: before, such columns were kept as extras and every method ran without them."""
    cols = {n: np.full(N, -9.81 if n.endswith("z") else 0.01) for n in names}
    p = save(tmp_path, frame(roll=None, pitch=None, yaw=None, **cols))  # the format's own columns absent
    listed = ", ".join(repr(n) for n in names)
    with raises(p, "run.csv", listed, "not in the log format", f"did you mean {suggested}?"):
        read_run(p)


def test_accelerometer_as_ax_names_acc_x_and_what_it_holds(tmp_path):
    acc = {"ax": np.zeros(N), "ay": np.zeros(N), "az": np.full(N, -9.81)}
    p = save(tmp_path, frame(**acc))
    with raises(p, "run.csv", "columns 'ax', 'ay', 'az'", "did you mean acc_x, acc_y, acc_z?",
                "m/s^2, accelerometer specific force in body axes"):
        read_run(p)
    with raises(p, "run 'r'", "'ax'"):   # write_run validates the same way
        Run("r", None, frame(**acc))


def test_velocity_alias_says_u_v_w_are_body_frame(tmp_path):
    p = save(tmp_path, frame(vx=np.zeros(N)))
    with raises(p, "'vx'", "did you mean u?", "body-frame velocity; a velocity in NED has no column"):
        read_run(p)


@pytest.mark.parametrize("name, suggested", [
    ("thrust1", "thrust_1"), ("pwm1", "pwm_1"), ("motor_1", "pwm_1 or thrust_1"), ("PWM_1", "pwm_1"),
    ("time", "t"), ("timestamp", "t")])
def test_actuator_and_time_aliases(tmp_path, name, suggested):
    if name in ("time", "timestamp"):
        cols = {"t": None, name: np.arange(N) * 0.1}
    else:
        cols = no_force(**{name: np.full(N, 1500.0)})
    p = save(tmp_path, frame(**cols))
    with raises(p, "run.csv", repr(name), f"did you mean {suggested}?"):
        read_run(p)


def test_an_alias_beside_its_format_column_or_empty_is_an_extra_column(tmp_path):
    """Conservative: ``timestamp`` beside ``t`` (a second clock) is kept, and an entirely empty
    ``ax`` counts as absent."""
    run = read_run(save(tmp_path, frame(timestamp=1.7e9 + np.arange(N), ax=np.full(N, np.nan))))
    assert run.extra_columns == ["timestamp"] and run.empty_columns == ["ax"]


def test_columns_outside_the_format_are_kept_and_said(tmp_path):
    """Not aliases (magnetometer, a raw ADC value, a temperature): kept, not used, and a note
    (:attr:`Run.notes`, printed by every command) names them."""
    extra = {"mag_x": np.ones(N), "mag_y": np.ones(N), "voltage_raw": np.full(N, 812.0), "temperature": np.full(N, 9.0)}
    run = read_run(save(tmp_path, frame(**extra)))
    assert run.extra_columns == list(extra)
    assert run.notes == [f"{tmp_path / 'run.csv'}: columns not in the log format, not used: "
                         "mag_x, mag_y, voltage_raw, temperature"]
    plain = read_run(save(tmp_path, frame(), name="plain.csv"))
    assert plain.notes == [] and plain.extra_columns == []
    import uvsim

    veh = uvsim.load_vehicle("bluerov2_heavy")
    np.testing.assert_array_equal(uvsim.simulate_run(veh, run).y, uvsim.simulate_run(veh, plain).y)


def test_dataset_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    z = 1 + rng.normal(size=N)
    z[1] = np.nan
    runs = [
        Run("surge_01", None, frame(u=rng.normal(size=N)), dof="surge"),
        Run("heave_01", None, frame(**no_force(x=None, y=None, z=z, **pwm(8, 1600.0))),
            dof="heave", weight=0.5, split="validation"),
        Run("free", None, frame(**no_force(**{f"thrust_{i}": rng.normal(size=N) for i in (1, 2)}))),
    ]
    out = write_dataset(tmp_path / "ds", runs, vehicle="bluerov2_heavy", description="test data")
    ds = read_dataset(out)
    assert isinstance(ds, Dataset)
    assert ds.path == tmp_path / "ds"
    assert ds.vehicle == "bluerov2_heavy" and ds.description == "test data"
    assert [r.name for r in ds.runs] == ["surge_01", "heave_01", "free"]
    for a, b in zip(runs, ds.runs):
        pd.testing.assert_frame_equal(a.data, b.data)  # exact: full float precision
        assert (a.dof, a.weight, a.split) == (b.dof, b.weight, b.split)
        assert b.path == tmp_path / "ds" / f"{a.name}.csv"
    assert [r.name for r in ds.train] == ["surge_01", "free"]
    assert [r.name for r in ds.validation] == ["heave_01"]
    assert [r.name for r in ds.by_dof("heave")] == ["heave_01"]
    assert ds.by_dof("yaw") == []
    manifest = yaml.safe_load((out / "manifest.yaml").read_text())
    assert manifest["runs"][2] == {"file": "free.csv", "weight": 1.0, "split": "train"}
    # reading the manifest file itself works too
    assert [r.name for r in read_dataset(out / "manifest.yaml").runs] == ["surge_01", "heave_01", "free"]


def test_manifest_defaults_and_extra_keys(tmp_path):
    save(tmp_path, frame(), "a.csv")
    (tmp_path / "manifest.yaml").write_text("vehicle: v\nnoise: {z: 0.01}\nruns:\n  - file: a.csv\n")
    ds = read_dataset(tmp_path)
    r = ds.runs[0]
    assert (r.dof, r.weight, r.split) == (None, 1.0, "train")
    assert ds.description == "" and ds.meta == {"noise": {"z": 0.01}}


def test_closed_loop_is_a_run_attribute_that_travels_with_the_run(tmp_path):
    """``closed_loop`` (flown under an autopilot): written only when said and read back (what the
    verdict reads to judge over windows, docs/diagnose.md; a run cut at a gap keeps it: test_gaps)."""
    rng = np.random.default_rng(5)
    runs = [Run("held", None, frame(u=rng.normal(size=N)), closed_loop=True),
            Run("manual", None, frame(u=rng.normal(size=N)), closed_loop=False),
            Run("unsaid", None, frame(u=rng.normal(size=N)))]
    out = write_dataset(tmp_path / "ds", runs, vehicle="bluerov2_heavy")
    entries = yaml.safe_load((out / "manifest.yaml").read_text())["runs"]
    assert [e.get("closed_loop") for e in entries] == [True, False, None] and "closed_loop" not in entries[2]
    back = read_dataset(out).runs
    assert [r.closed_loop for r in back] == [True, False, None]


def test_parquet_round_trip(tmp_path):
    pytest.importorskip("pyarrow")
    run = Run("p", None, frame(**no_force(**pwm(3))), dof="yaw")
    ds = read_dataset(write_dataset(tmp_path, [run], vehicle="v", suffix=".parquet"))
    assert ds.runs[0].path.suffix == ".parquet"
    pd.testing.assert_frame_equal(ds.runs[0].data, run.data)


def test_parquet_without_pyarrow_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setattr(logs, "_have_pyarrow", lambda: False)
    p = tmp_path / "r.parquet"
    p.write_bytes(b"PAR1")
    with raises(p, "r.parquet", "pyarrow"):
        read_run(p)
    with raises(p, "r.parquet", "pyarrow"):
        write_run(p, frame())


def test_write_run_accepts_frame_and_run(tmp_path):
    p = write_run(tmp_path / "sub" / "a.csv", frame())
    assert p.is_file()
    pd.testing.assert_frame_equal(read_run(p).data, Run("a", None, frame()).data)
    with raises(None, "t", "strictly increasing"):
        write_run(tmp_path / "b.csv", frame(t=np.zeros(N)))
    with raises(None, "b.txt", ".csv or .parquet"):
        write_run(tmp_path / "b.txt", frame())


# ----------------------------------------------------------------- bad runs

def test_missing_t(tmp_path):
    p = save(tmp_path, frame(t=None))
    with raises(p, "run.csv", "missing time column 't'"):
        read_run(p)


def test_t_nan_names_row(tmp_path):
    t = np.linspace(0, 1, N)
    t[3] = np.nan
    p = save(tmp_path, frame(t=t))
    with raises(p, "run.csv", "'t'", "row 3 (line 5"):
        read_run(p)


def test_t_not_strictly_increasing_names_first_row(tmp_path):
    t = np.array([0.0, 0.1, 0.2, 0.2, 0.1, 0.5])
    p = save(tmp_path, frame(t=t))
    with raises(p, "run.csv", "strictly increasing", "row 3"):
        read_run(p)


def test_no_measured_column_at_all(tmp_path):
    p = save(tmp_path, frame(x=None, y=None, z=None, roll=None, pitch=None, yaw=None))
    with raises(p, "run.csv", "no measured columns", "rates (p, q, r)"):
        read_run(p)


def test_gyro_only_run_is_accepted(tmp_path):
    """Issue 14: an IMU-only run (rates, no position, no attitude) is a valid run."""
    p = save(tmp_path, frame(x=None, y=None, z=None, roll=None, pitch=None, yaw=None,
                             p=np.zeros(N), q=np.full(N, 0.1), r=np.zeros(N)))
    run = read_run(p)
    assert run.signals() == ["rates"] and not run.has_attitude
    assert np.isnan(run.quaternion).all()


def test_no_inputs(tmp_path):
    p = save(tmp_path, frame(**no_force()))
    with raises(p, "run.csv", "no input columns"):
        read_run(p)


@pytest.mark.parametrize("extra", [pwm(4), {"thrust_1": np.ones(N)}])
def test_mixed_input_kinds(tmp_path, extra):
    p = save(tmp_path, frame(**extra))
    with raises(p, "run.csv", "mixed input kinds"):
        read_run(p)


def test_partial_force_columns(tmp_path):
    p = save(tmp_path, frame(K=None, N=None))
    with raises(p, "run.csv", "all six", "['K', 'N']"):
        read_run(p)


def test_thrust_columns_with_gap(tmp_path):
    cols = {"thrust_1": np.ones(N), "thrust_3": np.ones(N)}
    p = save(tmp_path, frame(**no_force(**cols)))
    with raises(p, "run.csv", "without gaps", "thrust_2"):
        read_run(p)


@pytest.mark.parametrize("name", ["thrust1", "PWM_1", "pwm_0", "pwm_01"])
def test_misnamed_actuator_column(tmp_path, name):
    p = save(tmp_path, frame(**no_force(**{name: np.full(N, 1500.0)})))
    with raises(p, "run.csv", repr(name), "thrust_1"):
        read_run(p)


def test_nan_in_inputs_names_column_and_row(tmp_path):
    cols = pwm(4)
    cols["pwm_2"][4] = np.nan
    p = save(tmp_path, frame(**no_force(**cols)))
    with raises(p, "run.csv", "'pwm_2'", "row 4"):
        read_run(p)


@pytest.mark.parametrize("bad", [999.0, 2000.5, 0.0, 0.5])
def test_pwm_out_of_range_names_column_and_row(tmp_path, bad):
    cols = pwm(4)
    cols["pwm_3"][2] = bad
    p = save(tmp_path, frame(**no_force(**cols)))
    with raises(p, "run.csv", "'pwm_3'", "row 2", "1000..2000 us"):
        read_run(p)


def test_pwm_range_limits_are_accepted(tmp_path):
    cols = pwm(2)
    cols["pwm_1"][:] = 1000.0
    cols["pwm_2"][:] = 2000.0
    assert read_run(save(tmp_path, frame(**no_force(**cols)))).n_thrusters == 2


def test_quaternion_far_from_unit_names_row(tmp_path):
    q = np.tile([1.0, 0.0, 0.0, 0.0], (N, 1))
    q[4] = [1.02, 0, 0, 0]
    p = save(tmp_path, frame(roll=None, pitch=None, yaw=None, **dict(zip(["qw", "qx", "qy", "qz"], q.T))))
    with raises(p, "run.csv", "row 4", "norm 1.02"):
        read_run(p)


def test_partial_quaternion_columns(tmp_path):
    p = save(tmp_path, frame(qw=np.ones(N), qx=np.zeros(N), qy=np.zeros(N)))
    with raises(p, "run.csv", "partial quaternion", "qz"):
        read_run(p)


def test_quaternion_with_an_entirely_empty_component_is_partial(tmp_path):
    p = save(tmp_path, frame(qw=np.ones(N), qx=np.zeros(N), qy=np.zeros(N), qz=np.full(N, np.nan)))
    with raises(p, "run.csv", "partial quaternion"):
        read_run(p)


def test_roll_pitch_without_yaw(tmp_path):
    """Issue 14: a magnetometer-free IMU logs roll and pitch only: accepted, yaw is NaN,
    and there is no full attitude (no quaternion)."""
    run = read_run(save(tmp_path, frame(yaw=None)))
    assert run.has_attitude and not run.has_full_attitude
    assert run.euler_mask.tolist() == [True, True, False]
    assert np.isnan(run.euler[:, 2]).all() and np.isfinite(run.euler[:, :2]).all()
    assert np.isnan(run.quaternion).all()
    assert run.measured_columns["attitude"] == ["roll", "pitch"]


def test_depth_and_accelerometer_columns(tmp_path):
    acc = {"acc_x": np.zeros(N), "acc_y": np.zeros(N), "acc_z": np.full(N, -9.81)}
    dep = np.full(N, np.nan)
    dep[::3] = 1.5
    run = read_run(save(tmp_path, frame(x=None, y=None, z=None, depth=dep, **acc)))
    assert run.signals() == ["depth", "attitude", "acceleration"]
    np.testing.assert_array_equal(run.depth, dep)
    np.testing.assert_array_equal(run.acceleration[:, 2], np.full(N, -9.81))
    assert run.extra_columns == []


def test_partial_accelerometer_columns(tmp_path):
    p = save(tmp_path, frame(acc_x=np.zeros(N), acc_z=np.zeros(N)))
    with raises(p, "run.csv", "partial acceleration", "['acc_x', 'acc_z']"):
        read_run(p)


def test_manifest_vehicle_name_resolves_beside_the_manifest(tmp_path):
    """Issue 14: ``vehicle: myrov`` with myrov.yaml next to manifest.yaml is that file;
    a built-in name without such a file stays a built-in."""
    run = read_run(save(tmp_path, frame()))
    write_dataset(tmp_path / "ds", [run], vehicle="myrov")
    (tmp_path / "ds" / "myrov.yaml").write_text("name: myrov\n")
    ds = read_dataset(tmp_path / "ds")
    assert ds.vehicle_file == tmp_path / "ds" / "myrov.yaml"
    write_dataset(tmp_path / "ds2", [run], vehicle="bluerov2_heavy")
    assert read_dataset(tmp_path / "ds2").vehicle_file is None


def test_quaternion_and_euler_must_agree(tmp_path):
    q = {"qw": np.ones(N), "qx": np.zeros(N), "qy": np.zeros(N), "qz": np.zeros(N)}
    ok = frame(roll=np.zeros(N), pitch=np.zeros(N), yaw=np.zeros(N), **q)
    assert read_run(save(tmp_path, ok, "ok.csv")).signals() == ["position", "attitude"]
    p = save(tmp_path, frame(**q))  # yaw = 0.3 + 0.1 t, quaternion says 0
    with raises(p, "run.csv", "disagree", "row 0"):
        read_run(p)


def test_non_numeric_cell_names_column_and_row(tmp_path):
    p = save(tmp_path, frame())
    lines = p.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[3].split(",")
    cells[header.index("y")] = "n/a?"
    lines[3] = ",".join(cells)
    p.write_text("\n".join(lines) + "\n")
    with raises(p, "run.csv", "'y'", "row 2 (line 4", "'n/a?'", "not a number"):
        read_run(p)


def test_infinite_value_is_an_error(tmp_path):
    z = np.ones(N)
    z[1] = np.inf
    p = save(tmp_path, frame(z=z))
    with raises(p, "run.csv", "'z'", "row 1", "infinite"):
        read_run(p)


def test_duplicate_csv_column(tmp_path):
    p = tmp_path / "run.csv"
    df = frame()
    df.insert(2, "x_dup", df["x"])
    df.to_csv(p, index=False)
    p.write_text(p.read_text().replace("x_dup", "x", 1))
    with raises(p, "run.csv", "'x'", "more than once"):
        read_run(p)


def test_n_thrusters_mismatch(tmp_path):
    p = save(tmp_path, frame(**no_force(**pwm(4))))
    with raises(p, "run.csv", "expected 8 thrusters", "4 pwm columns"):
        read_run(p, n_thrusters=8)
    p2 = save(tmp_path, frame(), "force.csv")
    with raises(p2, "force.csv", "expected 8 thrusters", "force inputs"):
        read_run(p2, n_thrusters=8)


def test_too_few_rows_and_unknown_suffix(tmp_path):
    p = save(tmp_path, frame().iloc[:1])
    with raises(p, "run.csv", "at least 2 samples"):
        read_run(p)
    q = tmp_path / "run.txt"
    q.write_text("t\n0\n")
    with raises(q, "run.txt", ".csv or .parquet"):
        read_run(q)


@pytest.mark.parametrize("kw, frag", [
    ({"dof": "forward"}, "dof 'forward'"),
    ({"split": "test"}, "split 'test'"),
    ({"weight": 0}, "weight 0"),
])
def test_read_run_checks_attributes(tmp_path, kw, frag):
    p = save(tmp_path, frame())
    with raises(p, "run.csv", frag):
        read_run(p, **kw)


# ----------------------------------------------------------------- bad datasets

def make_ds(tmp_path, manifest_text, files=("a.csv",)):
    for f in files:
        save(tmp_path, frame(), f)
    (tmp_path / "manifest.yaml").write_text(manifest_text)
    return tmp_path


def test_manifest_missing(tmp_path):
    with raises(None, "manifest.yaml", "not found"):
        read_dataset(tmp_path)


@pytest.mark.parametrize("text, frag", [
    ("runs: [file: a.csv\n  - {", "not valid YAML"),
    ("- a.csv\n", "expected a mapping"),
    ("vehicle: v\n", "'runs' must be a non-empty list"),
    ("runs: []\n", "'runs' must be a non-empty list"),
    ("runs:\n  - a.csv\n", "runs[0]: expected a mapping with a 'file'"),
    ("runs:\n  - file: a.csv\n    wieght: 2\n", "unknown key 'wieght' (did you mean 'weight'?)"),
    ("vehicle: [1, 2]\nruns:\n  - file: a.csv\n", "'vehicle' must be"),
])
def test_manifest_unparseable_or_malformed(tmp_path, text, frag):
    ds = make_ds(tmp_path, text)
    with raises(None, "manifest.yaml", frag):
        read_dataset(ds)


@pytest.mark.parametrize("entry, frag", [
    ("dof: forward", "dof 'forward' is not one of"),
    ("dof: Surge", "dof 'Surge'"),
    ("split: test", "split 'test' is not one of"),
    ("weight: 0", "weight 0 must be a positive finite number"),
    ("weight: -1.5", "weight -1.5"),
    ("weight: .nan", "weight nan"),
    ("weight: .inf", "weight inf"),
    ("weight: heavy", "weight 'heavy'"),
    ("weight: true", "weight True"),
    ("closed_loop: yes please", "closed_loop 'yes please' must be true"),
    ("closed_loop: 1", "closed_loop 1 must be true"),
])
def test_manifest_bad_run_attributes(tmp_path, entry, frag):
    ds = make_ds(tmp_path, f"runs:\n  - file: a.csv\n    {entry}\n")
    with raises(None, "manifest.yaml: runs[0]", frag):
        read_dataset(ds)


def test_run_file_listed_but_missing(tmp_path):
    ds = make_ds(tmp_path, "runs:\n  - file: a.csv\n  - file: b.csv\n")
    with raises(None, "runs[1]", "'b.csv' does not exist"):
        read_dataset(ds)


def test_duplicate_file_entries(tmp_path):
    ds = make_ds(tmp_path, "runs:\n  - file: a.csv\n  - file: ./a.csv\n    dof: surge\n")
    with raises(None, "runs[1]", "'./a.csv' is listed more than once"):
        read_dataset(ds)


def test_bad_run_file_in_dataset_names_that_file(tmp_path):
    ds = make_ds(tmp_path, "runs:\n  - file: a.csv\n  - file: b.csv\n")
    save(tmp_path, frame(t=None), "b.csv")
    with raises(None, "b.csv", "missing time column"):
        read_dataset(ds)


def test_write_dataset_rejects_duplicate_names(tmp_path):
    runs = [Run("a", None, frame()), Run("a", None, frame())]
    with raises(None, "two runs are named 'a'"):
        write_dataset(tmp_path, runs, vehicle="v")


def test_blank_lines_keep_line_numbers_right(tmp_path):
    p = save(tmp_path, frame())
    text = p.read_text()
    (tmp_path / "trailing.csv").write_text(text + "\n\n")
    assert len(read_run(tmp_path / "trailing.csv").data) == N
    lines = text.splitlines()
    lines.insert(3, "")  # becomes line 4 = row 2
    p.write_text("\n".join(lines) + "\n")
    with raises(p, "run.csv", "'t'", "row 2 (line 4 of the file)", "empty"):
        read_run(p)


def test_header_only_and_empty_files(tmp_path):
    p = tmp_path / "run.csv"
    p.write_text("t,z,roll,pitch,yaw,pwm_1\n")
    with raises(p, "run.csv", "at least 2 samples, found 0"):
        read_run(p)
    p.write_text("")
    with raises(p, "run.csv", "cannot parse as CSV"):
        read_run(p)


def test_in_memory_object_columns_are_converted():
    df = frame().astype(object)
    run = Run("mem", None, df)
    assert all(run.data.dtypes == np.float64)
    df.loc[1, "z"] = "deep"
    with raises(None, "run 'mem'", "'z'", "row 1", "'deep'"):
        Run("mem", None, df)


def test_pwm_message_gives_plain_number(tmp_path):
    cols = pwm(2)
    cols["pwm_1"][0] = 2500.0
    p = save(tmp_path, frame(**no_force(**cols)))
    with raises(p, "PWM 2500.0 us outside"):
        read_run(p)


def test_vehicle_file_is_resolved_against_dataset_dir(tmp_path):
    ds = read_dataset(make_ds(tmp_path, "vehicle: my_rov.yaml\nruns:\n  - file: a.csv\n"))
    assert ds.vehicle_file == tmp_path / "my_rov.yaml"
    ds.vehicle = "bluerov2_heavy"
    assert ds.vehicle_file is None


def test_kept_columns_follow_the_table(tmp_path):
    """The column arrays a run keeps (Run._column) are the table's, follow a replaced table, are
    not pickled, and cannot be changed through an accessor."""
    import pickle

    run = read_run(save(tmp_path, frame()))
    t = run.t
    np.testing.assert_array_equal(t, run.data["t"].to_numpy())
    assert not t.flags.writeable
    with pytest.raises(ValueError):
        t[0] = 1.0
    u = run.inputs
    np.testing.assert_array_equal(u, run.data[run.input_columns].to_numpy())
    u[:] = -1.0  # a fresh array each call: the run's inputs are untouched
    np.testing.assert_array_equal(run.inputs[:, 0], 10.0)
    np.testing.assert_array_equal(run.position[:, 0], run.data["x"].to_numpy())
    # a derived run (another table) reads its own table, the original keeps its own
    other = run.data.copy()
    other["X"] = 3.0
    d = run.derived(other)
    np.testing.assert_array_equal(d.inputs[:, 0], 3.0)
    np.testing.assert_array_equal(run.inputs[:, 0], 10.0)
    # a table assigned to the run is read from then on
    run.data = other.iloc[:3].reset_index(drop=True)
    assert run.t.shape == (3,) and run.inputs.shape == (3, 6)
    back = pickle.loads(pickle.dumps(d))
    assert "_kept_columns" not in back.__dict__
    np.testing.assert_array_equal(back.inputs, d.inputs)


def test_kept_columns_see_edits_in_place(tmp_path):
    """A column assigned, a column added and a value edited in the run's own table after the
    arrays were read are what the accessors give next (as a notebook edits a run)."""
    run = read_run(save(tmp_path, frame()))
    assert run.inputs[0, 0] == 10.0 and run.t[-1] == 0.5 and not run.has_velocity
    run.data["X"] = run.data["X"] + 1.0
    np.testing.assert_array_equal(run.inputs[:, 0], 11.0)
    run.data.loc[2, "t"] = 0.25
    assert run.t[2] == 0.25
    run.data["u"] = 0.3
    np.testing.assert_array_equal(run.velocity[:, 0], 0.3)
