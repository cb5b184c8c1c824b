"""Field-like logs of a BlueROV2 Heavy flown by an ArduSub-like autopilot (issue 48, item 5).

``sample_field(seed, case=None) -> dict`` draws every random choice of one dataset (plain data);
``generate_field(spec, out_dir)`` flies it in closed loop on this package's truth model
(:mod:`uvsim.scenarios.dynamics`) and writes a LOG_FORMAT dataset, the given model's vehicle file
and ``truth.yaml`` with the right catalogue answer (``expected``).  Nothing here imports uvsim's
model, simulator, fitting, calibration or diagnosis (tests/test_calibration_structural.py and
tests/test_field_logs_generator.py parse the sources).  docs/scenarios.md, "Field logs", lists
every distribution and its source.

The loop (:mod:`uvsim.scenarios.autopilot`), at 50 Hz: pilot sticks -> ArduSub modes (STABILIZE or
DEPTH HOLD, heading hold) on the complementary filter's attitude (no compass: yaw drifts with the
gyro bias) and the pressure sensor's depth -> the Heavy's mixer -> PWM -> T200 curve -> the fault
-> the truth.  The log is written at 10 or 5 Hz: PWM, gyro, accelerometer, filter roll/pitch/yaw
(yaw to 0.01 deg), depth of a pressure sensor 0.1-0.2 m off the origin, DVL velocity at 5 Hz with
drop-outs, every row stamped by a topside clock with +-15 ms of jitter.

The truth differs from the given model (the shipped ``bluerov2_heavy`` coefficients) in values and
structure in every case, clean ones too: added mass +10-20 %, damping +-20 %, inertia +-5 %, and
translational quadratic drag along the relative velocity (``D_Q,i |v_r| v_r,i``: the drag of a
bluff body acts against the flow, coupling surge, sway and heave) where the model has the
diagonal ``D_Q,i |v_r,i| v_r,i``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from uvsim.files import plain
from uvsim.logs import Run, write_dataset
from uvsim.scenarios import autopilot as ap
from uvsim.scenarios.dynamics import N_BASE, NU, POS, QUAT, Plant, cross, matvec, rotation, to_body
from uvsim.scenarios.effects import CABLE_CD, CABLE_DIAMETER, LEAD_DENSITY, Ballast, ScenarioError, frame_point
from uvsim.scenarios.generate import TRUTH_FILE, dump_yaml, vehicle_document
from uvsim.scenarios.truth import base_parts, equilibrium_attitude
from uvsim.scenarios.vehicle_data import ADDED_MASS_NAMES, INERTIA_NAMES, LINEAR_NAMES, QUADRATIC_NAMES, \
    load_vehicle_data

#: Cases and the catalogue answer that is right for each (``expected`` in truth.yaml).
CASES = ("clean", "dead", "reversed", "weak", "fouled", "current", "weight", "tether", "tilted_thruster",
         "depth_drag")
OUTSIDE = ("tilted_thruster", "depth_drag")
MODEL_NAME = "myrov"
#: Log rates (Hz): ArduSub's telemetry streams as a topside logs them (QGroundControl's
#: ``SR0_*`` rates: 10 Hz for attitude and raw sensors, some setups 5 Hz).
LOG_RATES = (10.0, 5.0)
#: DVL rate, Hz (Water Linked DVL A50: 2-15 Hz; 5 Hz is its rate over a few metres of water).
DVL_HZ = 5.0
#: Topside clock jitter, s: stamps uniform within +-15 ms of the sample time (issue 48: MAVLink
#: over a tether link and a topside computer's scheduler).
CLOCK_JITTER = 0.015
#: RK4 sub-steps per 20 ms control tick (h = 10 ms: the fastest closed-loop mode, roll at
#: ~3 rad/s, is resolved ~30 times per period).
SUBSTEPS = 2

# --- distributions (each with its source or stated as ours) ----------------------------------
#: Truth hydrodynamics against the given model: added mass x U(1.10, 1.20) (issue 48: "added mass
#: +15 %"; Orjales et al. 2025 Table 2 vs 5 differ by up to 20 % between two estimates), damping x
#: U(0.8, 1.2), inertia x U(0.95, 1.05) (ours).
ADDED_MASS_FACTOR, DAMPING_SPREAD, INERTIA_SPREAD = (1.10, 1.20), 0.2, 0.05
#: Runs per dataset and their length, s (ours: a 5-8 minute session cut into dives, short enough
#: for a diagnosis of a few minutes).
N_TRAIN, N_VALIDATION, RUN_SECONDS, PAUSE_SECONDS = 4, 2, (30.0, 45.0), (10.0, 40.0)
#: Starting depth, m (a harbour or a lake shore: 1.5-5 m).
START_DEPTH = (1.5, 5.0)
#: Share of runs flown in DEPTH HOLD (the others in STABILIZE).
P_DEPTH_HOLD = 0.75
#: Gyro: residual bias after ArduPilot's gyro calibration at boot, rad/s per axis, 0.05-0.3 deg/s
#: (ours; the ICM-20602's zero-rate offset is +-1 deg/s before calibration, TDK InvenSense
#: DS-000176); white noise 0.0015-0.004 rad/s at 50 Hz (its 0.004 deg/s/sqrt(Hz) density over the
#: filter bandwidth, plus vibration of the thrusters).
GYRO_BIAS, GYRO_SIGMA = (np.radians(0.05), np.radians(0.3)), (0.0015, 0.004)
#: Accelerometer: bias 0.02-0.1 m/s^2 per axis, noise 0.02-0.06 m/s^2 (ICM-20602 DS-000176:
#: +-25 mg zero-g offset, 100 ug/sqrt(Hz); thruster vibration dominates on an ROV; ours).
ACC_BIAS, ACC_SIGMA = (0.02, 0.1), (0.02, 0.06)
#: Pressure sensor: 0.1-0.2 m from the origin (a Bar30 on the end cap), noise 2-5 mm (Blue
#: Robotics Bar30, MS5837-30BA: 0.2 mbar resolution = 2 mm of water).
PRESSURE_OFFSET, PRESSURE_SIGMA = (0.1, 0.2), (0.002, 0.005)
#: Climb-rate estimate of the inertial navigation, noise m/s (ours).
CLIMB_SIGMA = 0.02
#: DVL: noise 3-10 mm/s (Water Linked A50 datasheet: long-term accuracy +-1.01 %, 0.1 mm/s
#: resolution; bottom texture and altitude dominate), 1-4 drop-outs per run of 0.6-6 s (loss of
#: bottom lock over weed or a steep slope; ours).
DVL_SIGMA, DVL_DROPOUTS, DVL_DROPOUT_S = (0.003, 0.01), (1, 4), (0.6, 6.0)

# faults and effects
#: Weak thruster: gain 0.3-0.8 (issue 48); fouled: a line or weed round the propeller, gain
#: 0.5-0.85 forward and a further 0.5-0.8 in reverse (the wake pushes the fouling into the duct;
#: ours).
WEAK_GAIN, FOULED_GAIN, FOULED_REVERSE = (0.3, 0.8), (0.5, 0.85), (0.5, 0.8)
#: Current: 0.1-0.3 m/s (a harbour's tidal stream; Fossen 2021 sec. 8.3 models it as slowly
#: varying), its direction turning by 20-70 deg over the session (issue 48: "up to 70 deg").
CURRENT_SPEED, CURRENT_TURN = (0.1, 0.3), (np.radians(20.0), np.radians(70.0))
#: Lead weight: 1-4 N net (90-360 g of lead) on the frame (ours; lead density CRC Handbook).
LEAD_WEIGHT = (1.0, 4.0)
#: Tether from a spool at the surface: anchor 3-8 m away, drifting 0-3 cm/s (a boat or a float),
#: the spool's brake 1-4 N of tension plus 2-10 N/m beyond the paid-out length, paid out at
#: 0-2 cm/s (ours; Fathom tether D = 7.6 mm, Blue Robotics).
SPOOL_DIST, SPOOL_DRIFT, SPOOL_TENSION, SPOOL_K, SPOOL_RATE = (3.0, 8.0), (0.0, 0.03), (1.0, 4.0), (2.0, 10.0), \
    (0.0, 0.02)
#: Tilted thruster (outside the catalogue): a bent mount turns one thruster's axis by 10-25 deg.
TILT = (np.radians(10.0), np.radians(25.0))
#: Depth-dependent drag (outside the catalogue): a hanging cable or hose of diameter 7.6-25 mm
#: whose wetted length is the depth, a fraction 0.5-1 of it dragged along horizontally:
#: ``F = -1/2 rho C_d D (frac z) |v_h| v_h`` (cylinder C_d 1.2, Hoerner 1965 ch. 3).
HOSE_DIAMETER, HOSE_FRACTION = (0.0076, 0.025), (0.5, 1.0)


def _u(rng, lo_hi, nd=4):
    return round(float(rng.uniform(*lo_hi)), nd)


def expected_answer(case: str, thruster: int | None = None):
    """The catalogue answer that is right for ``case`` (truth.yaml ``expected``)."""
    if case == "clean":
        return "none"
    if case in OUTSIDE:
        return "outside_catalogue"
    if case == "dead":
        return {"effect": "thruster_gain", "variant": f"unit_{thruster}", "answer": "dead"}
    if case == "reversed":
        return {"effect": "thruster_gain", "variant": f"reversed_{thruster}"}
    if case in ("weak", "fouled"):
        return {"effect": "thruster_gain", "variant": f"unit_{thruster}"}
    return {"effect": {"current": "current", "weight": "ballast", "tether": "tether"}[case]}


def _fault(rng, case: str, start_depth: float) -> dict:
    if case == "clean":
        return {}
    if case in ("dead", "reversed", "weak", "fouled", "tilted_thruster"):
        # a reversed unit is a horizontal one (1-4): with a vertical unit reversed the roll/pitch
        # loop has positive feedback on it and the vehicle flips at once (seen in the generator:
        # roll past 180 deg within 2 s), which a pilot notices before any session is logged
        k = int(rng.integers(1, 5 if case == "reversed" else 9))
        d = {"thruster": k}
        if case == "dead":
            d["gain"] = 0.0
        elif case == "reversed":
            d["gain"] = -1.0
        elif case == "weak":
            d["gain"] = _u(rng, WEAK_GAIN, 3)
        elif case == "fouled":
            d.update(gain=_u(rng, FOULED_GAIN, 3), reverse_ratio=_u(rng, FOULED_REVERSE, 3))
        else:
            d.update(tilt_rad=_u(rng, TILT), tilt_about=float(rng.uniform(0, 2 * np.pi)))
        return d
    if case == "current":
        return {"speed": _u(rng, CURRENT_SPEED, 3), "azimuth0": _u(rng, (-np.pi, np.pi)),
                "turn": _u(rng, CURRENT_TURN) * float(rng.choice([-1.0, 1.0]))}
    if case == "weight":
        w = _u(rng, LEAD_WEIGHT, 3)
        return {"weight": w, "position": [round(x, 3) for x in frame_point(rng)], "density": LEAD_DENSITY}
    if case == "tether":
        az = rng.uniform(-np.pi, np.pi)
        dist = rng.uniform(*SPOOL_DIST)
        drift_az = rng.uniform(-np.pi, np.pi)
        drift = rng.uniform(*SPOOL_DRIFT)
        return {"anchor0": [round(dist * np.cos(az), 3), round(dist * np.sin(az), 3), 0.0],
                "anchor_velocity": [round(drift * np.cos(drift_az), 4), round(drift * np.sin(drift_az), 4), 0.0],
                "attach": [round(x, 3) for x in frame_point(rng)], "tension": _u(rng, SPOOL_TENSION, 3),
                "stiffness": _u(rng, SPOOL_K, 3), "length0": round(float(np.hypot(dist, start_depth)), 3),
                "payout_rate": _u(rng, SPOOL_RATE)}
    if case == "depth_drag":
        return {"diameter": _u(rng, HOSE_DIAMETER), "fraction": _u(rng, HOSE_FRACTION, 3), "cd": CABLE_CD}
    raise ScenarioError(f"field logs: case {case!r}; expected one of {list(CASES)}")


def sample_field(seed: int, case: str | None = None, *, duration=None, n_train: int = N_TRAIN,
                 n_validation: int = N_VALIDATION, log_hz: float | None = None) -> dict:
    """Every random choice of one field dataset (module docstring), from ``seed``.  ``case``
    defaults to one drawn from :data:`CASES`; ``duration`` (s) fixes the runs' length."""
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ScenarioError(f"sample_field: seed must be a non-negative integer, got {seed!r}")
    if case is not None and case not in CASES:
        raise ScenarioError(f"sample_field: case {case!r}; expected one of {list(CASES)}")
    rng = np.random.default_rng([int(seed), 48])
    case = case or str(rng.choice(CASES))
    rate = float(log_hz or rng.choice(LOG_RATES))
    dur = float(duration) if duration is not None else round(float(rng.uniform(*RUN_SECONDS)), 1)
    nominal = load_vehicle_data()
    factors = {k: _u(rng, ADDED_MASS_FACTOR) for k in ADDED_MASS_NAMES}
    factors.update({k: _u(rng, (1 - DAMPING_SPREAD, 1 + DAMPING_SPREAD)) for k in LINEAR_NAMES + QUADRATIC_NAMES})
    factors.update({k: _u(rng, (1 - INERTIA_SPREAD, 1 + INERTIA_SPREAD)) for k in INERTIA_NAMES})
    az = rng.uniform(0, 2 * np.pi)
    r = rng.uniform(*PRESSURE_OFFSET)
    pressure = [round(-r * abs(np.cos(az)), 3), round(r * np.sin(az) * 0.3, 3), round(rng.uniform(-0.05, 0.05), 3)]
    sensors = {"imu": {"position": [_u(rng, (0.0, 0.1), 3), _u(rng, (-0.02, 0.02), 3), _u(rng, (-0.06, 0.0), 3)],
                       "gyro_sigma": _u(rng, GYRO_SIGMA, 5), "acc_sigma": _u(rng, ACC_SIGMA, 4)},
               "pressure": {"position": pressure, "sigma": _u(rng, PRESSURE_SIGMA, 4)},
               "dvl": {"position": [_u(rng, (-0.1, 0.1), 3), 0.0, _u(rng, (0.08, 0.14), 3)],
                       "sigma": _u(rng, DVL_SIGMA, 4), "rate_hz": DVL_HZ},
               "clock": {"jitter": CLOCK_JITTER, "law": "uniform"}}
    runs, t_start = [], 0.0
    n = n_train + n_validation
    depth0 = _u(rng, START_DEPTH, 2)
    for i in range(n):
        split = "train" if i < n_train else "validation"
        bias = [float(rng.uniform(*GYRO_BIAS) * rng.choice([-1, 1])) for _ in range(3)]
        gaps = []
        for _ in range(int(rng.integers(DVL_DROPOUTS[0], DVL_DROPOUTS[1] + 1))):
            a = float(rng.uniform(min(2.0, 0.25 * dur), max(dur - 2.0, 0.5 * dur)))
            gaps.append([round(a, 2), round(a + float(rng.uniform(*DVL_DROPOUT_S)), 2)])
        runs.append({"name": f"{'val' if split == 'validation' else 'dive'}_{i + 1:02d}", "split": split,
                     "session_start": round(t_start, 2), "depth0": depth0 if i == 0 else _u(rng, START_DEPTH, 2),
                     "yaw0": _u(rng, (-np.pi, np.pi)),
                     "mode": "depth_hold" if rng.random() < P_DEPTH_HOLD else "stabilize",
                     "gyro_bias": [round(b, 6) for b in bias],
                     "acc_bias": [float(_u(rng, ACC_BIAS) * rng.choice([-1, 1])) for _ in range(3)],
                     "dvl_dropouts": gaps, "sticks": ap.sample_sticks(rng, dur)})
        t_start += dur + float(rng.uniform(*PAUSE_SECONDS))
    fault = _fault(rng, case, runs[0]["depth0"])
    return {"generator": "uvsim.scenarios.field", "seed": int(seed), "case": case,
            "expected": expected_answer(case, fault.get("thruster")), "fault": fault, "log_hz": rate,
            "control_hz": ap.CONTROL_HZ, "duration": dur, "session_seconds": round(t_start, 2),
            "vehicle": {"file": nominal.name, "factors": factors, "coupled_drag": "translational quadratic drag "
                        "D_Q,i |v_r| v_r,i (along the relative velocity)"},
            "sensors": sensors, "runs": runs}


