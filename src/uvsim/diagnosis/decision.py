"""Is a fitted effect real: the evidence for one candidate and the rule that accepts it.

* :func:`judge` -- accept an effect: physical values, an in-sample robust Wald test of
  "the effect is off" (:func:`wald`), and a validation improvement confirmed by a block
  bootstrap over windows (:func:`uvsim.fitting.compare.bootstrap_improvement`), or a
  large improvement of the validation runs' free simulation (:func:`open_loop_evidence`).
* :func:`compare` -- the evidence :func:`judge` reads, for a model with the effect against
  the model without it; the verdict on the validation runs' free simulations
  (:func:`open_loop_verdict`) is part of it.
* :func:`clearly_better` -- one model's validation cost below another's both statistically and
  practically: how the choices among judged candidates (:mod:`uvsim.diagnosis.step_choice`,
  :mod:`uvsim.diagnosis.unit_choice`) compare two of them.

Which of a step's accepted candidates wins, the challenges of the winner by its variants, the
base model's challenge and backward elimination are :mod:`uvsim.diagnosis.step_choice`.  The
thresholds are module constants, stated with the reason for each; docs/diagnose.md gives the
method and its references.
"""
from __future__ import annotations

import numpy as np
from scipy.stats import chi2

from uvsim.diagnosis.candidates import below_supply, search_bound_hits
from uvsim.fitting.compare import bootstrap_improvement
from uvsim.fitting import verdict

#: One-sided confidence level of "significantly better" (block bootstrap), used to compare
#: variants; the acceptance of an effect uses VAL_LEVEL together with the Wald test.
LEVEL = 0.99
#: Acceptance: the robust Wald test of "the effect is off" on the training fit must give a
#: p-value below WALD_P, and the validation cost must drop by MIN_RELATIVE with the drop
#: confirmed in VAL_LEVEL of the block-bootstrap resamples of the validation windows.  The
#: two pieces of evidence are complementary: on clean scenarios the Wald test alone accepted
#: spurious thruster lags (p ~ 1e-6) that made the validation runs worse, and a handful of
#: validation windows alone (two runs) cannot reach 99 % for a real but moderate effect.
WALD_P = 1e-4
VAL_LEVEL = 0.9
#: Smallest share of the validation cost an accepted effect must remove (practical
#: significance: with thousands of samples a 1 % improvement can be "significant").
MIN_RELATIVE = 0.05
#: The second way to accept an effect: the held-out runs' *free simulation* confirms it.  The
#: windowed cost restarts every window from node states estimated on the data, so it hides
#: what an effect does over a whole run: a current's or a tether's drift (benchmark seed 85:
#: a 1.3 cm/s current removes 3.4 % of the windowed validation cost and 98.5 % of the
#: open-loop position error).  An effect is then accepted when the verdict on the free
#: simulations (:func:`open_loop_verdict`) is *better* and some logged channel's open-loop
#: mean squared error falls by at least OPEN_LOOP_GAIN with the fall's upper bound at the
#: verdict's level below 1 (the channel is better beyond the noise), the windowed validation
#: cost falls too (confirmed at VAL_LEVEL, any size), and the training fit's robust Wald test
#: gives p < OPEN_LOOP_WALD_P (the conventional 1 % level: the held-out free simulation is
#: the stronger, independent piece of evidence, so the in-sample test need not carry the
#: 1e-4 of the windowed path).
OPEN_LOOP_GAIN = 0.5
OPEN_LOOP_WALD_P = 1e-2


def wald(res, c) -> dict:
    """In-sample Wald test of the effect being off (``c.null``) with the fit's cluster-robust
    covariance (windows as clusters, so correlated residuals within a window do not make it
    optimistic): ``W = (theta - theta_0)^T C^-1 (theta - theta_0)`` ~ chi^2_k under the null."""
    null = c.null
    idx = [res.names.index(n) for n in null if n in res.names]
    if not idx:
        return {"W": None, "k": 0, "p": None}
    d = np.array([res.values[res.names[i]] - null[res.names[i]] for i in idx])
    C = res.covariance[np.ix_(idx, idx)]
    W = float(d @ np.linalg.pinv(C) @ d)
    return {"W": W, "k": len(idx), "p": float(chi2.sf(W, len(idx)))}


