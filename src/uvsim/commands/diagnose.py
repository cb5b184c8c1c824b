"""``uvsim diagnose``: which effects does the model lack?  Fit them and report before/after.

    uvsim diagnose --data DIR [--vehicle NAME|FILE] [--json report.json] [--plots DIR] [--out fixed.yaml]
                   [--retune X_uu,N_rr] [--only current,tether] [--noise depth=0.01,attitude=0.005]
                   [--weights position=1,depth=0] [--horizon 3] [--max-effects 2] [--workers 2]
                   [--checkpoint CKPT] [--resume CKPT] [--progress | --no-progress]
"""
from __future__ import annotations

import json
from pathlib import Path

from uvsim.commands import lag_option, parse_pairs
from uvsim.commands.checks import (add_allow_argument, add_judge_horizon_argument, add_progress_arguments,
                                   check_outputs, check_runs_at_door, judge_option, judged_label,
                                   command_progress, diagnosis_caveats, diagnosis_problems, refusal, remove_checkpoints,
                                   say)
from uvsim.fitting.verdict import EXIT_CODES
from uvsim.fitting.verdict import table as verdict_table


def register(subparsers) -> None:
    from uvsim.diagnosis.candidates import EFFECTS
    from uvsim.fit_settings import DEFAULT_HORIZON

    p = subparsers.add_parser(
        "diagnose", help="trace the residual of a model to missing effects, fit them, report before/after",
        description="Forward selection of catalogue effects (" + ", ".join(EFFECTS) + "): every candidate is "
                    "screened by equation error, the best are fitted through the simulator (windowed prediction "
                    "error on the training runs) and one is kept only if the verdict on the validation runs' free "
                    "simulations calls it better (docs/calibration.md 'The verdict'); repeat with the rest.  See "
                    "docs/diagnose.md.",
        epilog="Exit status: 0 the corrected model is 'better' than the given one (or nothing changed); 3 a "
               "'trade-off' (corrected vehicle written, the worse channels named); 2 'worse', 'refused' (a sanity "
               "check failed) or an error (report and plots written, no corrected vehicle).")
    p.add_argument("--data", required=True, help="dataset directory (manifest.yaml + runs, docs/log_format.md)")
    p.add_argument("--vehicle", help="built-in vehicle name or vehicle YAML (default: the manifest's vehicle)")
    p.add_argument("--json", dest="json_out", help="write the report as JSON to this file")
    p.add_argument("--plots", help="directory for plots (validation runs before/after, steps); written whatever "
                                   "the verdict")
    p.add_argument("--out", help="write the corrected vehicle YAML here")
    p.add_argument("--retune", help="comma-separated base coefficients re-fitted with every model (e.g. X_uu,N_rr)")
    p.add_argument("--only", help="comma-separated catalogue effects to try (default: all)")
    p.add_argument("--noise", help="noise levels by signal group or channel, e.g. depth=0.01,attitude=0.005 "
                                   "(default: estimated from the data at each sensor's native rate)")
    p.add_argument("--weights", help="weights by signal group or channel, e.g. position=1,depth=0 (default 1)")
    p.add_argument("--horizon", type=float, default=DEFAULT_HORIZON,
                   help=f"window length of the fits, s (default {DEFAULT_HORIZON:g})")
    p.add_argument("--max-effects", type=int, default=2, help="most effects to add (default 2)")
    p.add_argument("--top", type=int, default=3, help="candidates fitted through the simulator per step (default 3)")
    p.add_argument("--max-iter", type=int, default=12, help="Levenberg-Marquardt iterations per fit (default 12)")
    p.add_argument("--attitude-lag", default="auto", metavar="auto|SECONDS",
                   help="time constant of the attitude filter's lag on logged Euler angles: 'auto' (default, "
                        "estimated from the gyro, as uvsim calibrate does), a number, or 0 for none")
    add_judge_horizon_argument(p, "given")
    p.add_argument("--workers", type=int, default=1, help="processes for the simulations (same result)")
    p.add_argument("--checkpoint", help="file saved after every finished fit (default: the --json or --out file "
                                        "plus .ckpt; none without either)")
    p.add_argument("--resume", metavar="CKPT", help="continue an interrupted diagnosis from its checkpoint "
                                                    "(same dataset, vehicle and settings)")
    add_allow_argument(p)
    add_progress_arguments(p, quiet=True)
    p.set_defaults(func=run)


def _list(s):
    return [x.strip() for x in s.split(",") if x.strip()] if s else None