# --- truth ------------------------------------------------------------------------------------
def truth_vehicle(spec: dict):
    nominal = load_vehicle_data()
    return nominal, nominal.with_coefficients({k: nominal.coefficients[k] * f
                                               for k, f in spec["vehicle"]["factors"].items()})


def _rotate(d: np.ndarray, angle: float, about: float) -> np.ndarray:
    """``d`` turned by ``angle`` about an axis perpendicular to it (at ``about`` rad round it)."""
    d = d / np.linalg.norm(d)
    e1 = np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    axis = np.cos(about) * e1 + np.sin(about) * np.cross(d, e1)
    return d * np.cos(angle) + np.cross(axis, d) * np.sin(angle) + axis * (axis @ d) * (1 - np.cos(angle))


def _current_ned(fault: dict, t_session: np.ndarray, session: float) -> np.ndarray:
    az = fault["azimuth0"] + fault["turn"] * t_session / max(session, 1e-9)
    return fault["speed"] * np.array([np.cos(az), np.sin(az), np.zeros_like(az)])


def _plant(spec: dict, veh, n: int):
    """The truth plant of ``n`` runs with the case's static effects and wrenches."""
    case, fault = spec["case"], spec["fault"]
    parts = base_parts(veh, n, veh.n_thrusters)
    quad = parts["quadratic"][:3].copy()
    parts["quadratic"][:3] = 0.0                     # translational quadratic drag: Plant.along_flow
    A = veh.allocation()
    if case == "tilted_thruster":
        k = fault["thruster"] - 1
        d = _rotate(veh.thruster_directions[k], fault["tilt_rad"], fault["tilt_about"])
        A[:, k] = np.r_[d, np.cross(veh.thruster_positions[k], d)]
    if case == "weight":
        Ballast(variant="lead", magnitude=fault["weight"], weight=fault["weight"], position=fault["position"],
                density=LEAD_DENSITY, mass=float(fault["weight"] * LEAD_DENSITY
                                                 / (veh.g * (LEAD_DENSITY - veh.rho)))).modify(parts, np.ones(n, bool))
    if case == "current":
        parts["current"][:] = _current_ned(fault, np.zeros(n), 1.0)
    t0 = np.array([r["session_start"] for r in spec["runs"]])

    wrenches = []
    if case == "tether":
        a0, va = np.asarray(fault["anchor0"])[:, None], np.asarray(fault["anchor_velocity"])[:, None]
        ra = np.asarray(fault["attach"], dtype=float)

        def spool(ctx):
            ts = t0 + ctx.t
            d = a0 + va * ts - (ctx.pos + np.einsum("ijn,j->in", ctx.R, ra))
            L = np.sqrt((d * d).sum(axis=0))
            free = fault["length0"] + fault["payout_rate"] * ts
            F = (fault["tension"] + fault["stiffness"] * np.maximum(L - free, 0.0)) * d / np.maximum(L, 1e-9)
            f = to_body(ctx.R, F)
            return np.concatenate((f, cross(np.broadcast_to(ra[:, None], f.shape), f)))

        wrenches.append(spool)
    if case == "depth_drag":
        c = 0.5 * veh.rho * fault["cd"] * fault["diameter"] * fault["fraction"]

        def hose(ctx):
            vn = matvec(ctx.R, ctx.nu_r[:3])
            vn[2] = 0.0
            F = -c * np.maximum(ctx.pos[2], 0.0) * np.sqrt((vn * vn).sum(axis=0)) * vn
            return np.concatenate((to_body(ctx.R, F), np.zeros((3, F.shape[1]))))

        wrenches.append(hose)
    plant = Plant(allocation=np.repeat(A[:, :, None], n, axis=2), along_flow=quad, **parts)
    plant.wrenches = wrenches
    if case == "current":
        plant.has_current = True
    return plant, parts


