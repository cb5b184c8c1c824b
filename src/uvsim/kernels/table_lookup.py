"""A thrust table on uniformly spaced knots, evaluated in one pass: the compiled form of
:meth:`uvsim.thrust_curves.TabulatedThrustCurve._thrust` for large inputs (issue 46).

The numpy form there makes six temporaries the size of the input (a batch's 46,080 x 8 PWM
values: 2.9 MB each) and ran at 10 ms per chunk of the batched benchmark, a tenth of a worker's
time; this loop does the same operations in the same order per value, so the thrust is the same
to the bit (``tests/test_kernels.py`` compares them), at 0.6 ms.  The numpy form stays the
reference and runs where numba is not installed or the setting says numpy
(:func:`uvsim.kernels.compiled_uniform_table`).
"""
from __future__ import annotations


def uniform_table(pwm, x0, step, fp, out):
    """``out[k]`` = the linear interpolation of the knots ``x0 + j step`` -> ``fp[j]`` at ``pwm[k]``.

    Parameters
    ----------
    pwm : (n,) float, within the knots (the caller checks the range).
    x0, step : first knot and spacing, us.
    fp : (m,) float, thrust at the knots, N.
    out : (n,) float, written.
    """
    last = fp.size - 2
    for k in range(pwm.size):
        u = (pwm[k] - x0) / step
        i = min(int(u), last)
        t = u - i
        out[k] = fp[i] * (1.0 - t) + fp[i + 1] * t