def format_table(report: dict) -> str:
    """Each step's candidates and the before/after lines as text."""
    lines = []
    for st in report["steps"]:
        what = " (the base model: thrust curve)" if st["step"] == 0 else ""
        lines.append(f"step {st['step']}{what}: validation cost {st['before_cost_per_entry']:.3f} (squared noise "
                     f"sigmas per residual) with {st.get('model', 'the given model')}")
        lines += _screening_lines(st.get("screening") or {})
        lines.append(f"  {'candidate':30s} {'screen':>7s} {'Wald p':>8s} {'val cost':>9s} {'change':>8s} {'P(better)':>9s}  "
                     "accepted  why")
        screen = {(s["effect"], s["variant"]): s["screening_reduction"] for s in st["screened"]}
        shown = set()
        for c in st["candidates"]:
            key = (c["effect"], c["variant"])
            shown.add(key)
            red = screen.get(key)
            if "compare" in c:
                wp = c["compare"].get("wald", {}).get("p")
                lines.append(f"  {c['effect'] + ':' + c['variant']:30s} {_pct(red):>7s} "
                             f"{('%.1e' % wp) if wp is not None else '-':>8s} {c['validation_cost_per_entry']:9.3f} {-100 * c['compare']['relative']:+7.1f}% "
                             f"{c['compare']['p_better']:9.3f}  {'YES' if c['chosen'] else ('(yes)' if c['accepted'] else 'no'):8s}  {c['why']}")
            else:
                lines.append(f"  {c['effect'] + ':' + c['variant']:30s} {_pct(red):>7s} {'':>8s} {'':>9s} {'':>8s} {'':>9s}  "
                             f"{'no':8s}  {c['why']}")
        rest = [f"{e}:{v} {_pct(r)}" for (e, v), r in screen.items() if (e, v) not in shown]
        if rest:
            lines.append("  screened only: " + ", ".join(rest))
    lines.append("(screen: share of the equation error a candidate removes; val cost: validation cost per residual "
                 "in squared noise sigmas; change: of the validation cost)")
    lines.append("")
    lines.append(f"effects: {report['effect']}   confidence: {report['confidence']}")
    for e in report["effects"]:
        lines.append(f"  {e['effect']}:{e['variant']}" + (f": {e['answer']}" if e.get("answer") else ""))
        for k, d in e["parameters"].items():
            std = f" +- {d['std']:.2g}" if d.get("std") is not None else ""
            lines.append(f"    {k} = {d['value']:.5g}{std} {d['unit']}")
    for k, d in report.get("retuned", {}).items():
        lines.append(f"  re-tuned {k}: {d['before']:.5g} -> {d['value']:.5g}"
                     + ("  AT BOUND (the edge of the re-tune's range: the data push it further)"
                        if d.get("at_bound") else ""))
    rv = report.get("retune_verdict")
    if rv is not None and not rv["kept"]:
        lines.append(f"  re-tune of {', '.join(rv['retune'])} not kept: {rv['message']}")
    lines.append(report["message"])
    for n in report.get("not_observable") or []:
        lines.append(f"not observable: {n['effect']} ({n['variants']}): {n['why']}")
    v = report.get("verdict") or {}
    if v.get("check"):
        lines.append(f"verdict: {v['status']}; what to check:")
        lines += [f"  - {c}" for c in v["check"]]
    lines.append("")
    mv = report.get("model_verdict")
    what = judged_label(report)
    if mv is not None:  # the one measure, as calibrate prints it (uvsim.fitting.verdict)
        lines.append(f"verdict on the validation runs ({what}, every logged channel):")
        lines += ["  " + line for line in verdict_table(mv)]
    else:
        lines.append(f"{'validation RMSE (' + what + ')':28s} {'given model (unchanged)':>24s}")
        for k, v in report["rmse_before"].items():
            lines.append(f"{k:28s} {v:24.5g}")
    lines.append(f"{report['fits']} fits in {report['seconds']:.1f} s")
    return "\n".join(lines)


def _screening_lines(info: dict) -> list[str]:
    """What the equation-error screening of a step could not use (nothing when it used every
    training run): the runs left out and why, or that it was off."""
    skipped = info.get("not_used") or {}
    if not skipped:
        return []
    used = info.get("runs") or []
    head = (f"  screening by equation error on {len(used)} of {len(used) + len(skipped)} training run(s)"
            if used else "  no screening by equation error (no training run allows it)")
    return [head + "; not used:"] + [f"    {why}" for why in skipped.values()]


def _pct(x):
    return "-" if x is None else f"{100 * x:.1f}%"


