"""``uvsim calibrate``: fit a vehicle model to a dataset (docs/calibration.md).

    uvsim calibrate --data DIR [--vehicle NAME|FILE] [--dof surge,...] [--free z_b,thruster_gain_*]
                    [--fix NAME,...] [--bounds NAME=LO:HI,...] [--weights NAME=W,...] [--noise NAME=SIGMA,...]
                    [--horizons 2,6] [--continuity 0.05] [--no-gyro-bias] [--no-prior] [--loss huber] [--sample-weighting per_sample] [--seed S]
                    [--population P --generations G]
                    [--workers N] [--dask ADDR|local] [--checkpoint CKPT] [--resume CKPT] [--no-refine]
                    --out fitted.yaml [--json report.json] [--plots DIR] [--progress]

Seed 000's GA per DOF for runs marked with one DOF, then one joint windowed
prediction-error fit of every training run (marked and ``dof: mixed``).
"""
from __future__ import annotations

import json
import logging
import math
import sys
from pathlib import Path

from uvsim.commands import lag_option, parse_pairs
from uvsim.commands.checks import (add_allow_argument, add_progress_arguments, calibration_problems, check_outputs,
                                   check_runs_at_door, say, want_progress)
from uvsim.errors import UvsimError
from uvsim.fitting.verdict import EXIT_CODES

ADDED_MASS_ROWS = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")


def register(sub) -> None:
    from uvsim.calibration.calibrator import DEFAULT_SAMPLE_WEIGHTING
    from uvsim.fitting.objective import LOSSES
    from uvsim.measurements import SAMPLE_WEIGHTINGS

    p = sub.add_parser("calibrate", help="fit a vehicle model to logged runs (seed 000 GA per DOF + joint "
                                         "prediction-error fit of all runs)")
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
                   help="window lengths (s) of the joint fit's continuation, 'whole' for whole runs (default 2,whole: "
                        "2 s windows, then whole runs with each channel scaled by its own error, the verdict's "
                        "measure)")
    p.add_argument("--continuity", default=None, metavar="C1,C2,...",
                   help="factors of the continuity defects' sd at the last horizon, one stage each (default 0.05: "
                        "windows restart little, so the fit improves the free simulation; 1 is diagnosis' softer "
                        "setting)")
    p.add_argument("--max-iter", type=int, default=80,
                   help="Levenberg-Marquardt iterations per horizon; a last stage that stops there is reported as "
                        "unfinished (exit 2) unless --keep-worse")
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
                        "model, or a fit that failed a sanity check such as the iteration limit); the exit status "
                        "stays 2 and report.json says status.verdict: worse")
    p.add_argument("--plots", default=None, help="directory for plots (measured vs simulated, error boxplots, "
                                                 "GA convergence); written whatever the verdict")
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
    from uvsim.calibration.calibrator import DEFAULT_HORIZONS

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
    from uvsim.calibration.calibrator import DEFAULT_CONTINUITY
    from uvsim.fitting.objective import continuity_factors

    if not text:
        return DEFAULT_CONTINUITY
    try:
        return tuple(continuity_factors([float(item) for item in text.split(",")]))
    except (ValueError, UvsimError):
        raise UvsimError(f"--continuity: expected positive numbers separated by commas, got {text!r}") from None


def _fmt(v):
    return "n/a" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.6g}"