def open_loop_verdict(before: dict, after: dict) -> dict:
    """The verdict (:func:`uvsim.fitting.verdict.compare`, the one calibration gives) on the model
    ``after`` against ``before``, from their :meth:`SimulatorFits.open_loop_blocks
    <uvsim.diagnosis.simulator_fits.SimulatorFits.open_loop_blocks>`, with ``ok`` (the verdict is *better*:
    pooled error lower beyond the noise and no channel worse) and ``why`` (its message)."""
    v = verdict.compare(before["meas"], before["preds"], after["preds"], names=("the current model", "the candidate"))
    return {**v, "why": v["message"]}


def compare(before: dict, after: dict, fit, c) -> dict:
    """The evidence for effect ``c`` in the model ``after`` against the model ``before``
    (each :meth:`SimulatorFits.validation <uvsim.diagnosis.simulator_fits.SimulatorFits.validation>`):
    the block bootstrap of their validation windows, the robust Wald test of ``c`` in
    ``fit`` (the training fit that has it), and the verdict on the free simulations of the
    validation runs (``guard``, :func:`open_loop_verdict`) when ``before`` has them."""
    cmp = bootstrap_improvement(before["windows"], after["windows"], level=LEVEL)
    cmp["wald"] = wald(fit, c)
    if "open_loop" in before:
        cmp["guard"] = open_loop_verdict(before["open_loop"], after["open_loop"])
        # what the guard compared: whole runs, or windows of closed-loop logs (uvsim.fitting.evaluate.windowed)
        cmp["guard"]["horizon_s"] = before["open_loop"].get("horizon_s")
    return cmp


def judge(row, val_cur) -> tuple[bool, str]:
    """The acceptance rule (it marks ``row["bound_rejected"]`` / ``row["guard_blocked"]`` when
    those were the reason): physical values, no parameter on the edge of its search range, an
    in-sample robust Wald
    test of the effect being off at :data:`WALD_P`, and on the validation runs a
    reduction of the cost by at least :data:`MIN_RELATIVE` that the block bootstrap over
    windows confirms at :data:`VAL_LEVEL` (one-sided); or, in place of the last three, the
    free simulation's evidence of :func:`open_loop_evidence`.  In both cases the verdict on the
    validation runs' free simulations (:func:`open_loop_verdict`, the calibration's) must be
    *better*: a candidate that trades one channel for another, or does not lower the pooled
    error beyond the noise, is not accepted."""
    if "compare" not in row:
        return False, row.get("why", "not fitted")
    cmp = row["compare"]
    if row["problem"]:
        return False, row["problem"]
    c = row["candidate"]
    values = row.get("values", {})
    low = below_supply(c, values)
    if low is not None:
        row["bound_rejected"], row["bound_hits"] = True, list(c.free)
        return False, low
    hits = search_bound_hits(c, values, row.get("at_bounds") or [])
    if hits:
        # the selector fits one more candidate for it (Selector.step, Selector.fit_judged)
        row["bound_rejected"], row["bound_hits"] = True, hits
        if hits == ["thruster_lag_time_constant"] and values[hits[0]] <= c.bounds[hits[0]][0] * 1.0001:
            return False, (f"time constant on its floor {c.bounds[hits[0]][0]:.3g} s (half the log's sample "
                           "interval): indistinguishable from the timing of the logged inputs (candidates._lag)")
        if hits == ["thrust_scale_scale"]:
            return False, (f"thrust scale on its floor {c.bounds[hits[0]][0]:g}, below what a supply voltage can "
                           "do: it stands in for something the model lacks (under an autopilot: a force the "
                           "thrusters hold against), so the base model is kept")
        return False, (f"{', '.join(hits)} on the edge of the search range: the data push this effect beyond "
                       "what the catalogue considers physical, so it is not named (an effect outside the "
                       "catalogue or an error of the base model is the likelier cause)")
    w = cmp.get("wald") or {}
    g = cmp.get("guard")
    drift = open_loop_evidence(cmp)
    if drift is not None:
        return True, drift
    if w.get("p") is not None and not w["p"] < WALD_P:
        return False, (f"not significant in the training runs: robust Wald test p = {w['p']:.2g} "
                       f"(needs < {WALD_P:g}; the fitted effect is indistinguishable from none)")
    if cmp["relative"] < MIN_RELATIVE:
        return False, (f"does not help the validation runs: validation cost {-100 * cmp['relative']:+.1f} % "
                       f"(needs a reduction of >= {100 * MIN_RELATIVE:.0f} %)")
    if cmp["p_better"] < VAL_LEVEL:
        return False, (f"not confirmed on the validation runs: the cost drops {100 * cmp['relative']:.1f} % but "
                       f"the bootstrap over windows finds it better in only {100 * cmp['p_better']:.0f} % of "
                       f"resamples (needs {100 * VAL_LEVEL:.0f} %)")
    if g is not None and not g["ok"]:
        # everything but the verdict passed: a richer variant (a piece's own mass) may still pass it
        row["guard_blocked"] = True
        return False, g["why"]
    return True, (f"significant: Wald p = {w.get('p', float('nan')):.1g} in training, validation cost "
                  f"-{100 * cmp['relative']:.1f} % (better in {100 * cmp['p_better']:.1f} % of resamples); "
                  + (g["why"] if g is not None else "open-loop verdict not run"))