def _thrust(spec: dict, curve, pwm: np.ndarray) -> np.ndarray:
    """Delivered thrust (8, n) of PWM commands: the T200 curve, then the case's fault."""
    f = curve.thrust(pwm)
    fault = spec["fault"]
    if spec["case"] in ("dead", "reversed", "weak", "fouled"):
        k = fault["thruster"] - 1
        g = fault["gain"]
        if spec["case"] == "fouled":
            g = np.where(f[k] < 0, g * fault["reverse_ratio"], g)
        f[k] = g * f[k]
    return f


def simulate_field(spec: dict, noise: bool = True) -> dict:
    """Fly every run of ``spec`` in closed loop; per run (first axis) at the control rate:
    ``t``, truth ``pos``, ``quat``, ``nu``, ``nu_dot``, the autopilot's ``pwm`` and delivered
    ``thrust``, and the readings ``gyro``, ``acc``, ``rpy`` (filter), ``depth``."""
    nominal, veh = truth_vehicle(spec)
    runs = spec["runs"]
    n = len(runs)
    dt = 1.0 / spec["control_hz"]
    n_t = int(round(spec["duration"] * spec["control_hz"])) + 1
    rng = np.random.default_rng([spec["seed"], 48, 1])
    plant, parts = _plant(spec, veh, n)
    dirs = ap.motor_directions(nominal.thruster_directions, nominal.thruster_positions)
    s = spec["sensors"]
    r_imu, r_p = np.asarray(s["imu"]["position"]), np.asarray(s["pressure"]["position"])
    bias = np.array([r["gyro_bias"] for r in runs]).T
    acc_bias = np.array([r["acc_bias"] for r in runs]).T
    # initial state: at rest at the static attitude (a weight tilts it), heading as drawn
    y = np.zeros((N_BASE + veh.n_thrusters, n))
    rpy0 = []
    for i, r in enumerate(runs):
        roll, pitch = equilibrium_attitude(parts["load_moment"][:, i])
        yaw = r["yaw0"]
        cr, sr, cp, sp, cy, sy = np.cos(roll / 2), np.sin(roll / 2), np.cos(pitch / 2), np.sin(pitch / 2), \
            np.cos(yaw / 2), np.sin(yaw / 2)
        y[QUAT, i] = [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                      cr * cp * sy - sr * sp * cy]
        y[2, i] = r["depth0"]
        rpy0.append([roll, pitch, yaw])
    filt = ap.Filter(np.array(rpy0).T, dt)
    pilot = ap.Autopilot(n, dt, np.array([r["mode"] == "depth_hold" for r in runs]),
                         depth0=y[2] + (rotation(y[QUAT])[2] * r_p[:, None]).sum(axis=0),
                         yaw0=np.array(rpy0)[:, 2])
    t = np.arange(n_t) * dt
    sticks = np.stack([ap.sticks_at(r["sticks"], t) for r in runs], axis=2)      # (4, n_t, n)
    t0 = np.array([r["session_start"] for r in runs])
    keys = ("pos", "quat", "nu", "nu_dot", "pwm", "thrust", "gyro", "acc", "rpy", "depth")
    out = {k: [] for k in keys}
    f = _thrust(spec, nominal.curve, np.full((veh.n_thrusters, n), ap.PWM_NEUTRAL))
    h = dt / SUBSTEPS

    def nz(sigma, shape):
        return rng.normal(0.0, sigma, shape) if noise else np.zeros(shape)

    for k in range(n_t):
        tk = t[k]
        if spec["case"] == "current":
            plant.current = _current_ned(spec["fault"], t0 + tk, spec["session_seconds"])
        nu_dot = plant.rhs(tk, y, f)[NU]
        R = rotation(y[QUAT])
        v, w = y[NU][:3], y[NU][3:]
        rr = np.broadcast_to(r_imu[:, None], w.shape)
        spec_f = (nu_dot[:3] + cross(w, v) + cross(nu_dot[3:], rr) + cross(w, cross(w, rr))
                  - veh.g * R[2])
        gyro = w + (bias if noise else 0.0) + nz(s["imu"]["gyro_sigma"], w.shape)
        acc = spec_f + (acc_bias if noise else 0.0) + nz(s["imu"]["acc_sigma"], w.shape)
        depth = y[2] + (R[2] * r_p[:, None]).sum(axis=0) + nz(s["pressure"]["sigma"], n)
        climb = matvec(R, v)[2] + nz(CLIMB_SIGMA, n)
        rpy = filt.update(gyro, acc)
        o = pilot.step(sticks[:, k], rpy, gyro, depth, climb)
        pwm = ap.pwm(o, dirs)
        f = _thrust(spec, nominal.curve, pwm)
        for key, val in zip(keys, (y[POS], y[QUAT], y[NU], nu_dot, pwm, f, gyro, acc, rpy, depth)):
            out[key].append(np.array(val))
        if k == n_t - 1:
            break
        if spec["case"] == "current":
            plant.current = _current_ned(spec["fault"], t0 + tk + 0.5 * dt, spec["session_seconds"])
        for j in range(SUBSTEPS):
            ts = tk + j * h
            k1 = plant.rhs(ts, y, f)
            k2 = plant.rhs(ts + 0.5 * h, y + 0.5 * h * k1, f)
            k3 = plant.rhs(ts + 0.5 * h, y + 0.5 * h * k2, f)
            k4 = plant.rhs(ts + h, y + h * k3, f)
            y = y + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
            y[QUAT] /= np.sqrt((y[QUAT] ** 2).sum(axis=0))
        if not np.all(np.isfinite(y)):
            raise ScenarioError(f"field logs seed {spec['seed']}: the truth diverged at t = {tk:.2f} s")
    res = {k: np.moveaxis(np.array(v), -1, 0) for k, v in out.items()}   # (n, n_t, ...)
    res["t"] = t
    return res


