"""Synthetic tank-test datasets generated with the simulator.

The maneuver set imitates the tank tests of seed 000 (sec. 4.2.2): for each degree of
freedom the thrusters that drive it are switched on at one of several PWM levels for
a few seconds and then off, so that each run shows acceleration, a (near) steady
speed and a coast-down; runs alternate forward and reverse.  Linear-DOF runs are
"observed" by underwater motion capture (position + attitude quaternion), rotational
runs by the onboard IMU (Euler angles + gyro rates), each with Gaussian noise of a
stated level (``DEFAULT_NOISE``).  Everything is seeded and reproducible.

``generate_dataset`` writes a LOG_FORMAT dataset (manifest.yaml + CSV files); the
truth model, the effects switched on and the noise levels are recorded in the
manifest so that tests can compare fitted values with the truth.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from uvsim.errors import UvsimError
from uvsim.kinematics import quat_multiply, quat_normalize, quat_to_euler
from uvsim.logged_run import Run
from uvsim.logs import write_dataset
from uvsim.simulate import simulate_batch
from uvsim.vehicle import DOFS, load_vehicle

#: Thruster sign patterns that drive one DOF for the BlueROV2 Heavy layout of
#: ``vehicles/bluerov2_heavy.yaml`` (T1..T4 horizontal, T5..T8 vertical).
BLUEROV2_HEAVY_PATTERNS = {
    "surge": [1, 1, 1, 1, 0, 0, 0, 0],
    "sway": [-1, 1, 1, -1, 0, 0, 0, 0],
    "heave": [0, 0, 0, 0, 1, 1, 1, 1],
    "roll": [0, 0, 0, 0, 1, -1, 1, -1],
    "pitch": [0, 0, 0, 0, -1, -1, 1, 1],
    "yaw": [-1, 1, -1, 1, 0, 0, 0, 0],
}

#: PWM offsets from neutral (1500 us) for the 8 runs per DOF.  The T200 deadband is
#: 1472-1528 us (data/thrusters/SOURCE.md), so offsets start above 28 us.  Roll and
#: pitch use small offsets: the metacentric restoring moment of the BlueROV2
#: (B z_b = 3.2 N m) limits their stable range (seed 000 sec. 5).
DEFAULT_LEVELS = {
    "surge": [35, 45, 55, 65, 75, 90, 105, 120],
    "sway": [35, 45, 55, 65, 75, 90, 105, 120],
    "heave": [35, 45, 55, 65, 75, 90, 105, 120],
    "roll": [32, 35, 38, 41, 44, 47, 50, 55],
    "pitch": [35, 40, 45, 50, 55, 60, 65, 70],
    "yaw": [35, 45, 55, 65, 75, 90, 105, 120],
}

#: Measurement noise (1 sigma) of the synthetic sensors.  These are stated assumptions,
#: typical of the instruments named in seed 000 sec. 4.2.2: Qualisys underwater motion
#: capture (mm-level position) and a Pixhawk IMU (attitude from its filter, gyro rates).
DEFAULT_NOISE = {
    "position": 0.002,   # m, motion capture
    "depth": 0.01,       # m, pressure sensor (Bar30-class)
    "mocap_attitude": 0.005,  # rad, motion-capture rigid-body attitude
    "imu_attitude": 0.01,     # rad, IMU filter roll/pitch/yaw
    "rates": 0.005,      # rad/s, gyro
    "velocity": 0.01,    # m/s, DVL
}

#: Which signals each DOF's runs record by default (seed 000 sec. 4.2.2).
DEFAULT_SIGNALS = {
    "surge": ("position", "mocap_attitude"),
    "sway": ("position", "mocap_attitude"),
    "heave": ("position", "mocap_attitude"),
    "roll": ("imu_attitude", "rates"),
    "pitch": ("imu_attitude", "rates"),
    "yaw": ("imu_attitude", "rates"),
}

SIGNAL_KINDS = ("position", "depth", "mocap_attitude", "imu_attitude", "rates", "velocity")


def step_profile(t: np.ndarray, on: float, off: float) -> np.ndarray:
    """1 on ``[on, off)``, 0 elsewhere."""
    return ((t >= on) & (t < off)).astype(float)


def tank_test_pwm(dof: str, offset: float, t: np.ndarray, *, sign: int = 1, on: float = 1.0, off: float = 7.0,
                  patterns: Mapping[str, Sequence[int]] = BLUEROV2_HEAVY_PATTERNS) -> np.ndarray:
    """PWM commands (n_t, n_thrusters) for one tank run: the DOF's thrusters at
    ``1500 + sign * offset * pattern`` during ``[on, off)`` and neutral otherwise."""
    if dof not in patterns:
        raise UvsimError(f"dof {dof!r}: no thruster pattern (known: {', '.join(patterns)})")
    pat = np.asarray(patterns[dof], float)
    return 1500.0 + sign * offset * step_profile(t, on, off)[:, None] * pat[None, :]


def measure(y: np.ndarray, t: np.ndarray, signals: Sequence[str], noise: Mapping[str, float],
            rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Noisy measurement columns from simulated states ``y`` (n_t, n_y)."""
    out: dict[str, np.ndarray] = {}
    n = t.size
    for s in signals:
        if s not in SIGNAL_KINDS:
            raise UvsimError(f"signal {s!r}: expected one of {', '.join(SIGNAL_KINDS)}")
        sd = float(noise.get(s, DEFAULT_NOISE[s]))
        if s == "position":
            p = y[:, 0:3] + rng.normal(0, sd, (n, 3))
            out.update(x=p[:, 0], y=p[:, 1], z=p[:, 2])
        elif s == "depth":
            out["z"] = y[:, 2] + rng.normal(0, sd, n)
        elif s == "mocap_attitude":
            # small random rotation (rotation vector with sd per axis) applied to the truth
            rv = rng.normal(0, sd, (n, 3))
            ang = np.linalg.norm(rv, axis=1, keepdims=True)
            axis = np.divide(rv, ang, out=np.zeros_like(rv), where=ang > 0)
            dq = np.concatenate([np.cos(ang / 2), axis * np.sin(ang / 2)], axis=1)
            q = quat_normalize(quat_multiply(y[:, 3:7], dq))
            out.update(qw=q[:, 0], qx=q[:, 1], qy=q[:, 2], qz=q[:, 3])
        elif s == "imu_attitude":
            e = quat_to_euler(y[:, 3:7]) + rng.normal(0, sd, (n, 3))
            e = (e + np.pi) % (2 * np.pi) - np.pi
            out.update(roll=e[:, 0], pitch=e[:, 1], yaw=e[:, 2])
        elif s == "rates":
            r = y[:, 10:13] + rng.normal(0, sd, (n, 3))
            out.update(p=r[:, 0], q=r[:, 1], r=r[:, 2])
        elif s == "velocity":
            v = y[:, 7:10] + rng.normal(0, sd, (n, 3))
            out.update(u=v[:, 0], v=v[:, 1], w=v[:, 2])
    return out


