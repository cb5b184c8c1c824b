"""``uvsim diagnose``: which effect does the model lack?  Fit it and report before/after.

    uvsim diagnose --data DIR --vehicle NAME|FILE --json report.json [--plots DIR] [--out fixed.yaml]
                   [--retune X_u,X_uu] [--only current,tether] [--noise position=0.002,attitude=0.005]
                   [--weights position=1,attitude=2]
"""
from __future__ import annotations

import json
from pathlib import Path

from uvsim.commands import parse_pairs
from uvsim.commands.checks import add_allow_argument, check_outputs, check_runs_at_door, diagnosis_problems, fail_if, say


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "diagnose", help="trace the residual of a model to a missing effect, fit it, report before/after",
        description="Simulate every run of a dataset with the given vehicle, compute the residuals (output "
                    "and inverse-dynamics force), fit each catalogue effect (current, tether, thruster_lag, "
                    "thrust_asymmetry, ballast, coupled_damping, bottom_effect) on the training runs, score them by BIC on "
                    "the validation runs and keep the best one only if it is significant.  See docs/diagnose.md.")
    p.add_argument("--data", required=True, help="dataset directory (manifest.yaml + runs, docs/log_format.md)")
    p.add_argument("--vehicle", help="built-in vehicle name or vehicle YAML (default: the manifest's vehicle)")
    p.add_argument("--json", dest="json_out", help="write the report as JSON to this file")
    p.add_argument("--plots", help="directory for residual plots (before/after over time)")
    p.add_argument("--out", help="write the corrected vehicle YAML here")
    p.add_argument("--retune", help="comma-separated base coefficients re-tuned with every candidate (e.g. X_u,X_uu)")
    p.add_argument("--only", help="comma-separated catalogue effects to try (default: all)")
    p.add_argument("--noise", help="noise levels per signal group, e.g. position=0.002,attitude=0.005 "
                                   "(default: estimated from the data)")
    p.add_argument("--weights", help="per signal group weights, e.g. position=1,attitude=2 (default 1 each)")
    p.add_argument("--max-nfev", type=int, default=30, help="evaluation budget of each fit (default 30)")
    p.add_argument("--quiet", action="store_true", help="no progress messages")
    add_allow_argument(p)
    p.set_defaults(func=run)


def _list(s):
    return [x.strip() for x in s.split(",") if x.strip()] if s else None


def _fmt(d: dict) -> str:
    return ", ".join(f"{k} {v:.4g}" for k, v in d.items())


def format_table(report: dict) -> str:
    """The candidate table and the before/after lines as text."""
    lines = [f"{'candidate':18s} {'k':>2s} {'train RMS':>9s} {'val RMS':>9s} {'dBIC':>9s}  accepted  why",
             "-" * 100]
    for c in report["candidates"]:
        if "score" not in c:
            lines.append(f"{c['name']:18s} {'':>2s} {'':>9s} {'':>9s} {'':>9s}  {'no':8s}  {c['why']}")
            continue
        lines.append(f"{c['name']:18s} {c['n_parameters']:2d} {c['train_rms_noise_sigmas']:9.2f} "
                     f"{c['validation_rms_noise_sigmas']:9.2f} {c['score']['delta_bic']:9.1f}  "
                     f"{'YES' if c['accepted'] else 'no':8s}  {c['why']}")
    lines.append("(RMS in noise sigmas: every signal divided by its noise level; dBIC = BIC - BIC of the given model)")
    lines.append("")
    lines.append(f"effect: {report['effect']}   confidence: {report['confidence']}")
    for k, d in report["parameters"].items():
        std = f" +- {d['std']:.2g}" if d.get("std") is not None else ""
        lines.append(f"  {k} = {d['value']:.5g}{std} {d['unit']}")
    lines.append(report["message"])
    lines.append("")
    lines.append(f"{'validation RMSE':18s} {'before':>12s} {'after':>12s}")
    for k in report["rmse_before"]:
        lines.append(f"{k:18s} {report['rmse_before'][k]:12.5g} {report['rmse_after'].get(k, float('nan')):12.5g}")
    return "\n".join(lines)


def run(args) -> int:
    from uvsim.diagnosis import diagnose, save_fixed_vehicle
    from uvsim.errors import CalibrationError
    from uvsim.logs import read_dataset
    from uvsim.plausibility import parse_allow
    from uvsim.vehicle import load_vehicle

    progress = None if args.quiet else (lambda m: print(f"uvsim diagnose: {m}", flush=True))
    noise, weights = parse_pairs(args.noise, "--noise"), parse_pairs(args.weights, "--weights")
    check_outputs({"--json": args.json_out, "--out": args.out}, {"--plots": args.plots})
    ds = read_dataset(args.data)
    if args.vehicle is None and ds.vehicle is None:
        raise CalibrationError(f"{ds.path}: no --vehicle given and the manifest names none")
    veh = load_vehicle(args.vehicle if args.vehicle is not None else (ds.vehicle_file or ds.vehicle))
    notes = check_runs_at_door("diagnose", ds.runs, veh, args.allow)
    diag = diagnose(ds, veh, retune=_list(args.retune), only=_list(args.only), noise=noise, weights=weights,
                    max_nfev=args.max_nfev, progress=progress, allow=parse_allow(args.allow))
    rep = diag.report
    split = rep["runs"]["split"]
    if split != "from the manifest":  # the runs were re-split: say so (it is in the report too)
        line = f"note: {ds.path / 'manifest.yaml'}: {split} ({', '.join(rep['runs']['validation'])})"
        say("diagnose", line)
        notes.append(line)
    rep["input_notes"] = notes
    problems = diagnosis_problems(rep, diag.validation)
    rep["status"] = {"ok": not problems, "problems": problems}
    if args.json_out:
        Path(args.json_out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json_out).write_text(json.dumps(rep, indent=2, default=float))
    fail_if(problems, "diagnose", "No corrected vehicle was written" + (f"; the report is in {args.json_out}."
                                                                        if args.json_out else "."))
    print(format_table(rep))
    if args.json_out:
        print(f"report: {args.json_out}")
    if args.out:
        save_fixed_vehicle(diag, args.out)
        print(f"corrected vehicle: {args.out}")
    if args.plots:
        from uvsim.plotting.diagnosis import plot_diagnosis

        files = plot_diagnosis(diag, args.plots)
        print(f"plots: {', '.join(str(f) for f in files)}")
    return 0
