"""``uvsim simulate --vehicle V --run RUN.csv --out OUT.csv [--current N,E,D] [--compare [--plot P]]``.

``--compare`` prints RMSE, NRMSE and Fit % of every channel the run logged (position,
depth at the pressure sensor, Euler angles, velocities, rates, accelerometer specific
force at the IMU) against the simulation and writes a measured-vs-simulated figure with
a 3-D trajectory view.  Without ``--vehicle`` the vehicle of the dataset the run belongs
to (``manifest.yaml`` beside it) is used.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from uvsim.commands.checks import (add_allow_argument, add_progress_arguments, check_outputs, check_runs_at_door,
                                   command_progress, say)
from uvsim.errors import UvsimError
from uvsim.vehicle_schema import check_current_speed

ANGLES = ("roll", "pitch", "yaw")


def _triple(text: str):
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        raise UvsimError(f"--current: expected three numbers N,E,D in m/s, got {text!r}") from None
    if len(vals) != 3 or not all(np.isfinite(vals)):
        raise UvsimError(f"--current: expected three finite numbers N,E,D in m/s, got {text!r}")
    check_current_speed(vals, f"--current {text}", UvsimError)
    return vals


def register(sub) -> None:
    p = sub.add_parser("simulate", help="simulate a logged run's inputs from its first measured state")
    p.add_argument("--vehicle", default=None,
                   help="built-in name or vehicle YAML (default: the vehicle of the manifest beside the run)")
    p.add_argument("--run", required=True, help="run file (.csv or .parquet, LOG_FORMAT columns)")
    p.add_argument("--out", default=None,
                   help="output CSV (t, x, y, z, qw..qz, roll, pitch, yaw, u..r); required without --compare")
    p.add_argument("--current", default=None, help="constant NED current N,E,D in m/s")
    p.add_argument("--method", default="rk4", help="rk4 (default) or a scipy solve_ivp method (RK45, DOP853, ...)")
    p.add_argument("--substeps", type=int, default=1, help="RK4 steps per sample interval (default 1)")
    p.add_argument("--initial-window", type=float, default=0.0, metavar="S",
                   help="estimate the initial position/attitude by a quadratic fit over the first S seconds "
                        "(default 0: the first measured sample)")
    p.add_argument("--compare", action="store_true",
                   help="print RMSE / NRMSE / Fit %% per logged channel and write a measured-vs-simulated plot")
    p.add_argument("--plot", default=None, help="figure for --compare (default: <out>_compare.png beside --out, else "
                                                "<run name>_compare.png in the current directory, never beside the run)")
    add_allow_argument(p)
    add_progress_arguments(p)
    p.set_defaults(func=_run)


def _vehicle_for(args):
    from uvsim.logs import MANIFEST, read_dataset

    if args.vehicle:
        return args.vehicle
    manifest = Path(args.run).parent / MANIFEST
    if manifest.is_file():
        ds = read_dataset(manifest)
        if ds.vehicle:
            return ds.vehicle_file or ds.vehicle
    raise UvsimError("--vehicle: not given and no manifest.yaml with a vehicle beside the run")


def _run(args) -> int:
    from uvsim.gaps import split_run
    from uvsim.initial_state import check_initial_window
    from uvsim.latency import delay_inputs
    from uvsim.logs import read_run, write_run
    from uvsim.simulate import check_method, check_substeps, simulate_run
    from uvsim.vehicle import load_vehicle

    if args.out is None and not args.compare:
        raise UvsimError("--out: required unless --compare is given")
    current = _triple(args.current) if args.current else None
    check_method(args.method)
    if args.compare and not args.plot:  # the shipped runs live in the installed package: never write beside them
        base = Path(args.out) if args.out else Path(Path(args.run).stem)
        args.plot = str(base.with_name(base.stem + "_compare.png"))
    check_substeps(args.substeps)
    check_initial_window(args.initial_window, where="--initial-window")
    check_outputs({"--out": args.out, "--plot": args.plot}, inputs={"--run": args.run, "--vehicle": args.vehicle})
    veh = load_vehicle(_vehicle_for(args))
    run = read_run(args.run)
    check_initial_window(args.initial_window, float(run.t[-1] - run.t[0]), "--initial-window")
    segments = split_run(run)  # a run with gaps: each segment from its own first measured state (uvsim.gaps)
    check_runs_at_door("simulate", segments, veh, args.allow)
    progress = command_progress("simulate", args)
    pieces = []
    for seg in segments:
        seg = delay_inputs(seg, veh.sensor_latency)  # as simulate_run applies them (and --compare's forces)
        pieces.append((seg, simulate_run(veh, seg, current=current, method=args.method, substeps=args.substeps,
                                         initial_window_s=args.initial_window, progress=progress)))
    if veh.sensor_latency:
        print(f"inputs applied {veh.sensor_latency * 1000:.1f} ms late (the vehicle's sensors.latency)")
    if args.out:
        import pandas as pd

        df = pd.concat([res.to_pandas() for _, res in pieces], ignore_index=True)
        cols = ["t", "x", "y", "z", "qw", "qx", "qy", "qz", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r"]
        extra = [c for c in df.columns if c not in cols]
        df = df[cols + extra]
        write_run(args.out, df)
        per = f" in {len(pieces)} segments, each from its own first measured state" if len(pieces) > 1 else ""
        print(f"simulated {run.name}{per}: {len(df)} samples, {df.t.iloc[-1] - df.t.iloc[0]:.2f} s -> {args.out}")
    if args.compare:
        _compare(args, veh, run, pieces, current, progress)
    return 0


# ---------------------------------------------------------------------------- --compare
def _specific_force(veh, run, y, current) -> np.ndarray:
    """Accelerometer specific force at the IMU, body axes (m/s^2), along the simulation:
    ``f = v_dot + w x v + w_dot x r + w x (w x r) - g R^T e_3`` with ``nu_dot`` from the
    model's equations of motion at each sample (log format: level at rest reads (0, 0, -g));
    the accelerometer model of the fits (:func:`uvsim.measurements.specific_force`)."""
    from uvsim.measurements import specific_force
    from uvsim.model import Model

    n = len(run.t)
    ov = {} if current is None else dict(zip(("current_n", "current_e", "current_d"), current))
    model = Model(veh, ov, n=n, input_kind=run.input_kind)
    with np.errstate(all="ignore"):
        nud = model.rhs(float(run.t[0]), y, run.inputs, run.voltage)[:, 7:13]
    return specific_force(y, nud, veh.sensors.get("imu"), veh.g)


def compare_channels(veh, run, res, current=None) -> list[dict]:
    """Measured and simulated series of every channel the run logged.

    Returns ``[{"name", "unit", "measured" (n,), "simulated" (n,)}]``; angles in
    degrees, the simulated angle on the measured angle's branch (no 2 pi jumps)."""
    from uvsim.kinematics import quat_to_euler, quat_to_rotation

    y = res.y
    d = run.data
    out = []

    def add(name, unit, meas, sim):
        out.append({"name": name, "unit": unit, "measured": np.asarray(meas, float), "simulated": np.asarray(sim, float)})

    for j, c in enumerate("xyz"):
        if c in d:
            add(c, "m", d[c], y[:, j])
    if run.has_depth:
        r_p = np.asarray(veh.sensors.get("pressure", np.zeros(3)), float)
        add("depth", "m", run.depth, y[:, 2] + quat_to_rotation(y[:, 3:7])[:, 2, :] @ r_p)
    if run.has_attitude:
        em, es = run.euler, quat_to_euler(y[:, 3:7])
        for j, name in enumerate(ANGLES):
            ok = np.isfinite(em[:, j])
            if not run.euler_mask[j] or not ok.any():
                continue
            m = np.full(len(run.t), np.nan)
            m[ok] = np.unwrap(em[ok, j])
            # the simulated angle, unwrapped on its own and put on the measured angle's branch
            # at the first logged sample (a continuous curve; errors are the wrapped differences)
            s = np.unwrap(es[:, j])
            i0 = int(np.flatnonzero(ok)[0])
            s = s + 2 * np.pi * np.round((m[i0] - s[i0]) / (2 * np.pi))
            add(name, "deg", np.degrees(m), np.degrees(s))
    for j, c in enumerate(("u", "v", "w", "p", "q", "r")):
        if c in d:
            add(c, "m/s" if j < 3 else "rad/s", d[c], y[:, 7 + j])
    if run.has_acceleration:
        f = _specific_force(veh, run, y, current)
        for j, c in enumerate(("acc_x", "acc_y", "acc_z")):
            add(c, "m/s^2", run.acceleration[:, j], f[:, j])
    return out


