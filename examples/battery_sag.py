"""What a sagging battery does to a calibration (docs/thrusters.md, "Battery-aware thrust").

Truth: the BlueROV2 Heavy (Orjales et al. 2025 Table 5) with the voltage-dependent T200
curve (``curve: {voltage_table: t200}``).  Six surge runs of 12 s at 50 Hz (a slow and a fast
forward step and a reverse step of PWM on T1..T4) are logged while a battery discharges over the session:
open-circuit voltage 16.6 V falling to 13.6 V, minus a load sag of 0.8 V at full
command (a synthetic battery, stated here, not a measured one).  Position noise 2 mm.

The same runs are calibrated (surge DOF, seed 000 GA + refinement) twice, starting from
the truth with its surge coefficients (X_u, X_uu, X_udot) set to the initial estimates
of bluerov2_heavy_initial.yaml (the other DOFs are known, so only surge is tested):
  A: with the logged ``voltage`` column (thrust from the curve at the logged voltage);
  B: without it (every sample at the nominal 16 V, i.e. what a voltage-blind model sees).

    python examples/battery_sag.py [PNG]      (~2 min on one core)
"""
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

import uvsim
from uvsim.calibration import Calibrator
from uvsim.logs import Run, write_dataset
from uvsim.plotting.battery import battery_sag_figure
from uvsim.vehicle import load_vehicle, vehicle_from_dict

FAMILY = {"voltage_table": "t200", "nominal_voltage": 16.0}
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("docs/img/battery_sag_calibration.png")


def with_family(name):
    d = load_vehicle(name).to_dict()
    d["thrusters"] = dict(d["thrusters"], curve=FAMILY)
    return vehicle_from_dict(d, source=f"{name} + t200 voltage family")


truth = with_family("bluerov2_heavy")
# start: the truth with its surge coefficients replaced by the initial estimates of
# bluerov2_heavy_initial.yaml ([O25] Table 2), so that only the surge fit differs
initial = load_vehicle("bluerov2_heavy_initial").parameters()
start = truth.with_parameters({k: initial[k] for k in ("X_u", "X_uu", "X_udot")})
rng = np.random.default_rng(2025)
dt, n_runs, dur = 0.02, 6, 12.0
t = np.arange(0.0, dur, dt)
runs_a, runs_b, volt_trace = [], [], []
for k in range(n_runs):
    low, level = rng.uniform(1550, 1590), rng.uniform(1660, 1780)
    cmd = np.full(t.size, 1500.0)
    cmd[(t >= 0.5) & (t < 3.5)] = low     # slow: linear damping
    cmd[(t >= 3.5) & (t < 7.0)] = level   # fast: quadratic damping
    cmd[(t >= 8.0) & (t < 11.0)] = 3000.0 - level  # reverse
    pwm = np.full((t.size, 8), 1500.0)
    pwm[:, :4] = cmd[:, None]
    v_oc = 16.6 - 3.0 * (k + t / dur) / n_runs
    volts = v_oc - 0.8 * np.abs(cmd - 1500.0) / 400.0
    res = uvsim.simulate(truth, t, pwm, input_kind="pwm", voltage=volts)
    df = pd.DataFrame({"t": t})
    for j, c in enumerate("xyz"):
        df[c] = res.position[:, j] + rng.normal(0, 0.002, t.size)
    e = res.euler + rng.normal(0, 0.005, (t.size, 3))
    df["roll"], df["pitch"], df["yaw"] = e[:, 0], e[:, 1], e[:, 2]
    for j in range(8):
        df[f"pwm_{j + 1}"] = pwm[:, j]
    split = "validation" if k == n_runs - 1 else "train"
    runs_b.append(Run(name=f"surge_{k + 1:02d}", path=None, data=df.copy(), dof="surge", split=split))
    df["voltage"] = volts
    runs_a.append(Run(name=f"surge_{k + 1:02d}", path=None, data=df, dof="surge", split=split))
    volt_trace.append((k * dur + t, volts))

work = Path(tempfile.mkdtemp(prefix="battery_sag_"))
fits = {}
for label, runs in (("A: logged voltage", runs_a), ("B: nominal 16 V", runs_b)):
    ds = write_dataset(work / label[0], runs, vehicle="bluerov2_heavy")
    cal = Calibrator(dofs="surge", population=60, generations=30, seed=1).fit(ds, start)
    fits[label] = cal.params_
true = truth.parameters()
names = sorted(fits["A: logged voltage"])
print(f"{'parameter':>10} {'truth':>10} " + " ".join(f"{k:>20}" for k in fits))
for p in names:
    print(f"{p:>10} {true[p]:>10.4g} " + " ".join(f"{fits[k][p]:>10.4g} ({100 * (fits[k][p] / true[p] - 1):+6.1f} %)"
                                                    for k in fits))
curve = truth.actuators.curves[0]
battery_sag_figure(volt_trace, curve, fits, true, OUT)
print(f"figure -> {OUT}")
