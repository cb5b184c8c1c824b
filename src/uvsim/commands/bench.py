"""``uvsim bench [--json] [--quick] [--only AREA,...]``: speed figures (docs/performance.md)."""
from __future__ import annotations

import json
import os
import platform


def register(sub) -> None:
    p = sub.add_parser("bench", help="measure simulator / calibration speed")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quick", action="store_true", help="smaller problems (a smoke test, not the recorded figures)")
    p.add_argument("--only", default=None, help="comma-separated areas (core, hydro, sam, calibration, diagnosis; "
                                                 "calibrate-realsensor runs only when named)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from uvsim.benchmarks import available
    from uvsim.errors import UvsimError

    mods = available()
    if args.only:
        want = [a.strip() for a in args.only.split(",") if a.strip()]
        unknown = [a for a in want if a not in mods]
        if unknown:
            raise UvsimError(f"--only: unknown area(s) {unknown}; available: {', '.join(mods)}")
        mods = {a: mods[a] for a in want}
    else:
        mods = {a: m for a, m in mods.items() if getattr(m, "DEFAULT", True)}
    results: dict = {}
    desc: dict = {}
    for area, mod in mods.items():
        if not args.json:
            print(f"[{area}] running ...", flush=True)
        results.update(mod.run(quick=args.quick))
        desc.update(getattr(mod, "DESCRIPTIONS", {}))
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    for k, v in results.items():
        print(f"  {k:34s} {v:14,.1f}   {desc.get(k, '')}")
    return 0
