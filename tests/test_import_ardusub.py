"""``uvsim import ardusub`` on the two shipped real ArduSub logs (issue 11 item 1).

The expected values are read from the logs in the tests with pymavlink directly
(not through the importer), or come from the logs' SOURCE note and ArduPilot's
frame tables."""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
import yaml

from uvsim.cli import main
from uvsim.errors import LogFormatError
from uvsim.importers.ardusub_frames import check_frame, expected_signs
from uvsim.importers.ardusub_import import import_ardusub
from uvsim.logs import read_dataset
from uvsim.vehicle import load_vehicle

mavutil = pytest.importorskip("pymavlink.mavutil")

DATA = Path(__file__).resolve().parents[1] / "src" / "uvsim" / "data" / "external" / "ardusub-log-tools-samples"
TLOG, BIN = DATA / "small.tlog", DATA / "small.BIN"


def _messages(path, typ):
    m = mavutil.mavlink_connection(str(path))
    out = []
    while True:
        msg = m.recv_match(type=typ)
        if msg is None:
            return out
        out.append(msg)


@pytest.fixture(scope="module")
def tlog_ds(tmp_path_factory):
    out = tmp_path_factory.mktemp("tlog")
    res = import_ardusub(TLOG, out, adapt_vehicle=True)
    return res, read_dataset(out)


@pytest.fixture(scope="module")
def bin_ds(tmp_path_factory):
    out = tmp_path_factory.mktemp("bin")
    res = import_ardusub(BIN, out, adapt_vehicle=True)
    return res, read_dataset(out)


# ------------------------------------------------------------------------- the .tlog
def test_tlog_armed_run_and_its_record(tlog_ds):
    res, ds = tlog_ds
    assert [r.name for r in ds.runs] == ["small_armed_01"]
    run = ds.runs[0]
    assert run.dof == "mixed"
    # SOURCE.md: armed for about 16 s (206.7 .. 222.7 s after the log start, 1 Hz heartbeats)
    assert 14.5 < run.t[-1] < 17.0
    imp = ds.meta["import"]
    assert imp["source"]["sha256"] == "eff77a4cf881aa46316c15695b9d59d848ebc72d5edef9622230e5378dc0e1a7"
    assert imp["frame"]["name"] == "VECTORED_6DOF"
    assert imp["frame"]["adapted"]["flipped"] == ["T5_vert_front_right", "T8_vert_rear_left"]
    assert set(run.measured_columns) == {"position", "depth", "attitude", "rates"}
    assert ds.vehicle == "bluerov2_heavy_small" and ds.vehicle_file.is_file()
    # the record names every stream with its rate; motors at the logged 2 Hz, held between samples
    assert imp["streams"]["motors"]["median_rate_hz"] == pytest.approx(2.0, rel=0.01)
    assert "zero-order hold" in imp["streams"]["motors"]["held"]


def test_tlog_values_are_the_logged_ones(tlog_ds):
    res, ds = tlog_ds
    run = ds.runs[0]
    t0 = ds.meta["import"]["runs"]["small_armed_01"]["t0_s"]
    att = [m for m in _messages(TLOG, "ATTITUDE") if m.get_srcSystem() == 1]
    tb = np.array([m.time_boot_ms / 1e3 for m in att])
    inside = (tb >= t0 - 1e-9) & (tb <= t0 + run.t[-1] + 1e-9)
    roll_log = np.array([m.roll for m in att])[inside]
    d = run.data.dropna(subset=["roll"])
    assert len(d) == inside.sum()
    np.testing.assert_allclose(d["roll"].to_numpy(), roll_log, rtol=0, atol=1e-7)
    np.testing.assert_allclose(d["r"].to_numpy(), np.array([m.yawspeed for m in att])[inside], atol=1e-7)
    # SOURCE.md: at the surface, pressure 1015.4..1018.0 hPa -> depth within 0.3 m of zero
    depth = run.depth[np.isfinite(run.depth)]
    assert np.all(np.abs(depth) < 0.3)
    # SYS_STATUS.voltage_battery is in mV
    volts = {m.voltage_battery / 1000.0 for m in _messages(TLOG, "SYS_STATUS")}
    assert set(run.data["voltage"].dropna()) <= volts
    # the pilot's forward commands reach servo1..4 (SOURCE.md: up to 1693..1723 us)
    assert run.data[["pwm_1", "pwm_2", "pwm_3", "pwm_4"]].to_numpy().max() > 1650


