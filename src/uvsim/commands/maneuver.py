"""``uvsim maneuver NAME --out traj.csv [--plots DIR]``: SAM hydrobatic maneuvers.

NAME: tight_loop, turbo_turn, helix, lcg_sweep, accelerating_turn (seed 003 sec. V-C).
Writes the LOG_FORMAT columns (commands as thrust_1..7 in the order rpm_1, rpm_2,
tv_pitch, tv_yaw, vbs, lcg, tcg) plus the actuator states, prints the measured numbers.
"""
from __future__ import annotations

import json


def register(subparsers) -> None:
    from uvsim.maneuvers import MANEUVERS
    from uvsim.sam.buildup import DATASETS

    p = subparsers.add_parser(
        "maneuver", help="simulate a SAM hydrobatic maneuver (seed 003) and write CSV / plots",
        description="Simulate a SAM maneuver with the component build-up model and write the trajectory "
                    "(LOG_FORMAT columns; inputs thrust_1..7 = SAM commands rpm_1, rpm_2, tv_pitch, tv_yaw, "
                    "vbs, lcg, tcg) plus actuator states.")
    p.add_argument("name", choices=list(MANEUVERS), help="maneuver")
    p.add_argument("--out", required=True, help="output CSV file")
    p.add_argument("--plots", help="directory for PNG plots (trajectory, angles/rates, actuators)")
    p.add_argument("--dataset", choices=list(DATASETS), default="multifidelity", help="hull data set")
    p.add_argument("--dt", type=float, help="RK4 step and sample interval, s (default per maneuver)")
    p.add_argument("--duration", type=float, help="duration, s (default per maneuver)")
    p.add_argument("--json", action="store_true", help="print the measured numbers as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from uvsim.commands.checks import check_outputs
    from uvsim.logs import write_run
    from uvsim.maneuvers import run_maneuver

    check_outputs({"--out": args.out}, {"--plots": args.plots})
    res = run_maneuver(args.name, dataset=args.dataset, dt=args.dt, duration=args.duration)
    out = Path(args.out)
    if out.parent and not out.parent.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
    write_run(out, res.frame)
    info = dict(res.metrics, maneuver=args.name, dataset=args.dataset, csv=str(out),
                simulated_s=float(res.frame["t"].iloc[-1]), wall_s=res.wall_time,
                realtime_factor=float(res.frame["t"].iloc[-1]) / res.wall_time)
    if args.plots:
        from uvsim.plotting.sam import plot_maneuver

        info["plots"] = [str(p) for p in plot_maneuver(res.frame, args.plots, args.name)]
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        for k, v in info.items():
            print(f"{k}: {v:.4g}" if isinstance(v, float) else f"{k}: {v}")
    return 0
