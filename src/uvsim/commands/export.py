"""``uvsim export VEHICLE --to gz-sim|uuv-simulator|json --out FILE`` (docs/import_export.md)."""
from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser("export", help="write a vehicle as a Gazebo (gz-sim) / UUV Simulator model or JSON")
    p.set_defaults(func=lambda args: 0)
