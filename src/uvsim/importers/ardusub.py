"""ArduSub logs (.BIN DataFlash, .tlog MAVLink telemetry) -> uvsim dataset.

Read with pymavlink (``uvsim[ardusub]``).  What goes where (docs/import_export.md):

=================  ==========================================  =====================================
column             .BIN (DataFlash)                            .tlog (MAVLink)
=================  ==========================================  =====================================
roll, pitch, yaw   ATT.Roll/Pitch/Yaw (deg -> rad)             ATTITUDE.roll/pitch/yaw (rad)
p, q, r            IMU.GyrX/GyrY/GyrZ (rad/s)                  ATTITUDE.rollspeed/pitchspeed/yawspeed
acc_x..acc_z       IMU.AccX/AccY/AccZ (m/s^2; level at rest    SCALED_IMU[n].xacc.. (mG x 9.80665e-3)
                   reads (0, 0, -g), like the log format)
depth              BARO[BARO_PRIMARY].Press (Pa)               SCALED_PRESSURE[n].press_abs (hPa)
x, y (, z)         VISP.PX/PY/PZ, else XKF1.PN/PE when the     VISION_POSITION_ESTIMATE.x/y/z, else
                   EKF has a horizontal position source        LOCAL_POSITION_NED.x/y (same rule)
pwm_1..pwm_n       RCOU.C<servo of Motor i>                    SERVO_OUTPUT_RAW.servo<n>_raw
voltage            BAT.Volt (instance 0)                       SYS_STATUS.voltage_battery (mV)
=================  ==========================================  =====================================

Depth: ``(p - p_surface) / (rho g)`` with g = 9.80665 m/s^2 and rho = 1000 kg/m^3 x the
specific gravity (ArduPilot ``BARO_SPEC_GRAV``: 1.00 fresh, 1.024 salt water, AP_Baro.h);
``p_surface`` is given, or the median pressure before the first arming, or the
autopilot's own ground calibration ``BAROn_GND_PRESS``, in that order (the manifest says
which).  Time base: the autopilot's boot clock in seconds (DataFlash ``TimeUS``; MAVLink
``time_boot_ms`` / ``time_usec``); tlog messages without a boot time (SYS_STATUS,
HEARTBEAT, VISION_POSITION_ESTIMATE) are placed on it through the ground station's
receive time (median offset, reported with its spread).
"""
from __future__ import annotations

import contextlib
import hashlib
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from uvsim.errors import LogFormatError
from uvsim.schema import whole_number
from uvsim.vehicle_schema import check_water_density
from uvsim.importers import require
from uvsim.importers.flight_modes import closed_loop_over
from uvsim.importers.timeline import Stream

G_BARO = 9.80665  # m/s^2, standard gravity used to turn pressure into depth
WATER = {"fresh": 1.0, "salt": 1.024}  # specific gravity, ArduPilot AP_Baro.h (_specific_gravity)
MG_TO_MS2 = 9.80665e-3  # MAVLink SCALED_IMU accelerations are in mG
#: Surface (air) pressure accepted for ``surface_pressure``, Pa: sea-level records span 870-1084 hPa
#: (WMO: Typhoon Tip 1979, Agata 1968), and a lake at 4000 m sits near 620 hPa (ISA); a value
#: outside is in another unit (hPa/mbar, kPa, psi), not air pressure in Pa.
SURFACE_PRESSURE_PA = (55_000.0, 110_000.0)
ARMED_FLAG = 128  # MAV_MODE_FLAG_SAFETY_ARMED in HEARTBEAT.base_mode
BIN_TYPES = ["ATT", "IMU", "BARO", "XKF1", "VISP", "RCOU", "BAT", "ARM", "EV", "PARM", "MSG", "MODE"]
TLOG_TYPES = ["ATTITUDE", "SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3", "SCALED_PRESSURE", "SCALED_PRESSURE2",
              "SCALED_PRESSURE3", "LOCAL_POSITION_NED", "VISION_POSITION_ESTIMATE", "SERVO_OUTPUT_RAW",
              "SYS_STATUS", "HEARTBEAT", "PARAM_VALUE", "STATUSTEXT", "RAW_IMU"]


