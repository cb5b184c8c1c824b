"""The projected scores of a fit's windows summed window by window, in one pass: the compiled form of
:func:`uvsim.fitting.linearization._window_sums` applied to ``J * r[:, None]`` (issue 46).

The numpy form multiplies the whole (m, p) matrix by the residuals and sums every column by
:func:`numpy.bincount`, one pass per column; on a 35-s, 100 Hz run with 35 parameters that was a
twentieth of a linearization.  This loop does the same operations in the same order per value (the
product ``J[i, j] * r[i]``, then the additions into each window's sum in the order of the entries,
from zero, as ``bincount`` adds its weights), so the sums are the same to the bit
(``tests/test_kernels.py``).  The numpy form stays the reference and runs where numba is not
installed or the setting says numpy.
"""
from __future__ import annotations


def window_sums(J, r, cluster, out):
    """``out[w, j] = sum of J[i, j] * r[i] over the entries i of window w`` (``cluster[i] == w``),
    added in the order of ``i``.

    Parameters
    ----------
    J : (m, p) float.
    r : (m,) float.
    cluster : (m,) int, each in ``[0, nw)``.
    out : (nw, p) float, zeros on entry; written.
    """
    m, p = J.shape
    for i in range(m):
        w = cluster[i]
        ri = r[i]
        for j in range(p):
            out[w, j] += J[i, j] * ri
