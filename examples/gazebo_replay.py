"""Replay a 60 s maneuver of the BlueROV2 Heavy through the exported Gazebo models (docs/import_export.md,
"Use your calibrated model in Gazebo"): the default gz-sim export at 0.5 and 1 ms, gz-sim's plugin added mass,
UUV Simulator's HMFossen, the same with the added mass scaled to 0.3, and each mode's stable physics step.

    python examples/gazebo_replay.py      # about 2 minutes
"""
import time

import numpy as np

from uvsim.export.replay import replay_check, stable_step
from uvsim.vehicle import load_vehicle, vehicle_from_dict

veh = load_vehicle("bluerov2_heavy")
t = np.arange(0, 60.0 + 1e-9, 0.02)
# 10 s each: surge; surge and a turn; sway; heave (up); back and the other turn; a mixed leg (X, Y, Z, K, M, N)
phases = [[10, 0, 0, 0, 0, 0], [10, 0, 0, 0, 0, 1.0], [0, 8, 0, 0, 0, 0], [0, 0, -5, 0, 0, 0], [-8, 0, 0, 0, 0, -1.0],
          [10, 5, 0, 0, 0, 0.5]]
U = np.array([phases[min(int(x // 10), 5)] for x in t], float)
d = veh.to_dict()
d["added_mass"] = {"matrix": (0.3 * np.asarray(d["added_mass"]["matrix"])).tolist()}
light = vehicle_from_dict(d, source="BlueROV2 Heavy with 0.3 x its added mass")
for v, target, mode, h in ((veh, "gz-sim", "fluid", 0.0005), (veh, "gz-sim", "fluid", 0.001),
                           (veh, "gz-sim", "plugin", 0.001), (veh, "uuv-simulator", None, 0.001),
                           (light, "gz-sim", "fluid", 0.001), (light, "gz-sim", "plugin", 0.001),
                           (light, "uuv-simulator", None, 0.001)):
    t0 = time.time()
    with np.errstate(all="ignore"):
        r = replay_check(v, t, U, input_kind="force", target=target, added_mass=mode, physics_step=h)
    print(("0.3 x added mass: " if v is light else "") + r.summary(), f"({time.time() - t0:.0f} s)", flush=True)
for target, mode in (("gz-sim", "fluid"), ("gz-sim", "plugin"), ("uuv-simulator", "fluid")):
    s = stable_step(veh, added_mass=mode, target=target)
    print(f"stable step, {target} {mode if target == 'gz-sim' else ''}: overall {s['overall']:.4g} s; "
          + ", ".join(f"{k} {v['h_max']:.3g} s (added/rigid {v['ratio']:.3g})" for k, v in s.items() if k != "overall"))
