"""ROS 1 / ROS 2 bags -> uvsim dataset, driven by a topic map (``uvsim import bag``).

Read with rosbags (``uvsim[ros]``; no ROS installation needed; ROS 1 ``.bag`` files and
ROS 2 bag directories).  The map (YAML) names, per stream, a topic and how to read it::

    vehicle: bluerov2_heavy          # default vehicle of the dataset
    frame: enu_flu                   # default frame of pose/imu/odometry topics: enu_flu (ROS REP-103) or ned_frd
    stamp: header                    # header (msg.header.stamp, default), bag (receive time) or a field, see below
    types: {"mavros_msgs/msg/RCOut": "std_msgs/Header header\\nuint16[] channels"}   # only if the bag lacks them
    streams:
      pose:     {topic: /mocap/rov/pose, type: pose}                 # PoseStamped: position + attitude
      imu:      {topic: /mavros/imu/data, type: imu, use: [rates, acceleration]}
      depth:    {topic: /mavros/imu/static_pressure, type: pressure, surface_pressure: 101325, density: 1000}
      motors:   {topic: /mavros/rc/out, type: pwm, field: channels, elements: [0, 1, 2, 3, 4, 5, 6, 7]}
      battery:  {topic: /mavros/battery, type: voltage, field: voltage}
      mode:     {topic: /mavros/state, type: mode}                   # flight mode -> closed_loop

Stream types:

* ``pose`` (geometry_msgs PoseStamped / PoseWithCovarianceStamped / TransformStamped,
  ``field`` = path to the Pose, default ``pose``): ``x, y, z`` and ``qw..qz``;
* ``odometry`` (nav_msgs Odometry; px4_msgs VehicleOdometry with ``frame: ned_frd`` and
  fields ``position``, ``q``, ``velocity``, ``angular_velocity``): position, attitude, body
  velocities ``u, v, w`` and rates ``p, q, r`` (``use`` selects);
* ``imu`` (sensor_msgs Imu): attitude (``orientation``), ``p, q, r``, ``acc_x..acc_z``
  (``use``: any of attitude, rates, acceleration; default rates and acceleration);
* ``pressure`` (sensor_msgs FluidPressure, Pa, or ``field``): ``depth = (p - surface_pressure)
  / (density x 9.80665)``; ``depth`` (a depth in m at ``field``, default ``data``);
* ``pwm`` / ``thrust``: an array field (``field``, default ``channels`` for pwm, ``data``
  otherwise) and the ``elements`` that are thrusters 1..n, with ``scale`` and ``offset``
  (value -> ``offset + scale x value``; PX4 ActuatorMotors ``control`` in [-1, 1] maps
  to PWM with offset 1500 and scale 400 on a 1100-1900 us ESC setup).  Samples with a
  NaN element (PX4: motor disarmed) are dropped and counted;
* ``voltage``: a battery voltage (V) at ``field`` (sensor_msgs BatteryState ``voltage``);
* ``fields``: a generic ``{column: field path}`` mapping for anything else;
* ``mode``: the autopilot's flight mode, a string at ``field`` (default ``mode``: mavros_msgs
  State).  It is no column: each run's ``closed_loop`` in the manifest comes from it
  (:mod:`uvsim.importers.flight_modes`): true where every mode over the run is one of
  ``closed_loop_modes``, false where every one is one of ``open_loop_modes`` (defaults: ArduSub's
  mode names, MANUAL open loop and every mode that holds a state closed loop), not written
  otherwise.  A report up to one median reporting interval after a run's start stands for the
  mode at the start.

Any stream but the thruster commands may say ``optional: true``: a map that fits several setups
then skips a topic the bag lacks, and the import record lists it (``optional_streams_missing``).

Frames: ``enu_flu`` topics are converted to uvsim's NED/FRD (positions ``(n, e, d) =
(y, x, -z)``, attitude ``R_ned_frd = T R_enu_flu S``, body vectors ``(x, -y, -z)``; a ROS
accelerometer at rest reads +g up, which becomes (0, 0, -g) as the log format wants);
``ned_frd`` topics are taken as they are.  Field paths are dotted, with ``[i]`` for an
array element.  Time: seconds from the first message of any mapped topic (the
manifest's ``import.time_base`` gives the absolute start).
"""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from uvsim.errors import LogFormatError
from uvsim.files import load_yaml
from uvsim.importers import require
from uvsim.importers.build import build_runs
from uvsim.importers.flight_modes import CLOSED_LOOP_NAMES, OPEN_LOOP_NAMES, closed_loop_over, mode_name, mode_record
from uvsim.importers.segments import Segment, load_segments, write_imported_dataset
from uvsim.importers.timeline import MERGE_TOL_S, Stream
from uvsim.kinematics import quat_multiply
from uvsim.log_aliases import format_name
from uvsim.log_columns import FORMAT_COLUMNS