def jsonable(obj):
    """Replace NaN/inf by None and numpy scalars by Python numbers, recursively."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    return obj


def _notes(cal) -> dict:
    """Per fitted parameter: its value, 1-sigma or why there is none, previous value."""
    from uvsim.calibration.params import EFFECTIVE_INERTIA

    rep = cal.report_
    pair_of = {k: (d, pr) for d, pr in EFFECTIVE_INERTIA.items() for k in pr}
    notes = {}
    for k, v in cal.params_.items():
        sig = cal.uncertainty_.get(k)
        if sig is not None:
            s = f"+- {_fmt(sig)}"
        elif k in pair_of and k not in rep["free_parameters"]:
            d, (a, b) = pair_of[k]
            s = (f"only {a} + {b} = {rep['effective_inertia'][d]:.6g} +- "
                 f"{_fmt(rep['effective_inertia_uncertainty'].get(d))} is identifiable")
        else:
            s = "(GA value, not refined)"
        notes[k] = f"fitted {v:.6g} {s}; previous {_fmt(rep['initial_parameters'][k])}"
    return notes


def save_fitted_vehicle(cal, path) -> Path:
    """Write ``cal.vehicle_`` with each fitted value's previous value and uncertainty
    beside it (added-mass rows annotated too; parameters without a line of their own,
    such as z_b or thruster gains, in the header)."""
    from uvsim.vehicle import save_vehicle

    rep = cal.report_
    notes = _notes(cal)
    header = (f"Calibrated by `uvsim calibrate` from {rep['vehicle']} on {rep['dataset']}\n"
              + (f"GA (seed 000) for {', '.join(rep['dofs'])}: population {rep['settings']['population']}, "
                 f"{rep['settings']['generations']} generations, seed {rep['settings']['seed']}\n" if rep["dofs"] else "")
              + (f"joint prediction-error fit of {len(rep['training_runs'])} runs, windows "
                 f"{rep['settings']['horizons']} s\n" if rep["free_parameters"] else "")
              + f"validation RMSE {jsonable({k: round(v, 6) for k, v in rep['validation_rmse'].items()})}; "
                "uncertainties are 1-sigma (cluster-robust)")
    path = save_vehicle(cal.vehicle_, path, header=header, annotations=notes)
    keys = {line.strip().split(":", 1)[0] for line in Path(path).read_text().splitlines() if ":" in line}
    other = [f"{k}: {n}" for k, n in notes.items() if k not in keys and k not in ADDED_MASS_ROWS]
    if other:  # no line of their own (z_b in r_b, thruster gains in the units): in the header
        path = save_vehicle(cal.vehicle_, path, header=header + "\n" + "\n".join(other), annotations=notes)
    # added mass is written as a 6x6 matrix: annotate its diagonal rows
    lines = Path(path).read_text().splitlines()
    out, in_am, row = [], False, 0
    for line in lines:
        if line.startswith("added_mass:"):
            in_am = True
        elif in_am and line and not line.startswith(" ") and not line.startswith("-"):
            in_am = False
        if in_am and line.lstrip().startswith("- [") and row < 6:
            name = ADDED_MASS_ROWS[row]
            if name in notes:
                line = f"{line}  # {name}: {notes[name]}"
            row += 1
        out.append(line)
    Path(path).write_text("\n".join(out) + "\n")
    return Path(path)


def _grouped_notes(notes) -> dict:
    """``"run NAME: TEXT; details"`` notes grouped by TEXT -> [NAME, ...]."""
    out: dict = {}
    for n in notes:
        head, sep, text = n.partition(": ")
        name = head[4:] if sep and head.startswith("run ") else ""
        out.setdefault(text.split(";")[0] if name else n, []).append(name or "-")
    return out


def print_summary(cal, out=None) -> None:
    """The summary table of a fitted Calibrator (docs/calibration.md)."""
    out = sys.stdout if out is None else out
    rep = cal.report_
    free = set(rep["free_parameters"])
    ident = rep["identifiability"]
    held = {c.split(" + ")[0] for c in ident.get("effective_inertia", [])}

    def say(s=""):
        print(s, file=out)

    prior = rep.get("prior", {}).get("parameters", {})
    say(f"{'parameter':18s} {'initial':>11s} {'fitted':>11s} {'1-sigma':>10s}"
        + (f" {'prior sd':>10s} {'moved':>7s} {'data':>5s}" if prior else "") + "  flags")
    for k, v in rep["parameters"].items():
        flags = []
        if k in rep["at_bounds"]:
            flags.append("AT BOUND")
        if k in rep["physical_limit"]:
            flags.append("AT PHYSICAL LIMIT")
        if k in ident.get("weakly_determined", []):
            flags.append("weak")
        if k in held:
            flags.append("held at the vehicle's value (its sum with the added inertia is fitted)")
        elif k not in free:
            flags.append("GA only")
        pr = prior.get(k)
        cols = ""
        if prior:
            cols = (f" {_fmt(pr['prior_sd']):>10s} {pr['moved_prior_sd']:+7.2f} "
                    f"{'' if pr['determined'] is None else format(pr['determined'], '5.0%'):>5s}" if pr else
                    f" {'':10s} {'':7s} {'':5s}")
        say(f"{k:18s} {rep['initial_parameters'][k]:11.5g} {v:11.5g} {_fmt(rep['uncertainty'][k]):>10s}{cols}  "
            f"{', '.join(flags)}")
    if prior:
        say(f"prior: the starting vehicle's values; 'moved' = (fitted - prior mean) / prior sd, 'data' = 1 - "
            f"posterior sd / prior sd (0 %: the prior alone); data weight {rep['prior']['data_weight']:.3g} "
            "(docs/calibration.md, 'Priors')")
    if ident.get("not_excited"):
        say(f"not excited by the data (left at their values): {', '.join(ident['not_excited'])}")
    for c in ident.get("effective_inertia", []):
        say(f"identifiable: {c}")
    if ident.get("not_identifiable"):
        say("the data determine only: " + "; ".join(ident["identifiable_combinations"]))
    for pair, r in ident.get("correlations", {}).items():
        say(f"correlated: {pair} ({r:+.3f})")
    for key, title, fmt in (("gyro_bias", "gyro bias per run (rad/s, p q r):", "+.5f"),
                            ("attitude_bias", "attitude filter offset per run (rad, roll pitch):", "+.5f"),
                            ("acc_bias", "accelerometer offset per run (m/s^2, x y z):", "+.4f")):
        if rep.get(key):
            say(title)
            for name, b in rep[key].items():
                say(f"  {name:28s} " + " ".join(f"{x:{fmt}}" for x in b))
            for flag in rep.get(f"{key}_flags", []):
                say(f"  FLAG {flag}")
    lag = rep["attitude_lag"]
    if lag["tau"]:
        say(f"attitude filter lag {lag['tau']:.3f} s ({lag['source']})")
    lat = rep.get("sensor_latency") or {}
    scan = lat.get("scan")
    if scan:
        verdict = (f"fitted again with {scan['best'] * 1000:.1f} ms" if scan["use"] else
                   f"kept {scan['current'] * 1000:.1f} ms (needs a {100 * scan['min_gain']:.0f} % lower cost)")
        say(f"sensor latency scan (fitted model, {scan['horizon_s']:g} s windows): lowest cost at "
            f"{scan['best'] * 1000:.1f} ms, {100 * scan['gain']:.1f} % below {scan['current'] * 1000:.1f} ms: {verdict}")
    elif lat.get("value"):
        say(f"sensor latency {lat['value'] * 1000:.1f} ms ({'the vehicle file' if lat['how'] == 'file' else 'given'})")
    sv = rep.get("supply_voltage_auto")
    if sv and sv.get("value") is not None:
        low = min(sv["training_fit_gain"].values(), default=float("nan"))
        say(f"supply voltage (auto): refit on the T200 voltage family found {sv['value']:.2f} V; training Fit % "
            f"{'higher in every channel (lowest gain ' if sv['used'] else 'not higher in every channel ('}"
            f"{low:+.1f} points): {'kept' if sv['used'] else 'the first fit kept'}")
    for text, runs in _grouped_notes(rep["notes"]).items():
        say(f"note: {text} ({len(runs)} run{'s' if len(runs) > 1 else ''}: {', '.join(runs[:3])}"
            f"{', ...' if len(runs) > 3 else ''})")
    say(f"training RMSE {jsonable(rep['training_rmse'])}")
    say(f"validation RMSE {jsonable(rep['validation_rmse'])} (initial {jsonable(rep['initial_validation_rmse'])})")
    if rep["validation_fit_percent"]:
        say("validation Fit %: " + ", ".join(f"{c} {v:.1f}" for c, v in rep["validation_fit_percent"].items()))


def _run(args) -> int:
    from uvsim.calibration import Calibrator
    from uvsim.calibration.inputs import resolve_vehicle
    from uvsim.logs import read_dataset
    from uvsim.plausibility import parse_allow

    out = Path(args.out)
    ckpt = args.checkpoint or str(out.with_suffix(out.suffix + ".ckpt"))
    weights, noise = parse_pairs(args.weights, "--weights"), parse_pairs(args.noise, "--noise")
    bounds, horizons, lag = parse_bounds(args.bounds), parse_horizons(args.horizons), lag_option(args.attitude_lag)
    check_outputs({"--out": out, "--json": args.json, "--checkpoint": ckpt}, {"--plots": args.plots})
    if args.resume:
        from uvsim.calibration.joint import joint_checkpoint_path

        if not (Path(args.resume).is_file() or joint_checkpoint_path(args.resume).is_file()):
            raise UvsimError(f"--resume: neither the checkpoint {args.resume} nor its joint-stage file "
                             f"{joint_checkpoint_path(args.resume)} exists")
    ds = read_dataset(args.data)
    veh = resolve_vehicle(args.vehicle, ds)
    notes = check_runs_at_door("calibrate", ds.runs, veh, args.allow)
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
                     attitude_lag=lag, latency=args.latency, supply_voltage=args.supply_voltage, low_speed_exponent=args.low_speed_exponent, progress=want_progress(args),
                     allow=parse_allow(args.allow))
    logger = logging.getLogger("uvsim")
    handler = None
    if not logger.handlers:  # "resuming from ..." and other notes reach the user
        handler = logging.StreamHandler(sys.stderr)
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
    status = finish_calibration(cal, ds, out, args.json, args.plots, keep_worse=args.keep_worse)
    return EXIT_CODES[status]


def outcome(rep, ds) -> tuple[str, str, list[str]]:
    """(status, why, problems) of a calibration report: the verdict's status ("better",
    "trade-off", "worse") and message, or "worse" when a sanity check fails
    (:func:`calibration_problems`: a diverged or exploding simulation, an unfinished fit, every
    parameter of a DOF on a bound), ``problems`` then saying which."""
    problems = calibration_problems(rep, ds)
    v = rep.get("verdict")
    if problems:
        return "worse", "worse: " + "; ".join(problems), problems
    if v is None:
        return "better", "no runs to compare with the starting model", []
    return v["status"], v["message"], []


def record_outcome(cal, ds, *, keep_worse: bool = False) -> tuple[str, str, bool]:
    """(status, why, keep) of a fitted Calibrator (:func:`outcome`), also written into its
    report's ``status``; ``keep``: whether the fitted vehicle may be written (*better* or
    *trade-off*, and *worse* only with ``keep_worse``)."""
    rep = cal.report_
    status, why, problems = outcome(rep, ds)
    keep = status in ("better", "trade-off") or keep_worse
    rep["status"] = {"ok": status == "better", "verdict": status, "exit_code": EXIT_CODES[status], "why": why,
                     "problems": problems, "vehicle_written": bool(keep)}
    return status, why, keep


def finish_calibration(cal, ds, out, json_path=None, plots=None, *, keep_worse: bool = False) -> str:
    """Write what a calibration's outcome allows and print it (docs/calibration.md, "The verdict"):
    report.json and the plots always; the fitted vehicle when the verdict is *better* or a
    *trade-off*, and for *worse* only with ``keep_worse``.  Returns the status."""
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


def print_verdict(rep, status: str, why: str, out=None) -> None:
    """The verdict's per-channel table and its one-paragraph message ``why`` (:func:`outcome`)."""
    from uvsim.fitting.verdict import table

    out = sys.stdout if out is None else out
    v = rep.get("verdict")
    if v is not None:
        print(f"verdict on the {v['split']} runs (free simulations, every logged channel):", file=out)
        for line in table(v):
            print("  " + line, file=out)
    print(f"VERDICT (exit {EXIT_CODES[status]}) {why}", file=out)


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
    say("calibrate", f"interrupted; {held}; continue with --resume {ckpt}")
