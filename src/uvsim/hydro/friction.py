"""Turbulent flat-plate skin-friction lines (mean coefficient over a plate of length L).

``"schoenherr"`` (default)
    Karman-Schoenherr line, ``0.242 / sqrt(C_f) = log10(Re C_f)`` (Schoenherr 1932), solved by
    Newton iteration.  It is the incompressible turbulent line that DATCOM sec. 4.1.5.1
    (Fig. 4.1.5.1-26, referenced by seed 003 eq. 15 as [18, Fig. 4.1.5]) is built on.
``"ittc57"``
    ITTC-1957 model-ship correlation line ``C_f = 0.075 / (log10 Re - 2)^2`` (ITTC 1957).
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import HydroError

FRICTION_LINES = ("schoenherr", "ittc57")


def skin_friction(re, line: str = "schoenherr") -> np.ndarray:
    """Mean turbulent skin-friction coefficient ``C_f`` (-) at length Reynolds number ``re``.

    Parameters
    ----------
    re : array_like
        Reynolds number based on the plate (body) length, > 1e3.
    line : {"schoenherr", "ittc57"}
    """
    re = np.asarray(re, dtype=float)
    if np.any(~np.isfinite(re)) or np.any(re <= 1e3):
        raise HydroError(f"skin friction: Reynolds number must be finite and > 1e3, got {re!r}")
    if line == "ittc57":
        return 0.075 / (np.log10(re) - 2.0) ** 2
    if line == "schoenherr":
        # Solve g(c) = 0.242/sqrt(c) - log10(re c) = 0 in s = 1/sqrt(c): 0.242 s = log10(re) - 2 log10(s)
        s = np.sqrt((np.log10(re) - 2.0) ** 2 / 0.075)  # start from ITTC-57
        for _ in range(50):
            g = 0.242 * s - np.log10(re) + 2.0 * np.log10(s)
            dg = 0.242 + 2.0 / (s * np.log(10.0))
            step = g / dg
            s = s - step
            if np.all(np.abs(step) < 1e-12 * s):
                break
        return 1.0 / s ** 2
    raise HydroError(f"unknown friction line {line!r}; expected one of {FRICTION_LINES}")