def channel_metrics(channels: list[dict]) -> list[dict]:
    """RMSE, NRMSE (RMSE / measured range) and Fit % per channel (:mod:`uvsim.metrics`)."""
    from uvsim.metrics import fit_percent, nrmse, rmse

    rows = []
    for ch in channels:
        m, s = ch["measured"], ch["simulated"]
        if ch["unit"] == "deg":  # compare angles by their wrapped difference
            s = m - (m - s + 180.0) % 360.0 + 180.0
        ok = np.isfinite(m) & np.isfinite(s)
        rows.append({"name": ch["name"], "unit": ch["unit"], "n": int(ok.sum()),
                     "rmse": float(rmse(m[ok] - s[ok])) if ok.any() else float("nan"),
                     "nrmse_percent": 100.0 * nrmse(m, s), "fit_percent": fit_percent(m, s)})
    return rows


def _joined(per_segment: list[list[dict]], lengths: list[int]) -> list[dict]:
    """The channels of several segments (:func:`compare_channels` of each) end to end: a
    channel a segment does not log is NaN there."""
    names = list(dict.fromkeys(c["name"] for chans in per_segment for c in chans))
    out = []
    for name in names:
        parts = [next((c for c in chans if c["name"] == name), None) for chans in per_segment]
        unit = next(c["unit"] for c in parts if c is not None)
        cat = {k: np.concatenate([c[k] if c is not None else np.full(n, np.nan) for c, n in zip(parts, lengths)])
               for k in ("measured", "simulated")}
        out.append({"name": name, "unit": unit, **cat})
    return out


