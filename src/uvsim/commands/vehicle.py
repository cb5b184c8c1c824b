"""``uvsim vehicle show NAME|FILE [--json]`` and ``uvsim vehicle list``."""
from __future__ import annotations

import json

import numpy as np


def register(sub) -> None:
    p = sub.add_parser("vehicle", help="show or list vehicle definitions")
    vs = p.add_subparsers(dest="vehicle_cmd", metavar="ACTION")
    vs.required = True
    s = vs.add_parser("show", help="print a vehicle's mass, inertia, added mass and damping")
    s.add_argument("vehicle", help="built-in name or path to a vehicle YAML file")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=_show)
    ls = vs.add_parser("list", help="list the built-in vehicles")
    ls.set_defaults(func=_list)


def _list(args) -> int:
    from uvsim.vehicle import builtin_vehicles, load_vehicle

    for name in builtin_vehicles():
        print(f"{name:28s} {load_vehicle(name).description}")
    return 0


def _show(args) -> int:
    from uvsim.vehicle import load_vehicle

    v = load_vehicle(args.vehicle)
    s = v.summary()
    if args.json:
        print(json.dumps(s, indent=2))
        return 0
    np.set_printoptions(precision=4, suppress=True)
    print(f"{s['name']}  ({s['source']})")
    print(f"  mass {s['mass']:.4g} kg, weight {s['weight']:.4g} N, buoyancy {s['buoyancy']:.4g} N")
    print(f"  r_g {s['r_g']} m, r_b {s['r_b']} m")
    print("  inertia (kg m^2):\n" + "\n".join("    " + str(r) for r in np.array(s["inertia"])))
    print("  added mass (positive):\n" + "\n".join("    " + str(r) for r in np.array(s["added_mass"])))
    print(f"  linear damping (paper sign):    {s['linear_damping']}")
    print(f"  quadratic damping (paper sign): {s['quadratic_damping']}")
    print(f"  thrusters: {s['n_thrusters']}, effects: {', '.join(map(str, s['effects'])) or 'none'}")
    return 0
