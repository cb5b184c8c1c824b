"""Estimating the sensor latency of a log (``Calibrator(latency="auto")``, ``--latency auto``).

After the joint fit, the fitted model predicts the training runs in short windows
(:data:`SCAN_HORIZON`, from the logged states; :class:`uvsim.fitting.objective.WindowedProblem`
at its reference nuisance) with the inputs delayed by each latency of a grid
(:data:`SCAN_GRID`; :mod:`uvsim.latency`).  The latency of lowest cost, refined by a parabola
through it and its neighbours, is taken when it lowers the cost by at least
:data:`MIN_GAIN` of the cost at the vehicle's own latency; the calibration then fits again
from its result with that latency (docs/calibration_sensors.md, "Sensor latency").

Why after the fit and not with the start model: a start model 20-40 % off mistakes its own
errors for a delay (too much added mass looks like a late response).  On the structural
benchmark's seeds 0, 1, 13 and 22 (truth latencies 15, 15 + a 45 ms thruster lag, 35 and 14
ms) the start model's scan gave 100, 100, 50 and 10 ms, the fitted model's 0, 40, 30 and
10 ms (measured 2026-11-27 with this scan; docs/calibration.md).  A fit already absorbs part
of a latency in its coefficients, so the estimate can fall short of the truth (seed 0), which
leaves the calibration as it was without the scan.
"""
from __future__ import annotations

import logging

import numpy as np

from uvsim.fitting.objective import WindowedProblem
from uvsim.fitting.parameters import ParameterSpace
from uvsim.latency import delay_inputs

log = logging.getLogger("uvsim")

#: Latencies tried, s: 0-100 ms in 10 ms steps (ArduSub's sensor path is tens of ms; one
#: 100 Hz sample is 10 ms).
SCAN_GRID = np.round(np.arange(0.0, 0.1001, 0.01), 3)
#: Window length of the scan's predictions, s: long enough for a delayed input to show in
#: the response, short enough that the model's own errors do not pile up.
SCAN_HORIZON = 1.0
#: Smallest relative decrease of the windowed cost that makes the latency worth fitting again
#: with: a one-parameter change to the model must buy more than the scan's own resolution; the
#: refit is still judged by the calibration's result check on the validation runs.
MIN_GAIN = 0.02


def windowed_costs(vehicle, runs, meas, latencies, *, attitude_bias: bool = False) -> np.ndarray:
    """Sum of squared windowed residuals of ``vehicle`` on ``runs`` with each sensor latency of
    ``latencies`` (s): what ``vehicle.with_latency(d)`` predicts, for every ``d`` in one windowed
    problem per input kind (the copies of a run with its inputs delayed by each ``d`` are rows of
    one batch: the same numbers as one problem per latency, one simulation instead of many)."""
    latencies = [float(d) for d in latencies]
    veh = vehicle.with_latency(0.0)  # the copies carry their delays themselves
    space = ParameterSpace([], veh.parameters(), {})
    total = np.zeros(len(latencies))
    kinds: dict = {}
    for r, m in zip(runs, meas):
        kinds.setdefault((r.input_kind, len(r.input_columns)), []).append((r, m))
    for group in kinds.values():
        copies = [(j, _shifted(r, d, j), m) for j, d in enumerate(latencies) for r, m in group]
        wp = WindowedProblem(veh, [c for _, c, _ in copies], [m for _, _, m in copies], space, SCAN_HORIZON,
                             attitude_bias=attitude_bias and any(m.has_filter_attitude for _, m in group))
        for (j, _, _), x in zip(copies, wp.residuals(np.zeros(0), wp.zero_nuisance())):
            total[j] += float(np.sum(x ** 2))
    return total


def _shifted(run, delay: float, j: int):
    """A copy of ``run`` as logged with its inputs delayed by ``delay`` (:func:`uvsim.latency.delay_inputs`)
    that a vehicle without latency takes as it is (named apart for the batch)."""
    late = delay_inputs(run, delay)
    out = late.derived(late.data, name=f"{run.name}@{j}")
    out.input_delay, out.as_logged = 0.0, None  # taken as logged by the scan's vehicle (no latency of its own)
    return out


def scan_latency(vehicle, runs, meas, *, attitude_bias: bool = False, grid=SCAN_GRID) -> dict:
    """The scan of the module docstring.  Returns ``{"grid": [s], "cost": [...], "best": s,
    "current": the vehicle's latency, "gain": relative cost decrease of best against current,
    "use": bool}``."""
    grid = [float(g) for g in grid]
    current = float(vehicle.sensor_latency)
    tried = grid if current in grid else [*grid, current]
    cost = windowed_costs(vehicle, runs, meas, tried, attitude_bias=attitude_bias).tolist()
    c_now = cost[tried.index(current)]
    cost = cost[:len(grid)]
    i = int(np.nanargmin(cost))
    best, c_best = grid[i], cost[i]
    if 0 < i < len(grid) - 1:  # the parabola's vertex through the minimum and its neighbours
        y0, y1, y2 = cost[i - 1], cost[i], cost[i + 1]
        den = y0 - 2 * y1 + y2
        if den > 0:
            d = grid[i] + 0.5 * (grid[i + 1] - grid[i]) * (y0 - y2) / den
            c = float(windowed_costs(vehicle, runs, meas, [d], attitude_bias=attitude_bias)[0])
            if c < c_best:
                best, c_best = round(d, 4), c
    gain = 1.0 - c_best / c_now if c_now > 0 else 0.0
    return {"grid": grid, "cost": cost, "best": best, "current": current, "gain": gain,
            "use": bool(best != current and gain >= MIN_GAIN), "min_gain": MIN_GAIN, "horizon_s": SCAN_HORIZON}


def refit_with_latency(joint, start_veh, fit_res, runs, meas, *, attitude_bias: bool = False, progress=None):
    """The scan with the fitted model, then the joint fit again from its result with the latency
    found when it is worth it (module docstring).

    Parameters
    ----------
    joint : ``joint(start_vehicle, names, tag) -> FitResult or None``, the calibration's joint stage
        freeing exactly ``names`` (the first fit's: no second screen), checkpointed under ``tag``.
    start_veh, fit_res : the first fit's start vehicle and result.
    runs, meas : the training runs and their measurement models.
    progress : the scan as a stage (:func:`uvsim.progress.as_progress`).

    Returns
    -------
    (fit, start_vehicle, scan)
        The fit to keep, its start vehicle (with the latency it was fitted at) and the scan
        (:func:`scan_latency`).
    """
    from uvsim.progress import as_progress

    fitted = start_veh.with_parameters(fit_res.values)
    with as_progress(progress).stage(f"sensor latency scan ({len(SCAN_GRID)} latencies, {len(runs)} runs)"):
        scan = scan_latency(fitted, runs, meas, attitude_bias=attitude_bias)
    if not scan["use"]:
        return fit_res, start_veh, scan
    log.info("sensor latency %.1f ms lowers the windowed cost by %.1f %%: fitting again with it",
             scan["best"] * 1000, 100 * scan["gain"])
    again = fitted.with_latency(scan["best"])
    res = joint(again, list(fit_res.names), ".latency")
    return (res if res is not None else fit_res), again, scan