@dataclass
class ArduSubLog:
    """What the importer took from one log."""

    path: Path
    kind: str                       # "bin" or "tlog"
    params: dict
    streams: list
    armed: list                     # [(start_s, end_s)] on the time base
    span: tuple                     # (first, last) time of the log, s
    meta: dict = field(default_factory=dict)
    motor_servo: dict = field(default_factory=dict)   # motor -> servo channel
    modes: list = field(default_factory=list)         # [(time_s, flight mode number)] on the time base

    def closed_loop(self, start: float, end: float) -> bool | None:
        """Whether the vehicle flew ``start..end`` under a mode that holds some state (True), in
        MANUAL (False), or not known (None: no mode logged, a mode of neither kind, or both)."""
        return closed_loop_over(self.modes, start, end)

    @property
    def frame_config(self) -> int:
        v = self.params.get("FRAME_CONFIG")
        if v is None:
            raise LogFormatError(f"{self.path}: the log has no FRAME_CONFIG parameter; the thruster layout "
                                 "cannot be checked")
        return int(v)

    def directions(self) -> dict:
        return {m: float(self.params.get(f"MOT_{m}_DIRECTION", 1.0)) for m in self.motor_servo}


# ---------------------------------------------------------------------------- reading
def _collect(path: Path, kind: str) -> tuple[dict, dict]:
    mavutil = require("pymavlink.mavutil", "ardusub", f"{path}: reading ArduSub logs")
    types = BIN_TYPES if kind == "bin" else TLOG_TYPES
    out: dict = {t: [] for t in types}
    info: dict = {}
    noise = io.StringIO()
    try:
        with contextlib.redirect_stdout(noise):
            conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
            while True:
                msg = conn.recv_match(type=types)
                if msg is None:
                    break
                d = msg.to_dict()
                if kind == "tlog":
                    d["_timestamp"] = float(getattr(msg, "_timestamp", np.nan))
                    d["_src"] = (msg.get_srcSystem(), msg.get_srcComponent())
                out[msg.get_type()].append(d)
    except Exception as exc:  # pymavlink raises many unrelated types on corrupt input
        raise LogFormatError(f"{path}: cannot be read as an ArduSub {kind.upper()} log by pymavlink: "
                             f"{type(exc).__name__}: {exc}") from None
    bad = noise.getvalue().count("bad header")
    if bad:
        info["skipped_bad_headers"] = bad
    if kind == "bin":
        off, size = getattr(conn, "offset", None), getattr(conn, "data_len", None)
        if off is not None and size is not None and off < size:
            info["truncated"] = f"the last {size - off} bytes are an incomplete record (log cut off at byte {off})"
    return out, info


def _arr(msgs, name, where) -> np.ndarray:
    try:
        return np.array([float(m[name]) for m in msgs])
    except KeyError:
        raise LogFormatError(f"{where}: field {name!r} missing (fields: {sorted(msgs[0])})") from None
    except (TypeError, ValueError):
        raise LogFormatError(f"{where}: field {name!r} is not numeric") from None


def _need(msgs, typ, path, purpose):
    if not msgs:
        raise LogFormatError(f"{path}: no {typ} message{purpose}")
    return msgs


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def _unwrap_u32(t_us: np.ndarray) -> np.ndarray:
    """MAVLink ``time_usec`` of SERVO_OUTPUT_RAW is uint32 (wraps after 71.6 min)."""
    jumps = np.concatenate([[0], np.cumsum(np.diff(t_us) < -2.0 ** 31)])
    return t_us + jumps * 2.0 ** 32


def _check_surface_pressure(p) -> None:
    lo, hi = SURFACE_PRESSURE_PA
    try:
        p = float(p)
    except (TypeError, ValueError):
        raise LogFormatError(f"surface pressure {p!r}: expected a number in Pa") from None
    if lo <= p <= hi:
        return
    hint = ""
    for unit, factor in (("hPa (mbar)", 100.0), ("kPa", 1000.0), ("psi", 6894.76), ("bar", 1e5)):
        if lo <= p * factor <= hi:
            hint = f"; it looks like {unit}: give {p * factor:.0f} Pa"
            break
    raise LogFormatError(f"surface pressure {p:g} Pa: expected an air pressure between {lo:.0f} and {hi:.0f} Pa"
                         f"{hint}")