def _measured_track(run) -> np.ndarray:
    """Measured NED position for the 3-D view (display only): depth on the z axis of a
    depth-only log, and each axis held between its samples so that x, y and depth logged by
    different sensors at different times form one track."""
    import pandas as pd

    meas = run.position.copy()
    if run.has_depth and np.isnan(meas[:, 2]).all():
        meas[:, 2] = run.depth
    return pd.DataFrame(meas).ffill().to_numpy()


def _with_breaks(pieces, chans: list[dict], lengths: list[int]):
    """The figure's times, simulated and measured tracks and channels, with one NaN sample
    in each gap between segments so that no line is drawn across it (display only)."""
    ends = np.cumsum(lengths)[:-1]
    gap_t = [0.5 * (a.t[-1] + b.t[0]) for (a, _), (b, _) in zip(pieces[:-1], pieces[1:])]

    def brk(x, fill=np.nan):
        return np.insert(x, ends, fill, axis=0)

    t = brk(np.concatenate([seg.t for seg, _ in pieces]), gap_t)
    sim = brk(np.concatenate([res.y[:, 0:3] for _, res in pieces]))
    meas = brk(np.concatenate([_measured_track(seg) for seg, _ in pieces]))
    chans = [{**c, "measured": brk(c["measured"]), "simulated": brk(c["simulated"])} for c in chans]
    return t, sim, meas, chans


#: Fewer samples than this in ``--compare``: the table is printed with a warning (a Fit % of a
#: handful of samples is mostly the noise of those samples).
MIN_COMPARE_SAMPLES = 20


def _compare(args, veh, run, pieces, current, progress=None) -> None:
    """Print the per-channel table and write the figure for the simulated ``pieces``
    ((segment, result) pairs: the run itself, or its segments when it has gaps)."""
    from uvsim.plotting.compare import compare_run

    lengths = [len(seg.t) for seg, _ in pieces]
    chans = _joined([compare_channels(veh, seg, res, current) for seg, res in pieces], lengths)
    rows = channel_metrics(chans)
    span = sum(seg.t[-1] - seg.t[0] for seg, _ in pieces)
    per = f" in {len(pieces)} segments (gaps left out)" if len(pieces) > 1 else ""
    print(f"{run.name} vs {veh.name}: {sum(lengths)} samples, {span:.2f} s{per}")
    if sum(lengths) < MIN_COMPARE_SAMPLES:
        say("simulate", f"warning: only {sum(lengths)} samples ({span:.2f} s): an RMSE and a Fit % over so few "
                        f"samples say little about the model; compare a run of at least {MIN_COMPARE_SAMPLES} samples")
    print(f"{'channel':>8} {'unit':>6} {'n':>6} {'RMSE':>11} {'NRMSE %':>9} {'Fit %':>9}")
    for r in rows:
        print(f"{r['name']:>8} {r['unit']:>6} {r['n']:>6d} {r['rmse']:>11.4g} {r['nrmse_percent']:>9.2f} "
              f"{r['fit_percent']:>9.2f}")
    t, sim, meas, chans = _with_breaks(pieces, chans, lengths)
    plot = Path(args.plot)
    from uvsim.progress import as_progress

    with as_progress(progress).stage(f"plot {plot}"):
        compare_run(t, chans, sim, meas, plot, title=f"{run.name}: measured vs {veh.name}")
    print(f"plot -> {plot}")