TYPES = ("pose", "odometry", "imu", "pressure", "depth", "pwm", "thrust", "voltage", "fields", "mode")
FRAMES = ("enu_flu", "ned_frd")
G0 = 9.80665
_Q_T = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])  # ENU -> NED: pi about (1, 1, 0)/sqrt(2)
_Q_S = np.array([0.0, 1.0, 0.0, 0.0])                      # FRD -> FLU: pi about x
_STREAM_KEYS = {"topic", "type", "field", "frame", "use", "elements", "scale", "offset", "surface_pressure",
                "density", "stamp", "fields", "closed_loop_modes", "open_loop_modes", "optional"}


def _get(msg, path: str, where: str):
    obj = msg
    for part in path.replace("]", "").split("."):
        name, _, idx = part.partition("[")
        if name:
            if not hasattr(obj, name):
                fields = [f for f in getattr(obj, "__dataclass_fields__", {})] or [a for a in dir(obj) if not a.startswith("_")]
                raise LogFormatError(f"{where}: field {path!r} not found ({name!r} is not one of {fields})")
            obj = getattr(obj, name)
        if idx:
            try:
                obj = obj[int(idx)]
            except (IndexError, TypeError, ValueError):
                raise LogFormatError(f"{where}: field {path!r}: element [{idx}] does not exist") from None
    return obj


def _stamp(msg, t_bag: int, spec, where: str) -> int:
    """Message time in integer nanoseconds (epoch stamps do not fit a float at 1 ns)."""
    if spec == "bag":
        return int(t_bag)
    if spec == "header":
        s = _get(msg, "header.stamp", where)
        return int(s.sec) * 1_000_000_000 + int(s.nanosec)
    return int(round(float(_get(msg, spec["field"], where)) * float(spec.get("scale", 1.0)) * 1e9))


def _vec(obj, names=("x", "y", "z")) -> list:
    if hasattr(obj, names[0]):
        return [float(getattr(obj, n)) for n in names]
    return [float(v) for v in np.asarray(obj, float).ravel()]


def _quat(obj) -> list:
    """(w, x, y, z) from a geometry_msgs Quaternion or a (w, x, y, z) array (px4_msgs)."""
    if hasattr(obj, "w"):
        return [float(obj.w), float(obj.x), float(obj.y), float(obj.z)]
    return [float(v) for v in np.asarray(obj, float).ravel()]


def _to_ned_frd(cols: dict, frame: str) -> dict:
    if frame == "ned_frd":
        return cols
    out = dict(cols)
    if "x" in cols:
        out["x"], out["y"], out["z"] = cols["y"], cols["x"], -cols["z"]
    if "qw" in cols:
        q = np.stack([cols[c] for c in ("qw", "qx", "qy", "qz")], axis=1)
        q = quat_multiply(quat_multiply(np.broadcast_to(_Q_T, q.shape), q), np.broadcast_to(_Q_S, q.shape))
        q = q * np.where(q[:, :1] < 0, -1.0, 1.0)
        out.update(qw=q[:, 0], qx=q[:, 1], qy=q[:, 2], qz=q[:, 3])
    for a, b, c in (("u", "v", "w"), ("p", "q", "r"), ("acc_x", "acc_y", "acc_z")):
        if a in cols:
            out[b], out[c] = -cols[b], -cols[c]
    return out