def read_ardusub(path, *, water: str | float | None = None, surface_pressure: float | None = None,
                 imu_instance: int = 0, progress=None) -> ArduSubLog:
    """Read one ArduSub log into streams (see the module docstring).

    Parameters
    ----------
    path : .BIN (DataFlash) or .tlog (MAVLink) file.
    water : "fresh", "salt", a density in kg/m^3, or None (the log's BARO_SPEC_GRAV, else fresh).
    surface_pressure : Pa, overrides the pre-dive / calibrated surface pressure.
    imu_instance : which IMU (DataFlash IMU.I) gives rates and accelerations.
    progress : the reading as a stage (:func:`uvsim.progress.as_progress`).
    """
    path = Path(path)
    whole_number(imu_instance, "imu_instance (--imu)", minimum=0, error=LogFormatError,
                 hint="; DataFlash numbers its IMUs 0, 1, 2")
    if surface_pressure is not None:
        _check_surface_pressure(surface_pressure)
    if not path.is_file():
        raise LogFormatError(f"{path}: log file does not exist")
    suffix = path.suffix.lower()
    if suffix in (".bin", ".log"):
        kind = "bin"
    elif suffix == ".tlog":
        kind = "tlog"
    else:
        raise LogFormatError(f"{path}: unknown log type {path.suffix!r}; expected .BIN (DataFlash) or .tlog (MAVLink)")
    from uvsim.progress import as_progress

    with as_progress(progress).stage(f"reading {path.name} ({path.stat().st_size / 1e6:.1f} MB) with pymavlink"):
        msgs, info = _collect(path, kind)
    reader = _bin_streams if kind == "bin" else _tlog_streams
    log = reader(path, msgs, water, surface_pressure, imu_instance)
    log.meta.update(info)
    log.meta["source"] = {"file": path.name, "format": "DataFlash .BIN" if kind == "bin" else "MAVLink .tlog",
                          "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "bytes": path.stat().st_size}
    return log


def _params(pairs, where) -> tuple[dict, list]:
    params, changed = {}, set()
    for name, value in pairs:
        if name in params and params[name] != value:
            changed.add(name)
        params[name] = value
    return params, sorted(changed)


def _density(water, params, where) -> tuple[float, str]:
    if water is None:
        sg = params.get("BARO_SPEC_GRAV")
        if sg is not None and float(sg) > 0:
            return 1000.0 * float(sg), f"log parameter BARO_SPEC_GRAV = {float(sg):g}"
        return 1000.0 * WATER["fresh"], "fresh water (no BARO_SPEC_GRAV in the log)"
    if isinstance(water, str) and water in WATER:
        return 1000.0 * WATER[water], f"{water} water (specific gravity {WATER[water]:g}, ArduPilot AP_Baro.h)"
    try:
        rho = float(water)
    except (TypeError, ValueError):
        raise LogFormatError(f"{where}: water {water!r}: expected fresh, salt or a density in kg/m^3") from None
    check_water_density(rho, f"{where}: water density", LogFormatError)
    return rho, f"given density {rho:g} kg/m^3"


def _depth_stream(t, press_pa, source, params, instance, armed, water, surface_pressure, where) -> Stream:
    rho, rho_from = _density(water, params, where)
    if surface_pressure is not None:
        p0, p0_from = float(surface_pressure), "given (--surface-pressure)"
    else:
        first_arm = armed[0][0] if armed else None
        pre = press_pa[t < first_arm] if first_arm is not None else np.array([])
        gnd = params.get(f"BARO{instance + 1}_GND_PRESS")
        if pre.size >= 3:
            p0, p0_from = float(np.median(pre)), f"median of the {pre.size} samples before the first arming"
        elif gnd is not None and float(gnd) > 0:
            p0, p0_from = float(gnd), (f"autopilot ground calibration BARO{instance + 1}_GND_PRESS (fewer than 3 "
                                       "pressure samples before the first arming)")
        else:
            raise LogFormatError(f"{where}: {source}: no surface pressure: fewer than 3 samples before arming and no "
                                 f"BARO{instance + 1}_GND_PRESS parameter; pass --surface-pressure PA")
    depth = (press_pa - p0) / (rho * G_BARO)
    notes = [f"depth = (p - {p0:.1f} Pa) / ({rho:g} kg/m^3 x {G_BARO} m/s^2); surface pressure: {p0_from}; "
             f"density: {rho_from}"]
    return Stream("depth", source, t, {"depth": depth}, notes=notes)


def _position_ok(xy: np.ndarray, params: dict) -> tuple[bool, str]:
    src = params.get("EK3_SRC1_POSXY")
    if src is not None and float(src) == 0:
        return False, "EK3_SRC1_POSXY = 0 (no horizontal position source)"
    if xy.size == 0 or np.all(xy == xy[:1]):
        return False, "the EKF's horizontal position never changes in this log (no position fix)"
    return True, f"EKF horizontal position (EK3_SRC1_POSXY = {src})"


def _armed_from_events(arm, ev, span) -> tuple[list, str]:
    events = [(m["TimeUS"] / 1e6, bool(m["ArmState"])) for m in arm]
    how = "ARM records"
    if not events:
        events = [(m["TimeUS"] / 1e6, m["Id"] == 10) for m in ev if m["Id"] in (10, 11)]
        how = "EV records 10/11"
    if not events:
        return [span], "no ARM/EV record: arming state unknown, the whole log is one segment"
    if not events[0][1]:
        how += "; the first record is a disarm, so the vehicle was armed when the log started"
    return _intervals(events, span, transitions=True), how


def _intervals(events, span, *, transitions: bool) -> list:
    """Armed intervals from ``[(t, armed)]``: arm/disarm *transitions* (DataFlash ARM/EV;
    a first disarm means armed since the log started) or periodic *states* (HEARTBEAT)."""
    out, start = [], None
    if transitions and not events[0][1]:
        start = span[0]
    for t, armed in events:
        if armed and start is None:
            start = t
        elif not armed and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, span[1]))
    return out


