"""Small "real sensor" datasets for the calibration tests (imported by tests/test_calibration_*.py).

Multi-DOF telegraph PWM runs (``dof: mixed``) of a truth BlueROV2 Heavy (seed 000
Table 5 with some parameters changed), simulated with ``uvsim.simulate_batch``; the
sensor readings are made here, written apart from ``uvsim.measurements`` (rotations
by scipy): a gyro with a constant bias per run, an accelerometer (specific force at
its lever arm), roll and pitch from an attitude filter (an explicit first-order lag
loop) without yaw, and the depth of a pressure sensor 0.15 m aft at 10 Hz, held on
the log grid.  The model vehicle file (Table 5 values, sensor positions) lies beside
the manifest; the truth goes to ``truth.yaml``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import yaml
from scipy.spatial.transform import Rotation

import uvsim
from uvsim.logs import Run, write_dataset
from uvsim.synthetic import BLUEROV2_HEAVY_PATTERNS

IMU = [0.05, 0.02, -0.06]
PRESSURE = [-0.15, 0.0, 0.0]
NOISE = {"gyro": 0.003, "acc": 0.02, "euler": 0.006, "depth": 0.005}
#: PWM offsets (us from neutral) of each DOF's pattern: roll/pitch small (restoring-limited).
LEVELS = {"surge": 70.0, "sway": 70.0, "heave": 70.0, "roll": 40.0, "pitch": 45.0, "yaw": 70.0}


def _telegraph(rng, t, n_switch):
    times = np.sort(rng.uniform(0.5, t[-1] - 0.5, n_switch))
    s = np.where(rng.random() < 0.5, 1.0, -1.0) * (-1.0) ** np.searchsorted(times, t)
    on = t >= rng.uniform(0.0, 1.0)
    return s * on


def _pwm(rng, t, dofs):
    pwm = np.full((t.size, 8), 1500.0)
    for d in dofs:
        pat = np.asarray(BLUEROV2_HEAVY_PATTERNS[d], float)
        pwm += LEVELS[d] * rng.uniform(0.7, 1.0) * _telegraph(rng, t, int(rng.integers(2, 5)))[:, None] * pat
    return np.clip(pwm, 1100.0, 1900.0)


def _lag(x, dt, tau):
    if tau <= 0:
        return x.copy()
    a = np.exp(-dt / tau)
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(1, len(x)):
        y[k] = a * y[k - 1] + (1 - a) * x[k]
    return y


def make_dataset(path, *, truth: dict, seed: int = 0, n_train: int = 4, n_val: int = 1, duration: float = 8.0,
                 rate: float = 50.0, dofs=("heave", "roll", "pitch", "yaw"), lag: float = 0.1, accelerometer=True,
                 depth_mode: str = "held", dof: str = "mixed") -> Path:
    """Write a dataset (module docstring) with truth parameters ``truth`` into ``path``;
    ``dof``: the manifest's dof of every run."""
    rng = np.random.default_rng(seed)
    path = Path(path)
    model = uvsim.load_vehicle("bluerov2_heavy")
    veh = model.with_parameters(truth)
    t = np.round(np.arange(int(duration * rate) + 1) / rate, 9)
    n_runs = n_train + n_val
    U = np.stack([_pwm(rng, t, [d for d in dofs if rng.random() < 0.75] or list(dofs[:1]))
                  for _ in range(n_runs)])
    pos0 = np.column_stack([rng.uniform(-0.5, 0.5, n_runs), rng.uniform(-0.5, 0.5, n_runs),
                            rng.uniform(1.0, 1.5, n_runs)])
    q0 = Rotation.from_euler("ZYX", np.column_stack([rng.uniform(-3, 3, n_runs), np.zeros((n_runs, 2))]))
    res = uvsim.simulate_batch(veh, t, U, input_kind="pwm", pos0=pos0, q0=q0.as_quat()[:, [3, 0, 1, 2]],
                               return_acceleration=True)
    runs, biases = [], {}
    step = int(round(rate / 10.0))
    for i in range(n_runs):
        y, nd = res.y[i], res.nu_dot[i]
        R = Rotation.from_quat(y[:, [4, 5, 6, 3]])
        v, w = y[:, 7:10], y[:, 10:13]
        b = rng.uniform(-0.02, 0.02, 3)
        name = f"{'run' if i < n_train else 'val'}_{i + 1:02d}"
        biases[name] = b.tolist()
        cols = {"t": t, **{f"pwm_{k + 1}": U[i, :, k] for k in range(8)}}
        gyro = w + b + rng.normal(0, NOISE["gyro"], w.shape)
        cols.update(p=gyro[:, 0], q=gyro[:, 1], r=gyro[:, 2])
        if accelerometer:
            r_i = np.asarray(IMU)
            down = R.inv().apply([0.0, 0.0, 1.0])
            f = (nd[:, :3] + np.cross(w, v) + np.cross(nd[:, 3:], r_i) + np.cross(w, np.cross(w, r_i))
                 - veh.g * down + rng.normal(0, NOISE["acc"], v.shape))
            cols.update(acc_x=f[:, 0], acc_y=f[:, 1], acc_z=f[:, 2])
        yaw_pitch_roll = np.unwrap(R.as_euler("ZYX"), axis=0)
        for j, c in ((2, "roll"), (1, "pitch")):
            cols[c] = _lag(yaw_pitch_roll[:, j], 1.0 / rate, lag) + rng.normal(0, NOISE["euler"], t.size)
        z_s = y[:, 2] + R.apply(PRESSURE)[:, 2]
        idx = np.arange(0, t.size, step)
        native = z_s[idx] + rng.normal(0, NOISE["depth"], idx.size)
        if depth_mode == "held":
            depth = native[np.searchsorted(idx, np.arange(t.size), side="right") - 1]
        else:
            depth = np.full(t.size, np.nan)
            depth[idx] = native
        cols["depth"] = depth
        runs.append(Run(name=name, path=None, data=pd.DataFrame(cols), dof=dof,
                        split="train" if i < n_train else "validation"))
    write_dataset(path, runs, vehicle="myrov", description="calibration test: mixed telegraph runs, real sensors")
    doc = model.to_dict()
    doc["name"] = "myrov"
    doc["sensors"] = {"imu": {"position": IMU}, "pressure": {"position": PRESSURE}}
    (path / "myrov.yaml").write_text(yaml.safe_dump(doc, sort_keys=False))
    (path / "truth.yaml").write_text(yaml.safe_dump({"parameters": {k: float(v) for k, v in truth.items()},
                                                     "gyro_bias": biases, "attitude_lag": lag, "noise": NOISE},
                                                    sort_keys=False))
    return path
