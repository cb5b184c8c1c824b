"""Savitzky-Golay smoothing and differentiation on the log's own time stamps.

A Savitzky-Golay filter fits, around each sample, a least-squares polynomial of order ``p``
to the ``win`` samples of its window and evaluates it (or its derivative) there (Savitzky &
Golay 1964). :func:`scipy.signal.savgol_filter` does this for uniform sampling, where the fit
reduces to one convolution. Topside logs are not uniform: their stamps jitter by +-15 ms at
10 Hz (issue 48), and a convolution would put the wrong time under every sample. Here the
local fit uses each window's actual time offsets ``t_j - t_i``: the same estimator, exact on
uniform stamps (it then equals scipy's interior values to rounding, tested), defined on any
increasing stamps; nothing is resampled. At the ends, as scipy's ``mode="interp"``, the first
and last full windows' polynomials are evaluated at the end samples.
"""
from __future__ import annotations

from math import factorial

import numpy as np

#: Stamps within this fraction of the median interval count as uniform (then scipy's
#: convolution is used, bit for bit what the project computed before).
UNIFORM_RTOL = 0.01


def is_uniform(t: np.ndarray) -> bool:
    d = np.diff(np.asarray(t, float))
    dt = float(np.median(d))
    return bool(np.all(np.abs(d - dt) <= UNIFORM_RTOL * dt))


def savgol_on_stamps(t: np.ndarray, x: np.ndarray, win: int, polyorder: int, deriv: int = 0) -> np.ndarray:
    """The ``deriv``-th derivative (0: the smoothed value) of ``x`` (n,) or (n, k) at the
    stamps ``t`` (n,), strictly increasing, by local polynomials of order ``polyorder`` over
    ``win`` samples (odd, ``polyorder < win <= n``)."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    one = x.ndim == 1
    X = x[:, None] if one else x
    n, half = t.size, win // 2
    if not (win % 2 and polyorder < win <= n):
        raise ValueError(f"need an odd window of more than {polyorder} samples within {n}, got {win}")
    centres = np.arange(half, n - half)
    idx = centres[:, None] + np.arange(-half, half + 1)[None, :]          # (m, win)
    scale = float(np.median(np.diff(t))) * half or 1.0                    # conditioning of the powers
    tau = (t[idx] - t[centres][:, None]) / scale                          # (m, win)
    V = tau[..., None] ** np.arange(polyorder + 1)                        # (m, win, p+1)
    # coefficients of each window's polynomial (in tau): (m, p+1, k); least squares per window
    coef = np.linalg.solve(np.swapaxes(V, 1, 2) @ V, np.swapaxes(V, 1, 2) @ X[idx])
    out = np.empty((n, X.shape[1]))

    def evaluate(c, s):  # the deriv-th derivative in t of sum_k c_k tau^k at tau = s, for rows of c
        k = np.arange(deriv, polyorder + 1)
        w = np.array([factorial(j) / factorial(j - deriv) for j in k]) / scale ** deriv
        return np.einsum("...k,...kc->...c", w * s[..., None] ** (k - deriv), c[..., k, :])

    out[centres] = evaluate(coef, np.zeros(centres.size))
    head, tail = np.arange(half), np.arange(n - half, n)
    out[head] = evaluate(np.broadcast_to(coef[0], (half, *coef.shape[1:])), (t[head] - t[half]) / scale)
    out[tail] = evaluate(np.broadcast_to(coef[-1], (half, *coef.shape[1:])), (t[tail] - t[n - 1 - half]) / scale)
    return out[:, 0] if one else out