def _extract(kind: str, spec: dict, msgs: list, where: str, columns: list) -> tuple[dict, list]:
    """Column arrays of one stream; ``columns`` names the pwm/thrust columns for arrays."""
    notes = []
    rows: dict[str, list] = {}

    def put(c, v):
        rows.setdefault(c, []).append(v)

    use = set(spec.get("use") or {"imu": ["rates", "acceleration"], "odometry": ["position", "attitude", "velocity",
                                                                                    "rates"]}.get(kind, []))
    for m in msgs:
        if kind == "pose":
            p = _get(m, spec.get("field", "pose"), where)
            pos = _get(p, "translation", where) if hasattr(p, "translation") else _get(p, "position", where)
            rot = _get(p, "rotation", where) if hasattr(p, "rotation") else _get(p, "orientation", where)
            for c, v in zip("xyz", _vec(pos)):
                put(c, v)
            for c, v in zip(("qw", "qx", "qy", "qz"), _quat(rot)):
                put(c, v)
        elif kind == "odometry":
            f = {"position": "pose.pose.position", "attitude": "pose.pose.orientation", "velocity": "twist.twist.linear",
                 "rates": "twist.twist.angular"}
            f.update(spec.get("fields") or {})
            if "position" in use:
                for c, v in zip("xyz", _vec(_get(m, f["position"], where))):
                    put(c, v)
            if "attitude" in use:
                for c, v in zip(("qw", "qx", "qy", "qz"), _quat(_get(m, f["attitude"], where))):
                    put(c, v)
            if "velocity" in use:
                for c, v in zip("uvw", _vec(_get(m, f["velocity"], where))):
                    put(c, v)
            if "rates" in use:
                for c, v in zip("pqr", _vec(_get(m, f["rates"], where))):
                    put(c, v)
        elif kind == "imu":
            if "attitude" in use:
                for c, v in zip(("qw", "qx", "qy", "qz"), _quat(_get(m, "orientation", where))):
                    put(c, v)
            if "rates" in use:
                for c, v in zip("pqr", _vec(_get(m, "angular_velocity", where))):
                    put(c, v)
            if "acceleration" in use:
                for c, v in zip(("acc_x", "acc_y", "acc_z"), _vec(_get(m, "linear_acceleration", where))):
                    put(c, v)
        elif kind in ("pressure", "depth", "voltage"):
            default = {"pressure": "fluid_pressure", "depth": "data", "voltage": "voltage"}[kind]
            put("value", float(_get(m, spec.get("field", default), where)))
        elif kind in ("pwm", "thrust"):
            arr = np.asarray(_get(m, spec.get("field", "channels" if kind == "pwm" else "data"), where), float).ravel()
            idx = spec["elements"]
            if max(idx) >= arr.size:
                raise LogFormatError(f"{where}: field {spec.get('field')!r} has {arr.size} elements; map asks for "
                                     f"element {max(idx)}")
            vals = float(spec.get("offset", 0.0)) + float(spec.get("scale", 1.0)) * arr[idx]
            for c, v in zip(columns, vals):
                put(c, v)
        else:  # fields
            for c, path in spec["fields"].items():
                put(c, float(_get(m, path, where)))
    return {k: np.asarray(v, float) for k, v in rows.items()}, notes


