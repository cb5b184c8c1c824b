"""The open-loop guard: a change to the model must not make any logged group (or channel) worse.

Shared by diagnosis (an effect is accepted only when it passes, :mod:`uvsim.diagnosis`) and
calibration (a fitted model worse than the model the user started from is not a success,
:mod:`uvsim.calibration.report`).

The windowed prediction error that the fits minimize restarts every window from
estimated node states, so it rewards a change that explains the next few seconds even
when the free simulation of a whole run drifts further away (issue 22: per-thruster
reverse ratios that cut the windowed cost by 5 % while the open-loop depth error grew
from 664 to 1011 mm).  The guard therefore simulates the validation runs from their
logged starts (:func:`uvsim.fitting.evaluate.open_loop`, the report's before/after
RMSE) with the current model and with the candidate, and compares them **per logged
signal group** (position, depth, attitude, velocity, rates, acceleration).

Per group the noise-normalized squared errors are summed over blocks of
:data:`BLOCK_S` seconds of each run; the candidate's change of the group total is judged
by a block bootstrap over these blocks (Kunsch 1989; the same resampling as
:func:`uvsim.fitting.compare.bootstrap_improvement`).  A group is *worse* when

* its error grows by more than :data:`TOLERANCE` and the growth is confirmed in at least
  :data:`WORSE_LEVEL` of the resamples (worse beyond the comparison's noise), or
* its error grows by more than :data:`MAX_WORSE`, whatever the resampling says (a few
  long validation runs cannot make a large loss "significant", and a model that is 10 %
  worse at something it was told to predict is not a diagnosis a user can trust).

A candidate with a worse group is not accepted, whatever its windowed cost.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from uvsim.fitting.compare import bootstrap_improvement
from uvsim.fitting.sensitivity import GROWTH, PERTURBATION

#: Block length of the bootstrap, s: as long as a diagnosis window (core.DEFAULT_HORIZON),
#: so neighbouring blocks of a drifting free simulation are only weakly dependent.
BLOCK_S = 3.0
#: Relative growth of a group's open-loop error below which it is not called worse (the
#: validation runs' own spread: a few per cent between equally good models).
TOLERANCE = 0.02
#: Share of bootstrap resamples in which the group must be worse for a growth beyond
#: TOLERANCE to count (one-sided, as VAL_LEVEL for the improvements, decision.py).
WORSE_LEVEL = 0.9
#: Growth that counts as worse without resampling (issue 22's acceptance bar: no accepted
#: effect may worsen a group's open-loop validation by more than 10 %).
MAX_WORSE = 0.10


#: Length (s) of the start of a run over which position and depth predictions are aligned
#: with the log before two models are compared (:func:`start_aligned`).
ALIGN_WINDOW_S = 3.0


def start_aligned(meas, evaluation: dict, window_s: float = ALIGN_WINDOW_S) -> dict:
    """``evaluation`` (an :func:`evaluate_runs` entry) with its predicted position and depth
    shifted by their mean residual over the run's first ``window_s`` seconds.

    An open-loop simulation starts from the first logged samples, and their noise (1-2 cm
    for a pressure sensor) offsets the whole predicted depth.  Two models share that start,
    so the offset adds the same error to both, but it can cancel part of one model's
    dynamic error and not the other's: on the calibration benchmark's seed 2 the start model
    validated 2.5 cm RMS in depth and uvsim with the generator's *true* coefficients 3.2 cm
    (the truth simulated from the true initial state matches the generator to 0.1 mm).  A
    translation moves a vehicle's trajectory without changing its dynamics, so shifting each
    prediction by its mean residual over the start removes the luck and keeps every drift
    after it (the same idea as estimating initial conditions before comparing models, as
    MathWorks' System Identification Toolbox ``compare`` does)."""
    pred = dict(evaluation["pred"])
    res = meas.residuals(pred)
    rows = meas.t <= meas.t[0] + window_s
    for g in ("position", "depth"):
        if g in pred:
            e = res[g][rows]
            ok = np.isfinite(e)
            n = ok.sum(axis=0)
            off = np.where(n > 0, np.where(ok, e, 0.0).sum(axis=0) / np.maximum(n, 1), 0.0)  # no sample: no shift
            pred[g] = pred[g] + off
    return {**evaluation, "pred": pred}


def block_costs(meas: Sequence, results: Sequence[dict], block_s: float = BLOCK_S, *, by: str = "group",
                exclude: Mapping[str, Sequence[str]] | None = None) -> dict:
    """Open-loop errors by group (``by="group"``) or channel (``by="channel"``) and block.

    Parameters
    ----------
    meas : the validation runs' measurement models (:mod:`uvsim.measurements`).
    results : :func:`uvsim.fitting.evaluate.open_loop` of those runs (same order).
    exclude : run name -> channels left out of that run (e.g. where the free simulation is
        set by its uncertain start, :mod:`uvsim.fitting.sensitivity`).

    Returns
    -------
    dict with ``groups``: group (or channel) -> (B,) noise-normalized sums of squares per
    block (blocks of every run, in run order), ``runs``: run name -> key -> sum, ``total``
    (inf when a simulation diverged), ``rmse``: key -> pooled RMSE in its unit, and the inputs
    (``meas``, ``results``, ``by``) for :func:`compare_open_loop`.
    """
    groups: dict[str, list] = {}
    runs: dict[str, dict] = {}
    sq: dict[str, list] = {}
    total = 0.0
    for m, o in zip(meas, results):
        res = m.residuals(o["pred"])
        t = np.asarray(m.t, float)
        blk = np.floor((t - t[0]) / block_s).astype(int)
        n_blk = int(blk.max()) + 1 if blk.size else 0
        runs[m.name] = {}
        for g, e in res.items():
            grp = m.groups[g]
            used = m.used(g)
            drop = [j for j, c in enumerate(grp.channels) if c in (exclude or {}).get(m.name, ())]
            if drop:
                used = used.copy()
                used[:, drop] = False
            if not used.any():
                continue
            sig = np.where(grp.logged, grp.sigma, 1.0)
            z = np.where(used, e / sig, 0.0)
            bad = used & ~np.isfinite(z)
            if bad.any():
                total = float("inf")
                z = np.where(bad, 1e6, z)  # a diverged simulation: a huge but finite error
            if by == "channel":  # one key per logged channel of the group
                keys = [(c, [j]) for j, c in enumerate(grp.channels) if used[:, j].any()]
            else:
                keys = [(g, list(range(len(grp.channels))))]
            for key, cols in keys:
                per_row = (z[:, cols] ** 2).sum(axis=1)
                per_blk = np.bincount(blk, weights=per_row, minlength=n_blk)
                groups.setdefault(key, []).append(per_blk)
                runs[m.name][key] = float(per_row.sum())
                ee = np.where(used[:, cols], e[:, cols], 0.0)
                sq.setdefault(key, []).append((float(np.nansum(ee ** 2)), int(used[:, cols].sum())))
                if np.isfinite(total):
                    total += float(per_row.sum())
    rmse = {g: float(np.sqrt(sum(s for s, _ in v) / max(sum(n for _, n in v), 1))) for g, v in sq.items()}
    return {"groups": {g: np.concatenate(v) for g, v in groups.items()}, "runs": runs, "total": total,
            "rmse": rmse, "meas": list(meas), "results": list(results), "by": by}


def compare_open_loop(before: Mapping, after: Mapping, *, refuse_newly_unstable: bool = False,
                      names: tuple = ("the current model", "the candidate")) -> dict:
    """:func:`guard` of two :func:`block_costs` results that also carry ``results``,
    ``meas`` and ``unstable`` (run name -> channels whose free simulation amplifies the
    uncertainty of its start, :func:`uvsim.fitting.sensitivity.initial_state_growth`):
    those channels of those runs, for either model, are left out for both (the guard's
    ``not_compared``).  Runs unstable for the candidate only are listed (``newly_unstable``);
    with ``refuse_newly_unstable`` they make ``ok`` False: what was left out there cannot be
    vouched for, and the current model was stable there.  The calibration's check refuses
    them; diagnosis does not, since an effect that restores position (a tether) can make the
    test's velocity change grow without the vehicle being unstable (the foreign suite's
    case b: its tether was refused and a thrust asymmetry named instead).  ``names``: how the
    refusal's message calls the two models (before, after)."""
    unstable: dict = {}
    for side in (before, after):
        for name, chans in (side.get("unstable") or {}).items():
            unstable.setdefault(name, set()).update(chans)
    if not unstable:
        return {**guard(before, after), "not_compared": {}, "newly_unstable": []}
    exclude = {k: sorted(v) for k, v in unstable.items()}
    by = before.get("by", "group")
    b = block_costs(before["meas"], before["results"], by=by, exclude=exclude)
    a = block_costs(after["meas"], after["results"], by=by, exclude=exclude)
    out = {**guard(b, a), "not_compared": exclude}
    new = [k for k in (after.get("unstable") or {}) if k not in (before.get("unstable") or {})]
    out["newly_unstable"] = new
    if new and refuse_newly_unstable:
        msg = (f"{names[1]}'s free simulation of {', '.join(new)} is unstable (a {max(PERTURBATION):g} m/s or rad/s "
               f"change of the start grows more than {GROWTH:g}x) where {names[0]}'s is not, so its attitude and "
               "rates there cannot be compared")
        out["why"] = msg if out["ok"] else f"{out['why']}; {msg}"
        out["ok"] = False
    return out


def guard(before: Mapping, after: Mapping) -> dict:
    """Compare the open-loop block costs of the current model (``before``) and a candidate
    (``after``), both from :func:`block_costs`; ``ok`` is False when any group is worse
    (module docstring).  Returns ``{"ok", "worse": [group, ...], "groups": {group:
    {"before", "after", "relative", "p_worse", "worse"}}, "why"}``."""
    out: dict = {"groups": {}, "worse": []}
    for g, a in before["groups"].items():
        b = after["groups"].get(g)
        if b is None or b.shape != a.shape:
            continue
        # improvement of `before` over `after` = how much worse the candidate is
        cmp = bootstrap_improvement(b, a, level=WORSE_LEVEL)
        rel = float(b.sum() / a.sum() - 1.0) if a.sum() > 0 else 0.0
        worse = bool(rel > MAX_WORSE or (rel > TOLERANCE and cmp["p_better"] >= WORSE_LEVEL))
        out["groups"][g] = {"before": float(a.sum()), "after": float(b.sum()), "relative": rel,
                            "p_worse": cmp["p_better"], "worse": worse,
                            "rmse_before": before["rmse"].get(g), "rmse_after": after["rmse"].get(g)}
        if worse:
            out["worse"].append(g)
    out["ok"] = not out["worse"]
    if out["worse"]:
        parts = [f"{g} {100 * out['groups'][g]['relative']:+.0f} % (worse in "
                 f"{100 * out['groups'][g]['p_worse']:.0f} % of resamples)" for g in out["worse"]]
        out["why"] = ("makes the open-loop validation worse: " + ", ".join(parts)
                      + f" (the guard allows +{100 * TOLERANCE:.0f} % within the noise, never "
                        f"+{100 * MAX_WORSE:.0f} %)")
    else:
        out["why"] = "no logged group's open-loop validation error is worse"
    return out