# --- the log ----------------------------------------------------------------------------------
def stamps(t: np.ndarray, rng: np.random.Generator, jitter: float = CLOCK_JITTER) -> np.ndarray:
    """Topside stamps of rows sampled at ``t``: ``t + U(-jitter, jitter)``, kept increasing
    (at log rates of 5-10 Hz, +-15 ms never reorders two rows; the max keeps it so anyway)."""
    s = t + rng.uniform(-jitter, jitter, t.size)
    gap = 0.05 * float(np.median(np.diff(t)))
    k = np.arange(t.size)
    return np.maximum.accumulate(s - gap * k) + gap * k


def log_tables(spec: dict, sim: dict) -> list[pd.DataFrame]:
    """The logged table of each run (docs/log_format.md columns)."""
    step = int(round(spec["control_hz"] / spec["log_hz"]))
    dvl_step = int(round(spec["log_hz"] / DVL_HZ))
    rng = np.random.default_rng([spec["seed"], 48, 2])
    clock = np.random.default_rng([spec["seed"], 48, 3])
    s = spec["sensors"]
    r_dvl = np.asarray(s["dvl"]["position"])
    tables = []
    for i, r in enumerate(spec["runs"]):
        idx = np.arange(0, sim["t"].size, step)
        t = sim["t"][idx]
        d = {"t": stamps(t, clock)}
        for j in range(sim["pwm"].shape[2]):
            d[f"pwm_{j + 1}"] = sim["pwm"][i, idx, j]
        rpy = sim["rpy"][i, idx]
        d["roll"], d["pitch"] = rpy[:, 0], rpy[:, 1]
        d["yaw"] = np.radians(np.round(np.degrees(rpy[:, 2]), 2))      # logged to 0.01 deg
        for j, c in enumerate("pqr"):
            d[c] = sim["gyro"][i, idx, j]
        for j, c in enumerate(("acc_x", "acc_y", "acc_z")):
            d[c] = sim["acc"][i, idx, j]
        d["depth"] = sim["depth"][i, idx]
        nu = sim["nu"][i, idx]
        vel = nu[:, :3] + np.cross(nu[:, 3:], r_dvl) + rng.normal(0.0, s["dvl"]["sigma"], (idx.size, 3))
        have = (np.arange(idx.size) % dvl_step) == 0
        for a, b in r["dvl_dropouts"]:
            have &= ~((t >= a) & (t < b))
        vel[~have] = np.nan
        d["u"], d["v"], d["w"] = vel.T
        tables.append(pd.DataFrame(d))
    return tables


