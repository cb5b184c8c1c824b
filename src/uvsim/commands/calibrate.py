"""``uvsim calibrate``: fit a vehicle model to a dataset (docs/calibration.md).

    uvsim calibrate --data DIR [--vehicle NAME|FILE] [--dof surge,...] [--free z_b,thruster_gain_*]
                    [--fix NAME,...] [--bounds NAME=LO:HI,...] [--weights NAME=W,...] [--noise NAME=SIGMA,...]
                    [--horizons 2,6] [--continuity 0.05] [--no-gyro-bias] [--no-prior] [--loss huber] [--sample-weighting per_sample] [--seed S]
                    [--population P --generations G]
                    [--workers N] [--dask ADDR|local] [--checkpoint CKPT] [--resume CKPT] [--no-refine]
                    [--supply-voltage auto] [--trade-off explore]
                    --out fitted.yaml [--json report.json] [--plots DIR] [--progress | --no-progress]

Seed 000's GA per DOF for runs marked with one DOF, then one joint windowed
prediction-error fit of every training run (marked and ``dof: mixed``).
"""
from __future__ import annotations

import json
import logging
from pathlib import Path

from uvsim.commands import lag_option, parse_pairs
from uvsim.commands.checks import (add_allow_argument, add_judge_horizon_argument, add_progress_arguments,
                                   check_outputs, check_runs_at_door, command_progress, judge_option,
                                   remove_checkpoints, say)
from uvsim.commands.calibration_output import (jsonable, print_summary, print_verdict,  # noqa: F401 (re-exported)
                                               record_outcome, save_fitted_vehicle)
from uvsim.errors import UvsimError
from uvsim.fitting.verdict import EXIT_CODES

