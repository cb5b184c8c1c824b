"""After a trade-off: which structure the fit lacked (``Calibrator(trade_off="explore")``,
``--trade-off explore``; docs/calibration_method.md, "After a trade-off").

A *trade-off* (:mod:`uvsim.fitting.verdict`) is a fit whose pooled validation error is lower
than the starting model's while some channel's is higher beyond the comparison's noise: the
fitted coefficients stand in for something the model cannot express, and they mispredict the
channels where the stand-in fails.  The verdict names what the model may lack there
(:data:`uvsim.fitting.verdict.HINTS`).  "explore" tests those of the hints a calibration can
fit, each as one hypothesis (:data:`HYPOTHESES`):

1. it applies when one of its channels is among the worse ones and it frees at least one
   parameter the fit did not (those the user fixed stay fixed);
2. the joint fit runs again from the first fit's values with the hypothesis' parameters freed
   beside the first fit's (the same priors, bounds, windows and whole-run last stage);
3. the refit is judged by the calibration's own verdict against the model the user started from,
   on the same validation runs.

The report (``trade_off``) lists each hypothesis with its verdict, its pooled change, its worse
channels and the values the freed parameters took.  The refit is **adopted** when its verdict
is *better* (pooled better beyond the noise, no channel worse); of several, the one with the
lowest pooled error.  Otherwise the first fit stands, with its trade-off, and the list says what
was tried and did not remove it: that is the finding, not a result.

**What adoption costs.**  The choice looks at the validation runs once per hypothesis (at most
:data:`MAX_LOOKS` looks): each look is a verdict at the one-sided 95 % level, so with two
hypotheses a *better* verdict found this way has up to twice the chance of a lucky pass that a
single verdict has.  The report says how many were looked at; give more or longer validation
runs when that matters.  The hypotheses are physical (a thruster mounted a centimetre or two off
its drawing; a centre of buoyancy off the file's), each a few parameters under the priors of
the vehicle file, not a search over models.

Measured on the structural benchmark (``uvsim bench calibrate-structural``, docs/calibration.md):
freeing the thruster positions for every seed turned one trade-off better and three better
seeds worse (records, "Freeing the thruster positions too"); freeing them only after a trade-off
leaves every seed that was better as it was, by construction.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from uvsim.errors import CalibrationError

#: The settings of ``trade_off``: None (the default: report the trade-off) or "explore".
SETTINGS = (None, "explore")
#: The most validation looks an exploration makes (one per hypothesis).
MAX_LOOKS = 2


@dataclass(frozen=True)
class Hypothesis:
    """A structure the fit may lack: ``families`` (``--free`` syntax) freed when one of
    ``channels`` is worse; ``tag``: its joint stage's checkpoint suffix; ``why``: one line."""

    name: str
    families: str
    channels: frozenset
    tag: str
    why: str


#: The hints of :data:`uvsim.fitting.verdict.HINTS` a calibration can fit.  Thruster positions:
#: a hand-built frame places a unit a centimetre or two off its drawing, and the lever arm sets
#: the yaw and roll moment of every thrust combination, so a fit of gains alone matches the
#: training runs' combinations and mispredicts the others (the structural benchmark's
#: ``thruster_position_error``, 1-3 cm).  Centre of buoyancy: the restoring moments of roll
#: and pitch and the attitude that tilts gravity into the accelerometer (a float or payload
#: moved, foam compressed).
HYPOTHESES = (
    Hypothesis("thruster positions", "thruster_x_*,thruster_y_*",
               frozenset({"yaw", "r", "roll", "p", "v", "y", "acc_y"}), ".positions",
               "the thrusters off the file's positions (the lever arms of the yaw and roll moments)"),
    Hypothesis("centre of buoyancy", "x_b,y_b,z_b",
               frozenset({"roll", "pitch", "p", "q", "acc_x", "acc_y"}), ".buoyancy",
               "the centre of buoyancy off the file's (the roll and pitch restoring moments)"),
)
#: The joint stage's progress label of each hypothesis' refit (uvsim.calibration.stages).
LABELS = {h.tag: f"joint fit again with the {h.name} freed (after a trade-off)" for h in HYPOTHESES}


