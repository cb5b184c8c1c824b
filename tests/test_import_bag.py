"""``uvsim import bag``: ROS 2 bags written here with rosbags' own writer round-trip into
datasets (issue 11 item 2).  The ENU/FLU -> NED/FRD conversion is checked against
rotations built in this file with scipy."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

import uvsim
from uvsim.cli import main
from uvsim.errors import LogFormatError
from uvsim.importers.rosbag import import_bag
from uvsim.logs import read_dataset

rosbag2 = pytest.importorskip("rosbags.rosbag2")
typesys = pytest.importorskip("rosbags.typesys")
Rotation = pytest.importorskip("scipy.spatial.transform").Rotation

MAPS = Path(uvsim.__file__).resolve().parent / "data" / "bag_maps"
T_ENU_NED = np.array([[0.0, 1, 0], [1, 0, 0], [0, 0, -1]])  # swaps N/E, flips down/up (its own inverse)
S_FLU_FRD = np.diag([1.0, -1, -1])
T0_NS = 1_700_000_000_000_000_000
RHO, P0, G0 = 1000.0, 101325.0, 9.80665


def _truth(dt=0.02, n=300, seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    pwm = np.full((n, 8), 1500.0)
    for k in range(0, n, 25):  # piecewise-constant commands, changing every 0.5 s
        pwm[k:] = np.round(rng.uniform(1350, 1650, 8))  # ESC commands are whole microseconds
    res = uvsim.simulate("bluerov2_heavy", t, pwm, input_kind="pwm", pos0=[1.0, -2.0, 3.0],
                         q0=[0.96, 0.05, -0.1, 0.25] / np.linalg.norm([0.96, 0.05, -0.1, 0.25]))
    return t, pwm, res


def _store():
    ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    ts.register(typesys.get_types_from_msg("std_msgs/Header header\nuint16[] channels\n", "mavros_msgs/msg/RCOut"))
    ts.register(typesys.get_types_from_msg("std_msgs/Header header\nbool connected\nbool armed\nbool guided\n"
                                           "bool manual_input\nstring mode\nuint8 system_status\n",
                                           "mavros_msgs/msg/State"))
    return ts


def _write_mavros_bag(path, t, pwm, res, acc_frd, volts, modes=()):
    """A mavros-like ROS 2 bag; ``modes``: ``[(t_s, mode string)]`` published on /mavros/state."""
    ts = _store()
    T = ts.types
    Header, Time = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    V3, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]

    def hdr(ns):
        return Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="map")

    R_ned = Rotation.from_quat(res.quaternion[:, [1, 2, 3, 0]]).as_matrix()
    R_enu = T_ENU_NED @ R_ned @ S_FLU_FRD
    q_enu = Rotation.from_matrix(R_enu).as_quat()  # x, y, z, w
    p_enu = res.position @ T_ENU_NED.T
    rates_flu = res.nu[:, 3:] @ S_FLU_FRD
    acc_flu = acc_frd @ S_FLU_FRD
    with rosbag2.Writer(path, version=9) as w:
        c_pose = w.add_connection("/mocap/rov/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)
        c_imu = w.add_connection("/mavros/imu/data", "sensor_msgs/msg/Imu", typestore=ts)
        c_p = w.add_connection("/mavros/imu/static_pressure", "sensor_msgs/msg/FluidPressure", typestore=ts)
        c_rc = w.add_connection("/mavros/rc/out", "mavros_msgs/msg/RCOut", typestore=ts)
        c_bat = w.add_connection("/mavros/battery", "sensor_msgs/msg/BatteryState", typestore=ts)
        if modes:
            c_st = w.add_connection("/mavros/state", "mavros_msgs/msg/State", typestore=ts)
            for tm, mode in modes:
                ns = T0_NS + int(round(tm * 1e9))
                st = T["mavros_msgs/msg/State"](hdr(ns), True, True, False, True, mode, 4)
                w.write(c_st, ns, ts.serialize_cdr(st, "mavros_msgs/msg/State"))
        for i, ti in enumerate(t):
            ns = T0_NS + int(round(ti * 1e9))
            pose = T["geometry_msgs/msg/PoseStamped"](hdr(ns), T["geometry_msgs/msg/Pose"](
                T["geometry_msgs/msg/Point"](*p_enu[i]), Q(*q_enu[i])))
            w.write(c_pose, ns + 1_000_000, ts.serialize_cdr(pose, "geometry_msgs/msg/PoseStamped"))
            imu = T["sensor_msgs/msg/Imu"](hdr(ns), Q(0.0, 0.0, 0.0, 1.0), np.zeros(9), V3(*rates_flu[i]), np.zeros(9),
                                           V3(*acc_flu[i]), np.zeros(9))
            w.write(c_imu, ns + 2_000_000, ts.serialize_cdr(imu, "sensor_msgs/msg/Imu"))
            rc = T["mavros_msgs/msg/RCOut"](hdr(ns), pwm[i].astype(np.uint16))
            w.write(c_rc, ns + 3_000_000, ts.serialize_cdr(rc, "mavros_msgs/msg/RCOut"))
            if i % 5 == 0:  # 10 Hz pressure
                fp = T["sensor_msgs/msg/FluidPressure"](hdr(ns), P0 + RHO * G0 * res.position[i, 2], 0.0)
                w.write(c_p, ns + 4_000_000, ts.serialize_cdr(fp, "sensor_msgs/msg/FluidPressure"))
            if i % 25 == 0:  # 2 Hz battery
                bat = T["sensor_msgs/msg/BatteryState"](
                    hdr(ns), voltage=volts[i], temperature=20.0, current=-5.0, charge=1.0, capacity=1.0,
                    design_capacity=1.0, percentage=0.5, power_supply_status=2, power_supply_health=1,
                    power_supply_technology=2, present=True, cell_voltage=np.zeros(0, np.float32),
                    cell_temperature=np.zeros(0, np.float32), location="", serial_number="")
                w.write(c_bat, ns + 5_000_000, ts.serialize_cdr(bat, "sensor_msgs/msg/BatteryState"))


@pytest.fixture(scope="module")
def mavros_bag(tmp_path_factory):
    t, pwm, res = _truth()
    rng = np.random.default_rng(5)
    acc_frd = rng.normal(size=(t.size, 3)) + [0.0, 0.0, -9.81]
    volts = np.linspace(16.4, 15.0, t.size)
    path = tmp_path_factory.mktemp("bags") / "mavros"
    _write_mavros_bag(path, t, pwm, res, acc_frd, volts)
    return path, t, pwm, res, acc_frd, volts


def test_ros2_bag_round_trips_through_import(mavros_bag, tmp_path):
    path, t, pwm, res, acc_frd, volts = mavros_bag
    out = import_bag(path, MAPS / "mavros_mocap.yaml", tmp_path / "ds")
    ds = read_dataset(out["dataset"])
    assert ds.vehicle == "bluerov2_heavy" and len(ds.runs) == 1
    run = ds.runs[0]
    assert len(run.t) == t.size  # all streams of one instant share a row: no resampling
    np.testing.assert_allclose(run.t, t, atol=1e-9)
    np.testing.assert_allclose(run.position, res.position, atol=1e-12)
    q = run.quaternion * np.sign(run.quaternion[:, :1] * res.quaternion[:, :1])
    np.testing.assert_allclose(q, res.quaternion, atol=1e-12)
    np.testing.assert_allclose(run.velocity[:, 3:], res.nu[:, 3:], atol=1e-12)
    np.testing.assert_allclose(run.acceleration, acc_frd, atol=1e-12)
    np.testing.assert_array_equal(run.inputs, pwm)
    ok = np.isfinite(run.depth)
    assert ok.sum() == 60
    np.testing.assert_allclose(run.depth[ok], res.position[ok, 2], atol=1e-9)
    np.testing.assert_allclose(run.data["voltage"].dropna().to_numpy(), volts[::25], atol=1e-5)
    rec = ds.meta["import"]
    assert rec["streams"]["motors"]["source"].startswith("/mavros/rc/out [mavros_msgs/msg/RCOut]")
    assert "converted to NED/FRD" in " ".join(rec["streams"]["pose"]["notes"])


def test_imported_bag_resimulates_to_the_truth(mavros_bag, tmp_path, capsys):
    path, t, pwm, res, *_ = mavros_bag
    assert main(["import", "bag", str(path), "--map", str(MAPS / "mavros_mocap.yaml"), "--out", str(tmp_path / "d")]) == 0
    capsys.readouterr()
    assert main(["simulate", "--run", str(tmp_path / "d" / "mavros.csv"), "--compare",
                 "--plot", str(tmp_path / "c.png")]) == 0
    table = capsys.readouterr().out
    rmse = {line.split()[0]: float(line.split()[3]) for line in table.splitlines()[2:] if line.strip()
            and not line.startswith("plot")}
    assert rmse["x"] < 1e-6 and rmse["z"] < 1e-6 and rmse["depth"] < 1e-6 and rmse["yaw"] < 1e-4
    assert set(rmse) >= {"x", "y", "z", "depth", "roll", "pitch", "yaw", "p", "q", "r", "acc_x"}


def _map_with(tmp_path, **changes):
    doc = yaml.safe_load((MAPS / "mavros_mocap.yaml").read_text())
    for key, val in changes.items():
        stream, field = key.split("__")
        doc["streams"][stream][field] = val
    p = tmp_path / "map.yaml"
    p.write_text(yaml.safe_dump(doc))
    return p


def test_missing_topic_and_wrong_field_name_the_topic_and_field(mavros_bag, tmp_path):
    path = mavros_bag[0]
    with pytest.raises(LogFormatError, match=r"topic '/mavros/battery_state' \(map streams.battery\) is not in the bag"):
        import_bag(path, _map_with(tmp_path, battery__topic="/mavros/battery_state"), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"topic /mavros/rc/out \(map streams.motors\) \(mavros_msgs/msg/RCOut\): "
                                             r"field 'chanels' not found"):
        import_bag(path, _map_with(tmp_path, motors__field="chanels"), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"field 'channels' has 8 elements; map asks for element 9"):
        import_bag(path, _map_with(tmp_path, motors__elements=[0, 1, 2, 3, 4, 5, 6, 9]), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"streams.depth: 'surface_pressure' must be a positive number"):
        import_bag(path, _map_with(tmp_path, depth__surface_pressure="sea"), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"streams.pose: type 'posestamped' is not one of"):
        import_bag(path, _map_with(tmp_path, pose__type="posestamped"), tmp_path / "o")
    with pytest.raises(LogFormatError, match="cannot be read as a ROS 1 or ROS 2 bag"):
        bad = tmp_path / "bad.bag"
        bad.write_bytes(b"#ROSBAG V2.0\nnot really")
        import_bag(bad, MAPS / "mavros_mocap.yaml", tmp_path / "o")


def test_flight_mode_of_mavros_state_says_closed_loop_per_run(tmp_path, capsys):
    """Issue 48: /mavros/state's mode decides each run's closed_loop (MANUAL: false, a mode that holds
    a state: true, both: not written), the 1 Hz reports standing for the mode one interval early;
    the shipped map skips the topic, and says so, when the bag did not record it."""
    t, pwm, res = _truth()
    rng = np.random.default_rng(5)
    acc = rng.normal(size=(t.size, 3)) + [0.0, 0.0, -9.81]
    volts = np.full(t.size, 16.0)
    modes = [(0.4, "MANUAL"), (1.4, "MANUAL"), (2.4, "MANUAL"), (3.4, "ALT_HOLD"), (4.4, "CMODE(2)"),
             (5.4, "ALT_HOLD")]
    bag = tmp_path / "modes"
    _write_mavros_bag(bag, t, pwm, res, acc, volts, modes=modes)
    seg = tmp_path / "segments.yaml"
    seg.write_text(yaml.safe_dump({"segments": [{"start": 0.0, "end": 2.9, "name": "manual"},
                                                {"start": 3.5, "end": 5.9, "name": "held"},
                                                {"start": 2.0, "end": 4.0, "name": "both"}]}))
    assert main(["import", "bag", str(bag), "--map", str(MAPS / "mavros_mocap.yaml"), "--out", str(tmp_path / "d"),
                 "--segments", str(seg)]) == 0
    out = capsys.readouterr().out
    assert "flight modes (/mavros/state [mavros_msgs/msg/State]): MANUAL from 0.4 s, ALT_HOLD from 3.4 s" in out
    ds = read_dataset(tmp_path / "d")
    assert {r.name: r.closed_loop for r in ds.runs} == {"manual": False, "held": True, "both": None}
    man = yaml.safe_load((tmp_path / "d" / "manifest.yaml").read_text())
    assert [("closed_loop" in e) for e in man["runs"]] == [True, True, False]
    rec = ds.meta["import"]["flight_modes"]
    assert [c["mode"] for c in rec["changes"]] == ["MANUAL", "ALT_HOLD"]  # CMODE(2) is ArduSub's ALT_HOLD
    assert rec["report_interval_s"] == pytest.approx(1.0)
    # the lead is one reporting interval: a run starting 1.2 s before the first report is not known
    early = tmp_path / "early.yaml"
    early.write_text(yaml.safe_dump({"segments": [{"start": 0.0, "end": 2.9}]}))
    mp = yaml.safe_load((MAPS / "mavros_mocap.yaml").read_text())
    mp["streams"]["mode"]["open_loop_modes"] = ["STABILIZE"]   # a map may say which modes are which
    mp["streams"]["mode"]["closed_loop_modes"] = ["MANUAL"]
    (tmp_path / "m.yaml").write_text(yaml.safe_dump(mp))
    import_bag(bag, tmp_path / "m.yaml", tmp_path / "e", segments=early)
    assert read_dataset(tmp_path / "e").runs[0].closed_loop is True
    # without the topic the shipped map skips the optional stream and the record says it
    plain = tmp_path / "plain"
    _write_mavros_bag(plain, t, pwm, res, acc, volts)
    res_plain = import_bag(plain, MAPS / "mavros_mocap.yaml", tmp_path / "p")
    assert "mode" in res_plain["record"]["optional_streams_missing"]
    assert "flight_modes" not in res_plain["record"]
    assert read_dataset(tmp_path / "p").runs[0].closed_loop is None


def test_mode_stream_map_errors_name_the_entry(mavros_bag, tmp_path):
    path = mavros_bag[0]
    with pytest.raises(LogFormatError, match=r"streams.mode: 'closed_loop_modes' must be a list of mode names"):
        import_bag(path, _map_with(tmp_path, mode__closed_loop_modes="ALT_HOLD"), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"streams.mode: modes \['MANUAL'\] are listed both"):
        import_bag(path, _map_with(tmp_path, mode__closed_loop_modes=["MANUAL"], mode__open_loop_modes=["MANUAL"]),
                   tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"streams.motors: 'optional' must be true or false, and the thruster"):
        import_bag(path, _map_with(tmp_path, motors__optional=True), tmp_path / "o")
    with pytest.raises(LogFormatError, match=r"streams.depth: 'open_loop_modes' must be a list of mode names"):
        import_bag(path, _map_with(tmp_path, depth__open_loop_modes=["MANUAL"]), tmp_path / "o")


def test_px4_map_reads_px4_msgs_layouts(tmp_path):
    """The shipped PX4 map against a bag written with px4_msgs v1.14 definitions."""
    ts = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    defs = {
        "px4_msgs/msg/VehicleOdometry": "uint64 timestamp\nuint64 timestamp_sample\nuint8 pose_frame\n"
        "float32[3] position\nfloat32[4] q\nuint8 velocity_frame\nfloat32[3] velocity\nfloat32[3] angular_velocity\n"
        "float32[3] position_variance\nfloat32[3] orientation_variance\nfloat32[3] velocity_variance\n"
        "uint8 reset_counter\nint8 quality\n",
        "px4_msgs/msg/SensorCombined": "uint64 timestamp\nfloat32[3] gyro_rad\nuint32 gyro_integral_dt\n"
        "int32 accelerometer_timestamp_relative\nfloat32[3] accelerometer_m_s2\nuint32 accelerometer_integral_dt\n"
        "uint8 accelerometer_clipping\nuint8 gyro_clipping\nuint8 accel_calibration_count\nuint8 gyro_calibration_count\n",
        "px4_msgs/msg/ActuatorMotors": "uint64 timestamp\nuint64 timestamp_sample\nuint16 reversible_flags\n"
        "float32[12] control\n",
        "px4_msgs/msg/BatteryStatus": "uint64 timestamp\nfloat32 voltage_v\nfloat32 current_a\n",
    }
    for k, v in defs.items():
        ts.register(typesys.get_types_from_msg(v, k))
    T = ts.types
    t = np.arange(40) * 0.025
    ctrl = np.zeros((t.size, 12), np.float32)
    ctrl[:, :8] = np.linspace(-0.5, 0.5, 8)
    ctrl[:4, :] = np.nan  # disarmed at the start
    q = np.array([0.9, 0.1, -0.2, 0.3]) / np.linalg.norm([0.9, 0.1, -0.2, 0.3])
    path = tmp_path / "px4"
    f32 = np.float32
    with rosbag2.Writer(path, version=9) as w:
        co = w.add_connection("/fmu/out/vehicle_odometry", "px4_msgs/msg/VehicleOdometry", typestore=ts)
        cs = w.add_connection("/fmu/out/sensor_combined", "px4_msgs/msg/SensorCombined", typestore=ts)
        ca = w.add_connection("/fmu/out/actuator_motors", "px4_msgs/msg/ActuatorMotors", typestore=ts)
        cb = w.add_connection("/fmu/out/battery_status", "px4_msgs/msg/BatteryStatus", typestore=ts)
        for i, ti in enumerate(t):
            us = 5_000_000 + int(round(ti * 1e6))
            ns = T0_NS + us * 1000 + 7_000_000  # receive times, a different clock: not used by the map
            od = T["px4_msgs/msg/VehicleOdometry"](us, us, 1, np.array([1.0, 2.0, 3.0 + ti], f32), q.astype(f32), 1,
                                                   np.zeros(3, f32), np.array([0.1, -0.2, 0.3], f32), np.zeros(3, f32),
                                                   np.zeros(3, f32), np.zeros(3, f32), 0, 100)
            w.write(co, ns, ts.serialize_cdr(od, "px4_msgs/msg/VehicleOdometry"))
            sc = T["px4_msgs/msg/SensorCombined"](us, np.zeros(3, f32), 0, 0, np.array([0.0, 0.0, -9.8], f32), 0, 0, 0, 0, 0)
            w.write(cs, ns, ts.serialize_cdr(sc, "px4_msgs/msg/SensorCombined"))
            am = T["px4_msgs/msg/ActuatorMotors"](us, us, 255, ctrl[i])
            w.write(ca, ns, ts.serialize_cdr(am, "px4_msgs/msg/ActuatorMotors"))
            if i % 10 == 0:
                w.write(cb, ns, ts.serialize_cdr(T["px4_msgs/msg/BatteryStatus"](us, f32(15.5), f32(3.0)),
                                                 "px4_msgs/msg/BatteryStatus"))
    res = import_bag(path, MAPS / "px4.yaml", tmp_path / "ds")
    run = read_dataset(res["dataset"]).runs[0]
    assert "4 samples with a NaN element dropped" in " ".join(res["record"]["streams"]["motors"]["notes"])
    np.testing.assert_allclose(run.inputs[0], 1500 + 400 * np.linspace(-0.5, 0.5, 8), atol=1e-4)
    np.testing.assert_allclose(run.quaternion[0], q, atol=1e-6)  # NED/FRD taken as is
    np.testing.assert_allclose(run.acceleration[0], [0.0, 0.0, -9.8], atol=1e-6)
    assert run.t[-1] == pytest.approx(t[-1] - t[4], abs=1e-6)  # the run starts at the first armed command