def _check_spec(name: str, spec, where: str) -> dict:
    w = f"{where}: streams.{name}"
    if not isinstance(spec, dict):
        raise LogFormatError(f"{w}: expected a mapping with topic and type")
    unknown = set(spec) - _STREAM_KEYS
    if unknown:
        raise LogFormatError(f"{w}: unknown key(s) {sorted(unknown)}; allowed: {sorted(_STREAM_KEYS)}")
    if not isinstance(spec.get("topic"), str):
        raise LogFormatError(f"{w}: 'topic' missing")
    if spec.get("type") not in TYPES:
        raise LogFormatError(f"{w}: type {spec.get('type')!r} is not one of {', '.join(TYPES)}")
    if spec["type"] in ("pwm", "thrust"):
        el = spec.get("elements")
        if not isinstance(el, list) or not el or not all(isinstance(i, int) and i >= 0 for i in el):
            raise LogFormatError(f"{w}: 'elements' must list the array indices (from 0) of thrusters 1..n")
    if spec["type"] == "pressure":
        for k in ("surface_pressure", "density"):
            if not isinstance(spec.get(k), (int, float)) or not spec[k] > 0:
                raise LogFormatError(f"{w}: '{k}' must be a positive number (Pa, kg/m^3)")
    if "optional" in spec and (not isinstance(spec["optional"], bool) or (spec["optional"]
                                                                         and spec["type"] in ("pwm", "thrust"))):
        raise LogFormatError(f"{w}: 'optional' must be true or false, and the thruster commands cannot be optional")
    for k in ("closed_loop_modes", "open_loop_modes"):
        if k in spec and (spec["type"] != "mode" or not isinstance(spec[k], list)
                          or not all(isinstance(m, str) and m.strip() for m in spec[k])):
            raise LogFormatError(f"{w}: '{k}' must be a list of mode names (strings), in a stream of type mode")
    if spec["type"] == "mode" and set(spec.get("closed_loop_modes", [])) & set(spec.get("open_loop_modes", [])):
        raise LogFormatError(f"{w}: modes {sorted(set(spec['closed_loop_modes']) & set(spec['open_loop_modes']))} "
                             "are listed both as closed_loop_modes and as open_loop_modes")
    if spec["type"] == "fields" and not isinstance(spec.get("fields"), dict):
        raise LogFormatError(f"{w}: 'fields' must map columns to field paths")
    for col in (spec["fields"] if spec["type"] == "fields" else {}):
        # a column under another tool's name would be written, then refused by the reader (uvsim.log_aliases)
        target = format_name(str(col), FORMAT_COLUMNS)
        if target is not None:
            raise LogFormatError(f"{w}: fields: column {col!r} is not in the log format; did you mean {target}? "
                                 "(docs/log_format.md; other names are kept as extra columns, not used)")
    if spec.get("frame") not in (None, *FRAMES):
        raise LogFormatError(f"{w}: frame {spec['frame']!r} is not one of {', '.join(FRAMES)}")
    return spec


def load_map(path) -> dict:
    """Read and check a topic map (module docstring); errors name the file and key."""
    path = Path(path)
    doc = load_yaml(path, error=LogFormatError, what="map file (YAML)")
    if not isinstance(doc, dict) or not isinstance(doc.get("streams"), dict) or not doc["streams"]:
        raise LogFormatError(f"{path}: expected a mapping with 'streams: {{name: {{topic: ..., type: ...}}}}'")
    unknown = set(doc) - {"vehicle", "frame", "stamp", "types", "streams", "description"}
    if unknown:
        raise LogFormatError(f"{path}: unknown key(s) {sorted(unknown)}")
    if doc.get("frame", "enu_flu") not in FRAMES:
        raise LogFormatError(f"{path}: frame {doc['frame']!r} is not one of {', '.join(FRAMES)}")
    for name, spec in doc["streams"].items():
        _check_spec(name, spec, str(path))
    kinds = [s["type"] for s in doc["streams"].values() if s["type"] in ("pwm", "thrust")]
    if len(kinds) != 1:
        raise LogFormatError(f"{path}: exactly one pwm or thrust stream is needed (the inputs), found {len(kinds)}")
    if sum(s["type"] == "mode" for s in doc["streams"].values()) > 1:
        raise LogFormatError(f"{path}: at most one stream of type mode (the flight mode) may be mapped")
    return doc


