"""``uvsim simulate --vehicle V --run RUN.csv --out OUT.csv [--current N,E,D]``."""
from __future__ import annotations

from uvsim.commands.checks import add_allow_argument, check_outputs, check_runs_at_door
from uvsim.errors import UvsimError


def _triple(text: str):
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        raise UvsimError(f"--current: expected three numbers N,E,D in m/s, got {text!r}") from None
    if len(vals) != 3:
        raise UvsimError(f"--current: expected three numbers N,E,D in m/s, got {text!r}")
    return vals


def register(sub) -> None:
    p = sub.add_parser("simulate", help="simulate a logged run's inputs from its first measured state")
    p.add_argument("--vehicle", required=True, help="built-in name or vehicle YAML file")
    p.add_argument("--run", required=True, help="run file (.csv or .parquet, LOG_FORMAT columns)")
    p.add_argument("--out", required=True, help="output CSV (t, x, y, z, qw..qz, roll, pitch, yaw, u..r)")
    p.add_argument("--current", default=None, help="constant NED current N,E,D in m/s")
    p.add_argument("--method", default="rk4", help="rk4 (default) or a scipy solve_ivp method (RK45, DOP853, ...)")
    p.add_argument("--substeps", type=int, default=1, help="RK4 steps per sample interval (default 1)")
    p.add_argument("--initial-window", type=float, default=0.0, metavar="S",
                   help="estimate the initial position/attitude by a quadratic fit over the first S seconds "
                        "(default 0: the first measured sample)")
    add_allow_argument(p)
    p.set_defaults(func=_run)


def _run(args) -> int:
    from uvsim.logs import read_run, write_run
    from uvsim.simulate import simulate_run
    from uvsim.vehicle import load_vehicle

    current = _triple(args.current) if args.current else None
    check_outputs({"--out": args.out})
    veh = load_vehicle(args.vehicle)
    run = read_run(args.run)
    check_runs_at_door("simulate", [run], veh, args.allow)
    res = simulate_run(veh, run, current=current, method=args.method, substeps=args.substeps,
                       initial_window_s=args.initial_window)
    df = res.to_pandas()
    cols = ["t", "x", "y", "z", "qw", "qx", "qy", "qz", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r"]
    extra = [c for c in df.columns if c not in cols]
    df = df[cols + extra]
    write_run(args.out, df)
    print(f"simulated {run.name}: {len(df)} samples, {df.t.iloc[-1] - df.t.iloc[0]:.2f} s -> {args.out}")
    return 0
