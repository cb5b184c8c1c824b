"""The attitude filter's lag on predicted Euler angles, in one pass: the compiled form of
``numpy.unwrap`` along time followed by :func:`uvsim.estimation.lag.first_order_lag` on a uniform
clock (``scipy.signal.lfilter``), as :meth:`uvsim.measurements.RunMeasurements._lag_segments`
applies them to every window of every parameter set (issue 46).

numpy's unwrap makes six temporaries the size of the input and the filter a seventh; in a
linearization of the real-log joint stage they were a tenth of the time.  This loop does the same
operations in the same order per value (the remainder as numpy's ``mod``: ``fmod``, then the
divisor added to a negative remainder; the running sum of the corrections; ``y = Z + b0 x`` with
``Z = a y_prev``, the filter's transposed direct form), so the angles are the same to the bit
(``tests/test_kernels.py``).  The numpy form stays the reference and runs where numba is not
installed, the setting says numpy, a sample is not finite or the clock is not uniform.
"""
from __future__ import annotations

import math

import numpy as np


def unwrapped_lag(x, y0, b0, a, out):
    """``out[n, :, k]``: the series ``x[n, :, k]`` (rad, L samples) unwrapped (jumps of more than
    pi taken as wraps, numpy.unwrap) and filtered by ``y[0] = y0[n, k]``, ``y[i] = b0 u[i] + a y[i-1]``.

    Parameters
    ----------
    x : (N, L, K) float, finite.
    y0 : (N, K) float, the filter's start.
    b0, a : the filter's coefficients (``1 - a`` and ``exp(-dt / tau)``).
    out : (N, L, K) float, written.
    """
    pi = math.pi
    period = 2.0 * math.pi
    N, L, K = x.shape
    for n in range(N):
        for k in range(K):
            y = y0[n, k]
            out[n, 0, k] = y
            prev = x[n, 0, k]
            cs = 0.0
            for i in range(1, L):
                p = x[n, i, k]
                dd = p - prev
                prev = p
                r = np.fmod(dd - (-pi), period)  # numpy.mod(dd - interval_low, period)
                if r != 0.0:
                    if r < 0.0:
                        r += period
                else:
                    r = 0.0
                m = r + (-pi)
                if m == -pi and dd > 0.0:
                    m = pi
                corr = m - dd
                if abs(dd) < pi:
                    corr = 0.0
                cs += corr
                y = a * y + b0 * (p + cs)
                out[n, i, k] = y