# -------------------------------------------------------------------------- the .BIN
def test_bin_imu_follows_the_log_format_sign_convention(bin_ds):
    """ArduPilot IMU.AccX..Z is specific force in body axes: a level vehicle at rest reads
    about (0, 0, -9.8) m/s^2, which is the log format's convention (docs/log_format.md)."""
    res, ds = bin_ds
    run = ds.runs[0]
    acc = run.acceleration[np.isfinite(run.acceleration).all(axis=1)]
    assert acc.shape[0] > 100
    assert np.mean(acc[:, 2]) == pytest.approx(-9.80665, abs=0.1)
    assert np.abs(np.mean(acc[:, :2], axis=0)).max() < 0.4
    assert np.abs(run.euler[:, :2][np.isfinite(run.euler[:, 0])]).max() < np.radians(2.0)


def test_bin_depth_uses_the_external_barometer_and_its_ground_calibration(bin_ds):
    res, ds = bin_ds
    run = ds.runs[0]
    imp = ds.meta["import"]
    assert "BARO[I=1]" in imp["streams"]["depth"]["source"]
    assert "BARO2_GND_PRESS" in imp["streams"]["depth"]["notes"][0]  # armed when the log starts
    t0 = imp["runs"][run.name]["t0_s"]
    baro = [m for m in _messages(BIN, "BARO") if m.I == 1]
    first = min((m for m in baro if m.TimeUS / 1e6 >= t0 - 1e-9), key=lambda m: m.TimeUS)
    gnd = [m.Value for m in _messages(BIN, "PARM") if m.Name == "BARO2_GND_PRESS"][-1]
    depth0 = run.depth[np.isfinite(run.depth)][0]
    assert depth0 == pytest.approx((first.Press - gnd) / (1000.0 * 9.80665), abs=1e-9)
    assert imp["position"].startswith("not written")  # EKF has no horizontal fix in this log
    assert "x" not in run.data and "z" not in run.data


def test_bin_run_ends_at_the_disarm(bin_ds):
    res, ds = bin_ds
    imp = ds.meta["import"]
    (start, end), = imp["armed_intervals_s"]
    assert end == pytest.approx(274.434708)  # ARM record, ArmState 0
    assert "armed when the log started" in imp["armed_from"]


def test_the_flight_mode_says_whether_a_run_was_flown_in_closed_loop(tlog_ds, bin_ds):
    """Both sample logs are flown in MANUAL (HEARTBEAT.custom_mode / MODE.ModeNum 19): the manifest
    says closed_loop: false, and the record lists the modes; a mode that holds a state over a
    whole segment is closed loop, a change of kind within it or no mode known says nothing."""
    from uvsim.importers.ardusub import ArduSubLog

    for res, ds in (tlog_ds, bin_ds):
        assert [r.closed_loop for r in ds.runs] == [False]
        modes = ds.meta["import"]["flight_modes"]
        assert [c["mode"] for c in modes["changes"]] == ["MANUAL"]
    log = ArduSubLog(Path("x.tlog"), "tlog", {}, [], [], (0.0, 40.0), modes=[(1.0, 19), (10.0, 0), (20.0, 2)])
    assert log.closed_loop(2.0, 9.0) is False            # MANUAL throughout
    assert log.closed_loop(11.0, 30.0) is True           # STABILIZE, then DEPTH HOLD (ALT_HOLD)
    assert log.closed_loop(5.0, 15.0) is None            # MANUAL, then STABILIZE
    assert log.closed_loop(0.0, 5.0) is None             # the mode at the start is not known
    assert ArduSubLog(Path("x.tlog"), "tlog", {}, [], [], (0.0, 1.0)).closed_loop(0.0, 1.0) is None