def check_setting(value):
    """``Calibrator(trade_off=...)`` checked: None or "explore"."""
    if value not in SETTINGS:
        raise CalibrationError(f"trade_off {value!r}: expected None or 'explore' (--trade-off explore)")
    return value


def applicable(worse, free, fixed, known) -> list[tuple[Hypothesis, list[str]]]:
    """The hypotheses to test after a trade-off in the channels ``worse``, each with the
    parameters it frees beside ``free`` (none of ``fixed``; only names in ``known``)."""
    import fnmatch

    out = []
    for h in HYPOTHESES:
        if not set(worse) & h.channels:
            continue
        pats = h.families.split(",")
        new = [k for k in known if any(fnmatch.fnmatchcase(k, p) for p in pats) and k not in free and k not in fixed]
        if new:
            out.append((h, new))
    return out[:MAX_LOOKS]


def summary(v: dict) -> dict:
    """The parts of a verdict an exploration records."""
    return {"status": v["status"], "pooled_rmse_change": v["pooled"]["rmse_change"], "worse": list(v["worse"]),
            "message": v["message"]}


def explore(refit, judge, first_verdict: dict, first_values: dict, free, fixed, known, initial: dict):
    """Test the hypotheses of the module docstring.

    Parameters
    ----------
    refit : ``refit(hypothesis, names) -> FitResult or None``, the joint stage from the first
        fit's values freeing ``names`` (the first fit's and the hypothesis').
    judge : ``judge(FitResult) -> verdict`` (:func:`uvsim.fitting.verdict.compare` of the model
        it gives against the starting model, as the calibration's verdict judges).
    first_verdict : the first fit's verdict (a trade-off); first_values : its fitted values.
    free, fixed : the first fit's free and the fixed parameter names; known : every parameter.
    initial : the starting vehicle's parameters (the report's shifts).

    Returns
    -------
    (record, adopted)
        ``record``: report.json's ``trade_off``; ``adopted``: the FitResult to keep, or None.
    """
    tried, best = [], None
    for h, new in applicable(first_verdict["worse"], free, fixed, known):
        t0 = time.perf_counter()
        res = refit(h, [*free, *new])
        entry = {"hypothesis": h.name, "why": h.why, "freed": new, "seconds": time.perf_counter() - t0}
        if res is None:
            entry.update(status="failed", message="the joint fit gave no result")
            tried.append(entry)
            continue
        v = judge(res)
        entry.update(summary(v))
        entry["values"] = {k: float(res.values[k]) for k in new}
        entry["shift"] = {k: float(res.values[k]) - float(initial[k]) for k in new}
        tried.append(entry)
        if v["status"] == "better" and (best is None or v["pooled"]["change"] < best[1]["pooled"]["change"]):
            best = (h, v, res)
    record = {"first_fit": {**summary(first_verdict), "parameters": {k: float(v) for k, v in first_values.items()}},
              "tried": tried, "validation_looks": len(tried),
              "adopted": None if best is None else best[0].name}
    return record, (None if best is None else best[2])


def message(record: dict) -> str:
    """One sentence on an exploration for the verdict's paragraph."""
    first = record["first_fit"]
    worse = ", ".join(first["worse"])
    if not record["tried"]:
        return (f"the first fit was a trade-off in {worse}; no hypothesis of --trade-off explore applies to those "
                "channels (docs/calibration_method.md, 'After a trade-off')")
    parts = []
    for e in record["tried"]:
        if e["status"] == "failed":
            parts.append(f"{e['hypothesis']}: the refit failed")
            continue
        far = max(e["shift"], key=lambda k: abs(e["shift"][k]))
        parts.append(f"{e['hypothesis']} freed: {e['status']} (pooled {100 * e['pooled_rmse_change']:+.0f} %"
                     + (f"; worse in {', '.join(e['worse'])}" if e["worse"] else "")
                     + f"; largest move {far} {1000 * e['shift'][far]:+.0f} mm)")
    head = (f"the first fit was a trade-off in {worse} (pooled {100 * first['pooled_rmse_change']:+.0f} %); "
            + "; ".join(parts))
    if record["adopted"]:
        n = record["validation_looks"]
        return (head + f"; the fit with the {record['adopted']} freed is kept ({n} "
                f"{'hypothesis' if n == 1 else 'hypotheses'} judged on the validation runs)")
    return head + "; none removed the trade-off, so the first fit stands"
