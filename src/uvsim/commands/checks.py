"""What the commands check before and after their work (docs/contracts.md).

Before: every output path can be written (:mod:`uvsim.files`), the runs make physical
sense for the vehicle (:mod:`uvsim.plausibility`, ``--allow NAME``), and what the
readers changed in the data (:attr:`uvsim.logs.Run.notes`) is printed.
After: a fit's result is sane before it is reported as a success (finite RMSE, not an
order of magnitude beyond the measured signals where the starting model's is not, not every
parameter of a DOF on a search bound), otherwise :class:`uvsim.errors.ResultCheckError` (exit status 2) says why.
"""
from __future__ import annotations

import math

from typing import Iterable, Mapping

from uvsim.errors import ResultCheckError
from uvsim.files import check_not_an_input, check_output_dir, check_output_file

# a fitted model whose RMSE exceeds EXPLODE_FACTOR times the spread of the measured signal predicts
# nothing: the fit "exploded" (uvsim.spread; the diagnosis decides by the same test when to judge
# closed-loop logs over windows)
from uvsim.spread import EXPLODE_FACTOR, beyond_spread as _exploded, signal_spread as _spread  # noqa: F401


def add_allow_argument(p) -> None:
    from uvsim.plausibility import CHECKS, NOT_ALLOWABLE

    names = ", ".join(c for c in CHECKS if c not in NOT_ALLOWABLE)
    p.add_argument("--allow", default=None, metavar="NAME[,NAME]",
                   help=f"turn these plausibility checks of the runs into warnings ({names}; docs/contracts.md)")


def add_judge_horizon_argument(p, who: str) -> None:
    """``--judge-horizon auto|whole|SECONDS`` (:func:`uvsim.fitting.evaluate.judged_prediction`); ``who``:
    the reference model ("given" for diagnose, "starting" for calibrate)."""
    p.add_argument("--judge-horizon", default="auto", metavar="auto|whole|SECONDS",
                   help="what the verdict, the RMSEs and the plots compare: 'auto' (default) free simulations of "
                        "whole runs, or predictions over windows from the logged states on closed-loop logs: 1 s when "
                        f"the manifest says a run was flown under an autopilot (closed_loop), 5 s when the {who} "
                        "model's free simulation leaves the validation data (docs/diagnose.md); 'whole'; "
                        "or a window length in seconds")


def judge_option(s: str):
    """``--judge-horizon``: "auto", "whole" or a number of seconds >= 0 (an error naming the option
    otherwise)."""
    from uvsim.errors import CalibrationError
    from uvsim.fitting.evaluate import check_judge_horizon

    if s in ("auto", "whole"):
        return s
    try:
        value = float(s)
    except ValueError:
        raise CalibrationError(f"--judge-horizon {s!r}: expected auto, whole or a number of seconds") from None
    return check_judge_horizon(value, "--judge-horizon")


def judged_label(report: Mapping) -> str:
    """What the verdict compared, in a few words (:func:`uvsim.fitting.evaluate.judged_label` of the
    report's ``judged``; imported here when used, so that the commands start light)."""
    from uvsim.fitting.evaluate import judged_label as label

    return label(report.get("judged"))


def _windows_caveat(judged: Mapping, who: str, doc: str, shown: str) -> str:
    """The caveat of a verdict judged over windows (``judged``: the report's record): why, when the
    log declared closed-loop runs (its ``declared``) or the reference model (``who``) left the data (its
    ``left_data``), and that ``shown`` are of the windows."""
    left, declared, split = judged.get("left_data"), judged.get("declared"), judged.get("split", "validation")
    why = ""
    if declared:
        why = f"the log says the {split} runs {', '.join(declared)} were flown under an autopilot (closed_loop in the " \
              "manifest), so "
    elif left:
        why = (f"the {who} model's free simulation of whole runs leaves the {split} data ({', '.join(left)} beyond "
               f"{EXPLODE_FACTOR:g} times the measured spread: a model flown open loop where the vehicle was under an "
               "autopilot, or a large missing effect), so ")
    return (f"{why}the models were judged on predictions over windows of {judged['horizon_s']:g} s from the "
            f"logged states ({doc}, 'Closed-loop logs'); {shown} of those windows")