def read_bag(bag, mapping: dict, map_name: str = "map", progress=None) -> tuple[list, dict]:
    """Streams of ``bag`` as named by ``mapping`` (a checked map) and the time base; ``progress``:
    the reading as a stage (:func:`uvsim.progress.as_progress`)."""
    rb = require("rosbags.highlevel", "ros", f"{bag}: reading ROS bags")
    typesys = require("rosbags.typesys", "ros", f"{bag}: reading ROS bags")
    bag = Path(bag)
    if not bag.exists():
        raise LogFormatError(f"{bag}: bag does not exist")
    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    for msgtype, text in (mapping.get("types") or {}).items():
        store.register(typesys.get_types_from_msg(text, msgtype))
    try:
        reader = rb.AnyReader([bag], default_typestore=store)
        reader.open()
    except Exception as exc:  # rosbags raises its own error types for unreadable bags
        raise LogFormatError(f"{bag}: cannot be read as a ROS 1 or ROS 2 bag: {type(exc).__name__}: {exc}") from None
    from uvsim.progress import as_progress

    size = sum(f.stat().st_size for f in ([bag] if bag.is_file() else bag.rglob("*")) if f.is_file())
    with as_progress(progress).stage(f"reading {bag.name} ({size / 1e6:.1f} MB), {len(mapping['streams'])} "
                                     "topic(s)"):
        try:
            topics = {c.topic: c for c in reader.connections}
            streams, t_first = [], []
            raw_streams, missing = [], {}
            for name, spec in mapping["streams"].items():
                topic = spec["topic"]
                where = f"{bag}: topic {topic} (map streams.{name})"
                if topic not in topics and spec.get("optional"):
                    missing[name] = f"{topic} is not in the bag (optional in the map)"
                    continue
                if topic not in topics:
                    raise LogFormatError(f"{bag}: topic {topic!r} (map streams.{name}) is not in the bag; "
                                         f"topics: {sorted(topics)}")
                conns = [c for c in reader.connections if c.topic == topic]
                msgs, times = [], []
                stamp = spec.get("stamp", mapping.get("stamp", "header"))
                for conn, t_bag, raw in reader.messages(connections=conns):
                    try:
                        m = reader.deserialize(raw, conn.msgtype)
                    except Exception as exc:
                        raise LogFormatError(f"{where}: cannot deserialize {conn.msgtype}: {exc}") from None
                    msgs.append(m)
                    times.append(_stamp(m, t_bag, stamp, f"{where} ({conn.msgtype})"))
                if not msgs:
                    raise LogFormatError(f"{where}: topic has no messages")
                raw_streams.append((name, spec, msgs, np.asarray(times, dtype=np.int64), f"{where} ({conns[0].msgtype})",
                                    stamp))
                t_first.append(min(times))
        finally:
            reader.close()
    t0 = min(t_first)
    n_in = 0
    meta = {"time_base": f"s since the first mapped message, at {t0} ns on the stamps' clock",
            "t0_clock_ns": int(t0)}
    if missing:
        meta["optional_streams_missing"] = missing
    for name, spec, msgs, times, where, stamp in raw_streams:
        kind = spec["type"]
        src = f"{spec['topic']} [{where.rsplit('(', 1)[-1].rstrip(')')}]"
        if kind == "mode":  # no column: the runs' closed_loop (import_bag)
            t_s = (times - t0) * 1e-9
            names = [mode_name(_get(m, spec.get("field", "mode"), where)) for m in msgs]
            order = np.argsort(t_s, kind="stable")
            meta["modes"] = {"stream": name, "source": src,
                             "reports": [(float(t_s[i]), names[i]) for i in order],
                             "interval_s": float(np.median(np.diff(t_s[order]))) if len(msgs) > 1 else 0.0,
                             "closed": list(spec.get("closed_loop_modes", CLOSED_LOOP_NAMES)),
                             "open": list(spec.get("open_loop_modes", OPEN_LOOP_NAMES))}
            continue
        frame = spec.get("frame", mapping.get("frame", "enu_flu"))
        cols_in = None
        if kind in ("pwm", "thrust"):
            cols_in = [f"{kind}_{i + 1}" for i in range(len(spec["elements"]))]
            n_in = len(cols_in)
        cols, notes = _extract(kind, spec, msgs, where, cols_in)
        role = "measured"
        if kind in ("pose", "odometry", "imu"):
            cols = _to_ned_frd(cols, frame)
            notes.append(f"frame {frame}" + (" converted to NED/FRD" if frame == "enu_flu" else ""))
        elif kind == "pressure":
            rho, p0 = float(spec["density"]), float(spec["surface_pressure"])
            cols = {"depth": (cols["value"] - p0) / (rho * G0)}
            notes.append(f"depth = (p - {p0:g} Pa) / ({rho:g} kg/m^3 x {G0} m/s^2)")
        elif kind == "depth":
            cols = {"depth": cols["value"]}
        elif kind == "voltage":
            cols, role = {"voltage": cols["value"]}, "voltage"
        elif kind in ("pwm", "thrust"):
            role = "input"
            keep = np.isfinite(np.stack(list(cols.values()), axis=1)).all(axis=1)
            if (~keep).any():
                notes.append(f"{int((~keep).sum())} samples with a NaN element dropped (e.g. motors disarmed)")
                times, cols = times[keep], {k: v[keep] for k, v in cols.items()}
            if spec.get("scale") is not None or spec.get("offset") is not None:
                notes.append(f"value -> {float(spec.get('offset', 0.0)):g} + {float(spec.get('scale', 1.0)):g} x value")
        streams.append(Stream(name, src, (times - t0) * 1e-9, cols, role=role, notes=notes + [f"stamp: {stamp}"]))
    meta["n_thrusters"] = n_in
    return streams, meta


