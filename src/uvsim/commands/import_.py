"""``uvsim import ardusub LOG --out DIR`` and ``uvsim import bag BAG --map MAP --out DIR``
(docs/import_export.md)."""
from __future__ import annotations

from uvsim.commands.checks import add_progress_arguments, command_progress
from uvsim.errors import UvsimError


def _water(text):
    if text is None or text in ("fresh", "salt"):
        return text
    try:
        return float(text)
    except ValueError:
        raise UvsimError(f"--water: expected fresh, salt or a density in kg/m^3, got {text!r}") from None


def register(sub) -> None:
    p = sub.add_parser("import", help="turn a real vehicle log (ArduSub .BIN/.tlog, ROS bag) into a dataset")
    kinds = p.add_subparsers(dest="import_kind", metavar="KIND")
    kinds.required = True

    a = kinds.add_parser("ardusub", help="ArduSub DataFlash .BIN or MAVLink .tlog (needs uvsim[ardusub])")
    a.add_argument("log", help="the .BIN or .tlog file")
    a.add_argument("--out", required=True, help="dataset directory to write (manifest.yaml + one CSV per run)")
    a.add_argument("--vehicle", default=None,
                   help="vehicle name or YAML (default by FRAME_CONFIG: 2 -> bluerov2_heavy, "
                        "1 -> bluerov2_vectored_standin)")
    a.add_argument("--segments", default=None, help="segments YAML (start/end/dof/split/name); default: armed intervals")
    a.add_argument("--water", default=None, help="fresh, salt or a density in kg/m^3 (default: the log's BARO_SPEC_GRAV)")
    a.add_argument("--surface-pressure", type=float, default=None, metavar="PA",
                   help="surface pressure (Pa) for depth (default: pre-dive median, else BAROn_GND_PRESS)")
    a.add_argument("--adapt-vehicle", action="store_true",
                   help="when the log's motors are exactly reversed with respect to the vehicle (MOT_n_DIRECTION), "
                        "write an adapted copy of the vehicle beside the manifest instead of failing")
    a.add_argument("--imu", type=int, default=0, help="DataFlash IMU instance for rates and accelerations (default 0)")
    add_progress_arguments(a)
    a.set_defaults(func=_ardusub)

    b = kinds.add_parser("bag", help="ROS 1 (.bag) or ROS 2 bag directory (needs uvsim[ros])")
    b.add_argument("bag", help="the .bag file (ROS 1) or bag directory (ROS 2)")
    b.add_argument("--map", required=True, help="topic map YAML (examples in docs/import_export.md)")
    b.add_argument("--out", required=True, help="dataset directory to write")
    b.add_argument("--vehicle", default=None, help="vehicle name or YAML (default: the map's 'vehicle')")
    b.add_argument("--segments", default=None, help="segments YAML; default: the whole bag as one run")
    add_progress_arguments(b)
    b.set_defaults(func=_bag)




def _ardusub(args) -> int:
    from uvsim.importers.ardusub_import import import_ardusub
    from uvsim.importers.build import summary_lines

    res = import_ardusub(args.log, args.out, vehicle=args.vehicle, segments=args.segments,
                         water=_water(args.water), surface_pressure=args.surface_pressure,
                         adapt_vehicle=args.adapt_vehicle, imu_instance=args.imu,
                         progress=command_progress("import", args))
    print("\n".join(summary_lines(res)))
    return 0


def _bag(args) -> int:
    from uvsim.importers.build import summary_lines
    from uvsim.importers.rosbag import import_bag

    res = import_bag(args.bag, args.map, args.out, vehicle=args.vehicle, segments=args.segments,
                     progress=command_progress("import", args))
    print("\n".join(summary_lines(res)))
    return 0