def add_progress_arguments(p, quiet: bool = False) -> None:
    """``--progress`` / ``--no-progress`` (and ``--quiet``, the same as ``--no-progress``)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--progress", dest="progress", action="store_true", default=None,
                   help="progress bars for the long stages (default: bars when stderr is a terminal, else one line "
                        "per stage on stderr: 'uvsim COMMAND: STAGE ... done in 12.3 s')")
    g.add_argument("--no-progress", dest="progress", action="store_false", help="no progress output")
    if quiet:
        g.add_argument("--quiet", dest="progress", action="store_false", help="the same as --no-progress")


def command_progress(command: str, args):
    """The :class:`uvsim.progress.Progress` of ``uvsim COMMAND`` for its ``--progress`` options."""
    from uvsim.progress import Progress

    return Progress.for_command(command, args.progress)


def say(command: str, message: str) -> None:
    from uvsim.progress import write_line

    write_line(f"uvsim {command}: {message}")


def check_outputs(files: Mapping[str, object] = (), dirs: Mapping[str, object] = (),
                  inputs: Mapping[str, object] = ()) -> None:
    """Check output files ``{option: path}`` and directories before any work (None = not given);
    no output file may be one of the input files ``inputs`` ({option: path})."""
    for option, path in dict(files).items():
        if path is not None:
            check_output_file(path, option)
            check_not_an_input(path, option, inputs)
    for option, path in dict(dirs).items():
        if path is not None:
            check_output_dir(path, option)


def check_runs_at_door(command: str, runs, vehicle, allow_text: str | None) -> list[str]:
    """Plausibility of ``runs`` for ``vehicle`` and the readers' notes: raises for a
    finding not allowed, prints allowed findings and notes; returns the printed lines
    (for the report)."""
    from uvsim.input_sampling import chattering_input_notes
    from uvsim.plausibility import check_runs, parse_allow

    allow = parse_allow(allow_text)
    lines = [f"warning (allowed {f.check}): {f.message}" for f in check_runs(runs, vehicle, allow)]
    # the segments of a run cut at a gap share its notes (uvsim.gaps): each is said once
    lines += [f"note: {n}" for n in dict.fromkeys(n for r in runs for n in r.notes)]
    lines += unused_voltage_notes(runs, vehicle)
    lines += [f"note: {n}" for n in chattering_input_notes(runs)]
    for line in lines:
        say(command, line)
    return lines


def unused_voltage_notes(runs, vehicle) -> list[str]:
    """A note when PWM runs log the battery voltage and the vehicle's thrust curves do not
    depend on it (the column is read and then not used: said, not silent)."""
    act = getattr(vehicle, "actuators", None)
    logged = [r.name for r in runs if r.has_voltage and r.input_kind == "pwm"]
    if not logged or act is None or not act.curves or act.voltage_dependent:
        return []
    more = f", ... ({len(logged)} runs)" if len(logged) > 3 else ""
    return [f"note: the voltage column of {', '.join(logged[:3])}{more} is not used: the vehicle's thrust curves do "
            "not depend on the supply voltage (a battery-aware curve does: curve: {voltage_table: t200, "
            "nominal_voltage: 16}, docs/thrusters.md)"]


def rmse_problems(rmse: Mapping[str, float], runs, what: str,
                  start: Mapping[str, float] | None = None) -> list[str]:
    """Non-finite RMSEs and RMSEs beyond EXPLODE_FACTOR x the measured spread.

    With ``start`` (the same RMSEs of the model the user started from), a channel counts only
    where the start model's simulation stays finite and within the factor: a fit is not refused
    for what the start model does on the same runs (an open-loop unstable vehicle flown in
    closed loop); the verdict compares the two over the horizon both stay finite, and
    :func:`calibration_caveats` says where both leave the data."""
    spread = _spread(runs)
    bad = _exploded(rmse, spread) - (_exploded(start, spread) if start is not None else set())
    unlike_start = "" if start is None else " where the starting model's did not"
    out = []
    for k in (k for k in rmse if k in bad):
        v = rmse[k]
        if v is None or not math.isfinite(v):
            out.append(f"{what} {k} is not finite (the simulation diverged{unlike_start})")
        else:
            out.append(f"{what} {k} = {v:.4g} is {v / spread[k]:.3g} times the spread of the measured signal "
                       f"({spread[k]:.4g}); expected at most {EXPLODE_FACTOR:g} times "
                       f"(the simulation diverged{unlike_start})")
    return out


def remove_checkpoints(*paths) -> None:
    """Remove a finished command's checkpoint files (``paths``; absent ones are skipped): once its
    outputs are written, resuming has nothing left to save, and a diagnosis checkpoint holds tens
    of MB."""
    from pathlib import Path

    for p in paths:
        if p is not None and Path(p).is_file():
            Path(p).unlink()


def fail_if(problems: Iterable[str], command: str, hint: str) -> None:
    problems = list(problems)
    if problems:
        raise ResultCheckError(f"the result of {command} fails its sanity checks and is not reported as a "
                               f"success: {'; '.join(problems)}. {hint}")


def refusal(problems: list[str], verdict: dict | None) -> str:
    """The message of a fit refused by a sanity check: the ``problems``, then what the verdict
    (``{"message": ...}``, the one measure) said of the same fit, so that a fit the measure calls
    better is not read as worse."""
    alone = f"; without the check the verdict is {verdict['message']}" if verdict else ""
    return "refused: " + "; ".join(problems) + alone


def calibration_problems(rep: Mapping, ds) -> list[str]:
    """Sanity problems of a calibration report (``Calibrator.report_``), beside its verdict
    (:mod:`uvsim.fitting.verdict`, which judges the fitted model against the start)."""
    from uvsim.calibration.params import DOF_PARAMETERS

    probs = rmse_problems(rep["training_rmse"], [r for r in ds.runs if r.split == "train"], "training RMSE",
                          rep.get("initial_training_rmse"))
    probs += rmse_problems(rep["validation_rmse"], [r for r in ds.runs if r.split == "validation"],
                           "validation RMSE", rep.get("initial_validation_rmse"))
    hits = bound_hits(rep)
    for d in rep["dofs"]:
        names = [k for k in DOF_PARAMETERS.get(d, ()) if k in rep["parameters"]]
        if names and set(names) <= set(hits):
            probs.append(f"every fitted {d} parameter ({', '.join(names)}) ended on a search bound, so the data "
                         "do not determine them (wrong units, or a starting vehicle far off: widen --margin)")
    return probs


def _lost_angle_caveat(judged: Mapping, who: str, doc: str) -> list[str]:
    """The caveat of a verdict judged over whole runs whose reference model (``who``) lost an angle
    (``judged["lost_angles"]``, :func:`uvsim.fitting.evaluate.lost_angles`, recorded with whole runs
    only), else nothing."""
    lost = judged.get("lost_angles")
    if not lost:
        return []
    from uvsim.fitting.evaluate import lost_angles_text

    split = judged.get("split") or "validation"
    split = "training" if split == "train" else split
    return [f"the {who} model's free simulation of the {split} runs has lost "
            f"{lost_angles_text(lost)}, as a model "
            f"flown open loop does where an autopilot held the vehicle: over whole runs, {' and '.join(lost)} and the "
            "body-frame velocities of anything fixed in the world (a current, a tether's pull) are compared on "
            f"trajectories that have lost {'it' if len(lost) == 1 else 'them'}, so a trade-off there may be the "
            "comparison's own; if the runs were flown under an autopilot, say so (closed_loop: true in the "
            "manifest) or give --judge-horizon SECONDS, and predictions over windows from the logged states are "
            f"judged instead ({doc}, 'Closed-loop logs')"]


def calibration_caveats(rep: Mapping, ds) -> list[str]:
    """What a user should know about a calibration that does not change its verdict: a joint fit
    stopped at the iteration limit (*unfinished*) is judged like any other fit, by how its model
    compares with the start (issue 45: no heuristic refuses a fit whose validation is better),
    and a fitted model whose simulation leaves the data as the starting model's does (RMSE beyond
    EXPLODE_FACTOR x the signal's spread in both) predicts those channels no better in absolute
    terms, whatever the verdict says about the two."""
    out = []
    stages = (rep.get("refinement") or {}).get("stages") or []
    if stages and str(stages[-1].get("message", "")).startswith("maximum number of iterations"):
        out.append(f"unfinished: the joint fit's last stage stopped at the iteration limit "
                   f"({stages[-1].get('iterations')} iterations) before converging; the verdict judges the model "
                   "it reached, and raising --max-iter may move it")
    judged = rep.get("judged") or {}
    if judged.get("prediction") == "windows":
        out.append(_windows_caveat(judged, "starting", "docs/calibration.md", "the RMSEs, Fit % and plots are"))
        return out
    out += _lost_angle_caveat(judged, "starting", "docs/calibration.md")
    for split, key in (("train", "training_rmse"), ("validation", "validation_rmse")):
        spread = _spread([r for r in ds.runs if r.split == split])
        names = sorted(_exploded(rep.get(key) or {}, spread) & _exploded(rep.get("initial_" + key) or {}, spread))
        if names:
            out.append(f"on the {split} runs the simulations of both models leave the data ({', '.join(names)} "
                       f"beyond {EXPLODE_FACTOR:g} times the measured spread): better than the start there is "
                       "not yet a model that predicts them")
    return out


def diagnosis_caveats(rep: Mapping, val_runs) -> list[str]:
    """What a user should know about a diagnosis that does not change its verdict: where the
    given model's free simulation leaves the validation data (and whether the corrected one
    still does), as calibrate says it of the start model (:func:`calibration_caveats`); when it
    left them, the diagnosis judged predictions over windows instead (``rep["judged"]``,
    :func:`uvsim.fitting.evaluate.judged_prediction`), and that is said."""
    judged = rep.get("judged") or {}
    if judged.get("prediction") == "windows":  # (judged_prediction recorded which channels the given model left)
        return [_windows_caveat(judged, "given", "docs/diagnose.md", "the RMSEs reported are")]
    lost = _lost_angle_caveat(judged, "given", "docs/diagnose.md")
    spread = _spread(val_runs)
    given = _exploded(rep.get("rmse_before") or {}, spread)
    if not given:
        return lost
    still = sorted(given & _exploded(rep.get("rmse_after") or {}, spread))
    return [f"the given model's free simulation leaves the validation data ({', '.join(sorted(given))} beyond "
            f"{EXPLODE_FACTOR:g} times the measured spread: a model flown open loop where the vehicle was under an "
            "autopilot, or a large missing effect)" + (f"; the corrected model's still does in {', '.join(still)}"
                                                        if still else "; the corrected model's stays with it")] + lost


#: A fitted value within this fraction of its search range from a bound is "on the bound"
#: (a bounded least-squares solver such as scipy's 'trf' stays strictly inside its bounds,
#: so a value pushed against one ends a hair inside it).
BOUND_TOL = 1e-3


def bound_hits(rep: Mapping) -> dict[str, str]:
    """{parameter: "lower"|"upper"} for the fitted parameters on a search bound."""
    out = {}
    for k, v in rep["parameters"].items():
        if k not in rep["bounds"]:
            continue
        lo, hi = rep["bounds"][k]
        if min(v - lo, hi - v) <= BOUND_TOL * (hi - lo):
            out[k] = "lower" if abs(v - lo) <= abs(v - hi) else "upper"
    return out


def _all_on_bounds(name: str, values: Mapping[str, float | None]) -> str:
    """The problem of an accepted effect ``name`` whose every fitted parameter (``values``: name ->
    fitted value, None where the report has none) is on a search bound: the bound is where the fit
    stopped, not what the data say (issue 48: a thrust scale on its 0.5 floor under an autopilot that
    pushes against a tether the model lacks)."""
    listed = ", ".join(k if v is None else f"{k} {v:.4g}" for k, v in values.items())
    return (f"every fitted parameter of the accepted effect {name} ({listed}) ended on a bound of its search "
            "range: the data push it beyond what the catalogue considers physical, so the value is the bound, "
            "not an answer (an effect outside the catalogue, or a force the model lacks that an autopilot "
            "pushes against, is the likelier cause)")


def diagnosis_problems(rep: Mapping, val_runs) -> list[str]:
    """Sanity problems of a diagnosis report: the corrected model's simulation leaving the data
    where the given model's does not, an accepted effect all on its search bounds. The given
    model's own simulation leaving the data is not one (an open-loop model of a vehicle flown
    under an autopilot drifts; issue 48): :func:`diagnosis_caveats` says so."""
    from uvsim.diagnosis.summary import every_parameter_on_bound

    probs = rmse_problems(rep["rmse_after"], val_runs, "validation RMSE after the fit", rep["rmse_before"])
    final = (([{**rep["base_model"], "effect": "base_model"}] if rep.get("base_model") else [])
             + list(rep.get("effects") or []))
    if final and all("at_bound" in d for f in final for d in f["parameters"].values()):
        # the corrected model's own values (the final joint fit): a step's fit can end on a bound that a
        # later step's leaves (field logs, dead case seed 21: the thrust scale 0.5 in step 0, 0.61 beside
        # the dead unit); a dead unit's gain 0 is a physical floor, not a bound (uvsim.diagnosis.core)
        for f in final:
            if every_parameter_on_bound(f["parameters"]):
                probs.append(_all_on_bounds(f"{f['effect']}:{f['variant']}",
                                            {k: d.get("value") for k, d in f["parameters"].items()}))
        return probs
    for step in rep.get("steps", []):  # a report without the final fit's bounds
        chosen = next((c for c in step["candidates"] if c.get("chosen")), None)
        if chosen is not None and chosen.get("free") and set(chosen["free"]) <= set(chosen.get("at_bounds", ())):
            vals = chosen.get("values") or {}
            probs.append(_all_on_bounds(f"{chosen['effect']}:{chosen['variant']}", {k: vals.get(k) for k in chosen["free"]}))
    return probs