# --------------------------------------------------------------------- frame check
def test_frame_mismatch_is_an_error_naming_log_vehicle_and_thrusters(tmp_path):
    with pytest.raises(LogFormatError) as e:
        import_ardusub(TLOG, tmp_path / "x")
    msg = str(e.value)
    for part in ("small.tlog", "VECTORED_6DOF", "bluerov2_heavy.yaml", "T5_vert_front_right",
                 "MOT_5_DIRECTION=-1", "T8_vert_rear_left", "--adapt-vehicle"):
        assert part in msg
    assert "T6" not in msg and "T1_" not in msg


def test_frame_check_against_factors_built_by_hand():
    """A vehicle whose thruster i pushes along MOT_i_DIRECTION x (AP_Motors6DOF factors)
    passes; the same vehicle with one unit reversed fails on exactly that unit."""
    # VECTORED_6DOF, all directions +1: motor 1 = yaw +1, forward -1, lateral +1
    # -> positive command pushes backward and to starboard at the front right
    pos = np.array([[0.15, 0.11, 0.0], [0.15, -0.11, 0.0], [-0.15, 0.11, 0.0], [-0.15, -0.11, 0.0],
                    [0.12, 0.22, 0.0], [0.12, -0.22, 0.0], [-0.12, 0.22, 0.0], [-0.12, -0.22, 0.0]])
    d = np.array([[-1, 1, 0], [-1, -1, 0], [1, 1, 0], [1, -1, 0], [0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1]],
                 float) / np.array([[np.sqrt(2)]] * 4 + [[1.0]] * 4)
    B = np.vstack([d.T, np.cross(pos, d).T])
    names = [f"T{i + 1}" for i in range(8)]
    dirs = {m: 1.0 for m in range(1, 9)}
    _, bad = check_frame(B, names, 2, dirs, log="log", vehicle="veh")
    assert bad == []
    dirs[3] = -1.0
    _, bad = check_frame(B, names, 2, dirs, log="log", vehicle="veh")
    assert [r["thruster"] for r in bad] == ["T3"] and bad[0]["flippable"]
    with pytest.raises(LogFormatError, match="has 6 motors but vehicle veh has 8 thrusters"):
        check_frame(B, names, 1, dirs, log="log", vehicle="veh")
    assert expected_signs(2, {5: -1.0}, "log")[5].tolist() == [0, 0, -1, -1, 1, 0]


def test_shipped_heavy_matches_default_directions_except_two_verticals():
    """The shipped vehicle file follows ArduSub's VECTORED_6DOF table with directions
    (-1, -1, +1, +1, +1, +1, +1, +1); the real Heavy in small.tlog has MOT_5 = MOT_8 = -1."""
    veh = load_vehicle("bluerov2_heavy")
    dirs = dict(zip(range(1, 9), (-1, -1, 1, 1, 1, 1, 1, 1)))
    _, bad = check_frame(veh.actuators.matrix, veh.actuators.names, 2, dirs, log="l", vehicle="v")
    assert bad == []


# ------------------------------------------------------------------------ bad input
def test_truncated_bin(tmp_path):
    raw = BIN.read_bytes()
    short = tmp_path / "short.BIN"
    short.write_bytes(raw[:5000])
    with pytest.raises(LogFormatError, match=r"short.BIN: no ATT message \(attitude: ATT.Roll"):
        import_ardusub(short, tmp_path / "a", adapt_vehicle=True)
    cut = tmp_path / "cut.BIN"
    cut.write_bytes(raw[:150000])
    res = import_ardusub(cut, tmp_path / "b", adapt_vehicle=True)
    assert "incomplete record" in res["record"]["truncated"]


