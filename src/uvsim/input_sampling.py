"""Logged inputs that change like noise from one row to the next: a command faster than the log.

uvsim holds each logged input until the next row (zero-order hold, docs/model.md), as a vehicle
applies a command until the next one.  That is exact when the log holds every command.  An
autopilot that commands at its own loop rate (the field logs of uvsim.scenarios.field: 50 Hz)
and is logged slower (a topside log at 5-10 Hz) leaves rows that are snapshots of a command that
kept moving between them; under a hold mode driven by noisy sensors the command chatters, and the
held snapshot misstates the thrust between rows (on the project's field logs, the vertical
thrusters' held PWM at 10 Hz misses 26-44 % RMS of the delivered thrust and weakens the fitted
moments: docs/records/diagnose.md).  The log cannot say what happened between its rows, so uvsim
says so rather than guess.

**The sign of it.** Consecutive changes ``d_k = x_k - x_{k-1}`` of independent values have lag-1
autocorrelation exactly -1/2 (``d_k`` and ``d_{k+1}`` share ``x_k`` with opposite signs:
``cov = -var(x)``, ``var(d) = 2 var(x)``).  An input the log resolves changes in steps held over
rows (autocorrelation of its changes about 0) or in ramps and smooth sweeps (positive).  A column
is flagged when its changes' lag-1 autocorrelation is below :data:`CHATTER_AUTOCORR`, the midpoint
of the two, over at least :data:`MIN_CHANGES` changes (standard error about ``1/sqrt(n)``, 0.1,
so a resolved input at 0 lies 2.5 standard errors above the line).  Measured: the field logs'
vertical thrusters under depth hold -0.25 to -0.52, their horizontal ones +0.6 to +0.85; the
shipped tank tests and the ArduSub sample logs 0.
"""
from __future__ import annotations

import numpy as np

#: Flag below this lag-1 autocorrelation of an input's row-to-row changes (module docstring:
#: midway between 0, an input the log resolves, and -1/2, independent values).
CHATTER_AUTOCORR = -0.25
#: Fewest row-to-row changes for the statistic (module docstring: standard error ~0.1).
MIN_CHANGES = 100


def change_autocorrelation(x: np.ndarray) -> float | None:
    """Lag-1 autocorrelation of the row-to-row changes of ``x`` (n,), over its finite rows; None
    with fewer than :data:`MIN_CHANGES` changes or a constant input."""
    x = np.asarray(x, float)
    d = np.diff(x[np.isfinite(x)])
    if d.size < MIN_CHANGES:
        return None
    d = d - d.mean()
    v = float(np.mean(d * d))
    if v <= 0.0:
        return None
    return float(np.mean(d[1:] * d[:-1]) / v)


def chattering_inputs(run) -> dict[str, float]:
    """{input column: lag-1 autocorrelation of its changes} of ``run``'s inputs that change like
    noise from row to row (below :data:`CHATTER_AUTOCORR`)."""
    out = {}
    u = run.inputs  # (n, k), read from the table once
    for j, col in enumerate(run.input_columns):
        r = change_autocorrelation(u[:, j])
        if r is not None and r < CHATTER_AUTOCORR:
            out[col] = r
    return out


def chattering_input_notes(runs) -> list[str]:
    """One note for ``runs`` (none when no input chatters): the input columns that change like noise
    from row to row (:func:`chattering_inputs`), the runs they do it in and the log's rate there."""
    cols: dict[str, None] = {}
    names: dict[str, None] = {}
    rs, rates = [], []
    for run in runs:
        found = chattering_inputs(run)
        if not found:
            continue
        cols.update(dict.fromkeys(found))
        names[run.segment_of or run.name] = None  # a run cut at a gap: once
        rs += list(found.values())
        t = np.asarray(run.t, float)
        rates.append(1.0 / float(np.median(np.diff(t))))
    if not cols:
        return []
    order = {c: i for i, c in enumerate(runs[0].input_columns)}
    cols = dict.fromkeys(sorted(cols, key=lambda c: order.get(c, len(order))))
    lo, hi = min(rs), max(rs)
    span = f"{lo:.2f}" if abs(hi - lo) < 0.005 else f"{lo:.2f} to {hi:.2f}"
    r_lo, r_hi = min(rates), max(rates)
    hz = f"{r_lo:.2g}" if abs(r_hi - r_lo) < 0.05 * r_hi else f"{r_lo:.2g}-{r_hi:.2g}"
    shown = list(names)
    where = ", ".join(shown[:4]) + (f", ... ({len(shown)} runs)" if len(shown) > 4 else "")
    return [f"{', '.join(cols)} of {where} change like noise from one row to the next (lag-1 autocorrelation of "
            f"their changes {span}; an input the log resolves has 0 or more): if the autopilot commanded faster "
            f"than the log's {hz} Hz, each row is a snapshot that uvsim holds to the next row, which misstates what the "
            "actuators did between rows; log the inputs at the autopilot's rate (docs/log_format.md, \"Inputs logged "
            "slower than they were commanded\")"]
