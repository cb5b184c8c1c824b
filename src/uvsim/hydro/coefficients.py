"""Dimensional damping coefficients from the body methods (seed 003 Table II)."""
from __future__ import annotations

import numpy as np

from uvsim.hydro.body import BodyModel
from uvsim.hydro.datcom import datcom
from uvsim.hydro.jorgensen import jorgensen


def quadratic_damping(body: BodyModel, re: float, rho: float) -> dict:
    """``|X_uu|`` (alpha = 0) and ``|Y_vv| = |Z_ww|`` (alpha = 90 deg), kg/m, by each method.

    ``X_uu = 1/2 rho A C_D(0)``, ``Y_vv = Z_ww = 1/2 rho A C_D(90 deg)`` (= ``C_N(90)``), all with
    ``A = body.A``; by axial symmetry ``Y_vv = Z_ww``.
    """
    a = np.array([0.0, 0.5 * np.pi])
    q = 0.5 * rho * body.A
    out = {}
    for name, fn in (("jorgensen", jorgensen), ("datcom", datcom)):
        c = fn(body, a, re)
        out[name] = {"Xuu": float(q * abs(c.CD[0])), "Yvv": float(q * abs(c.CD[1])),
                     "Zww": float(q * abs(c.CD[1]))}
    return out