def _mode_record(modes: dict) -> dict:
    """The flight modes the bag reports (their changes) and what was taken from them."""
    return mode_record(modes["reports"], source=modes["source"], stream=modes["stream"],
                       report_interval_s=round(modes["interval_s"], 3),
                       rule=(f"true where every mode over a run is one of {modes['closed']}, false where every one "
                             f"is one of {modes['open']}, not written otherwise; a report up to one interval after "
                             "a run's start stands for the mode at its start"))


def import_bag(bag, map_path, out, *, vehicle=None, segments=None, tol: float = MERGE_TOL_S, progress=None) -> dict:
    """Import a bag with a topic map into dataset ``out`` (see the module docstring)."""
    bag, map_path = Path(bag), Path(map_path)
    mapping = load_map(map_path)
    streams, meta = read_bag(bag, mapping, map_path.name, progress)
    modes = meta.pop("modes", None)
    vehicle = vehicle or mapping.get("vehicle")
    if not vehicle:
        raise LogFormatError(f"{map_path}: no 'vehicle' in the map and none given (--vehicle)")
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(vehicle)
    if veh.n_thrusters != meta["n_thrusters"]:
        raise LogFormatError(f"{map_path}: the thruster stream lists {meta['n_thrusters']} elements but vehicle "
                             f"{veh.name} has {veh.n_thrusters} thrusters")
    end = max(float(s.t.max()) for s in streams)
    segs = load_segments(segments, bag.stem) if segments else [Segment(0.0, end, bag.stem.replace(" ", "_"),
                                                                        origin="whole bag")]
    if modes is not None:  # the flight mode over each run: its closed_loop (uvsim.importers.flight_modes)
        for seg in segs:
            seg.closed_loop = closed_loop_over(modes["reports"], seg.start, seg.end, modes["closed"], modes["open"],
                                               lead=modes["interval_s"])
    runs, rec = build_runs(streams, segs, where=str(bag), tol=tol)
    digest = hashlib.sha256()
    files = sorted(p for p in bag.rglob("*") if p.is_file()) if bag.is_dir() else [bag]
    for p in files:
        digest.update(p.read_bytes())
    record = {"tool": "uvsim import bag", "source": {"bag": bag.name, "files": [p.name for p in files],
                                                     "sha256": digest.hexdigest(), "map": map_path.name},
              **meta, "segments_from": f"segments file {Path(segments).name}" if segments else "the whole bag",
              **rec}
    if modes is not None:
        record["flight_modes"] = _mode_record(modes)
    entry = str(Path(vehicle).resolve()) if Path(str(vehicle)).suffix in (".yaml", ".yml") else str(vehicle)
    path = write_imported_dataset(out, runs, vehicle=entry,
                                  description=f"Imported from {bag.name} with {map_path.name} by uvsim import bag",
                                  record=record)
    return {"dataset": path, "vehicle": str(vehicle), "record": record,
            "runs": [(seg.name, float(df["t"].iloc[-1]), len(df)) for seg, df in runs]}
