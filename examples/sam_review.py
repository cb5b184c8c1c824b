"""SAM physics review (issue 12): the maneuvers after each fix, and the sensitivity to the
values that have no firm source (reverse thrust ratio, z_g, where the Munk moment lives).

Every configuration is the shipped vehicle file (src/uvsim/vehicles/sam.yaml) with a few
entries changed; each row of the printed tables is one run of every maneuver of
``uvsim.maneuvers`` (multifidelity hull data set, RK4 at dt = 0.02 s).

Run:  python examples/sam_review.py [--json OUT.json]
(docs/sam.md, "Physics review", quotes its output; the "old" column there comes from the
same metrics on the code before the review, commit dfee343.)
"""
import argparse
import copy
import json

import numpy as np

from uvsim.maneuvers import MANEUVERS, run_maneuver
from uvsim.vehicle import load_vehicle, vehicle_from_dict

# The values before the review (sam.yaml at commit dfee343): added mass = Lamb's k-factors
# times the vehicle mass 17.631 kg and its ellipsoid inertia; reverse thrust / 5; no thrust
# deduction; Reynolds-dependent c_dn.
OLD_ADDED_MASS = {"X_udot": 0.52633, "Y_vdot": 16.63765, "Z_wdot": 16.63765, "K_pdot": 0.019094,
                  "M_qdot": 1.685556, "N_rdot": 1.685556}

# the numbers printed per maneuver
KEYS = {
    "tight_loop": ["box_xz_m", "flight_path_rotation_deg", "loop_period_s", "mean_surge_m_s", "max_speed_m_s"],
    "turbo_turn": ["heading_rotation_deg", "time_to_90deg_heading_s", "mean_yaw_rate_rad_s", "yaw_rate_freq_hz", "yaw_rate_amplitude_rad_s",
                   "mean_surge_m_s", "box_xy_m", "depth_change_m"],
    "helix": ["heading_rotation_deg", "roll_range_deg", "extent_x_m", "extent_y_m", "extent_z_m"],
    "lcg_sweep": ["elevation_min_deg", "elevation_max_deg", "pitch_40_45s_deg", "pitch_80_85s_deg", "extent_z_m"],
    "accelerating_turn": ["max_speed_m_s", "time_to_90deg_heading_s", "turn_radius_m", "sideslip_deg",
                          "max_abs_roll_deg"],
}


def variant(damping=None, propulsion=None, added_mass=None, z_g=None):
    """The shipped SAM vehicle with some entries replaced (dicts of vehicle-file keys)."""
    d = copy.deepcopy(load_vehicle("sam").raw)
    d["damping"].update(damping or {})
    d["added_mass"].update(added_mass or {})
    if z_g is not None:
        d["rigid_body"]["r_g"] = [0.0, 0.0, float(z_g)]
    for e in d["effects"]:
        if e["type"] == "sam_propulsion":
            e.update(propulsion or {})
    return vehicle_from_dict(d, source="sam.yaml (review variant)")


def measure(veh) -> dict:
    out = {}
    for name in MANEUVERS:
        m = run_maneuver(name, vehicle=veh).metrics
        out[name] = {k: m[k] for k in KEYS[name]}
    return out


OLD_PHYSICS = dict(damping={"cdn_model": "reynolds"}, added_mass=OLD_ADDED_MASS,
                   propulsion={"reverse_thrust_ratio": 0.2, "thrust_deduction": 0.0})

# cumulative: each step adds one fix to the one before; the last is the shipped file
STEPS = [
    ("1 one Munk moment", OLD_PHYSICS),
    ("3 subcritical c_dn", dict(OLD_PHYSICS, damping={})),
    ("4 added mass from rho V", dict(OLD_PHYSICS, damping={}, added_mass={})),
    ("2 reverse ratio 0.797", dict(damping={}, propulsion={"thrust_deduction": 0.0})),
    ("7 thrust deduction 0.1", {}),
]

SENSITIVITY = [
    ("reverse ratio 0.2 ([SM])", dict(propulsion={"reverse_thrust_ratio": 0.2})),
    ("reverse ratio 1.0 ([FR])", dict(propulsion={"reverse_thrust_ratio": 1.0})),
    ("Munk moment in the tables", dict(damping={"munk_moment": "table"})),
    ("c_dn reynolds", dict(damping={"cdn_model": "reynolds"})),
] + [(f"z_g = {1000 * z:g} mm", dict(z_g=z)) for z in (0.001, 0.005, 0.010, 0.020)]


def _print(rows: dict):
    for name, keys in KEYS.items():
        print(f"\n{name}")
        print(f"  {'configuration':28s}" + "".join(f"{k[:22]:>24s}" for k in keys))
        for label, res in rows.items():
            print(f"  {label:28s}" + "".join(f"{res[name][k]:24.3f}" for k in keys))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write all numbers to this JSON file")
    args = ap.parse_args()
    steps = {label: measure(variant(**cfg)) for label, cfg in STEPS}
    print("Cumulative fixes (each row adds one):")
    _print(steps)
    sens = {"shipped": steps[STEPS[-1][0]]}
    sens.update({label: measure(variant(**cfg)) for label, cfg in SENSITIVITY})
    print("\nSensitivity (shipped file with one entry changed):")
    _print(sens)
    paths = {ds: {name: run_maneuver(name, vehicle=variant(damping={"dataset": ds})).frame[["x", "y", "z"]].to_numpy()
                  for name in MANEUVERS} for ds in ("multifidelity", "jorgensen", "datcom")}
    datasets = {ds: {name: float(np.abs(paths[ds][name] - paths["multifidelity"][name]).max()) for name in MANEUVERS}
                for ds in ("jorgensen", "datcom")}
    print("\nLargest position difference from the multifidelity run (m):")
    for ds, d in datasets.items():
        print(f"  {ds:10s}" + "".join(f"  {k} {v:.2f}" for k, v in d.items()))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"steps": steps, "sensitivity": sens, "datasets": datasets}, fh, indent=1)


if __name__ == "__main__":
    main()
