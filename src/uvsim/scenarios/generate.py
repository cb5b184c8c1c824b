"""Turn a :class:`ScenarioSpec` into a LOG_FORMAT dataset plus its truth record.

``generate(spec, out_dir)`` writes

* ``manifest.yaml`` and one CSV per run (``uvsim.logs.write_dataset``; no truth in them);
* ``myrov.yaml``: the model the user starts from, nominal Table 5 coefficients, the
  measured mass and buoyancy of this vehicle, and the sensor positions (``sensors:``);
* ``truth.yaml``: the spec, the truth vehicle (perturbed coefficients, buoyancy, CB), the
  effects with their parameters, ``effect_snr``, noise levels, sensor settings and every
  run's shape, initial state and sensor biases.

Structural overrides (spec.py): with ``vehicle.thruster_offsets`` the truth's thrusters sit at
the file's positions plus the offsets (its allocation and moment arms use them; ``myrov.yaml``
keeps the file's positions, ``truth.yaml`` lists both), and the logged thrust/PWM commands are
what a controller with the file's geometry sends for the run's force (``A_file^+``).  With a
sensor ``latency`` the truth is also integrated at ``t - latency`` (the log grid and the delayed
times in one non-uniform grid, inputs held from each log sample to the next as before) and
that sensor reads it there.  With ``sensors.clock`` the ``t`` column holds jittered stamps
(:func:`uvsim.scenarios.sensors.stamps`, their own noise stream: the sensor noise of the same
spec without jitter is unchanged).

Effect visibility (``effect_snr``): every validation run is simulated once more without
each effect (in the same batch); the noise-free sensor readings of the two differ by
``Delta``; ``effect_snr = sqrt(mean((Delta / sigma)^2))`` over all channels and samples of
the validation runs, ``sigma`` each channel's noise level (attitude: the rotation vector
between the two attitudes).  An effect is ``detectable`` when ``effect_snr >= 2``: its
signal on the validation runs is at least twice the noise RMS (docs/scenarios.md).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy.spatial.transform import Rotation

from uvsim.files import plain, safe_load
from uvsim.logs import Run, write_dataset
from uvsim.scenarios.effects import (CATALOGUED, MAGNITUDE_MEANING, MAGNITUDE_RANGES, CoupledDamping, ScenarioError,
                                     effect_from_dict)
from uvsim.scenarios.inputs import actuator_inputs, force_profile, initial_velocity
from uvsim.scenarios.sensors import GROUPS, columns, deviation_snr, measure, stamps
from uvsim.scenarios.spec import ScenarioSpec, sensor_suite
from uvsim.scenarios.truth import base_parts, equilibrium_attitude, simulate_truth
from uvsim.scenarios.vehicle_data import (ADDED_MASS_NAMES, INERTIA_NAMES, LINEAR_NAMES, PACKAGE_DIR,
                                          QUADRATIC_NAMES, load_thrust_table, load_vehicle_data)

#: ``effect_snr`` at or above which an effect counts as detectable.
DETECTABLE_SNR = 2.0
TRUTH_FILE = "truth.yaml"


class _Dumper(yaml.SafeDumper):
    """Short lists of numbers in flow style ([x, y, z]), everything else in block style."""


def _represent_list(dumper, data):
    flow = len(data) <= 8 and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def dump_yaml(doc) -> str:
    return yaml.dump(doc, Dumper=_Dumper, sort_keys=False)


def vehicles(spec: ScenarioSpec):
    """The nominal vehicle and the truth vehicle of a spec (:class:`VehicleData`)."""
    path = PACKAGE_DIR / "vehicles" / f"{spec.vehicle['file']}.yaml"
    if not path.exists():
        raise ScenarioError(f"scenario spec: vehicle.file {spec.vehicle['file']!r}: no built-in vehicle file "
                            f"{path.name}")
    nominal = load_vehicle_data(path)
    factors = spec.vehicle.get("factors", {})
    truth = nominal.with_coefficients({k: nominal.coefficients[k] * float(f) for k, f in factors.items()})
    r_b = nominal.r_b.copy()
    r_b[2] = float(spec.vehicle.get("z_b", r_b[2]))
    truth = truth.with_rigid_body(buoyancy=nominal.weight + float(spec.vehicle.get("net_buoyancy", 0.0)), r_b=r_b)
    if spec.vehicle.get("truth_curve"):  # the truth's thrusters follow another curve than the file's
        truth = dataclasses.replace(truth, curve=load_thrust_table(str(spec.vehicle["truth_curve"])))
    if "thruster_offsets" in spec.vehicle:  # the truth's thrusters are not where the file says
        try:
            off = np.asarray(spec.vehicle["thruster_offsets"], dtype=float)
        except (TypeError, ValueError):
            off = None
        if off is None or off.shape != nominal.thruster_positions.shape or not np.all(np.isfinite(off)):
            raise ScenarioError(f"scenario spec: vehicle.thruster_offsets = {spec.vehicle['thruster_offsets']!r}; "
                                f"expected {nominal.n_thrusters} [dx, dy, dz] in m (one per thruster of "
                                f"{nominal.name})")
        truth = dataclasses.replace(truth, thruster_positions=nominal.thruster_positions + off)
    return nominal, truth


def vehicle_document(v, *, name: str, description: str, sensors: dict | None = None) -> dict:
    """A vehicle file (dict) for ``v``: the parsed base file with its coefficients,
    buoyancy and CB replaced, plus a ``sensors:`` section."""
    doc = dict(v.document)
    doc["name"] = name
    doc["description"] = description
    rb = dict(doc.get("rigid_body", {}))
    rb["mass"] = float(v.mass)
    rb["buoyancy"] = float(v.buoyancy)
    rb["r_g"] = [float(x) for x in v.r_g]
    rb["r_b"] = [float(x) for x in v.r_b]
    rb["inertia"] = {**rb.get("inertia", {}), **{k: float(v.coefficients[k]) for k in INERTIA_NAMES}}
    doc["rigid_body"] = rb
    doc["added_mass"] = {k: float(v.coefficients[k]) for k in ADDED_MASS_NAMES}
    doc["damping"] = {"type": "diagonal", "linear": {k: float(v.coefficients[k]) for k in LINEAR_NAMES},
                      "quadratic": {k: float(v.coefficients[k]) for k in QUADRATIC_NAMES}}
    doc["effects"] = []
    units = (doc.get("thrusters") or {}).get("units") or []
    in_file = np.array([u.get("position", [0.0, 0.0, 0.0]) for u in units], dtype=float)
    if in_file.shape == v.thruster_positions.shape and not np.array_equal(in_file, v.thruster_positions):
        # a truth whose thrusters were moved (thruster_offsets): its own positions
        doc["thrusters"] = {**doc["thrusters"], "units": [{**u, "position": [float(x) for x in r]}
                                                          for u, r in zip(units, v.thruster_positions)]}
    if sensors:
        doc["sensors"] = sensors
    return plain(doc)


def _sensor_positions(spec: ScenarioSpec) -> dict:
    out = {}
    for section, name in (("imu", "imu"), ("depth", "pressure"), ("dvl", "dvl")):
        if section in spec.sensors:
            out[name] = {"position": [float(x) for x in spec.sensors[section]["position"]]}
    return out


def _input_names(kind: str, k: int) -> list[str]:
    return ["X", "Y", "Z", "K", "M", "N"] if kind == "force" else [f"{kind}_{i + 1}" for i in range(k)]


def simulate_spec(spec: ScenarioSpec, with_snr: bool = True) -> dict:
    """Simulate every run of ``spec`` (and, for ``effect_snr``, every validation run once
    without each effect) in one batch.  Returns the arrays :func:`generate` writes."""
    nominal, veh = vehicles(spec)
    effects = [effect_from_dict(d) for d in spec.effects]
    for e in effects:
        if isinstance(e, CoupledDamping):
            e.with_derivatives(dict(zip(LINEAR_NAMES, veh.linear_damping())),
                               dict(zip(QUADRATIC_NAMES, veh.quadratic_damping())))
    runs = spec.runs
    dt = 1.0 / float(spec.rate_hz)
    n_samples = [int(round(r["duration"] / dt)) + 1 for r in runs]
    t = np.arange(max(n_samples)) * dt
    trim = veh.buoyancy - veh.weight
    A = nominal.allocation()   # the controller's geometry: the file's (the truth's when no thruster is moved)
    logged = [actuator_inputs(force_profile(r["shape"], t), spec.input_kind, A, veh.curve, trim)[0] for r in runs]
    val = [i for i, r in enumerate(runs) if r["split"] == "validation"] or list(range(len(runs)))
    # rows: every run with all effects, then the validation runs without effect j
    row_run = list(range(len(runs)))
    active = [np.ones(len(runs), dtype=bool) for _ in effects]
    snr_rows = []
    if with_snr:
        for j in range(len(effects)):
            for i in val:
                snr_rows.append((j, i, len(row_run)))
                row_run.append(i)
                for jj in range(len(effects)):
                    active[jj] = np.append(active[jj], jj != j)
    active = np.array(active, dtype=bool).reshape(len(effects), len(row_run))
    # initial states: each row at rest at its own static attitude (ballast tilts it), yaw as drawn
    pos0, quat0, nu0, att0 = [], [], [], []
    for row, i in enumerate(row_run):
        parts = base_parts(veh, 1, 1)
        for e, on in zip(effects, active[:, row]):
            if on and e.type == "ballast":
                e.modify(parts, np.array([True]))
        roll, pitch = equilibrium_attitude(parts["load_moment"][:, 0])
        yaw = float(runs[i]["yaw0"])
        q = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_quat()
        pos0.append(runs[i]["pos0"])
        quat0.append([q[3], q[0], q[1], q[2]])
        nu0.append(initial_velocity(runs[i]["shape"]))
        att0.append([roll, pitch, yaw])
    U = np.array([logged[i] for i in row_run])
    kw = dict(effects=effects, active=active, pos0=np.array(pos0), quat0=np.array(quat0), nu0=np.array(nu0),
              max_step=spec.max_step)
    latencies = sorted({float(sec.get("latency", 0.0)) for sec in spec.sensors.values()} - {0.0})
    delayed = {}
    if not latencies:
        sim = simulate_truth(veh, t, U, spec.input_kind, **kw)
    else:
        grid, on_grid, at_delay = _delay_grid(t, latencies)
        held = np.searchsorted(t, grid + 1e-9, side="right") - 1     # the log sample whose input acts
        full = simulate_truth(veh, grid, U[:, held], spec.input_kind, **kw)
        sim = {"t": t, **{k: full[k][:, on_grid] for k in ("pos", "quat", "nu", "nu_dot", "thrust")}}
        for lat, (idx, started) in at_delay.items():
            d = {k: full[k][:, idx].copy() for k in ("pos", "quat", "nu", "nu_dot")}
            for k in ("pos", "quat", "nu"):                        # before the start: held at the initial state
                d[k][:, ~started] = full[k][:, :1]
            d["nu_dot"][:, ~started] = 0.0
            delayed[lat] = d
    return {"nominal": nominal, "truth": veh, "effects": effects, "t": t, "n_samples": n_samples, "logged": logged,
            "sim": sim, "delayed": delayed, "snr_rows": snr_rows, "validation": val, "att0": att0, "nu0": nu0,
            "trim": trim}


def _delay_grid(t: np.ndarray, latencies) -> tuple[np.ndarray, np.ndarray, dict]:
    """One grid holding the log times ``t`` and every ``t - latency >= 0``.

    Returns the grid, the grid index of each log time, and per latency the grid index of each
    ``t - latency`` (0 before the start) with a mask of those at or after the start.  A delayed
    time within 1 ns of a log time is that log time, so the inputs switch at the log times only.
    """
    tol = 1e-9
    extra = []
    for lat in latencies:
        x = t - lat
        x = x[x >= -tol]
        j = np.clip(np.searchsorted(t, x), 1, t.size - 1)
        near = np.minimum(np.abs(t[j] - x), np.abs(t[j - 1] - x))
        extra.append(x[near > tol])
    grid = np.concatenate([t] + extra)
    grid.sort()
    grid = grid[np.r_[True, np.diff(grid) > tol]]
    on_grid = np.searchsorted(grid, t - tol)
    at_delay = {}
    for lat in latencies:
        x = t - lat
        started = x >= -tol
        idx = np.where(started, np.searchsorted(grid, np.maximum(x, 0.0) - tol), 0)
        at_delay[lat] = (idx, started)
    return grid, on_grid, at_delay


def _truth_arrays(sim: dict, row: int, n: int, g: float, rate: float, delayed: dict | None = None) -> dict:
    keys = ("pos", "quat", "nu", "nu_dot")
    out = {"t": sim["t"][:n], **{k: sim[k][row, :n] for k in keys}, "g": g, "rate_hz": rate}
    if delayed:
        out["delayed"] = {lat: {k: d[k][row, :n] for k in keys} for lat, d in delayed.items()}
    return out


def effect_snr(spec: ScenarioSpec, res: dict) -> list[dict]:
    """Per effect: ``effect_snr`` (validation runs), per signal group, and ``detectable``."""
    veh, sim = res["truth"], res["sim"]
    out = []
    for j, eff in enumerate(res["effects"]):
        ss, n, per = 0.0, 0, {}
        for jj, i, row in res["snr_rows"]:
            if jj != j:
                continue
            n_i = res["n_samples"][i]
            dl = res.get("delayed")
            with_e = measure(_truth_arrays(sim, i, n_i, veh.g, spec.rate_hz, dl), spec.sensors, spec.runs[i], None)
            without = measure(_truth_arrays(sim, row, n_i, veh.g, spec.rate_hz, dl), spec.sensors, spec.runs[i],
                              None)
            s, m, groups = deviation_snr(with_e, without, spec.sensors)
            ss, n = ss + s, n + m
            for g, (gs, gn) in groups.items():
                a, b = per.get(g, (0.0, 0))
                per[g] = (a + gs, b + gn)
        snr = float(np.sqrt(ss / n)) if n else 0.0
        out.append({"effect_snr": snr, "effect_snr_by_signal": {g: float(np.sqrt(a / b)) if b else 0.0
                                                                for g, (a, b) in per.items()},
                    "detectable": bool(snr >= DETECTABLE_SNR)})
    return out


def _truth_record(spec, res, snr, run_records) -> dict:
    nominal, veh = res["nominal"], res["truth"]
    effects = []
    for eff, s in zip(res["effects"], snr):
        d = eff.to_dict()
        lo, hi = MAGNITUDE_RANGES[sensor_suite(spec)][eff.type]
        d.update(magnitude_range=[lo, hi], magnitude_meaning=MAGNITUDE_MEANING[eff.type],
                 catalogued=eff.type in CATALOGUED, **s)
        effects.append(d)
    structure = {}
    if "thruster_offsets" in spec.vehicle:
        structure["thruster_positions"] = {
            "bound_m": spec.vehicle.get("thruster_position_error"), "offsets_m": spec.vehicle["thruster_offsets"],
            "nominal_m": nominal.thruster_positions.tolist(), "truth_m": veh.thruster_positions.tolist()}
    if "clock" in spec.sensors:
        structure["time_jitter_s"] = spec.sensors["clock"]["jitter"]
    lat = {name: sec["latency"] for name, sec in spec.sensors.items() if sec.get("latency")}
    if lat:
        structure["sensor_latency_s"] = lat
    if any(r["shape"].get("shape") == "pilot" for r in spec.runs):
        structure["inputs"] = "pilot (gamepad, ArduSub manual mode)"
    doc = {
        "generator": "uvsim.scenarios",
        "seed": spec.seed,
        "profile": spec.profile,
        "description": spec.description,
        "input_kind": spec.input_kind,
        "rate_hz": spec.rate_hz,
        "model_vehicle_file": f"{spec.vehicle['model_name']}.yaml",
        "vehicle": vehicle_document(veh, name=f"truth_seed{spec.seed}", description="the truth (no effects)"),
        "coefficients": {"nominal": nominal.coefficients, "truth": veh.coefficients,
                         "factors": spec.vehicle.get("factors", {}), "perturbation": spec.vehicle.get("perturbation")},
        "buoyancy": {"mode": spec.vehicle["buoyancy"], "weight_N": veh.weight, "buoyancy_N": veh.buoyancy,
                     "net_N": veh.buoyancy - veh.weight, "trim_force_Z_N": res["trim"],
                     "z_b_nominal": float(nominal.r_b[2]), "z_b_truth": float(veh.r_b[2])},
        "effects": effects,
        "effect_snr": {e["type"]: e["effect_snr"] for e in effects},
        "detectability": {"criterion": f"effect_snr >= {DETECTABLE_SNR:g} (RMS of the noise-normalized sensor "
                                       "deviation it causes on the validation runs)"},
        "noise": {f"{sec}.{key}": spec.sensors[sec][key] for sec, _, key in GROUPS.values() if sec in spec.sensors},
        "sensors": spec.sensors,
        "integration": {"method": "RK4, fixed step", "max_step_s": spec.max_step,
                        "substeps_per_sample": int(np.ceil(1.0 / (spec.rate_hz * spec.max_step) - 1e-9))},
        "runs": run_records,
        "spec": spec.to_dict(),
    }
    if structure:  # issue 21's structural differences, listed only when present (older records unchanged)
        doc["structure"] = structure
    return plain(doc)


def generate(spec, out_dir, progress=None) -> Path:
    """Write the dataset of ``spec`` (a :class:`ScenarioSpec` or its dict) into ``out_dir``;
    ``progress``: the truth simulation as a stage (:func:`uvsim.progress.as_progress`).

    Returns the dataset directory (``uvsim.logs.read_dataset`` reads it)."""
    from uvsim.progress import as_progress

    if isinstance(spec, dict):
        spec = ScenarioSpec.from_dict(spec)
    spec.validate()
    out = Path(out_dir)
    seconds = sum(float(r["duration"]) for r in spec.runs)
    with as_progress(progress).stage(f"truth simulation of {len(spec.runs)} runs ({seconds:.0f} s of data, "
                                     f"RK4 step {1000 * spec.max_step:g} ms)"):
        res = simulate_spec(spec)
    veh, sim = res["truth"], res["sim"]
    rng = np.random.default_rng([int(spec.noise_seed), 0x5CE7])
    clock_rng = np.random.default_rng([int(spec.noise_seed), 0x5CE7, 1])   # time stamps: a stream of their own
    k = res["logged"][0].shape[1]
    names = _input_names(spec.input_kind, k)
    run_objs, records = [], []
    for i, r in enumerate(spec.runs):
        n_i = res["n_samples"][i]
        readings = measure(_truth_arrays(sim, i, n_i, veh.g, spec.rate_hz, res["delayed"]), spec.sensors, r, rng)
        data = {"t": sim["t"][:n_i]}
        if "clock" in spec.sensors:  # the logger's stamps of rows taken at the true times
            data["t"] = stamps(sim["t"][:n_i], float(spec.sensors["clock"]["jitter"]), spec.rate_hz, clock_rng)
        data.update({c: res["logged"][i][:n_i, j] for j, c in enumerate(names)})
        data.update(columns(readings, spec.sensors))
        run_objs.append(Run(name=r["name"], path=None, data=pd.DataFrame(data), dof=r["dof"], weight=r["weight"],
                            split=r["split"]))
        roll, pitch, yaw = res["att0"][i]
        rec = {"file": f"{r['name']}.csv", "dof": r["dof"], "split": r["split"], "duration": r["duration"],
               "n_samples": n_i, "shape": r["shape"], "amplitude_scale": r["amplitude_scale"],
               "initial_state": {"position": r["pos0"], "roll": roll, "pitch": pitch, "yaw": yaw,
                                 "nu": res["nu0"][i]}}
        for key in ("gyro_bias", "acc_bias"):
            if key in r and "imu" in spec.sensors:
                rec[key] = r[key]
        records.append(rec)
    model = spec.vehicle["model_name"]
    write_dataset(out, run_objs, vehicle=model, description=spec.description)
    doc = vehicle_document(res["nominal"].with_rigid_body(buoyancy=veh.buoyancy), name=model,
                           description=f"model vehicle of scenario {spec.profile} seed {spec.seed}: nominal "
                                       "coefficients (seed 000 Table 5), measured mass and buoyancy, sensor positions",
                           sensors=_sensor_positions(spec))
    header = ("# Model vehicle handed to the user with a generated scenario (uvsim.scenarios).\n"
              "# Coefficients: nominal BlueROV2 Heavy, src/uvsim/vehicles/bluerov2_heavy.yaml (seed 000 Table 2 and\n"
              "# Table 5, thrusters von Benzon et al. 2022); mass and buoyancy as measured for this vehicle;\n"
              "# sensors: positions of the instruments that logged the runs (m, body frame).\n")
    (out / f"{model}.yaml").write_text(header + dump_yaml(doc))
    truth = _truth_record(spec, res, effect_snr(spec, res), records)
    (out / TRUTH_FILE).write_text(dump_yaml(truth))
    return out


def load_truth(dataset_dir) -> dict:
    """Read ``truth.yaml`` of a generated dataset."""
    path = Path(dataset_dir) / TRUTH_FILE
    try:
        return safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ScenarioError(f"{path}: cannot read the truth record ({exc})") from None
