"""A thrust table on uniformly spaced knots, evaluated in one pass: the compiled form of
:meth:`uvsim.thrust_curves.TabulatedThrustCurve._thrust` for large inputs (issue 46), and of
:meth:`uvsim.voltage_curves.VoltageThrustCurve.thrust` (the same table per supply voltage,
bilinear in PWM and voltage: :func:`voltage_table`).

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


def voltage_table(pwm, volt, x0, step, volts, T, out):
    """``out[k]`` = the thrust at ``pwm[k]`` (us) and supply ``volt[k]`` (V) of the sheets ``T`` (m, n)
    measured at ``volts`` (m,) on the knots ``x0 + j step``: linear in PWM within each of the two
    sheets that bracket the voltage, then linear between them (the operations of
    :meth:`uvsim.voltage_curves.VoltageThrustCurve.thrust`, in its order; the caller checks the
    ranges and fills missing voltages).
    """
    last = T.shape[1] - 2
    top = volts.size - 2
    for k in range(pwm.size):
        u = (pwm[k] - x0) / step
        i = min(int(u), last)
        t = u - i
        v = volt[k]
        j = -1  # searchsorted(volts, v, side="right") - 1, clipped to 0 .. m - 2
        for s in range(volts.size):
            if volts[s] <= v:
                j = s
        j = min(max(j, 0), top)
        w = (v - volts[j]) / (volts[j + 1] - volts[j])
        lo = T[j, i] * (1.0 - t) + T[j, i + 1] * t
        hi = T[j + 1, i] * (1.0 - t) + T[j + 1, i + 1] * t
        out[k] = lo * (1.0 - w) + hi * w