def register(sub) -> None:
    from uvsim.fit_settings import DEFAULT_SAMPLE_WEIGHTING
    from uvsim.fit_settings import LOSSES
    from uvsim.fit_settings import SAMPLE_WEIGHTINGS

    p = sub.add_parser("calibrate", help="fit a vehicle model to logged runs (seed 000 GA per DOF + joint "
                                         "prediction-error fit of all runs)",
                       epilog="Exit status: 0 the verdict is 'better' (the fitted model beats the one you started from "
                              "on the validation runs, no channel worse); 3 'trade-off' (better pooled, some channel "
                              "worse: named; vehicle written); 2 'worse', 'refused' (a sanity check failed) or "
                              "an error (report and plots written, the vehicle only with --keep-worse). "
                              "docs/calibration.md, 'The verdict'.")
    p.add_argument("--data", required=True, help="dataset directory (manifest.yaml + runs)")
    p.add_argument("--vehicle", default=None, help="starting vehicle: built-in name, YAML file, or NAME with "
                                                    "NAME.yaml beside the manifest (default: the manifest's vehicle)")
    p.add_argument("--dof", default=None, help="comma-separated DOFs to fit (default: all)")
    p.add_argument("--free", default=None, metavar="NAME,...",
                   help="also fit these parameters or families in the joint stage, e.g. "
                        "z_b,thruster_gain_*,thruster_reverse_* (the real-log command of docs/calibration.md: the "
                        "CB height and every thruster's gain and reverse ratio)")
    p.add_argument("--fix", default=None, metavar="NAME,...", help="never fit these parameters or families")
    p.add_argument("--bounds", default=None, metavar="NAME=LO:HI,...",
                   help="search bounds (every stage), e.g. z_b=-0.05:0,thruster_gain_3=0.2:1.2")
    p.add_argument("--weights", default=None, metavar="NAME=W,...",
                   help="signal weights by group (position, depth, attitude, velocity, rates, acceleration) or "
                        "channel (x..z, depth, roll, pitch, yaw, u..w, p..r, acc_x..acc_z), every stage; "
                        "0 leaves a signal out")
    p.add_argument("--noise", default=None, metavar="NAME=SIGMA,...",
                   help="1-sigma noise level by group or channel (default: estimated from each run)")
    p.add_argument("--horizons", default=None, metavar="H1,H2,...",
                   help="window lengths (s) of the joint fit's continuation, 'whole' for whole runs, each channel "
                        "then scaled by its own error, the verdict's measure (default 2)")
    p.add_argument("--continuity", default=None, metavar="C1,C2,...",
                   help="factors of the continuity defects' sd at the last horizon, one stage each (default 0.05: "
                        "windows restart little, so the fit improves the free simulation; 1 is diagnosis' softer "
                        "setting)")
    p.add_argument("--max-iter", type=int, default=80,
                   help="Levenberg-Marquardt iterations per horizon (default 80); a last stage that stops there "
                        "is reported as unfinished beside the verdict, which judges the model it reached")
    p.add_argument("--no-gyro-bias", action="store_true", help="do not fit a gyro bias per run")
    p.add_argument("--no-acc-bias", action="store_true",
                   help="do not fit an accelerometer offset per run (runs logging acc_x, acc_y, acc_z)")
    p.add_argument("--no-attitude-bias", action="store_true",
                   help="do not fit a roll / pitch offset per run of an attitude filter (runs logging Euler angles "
                        "beside a gyro)")
    p.add_argument("--loss", choices=LOSSES, default="linear",
                   help="loss of the joint stage's measurement residuals: linear (least squares, default) or huber "
                        "(beyond 3 noise sigmas a residual costs linearly: spikes, dropouts, bursts of model error)")
    p.add_argument("--sample-weighting", choices=SAMPLE_WEIGHTINGS, default=DEFAULT_SAMPLE_WEIGHTING,
                   help="per_second (default): a channel logged at a lower rate than the run's fastest is weighted "
                        "up by the ratio of the rates (10 Hz depth beside a 100 Hz IMU: x10); per_sample: every "
                        "sample alike")
    p.add_argument("--no-prior", action="store_true",
                   help="joint fit by least squares within the bounds only, without the starting vehicle as a prior "
                        "(default: maximum a posteriori, docs/calibration.md 'Priors')")
    p.add_argument("--attitude-lag", default="auto", metavar="auto|SECONDS",
                   help="time constant of the attitude filter's lag on logged Euler angles: 'auto' (default, "
                        "estimated from the gyro), a number, or 0 for none")
    p.add_argument("--latency", default=None, metavar="auto|SECONDS",
                   help="how late the logged sensors read relative to the logged inputs: 'auto' (estimated after the "
                        "joint fit, and fitted again with it when it helps; docs/calibration.md 'Sensor latency'), a "
                        "number of seconds, or omitted: the vehicle file's sensors.latency (0 when it states none)")
    p.add_argument("--supply-voltage", choices=("auto",), default=None,
                   help="'auto': fit again with the thrusters on the T200 voltage family (supply_voltage freed) and "
                        "keep that fit when it fits the training runs better in every channel (vehicle on the "
                        "t200_16v curve; part of the real-log command; docs/calibration.md 'Supply voltage')")
    p.add_argument("--trade-off", choices=("explore",), default=None,
                   help="'explore': when the verdict is a trade-off, fit again with the structure the worse channels "
                        "point to freed (thruster positions; centre of buoyancy) and keep a refit whose verdict is "
                        "better (part of the real-log command; docs/calibration_method.md 'After a trade-off')")
    p.add_argument("--no-screen", action="store_true",
                   help="free every DOF's parameters for mixed runs, also those the data do not excite")
    p.add_argument("--ga-channels", choices=("own", "all"), default="own",
                   help="channels of each DOF's GA fitness: its own (seed 000, default) or all")
    p.add_argument("--seed", type=int, default=0, help="random seed (same seed -> identical result)")
    p.add_argument("--population", type=int, default=60, help="GA population per DOF (seed 000: 60)")
    p.add_argument("--generations", type=int, default=30, help="GA generations (seed 000: 30)")
    p.add_argument("--margin", type=float, default=0.5,
                   help="search range of inertias, added masses and damping around their values in the GA stage, "
                        "and in the joint stage with --no-prior (0.5 = +-50%%); with priors the joint stage's bounds "
                        "are physical limits (sign, factor 10)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes (GA and joint fit)")
    p.add_argument("--dask", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address, or 'local' (GA evaluations; needs uvsim[dask])")
    p.add_argument("--checkpoint", default=None, help="checkpoint file written after every GA generation and "
                                                      "joint iteration (default: <out>.ckpt)")
    p.add_argument("--resume", default=None, metavar="CKPT", help="continue from a checkpoint")
    p.add_argument("--no-refine", action="store_true", help="skip the joint fit (GA only)")
    p.add_argument("--low-speed-exponent", type=float, default=0.0,
                   help="extra GA run weight (amplitude/median)^-E favouring slow runs (default 0: manifest weights)")
    p.add_argument("--out", required=True, help="fitted vehicle YAML (complete, loadable by every command)")
    p.add_argument("--json", default=None, help="report JSON")
    p.add_argument("--keep-worse", action="store_true",
                   help="write the fitted vehicle also when the verdict is 'worse' (not better than the starting "
                        "model) or 'refused' (a fit that failed a sanity check); the exit status stays 2 and "
                        "report.json's status.verdict says which")
    p.add_argument("--plots", default=None, help="directory for plots (measured vs simulated, error boxplots, "
                                                 "GA convergence); written whatever the verdict")
    add_judge_horizon_argument(p, "starting")
    add_allow_argument(p)
    add_progress_arguments(p)
    p.set_defaults(func=_run)


def parse_bounds(text: str | None) -> dict | None:
    """``"z_b=-0.05:0,X_u=-1:-0.01"`` -> ``{"z_b": (-0.05, 0.0), ...}``."""
    if not text:
        return None
    out = {}
    for item in text.split(","):
        name, sep, rng = item.partition("=")
        lo, colon, hi = rng.partition(":")
        if not sep or not colon or not name.strip():
            raise UvsimError(f"--bounds: expected NAME=LOW:HIGH pairs separated by commas, got {item!r}")
        try:
            out[name.strip()] = (float(lo), float(hi))
        except ValueError:
            raise UvsimError(f"--bounds: {name.strip()}: LOW and HIGH must be numbers, got {rng!r}") from None
    return out


def parse_horizons(text: str | None):
    """``"2,6"`` -> ``(2.0, 6.0)``; ``whole`` -> None (whole runs); None -> the Calibrator's default."""
    from uvsim.fit_settings import DEFAULT_HORIZONS

    if not text:
        return DEFAULT_HORIZONS
    out = []
    for item in text.split(","):
        item = item.strip()
        if item in ("whole", "none", "run"):
            out.append(None)
            continue
        try:
            out.append(float(item))
        except ValueError:
            raise UvsimError(f"--horizons: expected window lengths in s or 'whole', got {item!r}") from None
    return tuple(out)


def parse_continuity(text: str | None):
    """``"1,0.05"`` -> ``(1.0, 0.05)``; None -> the Calibrator's default."""
    from uvsim.fit_settings import DEFAULT_CONTINUITY
    from uvsim.fitting.objective import continuity_factors

    if not text:
        return DEFAULT_CONTINUITY
    try:
        return tuple(continuity_factors([float(item) for item in text.split(",")]))
    except (ValueError, UvsimError):
        raise UvsimError(f"--continuity: expected positive numbers separated by commas, got {text!r}") from None


def _run(args) -> int:
    from uvsim.calibration import Calibrator
    from uvsim.calibration.inputs import resolve_vehicle
    from uvsim.logs import read_dataset
    from uvsim.plausibility import parse_allow

    out = Path(args.out)
    ckpt = args.checkpoint or str(out.with_suffix(out.suffix + ".ckpt"))
    weights, noise = parse_pairs(args.weights, "--weights"), parse_pairs(args.noise, "--noise")
    bounds, horizons, lag = parse_bounds(args.bounds), parse_horizons(args.horizons), lag_option(args.attitude_lag)
    judge, allow = judge_option(args.judge_horizon), parse_allow(args.allow)
    check_outputs({"--out": out, "--json": args.json, "--checkpoint": ckpt}, {"--plots": args.plots})
    if args.resume:
        from uvsim.calibration.joint import joint_checkpoint_path

        if not (Path(args.resume).is_file() or joint_checkpoint_path(args.resume).is_file()):
            raise UvsimError(f"--resume: neither the checkpoint {args.resume} nor its joint-stage file "
                             f"{joint_checkpoint_path(args.resume)} exists")
    ds = read_dataset(args.data)
    veh = resolve_vehicle(args.vehicle, ds)
    notes = check_runs_at_door("calibrate", ds.runs, veh, args.allow)
    progress = command_progress("calibrate", args)
    cal = Calibrator(dofs=args.dof, population=args.population, generations=args.generations, seed=args.seed,
                     margin=args.margin, workers=args.workers, dask=args.dask, checkpoint=ckpt, resume=args.resume,
                     refine=not args.no_refine, free=args.free, fix=args.fix, bounds=bounds,
                     signal_weights=weights, noise=noise, horizons=horizons,
                     continuity=parse_continuity(args.continuity), max_iter=args.max_iter,
                     gyro_bias=not args.no_gyro_bias, acc_bias=not args.no_acc_bias,
                     attitude_bias=not args.no_attitude_bias, prior=not args.no_prior, loss=args.loss,
                     sample_weighting=args.sample_weighting,
                     screen=not args.no_screen,
                     ga_channels=args.ga_channels,
                     attitude_lag=lag, latency=args.latency, supply_voltage=args.supply_voltage,
                     trade_off=args.trade_off,
                     low_speed_exponent=args.low_speed_exponent, progress=progress,
                     judge_horizon=judge, allow=allow)
    logger = logging.getLogger("uvsim")
    handler = None
    if not logger.handlers:  # "resuming from ..." and other notes reach the user
        from uvsim.progress import LineHandler

        handler = LineHandler()
        handler.setFormatter(logging.Formatter("%(message)s"))
        logger.addHandler(handler)
        logger.setLevel(logging.INFO)
    try:
        cal.fit(ds, veh)
    except KeyboardInterrupt:
        _say_resume(ckpt)
        raise
    finally:
        if handler is not None:
            logger.removeHandler(handler)
    rep = cal.report_
    rep["input_notes"] = notes
    status = finish_calibration(cal, ds, out, args.json, args.plots, keep_worse=args.keep_worse, progress=progress)
    from uvsim.calibration.joint import joint_checkpoint_path

    from uvsim.calibration.trade_off import LABELS

    remove_checkpoints(ckpt, *(joint_checkpoint_path(f"{ckpt}{tag}") for tag in ("", ".latency", ".supply", *LABELS)))
    return EXIT_CODES[status]


def finish_calibration(cal, ds, out, json_path=None, plots=None, *, keep_worse: bool = False, progress=None) -> str:
    """Write what a calibration's outcome allows and print it (docs/calibration.md, "The verdict"):
    report.json and the plots always; the fitted vehicle when the verdict is *better* or a
    *trade-off*, and for *worse* only with ``keep_worse``.  Returns the status.  ``progress``:
    the plots as a stage (:mod:`uvsim.progress`)."""
    from uvsim.progress import as_progress

    progress = as_progress(progress)
    rep = cal.report_
    status, why, keep = record_outcome(cal, ds, keep_worse=keep_worse)
    if keep:
        out.parent.mkdir(parents=True, exist_ok=True)
        save_fitted_vehicle(cal, out)
    if json_path:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(jsonable(rep), indent=2))
    if plots:
        from uvsim.plotting.calibration import plot_calibration

        with progress.stage(f"plots into {plots}"):
            plot_calibration(cal, ds, plots)
    stages = "; ".join(f"{'whole runs' if s['horizon_s'] is None else format(s['horizon_s'], 'g') + ' s windows'}: "
                       f"{s['iterations']} iterations, {s['message']}" for s in rep["refinement"].get("stages", []))
    print(f"calibrated {rep['vehicle']} on {len(rep['training_runs'])} training runs: "
          + (f"GA ({', '.join(rep['dofs'])}) {rep['evaluations']} evaluations in {rep['ga_seconds']:.1f} s; "
             if rep["dofs"] else "no GA (no run marked with a DOF); ")
          + (f"joint fit of {len(rep['free_parameters'])} parameters in {rep['refine_seconds']:.1f} s ({stages})"
             if rep["free_parameters"] else "no joint fit"))
    print_summary(cal)
    print_verdict(rep, status, why)
    if status != "better":
        say("calibrate", f"verdict {why}")
    written = [str(out)] if keep else []
    written += [str(json_path)] if json_path else []
    written += [f"plots in {plots}"] if plots else []
    print("-> " + (", ".join(written) if written else "nothing written")
          + ("" if keep else f" (the fitted vehicle is not written to {out}: keep it with --keep-worse)"))
    return status


def _say_resume(ckpt) -> None:
    """After an interrupt: what the checkpoints hold and how to continue."""
    from uvsim.calibration.joint import joint_checkpoint_path
    from uvsim.checkpoint import Checkpoint

    try:
        env = Checkpoint(ckpt, kind="ga", key="").read()
        held = f"{ckpt} holds the GA after {env['progress']}"
    except UvsimError:
        held = "no GA generation was checkpointed yet"
    joint = joint_checkpoint_path(ckpt)
    if Path(joint).is_file():
        held += f" and {joint} the joint fit's progress"
    again = joint_checkpoint_path(f"{ckpt}.latency")
    if Path(again).is_file():
        held += f" and {again} the refit with the estimated sensor latency"
    family = joint_checkpoint_path(f"{ckpt}.supply")
    if Path(family).is_file():
        held += f" and {family} the refit on the T200 voltage family (--supply-voltage auto)"
    from uvsim.calibration.trade_off import LABELS

    for tag, label in LABELS.items():
        again = joint_checkpoint_path(f"{ckpt}{tag}")
        if Path(again).is_file():
            held += f" and {again} the {label}"
    say("calibrate", f"interrupted; {held}; continue with --resume {ckpt}")
