"""``uvsim calibrate``: fit a vehicle's inertia, added mass and damping to a dataset.

    uvsim calibrate --data DIR --vehicle NAME|FILE [--dof surge,...] [--seed S]
                    [--population P --generations G] [--workers N] [--dask ADDR|local]
                    [--checkpoint CKPT] [--resume CKPT] --out fitted.yaml --json report.json [--plots DIR]

The method is seed 000's GA (Table 3 parameters, Table 4 settings) followed by a
least-squares refinement (docs/calibration.md).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from uvsim.commands import parse_pairs
from uvsim.commands.checks import (add_allow_argument, add_progress_arguments, bound_hits, calibration_problems,
                                   check_outputs, check_runs_at_door, fail_if, say, want_progress)

ADDED_MASS_ROWS = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="fit inertia, added mass and damping to logged runs (seed 000 GA + "
                                         "least-squares refinement)")
    p.add_argument("--data", required=True, help="dataset directory (manifest.yaml + runs)")
    p.add_argument("--vehicle", default=None, help="starting vehicle: built-in name or YAML file "
                                                    "(default: the manifest's vehicle)")
    p.add_argument("--dof", default=None, help="comma-separated DOFs to fit (default: all with training runs)")
    p.add_argument("--seed", type=int, default=0, help="random seed (same seed -> identical result)")
    p.add_argument("--population", type=int, default=60, help="GA population per DOF (seed 000: 60)")
    p.add_argument("--generations", type=int, default=30, help="GA generations (seed 000: 30)")
    p.add_argument("--margin", type=float, default=0.5, help="search range around initial values (0.5 = +-50%%)")
    p.add_argument("--workers", type=int, default=1, help="local worker processes for the GA evaluations")
    p.add_argument("--dask", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address, or 'local' (needs uvsim[dask])")
    p.add_argument("--checkpoint", default=None, help="checkpoint file written after every generation "
                                                      "(default: <out>.ckpt)")
    p.add_argument("--resume", default=None, metavar="CKPT", help="continue from a checkpoint")
    p.add_argument("--no-refine", action="store_true", help="skip the least-squares refinement")
    p.add_argument("--estimate-initial-velocity", action="store_true",
                   help="fit each run's unknown initial velocity (DOF axis) in the refinement")
    p.add_argument("--weights", default=None, metavar="NAME=W,...",
                   help="signal weights by group (position, attitude, velocity, rates) or channel "
                        "(x..z, roll, pitch, yaw, u..w, p..r); default: each DOF's own channels")
    p.add_argument("--low-speed-exponent", type=float, default=0.0,
                   help="extra run weight (amplitude/median)^-E favouring slow runs (default 0: manifest weights)")
    p.add_argument("--out", required=True, help="fitted vehicle YAML (complete, loadable by every command)")
    p.add_argument("--json", default=None, help="report JSON")
    p.add_argument("--plots", default=None, help="directory for plots (measured vs simulated, error boxplots, "
                                                 "GA convergence)")
    add_allow_argument(p)
    add_progress_arguments(p)
    p.set_defaults(func=_run)


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


def save_fitted_vehicle(cal, path) -> Path:
    """Write ``cal.vehicle_`` with each fitted value's previous value and
    uncertainty beside it (added-mass rows annotated too)."""
    from uvsim.vehicle import save_vehicle

    rep = cal.report_
    from uvsim.calibration.params import EFFECTIVE_INERTIA

    pair_of = {k: (d, pr) for d, pr in EFFECTIVE_INERTIA.items() for k in pr}
    notes = {}
    for k, v in cal.params_.items():
        sig = cal.uncertainty_.get(k)
        if sig is not None:
            s = f"+- {_fmt(sig)}"
        elif k not in pair_of or rep["effective_inertia_uncertainty"].get(pair_of[k][0]) is None:
            s = "no uncertainty (no refinement)" if not rep["settings"]["refine"] else "uncertainty not determined"
        else:
            d, (a, b) = pair_of[k]
            s = (f"only {a} + {b} = {rep['effective_inertia'][d]:.6g} +- "
                 f"{_fmt(rep['effective_inertia_uncertainty'].get(d))} is identifiable")
        notes[k] = f"fitted {v:.6g} {s}; previous {_fmt(rep['initial_parameters'][k])}"
    header = (f"Calibrated by `uvsim calibrate` from {rep['vehicle']} on {rep['dataset']}\n"
              f"DOFs {', '.join(rep['dofs'])}; seed 000 GA (population {rep['settings']['population']}, "
              f"{rep['settings']['generations']} generations, seed {rep['settings']['seed']}) + least squares\n"
              f"validation RMSE {jsonable({k: round(v, 6) for k, v in rep['validation_rmse'].items()})}; "
              "uncertainties are 1-sigma (Gauss-Newton, AR(1)-inflated)")
    path = save_vehicle(cal.vehicle_, path, header=header, annotations=notes)
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


def _run(args) -> int:
    from uvsim.calibration import Calibrator
    from uvsim.checkpoint import Checkpoint
    from uvsim.logs import read_dataset
    from uvsim.plausibility import parse_allow
    from uvsim.vehicle import load_vehicle

    out = Path(args.out)
    ckpt = args.checkpoint or str(out.with_suffix(out.suffix + ".ckpt"))
    weights = parse_pairs(args.weights, "--weights")
    check_outputs({"--out": out, "--json": args.json, "--checkpoint": ckpt}, {"--plots": args.plots})
    if args.resume:
        Checkpoint(args.resume, kind="ga", key="").read()  # exists and is a checkpoint, before any work
    ds = read_dataset(args.data)
    if args.vehicle is None and ds.vehicle is None:
        from uvsim.errors import CalibrationError

        raise CalibrationError(f"{ds.path}: no --vehicle given and the manifest names none")
    veh = load_vehicle(args.vehicle if args.vehicle is not None else (ds.vehicle_file or ds.vehicle))
    notes = check_runs_at_door("calibrate", ds.runs, veh, args.allow)
    cal = Calibrator(dofs=args.dof, population=args.population, generations=args.generations, seed=args.seed,
                     margin=args.margin, workers=args.workers, dask=args.dask, checkpoint=ckpt, resume=args.resume,
                     refine=not args.no_refine, estimate_initial_velocity=args.estimate_initial_velocity,
                     signal_weights=weights, low_speed_exponent=args.low_speed_exponent,
                     progress=want_progress(args), allow=parse_allow(args.allow))
    try:
        cal.fit(ds, veh)
    except KeyboardInterrupt:
        _say_resume(ckpt)
        raise
    rep = cal.report_
    rep["input_notes"] = notes
    problems = calibration_problems(rep, ds)
    if problems:
        if args.json:
            rep["status"] = {"ok": False, "problems": problems}
            Path(args.json).parent.mkdir(parents=True, exist_ok=True)
            Path(args.json).write_text(json.dumps(jsonable(rep), indent=2))
        fail_if(problems, "calibrate", f"Nothing was written to {out}" + (f"; the report is in {args.json}."
                                                                        if args.json else "."))
    rep["status"] = {"ok": True, "problems": []}
    out.parent.mkdir(parents=True, exist_ok=True)
    save_fitted_vehicle(cal, out)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(jsonable(rep), indent=2))
    if args.plots:
        from uvsim.plotting.calibration import plot_calibration

        plot_calibration(cal, ds, args.plots)
    hits = bound_hits(rep)
    print(f"calibrated {', '.join(rep['dofs'])} of {rep['vehicle']}: {rep['evaluations']} GA evaluations, "
          f"{rep['wall_seconds']:.1f} s")
    print(f"{'parameter':10s} {'initial':>11s} {'fitted':>11s} {'1-sigma':>10s}")
    for k, v in rep["parameters"].items():
        flag = f"  ON {hits[k].upper()} BOUND" if k in hits else ""
        print(f"{k:10s} {rep['initial_parameters'][k]:11.5g} {v:11.5g} {_fmt(rep['uncertainty'][k]):>10s}{flag}")
    if hits:
        print(f"{len(hits)} parameter(s) ended on a search bound (+-{100 * args.margin:g} % of the initial value): "
              f"{', '.join(hits)}. The fit would have gone further; their 1-sigma assumes an interior optimum "
              "and does not hold. Widen --margin or check the data and the starting vehicle.")
    for d, a in rep["identifiability"].items():
        if a["not_identifiable"]:
            print(f"{d}: identifiable: {', '.join(a['identifiable_combinations'])}")
    print(f"training RMSE {jsonable(rep['training_rmse'])}; validation RMSE {jsonable(rep['validation_rmse'])}")
    print(f"-> {out}" + (f", {args.json}" if args.json else "") + (f", plots in {args.plots}" if args.plots else ""))
    return 0


def _say_resume(ckpt) -> None:
    """After an interrupt: where the GA state is and how to continue."""
    from uvsim.checkpoint import Checkpoint
    from uvsim.errors import UvsimError

    try:
        env = Checkpoint(ckpt, kind="ga", key="").read()
    except UvsimError:
        say("calibrate", "interrupted before the first GA generation was checkpointed; start again")
        return
    say("calibrate", f"interrupted; {ckpt} holds the GA after {env['progress']}; continue with --resume {ckpt}")