def _bin_streams(path, msgs, water, surface_pressure, imu_instance) -> ArduSubLog:
    w = str(path)
    params, changed = _params(((m["Name"], m["Value"]) for m in msgs["PARM"]), w)
    att = _need(msgs["ATT"], "ATT", path, " (attitude: ATT.Roll, ATT.Pitch, ATT.Yaw)")
    t_att = _arr(att, "TimeUS", f"{w}: ATT") / 1e6
    all_t = [t_att] + [_arr(msgs[k], "TimeUS", f"{w}: {k}") / 1e6 for k in ("RCOU", "BARO", "IMU") if msgs[k]]
    span = (min(a.min() for a in all_t), max(a.max() for a in all_t))
    armed, armed_how = _armed_from_events(msgs["ARM"], msgs["EV"], span)
    streams = [Stream("attitude", "ATT.Roll, ATT.Pitch, ATT.Yaw (deg)", t_att, {
        "roll": np.radians(_arr(att, "Roll", f"{w}: ATT")),
        "pitch": np.radians(_arr(att, "Pitch", f"{w}: ATT")),
        "yaw": _wrap(np.radians(_arr(att, "Yaw", f"{w}: ATT")))}, notes=["deg -> rad; yaw wrapped to (-pi, pi]"])]
    imu = [m for m in msgs["IMU"] if int(m.get("I", 0)) == imu_instance]
    have = sorted({int(m.get("I", 0)) for m in msgs["IMU"]})
    if have and not imu:  # not a silent drop of the rates and accelerations
        raise LogFormatError(f"{w}: IMU instance {imu_instance} (--imu) is not in the log; it has IMU "
                             f"{', '.join(map(str, have))}: choose one of those")
    if imu:
        src = f"IMU[I={imu_instance}].GyrX..GyrZ (rad/s), AccX..AccZ (m/s^2)"
        streams.append(Stream("imu", src, _arr(imu, "TimeUS", f"{w}: IMU") / 1e6, {
            **{c: _arr(imu, f, f"{w}: IMU") for c, f in zip(("p", "q", "r"), ("GyrX", "GyrY", "GyrZ"))},
            **{c: _arr(imu, f, f"{w}: IMU") for c, f in zip(("acc_x", "acc_y", "acc_z"), ("AccX", "AccY", "AccZ"))}}))
    inst = int(params.get("BARO_PRIMARY", 0))
    baro = [m for m in msgs["BARO"] if int(m.get("I", 0)) == inst]
    if baro:
        tb = _arr(baro, "TimeUS", f"{w}: BARO") / 1e6
        streams.append(_depth_stream(tb, _arr(baro, "Press", f"{w}: BARO"), f"BARO[I={inst}].Press (Pa)", params,
                                     inst, armed, water, surface_pressure, f"{w}: BARO"))
    pos_note = _bin_position(msgs, params, streams, w)
    motor_servo = _motor_stream(params, w, "RCOU", msgs["RCOU"], lambda m: m["TimeUS"] / 1e6,
                                lambda n: f"C{n}", streams)
    bat = [m for m in msgs["BAT"] if int(m.get("Instance", m.get("Inst", 0))) == 0]
    if bat:
        streams.append(Stream("battery", "BAT[0].Volt (V)", _arr(bat, "TimeUS", f"{w}: BAT") / 1e6,
                              {"voltage": _arr(bat, "Volt", f"{w}: BAT")}, role="voltage"))
    firmware = next((m["Message"] for m in msgs["MSG"] if "ArduSub" in str(m.get("Message", ""))), None)
    meta = {"time_base": "autopilot boot clock, s (DataFlash TimeUS / 1e6)", "armed_from": armed_how,
            "position": pos_note, "firmware": firmware, "params_changed_during_log": changed}
    modes = [(float(m["TimeUS"]) / 1e6, int(m.get("ModeNum", m.get("Mode", -1)))) for m in msgs["MODE"]]
    return ArduSubLog(path, "bin", params, streams, armed, span, meta, motor_servo, modes)


