"""Comparing two fitted models on validation runs when residuals are autocorrelated.

Trajectory residuals are strongly autocorrelated (issue 14: lag-1 correlation
0.99-0.999), so criteria that count samples as independent (BIC, F-tests, even with an
AR(1) "effective sample size") either accept everything or nothing.  uvsim compares
models on *validation* runs through the windowed prediction error
(:mod:`uvsim.fitting.objective`): each model's node states are re-estimated on the
validation data with its parameters fixed, and the cost of every window is kept.  A
window's residuals may be correlated in any way; different windows are nearly
independent (each starts from its own fitted node).  The improvement of model B over
model A is then judged by a **block bootstrap over windows** (Kunsch 1989; Efron &
Tibshirani 1993 ch. 8): the windows' cost differences ``d_w = SSE_A,w - SSE_B,w`` are
resampled with replacement ``n_boot`` times; B is *significantly better* when the
lower one-sided ``1 - level`` quantile of the resampled total is above 0, i.e. the
improvement is not carried by a few windows.
"""
from __future__ import annotations

import numpy as np

#: Default one-sided confidence level of "significantly better".
LEVEL = 0.99
N_BOOT = 2000


def bootstrap_improvement(sse_a: np.ndarray, sse_b: np.ndarray, *, level: float = LEVEL, n_boot: int = N_BOOT,
                          seed: int = 0) -> dict:
    """Block-bootstrap comparison of per-window costs (module docstring).

    Parameters
    ----------
    sse_a, sse_b : (W,) cost of each validation window under model A and model B
        (same windows, same order).

    Returns
    -------
    dict with ``delta`` (total cost decrease A -> B), ``relative`` (delta / total A),
    ``lower`` (the ``1 - level`` quantile of the bootstrap totals), ``p_better`` (share
    of bootstrap totals above 0), ``significant`` (lower > 0), ``windows``.
    """
    a = np.asarray(sse_a, float)
    b = np.asarray(sse_b, float)
    if a.shape != b.shape or a.ndim != 1 or a.size == 0:
        raise ValueError(f"window costs must be two 1-D arrays of the same length, got {a.shape} and {b.shape}")
    d = a - b
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, d.size, (n_boot, d.size))
    tot = d[idx].sum(axis=1)
    lower = float(np.quantile(tot, 1.0 - level))
    total_a = float(a.sum())
    return {"delta": float(d.sum()), "relative": float(d.sum() / total_a) if total_a > 0 else 0.0,
            "lower": lower, "p_better": float(np.mean(tot > 0)), "significant": bool(lower > 0),
            "windows": int(d.size), "level": level}
