"""What ``uvsim calibrate`` prints and writes about a fitted Calibrator: the summary table, the
fitted vehicle file with each value's provenance, the verdict's table and line, and the outcome
(status, exit code, what may be written) of docs/calibration.md, "The verdict".  Shared by the
command, ``uvsim demo`` and ``examples/paper_workflow.py``."""
from __future__ import annotations

import math
import sys
from pathlib import Path

from uvsim.commands.checks import calibration_caveats, calibration_problems, refusal
from uvsim.fitting.verdict import EXIT_CODES

ADDED_MASS_ROWS = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")


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


def note_lines(notes) -> list[str]:
    """Per-run notes (:func:`_grouped_notes`) as the commands print them: ``note: TEXT (N runs: A, B, C, ...)``."""
    return [f"note: {text} ({len(runs)} run{'s' if len(runs) > 1 else ''}: {', '.join(runs[:3])}"
            f"{', ...' if len(runs) > 3 else ''})" for text, runs in _grouped_notes(notes).items()]


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
    for line in note_lines(rep["notes"]):
        say(line)
    say(f"training RMSE {_rmse_text(rep['training_rmse'])}")
    say(f"validation RMSE {_rmse_text(rep['validation_rmse'])} (initial {_rmse_text(rep['initial_validation_rmse'])})")
    if rep["validation_fit_percent"]:
        say("validation Fit %: " + ", ".join(f"{c} {v:.1f}" for c, v in rep["validation_fit_percent"].items()))


def _rmse_text(rmse) -> str:
    """``{group_unit: RMSE}`` as ``depth 0.0075 m, rates 0.00389 rad/s`` (4 significant digits)."""
    from uvsim.signals import UNITS

    if not rmse:
        return "(none)"
    out = []
    for k, v in rmse.items():
        group = str(k).partition("_")[0]
        out.append(f"{group} {v:.4g} {UNITS.get(group, '')}".rstrip() if v is not None and math.isfinite(v)
                   else f"{group} not finite")
    return ", ".join(out)


def outcome(rep, ds) -> tuple[str, str, list[str], list[str]]:
    """(status, why, problems, caveats) of a calibration report: the verdict's status ("better",
    "trade-off", "worse") and message, or "refused" when a sanity check fails
    (:func:`calibration_problems`: a simulation that diverges or explodes where the starting
    model's does not, every parameter of a DOF on a bound), ``problems`` then saying which and
    ``why`` what the verdict alone said (:func:`refusal`).
    ``why`` ends with the caveats that do not change the status (:func:`calibration_caveats`:
    an unfinished fit, simulations of both models that leave the data)."""
    problems = calibration_problems(rep, ds)
    caveats = calibration_caveats(rep, ds)
    v = rep.get("verdict")
    if problems:
        status, why = "refused", refusal(problems, v)
    elif v is None:
        status, why = "better", "no runs to compare with the starting model"
    else:
        status, why = v["status"], v["message"]
    for c in caveats:
        if c not in why:
            why += f"; {c}"
    return status, why, problems, caveats


def record_outcome(cal, ds, *, keep_worse: bool = False) -> tuple[str, str, bool]:
    """(status, why, keep) of a fitted Calibrator (:func:`outcome`), also written into its
    report's ``status``; ``keep``: whether the fitted vehicle may be written (*better* or
    *trade-off*; *worse* or *refused* only with ``keep_worse``)."""
    rep = cal.report_
    status, why, problems, caveats = outcome(rep, ds)
    keep = status in ("better", "trade-off") or keep_worse
    rep["status"] = {"ok": status == "better", "verdict": status, "exit_code": EXIT_CODES[status], "why": why,
                     "problems": problems, "caveats": caveats, "vehicle_written": bool(keep)}
    return status, why, keep


def print_verdict(rep, status: str, why: str, out=None) -> None:
    """The verdict's per-channel table and its one-paragraph message ``why`` (:func:`outcome`)."""
    from uvsim.commands.checks import judged_label
    from uvsim.fitting.verdict import table

    out = sys.stdout if out is None else out
    v = rep.get("verdict")
    if v is not None:
        print(f"verdict on the {v['split']} runs ({judged_label(rep)}, every logged channel):", file=out)
        for line in table(v):
            print("  " + line, file=out)
    print(f"VERDICT (exit {EXIT_CODES[status]}) {why}", file=out)