def _bin_position(msgs, params, streams, w) -> str:
    if msgs["VISP"]:
        v = msgs["VISP"]
        streams.append(Stream("position", "VISP.PX, PY, PZ (m, NED)", _arr(v, "TimeUS", f"{w}: VISP") / 1e6,
                              {c: _arr(v, f, f"{w}: VISP") for c, f in zip("xyz", ("PX", "PY", "PZ"))}))
        return "VISP (external navigation position)"
    xkf = [m for m in msgs["XKF1"] if int(m.get("C", 0)) == 0]
    if not xkf:
        return "none (no VISP or XKF1 records)"
    xy = np.stack([_arr(xkf, "PN", f"{w}: XKF1"), _arr(xkf, "PE", f"{w}: XKF1")], axis=1)
    ok, why = _position_ok(xy, params)
    if ok:
        streams.append(Stream("position", "XKF1[C=0].PN, PE (m, NED)", _arr(xkf, "TimeUS", f"{w}: XKF1") / 1e6,
                              {"x": xy[:, 0], "y": xy[:, 1]}))
        return why
    return f"not written: {why}"


def _motor_stream(params, w, typ, msgs, time_of, field_of, streams) -> dict:
    from uvsim.importers.ardusub_frames import motor_outputs

    motor_servo = motor_outputs(params, w)
    if not msgs:
        raise LogFormatError(f"{w}: no {typ} message (motor outputs); the importer needs the thruster commands")
    t = np.array([time_of(m) for m in msgs], float)
    cols, src = {}, []
    for motor in sorted(motor_servo):
        f = field_of(motor_servo[motor])
        vals = _arr(msgs, f, f"{w}: {typ}")
        cols[f"pwm_{motor}"] = vals
        src.append(f"Motor{motor}={typ}.{f}")
    streams.append(Stream("motors", ", ".join(src) + " (us)", t, cols, role="input"))
    return motor_servo