def _tlog_without(path_out, drop: str):
    """Rewrite small.tlog without one message type (tlog = 8-byte big-endian us time + packet)."""
    m = mavutil.mavlink_connection(str(TLOG))
    with open(path_out, "wb") as fh:
        while True:
            msg = m.recv_match()
            if msg is None:
                break
            if msg.get_type() in (drop, "BAD_DATA"):
                continue
            fh.write(struct.pack(">Q", int(msg._timestamp * 1e6)) + msg.get_msgbuf())


def test_tlog_without_attitude(tmp_path):
    p = tmp_path / "noatt.tlog"
    _tlog_without(p, "ATTITUDE")
    with pytest.raises(LogFormatError, match=r"noatt.tlog: no ATTITUDE message .*ATTITUDE.roll, pitch, yaw"):
        import_ardusub(p, tmp_path / "o", adapt_vehicle=True)


def test_not_a_log_and_unknown_suffix(tmp_path):
    g = tmp_path / "junk.BIN"
    g.write_bytes(b"not a dataflash log at all" * 10)
    with pytest.raises(LogFormatError, match="junk.BIN: no ATT message"):
        import_ardusub(g, tmp_path / "o")
    csv = tmp_path / "x.csv"
    csv.write_text("a")
    with pytest.raises(LogFormatError, match="unknown log type '.csv'"):
        import_ardusub(csv, tmp_path / "o")


def test_a_log_never_armed_says_so(tmp_path, monkeypatch):
    """A log whose vehicle is never armed (a public tlog of a bench session was) has no run by
    default: the error says why and what to give, not an empty list of skipped segments."""
    import uvsim.importers.ardusub_import as imp
    from uvsim.importers.ardusub import read_ardusub

    def unarmed(*a, **k):
        log = read_ardusub(*a, **k)
        log.armed = []
        return log

    monkeypatch.setattr(imp, "read_ardusub", unarmed)
    with pytest.raises(LogFormatError, match=r"small\.tlog: the vehicle is never armed in this log \(HEARTBEAT"):
        import_ardusub(TLOG, tmp_path / "out", adapt_vehicle=True)


def test_segments_yaml_errors_name_the_entry(tmp_path):
    seg = tmp_path / "seg.yaml"
    seg.write_text("segments:\n  - {start: 900, end: 910, dof: yaw}\n  - {start: 912, end: 905}\n")
    with pytest.raises(LogFormatError, match=r"seg.yaml: segments\[1\]: need finite start < end"):
        import_ardusub(TLOG, tmp_path / "o", segments=seg, adapt_vehicle=True)
    seg.write_text("segments:\n  - {start: 900, end: 910, dof: yawing}\n")
    with pytest.raises(LogFormatError, match=r"segments\[0\]: dof 'yawing'"):
        import_ardusub(TLOG, tmp_path / "o", segments=seg, adapt_vehicle=True)
    seg.write_text("segments:\n  - {start: 900, end: 910, stop: 3}\n")
    with pytest.raises(LogFormatError, match=r"unknown key\(s\) \['stop'\]"):
        import_ardusub(TLOG, tmp_path / "o", segments=seg, adapt_vehicle=True)