def generate_field(spec: dict, out_dir, *, sim: dict | None = None) -> Path:
    """Fly ``spec`` (:func:`sample_field`) and write the dataset into ``out_dir``; ``sim``, the
    caller's own ``simulate_field(spec)``, is written instead of flying it again."""
    out = Path(out_dir)
    sim = simulate_field(spec) if sim is None else sim
    tables = log_tables(spec, sim)
    # every run is flown under the autopilot (stabilize or depth hold), as the topside's log says
    runs = [Run(name=r["name"], path=None, data=tab, dof="mixed", split=r["split"], closed_loop=True)
            for r, tab in zip(spec["runs"], tables)]
    desc = (f"field logs (issue 48), seed {spec['seed']}: BlueROV2 Heavy under an ArduSub-like autopilot, "
            f"{spec['log_hz']:g} Hz topside log")
    write_dataset(out, runs, vehicle=MODEL_NAME, description=desc)
    nominal, veh = truth_vehicle(spec)
    sensors = {"imu": {"position": spec["sensors"]["imu"]["position"]},
               "pressure": {"position": spec["sensors"]["pressure"]["position"]},
               "dvl": {"position": spec["sensors"]["dvl"]["position"]}}
    doc = vehicle_document(nominal, name=MODEL_NAME, sensors=sensors,
                           description="the given model: the shipped bluerov2_heavy coefficients, sensor positions")
    (out / f"{MODEL_NAME}.yaml").write_text("# The given model of a field-log dataset (uvsim.scenarios.field): "
                                           "src/uvsim/vehicles/bluerov2_heavy.yaml\n" + dump_yaml(doc))
    truth = {**spec, "truth_coefficients": veh.coefficients, "nominal_coefficients": nominal.coefficients,
             "mixer": {"source": "ArduPilot libraries/AP_Motors/AP_Motors6DOF.cpp, SUB_FRAME_VECTORED_6DOF",
                       "factors_roll_pitch_yaw_throttle_forward_lateral": ap.MOTOR_FACTORS.tolist(),
                       "mot_direction": ap.motor_directions(nominal.thruster_directions,
                                                            nominal.thruster_positions).tolist(),
                       "pwm": "1500 + 400 * MOT_DIRECTION * clamp(output, -1, 1)"},
             "autopilot": {"gains": {k: np.asarray(v).tolist() for k, v in ap.GAINS.items()},
                           "filter_time_constant_s": ap.FILTER_TIME_CONSTANT, "pilot_gain": ap.PILOT_GAIN},
             "model_vehicle_file": f"{MODEL_NAME}.yaml"}
    (out / TRUTH_FILE).write_text(dump_yaml(plain(truth)))
    return out
