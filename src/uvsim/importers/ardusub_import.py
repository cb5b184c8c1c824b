"""``uvsim import ardusub``: one ArduSub log -> a dataset a calibration can read.

:func:`import_ardusub` reads the log (:func:`uvsim.importers.ardusub.read_ardusub`),
checks the log's thruster layout against the vehicle file
(:mod:`uvsim.importers.ardusub_frames`), cuts it into runs (armed intervals or a
segments YAML) and writes ``<out>/manifest.yaml`` plus one CSV per run.  The manifest's
``import`` section records the source file and its hash, the message types and fields
used, their rates, the time base, each run's start on it, every hold, shift, gap and
skipped segment.
"""
from __future__ import annotations

from pathlib import Path


from uvsim.errors import LogFormatError, VehicleError
from uvsim.importers.ardusub import read_ardusub
from uvsim.importers.flight_modes import SUB_MODES, mode_record
from uvsim.importers.ardusub_frames import FRAMES, adapted_vehicle_dict, check_frame, mismatch_message
from uvsim.importers.build import build_runs
from uvsim.importers.segments import Segment, load_segments, write_imported_dataset
from uvsim.importers.timeline import MERGE_TOL_S
from uvsim.vehicle import load_vehicle, save_vehicle, vehicle_from_dict

#: Vehicle used when none is given, by FRAME_CONFIG.
DEFAULT_VEHICLE = {2: "bluerov2_heavy", 1: "bluerov2_vectored_standin"}