def _tlog_streams(path, msgs, water, surface_pressure, imu_instance) -> ArduSubLog:
    w = str(path)
    att_all = _need(msgs["ATTITUDE"], "ATTITUDE", path, " (the importer needs ATTITUDE.roll, pitch, yaw)")
    srcs = [m["_src"] for m in att_all]
    sysid = max(set(srcs), key=srcs.count)[0]

    def mine(typ):
        return [m for m in msgs[typ] if m["_src"] == (sysid, 1)]

    att = mine("ATTITUDE")
    if not att:
        raise LogFormatError(f"{w}: no ATTITUDE message from the autopilot (system {sysid}, component 1)")
    tb = _arr(att, "time_boot_ms", f"{w}: ATTITUDE") / 1e3
    off = np.array([m["_timestamp"] for m in att]) - tb
    offset = float(np.median(off))
    spread = float(np.percentile(off, 95) - np.percentile(off, 5))

    def gcs_time(ms):
        return np.array([m["_timestamp"] for m in ms]) - offset

    params, changed = _params(((m["param_id"], m["param_value"]) for m in mine("PARAM_VALUE")), w)
    hb = [m for m in mine("HEARTBEAT")]
    span = (float(tb.min()), float(tb.max()))
    modes = []
    if hb:
        modes = [(float(t), int(m["custom_mode"])) for t, m in zip(gcs_time(hb), hb)]
        armed = _intervals(list(zip(gcs_time(hb), [bool(m["base_mode"] & ARMED_FLAG) for m in hb])), span,
                           transitions=False)
        armed_how = "HEARTBEAT.base_mode armed flag (1 Hz; placed on the boot clock by GCS receive time)"
    else:
        armed, armed_how = [span], "no HEARTBEAT from the autopilot: arming state unknown, the whole log is one segment"
    streams = [Stream("attitude", "ATTITUDE.roll, pitch, yaw (rad), rollspeed, pitchspeed, yawspeed (rad/s)", tb, {
        "roll": _arr(att, "roll", f"{w}: ATTITUDE"), "pitch": _arr(att, "pitch", f"{w}: ATTITUDE"),
        "yaw": _wrap(_arr(att, "yaw", f"{w}: ATTITUDE")),
        "p": _arr(att, "rollspeed", f"{w}: ATTITUDE"), "q": _arr(att, "pitchspeed", f"{w}: ATTITUDE"),
        "r": _arr(att, "yawspeed", f"{w}: ATTITUDE")})]
    notes = []
    for typ in ("SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3"):
        imu = mine(typ)
        if imu and any(m["zacc"] != 0 for m in imu):
            streams.append(Stream("imu", f"{typ}.xacc, yacc, zacc (mG)", _arr(imu, "time_boot_ms", f"{w}: {typ}") / 1e3,
                                  {c: _arr(imu, f, f"{w}: {typ}") * MG_TO_MS2
                                   for c, f in zip(("acc_x", "acc_y", "acc_z"), ("xacc", "yacc", "zacc"))},
                                  notes=["mG x 9.80665e-3 -> m/s^2"]))
            break
        if imu:
            notes.append(f"{typ} present but all-zero (no such IMU): not used")
    if mine("RAW_IMU"):
        notes.append("RAW_IMU not used (MAVLink defines its units as raw sensor counts)")
    inst = int(params.get("BARO_PRIMARY", 0))
    ptyp = ("SCALED_PRESSURE", "SCALED_PRESSURE2", "SCALED_PRESSURE3")[inst]
    pr = mine(ptyp)
    if pr:
        streams.append(_depth_stream(_arr(pr, "time_boot_ms", f"{w}: {ptyp}") / 1e3,
                                     _arr(pr, "press_abs", f"{w}: {ptyp}") * 100.0, f"{ptyp}.press_abs (hPa)",
                                     params, inst, armed, water, surface_pressure, f"{w}: {ptyp}"))
    vis = mine("VISION_POSITION_ESTIMATE")
    if vis:
        streams.append(Stream("position", "VISION_POSITION_ESTIMATE.x, y, z (m, NED)", gcs_time(vis),
                              {c: _arr(vis, c, f"{w}: VISION_POSITION_ESTIMATE") for c in "xyz"},
                              notes=["placed on the boot clock by GCS receive time"]))
        pos_note = "VISION_POSITION_ESTIMATE (external navigation)"
    else:
        lp = mine("LOCAL_POSITION_NED")
        xy = np.stack([_arr(lp, c, f"{w}: LOCAL_POSITION_NED") for c in "xy"], axis=1) if lp else np.zeros((0, 2))
        ok, why = _position_ok(xy, params)
        if ok:
            streams.append(Stream("position", "LOCAL_POSITION_NED.x, y (m, NED)",
                                  _arr(lp, "time_boot_ms", f"{w}: LOCAL_POSITION_NED") / 1e3,
                                  {"x": xy[:, 0], "y": xy[:, 1]}))
        pos_note = why if ok else f"not written: {why}"
    servo = [m for m in mine("SERVO_OUTPUT_RAW") if int(m.get("port", 0)) == 0]
    servo_t = _unwrap_u32(np.array([m["time_usec"] for m in servo], float)) / 1e6 if servo else np.array([])
    tmap = {id(m): tt for m, tt in zip(servo, servo_t)}
    motor_servo = _motor_stream(params, w, "SERVO_OUTPUT_RAW", servo, lambda m: tmap[id(m)],
                                lambda n: f"servo{n}_raw", streams)
    sys = [m for m in mine("SYS_STATUS") if m["voltage_battery"] not in (0, 65535)]
    if sys:
        streams.append(Stream("battery", "SYS_STATUS.voltage_battery (mV)", gcs_time(sys),
                              {"voltage": _arr(sys, "voltage_battery", f"{w}: SYS_STATUS") / 1000.0},
                              role="voltage", notes=["placed on the boot clock by GCS receive time"]))
    firmware = next((m["text"] for m in mine("STATUSTEXT") if "ArduSub" in str(m.get("text", ""))), None)
    meta = {"time_base": "autopilot boot clock, s (MAVLink time_boot_ms / time_usec)",
            "gcs_clock": {"offset_s": offset, "spread_s": spread,
                          "note": "GCS receive time - boot time over ATTITUDE; used for messages without a boot time"},
            "vehicle_system_id": int(sysid), "armed_from": armed_how, "position": pos_note, "firmware": firmware,
            "params_changed_during_log": changed}
    if notes:
        meta["notes"] = notes
    return ArduSubLog(path, "tlog", params, streams, armed, span, meta, motor_servo, modes)