def generate_runs(vehicle="bluerov2_heavy", *, dofs: Sequence[str] = DOFS, runs_per_dof: int = 8,
                  validation_per_dof: int = 2, duration: float = 14.0, rate: float = 50.0,
                  signals: Sequence[str] | Mapping[str, Sequence[str]] | None = None,
                  noise: Mapping[str, float] | None = None, seed: int = 0, input_kind: str = "pwm",
                  effects: Sequence | None = None, levels: Mapping[str, Sequence[float]] | None = None,
                  overrides: Mapping[str, float] | None = None, on: float = 1.0, off: float = 7.0,
                  low_speed_weight: float = 2.0) -> tuple[list[Run], dict]:
    """Simulate a tank-test maneuver set and return noisy :class:`Run` objects.

    Parameters
    ----------
    vehicle : truth vehicle (name, file or Vehicle).  Its thruster layout must match
        ``BLUEROV2_HEAVY_PATTERNS`` (8 thrusters).
    dofs : which DOFs to test; each gets ``runs_per_dof`` training runs plus
        ``validation_per_dof`` validation runs (levels in between the training levels).
    signals : measured signals for all runs, or a mapping dof -> signals
        (default ``DEFAULT_SIGNALS``).
    noise : 1-sigma noise per signal kind (default ``DEFAULT_NOISE``).
    input_kind : "pwm" (logged ESC commands), "thrust" (per-thruster N) or "force" (X..N).
    effects : force terms (dicts or ForceTerm) switched on in the truth model only.
    low_speed_weight : manifest weight of the lowest half of the levels (seed 000
        sec. 4.4 weights favour low-speed runs); the rest get weight 1.

    Returns
    -------
    runs, truth  where ``truth`` records the parameters, effects and noise.
    """
    veh = load_vehicle(vehicle)
    if effects:
        veh = veh.with_effects(list(effects))
    if veh.n_thrusters != 8:
        raise UvsimError(f"{veh.name}: tank maneuvers are defined for the 8-thruster BlueROV2 Heavy layout")
    if input_kind not in ("pwm", "thrust", "force"):
        raise UvsimError(f"input_kind {input_kind!r}: expected pwm, thrust or force")
    noise = {**DEFAULT_NOISE, **(noise or {})}
    levels = {**DEFAULT_LEVELS, **(levels or {})}
    rng = np.random.default_rng(seed)
    n_t = int(round(duration * rate)) + 1
    t = np.arange(n_t) / rate

    specs = []  # (dof, index, offset, sign, split, weight)
    for dof in dofs:
        lv = np.asarray(levels[dof], float)
        if lv.size < runs_per_dof:
            lv = np.linspace(lv.min(), lv.max(), runs_per_dof)
        train = lv[np.linspace(0, lv.size - 1, runs_per_dof).round().astype(int)] if runs_per_dof else np.array([])
        val = 0.5 * (train[:-1] + train[1:])[:: max(1, (runs_per_dof - 1) // max(validation_per_dof, 1))][:validation_per_dof] \
            if runs_per_dof > 1 else np.array([])
        med = np.median(train) if train.size else 0
        for i, off_us in enumerate(train):
            specs.append((dof, i, off_us, 1 if i % 2 == 0 else -1, "train", low_speed_weight if off_us <= med else 1.0))
        for j, off_us in enumerate(val):
            specs.append((dof, runs_per_dof + j, off_us, 1 if j % 2 == 0 else -1, "validation", 1.0))

    pwm = np.stack([tank_test_pwm(d, o, t, sign=s, on=on, off=off) for d, _, o, s, _, _ in specs])
    curve_thrust = veh.actuators.thrusts(pwm.reshape(-1, 8), "pwm", veh.actuators.prepare({}, 1)["groups"]).reshape(pwm.shape)
    if input_kind == "pwm":
        inputs = pwm
    elif input_kind == "thrust":
        inputs = curve_thrust
    else:
        inputs = curve_thrust @ veh.actuators.matrix.T
    res = simulate_batch(veh, t, inputs, input_kind=input_kind, overrides=overrides, on_blowup="raise")

    runs = []
    for k, (dof, i, off_us, sign, split, weight) in enumerate(specs):
        sig = (signals.get(dof) if isinstance(signals, Mapping) else signals) or DEFAULT_SIGNALS[dof]
        cols = {"t": np.round(t, 9)}
        # measurements are rounded to 1e-6 (m, rad, rad/s): far below the noise, keeps files small
        cols.update({c: np.round(v, 6) for c, v in measure(res.y[k], t, sig, noise, rng).items()})
        names = res.input_names
        for j, nm in enumerate(names):
            cols[nm] = np.round(inputs[k][:, j], 6)
        name = f"{dof}_{i + 1:02d}"
        runs.append(Run(name=name, path=None, data=pd.DataFrame(cols), dof=dof, weight=float(weight), split=split))
    truth = {
        "vehicle": veh.name,
        "parameters": {k: float(v) for k, v in {**veh.parameters(), **(overrides or {})}.items()},
        "effects": [e.to_dict() for e in veh.effects],
        "noise": {k: float(v) for k, v in noise.items()},
        "seed": int(seed),
        "input_kind": input_kind,
        "duration_s": float(duration),
        "rate_hz": float(rate),
    }
    return runs, truth


def generate_dataset(vehicle="bluerov2_heavy", out_dir="dataset", *, description: str | None = None,
                     manifest_vehicle: str | None = None, **kwargs):
    """Generate runs with :func:`generate_runs` and write them as a LOG_FORMAT dataset.

    The manifest records ``truth`` (parameters, effects, noise, seed).  Returns the
    :class:`uvsim.logs.Dataset` read back from disk.
    """
    from uvsim.logs import read_dataset

    runs, truth = generate_runs(vehicle, **kwargs)
    out = Path(out_dir)
    desc = description or (
        f"Synthetic tank tests generated by uvsim.synthetic from {truth['vehicle']}"
        f" (effects: {[e['type'] for e in truth['effects']] or 'none'}), seed {truth['seed']}"
    )
    write_dataset(out, runs, vehicle=manifest_vehicle or truth["vehicle"], description=desc)
    _add_manifest_meta(out / "manifest.yaml", {"truth": truth, "noise": truth["noise"]})
    return read_dataset(out)


def _add_manifest_meta(path: Path, meta: dict) -> None:
    import yaml

    from uvsim.files import safe_load

    d = safe_load(path.read_text())
    d.update(meta)
    path.write_text(yaml.safe_dump(d, sort_keys=False))