def test_missing_pymavlink_names_the_extra(tmp_path, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pymavlink.mavutil", None)  # import raises ImportError
    with pytest.raises(LogFormatError, match=r"pip install 'uvsim\[ardusub\]'"):
        import_ardusub(TLOG, tmp_path / "o")


# ------------------------------------------------------------------------ end to end
def test_cli_import_then_simulate_compare(tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["import", "ardusub", str(BIN), "--out", str(out), "--adapt-vehicle"]) == 0
    text = capsys.readouterr().out
    assert "small_armed_01" in text and "vehicle adapted" in text
    run = out / "small_armed_01.csv"
    plot = tmp_path / "cmp.png"
    assert main(["simulate", "--run", str(run), "--compare", "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    for ch in ("depth", "roll", "pitch", "yaw", "acc_z", "RMSE", "Fit %"):
        assert ch in text
    assert "x " not in text.split("channel")[1].split("plot")[0].replace("acc_x", "")
    assert plot.stat().st_size > 10_000
    assert main(["import", "ardusub", str(BIN), "--out", str(tmp_path / "e")]) == 2
    assert "T4_rear_left" in capsys.readouterr().err


def test_tlog_compares_and_bin_calibrates(tmp_path, capsys, monkeypatch):
    """The pairings the other end-to-end tests leave out: the .tlog through
    `simulate --compare`, the .BIN through `calibrate` (a fitted vehicle, or the verdict's
    refusal on this surface log; never a traceback)."""
    tl = tmp_path / "tl"
    assert main(["import", "ardusub", str(TLOG), "--out", str(tl), "--adapt-vehicle"]) == 0
    run = sorted(tl.glob("*.csv"))[0]
    capsys.readouterr()
    monkeypatch.chdir(tmp_path)  # the figure's default place is the working directory
    assert main(["simulate", "--run", str(run), "--compare"]) == 0
    assert (tmp_path / f"{run.stem}_compare.png").is_file()
    text = capsys.readouterr().out
    for ch in ("depth", "roll", "pitch", "RMSE", "Fit %"):
        assert ch in text
    bn = tmp_path / "bn"
    assert main(["import", "ardusub", str(BIN), "--out", str(bn), "--adapt-vehicle"]) == 0
    capsys.readouterr()
    out = tmp_path / "fit.yaml"
    rc = main(["calibrate", "--data", str(bn), "--population", "4", "--generations", "1", "--out", str(out)])
    err = capsys.readouterr().err
    if rc in (0, 3):  # better, or a trade-off (written, the channels named)
        assert load_vehicle(out).name
    else:
        assert rc == 2 and "verdict worse: " in err and not out.exists(), err


def test_calibrate_accepts_an_imported_dataset_with_a_dof_segment(tmp_path, capsys):
    """The imported dataset passes every input contract and the calibration runs; on this
    short surface log with a stand-in vehicle the fit predicts nothing (docs/import_export.md):
    when the verdict does not call it better, the message says that the starting model's simulation
    leaves the log, so windows were judged (exit 2, nothing written); never a silent success."""
    seg = tmp_path / "seg.yaml"
    seg.write_text(yaml.safe_dump({"segments": [{"start": 896.2, "end": 912.1, "dof": "yaw", "name": "yaw_1"}]}))
    ds = tmp_path / "ds"
    assert main(["import", "ardusub", str(TLOG), "--out", str(ds), "--segments", str(seg), "--adapt-vehicle"]) == 0
    out = tmp_path / "fit.yaml"
    rc = main(["calibrate", "--data", str(ds), "--population", "4", "--generations", "1", "--out", str(out)])
    if rc in (0, 3):  # better, or a trade-off (written, the channels named)
        assert load_vehicle(out).name
    else:
        err = capsys.readouterr().err
        assert rc == 2 and "verdict worse: " in err and "free simulation of whole runs leaves the training data" in err \
            and "judged on predictions over windows" in err, err
        assert not out.exists()


def test_calibrate_accepts_the_default_mixed_import(tmp_path, capsys):
    """The default import marks every armed interval `dof: mixed`; issue 14 calibrates such
    runs with the joint stage alone. On this 2-3 Hz surface log the fit cannot predict the
    motion, and the verdict and its caveat say so (exit 2, nothing written); what must not happen is
    the old "no training run is marked with a dof" refusal or a traceback."""
    ds = tmp_path / "ds"
    assert main(["import", "ardusub", str(TLOG), "--out", str(ds), "--adapt-vehicle"]) == 0
    capsys.readouterr()
    out = tmp_path / "fit.yaml"
    rc = main(["calibrate", "--data", str(ds), "--population", "4", "--generations", "1", "--out", str(out)])
    err = capsys.readouterr().err
    assert "no training run" not in err
    if rc in (0, 3):  # better, or a trade-off (written, the channels named)
        assert load_vehicle(out).name
    else:
        assert rc == 2 and "verdict worse: " in err and "free simulation of whole runs leaves the training data" in err \
            and "judged on predictions over windows" in err, err
        assert not out.exists()