def run(args) -> int:
    from uvsim.commands.calibration_output import note_lines
    from uvsim.diagnosis import diagnose, save_fixed_vehicle
    from uvsim.errors import CalibrationError
    from uvsim.logs import read_dataset
    from uvsim.plausibility import parse_allow
    from uvsim.vehicle import load_vehicle

    progress = command_progress("diagnose", args)
    noise, weights = parse_pairs(args.noise, "--noise"), parse_pairs(args.weights, "--weights")
    judge, lag, allow = judge_option(args.judge_horizon), lag_option(args.attitude_lag), parse_allow(args.allow)
    ckpt = args.checkpoint or next((f"{f}.ckpt" for f in (args.json_out, args.out) if f), None)
    check_outputs({"--json": args.json_out, "--out": args.out, "--checkpoint": ckpt}, {"--plots": args.plots})
    if args.resume and not Path(args.resume).is_file():
        raise CalibrationError(f"--resume: the checkpoint {args.resume} does not exist")
    ds = read_dataset(args.data)
    if args.vehicle is None and ds.vehicle is None:
        raise CalibrationError(f"{ds.path}: no --vehicle given and the manifest names none")
    veh = load_vehicle(args.vehicle if args.vehicle is not None else (ds.vehicle_file or ds.vehicle))
    notes = check_runs_at_door("diagnose", ds.runs, veh, args.allow)
    try:
        diag = diagnose(ds, veh, retune=_list(args.retune), only=_list(args.only), noise=noise, weights=weights,
                        horizon=args.horizon, max_effects=args.max_effects, top=args.top, max_iter=args.max_iter,
                        workers=args.workers, progress=progress, allow=allow, checkpoint=ckpt,
                        resume=args.resume, attitude_lag=lag, judge_horizon=judge)
    except KeyboardInterrupt:
        held = ckpt or args.resume
        if held and Path(held).is_file():
            say("diagnose", f"interrupted; {held} holds the finished fits; continue with --resume {held}")
        else:
            say("diagnose", "interrupted before the first fit finished" + (
                "" if held else " (no checkpoint: give --checkpoint, --json or --out to keep finished fits)"))
        raise
    rep = diag.report
    split = rep["runs"]["split"]
    if split != "from the manifest":  # the runs were re-split: say so (it is in the report too)
        line = f"note: {ds.path / 'manifest.yaml'}: {split}"
        say("diagnose", line)
        notes.append(line)
    for line in note_lines(rep.get("sampling_notes", [])):  # held, interpolated, noise floors and declarations
        say("diagnose", line)
    if rep["attitude_lag"]["tau"]:
        say("diagnose", f"attitude filter lag {rep['attitude_lag']['tau']:.3f} s ({rep['attitude_lag']['source']})")
    rep["input_notes"] = notes
    problems = diagnosis_problems(rep, diag.validation)
    mv = rep.get("model_verdict")
    if problems:   # the fit fails a sanity check, whatever the verdict said of it (which why keeps)
        status, why = "refused", refusal(problems, mv)
    else:
        status = mv["status"] if mv is not None else "better"
        why = mv["message"] if mv is not None else "the model is unchanged (no effect named, no re-tune kept)"
    keep = status in ("better", "trade-off")
    caveats = diagnosis_caveats(rep, diag.validation)
    rep["status"] = {"ok": status == "better", "verdict": status, "exit_code": EXIT_CODES[status], "why": why,
                     "problems": problems, "caveats": caveats, "vehicle_written": bool(keep and args.out)}
    if args.json_out:
        Path(args.json_out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json_out).write_text(json.dumps(rep, indent=2, default=float))
    print(format_table(rep))
    if args.json_out:
        print(f"report: {args.json_out}")
    if args.plots:
        from uvsim.plotting.diagnosis import plot_diagnosis

        with progress.stage(f"plots into {args.plots}"):
            files = plot_diagnosis(diag, args.plots)
        print(f"plots: {', '.join(str(f) for f in files)}")
    if args.out and keep:
        save_fixed_vehicle(diag, args.out)
        print(f"corrected vehicle: {args.out}")
    remove_checkpoints(ckpt, args.resume)  # finished: every fit is in the report
    print(f"VERDICT (exit {EXIT_CODES[status]}) {why}" + "".join(f"; {c}" for c in caveats))
    if status != "better":
        say("diagnose", f"verdict {why}" + ("" if keep or not args.out else
                                            f"; no corrected vehicle was written to {args.out}"))
    return EXIT_CODES[status]