def import_ardusub(log, out, *, vehicle=None, segments=None, water=None, surface_pressure=None,
                   adapt_vehicle: bool = False, tol: float = MERGE_TOL_S, imu_instance: int = 0,
                   progress=None) -> dict:
    """Import an ArduSub .BIN/.tlog into a dataset directory ``out``.

    Parameters
    ----------
    log : path of the log.
    out : dataset directory (created).
    vehicle : vehicle name or file; default by the log's FRAME_CONFIG (:data:`DEFAULT_VEHICLE`).
    segments : segments YAML (see :mod:`uvsim.importers.segments`); default: armed intervals.
    water : "fresh", "salt" or a density (kg/m^3) for depth; default the log's BARO_SPEC_GRAV.
    surface_pressure : Pa; default pre-dive median, else the autopilot's ground calibration.
    adapt_vehicle : when the log's motors are exactly reversed with respect to the vehicle
        file (MOT_n_DIRECTION), write ``<vehicle>_<log stem>.yaml`` beside the manifest with
        those thrusters' directions flipped instead of failing.
    progress : the reading of the log as a stage (:func:`uvsim.progress.as_progress`).

    Returns
    -------
    dict with "dataset" (Path), "runs" ([(name, duration s, rows)]), "vehicle", "record".
    """
    log = Path(log)
    data = read_ardusub(log, water=water, surface_pressure=surface_pressure, imu_instance=imu_instance,
                        progress=progress)
    where = str(log)
    fc = data.frame_config
    if vehicle is None:
        if fc not in DEFAULT_VEHICLE:
            raise LogFormatError(f"{where}: FRAME_CONFIG = {fc} ({FRAMES.get(fc, ('unknown',))[0]}): no default "
                                 "vehicle; pass --vehicle FILE")
        vehicle = DEFAULT_VEHICLE[fc]
    veh = load_vehicle(vehicle)
    B = veh.actuators.matrix
    if B is None:
        raise VehicleError(f"{veh.source}: the vehicle defines no thrusters; the log's motors cannot be mapped")
    table, bad = check_frame(B, list(veh.actuators.names), fc, data.directions(), log=where, vehicle=veh.source)
    out = Path(out)
    frame_rec = {"FRAME_CONFIG": fc, "name": FRAMES[fc][0], "vehicle": _vehicle_label(vehicle, veh), "thrusters": table,
                 "rule": "pwm_i = command of ArduSub Motor i = vehicle thruster i; sign of B[:, i] must equal "
                         "MOT_i_DIRECTION x AP_Motors6DOF factor on every axis the factor uses"}
    vehicle_entry = veh.name if str(vehicle) == veh.name else str(Path(vehicle).resolve())
    if bad:
        if not (adapt_vehicle and all(r["flippable"] for r in bad)):
            raise LogFormatError(mismatch_message(bad, fc, log=where, vehicle=veh.source))
        adapted = vehicle_from_dict(adapted_vehicle_dict(veh.to_dict(), bad), source=f"{veh.source} (adapted)")
        name = f"{veh.name}_{log.stem}".replace(" ", "_")
        adapted.name = name
        out.mkdir(parents=True, exist_ok=True)
        flipped = ", ".join(f"{r['thruster']} (MOT_{r['motor']}_DIRECTION={r['MOT_DIRECTION']:+g})" for r in bad)
        save_vehicle(adapted, out / f"{name}.yaml", header=(
            f"{veh.name} with the thruster directions of {log.name} (uvsim import ardusub --adapt-vehicle).\n"
            f"Flipped (PWM > 1500 us pushes the other way on this vehicle): {flipped}.\n"
            "The thrust curve is unchanged: its forward branch now acts along the flipped direction;\n"
            "a thruster whose reversed propeller runs in its weak (reverse) branch above 1500 us needs a\n"
            "per-thruster mirrored curve instead (docs/import_export.md)."))
        frame_rec["adapted"] = {"file": f"{name}.yaml", "flipped": [r["thruster"] for r in bad]}
        vehicle_entry = name
    if segments is not None:
        segs = load_segments(segments, log.stem)
        seg_from = f"segments file {Path(segments).name}"
    else:
        segs = [Segment(a, b, f"{log.stem}_armed_{k + 1:02d}".replace(" ", "_"), origin=f"armed interval {k + 1}")
                for k, (a, b) in enumerate(data.armed)]
        seg_from = f"armed intervals ({data.meta['armed_from']})"
        if not segs:
            raise LogFormatError(f"{where}: the vehicle is never armed in this log ({data.meta['armed_from']}), so "
                                 "there is no run to import; give the stretches to import in a segments YAML "
                                 "(--segments, docs/import_export.md)")
    for seg in segs:   # the flight mode the log records over the segment (ArduSubLog.closed_loop)
        seg.closed_loop = data.closed_loop(seg.start, seg.end)
    sources = _pwm_sources(data)
    runs, rec = build_runs(data.streams, segs, where=where, tol=tol, input_sources=sources)
    record = {"tool": "uvsim import ardusub", **data.meta, "log_span_s": list(data.span),
              "armed_intervals_s": [list(a) for a in data.armed], "segments_from": seg_from,
              "flight_modes": _mode_record(data),
              "frame": frame_rec, "motor_outputs": {f"pwm_{m}": f"Motor{m} on servo output {n}"
                                                    for m, n in sorted(data.motor_servo.items())},
              "inputs": sources, **rec}
    desc = (f"Imported from {log.name} ({data.meta['source']['format']}, {data.meta.get('firmware') or 'ArduSub'}) "
            f"by uvsim import ardusub")
    path = write_imported_dataset(out, runs, vehicle=vehicle_entry, description=desc, record=record)
    return {"dataset": path, "vehicle": vehicle_entry, "record": record,
            "runs": [(seg.name, float(df["t"].iloc[-1]), len(df)) for seg, df in runs]}


def _vehicle_label(spec, veh) -> str:
    from uvsim.vehicle import builtin_vehicles

    return f"{veh.name} (built-in)" if str(spec) in builtin_vehicles() else str(spec)


def _mode_record(data) -> dict:
    """The flight modes the log records (their changes) and what was taken from them."""
    return mode_record(data.modes, source="HEARTBEAT.custom_mode" if data.kind == "tlog" else "MODE.ModeNum",
                       name=lambda m: SUB_MODES.get(m, f"mode {m}"),
                       rule="true where every mode over a run holds some state (all but MANUAL and MOTOR_DETECT), "
                            "false where it is MANUAL throughout, not written otherwise")


def _pwm_sources(data) -> dict:
    out = {}
    for m, n in data.motor_servo.items():
        out[f"pwm_{m}"] = f"RCOU.C{n}" if data.kind == "bin" else f"SERVO_OUTPUT_RAW.servo{n}_raw"
    return out


__all__ = ["import_ardusub", "DEFAULT_VEHICLE"]
