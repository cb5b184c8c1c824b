"""The screening's fit of each candidate on the equation error (:meth:`uvsim.diagnosis.selector.Selector.screen`).

Each candidate is fitted together with the current model's free parameters by a few Gauss-Newton
steps on the inverse-dynamics residual (:func:`joint_gn`), from its catalogue starts
(:func:`best_of_starts`).  The tethers form a chain: each starts from the best simpler tether
before it (a small multi-start on the cheap equation error, the global stage), so they are fitted
in order, in this process.  The other candidates are independent of each other and of the chain:
given a :class:`~uvsim.fitting.worker_pool.WorkerPool` they are fitted in its processes while this
one fits the chain, with the same numbers (each candidate's fit is the same code on the same
inputs, with one BLAS thread everywhere).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from uvsim.diagnosis.candidates import Candidate
from uvsim.diagnosis.regression import BaseBlock
from uvsim.diagnosis.simulator_fits import free_space
from uvsim.diagnosis.starts import SLACK_GN_ITERATIONS, candidate_starts, slack_starts
from uvsim.errors import UvsimError
from uvsim.fitting.equation_error import EquationError


def joint_gn(veh, motions, c: Candidate, cur, vals0: Mapping, start: Mapping, block: BaseBlock,
             scale: np.ndarray, iterations: int = 2) -> dict:
    """Gauss-Newton on the equation error of candidate ``c`` together with the current
    free parameters: the candidate's columns are re-differentiated at every step, the
    current parameters' columns (``block``: per unit, at ``vals0``, factored once) are reused
    (they move little), so a step costs ``1 + len(c.free)`` evaluations."""
    base = dict(vals0)
    names_b = list(cur["free"])
    lo_b = np.array([cur["bounds"][n][0] for n in names_b])
    hi_b = np.array([cur["bounds"][n][1] for n in names_b])
    xc = {n: float(start.get(n, c.start[n])) for n in c.free}
    best = None
    for it in range(iterations + 1):
        sp = free_space(veh, c.free, c.bounds, xc, base)
        ee = EquationError(veh, motions, sp, scale=scale)
        if it == iterations:  # the last point needs its residual only
            Jc, r = None, ee.residuals(sp.z0[None])[0]
        else:
            Jc, r = ee.jacobian()
        rss = float(r @ r)
        if best is None or rss < best["rss"]:
            best = {"rss": rss, "values": {**{n: base[n] for n in names_b}, **xc}}
        if it == iterations:
            break
        d, _ = block.solve(Jc / sp.scale[:, None], r)
        nb = len(names_b)
        if nb:
            b = np.clip(np.array([base[n] for n in names_b]) + d[:nb], lo_b, hi_b)
            base.update(zip(names_b, map(float, b)))
        xc = {n: float(np.clip(xc[n] + dd, *c.bounds[n])) for n, dd in zip(c.free, d[nb:])}
    return best


def best_of_starts(shared, c: Candidate, starts=None) -> dict:
    """The best (lowest residual) of ``c``'s fits from ``starts`` (default its catalogue starts);
    ``shared``: (motions, current model, its values, the current parameters' block, scale).  A
    start the model refuses gives an infinite residual and its error."""
    motions, cur, vals0, block, scale = shared
    veh = cur["vehicle"].with_effects([c.spec]) if c.spec is not None else cur["vehicle"]
    its = SLACK_GN_ITERATIONS if "tether_slack_length" in c.free else 2
    best = None
    for st in candidate_starts(c) if starts is None else starts:
        try:
            r = joint_gn(veh, motions, c, cur, vals0, st, block, scale, iterations=its)
        except (UvsimError, np.linalg.LinAlgError, ValueError) as exc:
            r = {"rss": np.inf, "values": {}, "error": str(exc)}
        if best is None or r["rss"] < best["rss"]:
            best = r
    return best


def screen_candidates(cands, motions, cur, vals0, block: BaseBlock, scale, single: Mapping, rss0: float,
                      pool=None) -> list:
    """Screening numbers (``reduction``, ``values``, ``error`` when every start failed) of ``cands``
    in order (module docstring).  ``single``: a thruster gain's linearized optimum (values, residual
    sum of squares, curvature) by gain name, which a one-gain variant takes without a fit; ``pool``:
    a WorkerPool for the candidates outside the tether chain, or None."""
    shared = (motions, cur, vals0, block, scale)
    res: list = [None] * len(cands)
    chain, rest = [], []
    for i, c in enumerate(cands):
        if c.effect == "thruster_gain" and len(c.free) == 1 and c.free[0] in single:
            # one gain: the linearized optimum, held within the variant's range (a unit's gain
            # >= 0, a reversed unit's <= 0), so a reversed thruster ranks its own variant first
            vals, rss, curv = single[c.free[0]]
            g_hat = vals[c.free[0]]
            lo, hi = c.bounds[c.free[0]]
            g = min(max(g_hat, lo), hi)
            res[i] = {"reduction": max(0.0, 1.0 - (rss + (g - g_hat) ** 2 * curv) / rss0),
                      "values": {**vals, c.free[0]: g}}
        else:
            (chain if c.effect == "tether" else rest).append(i)

    def run_chain() -> dict:
        out, tether_best = {}, (np.inf, {})
        for i in chain:
            c = cands[i]
            starts = None
            if tether_best[1]:
                starts = [{**c.start, **{k: v for k, v in tether_best[1].items() if k in c.free}}]
                starts += slack_starts(c, starts[0])
            best = best_of_starts(shared, c, starts)
            if best.get("values") and best["rss"] < tether_best[0]:
                tether_best = (best["rss"], {k: v for k, v in best["values"].items() if k.startswith("tether_")})
            out[i] = best
        return out

    if pool is not None and len(rest) >= 2:
        got, bests = pool.map(best_of_starts, shared, [cands[i] for i in rest], meanwhile=run_chain)
    else:
        bests = run_chain()
        got = [best_of_starts(shared, cands[i]) for i in rest]
    bests.update(zip(rest, got))
    for i, best in bests.items():
        red = max(0.0, 1.0 - best["rss"] / rss0) if np.isfinite(best["rss"]) else 0.0
        res[i] = {"reduction": red, "values": best["values"], **({"error": best["error"]} if "error" in best else {})}
    return res