def open_loop_evidence(cmp) -> str | None:
    """The reason to accept an effect on the free simulation of the validation runs
    (:data:`OPEN_LOOP_GAIN`), or None when that evidence is missing: the verdict is *better*,
    some channel's open-loop mean squared error fell by OPEN_LOOP_GAIN and is better beyond
    the noise, the windowed validation cost fell (confirmed at VAL_LEVEL) and the training
    Wald test gives p < OPEN_LOOP_WALD_P.  ``cmp``: a fitted row's ``compare`` (windowed
    ``relative`` and ``p_better``, ``wald``, ``guard``)."""
    g, w = cmp.get("guard"), cmp.get("wald") or {}
    if g is None or not g["ok"] or w.get("p") is None or not w["p"] < OPEN_LOOP_WALD_P:
        return None
    if not (cmp["relative"] > 0.0 and cmp["p_better"] >= VAL_LEVEL):
        return None
    gained = {k: v for k, v in (g.get("channels") or {}).items()
              if v["mse_ratio"] <= 1.0 - OPEN_LOOP_GAIN and v["better"]}
    if not gained:
        return None
    parts = ", ".join(f"{k} {100 * v['rmse_change']:+.0f} %" for k, v in gained.items())
    h = g.get("horizon_s")
    judged = ("the free simulation of the validation runs: open-loop RMSE" if h is None else
              f"the validation runs' predictions over {h:g}-s windows from the logged states: RMSE")
    return (f"significant in {judged} {parts}, windowed "
            f"validation cost -{100 * cmp['relative']:.1f} % (better in {100 * cmp['p_better']:.1f} % of "
            f"resamples), Wald p = {w['p']:.1g} in training; {g['why']}")



def clearly_better(worse_windows, better_windows) -> bool:
    """``better`` beats ``worse`` on validation both statistically (block bootstrap at
    :data:`LEVEL`) and practically (by at least :data:`MIN_RELATIVE` of the cost): with
    thousands of residuals a 0.4 % difference can be "significant" (a ballast against the
    constant-tension tether that mimics it, benchmark seed 119), and such a difference must
    not outweigh parsimony."""
    cmp = bootstrap_improvement(worse_windows, better_windows, level=LEVEL)
    return bool(cmp["significant"]) and cmp["relative"] >= MIN_RELATIVE
