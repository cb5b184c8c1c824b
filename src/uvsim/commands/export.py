"""``uvsim export VEHICLE --to gz-sim|uuv-simulator|json --out FILE [--added-mass fluid|plugin]
[--check RUN.csv|standard [--physics-step S]] [--force]`` (docs/import_export.md)."""
from __future__ import annotations

import sys


def register(sub) -> None:
    from uvsim.export import TARGETS

    p = sub.add_parser("export", help="write a vehicle as a Gazebo (gz-sim) / UUV Simulator model or JSON")
    p.add_argument("vehicle", help="built-in name or vehicle YAML (e.g. a calibrated one)")
    p.add_argument("--to", required=True, choices=TARGETS, help="target format")
    p.add_argument("--out", required=True, help="file to write (.sdf, .xacro or .json)")
    p.add_argument("--added-mass", choices=("fluid", "plugin"), default=None,
                   help="gz-sim: added mass as SDF <fluid_added_mass> carried by the physics engine (fluid, default: "
                        "reproduces uvsim) or as Hydrodynamics xDotU.. terms (plugin: gz-sim applies +C_A(v)v there, "
                        "the opposite of Fossen's sign, and diverges when M_A >= M_RB; a warning says where)")
    p.add_argument("--force", action="store_true",
                   help="uuv-simulator: write the model even when uvsim's replay of UUV Simulator's equations "
                        "diverges with it, or its centre of gravity is off the body origin (refused otherwise, with "
                        "the reason)")
    p.add_argument("--check", metavar="RUN", default=None,
                   help="replay a logged run's inputs (CSV in the log format), or 'standard' for the built-in 60 s "
                        "maneuver, through the exported model under the target plugin's own equations and report "
                        "its deviation from uvsim's simulation, the stable physics step and the thrust tables")
    p.add_argument("--physics-step", type=float, default=None,
                   help="physics step of the replay, s (default 0.001, Gazebo's default max_step_size)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from uvsim.errors import VehicleError
    from uvsim.export import export_vehicle
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(args.vehicle)
    if args.check is None and args.physics_step is not None:
        raise VehicleError("--physics-step needs --check RUN")
    path, warnings, text = export_vehicle(veh, args.to, args.out, added_mass=args.added_mass, force=args.force)
    for w in warnings:
        print(f"uvsim export: warning: {w}", file=sys.stderr)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    print(f"exported {veh.name} ({veh.source}) to {args.to}: {path}")
    if args.check is not None:
        return _check(veh, args, text)
    return 0


def _check(veh, args, text) -> int:
    from uvsim.errors import VehicleError
    from uvsim.export.replay import DEFAULT_STEP, replay_check, stable_step, standard_maneuver
    from uvsim.export.thrust_tables import describe_thrust_check, file_thrust_check

    if args.to not in ("gz-sim", "uuv-simulator"):
        raise VehicleError(f"--check replays a Gazebo target (gz-sim, uuv-simulator), not {args.to}")
    h = DEFAULT_STEP if args.physics_step is None else args.physics_step
    if args.check == "standard":
        t, U = standard_maneuver(60.0)
        print("replaying the standard 60 s maneuver (uvsim.export.replay.standard_maneuver, generalized forces)")
        res = replay_check(veh, t, U, input_kind="force", target=args.to, physics_step=h, text=text)
    else:
        from uvsim.logs import read_run

        run = read_run(args.check)  # only its inputs are replayed; what the reader noted is said
        for n in run.notes:
            print(f"uvsim export: note: {n}", file=sys.stderr)
        res = replay_check(veh, run, target=args.to, physics_step=h, text=text)
    print(res.summary())
    mode = "fluid" if args.to == "gz-sim" and (args.added_mass or "fluid") == "fluid" else "plugin"
    st = stable_step(veh, added_mass=mode, target=args.to)
    worst = min((k for k in st if k != "overall"), key=lambda k: st[k]["h_max"])
    h_max = st["overall"]
    print("largest stable physics step for the added-mass and damping terms (linearized at 1 m/s, 1 rad/s): "
          + ("none: unstable at every step" if h_max == 0.0 else ("any" if h_max == float("inf") else f"{h_max:.4g} s"))
          + f" (limited by {worst}, added/rigid mass {st[worst]['ratio']:.3g})")
    if veh.actuators.curves:
        if args.to == "gz-sim":
            from uvsim.export.gz_sim import parse_gz_sdf as parse
        else:
            from uvsim.export.uuv_simulator import parse_uuv_xacro as parse
        print(describe_thrust_check(file_thrust_check(veh, parse(text), args.to), veh.actuators.curves))
    return 0 if not res.diverged else 2
