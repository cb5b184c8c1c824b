"""``uvsim export VEHICLE --to gz-sim|uuv-simulator|json --out FILE [--added-mass plugin|fluid]``
(docs/import_export.md)."""
from __future__ import annotations

import sys


def register(sub) -> None:
    from uvsim.export import TARGETS

    p = sub.add_parser("export", help="write a vehicle as a Gazebo (gz-sim) / UUV Simulator model or JSON")
    p.add_argument("vehicle", help="built-in name or vehicle YAML (e.g. a calibrated one)")
    p.add_argument("--to", required=True, choices=TARGETS, help="target format")
    p.add_argument("--out", required=True, help="file to write (.sdf, .xacro or .json)")
    p.add_argument("--added-mass", choices=("plugin", "fluid"), default="plugin",
                   help="gz-sim: added mass as Hydrodynamics xDotU.. terms (plugin, default) or as SDF "
                        "<fluid_added_mass> (fluid; DART physics; avoids the explicit added-mass instability)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from uvsim.export import export_vehicle
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(args.vehicle)
    path, warnings, text = export_vehicle(veh, args.to, args.out, added_mass=args.added_mass)
    for w in warnings:
        print(f"uvsim export: warning: {w}", file=sys.stderr)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    print(f"exported {veh.name} ({veh.source}) to {args.to}: {path}")
    return 0
